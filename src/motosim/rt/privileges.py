"""Real-time privileges of the loop's process, each applied or refused without failing.

A Python loop on a general-purpose kernel is soft real time at best; what makes its timing
usable is the scheduling policy and a quiet memory system (see the real-time guide, "Setting
up the lab PC"):

- ``SCHED_FIFO`` priority (:func:`os.sched_setscheduler`): the loop preempts every normal
  process; needs root, ``CAP_SYS_NICE`` or an ``ulimit -r`` (RLIMIT_RTPRIO) at least the
  priority;
- CPU affinity (:func:`os.sched_setaffinity`): the loop stays on one core (ideally one
  isolated with ``isolcpus``);
- locked memory (``mlockall(MCL_CURRENT | MCL_FUTURE)`` through :mod:`ctypes`): no page fault
  on the loop's memory; needs ``CAP_IPC_LOCK`` or a large ``ulimit -l``;
- a frozen, disabled garbage collector after warm-up (:func:`gc.freeze`, :func:`gc.disable`):
  a full collection of a scientific Python process takes milliseconds.

Each request returns a :class:`Privilege` saying whether it was applied and, if not, why
("not permitted", "not available on this system"); none raises, so the same command runs
on a laptop (with worse timing) and on a lab PC.
"""

import ctypes
import ctypes.util
import gc
import os
from collections.abc import Sequence
from dataclasses import dataclass

__all__ = [
    "Privilege",
    "apply_privileges",
    "freeze_gc",
    "lock_memory",
    "pin_cpus",
    "set_fifo_priority",
    "thaw_gc",
]

_MCL_CURRENT = 1
_MCL_FUTURE = 2


@dataclass(frozen=True, slots=True)
class Privilege:
    """The outcome of one request: its name, whether it was applied, and what happened."""

    name: str
    applied: bool
    detail: str

    def __str__(self) -> str:
        """``"NAME: applied"``, or ``"NAME: refused (DETAIL)"``.

        Examples
        --------
        >>> str(Privilege("mlockall", True, "applied"))
        'mlockall: applied'
        >>> str(Privilege("SCHED_FIFO 80", False, "not permitted"))
        'SCHED_FIFO 80: refused (not permitted)'
        """
        return f"{self.name}: applied" if self.applied else f"{self.name}: refused ({self.detail})"


def set_fifo_priority(priority: int) -> Privilege:
    """Put this process under ``SCHED_FIFO`` at ``priority`` (1..99).

    Examples
    --------
    >>> set_fifo_priority(0).applied    # out of range: refused, nothing changed
    False
    """
    name = f"SCHED_FIFO {priority}"
    if not hasattr(os, "sched_setscheduler"):
        return Privilege(name, False, "not available on this system")
    low = os.sched_get_priority_min(os.SCHED_FIFO)
    high = os.sched_get_priority_max(os.SCHED_FIFO)
    if not low <= priority <= high:
        return Privilege(name, False, f"priority outside {low}..{high}")
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except PermissionError:
        return Privilege(name, False, "not permitted (needs root, CAP_SYS_NICE or ulimit -r)")
    except OSError as err:
        return Privilege(name, False, f"refused: {err.strerror}")
    return Privilege(name, True, "applied")


def pin_cpus(cpus: Sequence[int]) -> Privilege:
    """Restrict this process to the CPUs ``cpus``."""
    name = f"CPU affinity {','.join(str(c) for c in cpus)}"
    if not hasattr(os, "sched_setaffinity"):
        return Privilege(name, False, "not available on this system")
    try:
        os.sched_setaffinity(0, set(cpus))
    except PermissionError:
        return Privilege(name, False, "not permitted")
    except (OSError, ValueError) as err:
        return Privilege(name, False, f"refused: {getattr(err, 'strerror', None) or err}")
    return Privilege(name, True, "applied")


def lock_memory() -> Privilege:
    """Lock the process's current and future pages in RAM (``mlockall``)."""
    name = "mlockall"
    path = ctypes.util.find_library("c")
    if path is None:
        return Privilege(name, False, "not available on this system (no C library)")
    libc = ctypes.CDLL(path, use_errno=True)
    if not hasattr(libc, "mlockall"):
        return Privilege(name, False, "not available on this system")
    if libc.mlockall(_MCL_CURRENT | _MCL_FUTURE) != 0:
        errno = ctypes.get_errno()
        return Privilege(name, False, f"not permitted ({os.strerror(errno)}; see ulimit -l)")
    return Privilege(name, True, "applied")


def freeze_gc() -> Privilege:
    """Collect, then freeze every object and disable the garbage collector.

    Call after warm-up (every kernel compiled, every buffer allocated), just before the first
    deadline; :func:`thaw_gc` undoes it after the loop.
    """
    gc.collect()
    gc.freeze()
    gc.disable()
    return Privilege("gc frozen and disabled", True, f"{gc.get_freeze_count()} objects frozen")


def thaw_gc() -> None:
    """Unfreeze the objects frozen by :func:`freeze_gc` and enable the collector again."""
    gc.unfreeze()
    gc.enable()


def apply_privileges(
    *, priority: int | None = None, cpus: Sequence[int] | None = None, mlock: bool = False
) -> tuple[Privilege, ...]:
    """Request the privileges asked for (None or False: not asked), each reported.

    Examples
    --------
    >>> apply_privileges()
    ()
    """
    out: list[Privilege] = []
    if priority is not None:
        out.append(set_fifo_priority(priority))
    if cpus:
        out.append(pin_cpus(cpus))
    if mlock:
        out.append(lock_memory())
    return tuple(out)
