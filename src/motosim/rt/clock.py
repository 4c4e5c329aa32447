"""Clocks for the real-time loop: the machine's monotonic clock and a lock-step simulated one.

Every piece of :mod:`motosim.rt` takes its time from a :class:`Clock` passed in, never from
the ``time`` module directly, so that the same loop runs against the wall clock in a lab and
deterministically, one period at a time, in the tests (style rule: time is injected).

:class:`MonotonicClock` waits for an *absolute* deadline: it sleeps until shortly before it
(``spin`` seconds, 200 us by default) and then polls the clock until the deadline has passed.
The sleep alone wakes late by the scheduler's latency (tens of microseconds to milliseconds
under ``SCHED_OTHER``); the final spin trades a little CPU for a wake-up within a few
microseconds of the deadline. Deadlines are absolute, so late wake-ups never accumulate into
drift, which a relative ``sleep(period)`` per cycle does (ROS 2 issue ros2/rcl#289).
"""

import time
from collections.abc import Callable
from typing import Protocol

from motosim.errors import MotosimError

__all__ = ["Clock", "MonotonicClock", "SimulatedClock"]


class Clock(Protocol):
    """What the loop needs of a clock: the time [s] and a wait until an absolute time [s]."""

    def now(self) -> float:
        """The current time [s] (monotonic, arbitrary origin)."""
        ...

    def sleep_until(self, deadline: float) -> None:
        """Return at or after ``deadline`` [s] (at once if it has passed)."""
        ...


class MonotonicClock:
    """The machine's ``CLOCK_MONOTONIC`` with a hybrid sleep-then-spin wait.

    Parameters
    ----------
    spin : float
        Time before each deadline [s] spent polling the clock instead of sleeping, >= 0;
        0 sleeps all the way (lower CPU use, later wake-ups).

    Examples
    --------
    >>> clock = MonotonicClock(spin=200e-6)
    >>> t0 = clock.now()
    >>> clock.sleep_until(t0 + 1e-3)
    >>> clock.now() >= t0 + 1e-3
    True
    """

    __slots__ = ("_spin",)

    def __init__(self, *, spin: float = 200e-6) -> None:
        if not 0.0 <= spin < 1.0:
            raise MotosimError(f"spin = {spin!r} s: expected a time in [0, 1) s")
        self._spin = float(spin)

    @property
    def spin(self) -> float:
        """The spinning margin before each deadline [s]."""
        return self._spin

    def now(self) -> float:
        """The monotonic time [s]."""
        return time.monotonic()

    def sleep_until(self, deadline: float) -> None:
        """Sleep until ``spin`` before ``deadline`` [s], then poll until it has passed."""
        monotonic = time.monotonic
        remaining = deadline - monotonic() - self._spin
        if remaining > 0.0:
            time.sleep(remaining)
        while monotonic() < deadline:
            pass


class SimulatedClock:
    """A lock-step clock: ``sleep_until`` jumps the time to the deadline at once.

    Listeners (``listen``) are called with the new time each time it moves forward, before
    ``sleep_until`` returns: a virtual rig stepped this way advances its plant and delivers the
    frames due by then, so a loop and a rig in one thread run deterministically.

    Parameters
    ----------
    start : float
        The initial time [s].

    Examples
    --------
    >>> clock = SimulatedClock()
    >>> seen = []
    >>> clock.listen(seen.append)
    >>> clock.sleep_until(0.01)
    >>> clock.now(), seen
    (0.01, [0.01])
    """

    __slots__ = ("_listeners", "_t")

    def __init__(self, start: float = 0.0) -> None:
        self._t = float(start)
        self._listeners: list[Callable[[float], None]] = []

    def listen(self, callback: Callable[[float], None]) -> None:
        """Call ``callback(t)`` each time the clock moves forward to ``t`` [s]."""
        self._listeners.append(callback)

    def now(self) -> float:
        """The simulated time [s]."""
        return self._t

    def advance(self, dt: float) -> None:
        """Move the time forward by ``dt`` >= 0 [s] (e.g. to model compute time)."""
        if not dt >= 0.0:
            raise MotosimError(f"dt = {dt!r} s: expected a non-negative time")
        self.sleep_until(self._t + dt)

    def sleep_until(self, deadline: float) -> None:
        """Jump to ``deadline`` [s] if it is later than now, telling the listeners."""
        if deadline > self._t:
            self._t = deadline
            for callback in self._listeners:
                callback(deadline)
