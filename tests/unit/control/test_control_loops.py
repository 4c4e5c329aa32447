"""Unit tests of the positive-feedback four-block loop (eq. (25))."""

import math

import numpy as np
import pytest

from motosim.control import (
    StateSpace,
    closed_loop_poles,
    four_block_norm,
    four_block_system,
    frequency_response,
)
from motosim.errors import MotosimError


def _random_ss(rng, n, m, p, stable=True):
    A = rng.standard_normal((n, n))
    if stable:
        A -= (np.max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)
    return StateSpace(
        A, rng.standard_normal((n, m)), rng.standard_normal((p, n)), rng.standard_normal((p, m))
    )


@pytest.mark.parametrize(("m", "p"), [(1, 1), (2, 1), (1, 2), (2, 3)])
def test_four_block_matches_transfer_formula(m, p):
    rng = np.random.default_rng(10 * m + p)
    G = _random_ss(rng, 3, m, p)
    K = _random_ss(rng, 2, p, m)
    K = StateSpace(K.A, K.B, K.C, 0.1 * K.D)  # keep I - D_G D_K well conditioned
    T = four_block_system(G, K)
    assert (T.n_inputs, T.n_outputs, T.n_states) == (p + m, p + m, 5)
    for w in (0.0, 0.3, 2.0, 50.0, math.inf):
        Gw = frequency_response(G, w)
        Kw = frequency_response(K, w)
        S = np.linalg.inv(np.eye(p) - Gw @ Kw)  # positive feedback, eq. (24)
        expected = np.vstack((np.eye(p), Kw)) @ S @ np.hstack((np.eye(p), Gw))
        np.testing.assert_allclose(frequency_response(T, w), expected, rtol=1e-9, atol=1e-12)


def test_unstable_loop_gives_inf_and_poles():
    # G = 1/(s + 1), K = 2 (positive feedback): closed-loop pole at s = +1.
    G = ([[-1.0]], [[1.0]], [[1.0]], [[0.0]])
    K = (np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[2.0]])
    np.testing.assert_allclose(closed_loop_poles(G, K), [1.0])
    assert four_block_norm(G, K) == math.inf
    # K = -2 (i.e. negative feedback with gain 2): pole at -3, stable.
    K_neg = (np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[-2.0]])
    np.testing.assert_allclose(closed_loop_poles(G, K_neg), [-3.0])
    # T(s) = [1; -2] (1 + 2 G)^-1 [1, G] -> [1; -2] [1, 0] as s -> inf: sigma = sqrt(1 + 2^2),
    # above sigma_max(T(0)) = sqrt(5) sqrt(2) / 3 (analytic).
    assert four_block_norm(G, K_neg) == pytest.approx(math.sqrt(5), rel=1e-9)


def test_dimension_mismatch_and_ill_posed_loop_raise():
    G = ([[-1.0]], [[1.0, 0.0]], [[1.0]], [[0.0, 0.0]])  # 2 inputs, 1 output
    K = ([[-1.0]], [[1.0]], [[1.0]], [[0.0]])  # 1x1: wrong
    with pytest.raises(MotosimError, match="controller is 1x1"):
        four_block_norm(G, K)
    G1 = ([[-1.0]], [[1.0]], [[1.0]], [[1.0]])
    K1 = (np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[1.0]])
    with pytest.raises(MotosimError, match="not well posed"):
        four_block_system(G1, K1)
    with pytest.raises(MotosimError, match="tuple"):
        four_block_system(G1, ([[-1.0]], [[1.0]]))  # type: ignore[arg-type]
