"""The rider's hands at the virtual rig of a lock-step run, as in the offline simulator.

:class:`motosim.rt.lockstep.Lockstep` builds the virtual rig of the scenario's rider, so a
rider whose arms hold the handlebar (:mod:`motosim.sim.hands`) holds it there too: with stiff
hands, no active torque and no motor current, the handlebar goes from 0 to the angle the hands
hold, along the offline run's angle (the same plant, sub-step for sub-step, read through the
DBC's 1e-5 rad scaling of the angle).
"""

from collections.abc import Callable

import numpy as np
import pytest

from motosim.params import load_parameters
from motosim.sim import prepare, simulate
from motosim.sim.scenario import parse_scenario

pytest.importorskip("can", reason="python-can is in the rt and dev dependency groups")
pytest.importorskip("cantools", reason="cantools is in the rt and dev dependency groups")

from motosim.rt.lockstep import Lockstep, free_limits

HOLD = 0.1
"""The angle the hands hold [rad]."""


def test_lockstep_rig_holds_the_handlebar_with_the_riders_hands() -> None:
    doc = {
        "scenario": {"name": "hold", "duration": 3.0},
        "rider": {
            "kind": "torque",
            "profile": 0.0,
            "hands": {"inertia": 0.1, "damping": 4.0, "stiffness": 50.0, "hold": HOLD},
        },
        "handlebar": {"friction": False},
        "controller": {"kind": "none"},
    }
    hb = load_parameters("simacom_handlebar", "handlebar")
    inputs = prepare(
        parse_scenario(doc, origin="test.toml"),
        sharp=load_parameters("sharp1971", "sharp"),
        true_handlebar=hb,
        nominal_handlebar=hb,
        controller=None,
    )
    offline = simulate(inputs, rng=np.random.default_rng(0))
    lock = Lockstep(inputs, free_limits(inputs.scenario.rates.control), channel="rt_hands")
    rows = lock.run()
    theta = rows[:, lock.runner.names.index("theta_h_meas")]
    assert theta.size == offline.t.size
    assert theta[-1] == pytest.approx(HOLD, rel=0.02)  # the hands took it there
    # the encoder's step is 3.8e-4 rad: the DBC's rounding shifts a crossing by a sample
    np.testing.assert_allclose(theta, offline["theta_h_meas"], atol=1e-3)


def _sensed(hands: str) -> object:
    """A square rider torque read by an ideal torque sensor, the paper's controller."""
    from motosim.control.torque_feedback import PAPER_CONTROLLER

    profile = {"kind": "square", "low": -5.0, "high": 5.0, "period": 0.5}
    rider = {"kind": "torque", "profile": profile}
    doc = {
        "scenario": {"name": "sensed", "duration": 2.0},
        "rider": rider | ({} if hands == "none" else {"hands": hands}),
        "estimator": {"name": "torque_sensor"},
        "controller": {"kind": "paper"},
    }
    hb = load_parameters("simacom_handlebar", "handlebar")
    return prepare(
        parse_scenario(doc, origin="test.toml"),
        sharp=load_parameters("sharp1971", "sharp"),
        true_handlebar=hb,
        nominal_handlebar=hb,
        controller=PAPER_CONTROLLER,
    )


@pytest.mark.parametrize("hands", ["none", "relaxed"])
def test_lockstep_reads_the_torque_sensor_as_offline(hands: str) -> None:
    """The rig sends the hands' torque in HB_TORQUE after each status frame and the loop's
    stack reads it: the estimate of the estimator ``torque_sensor`` is the offline one but
    for the DBC's 0.01 N*m scaling of the torque and, with the arms, their acceleration taken
    over the status period (offline: over the control period; both 1 ms here)."""
    inputs = _sensed(hands)
    offline = simulate(inputs, rng=np.random.default_rng(0))  # type: ignore[arg-type]
    lock = Lockstep(inputs, free_limits(1000.0), channel=f"rt_sensed_{hands}")  # type: ignore[arg-type]
    rows = lock.run()
    counters = lock.runner.counters()
    assert counters.fault == "NONE" and counters.torque_frames == rows.shape[0] == 2000
    error = rows[:, lock.runner.names.index("tau_r_hat")] - offline["tau_r_hat"]
    assert offline["tau_r_hat"] == pytest.approx(offline["tau_r"], abs=1e-12)  # ideal sensor
    assert np.sqrt(np.mean(error**2)) < 0.005 and np.max(np.abs(error)) < 0.01  # N*m


def _tamper(lock: Lockstep, change: "Callable[[bytes], bytes | None]") -> None:
    """From t = 0.5 s, the rig's HB_TORQUE frames go on the bus as ``change`` makes them
    (None: not sent)."""
    rig = lock.rig
    send, torque_id = rig.link.send, rig.codecs.torque.frame_id  # type: ignore[union-attr]

    def tampered(frame_id: int, data: bytes) -> bool:
        if frame_id == torque_id and rig.t >= 0.5:
            changed = change(data)
            return True if changed is None else send(frame_id, changed)
        return send(frame_id, data)

    rig.link.send = tampered  # type: ignore[method-assign]


def test_a_torque_sensor_that_stops_trips_its_watchdog() -> None:
    """No HB_TORQUE frame for the watchdog's 3 status periods: ``TORQUE_SENSOR``, while the
    status frames go on."""
    lock = Lockstep(_sensed("none"), free_limits(1000.0), channel="rt_sensor_stops")  # type: ignore[arg-type]
    _tamper(lock, lambda data: None)
    rows = lock.run()
    counters = lock.runner.counters()
    assert counters.fault == "TORQUE_SENSOR" and "HB_TORQUE" in counters.fault_reason
    # the last frame taken in the period of t = 0.499 s, the fault three periods on
    assert counters.fault_time == pytest.approx(0.502, abs=1.5e-3)
    assert counters.status_frames == rows.shape[0]
    assert rows[-1, lock.runner.names.index("i_safe")] == 0.0


def test_a_torque_frame_with_a_wrong_checksum_trips_the_checksum_fault() -> None:
    lock = Lockstep(_sensed("none"), free_limits(1000.0), channel="rt_sensor_crc")  # type: ignore[arg-type]
    _tamper(lock, lambda data: bytes([data[0] ^ 0x5A]) + data[1:])
    lock.run()
    counters = lock.runner.counters()
    assert counters.fault == "CHECKSUM"
    assert counters.fault_time == pytest.approx(0.5, abs=1.5e-3)
