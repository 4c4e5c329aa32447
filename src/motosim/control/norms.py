"""The H-infinity norm of a stable continuous-time system, by Hamiltonian level sets.

For ``G(s) = C (sI - A)^-1 B + D`` with A Hurwitz,

.. math::  \\|G\\|_\\infty = \\sup_{\\omega} \\sigma_{max}(G(j\\omega)),

and ``gamma > sigma_max(D)`` is a singular value of ``G(j omega)`` exactly when ``j omega`` is
an eigenvalue of the Hamiltonian matrix ``H(gamma)`` below. The two-step iteration of
Boyd & Balakrishnan (1990) and Bruinsma & Steinbuch (1990) raises a lower bound ``gamma_lb``:
it finds the imaginary-axis eigenvalues of ``H((1 + 2 rtol) gamma_lb)``, evaluates
``sigma_max`` at the midpoints of the frequency intervals they bound, and stops when the
Hamiltonian has no imaginary eigenvalue, so that ``gamma_lb <= ||G|| <= (1 + 2 rtol) gamma_lb``.
Convergence is quadratic. This is what SLICOT AB13DD implements (without its structure-
preserving eigensolver); our tests compare the two.

This module is the design-time norm used by :mod:`motosim.control.ncf` and
:mod:`motosim.control.fixed_order`; it depends only on numpy and scipy.
"""

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import eigvals, matrix_balance

from motosim.control.statespace import _from_array_likes
from motosim.errors import MotosimError

__all__ = ["hinf_norm"]

Array = NDArray[np.float64]

# |Re(lambda)| below this fraction of |lambda| counts as "on the imaginary axis". A false
# positive only costs one more frequency evaluation; a false negative would stop too early.
_IMAG_RTOL = 1e-6
_IMAG_ATOL = 1e-10
# Below (1 + _NEAR_D) sigma_max(D) the Hamiltonian's R^-1 is ill conditioned: use the pencil.
_NEAR_D = 1e-3
# Poles with Re(p) >= -_STAB_RTOL * ||A||_1 are treated as on or right of the imaginary axis.
_STAB_RTOL = 1e-12
_MAX_ITER = 60


def hinf_norm(
    A: ArrayLike, B: ArrayLike, C: ArrayLike, D: ArrayLike, *, rtol: float = 1e-10
) -> tuple[float, float]:
    """H-infinity norm of a stable continuous-time system and the frequency of its peak.

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix [1/s]; must be Hurwitz (every pole strictly in the left half-plane).
    B : array_like, shape (n, m)
        Input matrix.
    C : array_like, shape (p, n)
        Output matrix.
    D : array_like, shape (p, m)
        Direct feedthrough.
    rtol : float, optional
        Relative accuracy of the returned norm: the true norm lies in
        ``[gamma, (1 + 2 rtol) gamma]``. Default 1e-10.

    Returns
    -------
    gamma : float
        ``||G||_inf = sup_omega sigma_max(G(j omega))`` (same unit as y/u).
    omega_peak : float
        A frequency where the supremum is attained [rad/s]; ``math.inf`` when the peak is
        ``sigma_max(D)`` at infinite frequency. ``0.0`` for the zero system.

    Raises
    ------
    MotosimError
        If the shapes do not match, an entry is NaN or infinite, ``rtol`` is not in
        (0, 1e-2], or A has a pole on or right of the imaginary axis (the norm is then
        infinite, or the L-infinity norm is not the H-infinity norm).

    Notes
    -----
    With ``B~ = B / sqrt(gamma)``, ``C~ = C / sqrt(gamma)``, ``D~ = D / gamma``,
    ``R = I - D~^T D~`` and ``S = I - D~ D~^T`` (both positive definite for
    ``gamma > sigma_max(D)``)::

        H(gamma) = [[ A + B~ R^-1 D~^T C~,        B~ R^-1 B~^T            ],
                    [ -C~^T S^-1 C~,         -(A + B~ R^-1 D~^T C~)^T    ]]

    has ``j omega`` as an eigenvalue if and only if ``gamma`` is a singular value of
    ``G(j omega)`` (Boyd, Balakrishnan & Kabamba 1989). The initial lower bound is the
    largest of ``sigma_max(D)``, ``sigma_max(G(0))`` and ``sigma_max(G(j omega))`` at the
    pole magnitudes and damped frequencies of A. An eigenvalue counts as imaginary when
    ``|Re lambda| <= 1e-6 |lambda| + 1e-10 ||H||_1`` (a relative test, robust to the scaling
    of stiff models, with a floor for eigenvalues near zero); A is balanced first. For levels
    below ``(1 + 1e-3) sigma_max(D)``, where ``R^-1`` blows up, the same eigenvalues are
    taken (by QZ) from the extended pencil that needs no inverse::

        [[A, 0, B, 0], [0, -A^T, 0, -C^T], [C, 0, D, -gamma I], [0, B^T, -gamma I, D^T]]
        - s diag(I, I, 0, 0)

    References
    ----------
    S. Boyd, V. Balakrishnan, "A regularity result for the singular values of a transfer
    matrix and a quadratically convergent algorithm for computing its L-infinity norm",
    Systems & Control Letters 15:1-7, 1990.
    N. A. Bruinsma, M. Steinbuch, "A fast algorithm to compute the H-infinity-norm of a
    transfer function matrix", Systems & Control Letters 14:287-293, 1990.

    Examples
    --------
    >>> gamma, omega = hinf_norm([[0.0, 1.0], [-1.0, -0.2]], [[0.0], [1.0]], [[1.0, 0.0]], [[0.0]])
    >>> round(gamma, 6), round(omega, 4)
    (5.025189, 0.9899)
    """
    sys = _from_array_likes(A, B, C, D)
    if not (math.isfinite(rtol) and 0.0 < rtol <= 1e-2):
        raise MotosimError(f"rtol = {rtol!r}; expected 0 < rtol <= 1e-2")
    if sys.n_states > 0:
        poles = np.linalg.eigvals(sys.A).astype(np.complex128)
        alpha = float(np.max(poles.real))
        if alpha >= -_STAB_RTOL * float(np.linalg.norm(sys.A, 1)):
            raise MotosimError(
                f"A has a pole at {complex(poles[np.argmax(poles.real)]):.6g} on or right of "
                "the imaginary axis; the H-infinity norm needs a stable (Hurwitz) A"
            )
    else:
        poles = np.zeros(0, dtype=np.complex128)
    return _hinf_norm_stable(sys.A, sys.B, sys.C, sys.D, poles, rtol)


def _sigma_max_many(A: Array, B: Array, C: Array, D: Array, omega: Array) -> Array:
    """Largest singular value of ``G(j omega_i)`` for each entry of ``omega`` (inf allowed)."""
    out = np.empty(omega.shape[0])
    inf = np.isinf(omega)
    if np.any(inf):
        out[inf] = float(np.linalg.norm(D, 2)) if D.size else 0.0
    w = omega[~inf]
    if w.size:
        n = A.shape[0]
        M = 1j * w[:, None, None] * np.eye(n)[None, :, :] - A[None, :, :]
        X = np.linalg.solve(M, np.broadcast_to(B, (w.size, *B.shape)))
        G = C[None, :, :] @ X + D[None, :, :]
        out[~inf] = np.linalg.svd(G, compute_uv=False)[:, 0]
    return out


def _hamiltonian(A: Array, B: Array, C: Array, D: Array, gamma: float) -> Array:
    """The Hamiltonian H(gamma) of the Notes of :func:`hinf_norm`."""
    Bt = B / math.sqrt(gamma)
    Ct = C / math.sqrt(gamma)
    if not np.any(D):
        return np.block([[A, Bt @ Bt.T], [-Ct.T @ Ct, -A.T]])
    Dt = D / gamma
    Rinv = np.linalg.inv(np.eye(B.shape[1]) - Dt.T @ Dt)
    Sinv = np.linalg.inv(np.eye(C.shape[0]) - Dt @ Dt.T)
    BtRinv = Bt @ Rinv
    Ar = A + BtRinv @ (Dt.T @ Ct)
    return np.block([[Ar, BtRinv @ Bt.T], [-Ct.T @ Sinv @ Ct, -Ar.T]])


def _imaginary_frequencies(H: Array, N: Array | None = None) -> Array:
    """Sorted distinct omega >= 0 with j omega (numerically) an eigenvalue of H (or H - s N)."""
    if N is None:
        lam = np.linalg.eigvals(H)
    else:
        ab = eigvals(H, N, homogeneous_eigvals=True)
        alpha, beta = ab[0], ab[1]
        finite = np.abs(beta) > 1e-13 * np.abs(alpha)
        lam = alpha[finite] / beta[finite]
    # Relative test, plus an absolute floor for eigenvalues that are small compared with
    # ||H|| (their real parts carry an absolute error of order eps ||H||).
    floor = _IMAG_ATOL * float(np.linalg.norm(H, 1))
    on_axis = np.abs(lam.real) <= _IMAG_RTOL * np.abs(lam) + floor
    w = np.sort(np.abs(lam[on_axis].imag))
    if w.size == 0:
        return w
    keep = np.concatenate(([True], np.diff(w) > 1e-12 * np.maximum(w[1:], 1e-300)))
    return w[keep]


def _pencil(A: Array, B: Array, C: Array, D: Array, gamma: float) -> tuple[Array, Array]:
    """Extended pencil ``M - s N`` whose finite eigenvalues are those of H(gamma).

    ``(x, q, u, v)`` with ``s x = A x + B u``, ``s q = -A^T q - C^T v``,
    ``C x + D u = gamma v`` and ``B^T q + D^T v = gamma u``: no inverse of
    ``gamma^2 I - D^T D`` is formed, so levels just above ``sigma_max(D)`` stay well
    conditioned (QZ is backward stable on the pencil).
    """
    n, m = B.shape
    p = C.shape[0]
    Z = np.zeros
    M = np.block(
        [
            [A, Z((n, n)), B, Z((n, p))],
            [Z((n, n)), -A.T, Z((n, m)), -C.T],
            [C, Z((p, n)), D, -gamma * np.eye(p)],
            [Z((m, n)), B.T, -gamma * np.eye(m), D.T],
        ]
    )
    N = np.zeros_like(M)
    N[: 2 * n, : 2 * n] = np.eye(2 * n)
    return M, N


def _hinf_norm_stable(
    A: Array,
    B: Array,
    C: Array,
    D: Array,
    poles: NDArray[np.complex128],
    rtol: float,
    omega_hint: float | None = None,
) -> tuple[float, float]:
    """Level-set iteration for a system already known to be stable; see :func:`hinf_norm`.

    ``omega_hint`` [rad/s] (e.g. the previous peak in an optimisation loop) is added to the
    frequencies that give the initial lower bound.
    """
    n = A.shape[0]
    if B.shape[1] == 0 or C.shape[0] == 0:
        return 0.0, 0.0
    sigma_D = float(np.linalg.norm(D, 2))
    if n == 0:
        return sigma_D, math.inf
    # Balance A (a diagonal similarity leaves G unchanged) for stiff models.
    Ab, (scale, _) = matrix_balance(A, permute=False, separate=True)
    Bb = B / scale[:, None]
    Cb = C * scale[None, :]
    # Initial lower bound: infinity, DC, pole magnitudes and damped frequencies.
    hint = [] if omega_hint is None else [omega_hint]
    candidates = np.concatenate(([0.0], np.abs(poles), np.abs(poles.imag), hint))
    candidates = np.unique(candidates[np.isfinite(candidates)])
    gamma_lb, omega_lb = sigma_D, math.inf
    values = _sigma_max_many(Ab, Bb, Cb, D, candidates)
    best = int(np.argmax(values))
    if values[best] > gamma_lb:
        gamma_lb, omega_lb = float(values[best]), float(candidates[best])
    if gamma_lb == 0.0:
        return 0.0, 0.0
    for _ in range(_MAX_ITER):
        gamma = (1.0 + 2.0 * rtol) * gamma_lb
        if gamma < (1.0 + _NEAR_D) * sigma_D:
            w = _imaginary_frequencies(*_pencil(Ab, Bb, Cb, D, gamma))
        else:
            w = _imaginary_frequencies(_hamiltonian(Ab, Bb, Cb, D, gamma))
        if w.size == 0:
            break
        trial = np.concatenate((w, 0.5 * (w[:-1] + w[1:])))
        values = _sigma_max_many(Ab, Bb, Cb, D, trial)
        best = int(np.argmax(values))
        if values[best] <= gamma_lb:
            break  # spurious detections only: the bound cannot be raised any further
        gamma_lb, omega_lb = float(values[best]), float(trial[best])
    return gamma_lb, omega_lb
