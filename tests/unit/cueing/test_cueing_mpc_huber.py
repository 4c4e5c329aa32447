"""The roll plan's Huber cost on the perceived roll-rate error (``roll_canal_corner``).

The promise (:mod:`motosim.cueing.mpc`): up to the corner, in roll thresholds, the error
costs its square as in the squared design; beyond, it grows linearly with the same slope at
the corner (Huber, *Ann. Math. Statist.* 35(1), 1964), through two QP variables per step
whose optimum is the Huber function's split of the error.
"""

import dataclasses

import numpy as np
import pytest

from motosim.cueing import TELBAN_CARDULLO_2005, load_platform
from motosim.cueing.mpc import design_mpc
from motosim.cueing.platform import CueingConfig, parse_platform
from motosim.errors import MotosimError


def _config(corner: float) -> CueingConfig:
    cfg = load_platform("simacom_platform")
    return dataclasses.replace(cfg, mpc=dataclasses.replace(cfg.mpc, roll_canal_corner=corner))


def test_the_quadratic_part_is_the_squared_cost_and_only_roll_has_a_corner() -> None:
    squared = design_mpc(_config(0.0), TELBAN_CARDULLO_2005, 0.01)
    huber = design_mpc(_config(4.0), TELBAN_CARDULLO_2005, 0.01)
    roll_s, roll_h = squared.axes[0], huber.axes[0]
    assert roll_s.huber_M.shape[0] == 0 and roll_h.huber_M.shape[0] == roll_h.P.shape[0]
    w = roll_h.huber_weight
    # within the corner: w e^2 with e = (M u + E x0 - r) / thr, the squared design's terms
    np.testing.assert_allclose(
        roll_h.P + w * roll_h.huber_M.T @ roll_h.huber_M, roll_s.P, rtol=1e-10, atol=1e-12
    )
    np.testing.assert_allclose(
        roll_h.F + w * roll_h.huber_M.T @ roll_h.huber_E, roll_s.F, rtol=1e-10, atol=1e-12
    )
    assert roll_h.huber_thr == TELBAN_CARDULLO_2005.thresholds[0]
    for j in (1, 2):  # pitch and yaw keep the squared cost
        assert huber.axes[j].huber_M.shape[0] == 0
        np.testing.assert_array_equal(huber.axes[j].P, squared.axes[j].P)


def _roll_after(corner: float, roll_rate: float, monkeypatch: pytest.MonkeyPatch) -> float:
    """The roll target [rad] after 0.2 s of a held roll rate [rad/s] (predicted to fade)."""
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    import motosim.cueing.mpc as mpc

    # converged, to compare the optima: at the shipped iteration limit the two extra
    # variables per step move the plan a little even within the corner (the terminal-rows
    # test of test_cueing_preview.py runs the squared cost for that reason); the runs'
    # verdicts are the same converged (docs/guide/cueing.md)
    monkeypatch.setattr(mpc, "MAX_ITER", 20_000)
    plan = mpc.MpcCueing(design_mpc(_config(corner), TELBAN_CARDULLO_2005, 0.01))
    motion = np.array([roll_rate, 0.0, 0.0, 0.0, 0.0])
    for _ in range(20):
        roll = plan.step(motion, np.zeros(3))[0]
    return float(roll)


def test_within_the_corner_the_plan_is_the_squared_plan(monkeypatch: pytest.MonkeyPatch) -> None:
    # 6 deg/s (2 roll thresholds) fading over 0.15 s: errors under a corner of 4
    rate = np.radians(6.0)
    huber, squared = _roll_after(4.0, rate, monkeypatch), _roll_after(0.0, rate, monkeypatch)
    assert huber == pytest.approx(squared, rel=5e-3)  # within OSQP's tolerances (1e-4)


def test_beyond_the_corner_the_plan_chases_the_roll_rate_less(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # 20 deg/s (6.7 roll thresholds): beyond a corner of 1 threshold the error's cost grows
    # linearly, so the plan rolls less towards it than the squared cost makes it (1.03
    # against 1.52 deg after 0.2 s), though still towards it (the reference is neutral)
    rate = np.radians(20.0)
    huber, squared = _roll_after(1.0, rate, monkeypatch), _roll_after(0.0, rate, monkeypatch)
    assert 0.0 < huber < 0.8 * squared, (huber, squared)


def test_a_negative_corner_is_a_one_line_error() -> None:
    import tomllib
    from importlib import resources

    text = (resources.files("motosim.cueing") / "data" / "simacom_platform.toml").read_text()
    data = tomllib.loads(text)
    data["mpc"]["roll_canal_corner"] = -1.0
    with pytest.raises(MotosimError, match=r"roll_canal_corner = -1.0; expected") as info:
        parse_platform(data, origin="my.toml")
    assert "\n" not in str(info.value)
    del data["mpc"]["roll_canal_corner"]
    with pytest.raises(MotosimError, match="missing key 'roll_canal_corner' in \\[mpc\\]"):
        parse_platform(data, origin="my.toml")


def test_ctrl_c_taken_by_osqp_during_a_solve_interrupts_the_cueing() -> None:
    # OSQP catches SIGINT during a solve and returns the status OSQP_SIGINT: the plan braked
    # and went on, so Ctrl-C was lost and motosim cueing ran to its end (4 of 5 presses on a
    # 300 s run)
    osqp = pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    import unittest.mock

    from motosim.cueing.mpc import MpcCueing

    plan = MpcCueing(design_mpc(_config(0.0), TELBAN_CARDULLO_2005, 0.01))
    interrupted = unittest.mock.Mock()
    interrupted.info.status_val = osqp.SolverStatus.OSQP_SIGINT
    with (
        unittest.mock.patch.object(osqp.OSQP, "solve", return_value=interrupted),
        pytest.raises(KeyboardInterrupt),
    ):
        plan.step(np.array([0.1, 0.0, 0.0, 0.0, 0.0]), np.zeros(3))
