"""Glover-McFarlane normalized-coprime-factor H-infinity loop shaping (``ncfsyn``).

The paper (Section IV, eqs. (21)-(25)) models the handlebar uncertainty as a perturbation
of the normalized left coprime factors ``G_h = M^-1 N_h`` and asks for the controller that
minimises the four-block norm of eq. (25) for the shaped plant ``G_s = W_2 G_h W_1``. For the
full-order problem the optimum and a suboptimal controller are given in closed form by two
Riccati equations (Glover & McFarlane 1989; Skogestad & Postlethwaite 2005, Sec. 9.4). The
final controller for the real plant is ``K = W_1 K_s W_2``; this module handles ``K_s``.
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import solve_continuous_are

from motosim.control.statespace import StateSpace, _from_array_likes
from motosim.errors import MotosimError

__all__ = ["NcfsynResult", "ncfsyn"]

Array = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class NcfsynResult:
    """A Glover-McFarlane loop-shaping controller ``K_s`` and its robustness level.

    Attributes
    ----------
    gamma_min : float
        Optimal four-block norm ``gamma_min = 1 / epsilon_max = sqrt(1 + rho(X Z))`` over all
        stabilising controllers (dimensionless, >= 1).
    gamma : float
        Level the controller was built for, ``factor * gamma_min``; the four-block norm of
        eq. (25) with this controller is <= ``gamma``.
    A, B, C, D : NDArray[np.float64]
        Controller state space, shapes (n, n), (n, p), (m, n), (m, p): ``u = K_s y`` in the
        **positive**-feedback convention of eq. (24), loop ``(I - G_s K_s)^-1``.
    """

    gamma_min: float
    gamma: float
    A: Array
    B: Array
    C: Array
    D: Array

    @property
    def controller(self) -> StateSpace:
        """The controller as a :class:`~motosim.control.statespace.StateSpace`."""
        return StateSpace(self.A, self.B, self.C, self.D)


def ncfsyn(
    A: ArrayLike, B: ArrayLike, C: ArrayLike, D: ArrayLike, factor: float = 1.1
) -> NcfsynResult:
    """Glover-McFarlane loop-shaping controller for the shaped plant ``G_s = (A, B, C, D)``.

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix of the shaped plant [1/s]; poles on the imaginary axis (the
        handlebar's integrator) are allowed.
    B : array_like, shape (n, m)
        Input matrix (m plant inputs, e.g. motor current [A]).
    C : array_like, shape (p, n)
        Output matrix (p measurements, e.g. ``theta_h`` [rad]).
    D : array_like, shape (p, m)
        Direct feedthrough; any value (``D = 0`` is the usual strictly proper case).
    factor : float, optional
        ``gamma = factor * gamma_min``; must be > 1 (the central formula is singular at the
        optimum). 1.1 is the customary choice; values below about 1.01 give badly
        conditioned controllers with very fast poles.

    Returns
    -------
    NcfsynResult
        ``gamma_min``, ``gamma`` and the controller ``(A, B, C, D)`` with n states, in the
        positive-feedback convention ``u = K_s y``, loop ``(I - G_s K_s)^-1`` (eq. (24)).
        For a negative-feedback implementation ``u = -K' y`` use ``K' = -K_s``.

    Raises
    ------
    MotosimError
        If ``factor <= 1`` or is not finite, the matrices are inconsistent or not finite, or
        the Riccati equations have no stabilising solution ((A, B) not stabilisable or
        (C, A) not detectable).

    Notes
    -----
    With ``S = I + D^T D``, ``R = I + D D^T`` and ``A_r = A - B S^-1 D^T C``, X and Z are the
    stabilising solutions of the generalised control and filter Riccati equations::

        A_r^T X + X A_r - X B S^-1 B^T X + C^T R^-1 C = 0
        A_r Z + Z A_r^T - Z C^T R^-1 C Z + B S^-1 B^T = 0

    ``gamma_min = sqrt(1 + rho(X Z))``, and for ``gamma > gamma_min``, with
    ``L = (1 - gamma^2) I + X Z`` and ``F = -S^-1 (D^T C + B^T X)``::

        A_K = A + B F + gamma^2 L^-T Z C^T (C + D F)
        B_K = gamma^2 L^-T Z C^T,   C_K = B^T X,   D_K = -D^T

    is a positive-feedback controller with
    ``|| [I; K] (I - G_s K)^-1 [I, G_s] ||_inf <= gamma`` (eq. (25) without ``G_w``).
    This is Skogestad & Postlethwaite, eqs. (9.86)-(9.88), and SLICOT SB10ID.

    References
    ----------
    K. Glover, D. McFarlane, "Robust stabilization of normalized coprime factor plant
    descriptions with H-infinity-bounded uncertainty", IEEE TAC 34(8):821-830, 1989.
    S. Skogestad, I. Postlethwaite, *Multivariable Feedback Control*, 2nd ed., Wiley 2005,
    Sec. 9.4.1-9.4.2, Example 9.3.

    Examples
    --------
    Unit-weight handlebar ``G_h = 1 / (J s^2 + beta s)``, J = 0.0415 kg m^2,
    beta = 13.956 N m s/rad (Table I):

    >>> J, beta = 0.0415, 13.956
    >>> res = ncfsyn([[0.0, 1.0], [0.0, -beta / J]], [[0.0], [1.0 / J]], [[1.0, 0.0]], [[0.0]])
    >>> round(res.gamma_min, 5)
    1.41436
    """
    plant = _from_array_likes(A, B, C, D)
    if not (isinstance(factor, int | float) and math.isfinite(factor) and factor > 1.0):
        raise MotosimError(f"factor = {factor!r}; expected a finite number > 1")
    n, m, p = plant.n_states, plant.n_inputs, plant.n_outputs
    if n == 0 or m == 0 or p == 0:
        raise MotosimError(f"plant has n, m, p = {n}, {m}, {p}; expected all >= 1")
    Ap, Bp, Cp, Dp = plant.A, plant.B, plant.C, plant.D
    S = np.eye(m) + Dp.T @ Dp
    R = np.eye(p) + Dp @ Dp.T
    Ar = Ap - Bp @ np.linalg.solve(S, Dp.T @ Cp)
    try:
        X = solve_continuous_are(Ar, Bp, Cp.T @ np.linalg.solve(R, Cp), S)
        Z = solve_continuous_are(Ar.T, Cp.T, Bp @ np.linalg.solve(S, Bp.T), R)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise MotosimError(
            f"no stabilising Riccati solution ({exc}); the shaped plant must be stabilisable "
            "and detectable"
        ) from None
    X = 0.5 * (X + X.T)
    Z = 0.5 * (Z + Z.T)
    rho = float(np.max(np.abs(np.linalg.eigvals(X @ Z))))
    gamma_min = math.sqrt(1.0 + rho)
    gamma = factor * gamma_min
    g2 = gamma * gamma
    L = (1.0 - g2) * np.eye(n) + X @ Z
    F = -np.linalg.solve(S, Dp.T @ Cp + Bp.T @ X)
    LtinvZCt = np.linalg.solve(L.T, Z @ Cp.T)
    Ak = Ap + Bp @ F + g2 * LtinvZCt @ (Cp + Dp @ F)
    Bk = g2 * LtinvZCt
    Ck = Bp.T @ X
    Dk = -Dp.T.copy()
    return NcfsynResult(gamma_min=gamma_min, gamma=gamma, A=Ak, B=Bk, C=Ck, D=Dk)
