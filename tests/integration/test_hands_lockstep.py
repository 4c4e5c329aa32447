"""The rider's hands at the virtual rig of a lock-step run, as in the offline simulator.

:class:`motosim.rt.lockstep.Lockstep` builds the virtual rig of the scenario's rider, so a
rider whose arms hold the handlebar (:mod:`motosim.sim.hands`) holds it there too: with stiff
hands, no active torque and no motor current, the handlebar goes from 0 to the angle the hands
hold, along the offline run's angle (the same plant, sub-step for sub-step, read through the
DBC's 1e-5 rad scaling of the angle).
"""

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


def test_lockstep_refuses_the_torque_sensor_in_one_line() -> None:
    """The loop does not read the torque sensor's frame: a lock-step run of the estimator
    ``torque_sensor`` would steer on no torque, and is refused as ``motosim run`` refuses it."""
    doc = {
        "scenario": {"name": "sensed", "duration": 0.1},
        "rider": {"kind": "torque", "profile": 1.0},
        "estimator": {"name": "torque_sensor"},
        "controller": {"kind": "paper"},
    }
    from motosim.control.torque_feedback import PAPER_CONTROLLER
    from motosim.errors import MotosimError

    hb = load_parameters("simacom_handlebar", "handlebar")
    inputs = prepare(
        parse_scenario(doc, origin="test.toml"),
        sharp=load_parameters("sharp1971", "sharp"),
        true_handlebar=hb,
        nominal_handlebar=hb,
        controller=PAPER_CONTROLLER,
    )
    with pytest.raises(MotosimError, match="torque_sensor") as err:
        Lockstep(inputs, free_limits(1000.0), channel="rt_sensed")
    assert "\n" not in str(err.value)
