"""Unit tests of motosim.control.hinf_norm (Hamiltonian level-set H-infinity norm)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motosim.control import frequency_response, hinf_norm
from motosim.errors import MotosimError


def _grid_max(A, B, C, D, omegas):
    return max(float(np.linalg.norm(frequency_response((A, B, C, D), w), 2)) for w in omegas)


def test_second_order_resonance_analytic():
    # 1/(s^2 + 2 zeta s + 1), zeta = 0.1: peak 1/(2 zeta sqrt(1 - zeta^2)) = 5.025189 at
    # omega = sqrt(1 - 2 zeta^2) = 0.989949 (textbook closed form).
    zeta = 0.1
    gamma, omega = hinf_norm([[0.0, 1.0], [-1.0, -2 * zeta]], [[0.0], [1.0]], [[1.0, 0.0]], [[0.0]])
    assert gamma == pytest.approx(1.0 / (2 * zeta * math.sqrt(1 - zeta**2)), rel=1e-9)
    assert round(gamma, 6) == 5.025189
    assert omega == pytest.approx(math.sqrt(1 - 2 * zeta**2), rel=1e-6)


def test_first_order_peak_at_dc():
    # 3/(s + 2): peak 1.5 at omega = 0 (analytic).
    gamma, omega = hinf_norm([[-2.0]], [[1.0]], [[3.0]], [[0.0]])
    assert gamma == pytest.approx(1.5, rel=1e-12)
    assert omega == 0.0


def test_peak_at_infinity_with_feedthrough():
    # (s + 1)/(s + 10) = 1 - 9/(s + 10): |G| rises from 0.1 at DC to sigma_max(D) = 1 at inf.
    gamma, omega = hinf_norm([[-10.0]], [[1.0]], [[-9.0]], [[1.0]])
    assert gamma == pytest.approx(1.0, rel=1e-12)
    assert omega == math.inf


def test_static_gain_has_no_states():
    # G = D = [3, 4]: sigma_max = 5 at every frequency.
    gamma, omega = hinf_norm(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), [[3.0, 4.0]])
    assert gamma == pytest.approx(5.0)
    assert omega == math.inf


def test_feedthrough_plus_resonance_is_sup_of_grid():
    # 0.5 + 1/(s^2 + 0.2 s + 1): D shifts the peak; check against a fine grid around it.
    A = [[0.0, 1.0], [-1.0, -0.2]]
    B, C, D = [[0.0], [1.0]], [[1.0, 0.0]], [[0.5]]
    gamma, omega = hinf_norm(A, B, C, D)
    grid = np.linspace(0.9, 1.1, 4001)
    assert _grid_max(A, B, C, D, grid) <= gamma * (1 + 1e-12)
    sigma_peak = float(np.linalg.norm(frequency_response((A, B, C, D), omega), 2))
    assert sigma_peak == pytest.approx(gamma, rel=1e-10)
    assert gamma > 5.025189  # adding a positive real D to the resonance raises the peak


def test_mimo_diagonal_and_rotation_invariance():
    # diag(1/(s+1), 2/(s+4), 10/(s^2+s+25)): norms 1, 0.5 and 10/sqrt(25*1 - 1/4) (analytic,
    # |1/(s^2 + 2 zeta wn s + wn^2)| peak = 1/(2 zeta wn^2 sqrt(1 - zeta^2)), zeta = 0.1, wn = 5).
    A = np.zeros((4, 4))
    A[0, 0], A[1, 1] = -1.0, -4.0
    A[2:, 2:] = [[0.0, 1.0], [-25.0, -1.0]]
    B = np.zeros((4, 3))
    B[0, 0], B[1, 1], B[3, 2] = 1.0, 2.0, 10.0
    C = np.zeros((3, 4))
    C[0, 0], C[1, 1], C[2, 2] = 1.0, 1.0, 1.0
    D = np.zeros((3, 3))
    expected = 10.0 / (2 * 0.1 * 25.0 * math.sqrt(1 - 0.01))
    gamma, _ = hinf_norm(A, B, C, D)
    assert gamma == pytest.approx(expected, rel=1e-9)
    rng = np.random.default_rng(3)
    Q1, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    Q2, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    T = rng.standard_normal((4, 4)) + 4 * np.eye(4)
    Ti = np.linalg.inv(T)
    gamma_rot, _ = hinf_norm(Ti @ A @ T, Ti @ B @ Q2, Q1 @ C @ T, D)
    assert gamma_rot == pytest.approx(expected, rel=1e-8)


def test_non_square_mimo_with_feedthrough_matches_grid():
    rng = np.random.default_rng(7)
    n, m, p = 5, 2, 3
    A = rng.standard_normal((n, n))
    A -= (np.max(np.linalg.eigvals(A).real) + 0.3) * np.eye(n)
    B, C, D = rng.standard_normal((n, m)), rng.standard_normal((p, n)), rng.standard_normal((p, m))
    gamma, omega = hinf_norm(A, B, C, D)
    grid = np.concatenate(([0.0], np.logspace(-3, 3, 3000)))
    assert _grid_max(A, B, C, D, grid) <= gamma * (1 + 1e-10)
    assert float(np.linalg.norm(frequency_response((A, B, C, D), omega), 2)) == pytest.approx(
        gamma, rel=1e-10
    )


def test_stiff_system():
    # 1/((s + 1e-3)(s + 1e4)): DC gain 1/10 = 0.1 is the peak (analytic).
    A = [[-1e-3, 1.0], [0.0, -1e4]]
    gamma, omega = hinf_norm(A, [[0.0], [1.0]], [[1.0, 0.0]], [[0.0]])
    assert gamma == pytest.approx(0.1, rel=1e-9)
    assert omega == pytest.approx(0.0, abs=1e-6)


def test_scaling_and_zero_system():
    A, B, C, D = [[0.0, 1.0], [-4.0, -0.4]], [[0.0], [1.0]], [[1.0, 0.0]], [[0.0]]
    g1, _ = hinf_norm(A, B, C, D)
    g3, _ = hinf_norm(A, B, [[-3.0, 0.0]], D)
    assert g3 == pytest.approx(3 * g1, rel=1e-10)
    assert hinf_norm(A, B, [[0.0, 0.0]], D) == (0.0, 0.0)


@pytest.mark.parametrize(
    "A",
    [
        [[1.0]],  # unstable
        [[0.0]],  # integrator
        [[0.0, 1.0], [-1.0, 0.0]],  # undamped oscillator, poles +/- j
        [[-1.0, 0.0], [0.0, 2.0]],  # one unstable mode
    ],
)
def test_unstable_or_marginal_a_raises(A):
    n = len(A)
    with pytest.raises(MotosimError, match="imaginary axis"):
        hinf_norm(A, np.ones((n, 1)), np.ones((1, n)), [[0.0]])


@pytest.mark.parametrize(
    ("A", "B", "C", "D", "match"),
    [
        ([[-1.0, 0.0]], [[1.0]], [[1.0]], [[0.0]], "square"),
        ([[-1.0]], [[1.0], [1.0]], [[1.0]], [[0.0]], "B has shape"),
        ([[-1.0]], [[1.0]], [[1.0, 2.0]], [[0.0]], "C has shape"),
        ([[-1.0]], [[1.0]], [[1.0]], [[0.0, 1.0]], "D has shape"),
        ([[np.nan]], [[1.0]], [[1.0]], [[0.0]], "NaN"),
        ([[-1.0]], [[np.inf]], [[1.0]], [[0.0]], "NaN"),
        ([[-1.0]], [["a"]], [[1.0]], [[0.0]], "numeric"),
    ],
)
def test_bad_input_raises(A, B, C, D, match):
    with pytest.raises(MotosimError, match=match):
        hinf_norm(A, B, C, D)


def test_bad_rtol_raises():
    with pytest.raises(MotosimError, match="rtol"):
        hinf_norm([[-1.0]], [[1.0]], [[1.0]], [[0.0]], rtol=0.0)


def test_error_is_a_value_error():
    with pytest.raises(ValueError, match="imaginary axis"):
        hinf_norm([[2.0]], [[1.0]], [[1.0]], [[0.0]])


def test_finite_peak_just_below_feedthrough_level_is_not_missed():
    # Regression: a four-block loop whose finite peak (about 2.445747797 near 16.4 rad/s)
    # sits within 1e-9 of sigma_max(D); the Hamiltonian at (1 + 2e-10) sigma_max(D) has
    # entries ~1e14 and once made a neighbouring controller report sigma_max(D) instead of a
    # 2.468 peak at 3.8 rad/s. Plant: Skogestad & Postlethwaite Example 9.3 (shaped).
    from scipy import signal

    from motosim.control import four_block_system

    num = np.polymul([200.0], [1.0, 2.0])
    den = np.polymul(np.polymul([10.0, 1.0], np.polymul([0.05, 1.0], [0.05, 1.0])), [1.0, 1e-6])
    G = signal.tf2ss(num, den)
    for a_k, c_k, d_k in [
        (-50.35281978085782, 85.96188616031607, -2.231968254304969),
        (-49.34913364, 84.28519303, -2.22362983),
    ]:
        T = four_block_system(G, ([[a_k]], [[1.0]], [[c_k]], [[d_k]]))
        gamma, _ = hinf_norm(T.A, T.B, T.C, T.D)
        grid = np.concatenate(([0.0], np.geomspace(1e-2, 1e3, 4000)))
        assert _grid_max(T.A, T.B, T.C, T.D, grid) <= gamma * (1 + 1e-10)
        assert gamma >= float(np.linalg.norm(T.D, 2))


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(1, 6),
    m=st.integers(1, 3),
    p=st.integers(1, 3),
    with_d=st.booleans(),
)
def test_properties_dual_similarity_and_lower_bound(seed, n, m, p, with_d):
    # Invariants: ||G|| = ||G^T|| (dual system), invariant under a state similarity, and
    # >= sigma_max(G(j w)) at any frequency, attained at the returned omega.
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A -= (np.max(np.linalg.eigvals(A).real) + rng.uniform(0.05, 2.0)) * np.eye(n)
    B, C = rng.standard_normal((n, m)), rng.standard_normal((p, n))
    D = rng.standard_normal((p, m)) if with_d else np.zeros((p, m))
    gamma, omega = hinf_norm(A, B, C, D)
    gamma_dual, _ = hinf_norm(A.T, C.T, B.T, D.T)
    assert gamma_dual == pytest.approx(gamma, rel=1e-8)
    T = rng.standard_normal((n, n)) + 3 * np.eye(n)
    if np.linalg.cond(T) < 1e3:
        Ti = np.linalg.inv(T)
        assert hinf_norm(Ti @ A @ T, Ti @ B, C @ T, D)[0] == pytest.approx(gamma, rel=1e-8)
    for w in rng.uniform(0.0, 10.0, 5):
        assert float(np.linalg.norm(frequency_response((A, B, C, D), w), 2)) <= gamma * (1 + 1e-10)
    peak = float(np.linalg.norm(frequency_response((A, B, C, D), omega), 2))
    assert peak == pytest.approx(gamma, rel=1e-9)
