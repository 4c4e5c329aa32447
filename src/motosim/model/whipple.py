"""The Whipple-Carvallo bicycle (rigid rolling contact), nonlinear, in Moore's coordinates.

Four rigid bodies (rear frame with the rider, rear wheel, front frame, front wheel) roll
without slipping on flat ground: the machine of Meijaard, Papadopoulos, Ruina & Schwab
(2007, Proc. R. Soc. A 463:1955-1982) and Basu-Mandal, Chatterjee & Papadopoulos (2007,
Proc. R. Soc. A 463:1983-2003), with toroidal wheels when the crown radii are not zero.

Coordinates and speeds are Moore's (2012, PhD dissertation, UC Davis): q1, q2 the rear
contact point on the ground (x forward, y right, z down), q3 yaw, q4 roll, q5 the rear
frame's pitch (lam when upright), q6 the rear wheel's angle, q7 steer, q8 the front wheel's
angle; u_i = q_i'. q5 is fixed by the front wheel touching the ground (:func:`pitch`),
u1, u2, u3, u5, u8 by rolling (:func:`dependent_speeds`); u4, u6, u7 are free.

The equations come from ``scripts/derive_multibody.py`` (Kane's method, SymPy), generated
into :mod:`motosim.model._generated_whipple` and compiled here with numba. Kane's equations
of the constrained system, ``C^T (M u' - f) = 0`` with C the null space of the constraints
``B u = 0``, and the constraints' derivative ``B u' + d/dt(B) u = 0`` are solved together
for the eight accelerations.
"""

import math
from functools import lru_cache
from typing import Any, NamedTuple, TypeAlias

import numpy as np
import numpy.typing as npt
from numba import njit

from motosim.errors import MotosimError
from motosim.model import _generated_whipple as gen
from motosim.params.checks import check_number
from motosim.params.multibody import MultibodyParameters

__all__ = [
    "DEPENDENT",
    "INDEPENDENT",
    "BenchmarkMatrices",
    "Torques",
    "accelerations",
    "benchmark_matrices",
    "dependent_speeds",
    "energy",
    "linearize",
    "moore_parameters",
    "pitch",
    "rk4_step",
    "upright_state",
]

Array: TypeAlias = npt.NDArray[Any]

DEPENDENT = (0, 1, 2, 4, 7)
"""Indices of the dependent speeds u1, u2, u3, u5, u8 (zero-based)."""
INDEPENDENT = (3, 5, 6)
"""Indices of the independent speeds u4 (roll rate), u6 (rear wheel), u7 (steer rate)."""

_DEP = np.array(DEPENDENT)
_IND = np.array(INDEPENDENT)
_NEWTON_TOL = 1e-14
_NEWTON_MAX = 50


class Torques(NamedTuple):
    """Input torques [N*m] of the rigid model (the generated code's ``INPUTS``)."""

    roll: float = 0.0
    """On the rear frame about the yaw frame's x axis, reacted by the ground (Meijaard's T_phi)."""
    rear_wheel: float = 0.0
    """On the rear wheel about its axle, reacted by the rear frame (drive positive backwards
    about y: a negative value drives forward)."""
    steer: float = 0.0
    """On the front frame about the steering axis, reacted by the rear frame (T_delta)."""
    front_wheel: float = 0.0
    """On the front wheel about its axle, reacted by the front frame."""


class BenchmarkMatrices(NamedTuple):
    """Meijaard's linearised equations ``M q'' + v C1 q' + (g K0 + v^2 K2) q = f``, q = (phi,
    delta): the 2x2 mass, damping-per-speed and stiffness matrices (SI units)."""

    M: Array
    C1: Array
    K0: Array
    K2: Array


@lru_cache(maxsize=64)
def _vector(params: MultibodyParameters) -> tuple[float, ...]:
    lam = params.lam
    cl, sl = math.cos(lam), math.sin(lam)
    # the rear frame's axes C are the upright axes pitched by lam (C.z along the steering axis)
    rot = np.array([[cl, 0.0, -sl], [0.0, 1.0, 0.0], [sl, 0.0, cl]])

    def in_c(x: float, z: float) -> tuple[float, float]:
        return x * cl - z * sl, x * sl + z * cl

    def tensor(prefix: str) -> tuple[float, float, float, float]:
        ixx, iyy, izz, ixz = (getattr(params, f"I_{prefix}{a}") for a in ("xx", "yy", "zz", "xz"))
        inertia = rot @ np.array([[ixx, 0.0, ixz], [0.0, iyy, 0.0], [ixz, 0.0, izz]]) @ rot.T
        return inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[2, 0]

    d1 = cl * (params.c + params.w - params.r_R * math.tan(lam))
    d3 = -cl * (params.c - params.r_F * math.tan(lam))
    d2 = params.w * sl + (params.r_R - params.r_F) * cl
    l1, l2 = in_c(params.x_B, params.z_B + params.r_R)
    l3, l4 = in_c(params.x_H - params.w, params.z_H + params.r_F)
    values = {
        "rR": params.r_R,
        "rF": params.r_F,
        "tR": params.t_R,
        "tF": params.t_F,
        "d1": d1,
        "d2": d2,
        "d3": d3,
        "l1": l1,
        "l2": l2,
        "l3": l3,
        "l4": l4,
        "g": params.g,
        "mC": params.m_B,
        "mD": params.m_R,
        "mE": params.m_H,
        "mF": params.m_F,
        "ID11": params.I_Rxx,
        "ID22": params.I_Ryy,
        "IF11": params.I_Fxx,
        "IF22": params.I_Fyy,
    }
    values.update(zip(("IC11", "IC22", "IC33", "IC31"), tensor("B"), strict=True))
    values.update(zip(("IE11", "IE22", "IE33", "IE31"), tensor("H"), strict=True))
    return tuple(float(values[name]) for name in gen.PARAMETERS)


def moore_parameters(params: MultibodyParameters) -> Array:
    """The generated code's parameter vector (Moore's geometry, inertias in the body axes).

    Parameters
    ----------
    params : MultibodyParameters
        Meijaard's parameters.

    Returns
    -------
    numpy.ndarray
        The values of :data:`motosim.model._generated_whipple.PARAMETERS`, in that order:
        Moore's (2012) d1, d2, d3 (the rear wheel centre's offset from the steering axis, the
        distance along it, the front wheel centre's offset), the mass centres l1..l4 in the
        rear and front frames' axes (x perpendicular to the steering axis, z along it), and
        the inertia tensors in those axes [SI units].
    """
    return np.array(_vector(params))


_holonomic = njit(cache=True)(gen.holonomic)
_constraint_matrix = njit(cache=True)(gen.constraint_matrix)
_constraint_bias = njit(cache=True)(gen.constraint_bias)
_mass_forcing = njit(cache=True)(gen.mass_forcing)
_energy = njit(cache=True)(gen.energy)


@njit(cache=True)
def _pitch(p: Array, q: Array, guess: Any) -> Any:
    """Newton's iteration on the front contact's height for q5 (q's other entries kept)."""
    work = q.copy()
    work[4] = guess
    for _ in range(_NEWTON_MAX):
        h, dh = _holonomic(p, work)
        step = h[0] / dh[0]
        work[4] = work[4] - step
        if abs(step) < _NEWTON_TOL:
            return work[4]
    return work[4] * np.nan


@njit(cache=True)
def _dependent(p: Array, q: Array, u: Array) -> Array:
    """u with its dependent entries solved from the rolling constraints."""
    B = _constraint_matrix(p, q)
    Bd = np.zeros((5, 5), dtype=B.dtype)
    rhs = np.zeros(5, dtype=B.dtype)
    for i in range(5):
        for j in range(5):
            Bd[i, j] = B[i, _DEP[j]]
        for j in range(3):
            rhs[i] -= B[i, _IND[j]] * u[_IND[j]]
    out = u.copy()
    solved = np.linalg.solve(Bd, rhs)
    for j in range(5):
        out[_DEP[j]] = solved[j]
    return out


@njit(cache=True)
def _accelerations(p: Array, q: Array, u: Array, r: Array) -> Array:
    M, f = _mass_forcing(p, q, u, r)
    B = _constraint_matrix(p, q)
    b = _constraint_bias(p, q, u)
    Bd = np.zeros((5, 5), dtype=B.dtype)
    Bi = np.zeros((5, 3), dtype=B.dtype)
    for i in range(5):
        for j in range(5):
            Bd[i, j] = B[i, _DEP[j]]
        for j in range(3):
            Bi[i, j] = B[i, _IND[j]]
    X = np.linalg.solve(Bd, Bi)
    C = np.zeros((8, 3), dtype=B.dtype)
    for j in range(3):
        C[_IND[j], j] = 1.0
        for i in range(5):
            C[_DEP[i], j] = -X[i, j]
    lhs = np.zeros((8, 8), dtype=M.dtype)
    rhs = np.zeros(8, dtype=M.dtype)
    lhs[:3, :] = C.T @ M
    rhs[:3] = C.T @ f
    lhs[3:, :] = B
    rhs[3:] = -b
    return np.linalg.solve(lhs, rhs)


@njit(cache=True)
def _rk4(p: Array, q: Array, u: Array, r: Array, h: float) -> tuple[Array, Array]:
    k1q, k1u = u, _accelerations(p, q, u, r)
    q2, u2 = q + 0.5 * h * k1q, u + 0.5 * h * k1u
    k2q, k2u = u2, _accelerations(p, q2, u2, r)
    q3, u3 = q + 0.5 * h * k2q, u + 0.5 * h * k2u
    k3q, k3u = u3, _accelerations(p, q3, u3, r)
    q4, u4 = q + h * k3q, u + h * k3u
    k4q, k4u = u4, _accelerations(p, q4, u4, r)
    return (
        q + h / 6.0 * (k1q + 2.0 * k2q + 2.0 * k3q + k4q),
        u + h / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u),
    )


def _array8(values: Any, what: str) -> Array:
    arr = np.asarray(values, dtype=float)
    if arr.shape != (8,):
        raise MotosimError(f"whipple: {what} has shape {arr.shape}; expected 8 values")
    if not np.all(np.isfinite(arr)):
        raise MotosimError(f"whipple: {what} = {arr.tolist()} is not finite; expected numbers")
    return arr


def _torques(torques: Torques | None) -> Array:
    return np.array(torques if torques is not None else Torques(), dtype=float)


def pitch(
    params: MultibodyParameters, roll: float, steer: float, guess: float | None = None
) -> float:
    """The rear frame's pitch q5 [rad] that puts the front wheel on the ground.

    Parameters
    ----------
    params : MultibodyParameters
        The machine.
    roll, steer : float
        q4 and q7 [rad].
    guess : float, optional
        Start of Newton's iteration; by default the steering axis tilt (upright pitch).

    Returns
    -------
    float
        q5 [rad].

    Raises
    ------
    MotosimError
        When the iteration does not converge (the front wheel cannot touch the ground).
    """
    q = np.zeros(8)
    q[3], q[6] = roll, steer
    p = moore_parameters(params)
    value = float(_pitch(p, q, params.lam if guess is None else guess))
    if not math.isfinite(value):
        raise MotosimError(
            f"whipple: no pitch puts the front wheel on the ground at roll = {roll:g} rad, "
            f"steer = {steer:g} rad; expected a configuration the wheels can touch"
        )
    return value


def dependent_speeds(params: MultibodyParameters, q: Any, u: Any) -> Array:
    """All eight speeds from the independent ones (u4, u6, u7), by the rolling constraints.

    Parameters
    ----------
    params : MultibodyParameters
        The machine.
    q : array_like, shape (8,)
        Coordinates q1..q8 (q5 satisfying the ground contact, see :func:`pitch`).
    u : array_like, shape (8,)
        Speeds; only u4, u6, u7 are read [rad/s].

    Returns
    -------
    numpy.ndarray, shape (8,)
        u with u1, u2 [m/s] and u3, u5, u8 [rad/s] solved.
    """
    return np.asarray(
        _dependent(moore_parameters(params), _array8(q, "q"), _array8(u, "u")), dtype=float
    )


def accelerations(
    params: MultibodyParameters, q: Any, u: Any, torques: Torques | None = None
) -> Array:
    """The derivatives of the eight generalised speeds, u1'..u8'.

    Parameters
    ----------
    params : MultibodyParameters
        The machine (e.g. ``load_parameters("benchmark_bicycle", "multibody")``).
    q : array_like, shape (8,)
        Moore's coordinates q1..q8 [m, rad], consistent with the ground contact.
    u : array_like, shape (8,)
        Speeds u_i = q_i' [m/s, rad/s], consistent with rolling.
    torques : Torques, optional
        Input torques; none by default.

    Returns
    -------
    numpy.ndarray, shape (8,)
        u1'..u8' [m/s^2, rad/s^2], the dependent ones from the constraints' derivative.
    """
    return np.asarray(
        _accelerations(
            moore_parameters(params), _array8(q, "q"), _array8(u, "u"), _torques(torques)
        ),
        dtype=float,
    )


def energy(params: MultibodyParameters, q: Any, u: Any) -> float:
    """Kinetic plus gravitational potential energy [J], zero potential at the ground."""
    return float(_energy(moore_parameters(params), _array8(q, "q"), _array8(u, "u"))[0])


def rk4_step(
    params: MultibodyParameters, q: Any, u: Any, h: float, torques: Torques | None = None
) -> tuple[Array, Array]:
    """One classical Runge-Kutta step of length ``h`` [s] of (q, u); returns the new (q, u)."""
    q_new, u_new = _rk4(
        moore_parameters(params), _array8(q, "q"), _array8(u, "u"), _torques(torques), h
    )
    return np.asarray(q_new), np.asarray(u_new)


def upright_state(params: MultibodyParameters, speed: float) -> tuple[Array, Array]:
    """Upright straight running at ``speed`` [m/s] along x: (q, u), the wheels rolling.

    Raises
    ------
    MotosimError
        If the speed is not a finite number within +/-150 m/s.
    """
    check_number(speed, where="whipple: speed", lower=-150.0, upper=150.0, unit="m/s")
    q = np.zeros(8)
    q[4] = pitch(params, 0.0, 0.0)
    u = np.zeros(8)
    u[5] = -speed / params.r_R
    return q, dependent_speeds(params, q, u)


_STEP = 1e-30
"""Imaginary step of the complex-step derivatives (Squire & Trapp 1998): with no difference
taken, the derivative is exact to rounding for any step this small."""


def _complex_response(params: MultibodyParameters, speed: float, which: str, index: int) -> Array:
    """d(u4', u7')/d(x) at upright running, x the state or input named by which/index."""
    p = moore_parameters(params).astype(complex)
    q0, u0 = upright_state(params, speed)
    q = q0.astype(complex)
    u = u0.astype(complex)
    r = np.zeros(4, dtype=complex)
    if which == "q":
        q[index] += 1j * _STEP
        q[4] = _pitch(p, q, complex(q0[4]))
    elif which == "u":
        u[index] += 1j * _STEP
    else:
        r[index] += 1j * _STEP
    u = _dependent(p, q, u)
    ud = _accelerations(p, q, u, r)
    return np.array([ud[3].imag, ud[6].imag]) / _STEP


def linearize(params: MultibodyParameters, speed: float) -> Array:
    """State matrix of the independent states about upright straight running.

    Parameters
    ----------
    params : MultibodyParameters
        The machine.
    speed : float
        Forward speed of the rear contact [m/s].

    Returns
    -------
    numpy.ndarray, shape (4, 4)
        A of x' = A x with x = (roll q4, steer q7, roll rate u4, steer rate u7), Meijaard's
        (phi, delta, phi', delta'). The derivatives are complex-step ones of the nonlinear
        equations (no difference is taken), exact to rounding.
    """
    columns = [_complex_response(params, speed, "q", i) for i in (3, 6)]
    columns += [_complex_response(params, speed, "u", i) for i in (3, 6)]
    lower = np.column_stack(columns)
    return np.vstack([np.hstack([np.zeros((2, 2)), np.eye(2)]), lower])


def benchmark_matrices(params: MultibodyParameters) -> BenchmarkMatrices:
    """Meijaard's M, C1, K0, K2 from the nonlinear equations (complex-step derivatives).

    The response to the roll and steer torques gives M^-1, the responses to the angles and
    rates at rest and at 1 m/s give the stiffness and damping; the equations are exactly
    quadratic in the speed, so K2 and C1 follow from the two speeds without truncation.
    """
    inverse = np.column_stack([_complex_response(params, 0.0, "r", i) for i in (0, 2)])
    M = np.linalg.inv(inverse)
    at_rest = linearize(params, 0.0)[2:, :]
    moving = linearize(params, 1.0)[2:, :]
    K0 = -(M @ at_rest[:, :2]) / params.g
    K2 = -(M @ moving[:, :2]) - params.g * K0
    C1 = -(M @ moving[:, 2:])
    return BenchmarkMatrices(M=M, C1=C1, K0=K0, K2=K2)
