"""The adaptive gradient law of eq. (9), with its sign corrected and normalised.

The paper minimises C_f = (tau_ref - Phi p)^2 / 2 with tau_ref = N k_t i_m and prints

    p' = -K Phi^T (N k_t i_m - Phi p)                                   (9, as printed)

Since dC_f/dp = -Phi^T (tau_ref - Phi p), that is gradient *ascent* for K > 0: the error grows
and the estimate diverges. The descent law is p' = +K Phi^T e, e = tau_ref - Phi p. With a
plain K it barely moves in a minute, because the columns of Phi differ by orders of magnitude
(RMS theta'' ~ 14 rad/s^2, theta' ~ 0.05 rad/s, sign ~ 0.9). The law used here scales each
parameter by its column's RMS, S = diag(1 / RMS(Phi_i)^2), and normalises by the regressor
size:

    p' = g S Phi^T e / (1 + Phi S Phi^T)

integrated by forward Euler at the sample period h (stable for g h < 2, since the normalised
step g h Phi S Phi^T / (1 + Phi S Phi^T) stays below g h). With g = 50 1/s it reaches Table I
to about 4 digits in about 30 s of a 0.1-2 Hz chirp (see the reference notes, section 7).
"""

import math
from typing import Literal

import numpy as np
from numba import njit
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.identification.least_squares import column_scale

__all__ = ["DIVERGENCE_LIMIT", "gradient_law"]

Array = NDArray[np.float64]

DIVERGENCE_LIMIT = 1e12
"""Scaled estimate size beyond which the law is declared diverged and stopped."""


@njit(cache=True)
def _gradient_kernel(
    A: Array, y: Array, q0: Array, step: float, passes: int, limit: float
) -> tuple[Array, int]:
    """Euler steps of q' = step/h * a^T e / (1 + a a^T) on scaled rows a; stops past limit."""
    n = A.shape[0]
    history = np.empty((n * passes, 3))
    q = q0.copy()
    k_out = 0
    for _ in range(passes):
        for k in range(n):
            a0, a1, a2 = A[k, 0], A[k, 1], A[k, 2]
            e = y[k] - (a0 * q[0] + a1 * q[1] + a2 * q[2])
            c = step * e / (1.0 + a0 * a0 + a1 * a1 + a2 * a2)
            q[0] += c * a0
            q[1] += c * a1
            q[2] += c * a2
            history[k_out] = q
            k_out += 1
            if abs(q[0]) + abs(q[1]) + abs(q[2]) > limit:
                return history[:k_out], k_out
    return history, k_out


def gradient_law(
    Phi: Array,
    y: Array,
    h: float,
    *,
    gain: float = 50.0,
    passes: int = 1,
    initial: Array | None = None,
    sign: Literal["descent", "printed"] = "descent",
) -> Array:
    """Run the normalised adaptive gradient law over the rows of eq. (8).

    Parameters
    ----------
    Phi : ndarray, shape (n, 3)
        Rows [theta_h'', theta_h', sign(theta_h')].
    y : ndarray, shape (n,)
        tau_ref = N k_t i_m [N*m].
    h : float
        Time between rows [s] (the sample period); the adaptation is integrated over it.
    gain : float
        g [1/s], > 0, with g h < 2 for stability of the discretised law.
    passes : int
        How many times the rows are replayed (off-line use of a short log), >= 1.
    initial : ndarray, shape (3,), optional
        Starting estimate [J_eq, beta_eq, beta_s]; zeros by default.
    sign : {"descent", "printed"}
        "descent" is the corrected law; "printed" is eq. (9) as printed (gradient ascent),
        kept to show that it diverges.

    Returns
    -------
    ndarray, shape (m, 3)
        The estimate after each row, m = n passes; shorter if the estimate grew past
        :data:`DIVERGENCE_LIMIT` (scaled), where the run stops.

    Raises
    ------
    MotosimError
        On invalid options or a zero regressor column.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> Phi = np.column_stack([14 * rng.standard_normal(6000), 0.05 * rng.standard_normal(6000),
    ...                        np.sign(rng.standard_normal(6000))])
    >>> history = gradient_law(Phi, Phi @ np.array([0.0415, 13.956, 1.734]), 0.01)
    >>> np.round(history[-1], 4)
    array([ 0.0415, 13.956 ,  1.734 ])
    """
    if not (math.isfinite(h) and h > 0.0):
        raise MotosimError(f"h = {h!r}; expected a sample period > 0 [s]")
    if not (math.isfinite(gain) and 0.0 < gain * h < 2.0):
        raise MotosimError(
            f"gain = {gain!r} 1/s with h = {h:g} s; expected 0 < gain * h < 2 for stability"
        )
    if passes < 1:
        raise MotosimError(f"passes = {passes!r}; expected >= 1")
    if sign not in ("descent", "printed"):
        raise MotosimError(f"sign = {sign!r}; expected 'descent' or 'printed'")
    rms = column_scale(Phi)
    A = np.ascontiguousarray(Phi / rms)
    q0 = np.zeros(3) if initial is None else np.asarray(initial, dtype=float) * rms
    step = gain * h * (1.0 if sign == "descent" else -1.0)
    history, _ = _gradient_kernel(
        A, np.ascontiguousarray(y, dtype=float), q0, step, int(passes), DIVERGENCE_LIMIT
    )
    return history / rms
