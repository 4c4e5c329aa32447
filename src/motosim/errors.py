"""Project exceptions.

Two kinds of failure, kept apart because a user acts differently on each:

- :class:`MotosimError`: invalid input, a parameter, an option, a file or a signal that the
  model cannot accept. Its message is one line that names the offending value and what was
  expected; the command line prints it and exits with code 2.
- :class:`MotosimWarning`: legal but implausible input (a handlebar inertia far from any real
  handlebar's, a speed outside the model's validated range, noise larger than the signal).
  The library emits it with :func:`warn` (the :mod:`warnings` machinery, so a script may
  filter or record it); the command line prints each as one line ``motosim: warning: ...``
  and goes on.
- :class:`RunFailedError`: the input was valid but the run did not succeed: the simulation
  diverged, the motorcycle fell, the loop faulted. The command line prints its one-line
  reason and exits with code 3; what the run computed until then is kept.
"""

import signal
import warnings
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = [
    "EXIT_BAD_INPUT",
    "EXIT_RUN_FAILED",
    "MotosimError",
    "MotosimWarning",
    "RunFailedError",
    "StopFlag",
    "stop_signals",
    "warn",
]

EXIT_BAD_INPUT = 2
"""Exit code of the command line for a :class:`MotosimError`."""
EXIT_RUN_FAILED = 3
"""Exit code of the command line for a :class:`RunFailedError`."""


def stop_signals() -> list[signal.Signals]:
    """The signals that stop a command as Ctrl-C does: SIGTERM and, where it exists, SIGHUP,
    less any this process was started with ignored (``nohup`` ignores SIGHUP so that a closed
    terminal does not stop the command: it keeps running).

    Examples
    --------
    >>> signal.SIGTERM in stop_signals()
    True
    """
    stops = [signal.SIGTERM, *([signal.SIGHUP] if hasattr(signal, "SIGHUP") else [])]
    return [sig for sig in stops if signal.getsignal(sig) is not signal.SIG_IGN]


class StopFlag:
    """A stop asked for by a signal, handed by the command to what writes its files.

    The command installs the signal handlers (SIGTERM, SIGHUP, Ctrl-C) and they call
    :meth:`request`; the writer (:class:`motosim.io.results.ResultWriter`) holds the stop
    while a block of rows goes to both files (:meth:`held`) and raises it at the next block
    (:meth:`check`), so a raise that landed where Python ignores exceptions (a finaliser, a
    weak-reference callback) still stops the run.
    """

    def __init__(self) -> None:
        self.name: str | None = None
        self.holding = False

    def request(self, name: str) -> None:
        """Remember the stop ``name`` (``"SIGTERM"``...); raise it at once unless held."""
        self.name = name
        if not self.holding:
            raise KeyboardInterrupt(name)

    def check(self) -> None:
        """Raise :class:`KeyboardInterrupt` if a stop was asked for."""
        if self.name is not None:
            raise KeyboardInterrupt(self.name)

    @contextmanager
    def held(self) -> Iterator[None]:
        """Within the block a stop is kept, not raised: a block of rows goes to both files or
        to neither (:meth:`check` raises it after)."""
        self.holding = True
        try:
            yield
        finally:
            self.holding = False


class MotosimError(ValueError):
    """Invalid input: a parameter, an option, a file or a signal that the model cannot accept."""


class RunFailedError(RuntimeError):
    """A valid run that failed: it diverged, fell over or faulted (one-line reason).

    Attributes
    ----------
    time : float or None
        Simulated or loop time of the failure [s], when known.
    """

    def __init__(self, reason: str, *, time: float | None = None) -> None:
        super().__init__(reason)
        self.time = time


class MotosimWarning(UserWarning):
    """Legal but implausible input: accepted, with a one-line warning naming the value, the
    typical range and why."""


def warn(message: str) -> None:
    """Emit a :class:`MotosimWarning` (one line) through :func:`warnings.warn`."""
    warnings.warn(" ".join(message.split()), MotosimWarning, stacklevel=3)
