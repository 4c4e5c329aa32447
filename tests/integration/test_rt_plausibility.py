"""The frozen-sensor monitor of the safety stage, lock-step against the virtual rig.

Each scenario of ``scenarios/`` runs through the real-time loop (the compiled stack, the
safety stage with the handlebar's parameters) against the virtual rig over python-can's
virtual bus on a simulated clock, with the scenario's rider at the rig: its torque profile,
or the virtual rider steering by the run's state stream (as ``motosim rig`` does). Without a
fault, the monitor must never trip; with the rig's frozen encoder it must trip within a
bounded number of periods once the motor torque changes, at 100 Hz and at 1 kHz.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.io.runs import load_scenario
from motosim.rt.clock import SimulatedClock
from motosim.rt.config import load_realtime, rig_settings
from motosim.rt.loop import RateLoop
from motosim.rt.rig import RigFaults, RigRider, VirtualRig
from motosim.rt.run import RealtimeRunner, RunSettings
from motosim.rt.safety import SafetyLimits, State
from motosim.rt.stack import CompiledStack
from motosim.sim import build_rig, build_stack
from motosim.sim.closed_loop import RunInputs

pytest.importorskip("can", reason="python-can is in the rt and dev dependency groups")
pytest.importorskip("cantools", reason="cantools is in the rt and dev dependency groups")

from motosim.io.can import handlebar_codecs, open_link

SCENARIOS = Path(__file__).parents[2] / "scenarios"
FILES = sorted(SCENARIOS.glob("*.toml")) + sorted(SCENARIOS.glob("paper/*.toml"))

# the limits of scenarios/realtime_square.toml (the bench handlebar), hands-off detection
# off so that only the protections under test act
LIMITS = SafetyLimits(
    max_current=10.0,
    max_slew=2000.0,
    max_speed=6.0,
    speed_band=4.0,
    soft_stop=0.6,
    hard_stop=0.8,
    end_stop_gain=50.0,
    hands_off_torque=0.0,
    hands_off_time=1.0,
    hands_off_gain=0.3,
)

_channels = iter(range(10**6))


def _lockstep(
    inputs: RunInputs,
    realtime: dict[str, object],
    *,
    faults: RigFaults | None = None,
    limits: SafetyLimits = LIMITS,
) -> tuple[RealtimeRunner, np.ndarray, float]:
    """Run ``inputs`` lock-step against the rig; the runner, its rows and the largest turn
    of a free handlebar [rad] the frozen-sensor monitor predicted."""
    from motosim.rt.rig import VirtualRider
    from motosim.rt.telemetry import StateReceiver, StateSender

    sc = inputs.scenario
    rate = sc.rates.control
    settings = rig_settings(sc, realtime, origin="test")
    if faults is not None:
        settings = dataclasses.replace(settings, faults=faults)
    model = build_stack(inputs)
    world = build_rig(inputs, rng=np.random.default_rng(sc.seed))
    receiver = sender = None
    rider: object
    if sc.rider.profile is not None:
        t_fine = np.arange(round(sc.duration * settings.plant_rate) + 1) / settings.plant_rate
        rider = sc.rider.profile.sample(t_fine, inputs.tables)
    else:
        receiver = StateReceiver(("127.0.0.1", 0))
        sender = StateSender(receiver.address)
        rider = VirtualRider(world, receiver, rate=rate)
    codecs = handlebar_codecs()
    channel = f"virtual:plausibility{next(_channels)}"
    try:
        with open_link(channel) as host, open_link(channel) as drive:
            rig = VirtualRig(  # the scenario's hands, as `motosim rig` gives them
                inputs.true_handlebar,
                settings,
                codecs,
                drive,
                RigRider(rider, arms=world.arms, hands_off=world.hands_off),
                np.random.default_rng(sc.seed),
            )
            runner = RealtimeRunner(
                CompiledStack(model, force=world.force, side_force=world.side_force),
                host,
                codecs,
                RunSettings(
                    limits=limits,
                    rate=rate,
                    periods_per_frame=model.measure_every,
                    handlebar=inputs.nominal_handlebar,
                    capacity=round(sc.duration * rate) + 8,
                ),
                telemetry=None if sender is None else sender.send,
            )
            clock = SimulatedClock()
            clock.listen(rig.advance_to)
            peak = [0.0]

            def period(k: int, t: float) -> bool:
                carry_on = runner.period(k, t)
                peak[0] = max(peak[0], runner.safety.free_turn)
                return carry_on

            RateLoop(rate, clock).run(period, periods=round(sc.duration * rate))
    finally:
        if sender is not None and receiver is not None:
            sender.close()
            receiver.close()
    return runner, runner.ring.drain(), peak[0]


@pytest.mark.parametrize("path", FILES, ids=lambda p: str(p.relative_to(SCENARIOS)))
def test_no_false_trip_on_the_scenarios(path: Path) -> None:
    from motosim.rt.rig import VirtualRider

    if load_scenario(path).motorcycle.model == "multibody":  # training at the limits: offline

        def refused() -> None:
            inputs, _ = load_realtime(str(path))
            VirtualRider.check(build_rig(inputs, rng=np.random.default_rng(0)))

        with pytest.raises(MotosimError, match=r"read offline only|rider steers Sharp 1971 only"):
            refused()
        return
    inputs, realtime = load_realtime(str(path))
    if inputs.scenario.motorcycle.input == "true":
        pytest.skip('motorcycle input = "true" is simulation-only; motosim run refuses it')
    runner, rows, peak = _lockstep(inputs, realtime)
    assert runner.counters().fault == "NONE", runner.counters().fault_reason
    assert rows[-1, runner.names.index("state")] == State.RUNNING
    # the training runs stay well inside the frozen-sensor monitor's angle: a margin of 3 to
    # its threshold (the measured peaks are in the real-time guide)
    assert peak < LIMITS.frozen_angle / 3.0


def _lane_change(rate: float) -> tuple[RunInputs, dict[str, object]]:
    inputs, realtime = load_realtime(str(SCENARIOS / "lane_change_20.toml"))
    rates = dataclasses.replace(inputs.scenario.rates, control=rate, measurement=rate)
    sc = dataclasses.replace(inputs.scenario, rates=rates, duration=6.0)
    return dataclasses.replace(inputs, scenario=sc), realtime


@pytest.mark.parametrize("rate", [100.0, 1000.0])
def test_a_frozen_encoder_trips_the_monitor_and_zeroes_the_command(rate: float) -> None:
    # lane_change_20: the virtual rider steers into the lane change from 2.5 s (x = 50 m at
    # 20 m/s) and the encoder freezes at 3.0 s, while the stack drives the handlebar. The
    # stack's observer then reads the still angle as a rider holding against the motor, the
    # virtual motorcycle turns on that estimate and the command changes: the monitor trips
    # (measured: after 0.17 s at 100 Hz, 0.22 s at 1 kHz; the bound is 0.5 s)
    inputs, realtime = _lane_change(rate)
    runner, rows, _ = _lockstep(inputs, realtime, faults=RigFaults(frozen_encoder=3.0))
    col = {name: j for j, name in enumerate(runner.names)}
    theta, sent = rows[:, col["theta_h_meas"]], rows[:, col["i_safe"]]
    assert runner.counters().fault == "FROZEN_SENSOR"
    k = int(np.argmax(rows[:, col["fault"]] > 0))  # the period the fault was detected
    frozen = int(np.argmax(rows[:, col["t"]] >= 3.0))  # its first frame comes a period later
    assert np.all(theta[frozen + 1 : k + 1] == theta[frozen + 1])  # it did freeze
    assert np.any(theta[frozen - 50 : frozen] != theta[frozen + 1])  # it moved before
    assert 0 < k - frozen <= round(0.5 * rate)
    # zero in the period of detection (and after), not before
    assert sent[k - 1] != 0.0 and np.all(sent[k:] == 0.0)
