"""Walcott-Zak observer: design checks and rider-torque reconstruction in simulation."""

import dataclasses

import numpy as np
import pytest
from estimation_scenarios import QUANTUM, STEP, rms_error, scenario
from scipy.linalg import eigvals

from motosim.errors import MotosimError
from motosim.estimation.differentiator import differentiate
from motosim.estimation.registry import ESTIMATORS, estimate, walcott_zak_for_step
from motosim.estimation.walcott_zak import WalcottZakObserver, design, invariant_zeros
from motosim.params import load_parameters

LIPSCHITZ = 300.0  # bound on |theta_h''| for the differentiator [rad/s^2]


@pytest.fixture(scope="module")
def hb():
    return load_parameters("simacom_handlebar", "handlebar")


def _run(observer, theta, current, rate):
    out = np.empty(theta.size)
    for k in range(theta.size):
        _, out[k] = observer.step(theta[k], rate[k], current[k])
    return out


def _observe(gains, run, *, quantised=False):
    t = run["t"]
    h = t[1] - t[0]
    theta = np.round(run["theta_h"] / QUANTUM) * QUANTUM if quantised else run["theta_h"]
    rate = differentiate(theta, h, LIPSCHITZ)
    return _run(WalcottZakObserver(gains, h), theta, run["i_m"], rate)


# --- design -------------------------------------------------------------------------------


@pytest.mark.parametrize("poles", [(-0.1, -60.0), (-40.0, -60.0), (-300.0, -5.0)])
def test_design_places_poles_and_solves_lyapunov_and_matching(hb, poles):
    g = design(hb, poles=poles)
    A_L = g.A - g.L @ g.C
    np.testing.assert_allclose(np.sort(eigvals(A_L).real), np.sort(poles), rtol=1e-12)
    assert np.allclose(g.P, g.P.T) and np.all(np.linalg.eigvalsh(g.P) > 0)
    lyap = A_L.T @ g.P + g.P @ A_L + g.Q  # eq. (13)
    assert np.linalg.norm(lyap) < 1e-9
    assert np.linalg.norm(g.P @ g.D - g.C.T @ g.F) < 1e-9  # eq. (14)


def test_angle_alone_fails_the_matching_condition(hb):
    with pytest.raises(MotosimError, match=r"matching condition fails, rank\(C D\) = 0"):
        design(hb, outputs=("theta_h",))


def test_rate_alone_has_an_invariant_zero_at_the_origin(hb):
    # (A, D, [1 0]): theta_h is not seen, a zero at s = 0
    with pytest.raises(MotosimError, match="invariant zeros"):
        design(hb, outputs=("theta_h_dot",))


def test_invariant_zeros_of_eq15_outputs_are_none(hb):
    g = design(hb)
    assert invariant_zeros(g.A, g.D, g.C).size == 0
    # a system with a known zero: D = [1, 1], C = [[1, 0]] on A = diag(-1, -2) -> zero at -1.5
    z = invariant_zeros(np.diag([-1.0, -2.0]), np.array([1.0, 1.0]), np.array([[1.0, 1.0]]))
    np.testing.assert_allclose(z, [-1.5], atol=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"outputs": ("theta_h", "delta")}, "outputs"),
        ({"poles": (-1.0, 2.0)}, "poles"),
        ({"poles": (-1.0,)}, "poles"),
        ({"eta": 0.0}, "eta"),
        ({"epsilon": -1.0}, "epsilon"),
        ({"state_weight": np.diag([1.0, -1.0])}, "state_weight"),
        ({"dead_zone": -0.1}, "dead_zone"),
        ({"sign_convention": "minus"}, "sign_convention"),
    ],
)
def test_bad_design_options_raise(hb, kwargs, match):
    with pytest.raises(MotosimError, match=match):
        design(hb, **kwargs)


def test_too_fast_injection_for_the_step_raises(hb):
    with pytest.raises(MotosimError, match="sampled injection loop is unstable"):
        WalcottZakObserver(design(hb, injection_bandwidth=800.0), 0.01)


def test_stepper_reset_reproduces_the_run(hb):
    run = scenario(1000.0, True)
    rate = differentiate(run["theta_h"], 1e-3, LIPSCHITZ)
    obs = WalcottZakObserver(design(hb), 1e-3)
    n = 300
    first = _run(obs, run["theta_h"][:n], run["i_m"][:n], rate[:n])
    obs.reset()
    np.testing.assert_array_equal(_run(obs, run["theta_h"][:n], run["i_m"][:n], rate[:n]), first)


# --- reconstruction (section V, Figs. 11 and 14) -------------------------------------------


@pytest.mark.parametrize("friction", [False, True], ids=["no_friction", "friction_compensated"])
def test_reconstructs_square_rider_torque_at_1khz(hb, friction):
    run = scenario(1000.0, friction)
    nominal = hb if friction else dataclasses.replace(hb, beta_s=0.0)
    tau_hat = _observe(design(nominal), run)
    assert rms_error(run["t"], run["tau_r"], tau_hat) < 0.02 * STEP


def test_printed_injection_sign_diverges(hb):
    run = scenario(1000.0, False)
    nominal = dataclasses.replace(hb, beta_s=0.0)
    tau_hat = _observe(design(nominal, sign_convention="printed"), run)
    err = rms_error(run["t"], run["tau_r"], tau_hat)
    assert err > 0.5 * STEP  # the consistent sign gives < 2 %


@pytest.mark.parametrize("J_factor", [0.5, 1.5])
@pytest.mark.parametrize("beta_factor", [0.5, 1.5])
def test_robust_to_half_wrong_inertia_and_damping(hb, J_factor, beta_factor):
    run = scenario(1000.0, True)
    nominal = dataclasses.replace(
        hb, J_eq=J_factor * hb.J_eq, beta_eq=beta_factor * hb.beta_eq, J_m=0.0, beta_vm=0.0
    )
    tau_hat = _observe(design(nominal), run)
    assert np.all(np.isfinite(tau_hat)) and np.max(np.abs(tau_hat)) < design(nominal).eta
    assert rms_error(run["t"], run["tau_r"], tau_hat) < 0.08 * STEP


@pytest.mark.parametrize("friction", [False, True], ids=["no_friction", "friction_compensated"])
def test_100hz_quantised_beats_baselines(hb, friction):
    run = scenario(100.0, friction)
    nominal = hb if friction else dataclasses.replace(hb, beta_s=0.0)
    theta = np.round(run["theta_h"] / QUANTUM) * QUANTUM
    errors = {
        name: rms_error(
            run["t"], run["tau_r"], estimate(name, run["t"], theta, run["i_m"], nominal)[1]
        )
        for name in ESTIMATORS
    }
    assert errors["walcott_zak"] < 0.15 * STEP
    assert errors["walcott_zak"] < errors["inverse_dynamics"], errors
    assert errors["walcott_zak"] < errors["kalman"], errors


def test_registry_builds_fresh_steppers(hb):
    for name, factory in ESTIMATORS.items():
        est = factory(hb, 0.01)
        x_hat, tau_hat = est.step(0.0, 0.0, 0.0)
        assert x_hat.shape == (2,) and tau_hat == 0.0, name
    assert isinstance(walcott_zak_for_step(hb, 0.01), WalcottZakObserver)


def test_estimate_rejects_bad_input(hb):
    t = np.arange(0.0, 0.1, 0.01)
    with pytest.raises(MotosimError, match="unknown"):
        estimate("oracle", t, t, t, hb)
    with pytest.raises(MotosimError, match="uniformly"):
        estimate("kalman", t**2, t, t, hb)
    with pytest.raises(MotosimError, match="i_m has shape"):
        estimate("kalman", t, t, t[:-1], hb)


@pytest.mark.parametrize("projection", [True, False])
def test_stuck_handlebar_keeps_the_estimate_within_the_friction_band(hb, projection):
    """While the handlebar sticks, N k_t i_m + tau_r + tau_p = 0 for any |tau_p| <= beta_s
    (Coulomb friction, eqs. (6)-(7)): motor-current changes smaller than beta_s / (N k_t)
    do not tell the rider's torque. With the stick projection the estimate keeps its last
    value until the current leaves that band, then moves by the excess only; the plain
    dead-zoned compensation (Remark 5.2) reads every change as rider torque."""
    h = 1e-3
    observer = WalcottZakObserver(design(hb), h, stick_projection=projection)
    nkt, band = hb.torque_per_amp, hb.beta_s
    steps = round(0.5 / h)
    inside = 0.8 * band / nkt  # a current change the friction holds [A]
    beyond = 1.5 * band / nkt  # one it cannot hold alone [A]
    estimates = {}
    for name, current in (("rest", 0.0), ("inside", inside), ("beyond", beyond)):
        for _ in range(steps):
            _, tau_hat = observer.step(0.0, 0.0, current)
        estimates[name] = tau_hat
    assert estimates["rest"] == pytest.approx(0.0, abs=1e-9)
    if projection:
        assert estimates["inside"] == pytest.approx(0.0, abs=1e-3 * band)
        # beyond the band the friction holds beta_s and the rider the rest
        assert estimates["beyond"] == pytest.approx(-(nkt * beyond - band), rel=1e-3)
    else:
        assert estimates["inside"] == pytest.approx(-nkt * inside, rel=1e-3)
        assert estimates["beyond"] == pytest.approx(-nkt * beyond, rel=1e-3)
