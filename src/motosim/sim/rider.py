"""A virtual rider that steers the Sharp motorcycle by handlebar torque to follow a path.

The rider is a speed-scheduled linear-quadratic regulator about the steady turn of the path's
curvature. At each design speed v the steady turn with yaw rate kappa v is solved from the
lateral model (``x_ss`` and ``tau_ss`` per unit curvature), and an LQR gain is computed for the
model augmented with the course-angle error e_chi = psi - psi_path + v_y / v and the lateral
offset e_y (e_y' = v e_chi). The rider then applies

    tau_r = tau_ss(kappa) - K_x (x - x_ss(kappa)) - K_chi e_chi - K_y e_y,

with the curvature taken a preview time ahead, as riders look ahead, and the torque limited to
what a rider can apply. Gains are interpolated linearly in speed.
"""

import functools
import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray
from scipy.linalg import solve_continuous_are

from motosim.choices import RIDER_SPEEDS
from motosim.errors import MotosimError
from motosim.model import sharp as sharp_model
from motosim.params.sharp import SharpParameters

__all__ = ["SPEED_RANGE", "RiderGains", "design_rider", "rider_torque"]

Array = NDArray[np.float64]

SPEED_RANGE = RIDER_SPEEDS
"""Speeds the virtual rider's gains are scheduled over by default [m/s]
(:data:`motosim.choices.RIDER_SPEEDS`)."""


@dataclass(frozen=True, slots=True)
class RiderGains:
    """Gain schedule of the virtual rider.

    Attributes
    ----------
    speeds : ndarray, shape (n,)
        Design speeds [m/s], increasing.
    K : ndarray, shape (n, 10)
        State-feedback gains on [x (8), e_chi, e_y] [N*m per state unit].
    x_ss : ndarray, shape (n, 8)
        Steady-turn state per unit curvature [state unit * m].
    tau_ss : ndarray, shape (n,)
        Steady-turn rider torque per unit curvature [N*m*m].
    preview : float
        Preview time of the curvature [s].
    max_torque : float
        Largest torque the rider applies [N*m].
    """

    speeds: Array
    K: Array
    x_ss: Array
    tau_ss: Array
    preview: float
    max_torque: float


def _steady_turn(A: Array, B: Array, speed: float) -> tuple[Array, float]:
    """State and torque of the steady turn of unit curvature (yaw rate = speed)."""
    system = np.zeros((9, 9))
    system[:8, :8] = A
    system[:8, 8] = B
    system[8, 1] = 1.0
    rhs = np.zeros(9)
    rhs[8] = speed
    sol = np.asarray(np.linalg.solve(system, rhs), dtype=np.float64)
    return sol[:8], float(sol[8])


@functools.lru_cache(maxsize=32)
def _schedule(
    p: SharpParameters,
    speeds: tuple[float, ...],
    lateral_tolerance: float,
    course_tolerance: float,
    roll_tolerance: float,
    torque_scale: float,
) -> tuple[Array, Array, Array]:
    """K, x_ss and tau_ss at the design speeds (cached: campaigns reuse one rider)."""
    grid = np.asarray(speeds)
    K = np.empty((grid.size, 10))
    x_ss = np.empty((grid.size, 8))
    tau_ss = np.empty(grid.size)
    Q = np.zeros((10, 10))
    Q[4, 4] = 1.0 / roll_tolerance**2
    Q[8, 8] = 1.0 / course_tolerance**2
    Q[9, 9] = 1.0 / lateral_tolerance**2
    R = np.array([[1.0 / torque_scale**2]])
    for i, v in enumerate(grid):
        lin = sharp_model.linearize(p, float(v))
        A, B = lin.A, lin.B[:, 0]
        Aa = np.zeros((10, 10))
        Ba = np.zeros(10)
        Aa[:8, :8] = A
        Ba[:8] = B
        Aa[8, :8] = A[0] / v
        Aa[8, 1] += 1.0
        Ba[8] = B[0] / v
        Aa[9, 8] = v
        P = solve_continuous_are(Aa, Ba[:, None], Q, R)
        K[i] = (np.linalg.solve(R, Ba[None, :] @ P))[0]
        x_ss[i], tau_ss[i] = _steady_turn(A, B, float(v))
    return K, x_ss, tau_ss


def design_rider(
    p: SharpParameters,
    *,
    speeds: Array | None = None,
    lateral_tolerance: float = 0.3,
    course_tolerance: float = 0.05,
    roll_tolerance: float = 0.3,
    torque_scale: float = 10.0,
    preview: float = 0.3,
    max_torque: float = 70.0,
) -> RiderGains:
    """Design the rider's gain schedule for the motorcycle ``p``.

    Parameters
    ----------
    p : SharpParameters
        The motorcycle.
    speeds : ndarray, optional
        Design speeds [m/s]; by default every 1 m/s from 3 to 60 m/s.
    lateral_tolerance, course_tolerance, roll_tolerance : float
        Bryson weights: errors of this size [m, rad, rad] cost as much as ``torque_scale``.
    torque_scale : float
        Torque [N*m] that costs as much as the tolerances.
    preview : float
        How far ahead the rider reads the curvature [s].
    max_torque : float
        Torque limit [N*m].

    Returns
    -------
    RiderGains

    Raises
    ------
    MotosimError
        If a setting is out of range.
    """
    grid = (
        np.arange(SPEED_RANGE[0], SPEED_RANGE[1] + 0.01, 1.0)
        if speeds is None
        else np.asarray(speeds, dtype=float)
    )
    for name, value in (
        ("lateral_tolerance", lateral_tolerance),
        ("course_tolerance", course_tolerance),
        ("roll_tolerance", roll_tolerance),
        ("torque_scale", torque_scale),
        ("max_torque", max_torque),
    ):
        if not (math.isfinite(value) and value > 0):
            raise MotosimError(f"rider {name} = {value!r}; expected a finite number > 0")
    if not (math.isfinite(preview) and preview >= 0):
        raise MotosimError(f"rider preview = {preview!r}; expected a finite time >= 0 [s]")
    K, x_ss, tau_ss = _schedule(
        p,
        tuple(float(v) for v in grid),
        lateral_tolerance,
        course_tolerance,
        roll_tolerance,
        torque_scale,
    )
    return RiderGains(grid, K, x_ss, tau_ss, float(preview), float(max_torque))


@njit(cache=True)
def _project(px: NDArray[np.float64], py: NDArray[np.float64], x: float, y: float, k: int) -> int:
    """Index of the path sample nearest to (x, y), searched locally from ``k``."""
    n = px.size
    best = (px[k] - x) ** 2 + (py[k] - y) ** 2
    while k + 1 < n:
        d = (px[k + 1] - x) ** 2 + (py[k + 1] - y) ** 2
        if d > best:
            break
        best, k = d, k + 1
    while k > 0:
        d = (px[k - 1] - x) ** 2 + (py[k - 1] - y) ** 2
        if d > best:
            break
        best, k = d, k - 1
    return k


@njit(cache=True)
def rider_torque(
    x_v: NDArray[np.float64],
    v_x: float,
    psi: float,
    pos_x: float,
    pos_y: float,
    k_path: int,
    path: NDArray[np.float64],
    ds: float,
    speeds: NDArray[np.float64],
    K: NDArray[np.float64],
    x_ss: NDArray[np.float64],
    tau_ss: NDArray[np.float64],
    preview: float,
    max_torque: float,
) -> tuple[float, int, float]:
    """The rider's torque for the motorcycle state, and the path index reached.

    ``path`` has rows x, y, psi, kappa (shape (4, n)). Returns (tau_r [N*m], index, e_y [m]).
    """
    px, py, ppsi, pk = path[0], path[1], path[2], path[3]
    k = _project(px, py, pos_x, pos_y, k_path)
    c, s = math.cos(ppsi[k]), math.sin(ppsi[k])
    dx, dy = pos_x - px[k], pos_y - py[k]
    e_y = -dx * s + dy * c
    e_psi = psi - ppsi[k]
    e_psi = (e_psi + math.pi) % (2.0 * math.pi) - math.pi
    e_chi = e_psi + x_v[0] / v_x
    ahead = min(k + int(v_x * preview / ds), pk.size - 1)
    kappa = pk[ahead]
    # linear interpolation of the schedule in speed, clamped at its ends
    j = int(np.searchsorted(speeds, v_x)) - 1
    j = min(max(j, 0), speeds.size - 2)
    w = min(max((v_x - speeds[j]) / (speeds[j + 1] - speeds[j]), 0.0), 1.0)
    tau = (1 - w) * tau_ss[j] * kappa + w * tau_ss[j + 1] * kappa
    for i in range(8):
        gain = (1 - w) * K[j, i] + w * K[j + 1, i]
        ref = ((1 - w) * x_ss[j, i] + w * x_ss[j + 1, i]) * kappa
        tau -= gain * (x_v[i] - ref)
    tau -= ((1 - w) * K[j, 8] + w * K[j + 1, 8]) * e_chi
    tau -= ((1 - w) * K[j, 9] + w * K[j + 1, 9]) * e_y
    tau = min(max(tau, -max_torque), max_torque)
    return tau, k, e_y
