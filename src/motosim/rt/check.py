"""``rt-check``: how late this machine wakes a loop at a given rate (the first thing to run).

:func:`check_timing` runs an empty :class:`~motosim.rt.loop.RateLoop` for a while and returns
its timing statistics: the wake-up latency is what the scheduler, the kernel and the machine
(a VM's steal time) add on their own, before any stack step runs.
"""

from motosim.errors import MotosimError
from motosim.rt.clock import Clock
from motosim.rt.loop import RateLoop, TimingStats
from motosim.rt.privileges import freeze_gc, thaw_gc

__all__ = ["check_timing"]


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
