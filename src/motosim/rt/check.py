"""How late this machine wakes a loop, judged against the real-time targets; what a run's
timing and faults advise.

:func:`check_timing` runs an empty :class:`~motosim.rt.loop.RateLoop` for a while and returns
its timing statistics: the wake-up latency is what the scheduler, the kernel and the machine
(a VM's steal time) add on their own, before any stack step runs. :func:`verdict` judges
timing statistics against :class:`Targets`; :func:`advice` says what a run's timing and its
fault point to.
"""

from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

from motosim.errors import MotosimError
from motosim.rt.clock import Clock
from motosim.rt.loop import RateLoop, TimingStats
from motosim.rt.privileges import Privilege, freeze_gc, thaw_gc

__all__ = ["Check", "Targets", "Verdict", "advice", "check_timing", "verdict"]


def check_timing(rate: float, duration: float, *, clock: Clock) -> TimingStats:
    """Run an empty loop at ``rate`` [Hz] for ``duration`` [s] and measure its timing.

    The garbage collector is frozen and disabled during the run (then restored).

    Examples
    --------
    >>> from motosim.rt.clock import SimulatedClock
    >>> s = check_timing(1000.0, 0.01, clock=SimulatedClock())
    >>> s.served, s.missed, s.wake_max
    (10, 0, 0.0)
    """
    if not (duration > 0.0 and duration * rate <= 1e8):
        raise MotosimError(f"duration = {duration!r} s: expected a positive time")
    periods = round(duration * rate)
    loop = RateLoop(rate, clock, capacity=max(periods, 1))
    freeze_gc()
    try:
        loop.run(lambda k, t: True, periods=periods)
    finally:
        thaw_gc()
    return loop.stats()


@dataclass(frozen=True, slots=True)
class Targets:
    """The real-time targets a loop's timing is judged against.

    The defaults are motosim's targets for a 1 kHz handlebar loop, those the real-time
    guide measures against: a wake-up within 100 us of the deadline at p99, at most 0.1 %
    of the deadlines missed, and a step's compute p99 within a fifth of the period (200 us
    at 1 kHz), which leaves the rest of the period to the bus and the drive's answer.

    Attributes
    ----------
    wake_p99 : float
        Largest p99 wake-up latency after the deadline [s].
    missed : float
        Largest fraction of the deadlines missed.
    compute_share : float
        Largest p99 compute time of a step, as a share of the period.
    """

    wake_p99: float = 100e-6
    missed: float = 1e-3
    compute_share: float = 0.2

    def __post_init__(self) -> None:
        for name, value in (
            ("wake_p99", self.wake_p99),
            ("missed", self.missed),
            ("compute_share", self.compute_share),
        ):
            if not (0.0 < value < 1.0):
                raise MotosimError(f"{name} = {value!r}; expected a value in (0, 1)")


class Check(NamedTuple):
    """One target against its measured value (both in the target's unit)."""

    name: str
    value: float
    limit: float
    unit: str

    @property
    def passed(self) -> bool:
        """Whether the value is within the limit (a NaN value fails)."""
        return self.value <= self.limit

    def line(self) -> str:
        """``PASS wake-up p99 12.3 us <= 100 us`` (or FAIL, with ``>``)."""
        scale = 1e6 if self.unit == "us" else 100.0 if self.unit == "%" else 1.0
        sign = "<=" if self.passed else ">"
        return (
            f"{'PASS' if self.passed else 'FAIL'} {self.name} {self.value * scale:.3g} "
            f"{self.unit} {sign} {self.limit * scale:.3g} {self.unit}"
        )


class Verdict(NamedTuple):
    """The checks of a loop's timing against :class:`Targets`."""

    checks: tuple[Check, ...]

    @property
    def passed(self) -> bool:
        """Whether every check passed."""
        return all(check.passed for check in self.checks)

    def as_dict(self) -> dict[str, object]:
        """``{"pass": bool, "checks": [{"name", "value", "limit", "unit", "pass"}]}`` (SI)."""
        return {
            "pass": self.passed,
            "checks": [c._asdict() | {"pass": c.passed} for c in self.checks],
        }


def verdict(stats: TimingStats, targets: Targets = Targets()) -> Verdict:
    """Judge a loop's timing against ``targets``.

    A loop that served no step fails every check (its figures are NaN).

    Examples
    --------
    >>> from motosim.rt.loop import timing_stats
    >>> import numpy as np
    >>> stats = timing_stats(1000.0, np.full(99, 20e-6), np.full(99, 5e-6), periods=100,
    ...                      missed=1)
    >>> [c.passed for c in verdict(stats).checks]
    [True, False, True]
    """
    period = 1.0 / stats.rate
    missed = stats.miss_ratio if stats.served else float("nan")
    return Verdict(
        (
            Check("wake-up p99", stats.wake_p99, targets.wake_p99, "us"),
            Check("missed deadlines", missed, targets.missed, "%"),
            Check("compute p99", stats.compute_p99, targets.compute_share * period, "us"),
        )
    )


_PRIVILEGE_HELP = "(the real-time guide: Setting up the lab PC)"


def _late_advice(stats: TimingStats, asked: bool, privileges: Sequence[Privilege]) -> str:
    """Why a loop that missed deadlines was late, and what to do (``asked``: whether
    --fifo, --cpu and --mlock were all given)."""
    share = (
        f"{100.0 * stats.miss_ratio:.1f} % of the deadlines were missed: this PC woke the loop late"
    )
    refused = [p.name for p in privileges if not p.applied]
    if refused:
        return (
            f"{share}; refused: {', '.join(refused)}: give the process the rights {_PRIVILEGE_HELP}"
        )
    if not asked:
        return (
            f"{share}; check it with motosim rt-check and give --fifo 80 --cpu 1 --mlock "
            f"{_PRIVILEGE_HELP}"
        )
    return (
        f"{share} under --fifo, --cpu and --mlock: other work shares the loop's CPU; check "
        "this PC with motosim rt-check and keep that CPU for the loop (isolcpus, the rig on "
        f"another CPU) {_PRIVILEGE_HELP}"
    )


def advice(
    stats: TimingStats,
    fault: str,
    *,
    asked_all: bool,
    privileges: Sequence[Privilege] = (),
    bus: str = "",
) -> list[str]:
    """What a real-time run's timing and safety ``fault`` (its name) point to, one line each
    (none: nothing); ``asked_all``: whether --fifo, --cpu and --mlock were all given,
    ``privileges`` those applied or refused, ``bus`` the run's ``--bus``.

    Examples
    --------
    >>> from motosim.rt.loop import timing_stats
    >>> import numpy as np
    >>> quiet = timing_stats(1000.0, np.zeros(10), np.zeros(10), periods=10, missed=0)
    >>> advice(quiet, "WATCHDOG", asked_all=True)[0][:46]
    "the drive's status frames stopped coming: the "
    """
    late = stats.miss_ratio > 0.01
    lines = []
    if fault == "NO_DRIVE":
        lines.append(
            f"no status frame came from the drive: is motosim rig (or the drive) running on "
            f"--bus {bus}, the same bus and multicast group as this run?"
        )
    elif fault == "WATCHDOG" and not late:
        lines.append(
            "the drive's status frames stopped coming: the rig or the bus, not this loop "
            "(did motosim rig end or stall? its --duration counts from its own start; on a "
            "CAN bus: the cable, the termination, the drive's power)"
        )
    elif fault == "TORQUE_SENSOR":
        lines.append(
            'the scenario reads a torque sensor ([estimator] name = "torque_sensor") and '
            "its HB_TORQUE frames stopped or never came: does the drive send them (motosim "
            "rig does for such a scenario)?"
        )
    if late:
        lines.append(_late_advice(stats, asked_all, privileges))
    return lines
