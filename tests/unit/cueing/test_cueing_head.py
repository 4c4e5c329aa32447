"""Motion at the rider's head against an independent world-frame computation."""

import numpy as np
import pytest

from motosim.cueing.head import check_rate, platform_motion, vehicle_motion
from motosim.cueing.platform import RiderHead, load_platform
from motosim.errors import MotosimError
from motosim.timeseries import TimeSeries

G = 9.81


def _rot(phi: np.ndarray, theta: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """Body-to-world rotation Rz(psi) Ry(theta) Rx(phi), shape (n, 3, 3)."""
    c, s = np.cos, np.sin
    n = phi.size
    Rx = np.zeros((n, 3, 3))
    Ry = np.zeros((n, 3, 3))
    Rz = np.zeros((n, 3, 3))
    Rx[:, 0, 0] = 1
    Rx[:, 1, 1], Rx[:, 1, 2], Rx[:, 2, 1], Rx[:, 2, 2] = c(phi), -s(phi), s(phi), c(phi)
    Ry[:, 1, 1] = 1
    Ry[:, 0, 0], Ry[:, 0, 2], Ry[:, 2, 0], Ry[:, 2, 2] = c(theta), s(theta), -s(theta), c(theta)
    Rz[:, 2, 2] = 1
    Rz[:, 0, 0], Rz[:, 0, 1], Rz[:, 1, 0], Rz[:, 1, 1] = c(psi), -s(psi), s(psi), c(psi)
    return np.asarray(Rz @ Ry @ Rx)


@pytest.fixture
def rider() -> RiderHead:
    return RiderHead(x=1.0, height=1.45, pitch_gain=0.007, pitch_frequency=12.0, pitch_damping=0.5)


def _manoeuvre(dt: float) -> TimeSeries:
    """Smooth speed, lateral velocity, yaw rate and lean: a weave-like manoeuvre."""
    t = np.arange(0.0, 6.0, dt)
    v_x = 15.0 + 3.0 * np.sin(0.7 * t)
    v_y = 0.3 * np.sin(1.3 * t)
    psi_dot = 0.25 * np.sin(0.9 * t) + 0.1
    phi = 0.4 * np.sin(0.9 * t + 0.3)
    phi_dot = 0.36 * np.cos(0.9 * t + 0.3)
    data = np.column_stack([v_x, v_y, psi_dot, phi_dot, phi])
    return TimeSeries(t, data, ("v_x", "v_y", "psi_dot", "phi_dot", "phi"))


def test_vehicle_motion_matches_world_frame_differences(rider: RiderHead) -> None:
    # Independent check: integrate the contact point and heading in the world frame, place
    # the head with the body rotation, difference twice and rotate the specific force back.
    dt = 1e-3
    ts = _manoeuvre(dt)
    vm = vehicle_motion(ts, rider)
    t = ts.t
    psi = np.concatenate([[0.0], np.cumsum(0.5 * (ts["psi_dot"][1:] + ts["psi_dot"][:-1]) * dt)])
    R = _rot(ts["phi"], vm["theta"], psi)
    Rz = _rot(np.zeros_like(t), np.zeros_like(t), psi)
    v_origin = np.einsum("nij,nj->ni", Rz, np.column_stack([ts["v_x"], ts["v_y"], 0 * t]))
    offset = np.einsum("nij,j->ni", R, np.array([rider.x, 0.0, -rider.height]))
    v_head = v_origin + np.gradient(offset, dt, axis=0)
    a_head = np.gradient(v_head, dt, axis=0)
    f_world = a_head - np.array([0.0, 0.0, G])
    f_body = np.einsum("nji,nj->ni", R, f_world)
    # body angular velocity from R^T dR/dt
    W = np.einsum("nji,njk->nik", R, np.gradient(R, dt, axis=0))
    omega = np.column_stack([W[:, 2, 1], W[:, 0, 2], W[:, 1, 0]])
    inner = slice(50, -50)
    got_f = np.column_stack([vm["f_x"], vm["f_y"], vm["f_z"]])
    got_w = np.column_stack([vm["omega_x"], vm["omega_y"], vm["omega_z"]])
    np.testing.assert_allclose(got_f[inner], f_body[inner], atol=2e-3)
    np.testing.assert_allclose(got_w[inner], omega[inner], atol=1e-5)


def test_balanced_steady_turn_has_no_lateral_force_at_the_contact_height() -> None:
    # A steady turn leaned at atan(v psi_dot / g): the resultant stays in the rider's plane.
    rider = RiderHead(x=0.0, height=1e-9, pitch_gain=0.0, pitch_frequency=10.0, pitch_damping=1)
    t = np.arange(0.0, 2.0, 0.01)
    v, r = 15.0, 0.4
    phi = np.full_like(t, np.arctan(v * r / G))
    data = np.column_stack([np.full_like(t, v), 0 * t, np.full_like(t, r), 0 * t, phi])
    vm = vehicle_motion(TimeSeries(t, data, ("v_x", "v_y", "psi_dot", "phi_dot", "phi")), rider)
    np.testing.assert_allclose(vm["f_y"], 0.0, atol=1e-6)
    np.testing.assert_allclose(vm["f_z"], -np.hypot(G, v * r), rtol=1e-9)
    np.testing.assert_allclose(vm["omega_y"], r * np.sin(phi), rtol=1e-12)  # yaw seen leaned


def test_braking_pitches_nose_down(rider: RiderHead) -> None:
    t = np.arange(0.0, 4.0, 0.01)
    v_x = np.where(t < 1.0, 20.0, 20.0 - 5.0 * (t - 1.0))  # 5 m/s^2 braking from 1 s
    z = 0 * t
    ts = TimeSeries(
        t, np.column_stack([v_x, z, z, z, z]), ("v_x", "v_y", "psi_dot", "phi_dot", "phi")
    )
    vm = vehicle_motion(ts, rider)
    assert vm["a_x"][200] == pytest.approx(-5.0)
    assert vm["theta"][-1] == pytest.approx(-5.0 * rider.pitch_gain, rel=1e-3)  # quasi-static


def test_platform_roll_at_rest_tilts_gravity() -> None:
    platform = load_platform("simacom_platform").platform
    t = np.arange(0.0, 1.0, 0.01)
    roll = np.full_like(t, 0.2)
    pm = platform_motion(t, roll, 0 * t, 0 * t, platform)
    np.testing.assert_allclose(pm["f_y"], -G * np.sin(0.2), rtol=1e-12)
    np.testing.assert_allclose(pm["f_z"], -G * np.cos(0.2), rtol=1e-12)


def test_missing_signal_and_uneven_rate_are_one_line_errors(rider: RiderHead) -> None:
    t = np.arange(0.0, 1.0, 0.01)
    with pytest.raises(MotosimError, match="no signal 'v_y'"):
        vehicle_motion(TimeSeries(t, np.zeros((t.size, 1)), ("v_x",)), rider)
    with pytest.raises(MotosimError, match="constant rate"):
        check_rate(np.array([0.0, 0.01, 0.03, 0.04]))
