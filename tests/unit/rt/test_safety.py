"""The safety stage: each protection and each fault observed, time to zero counted in periods."""

import itertools
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from motosim.errors import MotosimError
from motosim.params import load_parameters
from motosim.rt.safety import Fault, SafetyLimits, SafetyStage, State

HB = load_parameters("simacom_handlebar", "handlebar")

LIMITS = SafetyLimits(
    max_current=20.0,
    max_slew=1e6,  # no slew limit unless a test asks for one
    max_speed=5.0,
    speed_band=5.0,
    soft_stop=0.5,
    hard_stop=0.8,
    end_stop_gain=40.0,
    hands_off_torque=0.0,
    hands_off_time=0.2,
    hands_off_gain=0.25,
)


class Driver:
    """Feeds a stage fresh status frames and steps it, as the loop does."""

    def __init__(
        self,
        limits: SafetyLimits = LIMITS,
        rate: float = 1000.0,
        *,
        handlebar: bool = False,
        periods_per_frame: int = 1,
    ) -> None:
        self.stage = SafetyStage(
            limits,
            dt=1.0 / rate,
            handlebar=HB if handlebar else None,
            periods_per_frame=periods_per_frame,
        )
        self.counter = 0

    def period(self, command: float = 10.0, *, frame: bool = True, **kw: float) -> float:
        if frame:
            self.counter = (self.counter + 1) % 15  # E2E Profile 1's counter, 0 to 14
            self.stage.status_frame(checksum_ok=True, counter=self.counter, drive_fault=False)
        args = {"theta": 0.0, "omega": 0.0, "tau_hat": 5.0} | kw
        return self.stage.step(command, **args)

    def running(self) -> "Driver":
        self.stage.enable()
        k = 0
        while self.stage.state != State.RUNNING:  # the angle moves: no frozen sensor
            k += 1
            self.period(theta=1e-3 * (k % 2))
        assert self.period() == 10.0
        return self


def test_fade_in_takes_half_a_second_on_every_enable() -> None:
    d = Driver(rate=100.0)
    d.stage.enable()
    out = [d.period() for _ in range(60)]
    assert out[0] == pytest.approx(10.0 * 0.02) and out[49] == pytest.approx(10.0)
    assert all(b >= a for a, b in itertools.pairwise(out))
    d.stage.request_stop()  # fade-out, then idle
    out = [d.period() for _ in range(60)]
    assert out[0] == pytest.approx(9.8) and out[49] == 0.0 and d.stage.state == State.IDLE
    d.stage.enable()
    assert d.period() == pytest.approx(0.2)  # fades in again


@pytest.mark.parametrize("rate", [100.0, 1000.0])
def test_watchdog_trips_within_three_periods(rate: float) -> None:
    d = Driver(rate=rate).running()
    out = [d.period(frame=False) for _ in range(3)]
    assert out[:2] == [10.0, 10.0] and out[2] == 0.0
    assert d.stage.fault == Fault.WATCHDOG and "3 periods" in d.stage.describe()
    assert d.period() == 0.0  # latched, even with frames back


def test_stale_or_duplicated_frames_do_not_feed_the_watchdog() -> None:
    d = Driver().running()
    for _ in range(2):
        assert not d.stage.status_frame(checksum_ok=True, counter=d.counter, drive_fault=False)
        assert d.period(frame=False) == 10.0
    assert not d.stage.status_frame(checksum_ok=True, counter=d.counter, drive_fault=False)
    assert d.period(frame=False) == 0.0 and d.stage.fault == Fault.WATCHDOG
    assert d.stage.frames_stale == 3


def test_lost_frames_are_counted_not_faults() -> None:
    # two frames lost on the bus, two periods without a frame: Profile 1's tolerance widened
    # by one per period takes the counter's step of 3
    d = Driver().running()
    for _ in range(2):
        d.counter += 1
        assert d.period(frame=False) == 10.0
    assert d.period() == 10.0 and d.stage.frames_lost == 2


@pytest.mark.parametrize(
    ("fault", "inject"),
    [
        (Fault.CHECKSUM, lambda s: s.status_frame(checksum_ok=False, counter=9, drive_fault=False)),
        (
            Fault.DRIVE_FAULT,
            lambda s: s.status_frame(checksum_ok=True, counter=9, drive_fault=True),
        ),
        (Fault.ESTOP_CAN, lambda s: s.estop_frame(checksum_ok=True, pressed=True)),
        (Fault.CHECKSUM, lambda s: s.estop_frame(checksum_ok=False, pressed=False)),
        (Fault.ESTOP_KEY, lambda s: s.trip(Fault.ESTOP_KEY)),
    ],
)
def test_a_fault_frame_zeroes_the_command_in_the_same_period(fault: Fault, inject: object) -> None:
    d = Driver(LIMITS.__class__(**{**_fields(LIMITS), "max_slew": 100.0})).running()
    inject(d.stage)  # type: ignore[operator]
    assert d.period(frame=False) == 0.0  # no slew limit on the way down
    assert d.stage.state == State.FAULT and d.stage.fault == fault


@pytest.mark.parametrize(
    "bad", [{"command": math.nan}, {"theta": math.inf}, {"omega": -math.inf}, {"tau_hat": math.inf}]
)
def test_non_finite_values_zero_the_command(bad: dict[str, float]) -> None:
    d = Driver().running()
    assert d.period(**bad) == 0.0 and d.stage.fault == Fault.NON_FINITE


def test_beyond_the_hard_stop_is_a_fault() -> None:
    d = Driver().running()
    assert d.period(theta=-0.81) == 0.0 and d.stage.fault == Fault.END_STOP


def test_soft_end_stop_drops_the_outward_push_and_pulls_back() -> None:
    d = Driver().running()
    assert d.period(10.0, theta=0.6) == pytest.approx(-40.0 * 0.1)  # 0.1 rad past 0.5
    assert d.period(-3.0, theta=0.6) == pytest.approx(-3.0 - 4.0)  # inward push kept
    assert d.period(-10.0, theta=-0.55) == pytest.approx(40.0 * 0.05)


@given(
    command=st.floats(-20.0, 20.0),
    omega=st.floats(-30.0, 30.0),
)
def test_the_speed_limiter_only_ever_reduces_the_command(command: float, omega: float) -> None:
    d = Driver().running()
    out = d.period(command, omega=omega)
    assert abs(out) <= abs(command) and out * command >= 0.0
    if abs(omega) <= LIMITS.max_speed or command * omega <= 0.0:
        assert out == command
    if abs(omega) >= LIMITS.max_speed + LIMITS.speed_band and command * omega > 0.0:
        assert out == 0.0


def test_clamp_and_slew_rate() -> None:
    d = Driver(LIMITS.__class__(**{**_fields(LIMITS), "max_slew": 1000.0}), rate=1000.0)
    d.stage.enable()
    for _ in range(600):
        d.period(0.0)
    out = [d.period(100.0) for _ in range(30)]
    assert out[0] == pytest.approx(1.0) and out[9] == pytest.approx(10.0)  # 1000 A/s
    assert max(out) == 20.0  # clamped


def test_hands_off_reduces_the_gain_until_the_rider_holds_again() -> None:
    lim = LIMITS.__class__(**{**_fields(LIMITS), "hands_off_torque": 0.5})
    d = Driver(lim, rate=100.0).running()
    out = [d.period(tau_hat=0.1) for _ in range(25)]
    assert out[18] == 10.0 and out[19] == pytest.approx(2.5) and d.stage.hands_off  # 0.2 s
    # the rider takes the handlebar: the whole command at once (within the slew limit)
    assert d.period(tau_hat=2.0) == 10.0 and not d.stage.hands_off


def test_clear_then_enable_fades_in_again() -> None:
    d = Driver().running()
    d.stage.trip(Fault.ESTOP_KEY)
    d.stage.enable()  # ignored while latched
    assert d.period() == 0.0
    d.stage.clear()
    d.stage.enable()
    assert d.period() == pytest.approx(10.0 * 0.002)


def test_watchdog_waits_while_idle() -> None:
    d = Driver()
    for _ in range(10):
        assert d.period(frame=False) == 0.0
    assert d.stage.fault == Fault.NONE


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("max_current", 0.0),
        ("max_slew", math.nan),
        ("hard_stop", 0.4),
        ("hands_off_gain", 1.5),
        ("watchdog_periods", 0),
        ("watchdog_periods", True),  # a TOML true is no count of periods
        ("watchdog_periods", 2.0),
        ("end_stop_gain", -1.0),
    ],
)
def test_bad_limits_are_refused(key: str, value: float) -> None:
    with pytest.raises(MotosimError, match=key):
        SafetyLimits(**{**_fields(LIMITS), key: value})


def _fields(limits: SafetyLimits) -> dict[str, float]:
    return {name: getattr(limits, name) for name in SafetyLimits.__dataclass_fields__}


@pytest.mark.parametrize(("rate", "frozen_angle"), [(100.0, 0.05), (1000.0, 0.05), (1000.0, 0.2)])
def test_frozen_sensor_trips_when_a_free_handlebar_would_have_turned(
    rate: float, frozen_angle: float
) -> None:
    # frozen_angle: the default 0.05 rad, and a scenario's [realtime.safety] frozen_angle
    limits = SafetyLimits(**{**_fields(LIMITS), "frozen_angle": frozen_angle})
    d = Driver(limits, rate=rate, handlebar=True).running()
    # a rider holding the handlebar still against a steady 10 A (30 N*m) is legitimate
    assert all(d.period(10.0, theta=0.1) == 10.0 for _ in range(round(5 * rate)))
    # the command moves by 3 A (9 N*m) and the angle stands still: a free handlebar of
    # Table I (beta_eq = 13.956 N*m*s/rad, beta_s = 1.734 N*m, N k_t = 3 N*m/A) turns at
    # (9 - 2 beta_s) / beta_eq = 0.396 rad/s beyond the dead band, so 0.05 rad after
    # 0.126 s (0.2 rad after 0.505 s); the monitor uses the current sent the period before:
    # one period later
    speed = (3.0 * HB.torque_per_amp - 2.0 * HB.beta_s) / HB.beta_eq
    expected = math.floor(frozen_angle / (speed / rate)) + 2
    out = [d.period(13.0, theta=0.1) for _ in range(expected + 5)]
    first_zero = out.index(0.0) + 1
    assert first_zero == expected and d.stage.fault == Fault.FROZEN_SENSOR
    assert all(v == 13.0 for v in out[: first_zero - 1]) and not any(out[first_zero - 1 :])
    assert "frozen angle sensor" in d.stage.describe()


def test_frozen_sensor_monitor_accepts_changes_within_friction_and_a_moving_angle() -> None:
    d = Driver(handlebar=True).running()
    # a change of 1 A (3 N*m) stays within twice the dry friction (3.47 N*m): a handlebar
    # held in its friction band need not move
    assert all(d.period(11.0, theta=0.1) == 11.0 for _ in range(5000))
    # a change of 5 A with the angle moving by one count every 20 ms: each change restarts
    # the monitor (0.02 s at 0.85 rad/s beyond the band is 0.017 rad < 0.05 rad)
    count = 2 * math.pi / 2**14
    for k in range(5000):
        assert d.period(16.0, theta=0.1 + count * (k // 20)) == 16.0
    assert d.stage.fault == Fault.NONE and d.stage.free_turn < 0.05


def test_frozen_sensor_monitor_rests_during_a_stops_fade_out() -> None:
    # a steady turn held at 10 A (30 N*m), then a stop: the command fades to zero over
    # 0.5 s with the angle still, which would be a 0.4 rad turn of a free handlebar
    d = Driver(handlebar=True).running()
    assert all(d.period(10.0, theta=0.1) == 10.0 for _ in range(1000))
    d.stage.request_stop()
    out = [d.period(10.0, theta=0.1) for _ in range(600)]
    assert out[-1] == 0.0 and d.stage.state == State.IDLE and d.stage.fault == Fault.NONE


def test_the_scale_told_to_the_stack_is_the_share_the_stage_passes() -> None:
    # what the stack's estimator is told the drive will carry (the fade and the hands-off
    # gain): the stage's output over its command, in every period but the one in which
    # the hands-off flag itself changes (decided on that period's estimate)
    lim = LIMITS.__class__(**{**_fields(LIMITS), "hands_off_torque": 0.5})
    d = Driver(lim, rate=100.0)
    assert d.stage.scale == 0.0 and d.period(command=2.0) == 0.0  # idle: nothing passes
    d.stage.enable()
    flips = 0
    for k in range(120):  # the fade-in, the rider holding, then nobody (hands-off at 0.2 s)
        predicted, before = d.stage.scale, d.stage.hands_off
        out = d.period(command=2.0, tau_hat=5.0 if k < 80 else 0.0, theta=1e-3 * (k % 2))
        if d.stage.hands_off != before:
            flips += 1
            continue
        assert out == pytest.approx(2.0 * predicted), k
    assert flips == 1 and d.stage.hands_off and d.stage.scale == pytest.approx(0.25)


def test_an_older_frame_after_a_newer_is_not_used() -> None:
    # A frame whose counter is behind the last one (delivered out of order) is not fresh and
    # not counted as 14 lost frames: Profile 1's WRONGSEQUENCE. Each of the three receive
    # cycles widens the tolerance by one: the drive's next frame may be 5 on (4 lost).
    d = Driver().running()
    newest = d.counter
    for back in (1, 2, 8):
        older = (newest - back) % 15
        assert not d.stage.status_frame(checksum_ok=True, counter=older, drive_fault=False)
    assert d.stage.frames_stale == 3 and d.stage.frames_lost == 0
    assert d.stage.status_frame(checksum_ok=True, counter=(newest + 5) % 15, drive_fault=False)
    assert d.stage.frames_lost == 4


@pytest.mark.parametrize(("lost", "first", "seen"), [(8, True, 8), (15, False, 0)])
def test_a_long_gap_is_taken_up_again(lost: int, first: bool, seen: int) -> None:
    # After 8 frames lost (8 periods without a frame: a watchdog of 20 frames holds them)
    # the counter has stepped 9 ahead: Profile 1's tolerance, widened by the 8 receive
    # cycles without a frame, takes it at once (OKSOMELOST). After more than 13 cycles
    # without a new counter it may have come round (15 values; 15 lost: one step on, the
    # loss unseen): the first frame is SYNC, not used, the next one OK.
    d = Driver(SafetyLimits(**{**_fields(LIMITS), "watchdog_periods": 20})).running()
    start = d.counter
    for _ in range(lost):
        assert d.period(frame=False) == 10.0
    fresh = []
    for k in range(lost + 1, lost + 10):
        counter = (start + k) % 15
        fresh.append(d.stage.status_frame(checksum_ok=True, counter=counter, drive_fault=False))
        assert d.stage.step(10.0, theta=0.0, omega=0.0, tau_hat=5.0) == 10.0
    assert fresh == [first] + [True] * 8
    assert d.stage.frames_lost == seen and d.stage.frames_stale == 0
    assert d.stage.fault == Fault.NONE


@pytest.mark.parametrize("same_period", [False, True])
def test_two_older_frames_after_a_newer_are_refused(same_period: bool) -> None:
    # Frames 8 and 9 delivered late after 10 (in two periods, or in one): both older, both
    # refused (WRONGSEQUENCE, the last counter kept), the drive's next frame 11 is one step
    # on.
    d = Driver(SafetyLimits(**{**_fields(LIMITS), "watchdog_periods": 20})).running()
    newest = d.counter
    fresh = []
    for back in (2, 1):
        older = (newest - back) % 15
        fresh.append(d.stage.status_frame(checksum_ok=True, counter=older, drive_fault=False))
        if not same_period:
            d.period(frame=False)
    assert fresh == [False, False]
    assert d.period() == 10.0  # newest + 1
    assert d.stage.frames_stale == 2 and d.stage.frames_lost == 0


@pytest.mark.parametrize(("periods_per_frame", "frames"), [(1, 3), (10, 3), (1, 12)])
def test_a_gateway_replaying_its_last_frames_trips_the_watchdog(
    periods_per_frame: int, frames: int
) -> None:
    # The drive is gone and a gateway replays its last three frames (8, 9, 10, 8, ...), one
    # per frame period: none is valid, and the watchdog trips after its frame periods as
    # for a silent bus. A watchdog of up to 12 frames trips: Profile 1's tolerance, widened
    # by one per cycle while nothing is taken, takes the replayed 8 at its 13th frame.
    limits = SafetyLimits(**{**_fields(LIMITS), "watchdog_periods": frames})
    d = Driver(limits, periods_per_frame=periods_per_frame).running()
    newest = d.counter
    replay = itertools.cycle([(newest - 2) % 15, (newest - 1) % 15, newest])
    out, accepted = [], 0
    for k in range(1, 200 * periods_per_frame + 1):
        if k % periods_per_frame == 0:
            counter = next(replay)
            accepted += d.stage.status_frame(checksum_ok=True, counter=counter, drive_fault=False)
        out.append(d.stage.step(10.0, theta=0.0, omega=0.0, tau_hat=5.0))
        if d.stage.fault != Fault.NONE:
            break
    watchdog = frames * periods_per_frame
    assert accepted == 0 and d.stage.fault == Fault.WATCHDOG
    assert out == [10.0] * (watchdog - 1) + [0.0]


def test_an_older_frame_then_the_next_one_is_no_long_gap() -> None:
    # one older frame delivered late, then the drive's next frame: the older one refused,
    # the next one taken as one step after the newest (not as a counter taken up again)
    d = Driver().running()
    newest = d.counter
    older, following = (newest - 3) % 15, (newest + 1) % 15
    assert not d.stage.status_frame(checksum_ok=True, counter=older, drive_fault=False)
    assert d.stage.status_frame(checksum_ok=True, counter=following, drive_fault=False)
    assert d.stage.frames_lost == 0 and d.stage.frames_stale == 1
    # and a frame repeated twice is no counter going on
    for _ in range(2):
        assert not d.stage.status_frame(checksum_ok=True, counter=following, drive_fault=False)


@pytest.mark.parametrize("lost", [7, 9, 13])
def test_a_watchdog_longer_than_the_counters_window_is_kept(lost: int) -> None:
    # watchdog_periods = 20 frames (a lab's lossy bus): a burst of 7 to 13 frames lost must
    # not trip it, however the counter jumped (14 lost: see the long gap's test)
    d = Driver(SafetyLimits(**{**_fields(LIMITS), "watchdog_periods": 20}), rate=100.0)
    d.running()
    for _ in range(lost):  # the frames lost: their counts are used by the drive
        d.counter = (d.counter + 1) % 15
        assert d.period(frame=False) == 10.0
    out = [d.period() for _ in range(20)]
    assert out == [10.0] * 20 and d.stage.fault == Fault.NONE
    assert d.stage.frames_lost == lost


def test_a_drive_fault_counts_even_in_a_frame_not_used() -> None:
    # a drive that restarts its counter (read as an older frame) while reporting a fault:
    # the fault trips at once, not after the counter is taken up again
    d = Driver().running()
    older = (d.counter - 3) % 15
    assert not d.stage.status_frame(checksum_ok=True, counter=older, drive_fault=True)
    assert d.stage.fault == Fault.DRIVE_FAULT and d.period(frame=False) == 0.0


@pytest.mark.parametrize("skipped", [1, 2, 5, 50])
def test_deadlines_a_late_loop_skipped_count_for_the_watchdog(skipped: int) -> None:
    # The watchdog promises zero torque once no valid status frame came for
    # watchdog_periods (3) periods of the loop. A loop that is late skips deadlines (it
    # does not step then): the drive's silence meanwhile counts, so the first step after
    # 3 or more periods of silence sends zero (counting only the steps, a stall of 50
    # periods would leave the stale command on for 2 more periods).
    d = Driver(rate=1000.0)
    d.stage.enable()
    t = 0.0
    for _ in range(600):  # the fade-in, with a status frame in every period
        d.period(now=t, theta=1e-3 * (round(t * 1e3) % 2))
        t += 1e-3
    assert d.stage.state == State.RUNNING
    t += skipped * 1e-3  # the deadlines skipped, without a status frame
    out = d.period(frame=False, now=t)
    if skipped + 1 >= 3:
        assert out == 0.0 and d.stage.fault == Fault.WATCHDOG
    else:
        assert out == 10.0 and d.period(frame=False, now=t + 1e-3) == 0.0


def test_a_status_frame_after_skipped_deadlines_feeds_the_watchdog() -> None:
    # a loop late by 10 periods whose drive kept sending: the frames read after the stall
    # are fresh, the watchdog does not trip
    d = Driver(rate=1000.0)
    d.stage.enable()
    for k in range(600):
        d.period(now=k * 1e-3, theta=1e-3 * (k % 2))
    assert d.period(now=0.610) == 10.0 and d.stage.fault == Fault.NONE


def test_a_stop_goes_idle_only_once_the_command_sent_is_zero() -> None:
    # A slew-rate limit slower than the fade (5 A/s against 10 A over 0.5 s): the fade-out
    # promises a command sent that comes down to zero, never a step; the stage stays
    # STOPPING (the drive enabled) until it is zero. Before, it went IDLE with the
    # envelope at 0 while 7.5 A were sent, and the next period stepped to 0 A.
    d = Driver(SafetyLimits(**{**_fields(LIMITS), "max_slew": 5.0}), rate=100.0)
    d.stage.enable()
    for _ in range(400):  # 10 A reached at 0.05 A per period
        d.period()
    assert d.stage.state == State.RUNNING and d.period() == 10.0
    d.stage.request_stop()
    out, states = [], []
    while d.stage.state != State.IDLE and len(out) < 1000:
        out.append(d.period())
        states.append(d.stage.state)
    assert out[-1] == 0.0 and all(s == State.STOPPING for s in states[:-1])
    steps = [a - b for a, b in itertools.pairwise([10.0, *out])]
    assert all(0.0 <= step <= 0.05 + 1e-12 for step in steps)  # 5 A/s at 100 Hz
    assert len(out) == 200 and d.period() == 0.0  # 10 A at 5 A/s: 2 s


def test_hands_off_scales_the_stacks_command_not_the_end_stops_spring() -> None:
    # Hands-off detection reduces the feedback gain (the stack's command) while nobody
    # holds the handlebar; the soft end stop's spring is a limit of its own and must keep
    # its full strength then, when nothing else holds the handlebar back (scaled with the
    # command, it would be 25 % here and nothing with hands_off_gain = 0).
    for gain in (0.25, 0.0):
        lim = SafetyLimits(**{**_fields(LIMITS), "hands_off_torque": 0.5, "hands_off_gain": gain})
        d = Driver(lim, rate=100.0).running()
        for _ in range(25):  # 0.25 s without the rider's torque: hands off after 0.2 s
            d.period(tau_hat=0.1)
        assert d.stage.hands_off
        assert d.period(10.0, theta=0.3, tau_hat=0.1) == pytest.approx(10.0 * gain)
        # 0.2 rad beyond the soft stop: the spring's 40 A/rad whole, the push out dropped
        assert d.period(0.0, theta=0.7, tau_hat=0.1) == pytest.approx(-8.0)
        assert d.period(10.0, theta=0.7, tau_hat=0.1) == pytest.approx(-8.0)
        assert d.period(-4.0, theta=0.7, tau_hat=0.1) == pytest.approx(-4.0 * gain - 8.0)


def test_a_period_without_an_estimate_keeps_the_hands_off_gain() -> None:
    # tau_hat NaN is "no estimate this period": it must not give the full gain back while
    # nobody holds the handlebar: the reduced gain is not skipped with the detection
    lim = SafetyLimits(**{**_fields(LIMITS), "hands_off_torque": 0.5})
    d = Driver(lim, rate=100.0).running()
    for _ in range(25):
        d.period(tau_hat=0.1)
    assert d.stage.hands_off and d.period(tau_hat=math.nan) == pytest.approx(2.5)
    assert d.stage.hands_off and d.stage.fault == Fault.NONE


@given(
    command=st.floats(-20.0, 20.0),
    theta=st.floats(-0.79, 0.79),
    speed=st.floats(LIMITS.max_speed + LIMITS.speed_band, 100.0),
    sign=st.sampled_from([-1.0, 1.0]),
)
def test_nothing_the_stage_sends_pushes_a_handlebar_too_fast_faster(
    command: float, theta: float, speed: float, sign: float
) -> None:
    # At max_speed + speed_band and beyond, the speed limiter promises no torque in the
    # direction of motion, at any angle: beyond the soft stop the end stop's spring pulls
    # back, and on a handlebar already returning too fast it must not push it faster
    # (the spring added after the limiter would give 40 A/rad * 0.29 rad = 11.6 A with a
    # handlebar at 0.79 rad coming back at 100 rad/s).
    omega = sign * speed
    d = Driver().running()
    out = d.period(command, theta=theta, omega=omega)
    assert out * omega <= 0.0
    still = Driver().running().period(command, theta=theta, omega=0.0)
    assert abs(out) <= abs(still) and out * still >= 0.0  # it only ever reduces


@pytest.mark.parametrize("periods_per_frame", [math.nan, 2.5, 0, True])
def test_periods_per_frame_must_be_a_whole_count(periods_per_frame: object) -> None:
    # the watchdog waits watchdog_periods * periods_per_frame periods: a NaN made that
    # count one it never reached (the watchdog off) and was accepted, as was 2.5
    with pytest.raises(MotosimError, match="periods_per_frame"):
        SafetyStage(LIMITS, dt=1e-3, periods_per_frame=periods_per_frame)  # type: ignore[arg-type]


def test_the_watchdog_waits_its_frame_periods_under_a_faster_loop() -> None:
    # 100 Hz status frames under a 1 kHz loop: 3 frame periods are 30 loop periods
    stage = SafetyStage(LIMITS, dt=1e-3, periods_per_frame=np.int64(10))  # type: ignore[arg-type]
    assert stage.watchdog_periods == 30


def test_clear_starts_the_frozen_sensor_monitor_afresh() -> None:
    # After a FROZEN_SENSOR fault is cleared (a new sensor fitted, the handlebar at rest at
    # the same count), the monitor must start from the new fade-in's torque, not compare it
    # with the torque of the fault's time: before, the first period of the fade-in tripped
    # it again (0 A now against 13 A then, with the turn already beyond frozen_angle).
    d = Driver(handlebar=True).running()
    for _ in range(1000):
        d.period(10.0, theta=0.1)
    for _ in range(300):
        d.period(13.0, theta=0.1)
    assert d.stage.fault == Fault.FROZEN_SENSOR
    d.stage.clear()
    d.stage.enable()
    out = [d.period(0.5, theta=0.1) for _ in range(600)]  # 1.5 N*m: within the dead band
    assert d.stage.fault == Fault.NONE and out[-1] == 0.5 and d.stage.free_turn == 0.0


def test_a_status_frame_in_the_watchdogs_last_period_keeps_it_quiet() -> None:
    # the boundary: two periods without status, a frame in the third: no trip; then three
    # periods without: the third sends zero (the watchdog's 3 periods, exactly)
    d = Driver(rate=1000.0).running()
    assert [d.period(frame=False) for _ in range(2)] == [10.0, 10.0]
    assert d.period() == 10.0 and d.stage.fault == Fault.NONE
    assert [d.period(frame=False) for _ in range(3)] == [10.0, 10.0, 0.0]


def test_the_alive_counter_wraps_round_without_a_loss() -> None:
    # Profile 1's counter runs 0 to 14: 13, 14, 0, 1 are four frames in a row, none lost,
    # none stale; 15 is no counter (refused, counted stale)
    stage = SafetyStage(LIMITS, dt=1e-3)
    fresh = [
        stage.status_frame(checksum_ok=True, counter=c, drive_fault=False) for c in (13, 14, 0, 1)
    ]
    assert fresh == [True] * 4 and stage.frames_lost == 0 and stage.frames_stale == 0
    assert not stage.status_frame(checksum_ok=True, counter=15, drive_fault=False)
    assert stage.frames_stale == 1


@pytest.mark.parametrize("late", [0, 15, 25])
def test_a_long_gap_is_taken_up_when_the_loop_is_late_as_the_frames_come_back(late: int) -> None:
    # 100 Hz status frames under a 1 kHz loop, frames 50..56 lost (7), the watchdog 9
    # frames: frame 57 is taken at once, its receive cycles counted from the frame
    # periods since frame 49. The loop is late by `late` periods as the frames come back:
    # they are read in the period after its skipped deadlines, which its step counts only
    # after them; the cycles are counted from the frame's `now`.
    limits = SafetyLimits(**{**_fields(LIMITS), "watchdog_periods": 9})
    stage = SafetyStage(limits, dt=1e-3, periods_per_frame=10)
    stage.enable()
    sent = [(10 * i + 3, i % 15) for i in range(120) if not 50 <= i < 57]  # period, counter
    previous, k, out = -1, 0, []
    while k < 1200:
        if k == 570:
            k += late  # the deadlines a late loop skipped as frame 57 (due at 573) comes
        for due, counter in sent:  # the frames come in order, read by the next period
            if previous < due <= k:
                stage.status_frame(
                    checksum_ok=True, counter=counter, drive_fault=False, now=k * 1e-3
                )
        out.append(stage.step(5.0, theta=0.0, omega=0.0, tau_hat=math.nan, now=k * 1e-3))
        previous, k = k, k + 1
    assert stage.fault == Fault.NONE and out[-1] == 5.0
    assert stage.frames_lost == 7 and stage.frames_stale == 0
