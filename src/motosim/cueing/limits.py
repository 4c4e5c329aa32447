"""The final limit manager: angle, rate and acceleration limits, no overshoot across neutral.

Each axis follows its target (the cueing algorithm's command) as a discrete double
integrator whose speed change per step is at most ``A dt``. The speed chosen at each step is
the largest that still lets the axis stop, braking at ``A`` in the discrete steps that
follow, before

- the target (so a held target is reached without overshoot),
- each angle limit ``+/-X``,
- neutral, when the target and the axis are on the same side of it and the target is not
  planned to move towards it (so a command that returns to neutral is never carried across
  it, and a planned trajectory that sweeps through neutral, the MPC's, is not stopped there
  for a step: a stop of 0.01 s at 120 deg/s^2 is a jolt the rider feels),

and it is clipped to the rate limit ``V`` and to ``v_prev +/- A dt``. A target that comes
with its own planned rate (the MPC's, ``target_rate``) is followed at that rate plus the
braking speed towards what is left of the offset, so a trajectory already within the limits
passes without the lag of braking towards each sample; the bounds, and so the guarantee
below, are the same. The stopping
distance of the discrete braking from speed ``v = (n + f) A dt`` (``n`` integer, ``0 <= f
< 1``) after moving ``v dt`` this step is exactly ``A dt^2 (n + 1)(n / 2 + f)``, which is
inverted in closed form. By induction the admissible speed interval is never empty, so
every output sample satisfies ``|x| <= X``, ``|x_k - x_{k-1}| <= V dt`` and
``|x_k - 2 x_{k-1} + x_{k-2}| <= A dt^2`` whatever the input, the guarantee being exact up
to floating-point rounding.

:func:`actuator_response` is the platform twin: the achieved angles through the actuators'
first-order position loops, discretised exactly (a convex combination per step, so it
keeps the three limits).
"""

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray

from motosim.cueing.platform import Platform
from motosim.errors import MotosimError

__all__ = [
    "LimitDesign",
    "actuator_response",
    "apply_limits",
    "design_limits",
    "limit_step",
]

Array = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class LimitDesign:
    """Limits of the three axes at one loop period.

    Attributes
    ----------
    dt : float
        Loop period [s].
    angle, rate, accel : tuple of float
        Roll, pitch and yaw limits [rad], [rad/s], [rad/s^2].
    """

    dt: float
    angle: tuple[float, float, float]
    rate: tuple[float, float, float]
    accel: tuple[float, float, float]

    def coefficients(self) -> Array:
        """Array (3, 4) of ``[X, V, A, dt]`` per axis, what :func:`limit_step` reads."""
        return np.array(
            [[self.angle[i], self.rate[i], self.accel[i], self.dt] for i in range(3)],
            dtype=np.float64,
        )


def design_limits(platform: Platform, dt: float) -> LimitDesign:
    """The limit manager of ``platform`` at the loop period ``dt`` [s].

    Raises
    ------
    MotosimError
        If ``dt`` is not a finite number > 0.
    """
    if not (math.isfinite(dt) and dt > 0.0):
        raise MotosimError(f"loop period dt = {dt!r}; expected a finite number > 0 [s]")
    axes = platform.axes
    return LimitDesign(
        dt=dt,
        angle=(axes[0].angle, axes[1].angle, axes[2].angle),
        rate=(axes[0].rate, axes[1].rate, axes[2].rate),
        accel=(axes[0].accel, axes[1].accel, axes[2].accel),
    )


@njit(cache=True, inline="always")
def _brake_speed(distance: float, c: float, h: float) -> float:
    """Largest speed from which moving one step then braking by ``c`` per step stays within
    ``distance`` (``c = A dt``, ``h = A dt^2``)."""
    if distance <= 0.0:
        return 0.0
    e = distance / h
    n = math.floor((math.sqrt(1.0 + 8.0 * e) - 1.0) / 2.0)
    f = min(1.0, max(0.0, e / (n + 1.0) - 0.5 * n))
    return c * (n + f)


@njit(cache=True)
def limit_step(lim: Array, state: Array, target: float, target_rate: float = 0.0) -> float:
    """One loop step of the limit manager on one axis.

    Parameters
    ----------
    lim : ndarray, shape (4,)
        ``[X, V, A, dt]``: angle [rad], rate [rad/s], acceleration [rad/s^2] limits and the
        loop period [s] (a row of :meth:`LimitDesign.coefficients`).
    state : ndarray, shape (2,)
        Last output [rad] and its rate [rad/s], updated in place (zeros at neutral rest).
    target : float
        The commanded angle [rad].
    target_rate : float, optional
        The command's own rate [rad/s] when it is a planned trajectory (the MPC's), followed
        without the lag of braking towards each sample; 0 for a command without one.

    Returns
    -------
    float
        The limited angle [rad].
    """
    X, V, A, dt = lim[0], lim[1], lim[2], lim[3]
    x, v = state[0], state[1]
    c = A * dt
    h = c * dt
    u = min(X, max(-X, target))
    e = u - x - target_rate * dt  # the offset left once the target's own motion is followed
    wanted = _brake_speed(abs(e), c, h)
    if e < 0.0:
        wanted = -wanted
    wanted += target_rate
    hi = min(v + c, V, _brake_speed(X - x, c, h))
    lo = max(v - c, -V, -_brake_speed(X + x, c, h))
    floor, ceiling = -X, X
    # do not carry the axis across neutral, unless the target's own plan heads for it
    if u >= 0.0 and x >= 0.0 and target_rate >= 0.0:
        lo = max(lo, -_brake_speed(x, c, h))
        floor = 0.0
    if u <= 0.0 and x <= 0.0 and target_rate <= 0.0:
        hi = min(hi, _brake_speed(-x, c, h))
        ceiling = 0.0
    if lo > hi + 1e-9 * c:  # only from a state not reachable under the limits: brake hardest
        lo = hi = v - c if v > 0.0 else v + c
        floor, ceiling = -X, X
    elif lo > hi:  # an empty interval by rounding only: keep the braking bound
        hi = lo
    v_new = min(hi, max(lo, wanted))
    x_new = min(ceiling, max(floor, x + v_new * dt))  # the bounds absorb rounding only
    state[1] = (x_new - x) / dt
    state[0] = x_new
    return float(x_new)


@njit(cache=True)
def _limit_run(lim: Array, targets: Array, rates: Array, out: Array) -> None:
    state = np.zeros(2)
    for j in range(targets.shape[1]):
        state[0] = 0.0
        state[1] = 0.0
        for k in range(targets.shape[0]):
            out[k, j] = limit_step(lim[j], state, targets[k, j], rates[k, j])


def apply_limits(design: LimitDesign, targets: Array, rates: Array | None = None) -> Array:
    """Run the limit manager over a whole series, from neutral rest.

    Parameters
    ----------
    design : LimitDesign
        From :func:`design_limits`, at the series' sample period.
    targets : ndarray, shape (n, 3)
        Roll, pitch and yaw commands [rad].
    rates : ndarray, shape (n, 3), optional
        Their planned rates [rad/s] (``target_rate`` of :func:`limit_step`); default zeros.

    Returns
    -------
    ndarray, shape (n, 3)
        The limited commands [rad].

    Raises
    ------
    MotosimError
        If ``targets`` is not (n, 3) and finite.

    Examples
    --------
    >>> from motosim.cueing.platform import load_platform
    >>> d = design_limits(load_platform("simacom_platform").platform, 0.01)
    >>> out = apply_limits(d, np.full((300, 3), 1.0))          # 57 deg on every axis
    >>> np.degrees(out[-1]).round(6)                            # held at the angle limits
    array([20., 10., 15.])
    """
    x = np.ascontiguousarray(targets, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 3 or not np.all(np.isfinite(x)):
        raise MotosimError(f"platform targets of shape {x.shape}; expected finite (n, 3)")
    v = np.zeros_like(x) if rates is None else np.ascontiguousarray(rates, dtype=np.float64)
    if v.shape != x.shape or not np.all(np.isfinite(v)):
        raise MotosimError(f"platform target rates of shape {v.shape}; expected finite {x.shape}")
    out = np.empty_like(x)
    _limit_run(design.coefficients(), x, v, out)
    return out


def actuator_response(platform: Platform, dt: float, commands: Array) -> Array:
    """Achieved platform angles: each axis a first-order lag at its bandwidth, from rest.

    ``y_k = a y_{k-1} + (1 - a) u_{k-1}`` with ``a = exp(-w dt)`` (the exact
    discretisation of ``w / (s + w)`` for a command held over the step).

    Parameters
    ----------
    platform : Platform
        Actuator bandwidths [rad/s].
    dt : float
        Loop period [s].
    commands : ndarray, shape (n, 3)
        Roll, pitch, yaw commands [rad].

    Returns
    -------
    ndarray, shape (n, 3)
        Achieved angles [rad].
    """
    from scipy.signal import lfilter

    out = np.empty_like(np.asarray(commands, dtype=np.float64))
    for j, axis in enumerate(platform.axes):
        a = math.exp(-axis.bandwidth * dt)
        out[:, j] = lfilter([0.0, 1.0 - a], [1.0, -a], commands[:, j])
    return out
