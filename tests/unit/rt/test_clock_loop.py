"""The clocks, the fixed-period loop, the sample ring and the privileges (lock-step, untimed)."""

import gc
from collections.abc import Callable

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.rt.check import check_timing
from motosim.rt.clock import MonotonicClock, SimulatedClock
from motosim.rt.loop import WARM_LEAD, FramePacedLoop, RateLoop
from motosim.rt.privileges import apply_privileges, freeze_gc, pin_cpus, thaw_gc
from motosim.rt.ring import SampleRing


def test_monotonic_clock_never_returns_before_the_deadline() -> None:
    clock = MonotonicClock(spin=100e-6)
    for _ in range(5):
        deadline = clock.now() + 2e-4
        clock.sleep_until(deadline)
        assert clock.now() >= deadline


def test_simulated_clock_tells_listeners_only_when_time_moves_forward() -> None:
    clock = SimulatedClock(1.0)
    seen: list[float] = []
    clock.listen(seen.append)
    clock.sleep_until(0.5)  # in the past: no move
    clock.advance(0.25)
    assert seen == [1.25] and clock.now() == 1.25


def test_deadlines_are_absolute_and_do_not_drift() -> None:
    # A step that uses 40 % of each period must not push later deadlines back.
    clock = SimulatedClock()
    loop = RateLoop(1000.0, clock)
    starts: list[float] = []

    def step(k: int, t: float) -> bool:
        starts.append(clock.now())
        clock.advance(0.4e-3)
        return True

    assert loop.run(step, periods=1000) == 1000
    assert starts[-1] == pytest.approx(1.0, abs=1e-12)
    stats = loop.stats()
    assert stats.missed == 0 and stats.compute_max == pytest.approx(0.4e-3)


def test_overruns_are_skipped_and_counted_never_bunched() -> None:
    clock = SimulatedClock()
    loop = RateLoop(100.0, clock)
    called: list[int] = []

    def step(k: int, t: float) -> bool:
        called.append(k)
        assert clock.now() == pytest.approx(t)  # never run late, back to back
        if k == 3:
            clock.advance(0.025)  # 2.5 periods: deadlines 4 and 5 have passed
        return True

    loop.run(step, periods=10)
    assert called == [0, 1, 2, 3, 6, 7, 8, 9]
    stats = loop.stats()
    assert (stats.periods, stats.served, stats.missed) == (10, 8, 2)


def test_a_step_returning_false_or_stop_ends_the_loop() -> None:
    loop = RateLoop(100.0, SimulatedClock())
    assert loop.run(lambda k, t: k < 4, periods=100) == 5
    loop.stop()  # a stop asked before run() is forgotten at the start of the next run
    assert loop.run(lambda k, t: (loop.stop() if k == 1 else None) is None, periods=9) == 2


@pytest.mark.parametrize(("rate", "capacity"), [(0.0, 1), (float("nan"), 1), (10.0, 0)])
def test_loop_refuses_bad_settings(rate: float, capacity: int) -> None:
    with pytest.raises(MotosimError):
        RateLoop(rate, SimulatedClock(), capacity=capacity)


def test_check_timing_on_a_simulated_clock_is_exact() -> None:
    stats = check_timing(100.0, 1.0, clock=SimulatedClock())
    assert (stats.served, stats.missed, stats.wake_p999) == (100, 0, 0.0)
    assert gc.isenabled()


def test_ring_returns_rows_in_order_and_counts_what_it_lost() -> None:
    ring = SampleRing(8, 3)
    for k in range(5):
        ring.push(np.full(3, float(k)))
    first = ring.drain()
    for k in range(5, 20):
        ring.push(np.full(3, float(k)))
    second = ring.drain()
    assert first[:, 0].tolist() == [0, 1, 2, 3, 4]
    assert second[:, 2].tolist() == list(range(12, 20)) and ring.dropped == 7
    assert ring.drain().shape == (0, 3)


def test_privileges_are_reported_not_raised() -> None:
    refused = pin_cpus([10_000])
    assert not refused.applied and refused.detail
    assert apply_privileges(priority=0)[0].applied is False
    frozen = freeze_gc()
    try:
        assert frozen.applied and not gc.isenabled()
    finally:
        thaw_gc()
    assert gc.isenabled()


def _drive(clock: SimulatedClock, times: list[float]) -> Callable[[float], bool]:
    """A drive whose status frames come at ``times`` [s]: the wait of a bus-paced loop."""
    pending = iter(times)
    due = [next(pending)]

    def wait(until: float) -> bool:
        if due[0] <= until:
            clock.sleep_until(due[0])
            due[0] = next(pending, float("inf"))
            return True
        clock.sleep_until(until)
        return False

    return wait


def test_a_bus_paced_loop_steps_once_per_frame_whenever_it_comes() -> None:
    clock = SimulatedClock()
    frames = [0.010, 0.0203, 0.0299, 0.040]  # 100 Hz with 0.3 ms of jitter
    loop = FramePacedLoop(100.0, clock, _drive(clock, frames), timeout=0.03)
    seen: list[tuple[int, float]] = []
    assert loop.run(lambda k, t: seen.append((k, t)) is None, periods=4) == 4
    assert seen == list(enumerate(frames))
    stats = loop.stats()
    assert stats.missed == 0 and stats.wake_max == pytest.approx(0.3e-3)


def test_a_bus_paced_loop_still_steps_when_the_frames_stop() -> None:
    # the wait times out after the watchdog's time (3 frame periods): the step runs (the
    # caller's safety stage trips then) and the frame periods without a frame are missed
    clock = SimulatedClock()
    loop = FramePacedLoop(100.0, clock, _drive(clock, [0.01, 0.02]), timeout=0.03)
    seen: list[tuple[int, float]] = []
    loop.run(lambda k, t: seen.append((k, round(t, 9))) is None, periods=10)
    assert seen == [(0, 0.01), (1, 0.02), (4, 0.05), (7, 0.08)]  # none past the run
    stats = loop.stats()
    assert loop.timeouts == 3 and stats.gaps == 10 - len(seen) and stats.missed == 0


def test_a_bus_paced_loop_counts_the_frames_it_answered_late_apart_from_the_drive_s_gaps() -> None:
    # each frame's deadline is the next one. A step stalled 2.5 periods answers the frame of
    # 0.02 s after the one of 0.03 s is due (missed); the next period reads the frames of 0.03
    # and 0.04 s together and answers the newer (0.03 s missed, 0.04 s answered in time). The
    # drive's own gap (no frame at 0.07 s) is not the loop's miss.
    clock = SimulatedClock()
    due = [0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.08, 0.09]
    read = [0]

    def wait(until: float) -> bool:
        if read[0] < len(due) and due[read[0]] <= until:
            clock.sleep_until(due[read[0]])
            read[0] += 1
            return True
        clock.sleep_until(until)
        return False

    def step(k: int, t: float) -> bool:
        while read[0] < len(due) and due[read[0]] <= clock.now():  # the period's bus read
            read[0] += 1
        if k == 1:
            clock.advance(0.025)
        return True

    loop = FramePacedLoop(100.0, clock, wait, timeout=0.03, received=lambda: read[0])
    assert loop.run(step, periods=9) == 7
    stats = loop.stats()
    assert (stats.missed, stats.gaps, stats.periods) == (2, 1, 9)


@pytest.mark.parametrize(("rate", "timeout"), [(0.0, 0.03), (100.0, 0.0), (100.0, float("nan"))])
def test_bus_paced_loop_refuses_bad_settings(rate: float, timeout: float) -> None:
    with pytest.raises(MotosimError):
        FramePacedLoop(rate, SimulatedClock(), lambda until: True, timeout=timeout)


def test_the_warm_up_runs_just_before_each_deadline() -> None:
    clock = SimulatedClock()
    calls: list[tuple[float, float]] = []
    loop = RateLoop(100.0, clock, warm=lambda until: calls.append((clock.now(), until)))
    steps: list[float] = []
    assert loop.run(lambda k, t: steps.append(t) is None, periods=3) == 3
    assert [c[0] for c in calls] == pytest.approx([t - WARM_LEAD for t in steps])
    assert [c[1] for c in calls] == pytest.approx(steps)  # told the deadline to warm until
    assert steps == pytest.approx([0.01, 0.02, 0.03])  # the deadlines unchanged
