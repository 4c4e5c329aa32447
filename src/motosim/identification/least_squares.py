"""Batch and recursive least squares on the regression of eq. (8).

Both solve min_p sum_k (y_k - Phi_k p)^2 over the used rows. Batch least squares also gives
95 % confidence intervals from the residual variance; recursive least squares gives the
history of the estimate, like the adaptive gradient law of eq. (9) but without a gain to tune.

Both inherit the bias of the differentiated regressors: at 100 Hz the handlebar time constant
J_eq / beta_eq (about 3 ms) is shorter than the sample period, and theta_h'' is poorly seen.
:mod:`motosim.identification.output_error` removes that bias.
"""

import math

import numpy as np
from numpy.typing import NDArray
from scipy import stats

from motosim.errors import MotosimError

__all__ = ["CONDITION_LIMIT", "batch_least_squares", "column_scale", "recursive_least_squares"]

Array = NDArray[np.float64]

CONDITION_LIMIT = 1e4
"""Largest condition number of the column-scaled regressor accepted as identifiable."""


def column_scale(Phi: Array) -> Array:
    """RMS of each regressor column, shape (3,); the per-parameter normalisation.

    Raises
    ------
    MotosimError
        If a column is identically zero (that parameter cannot be identified).
    """
    rms = np.sqrt(np.mean(Phi**2, axis=0))
    names = ("theta_h''", "theta_h'", "sign(theta_h')")
    for name, r in zip(names, rms, strict=True):
        if not (r > 0.0):
            raise MotosimError(
                f"excitation too poor to identify: regressor column {name} is zero; expected a "
                "moving handlebar"
            )
    return np.asarray(rms, dtype=float)


def _check_conditioning(Phi: Array) -> Array:
    if Phi.shape[0] < Phi.shape[1] * 5:
        raise MotosimError(
            f"excitation too poor to identify: {Phi.shape[0]} samples with the handlebar "
            f"moving; expected at least {Phi.shape[1] * 5}"
        )
    rms = column_scale(Phi)
    cond = float(np.linalg.cond(Phi / rms))
    if not (cond < CONDITION_LIMIT):
        raise MotosimError(
            f"excitation too poor to identify: scaled regressor condition number {cond:.3g}; "
            f"expected below {CONDITION_LIMIT:g} (excite more frequencies and amplitudes)"
        )
    return np.asarray(rms, dtype=float)


def batch_least_squares(Phi: Array, y: Array, *, confidence: float = 0.95) -> tuple[Array, Array]:
    """Least-squares estimate of p = [J_eq, beta_eq, beta_s] and its confidence intervals.

    Parameters
    ----------
    Phi : ndarray, shape (n, 3)
        Rows [theta_h'', theta_h', sign(theta_h')] of eq. (8).
    y : ndarray, shape (n,)
        N k_t i_m [N*m].
    confidence : float
        Level of the two-sided intervals, in (0, 1).

    Returns
    -------
    p : ndarray, shape (3,)
        [J_eq kg*m^2, beta_eq N*m*s/rad, beta_s N*m].
    interval : ndarray, shape (3, 2)
        Lower and upper bounds, p_i -/+ t_{(1+c)/2, n-3} sigma sqrt((Phi^T Phi)^-1_ii) with
        sigma^2 the residual variance. They assume independent residuals; the smoothing
        filter correlates neighbouring rows, so they are optimistic by about the square
        root of the window length in samples.

    Raises
    ------
    MotosimError
        If the excitation is too poor (rank, conditioning or too few rows).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> Phi = rng.standard_normal((200, 3))
    >>> p, ci = batch_least_squares(Phi, Phi @ np.array([0.04, 14.0, 1.7]))
    >>> np.round(p, 6)
    array([ 0.04, 14.  ,  1.7 ])
    """
    if not (0.0 < confidence < 1.0):
        raise MotosimError(f"confidence = {confidence!r}; expected in (0, 1)")
    rms = _check_conditioning(Phi)
    A = Phi / rms
    q, *_ = np.linalg.lstsq(A, y, rcond=None)
    residual = y - A @ q
    dof = Phi.shape[0] - Phi.shape[1]
    sigma2 = float(residual @ residual) / dof
    cov = sigma2 * np.linalg.inv(A.T @ A)
    half = float(stats.t.ppf(0.5 + 0.5 * confidence, dof)) * np.sqrt(np.diag(cov))
    p = q / rms
    half = half / rms
    return p, np.column_stack([p - half, p + half])


def recursive_least_squares(
    Phi: Array,
    y: Array,
    *,
    forgetting: float = 1.0,
    initial: Array | None = None,
    initial_covariance: float = 1e6,
) -> Array:
    """Recursive least squares on the rows of eq. (8), one row at a time.

    p_k = p_{k-1} + g_k (y_k - Phi_k p_{k-1}), g_k = P_{k-1} Phi_k^T / (lambda + Phi_k P_{k-1}
    Phi_k^T), P_k = (P_{k-1} - g_k Phi_k P_{k-1}) / lambda, run on column-scaled regressors so
    that one ``initial_covariance`` suits all three parameters.

    Parameters
    ----------
    Phi : ndarray, shape (n, 3)
        Rows of eq. (8).
    y : ndarray, shape (n,)
        N k_t i_m [N*m].
    forgetting : float
        lambda in (0, 1]; 1 weighs all rows equally (the batch solution, up to the prior).
    initial : ndarray, shape (3,), optional
        Starting estimate; zeros by default.
    initial_covariance : float
        P_0 = initial_covariance I on the scaled parameters, > 0.

    Returns
    -------
    ndarray, shape (n, 3)
        The estimate after each row.

    Raises
    ------
    MotosimError
        On invalid options or too poor an excitation.
    """
    if not (0.0 < forgetting <= 1.0):
        raise MotosimError(f"forgetting = {forgetting!r}; expected in (0, 1]")
    if not (math.isfinite(initial_covariance) and initial_covariance > 0.0):
        raise MotosimError(f"initial_covariance = {initial_covariance!r}; expected > 0")
    rms = _check_conditioning(Phi)
    A = Phi / rms
    q = np.zeros(3) if initial is None else np.asarray(initial, dtype=float) * rms
    P = initial_covariance * np.eye(3)
    history = np.empty((A.shape[0], 3))
    for k in range(A.shape[0]):
        a = A[k]
        Pa = P @ a
        g = Pa / (forgetting + a @ Pa)
        q = q + g * (y[k] - a @ q)
        P = (P - np.outer(g, Pa)) / forgetting
        P = 0.5 * (P + P.T)  # keep the covariance symmetric against round-off
        history[k] = q
    return history / rms
