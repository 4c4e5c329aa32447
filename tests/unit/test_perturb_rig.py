"""A campaign worker's rig perturbed in place is the rig :func:`build_rig` builds for the run.

What :func:`motosim.sim.closed_loop.perturb_rig` promises: for a run that differs from the
rig's only in its true handlebar and its seed, every array the rig draws from the run's
random numbers (the current sensor's noise and the torque sensor's error) is the one
:func:`~motosim.sim.closed_loop.build_rig` draws, bit for bit.
"""

import dataclasses

import numpy as np
import pytest

from motosim.params import load_parameters
from motosim.sim import prepare
from motosim.sim.closed_loop import RunInputs, build_rig, perturb_rig, rig_key
from motosim.sim.scenario import parse_scenario


def _inputs(seed: int, inertia_factor: float, current_noise: float) -> RunInputs:
    doc = {
        "scenario": {"name": "rig", "duration": 0.2, "seed": seed},
        "measurement": {"current_noise": current_noise},
        "rider": {"kind": "torque", "profile": 1.0},
        "handlebar": {"inertia_factor": inertia_factor},
        "estimator": {"name": "torque_sensor"},
        "controller": {"kind": "none"},
        "sensor": {"torque": {"noise": 0.3, "offset": 0.2}},
    }
    hb = load_parameters("simacom_handlebar", "handlebar")
    return prepare(
        parse_scenario(doc, origin="test.toml"),
        sharp=load_parameters("sharp1971", "sharp"),
        true_handlebar=hb,
        nominal_handlebar=hb,
        controller=None,
    )


@pytest.mark.parametrize("current_noise", [0.0, 0.05])
def test_perturbed_rig_draws_the_torque_sensor_error_of_its_seed(current_noise: float) -> None:
    first = _inputs(seed=1, inertia_factor=1.0, current_noise=current_noise)
    second = _inputs(seed=2, inertia_factor=1.4, current_noise=current_noise)
    assert rig_key(first.scenario) == rig_key(second.scenario)  # a worker reuses the rig
    reused = build_rig(first, rng=np.random.default_rng(1))
    reused = perturb_rig(reused, second, rng=np.random.default_rng(2))
    alone = build_rig(second, rng=np.random.default_rng(2))
    for field in ("handlebar", "current_noise", "torque_error"):
        assert np.array_equal(getattr(reused, field), getattr(alone, field)), field
    assert np.std(alone.torque_error) > 0.1  # the sensor's noise is there to differ


def test_perturbed_rig_without_a_torque_sensor_keeps_no_error() -> None:
    inputs = _inputs(seed=1, inertia_factor=1.0, current_noise=0.05)
    plain = dataclasses.replace(
        inputs,
        scenario=dataclasses.replace(
            inputs.scenario,
            estimator=dataclasses.replace(inputs.scenario.estimator, name="walcott_zak"),
            sensor=dataclasses.replace(inputs.scenario.sensor, torque=None),
        ),
    )
    rig = perturb_rig(
        build_rig(plain, rng=np.random.default_rng(1)), plain, rng=np.random.default_rng(3)
    )
    assert not np.any(rig.torque_error)
    assert np.array_equal(
        rig.current_noise, build_rig(plain, rng=np.random.default_rng(3)).current_noise
    )
