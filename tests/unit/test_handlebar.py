"""The handlebar model of eqs. (5)-(7) and (10)."""

from dataclasses import replace

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.model import handlebar as hm
from motosim.params import HandlebarParameters


def test_linear_model_eq10(handlebar: HandlebarParameters) -> None:
    lin = hm.linear_model(handlebar)
    J, beta, nkt = handlebar.J_eq, handlebar.beta_eq, handlebar.torque_per_amp
    np.testing.assert_allclose(lin.A, [[-beta / J, 0.0], [1.0, 0.0]])
    np.testing.assert_allclose(lin.B, [[nkt / J, 1.0 / J], [0.0, 0.0]])
    np.testing.assert_allclose(lin.C, [[0.0, 1.0]])
    # the mechanical pole beta/J = 336 rad/s (domain notes, from Table I)
    assert lin.poles()[0].real == pytest.approx(-336.29, abs=0.01)


def test_exact_step_matches_closed_form_without_friction(handlebar: HandlebarParameters) -> None:
    J, beta = handlebar.J_eq, handlebar.beta_eq
    torque, t = 5.0, 0.02
    theta, omega = hm.step_exact(0.0, 0.0, torque, J, beta, 0.0, t)
    a = beta / J
    assert omega == pytest.approx(torque / beta * (1 - np.exp(-a * t)), rel=1e-12)
    assert theta == pytest.approx(torque / beta * (t - (1 - np.exp(-a * t)) / a), rel=1e-12)


def test_stick_while_torque_below_dry_friction(handlebar: HandlebarParameters) -> None:
    J, beta, beta_s = handlebar.J_eq, handlebar.beta_eq, handlebar.beta_s
    assert hm.step_exact(0.1, 0.0, 0.99 * beta_s, J, beta, beta_s, 0.01) == (0.1, 0.0)
    # a moving handlebar with no torque stops and stays stopped
    theta, omega = hm.step_exact(0.0, 0.5, 0.0, J, beta, beta_s, 0.1)
    assert omega == 0.0 and theta > 0.0
    # a reversal inside one step ends moving the other way
    _, omega = hm.step_exact(0.0, 0.05, -10.0, J, beta, beta_s, 0.05)
    assert omega == pytest.approx((-10.0 + beta_s) / beta, rel=1e-4)


def test_exact_stick_slip_agrees_with_fine_smooth_friction(handlebar: HandlebarParameters) -> None:
    t = np.arange(0.0, 4.0, 1e-3)
    current = 1.5 * np.sign(np.sin(2 * np.pi * 0.7 * t)) + 0.8 * np.sin(2 * np.pi * 3.1 * t)
    exact = hm.simulate_handlebar(handlebar, t, current=current)
    smooth = hm.simulate_handlebar(
        handlebar, t, current=current, friction_width=1e-4, max_step=2e-6
    )
    scale = np.max(np.abs(exact["theta_h"]))
    assert np.max(np.abs(exact["theta_h"] - smooth["theta_h"])) < 0.01 * scale


def test_voltage_drive_quasi_static_and_electrical_agree(handlebar: HandlebarParameters) -> None:
    t = np.arange(0.0, 3.0, 1e-3)
    volts = 3.0 * np.sin(2 * np.pi * 1.0 * t)
    quasi = hm.simulate_handlebar(handlebar, t, voltage=volts, friction_width=1e-3, max_step=1e-5)
    full = hm.simulate_handlebar(
        handlebar, t, voltage=volts, electrical=True, friction_width=1e-3, max_step=1e-5
    )
    # L/R = 0.2 ms: the current lag is negligible next to the 3 ms mechanical time constant
    np.testing.assert_allclose(
        full["theta_h"], quasi["theta_h"], atol=3e-3 * np.ptp(quasi["theta_h"])
    )
    # eq. (7): u = R i + k_e N theta_dot
    u = handlebar.R * quasi["i_m"] + handlebar.k_e * handlebar.N * quasi["theta_h_dot"]
    np.testing.assert_allclose(u, volts, atol=1e-9)


def test_exact_step_is_stable_at_100_hz(handlebar: HandlebarParameters) -> None:
    """Forward Euler at 10 ms is unstable for beta/J = 336 1/s; the exact step is not."""
    frictionless = replace(handlebar, beta_s=0.0)
    t = np.arange(0.0, 1.0, 0.01)
    res = hm.simulate_handlebar(frictionless, t, current=np.where(t < 0.5, 1.0, 0.0), max_step=1.0)
    a = frictionless.beta_eq / frictionless.J_eq
    assert abs(1 - a * 0.01) > 1  # Euler's amplification factor
    assert np.max(np.abs(res["theta_h_dot"])) <= frictionless.torque_per_amp / frictionless.beta_eq


def test_bad_inputs(handlebar: HandlebarParameters) -> None:
    t = np.arange(0.0, 1.0, 0.01)
    with pytest.raises(MotosimError, match="exactly one of"):
        hm.simulate_handlebar(handlebar, t)
    with pytest.raises(MotosimError, match="current has shape"):
        hm.simulate_handlebar(handlebar, t, current=np.zeros(3))
    with pytest.raises(MotosimError, match="NaN"):
        hm.simulate_handlebar(handlebar, t, current=np.full(t.size, np.nan))
    with pytest.raises(MotosimError, match="strictly increasing"):
        hm.simulate_handlebar(handlebar, t[::-1], current=0.0)
    with pytest.raises(MotosimError, match="electrical dynamics need"):
        hm.simulate_handlebar(handlebar, t, voltage=1.0, electrical=True)
