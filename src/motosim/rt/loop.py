"""The fixed-period loop: absolute deadlines, overruns skipped and counted, timing recorded.

:class:`RateLoop` calls a step function once per period at the absolute deadlines
``t0 + k T``. A step that overruns (it ends after the next deadline), or a wake-up delayed
past it, does not make the loop run the missed steps back to back ("bunching", which would
send several commands to the drive at once): the deadlines that have passed are skipped and
counted as misses, and the loop resumes on the next deadline still ahead. This is the
"Ratekeeper" pattern of openpilot's ``common/realtime.py``.

:class:`FramePacedLoop` is the other way to pace the loop: by the drive's own status frame.
It blocks on the bus until the frame comes (a ``wait`` given by the caller, with a timeout)
and runs one step per frame, so that the stack's period is the drive's, without a second
clock beating against it. A wait that times out still runs a step (the caller's safety stage
trips its watchdog then), so a drive that stops sending cannot hold the loop.

The wake-up latency (time of wake-up minus deadline [s]) and the compute time of each step
[s] go into arrays preallocated before the first deadline; nothing inside the loop allocates
beyond Python's small floats, and nothing logs. :meth:`RateLoop.stats` summarises them once
the loop has ended.
"""

from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass

import numpy as np

from motosim.errors import MotosimError
from motosim.rt.clock import Clock

__all__ = ["WARM_LEAD", "FramePacedLoop", "RateLoop", "TimingStats", "timing_stats"]


@dataclass(frozen=True, slots=True)
class TimingStats:
    """Timing of a loop run.

    Attributes
    ----------
    rate : float
        The loop's rate [Hz].
    periods : int
        Deadlines that passed (served plus missed).
    served : int
        Steps run.
    missed : int
        Deadlines skipped because the loop was late.
    wake_p50, wake_p99, wake_p999, wake_max : float
        Wake-up latency after the deadline [s] (median, 99th, 99.9th percentile, maximum).
    compute_p50, compute_p99, compute_p999, compute_max : float
        Compute time of one step [s], same statistics.
    gaps : int
        A loop paced by the drive's frames (:class:`FramePacedLoop`): frame periods the
        drive left without a frame (its pace, not the loop's); 0 for a clock-paced loop.
    """

    rate: float
    periods: int
    served: int
    missed: int
    wake_p50: float
    wake_p99: float
    wake_p999: float
    wake_max: float
    compute_p50: float
    compute_p99: float
    compute_p999: float
    compute_max: float
    gaps: int = 0

    @property
    def miss_ratio(self) -> float:
        """Missed deadlines over all deadlines (0 when none passed)."""
        return self.missed / self.periods if self.periods else 0.0

    def as_dict(self) -> dict[str, float | int]:
        """The statistics as a flat dictionary (times in seconds), with ``miss_ratio``."""
        out: dict[str, float | int] = asdict(self)
        out["miss_ratio"] = self.miss_ratio
        return out


def timing_stats(
    rate: float, wake: np.ndarray, compute: np.ndarray, *, periods: int, missed: int, gaps: int = 0
) -> TimingStats:
    """Summarise wake-up latencies and compute times [s] of the served steps.

    Examples
    --------
    >>> s = timing_stats(100.0, np.zeros(3), np.full(3, 1e-4), periods=4, missed=1)
    >>> s.served, s.compute_max, s.miss_ratio
    (3, 0.0001, 0.25)
    """
    if wake.size == 0:
        nan = float("nan")
        return TimingStats(rate, periods, 0, missed, *(nan,) * 8, gaps=gaps)
    qs = (50.0, 99.0, 99.9)
    w = [float(x) for x in (*np.percentile(wake, qs), wake.max())]
    c = [float(x) for x in (*np.percentile(compute, qs), compute.max())]
    return TimingStats(
        rate, periods, int(wake.size), missed, w[0], w[1], w[2], w[3], c[0], c[1], c[2], c[3], gaps
    )


def _check_periods(periods: int) -> None:
    """Refuse a negative count of periods."""
    if periods < 0:
        raise MotosimError(f"periods = {periods!r}: expected a non-negative count")


WARM_LEAD = 50e-6
"""How long before a deadline the loop's ``warm`` is called [s]."""


class RateLoop:
    """Run a step at a fixed rate on absolute deadlines.

    Parameters
    ----------
    rate : float
        Steps per second [Hz], > 0.
    clock : Clock
        Where time comes from (:class:`~motosim.rt.clock.MonotonicClock` in a lab,
        :class:`~motosim.rt.clock.SimulatedClock` in tests).
    capacity : int
        Steps whose timing is kept (a ring: the last ``capacity`` steps are summarised).
    warm : callable, optional
        ``warm(deadline)``, called ``WARM_LEAD`` before each deadline (within the clock's
        spin: the wake-up is not delayed) to bring the step's code and data into the CPU's
        caches and keep them there until ``deadline`` [s]
        (:meth:`motosim.rt.run.RealtimeRunner.warm`); it must return before ``deadline``.
    woke : callable, optional
        For a step that waits for its deadline itself
        (:meth:`motosim.rt.run.RealtimeRunner.wait_period`: the wait's end, the bus read and
        the period in one compiled call): the loop then sleeps only until ``WARM_LEAD``
        before each deadline and calls the step, and ``woke()`` gives the time the step woke
        up on the clock [s] (:meth:`~motosim.rt.run.RealtimeRunner.woke`), for the wake-up
        latency and the compute time. ``warm`` is then not called.

    Examples
    --------
    >>> from motosim.rt.clock import SimulatedClock
    >>> clock = SimulatedClock()
    >>> loop = RateLoop(100.0, clock, capacity=16)
    >>> times = []
    >>> loop.run(lambda k, t: times.append(round(t, 6)) is None, periods=3)
    3
    >>> times
    [0.01, 0.02, 0.03]
    """

    def __init__(
        self,
        rate: float,
        clock: Clock,
        *,
        capacity: int = 1 << 17,
        warm: Callable[[float], object] | None = None,
        woke: Callable[[], float] | None = None,
    ) -> None:
        if not (np.isfinite(rate) and rate > 0.0):
            raise MotosimError(f"rate = {rate!r} Hz: expected a positive rate")
        if capacity < 1:
            raise MotosimError(f"capacity = {capacity!r}: expected at least 1 step")
        self._rate = float(rate)
        self._period = 1.0 / self._rate
        self._clock = clock
        self._wake = np.zeros(capacity)
        self._compute = np.zeros(capacity)
        self._served = 0
        self._missed = 0
        self._gaps = 0
        self._periods = 0
        self._stop = False
        self._warm = warm
        self._woke = woke

    def stop(self) -> None:
        """Ask the loop to end after the current step (safe from a signal handler)."""
        self._stop = True

    def run(self, step: Callable[[int, float], bool], *, periods: int) -> int:
        """Call ``step(k, t)`` once per period until it returns False, :meth:`stop` is
        called or ``periods`` (>= 0) pass; the number of steps run. ``k`` is the period's
        index (0, 1, ...; skipped indices are not called), ``t`` its time [s] on the clock:
        the deadline, the first one period from now (a frame-paced loop: the frame's
        arrival). The pacing (:meth:`_paces`) waits, records the timing and keeps the
        totals; this loop only calls the step."""
        _check_periods(periods)
        self._stop = False
        before = self._served
        for k, t in self._paces(periods):
            if not step(k, t):
                self._stop = True
        return self._served - before

    def _paces(self, periods: int) -> Iterator[tuple[int, float]]:
        """The periods of a run on the clock's deadlines: yields ``(k, deadline)`` when the
        step is due and records its timing once it has returned."""
        clock = self._clock
        now = clock.now
        sleep_until = clock.sleep_until
        warm = self._warm
        woken = self._woke
        wake, compute = self._wake, self._compute
        cap = wake.size
        period = self._period
        t0 = now() + period
        served = self._served
        missed = 0
        k = 0
        while k < periods and not self._stop:
            deadline = t0 + k * period
            if woken is not None:  # the step's own compiled wait ends at the deadline
                sleep_until(deadline - WARM_LEAD)
                yield k, deadline
                woke = woken()
            else:
                if warm is not None:
                    sleep_until(deadline - WARM_LEAD)
                    warm(deadline)
                sleep_until(deadline)
                woke = now()
                yield k, deadline
            done = now()
            slot = served % cap
            wake[slot] = woke - deadline
            compute[slot] = done - woke
            served += 1
            k += 1
            late = done - (t0 + k * period)
            if late >= 0.0:  # the next deadline has passed: skip it and any others passed
                skip = int(late // period) + 1
                missed += skip
                k += skip
        self._close(k, periods, missed, served)

    def _close(self, k: int, periods: int, missed: int, served: int) -> None:
        """Add a run's periods, misses and steps to the totals."""
        if k > periods:  # skipped deadlines past the end of the run are not misses
            missed -= k - periods
            k = periods
        self._missed += missed
        self._periods += k
        self._served = served

    def stats(self) -> TimingStats:
        """The timing of every run so far (the last ``capacity`` steps for the percentiles)."""
        n = min(self._served, self._wake.size)
        return timing_stats(
            self._rate,
            self._wake[:n],
            self._compute[:n],
            periods=self._periods,
            missed=self._missed,
            gaps=self._gaps,
        )


class FramePacedLoop(RateLoop):
    """Run a step each time the drive's status frame arrives (pacing by the bus).

    Each period the loop calls ``wait(until)``, which blocks until a status frame has arrived
    (True) or the clock reaches ``until`` [s] (False), then ``step(k, t)`` with ``t`` the time
    the wait returned. ``until`` is the last wake-up plus ``timeout`` (the watchdog's time),
    or plus ``first_timeout`` before the first frame. A timeout still runs the step (the
    caller's watchdog trips then) and ``k`` jumps over the frame periods without a frame.

    Each frame's deadline is the next one: the step that answers it must end within a frame
    period. Its :meth:`stats` are :class:`TimingStats` with these meanings: ``wake`` is the
    interval between two frames minus the nominal period (the drive's pace as the loop sees
    it: its jitter, negative for a frame early), ``compute`` the step's time, ``missed`` the
    frames that got no answer in time: a step longer than a frame period, and, given
    ``received``, every status frame read in a period that answered a newer one (the loop
    was late: it answers the newest frame, never a backlog one by one). ``gaps`` are the
    drive's: the frame periods without a frame (the periods that passed less the frames
    received, given ``received``; else those between two frames, a gap of ``n`` periods
    counting ``n - 1``).

    Parameters
    ----------
    rate : float
        The drive's status frame rate [Hz], > 0.
    clock : Clock
        The time.
    wait : callable
        ``wait(until) -> bool``, see above (``RealtimeRunner.wait_status``).
    timeout, first_timeout : float
        The longest wait for a frame [s], > 0, and for the first one.
    received : callable, optional
        ``received() -> int``: the status frames received so far, by the wait and the steps
        (``RealtimeRunner.status_frames``).
    capacity : int
        Steps whose timing is kept.

    Examples
    --------
    >>> from motosim.rt.clock import SimulatedClock
    >>> clock = SimulatedClock()
    >>> frames = iter([0.01, 0.02, 0.04, 0.05])  # a 100 Hz drive that lost its 3rd frame
    >>> def wait(until):
    ...     due = next(frames)
    ...     clock.sleep_until(min(due, until))
    ...     return due <= until
    >>> loop = FramePacedLoop(100.0, clock, wait, timeout=0.03)
    >>> ks = []
    >>> loop.run(lambda k, t: ks.append(k) is None, periods=5)
    4
    >>> ks, loop.stats().missed, loop.stats().gaps
    ([0, 1, 3, 4], 0, 1)
    """

    def __init__(
        self,
        rate: float,
        clock: Clock,
        wait: Callable[[float], bool],
        *,
        timeout: float,
        first_timeout: float | None = None,
        received: Callable[[], int] | None = None,
        capacity: int = 1 << 17,
    ) -> None:
        super().__init__(rate, clock, capacity=capacity)
        first = timeout if first_timeout is None else first_timeout
        if not (np.isfinite(timeout) and timeout > 0.0 and np.isfinite(first) and first > 0.0):
            raise MotosimError(
                f"timeout = {timeout!r} s, first_timeout = {first!r} s: expected positive times"
            )
        self._wait = wait
        self._received = received
        self._timeout = float(timeout)
        self._first_timeout = float(first)
        self._timeouts = 0

    @property
    def timeouts(self) -> int:
        """Waits that ended without a frame."""
        return self._timeouts

    def _paces(self, periods: int) -> Iterator[tuple[int, float]]:
        """The periods of a run paced by the frames: yields ``(k, t)`` once per frame (or
        timeout) and records its timing once the step has returned."""
        now = self._clock.now
        wait = self._wait
        received = self._received
        wake, compute = self._wake, self._compute
        cap = wake.size
        period = self._period
        served = self._served
        missed = gaps = timeouts = 0
        start = frames = received() if received is not None else 0
        k = 0
        last = now()
        limit = self._first_timeout
        first = True
        while k < periods and not self._stop:
            arrived = wait(last + limit)
            woke = now()
            if first and arrived:  # the first frame's arrival is not a period after anything
                gap, jitter, first = 1, 0.0, False
            else:
                gap = max(1, round((woke - last) / period))
                jitter = woke - last - gap * period
            if not arrived:
                timeouts += 1
            skip = gap - 1
            if k + skip >= periods:  # the run's last periods passed without a frame
                gaps += periods - k
                k = periods
                break
            gaps += skip
            k += skip
            slot = served % cap
            wake[slot] = jitter
            yield k, woke
            spent = now() - woke
            compute[slot] = spent
            if spent > period:  # the answer left after the next frame was due
                missed += 1
            if received is not None:  # frames read with a newer one got no answer of theirs
                read = received()
                if served > self._served:  # (the first step's were queued before the run)
                    missed += max(0, read - frames - (1 if arrived else 0))
                frames = read
            served += 1
            k += 1
            last = woke
            limit = self._timeout
        self._end(k, periods, missed, served, gaps, timeouts, frames - start)

    def _end(
        self,
        k: int,
        periods: int,
        missed: int,
        served: int,
        gaps: int,
        timeouts: int,
        frames: int,
    ) -> None:
        """Add a run's timeouts and gaps (the periods that passed less the ``frames``
        received, when they are counted) to the totals; close it (:meth:`_close`)."""
        if self._received is not None:
            gaps = max(0, k - frames)
        self._timeouts += timeouts
        self._gaps += gaps
        self._close(k, periods, missed, served)
