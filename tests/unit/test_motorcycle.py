"""Eq. (2) and the coupled lateral-longitudinal simulation."""

import numpy as np
import pytest
from scipy.linalg import expm

from motosim.errors import MotosimError
from motosim.model import sharp as model
from motosim.params import SharpParameters


def test_longitudinal_equation(sharp: SharpParameters) -> None:
    # consistent eq. (2): (m + J_R/r_D^2) v_x' = (tau_d - tau_b)/r_D + m psi_dot v_y + F_wx,
    # m + J_R/r_D^2 = 267.14 kg (Sharp 1971, Appendix 3: m_f + m_r, i_fy + i_Ry, R_r)
    acc = model.longitudinal_acceleration(
        sharp, v_y=0.5, psi_dot=0.2, drive_torque=300.0, brake_torque=100.0, wind_force=-50.0
    )
    want = (200.0 / 0.3048 + 248.09635 * 0.2 * 0.5 - 50.0) / 267.141393
    assert acc == pytest.approx(want, rel=1e-6)


def test_straight_running_speed(sharp: SharpParameters) -> None:
    t = np.linspace(0.0, 5.0, 501)
    res = model.simulate(sharp, t, initial_speed=10.0, drive_torque=400.0, wind_force=-30.0)
    acc = (400.0 / 0.3048 - 30.0) / 267.141393
    np.testing.assert_allclose(res["v_x"], 10.0 + acc * t, rtol=1e-7)  # m_eq rounded to 1e-9
    np.testing.assert_allclose(res["x"], 10.0 * t + 0.5 * acc * t**2, rtol=1e-7, atol=1e-9)
    assert np.all(res["phi"] == 0.0)


def test_constant_speed_matches_exact_linear_response(sharp: SharpParameters) -> None:
    """At constant speed the coupled integrator reproduces the matrix-exponential solution."""
    speed, dt = 15.0, 0.01
    t = np.arange(0.0, 3.0 + dt / 2, dt)
    torque = np.where(t < 0.2, 2.0, 0.0)
    res = model.simulate(sharp, t, initial_speed=speed, rider_torque=torque)
    lin = model.linearize(sharp, speed)
    Ad, Bd = lin.discretize(dt)
    x = np.zeros(8)
    for k in range(t.size - 1):
        x = Ad @ x + Bd[:, 0] * torque[k]
    got = res.data[-1, :8]
    scale = np.max(np.abs(res.data[:, :8]), axis=0)
    np.testing.assert_allclose(got, x, atol=1e-6 * scale.max(), rtol=1e-5)
    # the second-order yaw-v_y term changes v_x only slightly in this small manoeuvre
    assert abs(res["v_x"][-1] - speed) < 1e-2


def test_countersteering(sharp: SharpParameters) -> None:
    """A short push on the right handlebar grip leans the machine left and turns it left."""
    t = np.arange(0.0, 2.0, 0.01)
    res = model.simulate(sharp, t, initial_speed=20.0, rider_torque=np.where(t < 0.5, 5.0, 0.0))
    assert res["phi"][-1] < 0 and res["psi"][-1] < 0


def test_brakes_hold_at_minimum_speed(sharp: SharpParameters) -> None:
    t = np.linspace(0.0, 2.0, 201)
    res = model.simulate(sharp, t, initial_speed=5.0, brake_torque=3000.0)
    assert res["v_x"].min() == pytest.approx(model.MIN_SPEED)


def test_bad_speed_and_inputs(sharp: SharpParameters) -> None:
    t = np.linspace(0.0, 1.0, 11)
    for speed in (-1.0, 0.0, 0.5, float("nan")):
        with pytest.raises(MotosimError, match="expected a finite forward speed >= 1 m/s"):
            model.linearize(sharp, speed)
    with pytest.raises(MotosimError, match="brake_torque has a negative sample"):
        model.simulate(sharp, t, initial_speed=10.0, brake_torque=-1.0)
    with pytest.raises(MotosimError, match="rider_torque has shape"):
        model.simulate(sharp, t, initial_speed=10.0, rider_torque=np.zeros(3))
    with pytest.raises(MotosimError, match="initial_state has shape"):
        model.simulate(sharp, t, initial_speed=10.0, initial_state=np.zeros(3))


def test_discretize_is_exact_zoh(sharp: SharpParameters) -> None:
    lin = model.linearize(sharp, 25.0)
    Ad, _ = lin.discretize(0.005)
    np.testing.assert_allclose(Ad, expm(lin.A * 0.005), rtol=1e-10, atol=1e-12)


def test_stage_yaw_turn_matches_the_library_trigonometry() -> None:
    # cos(psi + d) and sin(psi + d) by angle addition and the Taylor series of the small turn
    # d equal math.cos and math.sin of psi + d to a few ulp plus a spacing of psi (the reference
    # rounds the sum psi + d by up to half a spacing), on both sides of the series' bound and
    # beyond it, at yaws over several turns
    psi = np.linspace(-20.0, 20.0, 401)
    for d in (0.0, 1e-9, -3e-4, 2e-3, -model._SERIES_TURN, model._SERIES_TURN, 0.05, -0.7):
        for p in psi:
            c, s = model._turned(p, np.cos(p), np.sin(p), d)
            tol = 4e-16 + np.spacing(abs(p))
            assert abs(c - np.cos(p + d)) <= tol and abs(s - np.sin(p + d)) <= tol, (p, d)
