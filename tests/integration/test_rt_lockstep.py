"""The loop against the virtual rig through python-can's virtual bus, lock-step (untimed).

A :class:`SimulatedClock` moves one period at a time; at each deadline the rig first advances
its handlebar to that time and sends the status frames due, then the loop reads them, steps a
stack, guards the command and sends it. Everything is deterministic.
"""

import math
import re
from collections.abc import Iterator

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.params import load_parameters
from motosim.rt.clock import SimulatedClock
from motosim.rt.fused import LoopColumn as C
from motosim.rt.loop import FramePacedLoop, RateLoop
from motosim.rt.rig import LockstepLink, RigFaults, RigRider, RigSettings, VirtualRig
from motosim.rt.run import RealtimeRunner, RunSettings
from motosim.rt.safety import Fault, SafetyLimits, State

pytest.importorskip("can", reason="python-can is in the rt and dev dependency groups")
pytest.importorskip("cantools", reason="cantools is in the rt and dev dependency groups")

from motosim.io.can import CanLink, handlebar_codecs, open_link

HB = load_parameters("simacom_handlebar", "handlebar")
CODECS = handlebar_codecs()
LIMITS = SafetyLimits(
    max_current=20.0,
    max_slew=5000.0,
    max_speed=20.0,
    speed_band=10.0,
    soft_stop=1.0,
    hard_stop=1.4,
    end_stop_gain=50.0,
    hands_off_torque=0.0,
    hands_off_time=0.5,
    hands_off_gain=0.5,
)


class SpringStack:
    """A stand-in stack: a virtual spring i = -K theta [A], recording its input."""

    names = ("theta_in", "i_out")
    compiled_parts = None  # a stack in Python

    def __init__(self, gain: float) -> None:
        self.gain = gain
        self._row = np.zeros(2)
        self.resets: list[tuple[float, float]] = []

    def reset(self, theta: float, current: float) -> None:
        self.resets.append((theta, current))

    def step(
        self, theta_meas: float, i_meas: float, fresh: bool, scale: float, torque: float
    ) -> float:
        command = -self.gain * theta_meas
        self._row[:] = theta_meas, command  # names: theta_in, i_out
        return command

    def row(self) -> np.ndarray:
        return self._row


def _settings(rate: float, **kw: object) -> RigSettings:
    base: dict[str, object] = {
        "plant_rate": 10_000.0,
        "status_rate": rate,
        "encoder_bits": 14,
        "current_noise": 0.0,
        "max_current": 30.0,
    }
    return RigSettings(**(base | kw))  # type: ignore[arg-type]


_channels = iter(range(10**6))


@pytest.fixture
def links() -> Iterator[tuple[CanLink, CanLink]]:
    channel = f"virtual:lockstep{next(_channels)}"
    host, drive = open_link(channel), open_link(channel)
    yield host, drive
    host.close()
    drive.close()


def _held_rig(drive: CanLink, settings: RigSettings, seed: int, samples: int) -> VirtualRig:
    """The rig with a rider holding 3 N*m for ``samples`` plant sub-steps, then on."""
    rider = RigRider(np.full(samples, 3.0))
    return VirtualRig(HB, settings, CODECS, drive, rider, np.random.default_rng(seed))


def _run(
    links: tuple[CanLink, CanLink],
    rate: float,
    seconds: float,
    *,
    rider: float = 0.0,
    gain: float = 20.0,
    **rig: object,
) -> tuple[RealtimeRunner, VirtualRig, np.ndarray]:
    host, drive = links
    settings = _settings(rate, **rig)
    tau = np.full(round(seconds * settings.plant_rate) + 1, rider)
    vrig = VirtualRig(HB, settings, CODECS, drive, RigRider(tau), np.random.default_rng(0))
    runner = RealtimeRunner(SpringStack(gain), host, CODECS, RunSettings(limits=LIMITS, rate=rate))
    clock = SimulatedClock()
    clock.listen(vrig.advance_to)
    RateLoop(rate, clock).run(runner.period, periods=round(seconds * rate))
    rows = runner.ring.drain()
    return runner, vrig, rows


def test_closed_loop_over_the_bus_settles_where_the_spring_balances_the_rider(
    links: tuple[CanLink, CanLink],
) -> None:
    runner, vrig, rows = _run(links, 1000.0, 2.0, rider=3.0, gain=20.0)
    # Eq. (5) at rest: tau_r + N k_t i_m = 0 within dry friction, with i_m = -K theta, so
    # theta = (tau_r +- beta_s) / (K N k_t); the encoder adds 2 pi / 2^14.
    stiffness = 20.0 * HB.torque_per_amp
    theta = rows[-1, C.theta_h_meas]
    assert abs(theta - 3.0 / stiffness) <= HB.beta_s / stiffness + 2 * math.pi / 2**14
    # every command but the last (sent after the rig's final advance) arrived
    assert vrig.commands == rows.shape[0] - 1 and runner.counters().fault == "NONE"
    assert rows[-1, C.state] == State.RUNNING
    # the command sent went through the DBC: the rig holds it to 1 mA
    assert vrig.i_cmd == pytest.approx(rows[-2, C.i_safe], abs=5e-4)


def test_the_first_status_resets_the_stack_and_the_torque_fades_in(
    links: tuple[CanLink, CanLink],
) -> None:
    runner, _, rows = _run(links, 100.0, 1.0, rider=3.0)
    sent = rows[:, C.i_safe]
    assert runner.stepper.resets == [(rows[0, C.theta_h_meas], rows[0, C.i_m_meas])]  # type: ignore[attr-defined]
    fade = rows[:50, C.state]
    assert fade[0] == State.FADE_IN and rows[55, C.state] == State.RUNNING
    assert np.all(np.abs(sent[:50]) <= np.abs(rows[:50, C.i_cmd]) + 1e-12)


@pytest.mark.parametrize("rate", [100.0, 1000.0])
@pytest.mark.parametrize(
    ("fault", "rig"),
    [
        (Fault.CHECKSUM, {"faults": RigFaults(bad_checksum=0.8)}),
        (Fault.ESTOP_CAN, {"faults": RigFaults(estop=0.8)}),
        (Fault.DRIVE_FAULT, {"faults": RigFaults(drive_fault=0.8)}),
    ],
)
def test_faults_at_the_rig_zero_the_command_in_the_period_they_arrive(
    links: tuple[CanLink, CanLink], rate: float, fault: Fault, rig: dict[str, object]
) -> None:
    runner, _, rows = _run(links, rate, 1.2, rider=3.0, **rig)
    k = int(np.argmax(rows[:, C.fault] > 0))  # the period the fault was detected
    assert runner.counters().fault == fault.name
    assert rows[k, C.t] == pytest.approx(0.8, abs=1.5 / rate)
    assert rows[k - 1, C.i_safe] != 0.0 and np.all(rows[k:, C.i_safe] == 0.0)


@pytest.mark.parametrize("rate", [100.0, 1000.0])
def test_bus_off_trips_the_watchdog_within_three_periods(
    links: tuple[CanLink, CanLink], rate: float
) -> None:
    runner, _, rows = _run(links, rate, 1.2, rider=3.0, bus_off_at=0.8, bus_off_duration=1.0)
    k = int(np.argmax(rows[:, C.fault] > 0))
    last_valid = 0.8 - 1.0 / rate  # the last status frame before the bus went off
    assert runner.counters().fault == "WATCHDOG"
    assert rows[k, C.t] - last_valid <= 3.0 / rate + 1e-9
    assert np.all(rows[k:, C.i_safe] == 0.0) and rows[k - 1, C.i_safe] != 0.0


def test_random_loss_and_latency_are_tolerated_and_counted(
    links: tuple[CanLink, CanLink],
) -> None:
    runner, vrig, _rows = _run(
        links, 1000.0, 1.0, rider=3.0, loss=0.05, latency=3e-4, jitter=1e-4, stale=0.02
    )
    c = runner.counters()
    assert c.fault == "NONE" and vrig.frames_dropped > 20
    assert c.frames_lost >= vrig.frames_dropped - 2 and c.frames_stale > 5


def test_a_stop_request_fades_out_and_ends_the_run(links: tuple[CanLink, CanLink]) -> None:
    host, drive = links
    settings = _settings(100.0)
    vrig = _held_rig(drive, settings, 1, 100_000)
    runner = RealtimeRunner(SpringStack(20.0), host, CODECS, RunSettings(limits=LIMITS, rate=100.0))
    clock = SimulatedClock()
    clock.listen(vrig.advance_to)

    def period(k: int, t: float) -> bool:
        if k == 100:
            runner.request_stop()
        return runner.period(k, t)

    served = RateLoop(100.0, clock).run(period, periods=1000)
    rows = runner.ring.drain()
    assert served == 100 + 50 and rows[-1, C.i_safe] == 0.0 and rows[-1, C.state] == State.IDLE
    envelope = 1.0 - np.arange(1, 51) / 50.0  # 0.5 s fade-out at 100 Hz
    assert np.allclose(rows[100:, C.i_safe], envelope * rows[100:, C.i_cmd], atol=1e-12)


def test_waiting_for_arm_keeps_the_torque_off_until_arm_then_fades_in(
    links: tuple[CanLink, CanLink],
) -> None:
    host, drive = links
    settings = _settings(100.0)
    vrig = _held_rig(drive, settings, 2, 100_000)
    runner = RealtimeRunner(
        SpringStack(20.0), host, CODECS, RunSettings(limits=LIMITS, rate=100.0, wait_for_arm=True)
    )
    clock = SimulatedClock()
    clock.listen(vrig.advance_to)

    def period(k: int, t: float) -> bool:
        if k == 30:
            runner.arm()  # the view's Arm button, from another thread in motosim run --view
        return runner.period(k, t)

    RateLoop(100.0, clock).run(period, periods=100)
    rows = runner.ring.drain()
    # the stack runs from the first status frame, the command sent stays 0 while IDLE
    assert np.all(rows[:30, C.state] == State.IDLE) and np.all(rows[:30, C.i_safe] == 0.0)
    assert len(runner.stepper.resets) == 1  # type: ignore[attr-defined]
    # from Arm on, the safety stage's 0.5 s fade-in (50 periods at 100 Hz), then RUNNING
    assert np.all(rows[30:79, C.state] == State.FADE_IN) and np.all(
        rows[79:, C.state] == State.RUNNING
    )
    envelope = np.arange(1, 51) / 50.0
    assert np.allclose(rows[30:80, C.i_safe], envelope * rows[30:80, C.i_cmd], atol=1e-12)
    assert np.any(rows[30:, C.i_safe] != 0.0)


def _paced(
    links: tuple[CanLink, CanLink],
    rate: float,
    seconds: float,
    *,
    rider: float = 3.0,
    rig_until: float = math.inf,
    **rig: object,
) -> tuple[RealtimeRunner, FramePacedLoop, np.ndarray, list[int]]:
    """The loop paced by the rig's status frames; the rig stops at ``rig_until`` [s]."""
    host, drive = links
    settings = _settings(rate, **rig)
    tau = np.full(round(seconds * settings.plant_rate) + 1, rider)
    vrig = VirtualRig(HB, settings, CODECS, drive, RigRider(tau), np.random.default_rng(0))
    clock = SimulatedClock()
    clock.listen(lambda t: vrig.advance_to(t) if t < rig_until else None)
    link = LockstepLink(host, clock, 1.0 / settings.plant_rate)
    runner = RealtimeRunner(
        SpringStack(20.0), link, CODECS, RunSettings(limits=LIMITS, rate=rate), clock=clock
    )
    frames: list[int] = []  # status frames handled by each period (its wait included)

    def period(k: int, t: float) -> bool:
        before = runner.status_frames
        carry_on = runner.period(k, t)
        frames.append(runner.status_frames - before)
        return carry_on

    def counted(until: float) -> bool:
        before = runner.status_frames
        got = runner.wait_status(until)
        frames.append(runner.status_frames - before)
        return got

    loop = FramePacedLoop(
        rate,
        clock,
        counted,
        timeout=runner.watchdog_time,
        first_timeout=runner.first_timeout,
        received=lambda: runner.status_frames,
    )
    loop.run(period, periods=round(seconds * rate))
    per_period = [a + b for a, b in zip(frames[0::2], frames[1::2], strict=False)]
    return runner, loop, runner.ring.drain(), per_period


@pytest.mark.parametrize("rate", [100.0, 1000.0])
def test_paced_by_the_bus_each_period_starts_on_a_status_frame(
    links: tuple[CanLink, CanLink], rate: float
) -> None:
    # latency and jitter on the frames: a clock-paced loop sees 0 or 2 frames in some
    # periods, a bus-paced loop exactly one, whenever it comes
    runner, loop, rows, per_period = _paced(links, rate, 1.0, latency=3e-4, jitter=1e-4)
    assert runner.counters().fault == "NONE" and rows[-1, C.state] == State.RUNNING
    assert per_period[1:] == [1] * (len(per_period) - 1)  # the first wait reads power-on's too
    assert loop.stats().missed == 0 and loop.timeouts == 0
    interval = np.diff(rows[:, C.t])
    assert np.mean(interval) == pytest.approx(1.0 / rate, rel=1e-2)
    assert np.ptp(interval) > 0.0  # the loop follows the frames' jitter, not a clock
    # and the same spring holds the rider's 3 N*m where eq. (5) balances them (see above)
    stiffness = 20.0 * HB.torque_per_amp
    assert (
        abs(rows[-1, C.theta_h_meas] - 3.0 / stiffness)
        <= HB.beta_s / stiffness + 2 * math.pi / 2**14
    )


@pytest.mark.parametrize("rate", [100.0, 1000.0])
def test_paced_by_the_bus_a_stopped_rig_trips_the_watchdog_within_its_periods(
    links: tuple[CanLink, CanLink], rate: float
) -> None:
    runner, loop, rows, _ = _paced(links, rate, 1.2, rig_until=0.8)
    k = int(np.argmax(rows[:, C.fault] > 0))
    assert runner.counters().fault == "WATCHDOG" and loop.timeouts >= 1
    # the wait for the next frame times out watchdog_periods (3) periods after the last
    # frame, and that period sends zero
    assert rows[k, C.t] - rows[k - 1, C.t] <= 3.0 / rate + 1e-9
    assert rows[k - 1, C.i_safe] != 0.0 and np.all(rows[k:, C.i_safe] == 0.0)
    # the run goes on sending zero at the watchdog's pace until its linger ends
    assert rows.shape[0] - k < 0.2 * rate


def test_paced_by_the_bus_without_a_drive_trips_no_drive_after_the_start_timeout(
    links: tuple[CanLink, CanLink],
) -> None:
    runner, loop, rows, _ = _paced(links, 100.0, 3.0, rig_until=0.0)
    assert runner.counters().fault == "NO_DRIVE" and np.all(rows[:, C.i_safe] == 0.0)
    stats = loop.stats()  # 1 s of frame periods without a frame: the drive's, not missed
    assert rows[0, C.t] == 0.0 and stats.gaps >= 100 and stats.missed == 0


@pytest.mark.parametrize("rate", [100.0, 1000.0])
def test_a_loop_late_while_the_bus_is_off_sends_zero_on_its_first_period_back(
    links: tuple[CanLink, CanLink], rate: float
) -> None:
    # The bus goes off at 0.8 s and the loop stalls for 5.5 periods in the period before
    # (it skips 5 deadlines): once back, 6 periods have passed without a status frame, more
    # than the watchdog's 3, so its first period sends zero: the skipped deadlines count,
    # else the stale command would go out for 2 more periods.
    host, drive = links
    settings = _settings(rate, bus_off_at=0.8, bus_off_duration=1.0)
    vrig = _held_rig(drive, settings, 0, 20_001)
    runner = RealtimeRunner(SpringStack(20.0), host, CODECS, RunSettings(limits=LIMITS, rate=rate))
    clock = SimulatedClock()
    clock.listen(vrig.advance_to)
    stall = round(0.8 * rate) - 1

    def period(k: int, t: float) -> bool:
        carry_on = runner.period(k, t)
        if k == stall:
            clock.advance(5.5 / rate)
        return carry_on

    loop = RateLoop(rate, clock)
    loop.run(period, periods=round(1.2 * rate))
    rows = runner.ring.drain()
    back = stall + 1  # the row of the first period served after the stall
    assert loop.stats().missed == 5 and rows[back, C.t] == pytest.approx(0.8 + 5.0 / rate)
    assert rows[stall, C.i_safe] != 0.0 and np.all(rows[back:, C.i_safe] == 0.0)
    assert runner.counters().fault == "WATCHDOG"


def test_the_end_of_a_run_fades_out_to_zero_under_a_slow_slew_limit(
    links: tuple[CanLink, CanLink],
) -> None:
    # After the runner's duration the torque fades out in the same run of the loop, which
    # motosim run gives max_periods: with a slew-rate limit slower than the fade (5 A/s:
    # 10 A need 2 s, the fade 0.5 s) the run must still end on a zero command with the
    # stage IDLE, never on a current left on (the drive would hold it). The rider's torque
    # rises to 30 N*m over 3 s against the spring (i = -30 theta: 9.4 A at 0.31 rad with
    # the friction), holds it to 4 s, then the rider lets go.
    host, drive = links
    tau = np.zeros(200_000)
    tau[:40_000] = 30.0
    tau[:30_000] = np.linspace(0.0, 30.0, 30_000)
    vrig = VirtualRig(HB, _settings(100.0), CODECS, drive, RigRider(tau), np.random.default_rng(3))
    limits = SafetyLimits(
        **{name: getattr(LIMITS, name) for name in SafetyLimits.__dataclass_fields__}
        | {"max_slew": 5.0}
    )
    runner = RealtimeRunner(
        SpringStack(30.0), host, CODECS, RunSettings(limits=limits, rate=100.0, duration=4.0)
    )
    clock = SimulatedClock()
    clock.listen(vrig.advance_to)
    loop = RateLoop(100.0, clock)
    total = loop.run(runner.period, periods=runner.max_periods)
    rows = runner.ring.drain()
    assert rows[399, C.state] == State.RUNNING and rows[399, C.i_safe] < -9.0
    served = total - 400  # the fade-out's periods
    assert runner.reached_end and total < runner.max_periods
    assert rows[-1, C.i_safe] == 0.0 and rows[-1, C.state] == State.IDLE
    assert np.all(rows[-served:-1, C.state] == State.STOPPING)
    assert np.all(np.abs(np.diff(rows[:, C.i_safe])) <= 0.05 + 1e-9)  # 5 A/s at 100 Hz, no step


class EstimateStack(SpringStack):
    """The spring, with an estimate and a rate in its row, the ``column`` named going NaN
    from ``bad_from``, its command still finite."""

    names = ("tau_r_hat", "theta_h_dot_hat")

    def __init__(self, gain: float, column: str, bad_from: int) -> None:
        super().__init__(gain)
        self.column, self.bad_from, self.steps = self.names.index(column), bad_from, 0

    def step(
        self, theta_meas: float, i_meas: float, fresh: bool, scale: float, torque: float
    ) -> float:
        command = -self.gain * theta_meas
        self._row[:] = (3.0, 0.0)
        if self.steps >= self.bad_from:
            self._row[self.column] = math.nan
        self.steps += 1
        return command


@pytest.mark.parametrize("column", EstimateStack.names)
def test_a_nan_estimate_or_rate_of_the_stack_zeroes_the_command(
    links: tuple[CanLink, CanLink], column: str
) -> None:
    # The NaN guard promises zero torque for a NaN in a measurement, the estimate or the
    # command: the stack's rider-torque estimate (tau_r_hat) or rate going NaN while its
    # command stays finite trips NON_FINITE in that period: a NaN estimate is not taken for
    # "no estimate", with which the command would go on.
    host, drive = links
    vrig = _held_rig(drive, _settings(100.0), 4, 20_001)
    runner = RealtimeRunner(
        EstimateStack(20.0, column, 70), host, CODECS, RunSettings(limits=LIMITS, rate=100.0)
    )
    clock = SimulatedClock()
    clock.listen(vrig.advance_to)
    RateLoop(100.0, clock).run(runner.period, periods=100)
    rows = runner.ring.drain()
    assert runner.counters().fault == "NON_FINITE"
    assert (
        rows[69, C.i_safe] != 0.0
        and np.all(rows[70:, C.i_safe] == 0.0)
        and rows[70, C.fault] == Fault.NON_FINITE
    )


@pytest.mark.parametrize("stall", [0.0, 8.5])
def test_the_speed_limiter_of_a_stack_without_a_rate_sees_the_handlebars_speed(
    links: tuple[CanLink, CanLink], stall: float
) -> None:
    # A stack whose row has no theta_h_dot_hat (a StackStepper in Python may have none): the
    # loop takes the handlebar's rate from the measured angle. With 100 Hz status frames
    # under a 1 kHz loop the angle changes once in ten periods; its change over one period
    # read a rate ten times the handlebar's, and the speed limiter (6 rad/s) cut the
    # command of a handlebar swinging at 1.8 rad/s in 96 periods of 3 s. The rate is the
    # change between two frames over their interval, on the loop's time: with the loop
    # late by 8.5 periods once per frame interval (its deadlines skipped), the periods
    # served between two frames read a rate up to five times too high, and the limiter cut
    # 32 of the 103 running periods.
    host, drive = links
    limits = SafetyLimits(
        **{name: getattr(LIMITS, name) for name in SafetyLimits.__dataclass_fields__}
        | {"max_speed": 6.0, "speed_band": 4.0}
    )
    t = np.arange(40_001) / 10_000.0
    tau = 25.0 * np.sin(2.0 * np.pi * t)  # the rider swings the handlebar at 1 Hz
    vrig = VirtualRig(HB, _settings(100.0), CODECS, drive, RigRider(tau), np.random.default_rng(3))
    runner = RealtimeRunner(
        SpringStack(5.0),
        host,
        CODECS,
        RunSettings(limits=limits, rate=1000.0, periods_per_frame=10),
    )
    clock = SimulatedClock()
    clock.listen(vrig.advance_to)

    def period(k: int, t: float) -> bool:
        carry_on = runner.period(k, t)
        if stall and k % 10 == 3:
            clock.advance(stall / 1000.0)  # late once per frame interval
        return carry_on

    loop = RateLoop(1000.0, clock)
    loop.run(period, periods=3000)
    rows = runner.ring.drain()
    assert (loop.stats().missed > 2000) == bool(stall)
    # the handlebar's speed: the measured angle's changes over the loop's time between them
    changes = np.flatnonzero(np.diff(rows[:, C.theta_h_meas]) != 0.0) + 1
    speed = np.max(np.abs(np.diff(rows[changes, C.theta_h_meas]) / np.diff(rows[changes, C.t])))
    assert 1.0 < speed < limits.max_speed and runner.counters().fault == "NONE"
    running = rows[:, C.state] == State.RUNNING
    assert np.sum(running) > 100
    assert np.array_equal(
        rows[running, C.i_safe], rows[running, C.i_cmd]
    )  # the command passed whole


def test_nothing_enables_the_torque_again_after_a_fault(links: tuple[CanLink, CanLink]) -> None:
    # An E-stop frame at 0.5 s latches the fault. What a user must do to have torque again
    # is start a new run: within this one, the drive's frames going on, the view's Arm
    # button and a stop request leave the command at zero and the stage in FAULT, and a
    # keyboard E-stop after it does not replace the first fault's reason.
    host, drive = links
    settings = _settings(100.0, faults=RigFaults(estop=0.5))
    vrig = _held_rig(drive, settings, 5, 100_000)
    runner = RealtimeRunner(
        SpringStack(20.0), host, CODECS, RunSettings(limits=LIMITS, rate=100.0, linger=5.0)
    )
    clock = SimulatedClock()
    clock.listen(vrig.advance_to)

    def period(k: int, t: float) -> bool:
        if k == 70:
            runner.arm()
        elif k == 80:
            runner.emergency_stop()
        elif k == 90:
            runner.request_stop()
        return runner.period(k, t)

    served = RateLoop(100.0, clock).run(period, periods=300)
    rows = runner.ring.drain()
    k = int(np.argmax(rows[:, C.fault] > 0))
    assert rows[k - 1, C.i_safe] != 0.0 and np.all(rows[k:, C.i_safe] == 0.0)
    assert np.all(rows[k:, C.state] == State.FAULT) and served == 300
    c = runner.counters()
    assert c.fault == "ESTOP_CAN" and c.status_frames >= 290 and c.frames_stale == 0


@pytest.mark.parametrize("stop", ["ctrl-c", "e-stop"])
def test_a_stop_during_the_fade_in(links: tuple[CanLink, CanLink], stop: str) -> None:
    # Ctrl-C 0.2 s into the 0.5 s fade-in fades the torque out from where the fade-in had
    # brought it (0.4 of the command, down by 0.02 of it per period at 100 Hz: never a
    # step up or to zero), then the run ends IDLE; an E-stop sends zero at once.
    host, drive = links
    vrig = _held_rig(drive, _settings(100.0), 6, 100_000)
    runner = RealtimeRunner(SpringStack(20.0), host, CODECS, RunSettings(limits=LIMITS, rate=100.0))
    clock = SimulatedClock()
    clock.listen(vrig.advance_to)

    def period(k: int, t: float) -> bool:
        if k == 20:
            runner.request_stop() if stop == "ctrl-c" else runner.emergency_stop()
        return runner.period(k, t)

    served = RateLoop(100.0, clock).run(period, periods=300)
    rows = runner.ring.drain()
    assert np.all(rows[:20, C.state] == State.FADE_IN)
    share = rows[:, C.i_safe] / np.where(rows[:, C.i_cmd] == 0.0, 1.0, rows[:, C.i_cmd])
    assert share[19] == pytest.approx(0.4)
    if stop == "ctrl-c":
        assert served == 40 and rows[-1, C.state] == State.IDLE and rows[-1, C.i_safe] == 0.0
        assert share[20:] == pytest.approx(0.4 - 0.02 * np.arange(1, 21))
        assert runner.counters().fault == "NONE"
    else:
        assert np.all(rows[20:, C.i_safe] == 0.0) and runner.counters().fault == "ESTOP_KEY"


def test_a_heartbeat_whose_first_deadline_was_skipped_is_sent_late_not_dropped() -> None:
    # The heartbeat goes out every 0.1 s (10 periods at 100 Hz). A loop late over the
    # deadline that was to send one (k = 20) sends it in the next period served (k = 21);
    # before, it went with the deadline, and the drive saw 0.2 s between two heartbeats.
    channel = f"virtual:heartbeat{next(_channels)}"
    host, drive, listener = open_link(channel), open_link(channel), open_link(channel)
    try:
        vrig = _held_rig(drive, _settings(100.0), 7, 20_001)
        runner = RealtimeRunner(
            SpringStack(20.0), host, CODECS, RunSettings(limits=LIMITS, rate=100.0)
        )
        clock = SimulatedClock()
        clock.listen(vrig.advance_to)

        def period(k: int, t: float) -> bool:
            carry_on = runner.period(k, t)
            if k == 19:
                clock.advance(1.5e-2)  # 1.5 periods late: the deadline k = 20 is skipped
            return carry_on

        RateLoop(100.0, clock).run(period, periods=50)
        counters, values = [], np.zeros(len(CODECS.heartbeat.names))
        at = CODECS.position(CODECS.heartbeat, "counter")
        while (frame := listener.receive()) is not None:
            if frame[0] == CODECS.heartbeat.frame_id:
                assert CODECS.heartbeat.decode(frame[1], values)
                counters.append(int(values[at]))
    finally:
        for link in (host, drive, listener):
            link.close()
    assert counters == [0, 1, 2, 3, 4]  # k = 0, 10, 21, 30, 40


def test_the_heartbeat_goes_on_through_the_fade_out_after_the_duration() -> None:
    # After the runner's duration the torque fades out in the same run of the loop. The
    # 10 Hz heartbeat must go on every 0.1 s through the fade-out (a drive supervising it
    # faults otherwise), its counter one on from the last.
    channel = f"virtual:heartbeat{next(_channels)}"
    host, drive, listener = open_link(channel), open_link(channel), open_link(channel)
    try:
        vrig = _held_rig(drive, _settings(100.0), 7, 200_001)
        runner = RealtimeRunner(
            SpringStack(20.0), host, CODECS, RunSettings(limits=LIMITS, rate=100.0, duration=3.0)
        )
        clock = SimulatedClock()
        clock.listen(vrig.advance_to)
        counters, stamps, ends = [], [], []
        values = np.zeros(len(CODECS.heartbeat.names))
        at = CODECS.position(CODECS.heartbeat, "counter")

        def period(k: int, t: float) -> bool:
            carry_on = runner.period(k, t)
            while (frame := listener.receive()) is not None:
                if frame[0] == CODECS.heartbeat.frame_id:
                    assert CODECS.heartbeat.decode(frame[1], values)
                    counters.append(int(values[at]))
                    stamps.append(t)
            if k == 299:  # the duration's last period
                ends.append(t)
            return carry_on

        loop = RateLoop(100.0, clock)
        served = loop.run(period, periods=runner.max_periods)
    finally:
        for link in (host, drive, listener):
            link.close()
    assert served == 300 + 50 and runner.safety.state == State.IDLE  # the 0.5 s fade-out
    # no deadline missed: the rows' count of them stays 0
    rows = runner.ring.drain()
    assert rows.shape[0] == 350 and np.all(rows[:, C.missed] == 0.0)
    assert sum(stamp > ends[0] for stamp in stamps) == 5
    assert counters == [n & 0xF for n in range(35)]  # one on from the last, none skipped
    assert np.allclose(np.diff(stamps), 0.1)


def test_the_rows_count_of_skipped_deadlines_is_the_loops_through_the_fade_out() -> None:
    # The rows' count of skipped deadlines is the loop's own count (its k less the periods
    # run), the fade-out after the duration included: the loop is 0.5 s late once before
    # the duration's end and the fade-out's rows keep that count.
    channel = f"virtual:missed{next(_channels)}"
    host, drive = open_link(channel), open_link(channel)
    try:
        vrig = _held_rig(drive, _settings(100.0), 7, 200_001)
        runner = RealtimeRunner(
            SpringStack(20.0), host, CODECS, RunSettings(limits=LIMITS, rate=100.0, duration=3.0)
        )
        clock = SimulatedClock()
        clock.listen(vrig.advance_to)

        def period(k: int, t: float) -> bool:
            carry_on = runner.period(k, t)
            if k == 100 and t < 1.05:  # once
                clock.advance(0.5)
            return carry_on

        loop = RateLoop(100.0, clock)
        loop.run(period, periods=runner.max_periods)
    finally:
        host.close()
        drive.close()
    rows = runner.ring.drain()
    skipped = loop.stats().missed
    served = int(np.sum(rows[:, C.t] > 2.995))  # the fade-out's rows
    assert skipped > 40 and served == 50 and runner.reached_end
    assert runner.safety.fault == Fault.NONE
    assert np.all(np.diff(rows[:, C.missed]) >= 0.0)
    assert np.all(rows[-served:, C.missed] == skipped)


def test_a_run_never_armed_ends_at_its_duration(links: tuple[CanLink, CanLink]) -> None:
    # The torque never on (no arm): the duration's end needs no fade-out, the run ends with
    # its last period, as many rows as the duration's periods.
    host, drive = links
    vrig = _held_rig(drive, _settings(100.0), 1, 100_000)
    runner = RealtimeRunner(
        SpringStack(20.0),
        host,
        CODECS,
        RunSettings(limits=LIMITS, rate=100.0, wait_for_arm=True, duration=1.0),
    )
    clock = SimulatedClock()
    clock.listen(vrig.advance_to)
    served = RateLoop(100.0, clock).run(runner.period, periods=runner.max_periods)
    rows = runner.ring.drain()
    assert served == 100 and rows.shape[0] == 100 and runner.reached_end
    assert np.all(rows[:, C.state] == State.IDLE) and np.all(rows[:, C.i_safe] == 0.0)


@pytest.mark.parametrize("duration", [-1.0, math.nan, math.inf])
def test_a_duration_that_is_no_time_is_refused_in_one_line(
    links: tuple[CanLink, CanLink], duration: float
) -> None:
    with pytest.raises(MotosimError, match=r"^duration = .* s: expected a time >= 0$"):
        RealtimeRunner(
            SpringStack(1.0),
            links[0],
            CODECS,
            RunSettings(limits=LIMITS, rate=100.0, duration=duration),
        )


@pytest.mark.parametrize(
    ("name", "value", "expected"),
    [
        ("rate", 0.0, "Hz: expected a positive rate"),
        ("rate", math.nan, "Hz: expected a positive rate"),
        ("linger", -0.1, "; expected a finite number >= 0 [s]"),
        ("start_timeout", 0.0, "; expected a finite number > 0 [s]"),
        ("periods_per_frame", 0, ": expected an integer >= 1"),
        ("capacity", 0, ": expected an integer >= 1"),
    ],
)
def test_a_run_setting_out_of_its_range_is_refused_in_one_line(
    name: str, value: float, expected: str
) -> None:
    with pytest.raises(MotosimError, match=rf"^{name} = [^\n]*{re.escape(expected)}$"):
        RunSettings(LIMITS, **({"rate": 100.0} | {name: value}))  # type: ignore[arg-type]
