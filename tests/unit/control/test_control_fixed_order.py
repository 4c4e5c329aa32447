"""Unit tests of the fixed-order (HIFOO-style) synthesis and of balanced truncation."""

import math

import numpy as np
import pytest
from scipy import signal

from motosim.control import (
    StateSpace,
    balanced_truncation,
    closed_loop_poles,
    fixed_order_synthesis,
    four_block_norm,
    hinf_norm,
    ncfsyn,
)
from motosim.control.fixed_order import _Problem
from motosim.errors import MotosimError

J_H, BETA = 0.0415, 13.956  # Table I of the paper: [kg m^2], [N m s/rad]


def weighted_handlebar() -> StateSpace:
    """G_h W1 with W1 = (s + 50)/(s + 0.5), N k_t = 1 (algorithms notes Sec. 2.3)."""
    return StateSpace(*signal.tf2ss([1.0, 50.0], np.polymul([J_H, BETA, 0.0], [1.0, 0.5])))


def _fd_gradient(problem: _Problem, theta: np.ndarray) -> np.ndarray:
    g = np.empty_like(theta)
    for i in range(theta.size):
        h = 1e-6 * max(1.0, abs(theta[i]))
        e = np.zeros_like(theta)
        e[i] = h
        fp, _ = problem.value_and_gradient(theta + e)
        fm, _ = problem.value_and_gradient(theta - e)
        g[i] = (fp - fm) / (2 * h)
    return g


@pytest.mark.parametrize("order", [1, 2])
def test_analytic_gradient_matches_finite_differences(order):
    G = weighted_handlebar()
    problem = _Problem(G, order)
    K = balanced_truncation(ncfsyn(G.A, G.B, G.C, G.D, 1.3).controller, order)
    theta = problem.pack(K) * (
        1 + 0.05 * np.random.default_rng(order).standard_normal(problem.size)
    )
    f, g = problem.value_and_gradient(theta)
    assert math.isfinite(f)
    np.testing.assert_allclose(
        g, _fd_gradient(problem, theta), rtol=2e-4, atol=1e-7 * np.abs(g).max()
    )


def test_gradient_at_infinite_peak_matches_formula():
    # Paper K on the unit-weight handlebar: peak sqrt(1 + b1^2) at infinity, so only b1 = D_K
    # matters, d gamma / d b1 = b1 / sqrt(1 + b1^2) (algorithms notes Sec. 2.3).
    G = StateSpace([[0.0, 1.0], [0.0, -BETA / J_H]], [[0.0], [1.0 / J_H]], [[1.0, 0.0]], [[0.0]])
    problem = _Problem(G, 1)
    b1, b0, a0 = -2.355, -613.7, 1445.0
    theta = np.array([-a0, b0 - b1 * a0, b1])  # (A_K, C_K, D_K) with B_K = 1
    f, g = problem.value_and_gradient(theta)
    assert f == pytest.approx(math.sqrt(1 + b1**2), rel=1e-9)
    np.testing.assert_allclose(g, [0.0, 0.0, b1 / math.sqrt(1 + b1**2)], atol=1e-9)


def test_static_and_second_order_controllers():
    G = weighted_handlebar()
    full = ncfsyn(G.A, G.B, G.C, G.D).gamma_min
    rng = np.random.default_rng(5)
    res0 = fixed_order_synthesis(G.A, G.B, G.C, G.D, order=0, rng=rng, n_starts=3)
    assert res0.order == 0
    assert res0.num is None
    assert res0.A.shape == (0, 0)
    assert res0.is_stable
    assert res0.gamma >= full * (1 - 1e-6)
    assert four_block_norm(G, res0.controller) == pytest.approx(res0.gamma, rel=1e-9)
    res2 = fixed_order_synthesis(G.A, G.B, G.C, G.D, order=2, rng=rng, n_starts=2, polish=False)
    assert res2.A.shape == (2, 2)
    assert res2.is_stable
    assert np.all(res2.closed_loop_poles.real < 0)
    assert full * (1 - 1e-6) <= res2.gamma <= res0.gamma + 1e-9


def test_mimo_first_order():
    # 2x2 plant, first-order controller with full state-space parametrisation.
    rng = np.random.default_rng(11)
    A = np.array([[-1.0, 2.0, 0.0], [0.0, -3.0, 1.0], [0.0, 0.0, 0.5]])
    B, C = rng.standard_normal((3, 2)), rng.standard_normal((2, 3))
    res = fixed_order_synthesis(
        A, B, C, np.zeros((2, 2)), order=1, rng=rng, n_starts=2, polish=False
    )
    assert res.B.shape == (1, 2)
    assert res.num is None
    assert res.is_stable
    assert res.gamma >= res.gamma_full_order * (1 - 1e-6)
    assert np.all(closed_loop_poles((A, B, C, np.zeros((2, 2))), res.controller).real < 0)


@pytest.mark.parametrize(
    ("kwargs", "match"), [({"order": -1}, "order"), ({"n_starts": 0}, "n_starts")]
)
def test_bad_options_raise(kwargs, match):
    G = weighted_handlebar()
    with pytest.raises(MotosimError, match=match):
        fixed_order_synthesis(G.A, G.B, G.C, G.D, rng=np.random.default_rng(0), **kwargs)


def test_balanced_truncation_error_bound_and_unstable_part():
    rng = np.random.default_rng(2)
    n = 8
    A = rng.standard_normal((n, n))
    A -= (np.max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)
    B, C, D = rng.standard_normal((n, 2)), rng.standard_normal((2, n)), np.zeros((2, 2))
    R = balanced_truncation((A, B, C, D), 4)
    assert R.n_states == 4
    # Error bound 2 * sum(discarded Hankel singular values) (Glover 1984).
    from scipy.linalg import solve_continuous_lyapunov

    Wc = solve_continuous_lyapunov(A, -B @ B.T)
    Wo = solve_continuous_lyapunov(A.T, -C.T @ C)
    hsv = np.sort(np.sqrt(np.abs(np.linalg.eigvals(Wc @ Wo))))[::-1]
    Ae = np.block([[A, np.zeros((n, 4))], [np.zeros((4, n)), R.A]])
    err, _ = hinf_norm(Ae, np.vstack((B, R.B)), np.hstack((C, -R.C)), D - R.D)
    assert err <= 2 * hsv[4:].sum() * (1 + 1e-8)
    # An unstable pole is kept exactly.
    Au = np.block([[A, np.zeros((n, 1))], [np.zeros((1, n)), np.array([[0.7]])]])
    Bu, Cu = np.vstack((B, np.ones((1, 2)))), np.hstack((C, np.ones((2, 1))))
    Ru = balanced_truncation((Au, Bu, Cu, D), 3)
    assert np.any(np.isclose(np.linalg.eigvals(Ru.A), 0.7))
    with pytest.raises(MotosimError, match="poles with Re >= 0"):
        balanced_truncation((Au, Bu, Cu, D), 0)
    assert balanced_truncation((A, B, C, D), n) is not None
