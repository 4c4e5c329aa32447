"""Model reduction by balanced truncation (square-root method), unstable part kept.

Used to seed the fixed-order search of :mod:`motosim.control.fixed_order` with a reduced
version of the full-order Glover-McFarlane controller, as HIFOO's ``INIT`` option does.
"""

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import schur, solve_continuous_lyapunov, solve_sylvester

from motosim.control.statespace import StateSpace, StateSpaceLike, as_state_space
from motosim.errors import MotosimError

__all__ = ["balanced_truncation"]

Array = NDArray[np.float64]


def _psd_factor(W: Array) -> Array:
    """A factor L with ``L L^T = W`` for a symmetric positive semidefinite W."""
    w, V = np.linalg.eigh(0.5 * (W + W.T))
    return np.asarray(V * np.sqrt(np.clip(w, 0.0, None))[None, :], dtype=np.float64)


def balanced_truncation(system: StateSpaceLike, order: int) -> StateSpace:
    """Reduce ``system`` to at most ``order`` states by balanced truncation.

    Parameters
    ----------
    system : StateSpace or tuple (A, B, C, D)
        The system to reduce; it may have poles in the closed right half-plane, which are
        kept exactly (additive stable/unstable decomposition).
    order : int
        Number of states wanted (>= number of poles with Re >= 0).

    Returns
    -------
    StateSpace
        The reduced system, same D. It has fewer than ``order`` states only when the stable
        part has fewer controllable-and-observable modes; returned unchanged if
        ``order >= n``.

    Raises
    ------
    MotosimError
        If ``order < 0`` or ``order`` is smaller than the number of unstable poles.

    Notes
    -----
    The stable part ``(A_s, B_s, C_s)`` is reduced with the square-root method: Gramians
    ``A_s W_c + W_c A_s^T + B_s B_s^T = 0``, ``A_s^T W_o + W_o A_s + C_s^T C_s = 0``, factors
    ``W_c = L_c L_c^T``, ``W_o = L_o L_o^T``, SVD ``L_o^T L_c = U Sigma V^T``; the kept states are
    those of the largest Hankel singular values ``Sigma``. The error bound is
    ``||G - G_r||_inf <= 2 sum(discarded Sigma)``.
    """
    sys = as_state_space(system)
    n = sys.n_states
    if not isinstance(order, int | np.integer) or order < 0:
        raise MotosimError(f"order = {order!r}; expected an integer >= 0")
    if order >= n:
        return sys
    A, B, C = sys.A, sys.B, sys.C
    T, Z, n_s = schur(A, output="real", sort="lhp")
    n_u = n - int(n_s)
    if n_u > order:
        raise MotosimError(
            f"system has {n_u} poles with Re >= 0; cannot reduce it to {order} states"
        )
    Bt = Z.T @ B
    Ct = C @ Z
    A11, A12, A22 = T[:n_s, :n_s], T[:n_s, n_s:], T[n_s:, n_s:]
    B1, B2 = Bt[:n_s], Bt[n_s:]
    C1, C2 = Ct[:, :n_s], Ct[:, n_s:]
    if n_u > 0 and n_s > 0:
        # Decouple: A11 X - X A22 + A12 = 0, x = [[I, X], [0, I]] x~.
        X = solve_sylvester(A11, -A22, -A12)
        B1 = B1 - X @ B2
        C2 = C1 @ X + C2
    r = order - n_u
    if n_s > 0 and r > 0:
        Lc = _psd_factor(solve_continuous_lyapunov(A11, -B1 @ B1.T))
        Lo = _psd_factor(solve_continuous_lyapunov(A11.T, -C1.T @ C1))
        U, hsv, Vt = np.linalg.svd(Lo.T @ Lc)
        r = min(r, int(np.sum(hsv > 1e-13 * max(float(hsv[0]), 1e-300))))
        s = 1.0 / np.sqrt(hsv[:r])
        Tl = (U[:, :r] * s[None, :]).T @ Lo.T
        Tr = Lc @ (Vt[:r].T * s[None, :])
        Ar, Br, Cr = Tl @ A11 @ Tr, Tl @ B1, C1 @ Tr
    else:
        Ar = np.zeros((0, 0))
        Br = np.zeros((0, B.shape[1]))
        Cr = np.zeros((C.shape[0], 0))
    nr = Ar.shape[0]
    Ared = np.zeros((nr + n_u, nr + n_u))
    Ared[:nr, :nr] = Ar
    Ared[nr:, nr:] = A22
    return StateSpace(Ared, np.vstack((Br, B2)), np.hstack((Cr, C2)), sys.D)
