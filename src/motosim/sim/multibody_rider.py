"""A virtual rider for the multibody motorcycle on tyres, scheduled on speed and lean.

The rider of :mod:`motosim.sim.rider` regulates Sharp's linear model about upright running;
at a large lean the multibody machine's in-plane motion (pitch, heave, the wheels' spins, the
forward speed) and its lateral motion couple, and the steady turn itself is far from the
upright state. This rider is therefore a linear-quadratic regulator about the steady turn
(:func:`motosim.model.trim.steady_turn`) on a grid of speeds and leans, as Sharp (2007)
schedules his preview controller on speed and lateral acceleration (a controller per trim
state of the nonlinear machine, joined by interpolation).

At each grid point (speed v, kinematic lean phi_k, the turn of radius v^2 / (g tan phi_k),
lean 0 being upright straight running):

* the steady turn gives the trim state x_ss, the steer torque tau_ss and the drive torque
  T_ss that hold it, and the rear contact's path curvature kappa_ss (the path a rider follows
  is the rear contact's ground track, :mod:`motosim.sim.paths`);
* the model is linearised about the trim by central differences of the compiled derivatives
  (:func:`motosim.model.tyred.derivatives`) in the fifteen coordinates that couple (heave,
  roll, pitch, steer, the six speeds but yaw's own angle, the wheels' spins, the relaxed side
  forces: :class:`Coupled`); position, yaw and the wheels' angles leave the dynamics
  unchanged and are left out;
* the rider's throttle, T = T_ss + k_v (v_target - u), is closed in that linear model, and
  the model is augmented, as in :mod:`motosim.sim.rider`, with the course-angle error
  e_chi = psi - psi_path + v_lat / u and the lateral offset e_y (e_y' = u e_chi);
* the LQR gain K on the steer torque minimises the Bryson-weighted cost of roll, course and
  lateral errors against the torque (Anderson & Moore 1990, ch. 2).

The rider then applies

    tau_r = tau_ss - K (x - x_ss, e_chi, e_y)

with the schedule interpolated bilinearly in the current forward speed and in the lean whose
trim follows the previewed curvature (the curvature a preview time ahead, as Sharp & Valtetsiotis
2001 and Sharp 2007 let riders look ahead; the lean is found from the trims' own curvatures,
so that the feedforward turn is the one on the path). Left turns use the right turn's tables
mirrored (the machine is symmetric). The torque is limited to what a rider applies.

References
----------
Sharp, R. S. (2007). Motorcycle steering control by road preview. *J. Dyn. Sys., Meas.,
Control* 129(4), 373-381.
Sharp, R. S., Valtetsiotis, V. (2001). Optimal preview car steering control. *Vehicle System
Dynamics* 35 (suppl.), 101-117.
Anderson, B. D. O., Moore, J. B. (1990). *Optimal Control: Linear Quadratic Methods*.
Prentice Hall.
"""

import math
from enum import IntEnum
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from motosim.errors import MotosimError
from motosim.model import _generated_tyred as gen
from motosim.model.tyred import ContactLoads, Index, Inputs, State, TyredModel, derivatives
from motosim.model.tyred import upright_state as _upright_state
from motosim.params.checks import check_number

__all__ = [
    "LEANS",
    "SPEEDS",
    "Coupled",
    "MultibodyRider",
    "design_multibody_rider",
    "multibody_rider_torque",
]

Array = NDArray[np.float64]

SPEEDS = (5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 40.0)
"""Design speeds by default [m/s]."""
LEANS = (0.0, 10.0, 20.0, 30.0, 35.0, 40.0)
"""Kinematic leans atan(v^2 kappa / g) of the design turns by default [deg]; the last is
0.84 g, within what the tyres hold on a road of friction 1."""


class Coupled(IntEnum):
    """Position of each state of the rider's linear model (its gains' columns).

    The first fifteen are the tyred model's states of the same names
    (:class:`motosim.model.tyred.Index`), then the course-angle error and the lateral offset.
    """

    z = 0
    roll = 1
    pitch = 2
    steer = 3
    forward = 4
    lateral = 5
    vertical = 6
    yaw_rate = 7
    roll_rate = 8
    pitch_rate = 9
    rear_spin = 10
    steer_rate = 11
    front_spin = 12
    Fy_r = 13
    Fy_f = 14
    e_chi = 15
    e_y = 16


N_COUPLED = 15
"""The coupled states of the machine (the trim's states): :class:`Coupled` up to ``Fy_f``."""
_STATES = np.array([int(Index[m.name]) for m in Coupled if m < N_COUPLED], dtype=np.int64)
"""Where each coupled state is in the tyred model's state array."""
_MIRRORED = ("roll", "steer", "lateral", "yaw_rate", "roll_rate", "steer_rate", "Fy_r", "Fy_f")
_MIRROR = np.array([-1.0 if m.name in _MIRRORED or m >= N_COUPLED else 1.0 for m in Coupled])
"""The sign each coupled state takes in the mirror image of a motion (a left turn for a
right one)."""


class MultibodyRider(NamedTuple):
    """The rider's schedule (build it with :func:`design_multibody_rider`).

    The tables are for right turns (kappa >= 0) at ``speeds`` x ``leans``; left turns mirror
    them.
    """

    speeds: Array
    """Design speeds [m/s], increasing, shape (n_v,)."""
    leans: Array
    """Kinematic leans of the design turns [rad], increasing from 0, shape (n_l,)."""
    curvature: Array
    """The rear contact's path curvature in each trim [1/m], shape (n_v, n_l)."""
    x_ss: Array
    """The trims' coupled states (:class:`Coupled` up to ``Fy_f``), shape (n_v, n_l, 15)."""
    tau_ss: Array
    """The steer torque that holds each trim [N*m], shape (n_v, n_l)."""
    drive_ss: Array
    """The drive torque that holds each trim's speed [N*m], shape (n_v, n_l)."""
    K: Array
    """Steer-torque gains on the :class:`Coupled` states [N*m per state unit], shape
    (n_v, n_l, 17)."""
    speed_gain: float
    """The throttle's gain on the speed error [N*m*s/m]."""
    preview: float
    """How far ahead the rider reads the curvature [s]."""
    max_torque: float
    """Steer torque limit [N*m]."""
    max_drive_torque: float
    """Drive torque limit [N*m]."""


def _trim_point(
    model: TyredModel, speed: float, lean: float, friction: float
) -> tuple[Array, float, float, float]:
    """The trim at (speed, kinematic lean): state array, tau_ss, drive_ss, curvature."""
    from motosim.model.trim import steady_turn

    if lean == 0.0:
        state = _upright_state(model, speed)
        return np.array(state, dtype=float), 0.0, 0.0, 0.0
    g = float(model.p[gen.PARAMETERS.index("g")])
    radius = speed**2 / (g * math.tan(lean))
    turn = steady_turn(model, speed, radius, friction=friction)
    x = np.array(turn.state, dtype=float)
    return x, turn.tau_r, turn.drive_torque, _contact_curvature(model, x)


def _contact_curvature(model: TyredModel, x: Array) -> float:
    """The curvature of the rear contact's ground path in the steady yawing motion [1/m]."""
    from motosim.model.tyred import observe

    loads = observe(model, x, 1.0)
    omega = x[Index.yaw_rate]
    # the centre of the motion, from the rear wheel centre: V + omega z x c = 0
    cx, cy = -x[Index.lateral] / omega, x[Index.forward] / omega
    return 1.0 / math.hypot(loads.x_r - x[Index.x] - cx, loads.y_r - x[Index.y] - cy)


def _jacobian(
    model: TyredModel, x0: Array, inputs: Inputs, friction: float
) -> tuple[Array, Array, Array]:
    """A, B_steer, B_drive of the coupled states about ``x0`` (central differences)."""
    inputs = inputs._replace(friction=friction)

    def rates(x: Array, u: Inputs) -> Array:
        return np.array(derivatives(model, State(*x), u), dtype=float)[_STATES]

    A = np.empty((N_COUPLED, N_COUPLED))
    for j, index in enumerate(_STATES):
        h = 1e-6 * max(1.0, abs(x0[index]))
        dx = np.zeros(x0.size)
        dx[index] = h
        A[:, j] = (rates(x0 + dx, inputs) - rates(x0 - dx, inputs)) / (2 * h)
    B = []
    for name in ("steer_torque", "drive_torque"):
        value = getattr(inputs, name)
        up = inputs._replace(**{name: value + 1e-3})
        down = inputs._replace(**{name: value - 1e-3})
        B.append((rates(x0, up) - rates(x0, down)) / 2e-3)
    return A, B[0], B[1]


def _gain(
    A: Array,
    B: Array,
    B_drive: Array,
    x0: Array,
    curvature: float,
    *,
    speed_gain: float,
    weights: tuple[float, float, float, float],
) -> Array:
    """The LQR gain of the augmented model with the throttle loop closed."""
    from scipy.linalg import solve_continuous_are

    n = N_COUPLED + 2
    fwd, lat = x0[Index.forward], x0[Index.lateral]
    Aa = np.zeros((n, n))
    Aa[:N_COUPLED, :N_COUPLED] = A
    Aa[:N_COUPLED, Coupled.forward] -= B_drive * speed_gain
    Ba = np.zeros(n)
    Ba[:N_COUPLED] = B
    # e_chi' = yaw_rate + (v_lat / u)' - kappa u, linearised about the trim
    Aa[Coupled.e_chi, :N_COUPLED] = Aa[Coupled.lateral, :N_COUPLED] / fwd
    Aa[Coupled.e_chi, :N_COUPLED] -= lat / fwd**2 * Aa[Coupled.forward, :N_COUPLED]
    Aa[Coupled.e_chi, Coupled.yaw_rate] += 1.0
    Aa[Coupled.e_chi, Coupled.forward] -= curvature
    Ba[Coupled.e_chi] = B[Coupled.lateral] / fwd - lat / fwd**2 * B[Coupled.forward]
    Aa[Coupled.e_y, Coupled.e_chi] = fwd
    roll_tolerance, course_tolerance, lateral_tolerance, torque_scale = weights
    Q = np.zeros((n, n))
    Q[Coupled.roll, Coupled.roll] = 1.0 / roll_tolerance**2
    Q[Coupled.e_chi, Coupled.e_chi] = 1.0 / course_tolerance**2
    Q[Coupled.e_y, Coupled.e_y] = 1.0 / lateral_tolerance**2
    R = np.array([[1.0 / torque_scale**2]])
    P = solve_continuous_are(Aa, Ba[:, None], Q, R)
    K = np.asarray((Ba[None, :] @ P)[0] * torque_scale**2, dtype=np.float64)
    closed = Aa - np.outer(Ba, K)
    if np.max(np.linalg.eigvals(closed).real) >= 0.0:
        raise MotosimError("multibody rider: the LQR leaves an unstable mode (no gain found)")
    return K


def _grid(values: ArrayLike | None, name: str, default: tuple[float, ...], scale: float) -> Array:
    grid = np.asarray(default if values is None else values, dtype=float) * scale
    if grid.ndim != 1 or grid.size < 2 or not np.all(np.isfinite(grid)):
        raise MotosimError(f"multibody rider: {name} = {values!r}; expected 2 or more numbers")
    if not np.all(np.diff(grid) > 0):
        raise MotosimError(f"multibody rider: {name} = {values!r}; expected increasing values")
    return grid


def design_multibody_rider(
    model: TyredModel,
    *,
    speeds: ArrayLike | None = None,
    leans: ArrayLike | None = None,
    friction: float = 1.0,
    lateral_tolerance: float = 0.3,
    course_tolerance: float = 0.05,
    roll_tolerance: float = 0.3,
    torque_scale: float = 10.0,
    preview: float = 0.3,
    max_torque: float = 70.0,
    speed_gain: float = 100.0,
    max_drive_torque: float = 1000.0,
) -> MultibodyRider:
    """Design the rider's schedule for the tyred motorcycle ``model``.

    Parameters
    ----------
    model : TyredModel
        The machine on its tyres (:func:`motosim.model.tyred.load_model`).
    speeds : sequence of float, optional
        Design speeds [m/s], increasing, 2 or more, each 1 to 100 (:data:`SPEEDS` by default).
    leans : sequence of float, optional
        Kinematic leans atan(v^2 kappa / g) of the design turns [deg], increasing from 0
        (:data:`LEANS` by default); every one must have a steady turn at every speed.
    friction : float, optional
        The road friction the trims are found on.
    lateral_tolerance, course_tolerance, roll_tolerance : float, optional
        Bryson weights: errors of this size [m, rad, rad] cost as much as ``torque_scale``.
    torque_scale : float, optional
        Steer torque [N*m] that costs as much as the tolerances.
    preview : float, optional
        How far ahead the rider reads the curvature [s].
    max_torque : float, optional
        Steer torque limit [N*m].
    speed_gain : float, optional
        The throttle's drive torque per unit speed error [N*m*s/m].
    max_drive_torque : float, optional
        Drive torque limit [N*m].

    Returns
    -------
    MultibodyRider

    Raises
    ------
    MotosimError
        If a setting is out of range, a grid is not increasing, or a grid point has no
        steady turn (:class:`motosim.model.trim.NoSteadyTurnError`, naming it).

    Examples
    --------
    >>> from motosim.model.tyred import load_model
    >>> rider = design_multibody_rider(
    ...     load_model("sel2004_motorcycle"), speeds=(15.0, 20.0), leans=(0.0, 30.0)
    ... )
    >>> round(float(rider.tau_ss[1, 1]), 1)  # trim.py's steer torque at 20 m/s, 30 deg [N*m]
    -10.8
    """
    v_grid = _grid(speeds, "speeds", SPEEDS, 1.0)
    l_grid = _grid(leans, "leans", LEANS, math.pi / 180.0)
    if not (1.0 <= v_grid[0] and v_grid[-1] <= 100.0):
        raise MotosimError(f"multibody rider: speeds = {speeds!r}; expected values in [1, 100] m/s")
    if l_grid[0] != 0.0 or l_grid[-1] >= math.radians(70.0):
        raise MotosimError(f"multibody rider: leans = {leans!r}; expected 0 first, below 70 deg")
    check_number(
        friction, where="multibody rider: friction", lower=0.0, upper=3.0, lower_closed=False
    )
    for name, value, unit in (
        ("lateral_tolerance", lateral_tolerance, "m"),
        ("course_tolerance", course_tolerance, "rad"),
        ("roll_tolerance", roll_tolerance, "rad"),
        ("torque_scale", torque_scale, "N*m"),
        ("max_torque", max_torque, "N*m"),
        ("speed_gain", speed_gain, "N*m*s/m"),
        ("max_drive_torque", max_drive_torque, "N*m"),
    ):
        check_number(
            value,
            where=f"multibody rider: {name}",
            lower=0.0,
            lower_closed=False,
            upper=1e6,
            unit=unit,
        )
    check_number(preview, where="multibody rider: preview", lower=0.0, upper=10.0, unit="s")
    nv, nl = v_grid.size, l_grid.size
    curvature = np.empty((nv, nl))
    x_ss = np.empty((nv, nl, N_COUPLED))
    tau_ss = np.empty((nv, nl))
    drive_ss = np.empty((nv, nl))
    K = np.empty((nv, nl, len(Coupled)))
    weights = (roll_tolerance, course_tolerance, lateral_tolerance, torque_scale)
    for i, v in enumerate(v_grid):
        for j, lean in enumerate(l_grid):
            x0, tau, drive, kappa = _trim_point(model, float(v), float(lean), friction)
            inputs = Inputs(steer_torque=tau, drive_torque=drive, friction=friction)
            A, B, B_drive = _jacobian(model, x0, inputs, friction)
            K[i, j] = _gain(A, B, B_drive, x0, kappa, speed_gain=speed_gain, weights=weights)
            curvature[i, j] = kappa
            x_ss[i, j] = x0[_STATES]
            tau_ss[i, j], drive_ss[i, j] = tau, drive
    return MultibodyRider(
        speeds=v_grid,
        leans=l_grid,
        curvature=curvature,
        x_ss=x_ss,
        tau_ss=tau_ss,
        drive_ss=drive_ss,
        K=K,
        speed_gain=float(speed_gain),
        preview=float(preview),
        max_torque=float(max_torque),
        max_drive_torque=float(max_drive_torque),
    )


@njit(cache=True)
def _project(px: Array, py: Array, x: float, y: float, k: int) -> int:
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
def _bracket(grid: Array, value: float) -> tuple[int, float]:
    """The interval of an increasing grid holding ``value`` and the weight of its upper end
    (clamped to the grid's ends)."""
    j = 0
    while j < grid.size - 2 and grid[j + 1] <= value:
        j += 1
    w = (value - grid[j]) / (grid[j + 1] - grid[j])
    return j, min(max(w, 0.0), 1.0)


@njit(cache=True)
def _bracket_lean(curvature: Array, i: int, w: float, value: float) -> tuple[int, float]:
    """:func:`_bracket` in the trims' curvatures blended between speeds i and i + 1."""
    n = curvature.shape[1]
    j = 0
    while j < n - 2 and (1.0 - w) * curvature[i, j + 1] + w * curvature[i + 1, j + 1] <= value:
        j += 1
    low = (1.0 - w) * curvature[i, j] + w * curvature[i + 1, j]
    high = (1.0 - w) * curvature[i, j + 1] + w * curvature[i + 1, j + 1]
    return j, min(max((value - low) / (high - low), 0.0), 1.0)


@njit(cache=True)
def _blend(table: Array, i: int, j: int, weights: tuple[float, float, float, float]) -> float:
    """The bilinear blend of ``table``'s corners (i, j) .. (i + 1, j + 1)."""
    value: float = (
        weights[0] * table[i, j]
        + weights[1] * table[i, j + 1]
        + weights[2] * table[i + 1, j]
        + weights[3] * table[i + 1, j + 1]
    )
    return value


@njit(cache=True)
def multibody_rider_torque(
    rider: MultibodyRider,
    x: Array,
    loads: ContactLoads,
    k_path: int,
    path: Array,
    ds: float,
    target_speed: float,
    braking: bool,
) -> tuple[float, float, int, float]:
    """The rider's steer and drive torques for the tyred model's state (compiled).

    Parameters
    ----------
    rider : MultibodyRider
        The schedule.
    x : ndarray, shape (20,)
        The tyred model's compiled state (:class:`motosim.model.tyred.Index`).
    loads : ContactLoads
        The contacts of ``x`` (:func:`motosim.model.tyred.observe`): the rear contact's
        ground position is the point that follows the path.
    k_path : int
        The path index reached at the previous call (0 at the start).
    path : ndarray, shape (4, n)
        Rows x, y [m], heading [rad], curvature [1/m] every ``ds``.
    ds : float
        The path's spacing [m].
    target_speed : float
        The speed the throttle holds [m/s].
    braking : bool
        Whether the rider brakes: the throttle is then closed.

    Returns
    -------
    steer_torque : float
        [N*m], within the rider's limit.
    drive_torque : float
        [N*m], 0 to the drive limit.
    index : int
        The path index nearest to the rear contact.
    e_y : float
        The rear contact's offset to the right of the path [m].
    """
    px, py, ppsi, pk = path[0], path[1], path[2], path[3]
    k = _project(px, py, loads.x_r, loads.y_r, k_path)
    c, s = math.cos(ppsi[k]), math.sin(ppsi[k])
    e_y = -(loads.x_r - px[k]) * s + (loads.y_r - py[k]) * c
    e_psi = x[Index.yaw] - ppsi[k]
    e_psi = (e_psi + math.pi) % (2.0 * math.pi) - math.pi
    forward = x[Index.forward]
    u = max(forward, 0.5)
    e_chi = e_psi + x[Index.lateral] / u
    ahead = min(k + int(u * rider.preview / ds), pk.size - 1)
    kappa = pk[ahead]
    side = 1.0 if kappa >= 0.0 else -1.0
    # bilinear in speed and in the lean whose trim has the previewed curvature
    i, w = _bracket(rider.speeds, forward)
    j, q = _bracket_lean(rider.curvature, i, w, abs(kappa))
    weights = ((1.0 - w) * (1.0 - q), (1.0 - w) * q, w * (1.0 - q), w * q)
    tau = _blend(rider.tau_ss, i, j, weights)
    drive = _blend(rider.drive_ss, i, j, weights)
    for m in range(N_COUPLED):
        mirror = _MIRROR[m] if side < 0.0 else 1.0
        error = mirror * x[_STATES[m]] - _blend(rider.x_ss[:, :, m], i, j, weights)
        tau -= _blend(rider.K[:, :, m], i, j, weights) * error
    tau -= _blend(rider.K[:, :, Coupled.e_chi], i, j, weights) * side * e_chi
    tau -= _blend(rider.K[:, :, Coupled.e_y], i, j, weights) * side * e_y
    steer_torque = min(max(side * tau, -rider.max_torque), rider.max_torque)
    drive_torque = 0.0
    if not braking:
        drive = drive + rider.speed_gain * (target_speed - forward)
        drive_torque = min(max(drive, 0.0), rider.max_drive_torque)
    return steer_torque, drive_torque, k, e_y
