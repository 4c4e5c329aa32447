"""Levant's first-order robust exact (super-twisting) differentiator, discretised.

The rider-torque observer of section III needs the handlebar rate theta_h' as an extra output
(eq. (15), y_a = [theta_h, theta_h']) and obtains it by differentiating the measured angle
with "a robust super-twisting exact differentiator" (the paper's ref. [21], Levant 1998).
This module provides that block in the run layer: a pure one-sample kernel compiled with
numba, a small stepper class around it and a batch function over the same kernel.

Continuous form, for an input f with |f''| <= L::

    z0' = -lambda_1 L^(1/2) |z0 - f|^(1/2) sign(z0 - f) + z1
    z1' = -lambda_0 L sign(z0 - f)

with Levant's gains lambda_1 = 1.5, lambda_0 = 1.1; z1 converges to f' in finite time.

Two discretisations are offered:

``"implicit"`` (default)
    Implicit (set-valued) Euler, solved in closed form. It does not chatter: while the
    second difference of the samples stays below h^2 lambda_0 L it *is* the backward
    difference (f_k - f_{k-1})/h, and when noise or quantisation makes it jump further it acts
    as a slope-limited filter.
``"explicit"``
    Explicit Euler, the usual textbook code. Kept as a reference only: it chatters by
    h lambda_0 L every step and is worse than a plain finite difference.
"""

import math
from typing import Literal

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from motosim.errors import MotosimError

__all__ = [
    "LAMBDA_0",
    "LAMBDA_1",
    "SuperTwistingDifferentiator",
    "cell_step",
    "differentiate",
    "std_step",
]

Array = NDArray[np.float64]
Method = Literal["implicit", "explicit"]

LAMBDA_1 = 1.5
"""Levant's gain on |z0 - f|^(1/2), multiplied by L^(1/2) (Levant 1998, 2003)."""
LAMBDA_0 = 1.1
"""Levant's gain on sign(z0 - f), multiplied by L (Levant 1998, 2003)."""


@njit(cache=True)
def std_step(
    z0: float, z1: float, f: float, h: float, l1: float, l2: float, implicit: bool
) -> tuple[float, float]:
    """Advance the super-twisting differentiator by one sample.

    Parameters
    ----------
    z0, z1 : float
        State at the previous sample: the filtered signal and its rate [unit, unit/s].
    f : float
        The new sample f_{k+1}.
    h : float
        Sampling step [s], > 0.
    l1, l2 : float
        lambda_1 L^(1/2) [(unit/s^2)^(1/2)] and lambda_0 L [unit/s^2].
    implicit : bool
        Implicit (closed-form set-valued) Euler if true, explicit Euler otherwise.

    Returns
    -------
    z0, z1 : float
        State at the new sample; z1 is the rate estimate.

    Notes
    -----
    Implicit step, with r = z0 + h z1 - f_{k+1}: if |r| <= h^2 l2 (sliding),
    z0 <- f_{k+1} and z1 <- z1 - r/h; otherwise with
    q = (-h l1 + sqrt(h^2 l1^2 + 4 (|r| - h^2 l2))) / 2,
    z0 <- f_{k+1} + sign(r) q^2 and z1 <- z1 - h l2 sign(r). The explicit step evaluates
    the right-hand side at (z0, z1) with the new sample.
    """
    if implicit:
        r = z0 + h * z1 - f
        h2l2 = h * h * l2
        if abs(r) <= h2l2:
            return f, z1 - r / h
        sgn = 1.0 if r > 0.0 else -1.0
        q = 0.5 * (-h * l1 + math.sqrt(h * h * l1 * l1 + 4.0 * (abs(r) - h2l2)))
        return f + sgn * q * q, z1 - h * l2 * sgn
    e = z0 - f
    sgn = 1.0 if e > 0.0 else (-1.0 if e < 0.0 else 0.0)
    return z0 + h * (z1 - l1 * math.sqrt(abs(e)) * sgn), z1 - h * l2 * sgn


@njit(cache=True)
def cell_step(
    z0: float, z1: float, count: float, h: float, quantum: float, a: float, b: float
) -> tuple[float, float]:
    """Advance a differentiator that knows the encoder's count by one sample.

    A quantised angle says only that the angle lies in the count's cell
    [count - q/2, count + q/2]. The step predicts the angle, p = z0 + h z1, and corrects
    by how far p left that cell, r = clip(p, cell) - p (0 inside it: a count that stays
    consistent with the prediction adds nothing):

        z0 <- p + a r,    z1 <- z1 + b r / h

    a set-membership (dead-zone) alpha-beta filter. A count edge is then no rate spike:
    when the angle crosses an edge the new cell holds the prediction, or misses it by the
    prediction's error only, and the rate moves by b times that error over h (a plain
    difference moves by q / h, the whole count over one step).

    Parameters
    ----------
    z0, z1 : float
        The angle [rad] (inside the last cell) and rate [rad/s] at the previous sample.
    count : float
        The measured, quantised angle, the centre of its cell [rad].
    h : float
        Sampling step [s], > 0.
    quantum : float
        q, the encoder's count [rad], > 0.
    a, b : float
        The angle's and the rate's share of the distance outside the cell [-], in (0, 1].

    Returns
    -------
    z0, z1 : float
        The angle and the rate at this sample.

    Examples
    --------
    >>> cell_step(0.0, 0.01, 0.0, 1e-3, 1e-3, 0.5, 0.1)  # the prediction stays in its cell
    (1e-05, 0.01)
    """
    p = z0 + h * z1
    half = 0.5 * quantum
    r = min(max(p, count - half), count + half) - p
    return p + a * r, z1 + b * r / h


@njit(cache=True)
def _run(y: Array, h: float, l1: float, l2: float, implicit: bool, rate0: float) -> Array:
    """Rate estimates at every sample; the state starts at (y[0], rate0)."""
    out = np.empty(y.size)
    z0, z1 = y[0], rate0
    out[0] = z1
    for k in range(1, y.size):
        z0, z1 = std_step(z0, z1, y[k], h, l1, l2, implicit)
        out[k] = z1
    return out


def _gains(lipschitz: float, dt: float, method: str) -> tuple[float, float, bool]:
    if not (math.isfinite(lipschitz) and lipschitz > 0):
        raise MotosimError(
            f"lipschitz = {lipschitz!r}; expected a finite bound > 0 on |f''| [unit/s^2]"
        )
    if not (math.isfinite(dt) and dt > 0):
        raise MotosimError(f"dt = {dt!r}; expected a finite step > 0 [s]")
    if method not in ("implicit", "explicit"):
        raise MotosimError(f"method = {method!r}; expected 'implicit' or 'explicit'")
    return LAMBDA_1 * math.sqrt(lipschitz), LAMBDA_0 * lipschitz, method == "implicit"


class SuperTwistingDifferentiator:
    """Stepper: the first-order super-twisting differentiator at a fixed step.

    Parameters
    ----------
    lipschitz : float
        L, a bound on |f''| of the differentiated signal [unit/s^2]; for the handlebar angle,
        a bound on the angular acceleration during real manoeuvres (tens to a few hundred
        rad/s^2), not the worst-case torque over inertia.
    dt : float
        Sampling step h [s].
    method : {"implicit", "explicit"}
        Discretisation; see the module notes.
    initial_rate : float
        z1 after :meth:`reset` [unit/s].

    Raises
    ------
    MotosimError
        If ``lipschitz`` or ``dt`` is not finite and positive, or ``method`` is unknown.

    Notes
    -----
    The first sample after :meth:`reset` only initialises z0 = f and returns
    ``initial_rate``.

    References
    ----------
    A. Levant, "Robust exact differentiation via sliding mode technique", Automatica 34(3),
    379-384, 1998.

    Examples
    --------
    >>> d = SuperTwistingDifferentiator(200.0, 0.01)
    >>> [round(d.step(2.0 * k * 0.01), 12) for k in range(4)]
    [0.0, 2.0, 2.0, 2.0]
    """

    def __init__(
        self, lipschitz: float, dt: float, method: Method = "implicit", initial_rate: float = 0.0
    ) -> None:
        self._l1, self._l2, self._implicit = _gains(lipschitz, dt, method)
        self.dt = float(dt)
        self.initial_rate = float(initial_rate)
        self.reset()

    def reset(self) -> None:
        """Forget the past: the next sample re-initialises the state."""
        self._started = False
        self.z0 = 0.0
        self.z1 = self.initial_rate

    def step(self, y: float) -> float:
        """Take the next sample ``y`` and return the rate estimate z1 [unit/s]."""
        if not self._started:
            self._started = True
            self.z0, self.z1 = float(y), self.initial_rate
            return self.z1
        self.z0, self.z1 = std_step(
            self.z0, self.z1, float(y), self.dt, self._l1, self._l2, self._implicit
        )
        return self.z1


def differentiate(
    y: ArrayLike,
    dt: float,
    lipschitz: float,
    *,
    method: Method = "implicit",
    initial_rate: float = 0.0,
) -> Array:
    """Differentiate uniformly sampled data with the super-twisting differentiator.

    Parameters
    ----------
    y : array_like, shape (n,)
        Samples f_k, n >= 1 [unit].
    dt : float
        Sampling step h [s].
    lipschitz : float
        L, a bound on |f''| [unit/s^2].
    method : {"implicit", "explicit"}
        Discretisation.
    initial_rate : float
        Rate estimate at the first sample [unit/s].

    Returns
    -------
    ndarray, shape (n,)
        Rate estimates z1 at each sample [unit/s], the same as
        :class:`SuperTwistingDifferentiator` stepped over ``y``.

    Raises
    ------
    MotosimError
        On a bad shape, a non-finite sample or bad gains.

    Examples
    --------
    >>> t = np.arange(0.0, 1.0, 0.01)
    >>> round(float(differentiate(3.0 * t, 0.01, 10.0)[-1]), 9)
    3.0
    """
    l1, l2, implicit = _gains(lipschitz, dt, method)
    arr = np.asarray(y, dtype=float)
    if arr.ndim != 1 or arr.size < 1:
        raise MotosimError(f"y has shape {arr.shape}; expected (n,) with n >= 1")
    if not np.all(np.isfinite(arr)):
        raise MotosimError("y has a NaN or infinite sample; expected finite values")
    return _run(arr, float(dt), l1, l2, implicit, float(initial_rate))
