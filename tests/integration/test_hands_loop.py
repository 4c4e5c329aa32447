"""The rider's hands and the torque sensor in the closed loop.

What the physics promises: with stiff hands and no active torque, nothing else acting on
it, the handlebar settles at the angle the hands hold, along the solution of the
second-order equation (J_eq + J_a) theta'' + (beta_eq + c_a) theta' + k_a (theta - hold) = 0;
a noise-free torque sensor makes the stack's estimate the rider's true torque (active and
passive), and the tracking no worse than with the observer; the default rider grips
relaxed, and with ``hands = "off"`` the rig is a pure torque source.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from motosim.io.runs import load_run
from motosim.params import load_parameters
from motosim.sim import prepare, simulate
from motosim.sim.closed_loop import RunInputs, build_rig
from motosim.sim.hands import GRIPS, NO_ARMS, arms_of
from motosim.sim.scenario import parse_scenario

ROOT = Path(__file__).parents[2]


def _inputs(doc: dict) -> RunInputs:
    sc = parse_scenario(doc, origin="test.toml")
    hb = load_parameters("simacom_handlebar", "handlebar")
    return prepare(
        sc,
        sharp=load_parameters("sharp1971", "sharp"),
        true_handlebar=hb,
        nominal_handlebar=hb,
        controller=None,
    )


def test_stiff_hands_settle_the_handlebar_at_the_hold_angle() -> None:
    """No motor current, no dry friction, no active torque: the arms' spring and the
    handlebar's and arms' damping bring it from 0 to the hold angle."""
    hold = 0.1
    doc = {
        "scenario": {"name": "hold", "duration": 4.0},
        "rider": {
            "kind": "torque",
            "profile": 0.0,
            "hands": {"inertia": 0.1, "damping": 4.0, "stiffness": 50.0, "hold": hold},
        },
        "handlebar": {"friction": False},
        "controller": {"kind": "none"},
    }
    inputs = _inputs(doc)
    run = simulate(inputs, rng=np.random.default_rng(0))
    hb = inputs.true_handlebar
    J, b, k = hb.J_eq + 0.1, hb.beta_eq + 4.0, 50.0
    s1, s2 = np.roots([J, b, k]).real  # overdamped: two real poles
    t = run.t
    exact = hold * (1.0 - (s2 * np.exp(s1 * t) - s1 * np.exp(s2 * t)) / (s2 - s1))
    # one exact step a 1 ms period with the spring's torque at its midpoint (second order
    # in the step): within 1e-5 of the step
    np.testing.assert_allclose(run["theta_h"], exact, atol=1e-5 * hold)
    assert run["theta_h"][-1] == pytest.approx(hold, abs=1e-3 * hold)


def _profile_doc(**extra: object) -> dict:
    return {
        "scenario": {"name": "sensed", "duration": 2.0},
        "rider": {
            "kind": "torque",
            "profile": {"kind": "square", "low": -5.0, "high": 5.0, "period": 1.0},
            "hands": "relaxed",
        },
        **extra,
    }


def test_noise_free_torque_sensor_gives_the_true_torque() -> None:
    doc = _profile_doc(
        estimator={"name": "torque_sensor"},
        sensor={"torque": {"noise": 0.0}},
        controller={"kind": "none"},
    )
    run = simulate(_inputs(doc), rng=np.random.default_rng(0))
    np.testing.assert_array_equal(run["tau_r_hat"], run["tau_r"])
    # the hands' passive torque is in it: not the square wave alone
    assert np.max(np.abs(np.abs(run["tau_r"]) - 5.0)) > 0.1


def test_torque_sensor_offset_and_low_pass() -> None:
    doc = _profile_doc(
        estimator={"name": "torque_sensor"},
        sensor={"torque": {"offset": 0.5, "low_pass": 20.0}},
        controller={"kind": "none"},
    )
    run = simulate(_inputs(doc), rng=np.random.default_rng(0))
    error = run["tau_r_hat"] - run["tau_r"]
    settled = (run.t % 0.5) > 0.3  # a 20 Hz low-pass settles within 0.05 s of each edge
    assert np.all(np.abs(error[settled] - 0.5) < 0.05)


def test_relaxed_hands_by_default_and_off_is_no_hands() -> None:
    """Without ``hands`` the rider grips relaxed (the run is the one of ``hands =
    "relaxed"``, row for row); "off" is a pure torque source (the pinned runs of
    ``tests/integration/test_stack_golden.py`` hold it to its figures)."""
    base = _profile_doc(controller={"kind": "none"})
    base["rider"] = {k: v for k, v in base["rider"].items() if k != "hands"}
    inputs = _inputs(base)
    assert inputs.scenario.rider.hands is None
    rig = build_rig(inputs, rng=np.random.default_rng(0))
    assert rig.arms == arms_of(GRIPS["relaxed"]) != NO_ARMS
    default = simulate(inputs, rng=np.random.default_rng(0))
    relaxed = simulate(
        _inputs(_profile_doc(controller={"kind": "none"})), rng=np.random.default_rng(0)
    )
    np.testing.assert_array_equal(default.data, relaxed.data)
    off = dataclasses.replace(
        inputs.scenario, rider=dataclasses.replace(inputs.scenario.rider, hands="off")
    )
    rig = build_rig(dataclasses.replace(inputs, scenario=off), rng=np.random.default_rng(0))
    assert rig.arms == NO_ARMS and rig.hands_off.shape == (0, 2) and not rig.sensed


def test_hands_off_phase_removes_every_torque() -> None:
    doc = _profile_doc(controller={"kind": "none"})
    doc["rider"]["hands_off"] = [[0.5, 1.2]]
    run = simulate(_inputs(doc), rng=np.random.default_rng(0))
    phase = (run.t >= 0.5) & (run.t < 1.2)
    assert np.all(run["tau_r"][phase] == 0.0)
    assert np.all(run["tau_r"][run.t < 0.5] != 0.0)


def test_torque_sensor_tracks_no_worse_than_the_observer() -> None:
    """The lane change at 20 m/s with relaxed hands: with a noise-free sensor the estimate
    is the true torque and the handlebar follows the steer angle at least as well."""
    run = load_run(ROOT / "scenarios" / "lane_change_20.toml")
    rider = dataclasses.replace(run.scenario.rider, hands="relaxed")
    observed = dataclasses.replace(run, scenario=dataclasses.replace(run.scenario, rider=rider))
    sc = parse_scenario(
        {
            "scenario": {"name": "lc", "duration": run.scenario.duration},
            "rider": {"kind": "virtual"},
            "estimator": {"name": "torque_sensor"},
        },
        origin="x",
    )
    sensed_sc = dataclasses.replace(observed.scenario, estimator=sc.estimator)
    sensed = dataclasses.replace(observed, scenario=sensed_sc)
    rms = {}
    for name, inputs in (("observer", observed), ("sensor", sensed)):
        out = simulate(inputs, rng=np.random.default_rng(0))
        rms[name] = float(np.sqrt(np.mean((out["theta_h"] - out["delta"]) ** 2)))
        if name == "sensor":
            np.testing.assert_array_equal(out["tau_r_hat"], out["tau_r"])
    assert rms["sensor"] <= rms["observer"]


def test_estimate_reads_a_logs_measured_torque(tmp_path: Path) -> None:
    """``motosim estimate --estimator torque_sensor`` on a log with ``tau_r_meas`` [N*m]:
    the estimate is the measured torque; without the column the log is refused."""
    import sys

    from motosim.cli.main import main
    from motosim.io import read_log, write_log
    from motosim.timeseries import TimeSeries

    t = np.arange(500) * 1e-3
    tau = 5.0 * np.sin(2 * np.pi * 2.0 * t)
    columns = np.column_stack([0.01 * np.sin(t), np.zeros_like(t), tau])
    log = tmp_path / "log.csv"
    write_log(log, TimeSeries(t, columns, ("theta_h", "i_m", "tau_r_meas")))
    out = tmp_path / "est.csv"
    with pytest.raises(SystemExit) as info:
        sys.exit(main(["estimate", str(log), "--estimator", "torque_sensor", "--out", str(out)]))
    assert info.value.code in (0, None)
    np.testing.assert_allclose(read_log(out, required=("tau_r_hat",))["tau_r_hat"], tau)
    bare = tmp_path / "bare.csv"
    write_log(bare, TimeSeries(t, columns[:, :2], ("theta_h", "i_m")))
    with pytest.raises(SystemExit) as info:
        sys.exit(
            main(
                [
                    "estimate",
                    str(bare),
                    "--estimator",
                    "torque_sensor",
                    "--out",
                    str(out),
                    "--overwrite",
                ]
            )
        )
    assert info.value.code == 2
