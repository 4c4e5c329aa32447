"""Unit tests of the Glover-McFarlane synthesis motosim.control.ncfsyn."""

import math

import numpy as np
import pytest

from motosim.control import StateSpace, closed_loop_poles, four_block_norm, ncfsyn
from motosim.errors import MotosimError

J_H, BETA = 0.0415, 13.956  # handlebar inertia [kg m^2] and viscous friction [N m s/rad], Table I


def handlebar(n_kt: float) -> StateSpace:
    """G_h = N k_t / (J s^2 + beta s), x = [theta_h, theta_h'] (eq. (10) with unit weights)."""
    return StateSpace(
        np.array([[0.0, 1.0], [0.0, -BETA / J_H]]),
        np.array([[0.0], [n_kt / J_H]]),
        np.array([[1.0, 0.0]]),
        np.array([[0.0]]),
    )


@pytest.mark.parametrize("factor", [1.0, 0.9, 0.0, -1.1, math.nan, math.inf])
def test_factor_not_above_one_raises(factor):
    G = handlebar(1.0)
    with pytest.raises(MotosimError, match="factor"):
        ncfsyn(G.A, G.B, G.C, G.D, factor=factor)


def test_unstabilisable_plant_raises():
    with pytest.raises(MotosimError, match="stabilisable"):
        ncfsyn([[1.0]], [[0.0]], [[1.0]], [[0.0]])


@pytest.mark.parametrize("n_kt", [0.02, 1.0, 20.0])
def test_handlebar_positive_feedback_convention(n_kt):
    # Unit-weight handlebar: gamma_min between sqrt(2) and 1.4172 for N k_t in [0.02, 20]
    # (algorithms notes Sec. 1.4, measured with scipy and SLICOT SB10ID).
    G = handlebar(n_kt)
    res = ncfsyn(G.A, G.B, G.C, G.D, factor=1.1)
    assert math.sqrt(2) - 1e-9 <= res.gamma_min <= 1.4173
    assert res.gamma == pytest.approx(1.1 * res.gamma_min)
    assert np.all(closed_loop_poles(G, res.controller).real < 0)
    assert four_block_norm(G, res.controller) <= res.gamma
    # The same matrices used with negative feedback (u = -K y) do not stabilise this plant.
    K_neg = StateSpace(res.A, res.B, -res.C, -res.D)
    assert four_block_norm(G, K_neg) == math.inf


def test_random_plants_with_feedthrough_meet_the_bound():
    # The closed form guarantees ||[I; K](I - G K)^-1 [I, G]||_inf <= gamma (S&P eq. (9.86)),
    # also with D != 0; checked on random MIMO plants, unstable ones included.
    rng = np.random.default_rng(42)
    for _ in range(25):
        n, m, p = (int(v) for v in rng.integers(1, [6, 3, 3], endpoint=True))
        A = rng.standard_normal((n, n))
        B, C = rng.standard_normal((n, m)), rng.standard_normal((p, n))
        D = rng.standard_normal((p, m)) * float(rng.random() < 0.7)
        for factor in (1.05, 1.5):
            res = ncfsyn(A, B, C, D, factor)
            assert res.A.shape == (n, n)
            assert res.B.shape == (n, p)
            assert res.C.shape == (m, n)
            assert res.D.shape == (m, p)
            assert res.gamma_min >= 1.0
            gamma = four_block_norm((A, B, C, D), res.controller)
            assert gamma <= res.gamma * (1 + 1e-8)
            assert gamma >= res.gamma_min * (1 - 1e-6)


def test_result_is_frozen():
    G = handlebar(1.0)
    res = ncfsyn(G.A, G.B, G.C, G.D)
    with pytest.raises(AttributeError):
        res.gamma = 2.0  # type: ignore[misc]
