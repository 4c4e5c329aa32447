"""The multibody motorcycle on tyres: the rear frame free in space, forces at the contacts.

The four bodies of :mod:`motosim.model.whipple` without the rolling constraints: the rear
frame moves freely (position of the rear wheel centre, yaw, roll, pitch), the wheels spin and
the front frame steers (9 coordinates, 9 speeds). Each wheel is a torus (crown radius t; a
knife edge when t = 0); its contact point is the torus's lowest point, which moves sideways
with camber. The ground pushes on each wheel at that point with

* a normal load from the radial compression (how far the point is below the ground) times
  the tyre's radial stiffness, plus a radial damping, never pulling;
* a longitudinal force from the longitudinal slip and a side force from the sideslip and the
  camber, relaxed to its steady value over the relaxation length
  (sigma / |V| F_y' + F_y = F_y,ss), both limited together by a friction ellipse of
  radius mu F_z, from either tyre law: a linear tyre (:func:`linear_tyre_forces`, no
  moments) or the Magic Formula motorcycle tyre of :mod:`motosim.model.tyres`
  (:func:`magic_tyre_forces`: combined slip, load dependence, the aligning and overturning
  moments through the contact Jacobians, the lateral relaxation length of the tyre set).

The generated code (``scripts/derive_multibody.py``, Kane's method) gives the mass matrix,
the forcing without tyre forces and the contact kinematics (positions, the slips'
ingredients, camber) with the Jacobians J, so that the tyres' generalised forces are J^T F.
Inputs: steer torque, rear drive torque, front and rear brake torques, road friction; the
aerodynamic drag rho C_d A / 2 v^2 acts at an aerodynamic centre on the rear frame, a
steering damper between the frames.
"""

import math
from dataclasses import dataclass
from enum import IntEnum
from typing import Any, NamedTuple, TypeAlias

import numpy as np
import numpy.typing as npt
from numba import njit
from numpy.typing import ArrayLike

from motosim.errors import MotosimError
from motosim.model import _generated_tyred as gen
from motosim.model.sharp import ModeTable, modes
from motosim.model.tyres import (
    TyreCoefficients,
    linear_tyre_coefficients,
    relaxation_lengths,
    steady_forces,
    tyre_coefficients,
)
from motosim.model.whipple import moore_parameters
from motosim.params import load_parameter_set, load_parameters
from motosim.params.checks import check_number
from motosim.params.multibody import MultibodyParameters
from motosim.params.sharp import SharpParameters, derived_geometry
from motosim.params.tyre import TyreParameters

__all__ = [
    "LATERAL",
    "ContactLoads",
    "Domain",
    "Index",
    "Inputs",
    "LinearTyre",
    "State",
    "TyredModel",
    "advance",
    "contact_loads",
    "derivatives",
    "domain",
    "held",
    "lateral_matrix",
    "lateral_system",
    "linear_tyre_forces",
    "linearised_tyre",
    "load_model",
    "magic_tyre_forces",
    "make_model",
    "observe",
    "outside",
    "rates",
    "sharp_machine",
    "sharp_modes",
    "step",
    "upright_state",
    "validate_inputs",
]

Array: TypeAlias = npt.NDArray[Any]

STEER_STOP = math.radians(35.0)
"""|steer| at a road motorcycle's steering stops [rad] (about 30-35 deg each way): beyond,
the front wheel has tucked under, the start of a fall."""
_MIN_SPEED = 0.5
"""Reference speed [m/s] below which the slips are divided by this speed instead (the slips'
definitions lose their meaning at a standstill)."""
_BRAKE_RATE = 500.0
"""The brakes' viscous zone around a locked wheel is at most this fast [1/s]: the torque
ramps from zero at lock to its full value over a spin rate of T_b / (500 I_yy), at least
0.5 rad/s, so that RK4 at 1 ms stays stable while a wheel locks."""
_MIN_BRAKE_SPIN = 0.5

_mass_forcing = njit(cache=True)(gen.mass_forcing)
_contacts = njit(cache=True)(gen.contacts)
_kinematics = njit(cache=True)(gen.kinematics)
_aero_jacobian = njit(cache=True)(gen.aero_jacobian)


@dataclass(frozen=True, slots=True)
class LinearTyre:
    """A linear tyre with first-order side-force relaxation, per unit normal load.

    Attributes
    ----------
    cornering : float
        Cornering stiffness per unit load, dF_y/dalpha / F_z [1/rad].
    camber : float
        Camber stiffness per unit load, dF_y/dgamma / F_z [1/rad].
    longitudinal : float
        Longitudinal slip stiffness per unit load, dF_x/dkappa / F_z [1].
    relaxation_length : float
        sigma [m].
    radial_stiffness : float
        Normal load per unit radial compression [N/m].
    radial_damping : float
        Normal load per unit compression rate [N*s/m].
    """

    cornering: float
    camber: float
    longitudinal: float
    relaxation_length: float
    radial_stiffness: float
    radial_damping: float

    def __post_init__(self) -> None:
        for name, low, high in (
            ("cornering", 0.0, 100.0),
            ("camber", 0.0, 10.0),
            ("longitudinal", 0.0, 200.0),
            ("relaxation_length", 1e-3, 2.0),
            ("radial_stiffness", 1e3, 1e7),
            ("radial_damping", 0.0, 1e5),
        ):
            check_number(
                getattr(self, name),
                where=f"linear tyre: {name}",
                lower=low,
                upper=high,
                lower_closed=True,
                upper_closed=True,
            )

    def as_array(self) -> Array:
        """The values in the compiled kernel's order (the attributes' order)."""
        return np.array(
            [
                self.cornering,
                self.camber,
                self.longitudinal,
                self.relaxation_length,
                self.radial_stiffness,
                self.radial_damping,
            ]
        )


class TyredModel(NamedTuple):
    """The compiled model's constants (build it with :func:`make_model`)."""

    p: Array
    """The generated code's parameter vector (``_generated_tyred.PARAMETERS``)."""
    rear: Array
    """The rear tyre (:meth:`LinearTyre.as_array`)."""
    front: Array
    """The front tyre."""
    drag: float
    """rho C_d A / 2 [kg/m]."""
    steer_damping: float
    """Steering damper [N*m*s/rad], a rider's arms' damping included (:func:`held`)."""
    steer_inertia: float
    """Inertia turning with the steer angle about the steering axis besides the front
    frame's, a rider's arms (:func:`held`) [kg*m^2]."""
    spin_inertia: Array
    """The wheels' spin inertias (rear, front) [kg*m^2], for the brakes' lock zone."""
    radii: Array
    """The wheels' radii (rear, front) [m]."""
    roll_limit: float
    """|roll| beyond which the machine has fallen [rad]."""
    steer_limit: float
    """|steer| beyond which the front wheel has tucked under, past a motorcycle's steering
    stops [rad]."""
    lam: float
    """The steering axis tilt [rad]: the rear frame's pitch when level on undeformed tyres."""
    magic: bool
    """Whether the tyres are the Magic Formula tyres ``mf_rear``, ``mf_front`` (else the
    linear tyres ``rear``, ``front``)."""
    mf_rear: TyreCoefficients
    """The rear Magic Formula tyre (a placeholder when ``magic`` is false)."""
    mf_front: TyreCoefficients
    """The front Magic Formula tyre."""


class State(NamedTuple):
    """The tyred model's state: coordinates, speeds and the relaxing side forces (SI)."""

    x: float
    """Rear wheel centre, ground x [m]."""
    y: float
    """Rear wheel centre, ground y (right) [m]."""
    z: float
    """Rear wheel centre, ground z (down: -height) [m]."""
    yaw: float
    roll: float
    pitch: float
    """The rear frame's pitch [rad] (the steering axis tilt when level)."""
    rear_angle: float
    steer: float
    front_angle: float
    forward: float
    """Rear wheel centre's velocity along the heading [m/s]."""
    lateral: float
    """Its velocity to the right, in the yaw frame [m/s]."""
    vertical: float
    """Its velocity downwards [m/s]."""
    yaw_rate: float
    roll_rate: float
    pitch_rate: float
    rear_spin: float
    """Rear wheel's spin relative to the rear frame about its axle [rad/s] (< 0 forward)."""
    steer_rate: float
    front_spin: float
    """Front wheel's spin relative to the front frame [rad/s] (< 0 rolling forward)."""
    Fy_r: float
    """Rear side force, relaxed [N] (+ to the right)."""
    Fy_f: float
    """Front side force, relaxed [N]."""


class Inputs(NamedTuple):
    """The rider's and the road's inputs."""

    steer_torque: float = 0.0
    """On the handlebar about the steering axis [N*m] (+ steers right)."""
    drive_torque: float = 0.0
    """On the rear wheel [N*m], positive driving forward."""
    front_brake_torque: float = 0.0
    """Front brake [N*m], >= 0, opposing the wheel's spin."""
    rear_brake_torque: float = 0.0
    """Rear brake [N*m], >= 0."""
    friction: float = 1.0
    """Road friction coefficient mu."""


class Domain(IntEnum):
    """Why a state is outside the model's domain (``INSIDE`` when it is not)."""

    INSIDE = 0
    FALLEN = 1
    REAR_LIFTED = 2
    FRONT_LIFTED = 3
    NOT_FINITE = 4
    STEER_STOP = 5


N_STATE = len(State._fields)


class Index(IntEnum):
    """Position of each :class:`State` field in the compiled state array (``x[Index.roll]``)."""

    x = 0
    y = 1
    z = 2
    yaw = 3
    roll = 4
    pitch = 5
    rear_angle = 6
    steer = 7
    front_angle = 8
    forward = 9
    lateral = 10
    vertical = 11
    yaw_rate = 12
    roll_rate = 13
    pitch_rate = 14
    rear_spin = 15
    steer_rate = 16
    front_spin = 17
    Fy_r = 18
    Fy_f = 19


assert tuple(Index.__members__) == State._fields

_COORDINATES = slice(Index.x, Index.front_angle + 1)
"""The coordinates among the compiled state (the generated code's q)."""
_SPEEDS = slice(Index.forward, Index.front_spin + 1)
"""The generalised speeds (its u)."""
_STEER_SPEED = Index.steer_rate - Index.forward
"""The steer rate's place among the generalised speeds (u = q' for the steer angle)."""


class ContactLoads(NamedTuple):
    """The tyre forces and slips at both contacts, and where the rear contact is (SI)."""

    F_xr: float
    """Rear longitudinal force on the wheel, along its heading [N] (< 0 braking)."""
    F_yr: float
    """Rear side force, relaxed and within the friction ellipse [N] (+ to the right)."""
    F_zr: float
    """Rear normal load [N]."""
    kappa_r: float
    """Rear longitudinal slip [-] (< 0 braking, -1 locked)."""
    alpha_r: float
    """Rear sideslip [rad]."""
    F_xf: float
    F_yf: float
    F_zf: float
    kappa_f: float
    alpha_f: float
    x_r: float
    """The rear contact's ground x [m]."""
    y_r: float
    """Its ground y (right) [m]."""


def make_model(
    params: MultibodyParameters,
    rear: LinearTyre | TyreParameters,
    front: LinearTyre | TyreParameters,
    *,
    drag: float = 0.0,
    aero_centre: tuple[float, float] | None = None,
    steer_damping: float = 0.0,
    steer_inertia: float = 0.0,
    roll_limit: float = 1.3,
    steer_limit: float = STEER_STOP,
) -> TyredModel:
    """Assemble the compiled model's constants.

    Parameters
    ----------
    params : MultibodyParameters
        The machine.
    rear, front : LinearTyre or TyreParameters
        The tyres, both linear relaxing tyres or both Magic Formula tyres (MF-MC, with their
        aligning and overturning moments, lateral relaxation lengths, radial stiffness and
        damping).
    drag : float, optional
        rho C_d A / 2 [kg/m]; no drag by default.
    aero_centre : (float, float), optional
        Where the drag acts, (x, z) in Meijaard's upright axes [m]; by default the rear
        frame's mass centre.
    steer_damping : float, optional
        Steering damper [N*m*s/rad].
    steer_inertia : float, optional
        Inertia turning with the steer angle about the steering axis besides the front
        frame's [kg*m^2] (a rider's arms: :func:`held`).
    roll_limit : float, optional
        |roll| beyond which :func:`domain` says the machine has fallen [rad].
    steer_limit : float, optional
        |steer| beyond which :func:`domain` says the front wheel tucked under [rad].
    """
    check_number(drag, where="tyred model: drag", lower=0.0, upper=10.0, lower_closed=True)
    check_number(
        steer_damping, where="tyred model: steer_damping", lower=0.0, upper=1e3, lower_closed=True
    )
    check_number(
        steer_inertia, where="tyred model: steer_inertia", lower=0.0, upper=10.0, lower_closed=True
    )
    check_number(roll_limit, where="tyred model: roll_limit", lower=0.1, upper=math.pi / 2)
    check_number(steer_limit, where="tyred model: steer_limit", lower=0.1, upper=math.pi / 2)
    magic = isinstance(rear, TyreParameters)
    if magic != isinstance(front, TyreParameters):
        raise MotosimError(
            "tyred model: one linear and one Magic Formula tyre; expected two of one kind"
        )
    if isinstance(rear, TyreParameters) and isinstance(front, TyreParameters):
        mf_rear, mf_front = tyre_coefficients(rear), tyre_coefficients(front)
        rear_array = np.array([0.0, 0.0, 0.0, rear.sigma_x, rear.k_z, rear.c_z])
        front_array = np.array([0.0, 0.0, 0.0, front.sigma_x, front.k_z, front.c_z])
    elif isinstance(rear, LinearTyre) and isinstance(front, LinearTyre):
        mf_rear = mf_front = _PLACEHOLDER
        rear_array, front_array = rear.as_array(), front.as_array()
    else:
        raise MotosimError("tyred model: tyres; expected LinearTyre or TyreParameters")
    x_a, z_a = aero_centre if aero_centre is not None else (params.x_B, params.z_B)
    cl, sl = math.cos(params.lam), math.sin(params.lam)
    rel_z = z_a + params.r_R
    la1, la2 = x_a * cl - rel_z * sl, x_a * sl + rel_z * cl
    p = np.concatenate([moore_parameters(params), [la1, la2]])
    assert len(p) == len(gen.PARAMETERS)
    return TyredModel(
        p=p,
        rear=rear_array,
        front=front_array,
        drag=float(drag),
        steer_damping=float(steer_damping),
        steer_inertia=float(steer_inertia),
        spin_inertia=np.array([params.I_Ryy, params.I_Fyy]),
        radii=np.array([params.r_R, params.r_F]),
        roll_limit=float(roll_limit),
        steer_limit=float(steer_limit),
        lam=float(params.lam),
        magic=magic,
        mf_rear=mf_rear,
        mf_front=mf_front,
    )


def held(model: TyredModel, inertia: float, damping: float) -> TyredModel:
    """The model with a rider's arms on the handlebar: their inertia J_a [kg*m^2] and
    damping c_a [N*m*s/rad] about the steering axis carried by the front frame.

    The arms add -J_a delta'' - c_a delta' to the steer torque, as on Sharp 1971's model
    (:func:`motosim.model.sharp.held_steering`; Cossalter, Doria, Lot & Massaro, Meccanica
    46, 2011, 279-292): J_a joins the mass matrix's steer entry, c_a the steering damper.
    Their stiffness is a torque about a held angle, left to whoever applies the steer torque.

    Examples
    --------
    >>> m = load_model("sel2004_motorcycle")
    >>> h = held(m, 0.05, 1.0)
    >>> round(h.steer_inertia, 3), round(h.steer_damping - m.steer_damping, 3)
    (0.05, 1.0)
    """
    check_number(inertia, where="held: inertia", lower=0.0, upper=10.0, lower_closed=True)
    check_number(damping, where="held: damping", lower=0.0, upper=1e3, lower_closed=True)
    return model._replace(
        steer_inertia=model.steer_inertia + inertia, steer_damping=model.steer_damping + damping
    )


_PLACEHOLDER = linear_tyre_coefficients(
    nominal_load=1.0,
    cornering_stiffness=1.0,
    camber_stiffness=0.0,
    slip_stiffness=1.0,
    relaxation_length=1.0,
    radius=1.0,
)
"""The Magic Formula slots of a model on linear tyres (never evaluated)."""


@njit(cache=True)
def magic_tyre_forces(
    c: TyreCoefficients, kin: Array, side_force: float, friction: float
) -> tuple[float, float, float, float, float, float, float, float, float]:
    """The Magic Formula tyre at one contact.

    Parameters
    ----------
    c : TyreCoefficients
        The tyre (:func:`motosim.model.tyres.tyre_coefficients`).
    kin : ndarray, shape (8,)
        The contact's kinematics from the generated ``contacts``.
    side_force : float
        The relaxed side force state [N].
    friction : float
        mu.

    Returns
    -------
    tuple of float
        F_x, F_y (the relaxed side force, both within the friction ellipse), F_z [N], the
        steady side force the relaxation tends to [N], kappa, alpha [rad], the aligning and
        overturning moments [N*m] (steady, scaled with the relaxed side force's share of the
        steady one) and the lateral relaxation length [m].
    """
    depth, depth_rate = kin[2], kin[3]
    load = 0.0
    if depth > 0.0:
        load = max(0.0, c.k_z * depth + c.c_z * depth_rate)
    speed = max(abs(kin[6]), _MIN_SPEED)
    kappa = -kin[4] / speed
    alpha = math.atan(-kin[5] / speed)
    camber = math.asin(min(1.0, max(-1.0, kin[7])))
    fx, steady, mz, mx = steady_forces(c, load, kappa, alpha, camber, friction)
    _, sigma = relaxation_lengths(c, load, speed)
    fy = side_force
    limit = friction * load
    total = math.sqrt(fx * fx + fy * fy)
    if total > limit:
        scale = limit / total if total > 0.0 else 0.0
        fx *= scale
        fy *= scale
    share = min(1.0, max(-1.0, fy / steady)) if abs(steady) > 1e-9 else 1.0
    return fx, fy, load, steady, kappa, alpha, mz * share, mx * share, sigma


@njit(cache=True)
def _tyre(
    model: TyredModel, front: bool, kin: Array, side_force: float, friction: float
) -> tuple[float, float, float, float, float, float, float, float, float]:
    """Either tyre law at one contact: as :func:`magic_tyre_forces` returns."""
    if model.magic:
        c = model.mf_front if front else model.mf_rear
        return magic_tyre_forces(c, kin, side_force, friction)
    tyre = model.front if front else model.rear
    fx, fy, fz, steady, kappa, alpha = linear_tyre_forces(tyre, kin, side_force, friction)
    return fx, fy, fz, steady, kappa, alpha, 0.0, 0.0, tyre[3]


@njit(cache=True)
def linear_tyre_forces(
    tyre: Array, kin: Array, side_force: float, friction: float
) -> tuple[float, float, float, float, float, float]:
    """The linear tyre at one contact: (F_x, F_y, F_z, F_y steady, kappa, alpha).

    Parameters
    ----------
    tyre : ndarray
        :meth:`LinearTyre.as_array`.
    kin : ndarray, shape (8,)
        The contact's kinematics from the generated ``contacts``.
    side_force : float
        The relaxed side force state [N].
    friction : float
        mu.

    Returns
    -------
    tuple of float
        Longitudinal and side forces on the wheel [N] (saturated by the friction ellipse),
        the normal load [N] (>= 0), the steady-state side force the relaxation tends to [N],
        the longitudinal slip and the sideslip [rad].
    """
    depth, depth_rate = kin[2], kin[3]
    load = 0.0
    if depth > 0.0:
        load = max(0.0, tyre[4] * depth + tyre[5] * depth_rate)
    speed = max(abs(kin[6]), _MIN_SPEED)
    kappa = -kin[4] / speed
    alpha = math.atan(-kin[5] / speed)
    camber = math.asin(min(1.0, max(-1.0, kin[7])))
    steady = load * (tyre[0] * alpha + tyre[1] * camber)
    fx = load * tyre[2] * kappa
    fy = side_force
    limit = friction * load
    total = math.sqrt(fx * fx + fy * fy)
    if total > limit:
        scale = limit / total if total > 0.0 else 0.0
        fx *= scale
        fy *= scale
    return fx, fy, load, steady, kappa, alpha


@njit(cache=True)
def _brake(torque: float, spin: float, inertia: float) -> float:
    """Brake torque on the wheel about its axle, opposing the relative spin."""
    zone = max(_MIN_BRAKE_SPIN, torque / (_BRAKE_RATE * max(inertia, 1e-6)))
    return -torque * min(1.0, max(-1.0, spin / zone))


@njit(cache=True)
def _add_contact(f: Array, J: Array, fx: float, fy: float, fz: float, mx: float, mz: float) -> None:
    """Add J^T (F_x, F_y, -F_z, M_x, M_z) to the generalised forces ``f`` in place.

    F_x along the wheel's heading, F_y across it (to the right), F_z the normal load (the
    ground pushes up), M_x the overturning moment about the heading, M_z the aligning moment
    about the downward normal, all on the wheel at its contact point.
    """
    for i in range(9):
        f[i] += J[0, i] * fx + J[1, i] * fy - J[2, i] * fz + J[3, i] * mx + J[4, i] * mz


@njit(cache=True)
def _derivatives(model: TyredModel, x: Array, inputs: Inputs) -> Array:
    q = x[_COORDINATES]
    u = x[_SPEEDS]
    steer = inputs.steer_torque - model.steer_damping * x[Index.steer_rate]
    rear = -inputs.drive_torque + _brake(
        inputs.rear_brake_torque, x[Index.rear_spin], model.spin_inertia[0]
    )
    front = _brake(inputs.front_brake_torque, x[Index.front_spin], model.spin_inertia[1])
    r = np.array([steer, rear, front])
    M, f = _mass_forcing(model.p, q, u, r)
    M[_STEER_SPEED, _STEER_SPEED] += model.steer_inertia
    kr, kf, Jr, Jf = _contacts(model.p, q, u)
    side_r, side_f = x[Index.Fy_r], x[Index.Fy_f]
    fxr, fyr, fzr, ssr, _, _, mzr, mxr, sigma_r = _tyre(model, False, kr, side_r, inputs.friction)
    fxf, fyf, fzf, ssf, _, _, mzf, mxf, sigma_f = _tyre(model, True, kf, side_f, inputs.friction)
    _add_contact(f, Jr, fxr, fyr, fzr, mxr, mzr)
    _add_contact(f, Jf, fxf, fyf, fzf, mxf, mzf)
    if model.drag > 0.0:
        Ja = _aero_jacobian(model.p, q)
        va = 0.0
        for i in range(9):
            va += Ja[0, i] * u[i]
        drag = -model.drag * va * abs(va)
        for i in range(9):
            f[i] += Ja[0, i] * drag
    out = np.empty(N_STATE)
    out[:9] = _kinematics(model.p, q, u)
    out[_SPEEDS] = np.linalg.solve(M, f)
    out[Index.Fy_r] = max(abs(kr[6]), _MIN_SPEED) / sigma_r * (ssr - side_r)
    out[Index.Fy_f] = max(abs(kf[6]), _MIN_SPEED) / sigma_f * (ssf - side_f)
    return out


@njit(cache=True)
def observe(model: TyredModel, x: Array, friction: float) -> ContactLoads:
    """The tyre forces and slips of the compiled state ``x`` on a road of ``friction`` mu."""
    kr, kf, _, _ = _contacts(model.p, x[_COORDINATES], x[_SPEEDS])
    fxr, fyr, fzr, _, kappa_r, alpha_r, _, _, _ = _tyre(model, False, kr, x[Index.Fy_r], friction)
    fxf, fyf, fzf, _, kappa_f, alpha_f, _, _, _ = _tyre(model, True, kf, x[Index.Fy_f], friction)
    return ContactLoads(
        fxr, fyr, fzr, kappa_r, alpha_r, fxf, fyf, fzf, kappa_f, alpha_f, kr[0], kr[1]
    )


@njit(cache=True)
def outside(model: TyredModel, x: Array) -> int:
    """Why the compiled state ``x`` is outside the model's domain, as a :class:`Domain` code
    (``Domain.INSIDE`` when it is not): :func:`domain` for compiled callers."""
    for i in range(x.size):
        if not math.isfinite(x[i]):
            return Domain.NOT_FINITE
    if abs(x[Index.roll]) > model.roll_limit:
        return Domain.FALLEN
    if abs(x[Index.steer]) > model.steer_limit:
        return Domain.STEER_STOP
    kr, kf, _, _ = _contacts(model.p, x[_COORDINATES], x[_SPEEDS])
    if kr[2] <= 0.0:
        return Domain.REAR_LIFTED
    if kf[2] <= 0.0:
        return Domain.FRONT_LIFTED
    return Domain.INSIDE


@njit(cache=True)
def _rk4(model: TyredModel, x: Array, inputs: Inputs, h: float) -> Array:
    k1 = _derivatives(model, x, inputs)
    k2 = _derivatives(model, x + 0.5 * h * k1, inputs)
    k3 = _derivatives(model, x + 0.5 * h * k2, inputs)
    k4 = _derivatives(model, x + h * k3, inputs)
    return x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


@njit(cache=True)
def advance(model: TyredModel, x: Array, inputs: Inputs, h: float) -> Array:
    """The compiled state ``x`` one classical Runge-Kutta step of ``h`` [s] later (compiled;
    no input checks): :func:`step` on the state's array."""
    return _rk4(model, x, inputs, h)


@njit(cache=True)
def rates(model: TyredModel, x: Array, inputs: Inputs) -> Array:
    """The compiled state's time derivative (compiled; no input checks)."""
    return _derivatives(model, x, inputs)


@njit(cache=True)
def _pack(s: State) -> Array:
    x = np.empty(N_STATE)
    x[0], x[1], x[2], x[3], x[4] = s.x, s.y, s.z, s.yaw, s.roll
    x[5], x[6], x[7], x[8] = s.pitch, s.rear_angle, s.steer, s.front_angle
    x[9], x[10], x[11], x[12], x[13] = s.forward, s.lateral, s.vertical, s.yaw_rate, s.roll_rate
    x[14], x[15], x[16], x[17] = s.pitch_rate, s.rear_spin, s.steer_rate, s.front_spin
    x[18], x[19] = s.Fy_r, s.Fy_f
    return x


@njit(cache=True)
def _unpack(x: Array) -> State:
    return State(
        x[0],
        x[1],
        x[2],
        x[3],
        x[4],
        x[5],
        x[6],
        x[7],
        x[8],
        x[9],
        x[10],
        x[11],
        x[12],
        x[13],
        x[14],
        x[15],
        x[16],
        x[17],
        x[18],
        x[19],
    )


@njit(cache=True)
def step(model: TyredModel, state: State, inputs: Inputs, h: float) -> State:
    """One classical Runge-Kutta step of length ``h`` [s] (compiled; no input checks)."""
    return _unpack(_rk4(model, _pack(state), inputs, h))


def validate_inputs(inputs: Inputs) -> Inputs:
    """Check the inputs at the edge (the compiled :func:`step` does not).

    Raises
    ------
    MotosimError
        Naming the first input that is not finite, a brake torque below 0, or a friction
        coefficient outside (0, 3].
    """
    for name in ("steer_torque", "drive_torque"):
        check_number(getattr(inputs, name), where=f"tyred inputs: {name}", unit="N*m")
    for name in ("front_brake_torque", "rear_brake_torque"):
        check_number(
            getattr(inputs, name),
            where=f"tyred inputs: {name}",
            lower=0.0,
            lower_closed=True,
            unit="N*m",
        )
    check_number(
        inputs.friction, where="tyred inputs: friction", lower=0.0, upper=3.0, lower_closed=False
    )
    return inputs


def derivatives(model: TyredModel, state: State, inputs: Inputs) -> State:
    """The state's time derivative, as a :class:`State` of rates (SI units per second)."""
    return State(*_derivatives(model, np.array(state, dtype=float), inputs))


def contact_loads(model: TyredModel, state: State, inputs: Inputs) -> dict[str, float]:
    """The tyre forces and slips at both contacts.

    Returns
    -------
    dict of str to float
        ``F_xr``, ``F_yr``, ``F_zr``, ``kappa_r``, ``alpha_r``, ``M_zr``, ``M_xr`` and the
        same for the front (``_f``) [N, 1, rad, N*m], ``camber_r``, ``camber_f`` [rad].
    """
    x = np.array(state, dtype=float)
    kr, kf, _, _ = gen.contacts(model.p, x[_COORDINATES], x[_SPEEDS])
    out: dict[str, float] = {}
    for suffix, front, kin, side in (
        ("r", False, kr, x[Index.Fy_r]),
        ("f", True, kf, x[Index.Fy_f]),
    ):
        fx, fy, fz, _, kappa, alpha, mz, mx, _ = _tyre(model, front, kin, side, inputs.friction)
        out |= {
            f"M_z{suffix}": mz,
            f"M_x{suffix}": mx,
            f"F_x{suffix}": fx,
            f"F_y{suffix}": fy,
            f"F_z{suffix}": fz,
            f"kappa_{suffix}": kappa,
            f"alpha_{suffix}": alpha,
            f"camber_{suffix}": math.asin(max(-1.0, min(1.0, kin[7]))),
        }
    return out


def domain(model: TyredModel, state: State) -> Domain:
    """Whether the state is one the model describes, and if not why.

    Returns
    -------
    Domain
        ``NOT_FINITE`` for a NaN or infinite value, ``FALLEN`` when |roll| exceeds the
        model's roll limit, ``STEER_STOP`` when |steer| exceeds its steer limit (the front
        wheel tucked under), ``REAR_LIFTED`` / ``FRONT_LIFTED`` when a wheel is off the ground,
        ``INSIDE`` otherwise.
    """
    return Domain(outside(model, np.array(state, dtype=float)))


def upright_state(model: TyredModel, speed: float) -> State:
    """Upright straight running at ``speed`` [m/s] on the tyres' static compression.

    The height and pitch of the rear frame are those at which the vertical and pitch
    accelerations vanish (Newton's iteration), the wheels roll without slip. With drag the
    state is not an equilibrium (nothing drives against it).

    Parameters
    ----------
    model : TyredModel
        The model.
    speed : float
        Forward speed [m/s].

    Raises
    ------
    MotosimError
        If the speed is not a finite number within +/-150 m/s, or no equilibrium is found.
    """
    check_number(speed, where="tyred model: speed", lower=-150.0, upper=150.0)
    r_R, r_F = float(model.radii[0]), float(model.radii[1])
    x = np.zeros(N_STATE)
    x[Index.z], x[Index.pitch] = -r_R, model.lam
    x[Index.forward] = speed
    x[Index.rear_spin], x[Index.front_spin] = -speed / r_R, -speed / r_F
    inputs = Inputs()
    balance = [Index.vertical, Index.pitch_rate]  # their rates vanish at the equilibrium
    for _ in range(50):
        residual = _derivatives(model, x, inputs)[balance]
        jac = np.empty((2, 2))
        for j, index in enumerate((Index.z, Index.pitch)):
            dx = np.zeros(N_STATE)
            dx[index] = 1e-7
            jac[:, j] = (
                _derivatives(model, x + dx, inputs)[balance]
                - _derivatives(model, x - dx, inputs)[balance]
            ) / 2e-7
        change = np.linalg.solve(jac, residual)
        x[Index.z] -= change[0]
        x[Index.pitch] -= change[1]
        if np.max(np.abs(change)) < 1e-13:
            break
    else:
        raise MotosimError(f"tyred model: no static equilibrium found at {speed:g} m/s")
    return State(*x)


LATERAL = tuple(
    int(i)
    for i in (
        Index.roll,
        Index.steer,
        Index.lateral,
        Index.yaw_rate,
        Index.roll_rate,
        Index.steer_rate,
        Index.Fy_r,
        Index.Fy_f,
    )
)
"""Roll, steer, lateral velocity, yaw rate, roll rate, steer rate, F_y rear, F_y front."""


def lateral_matrix(model: TyredModel, speed: float) -> Array:
    """Linearised lateral dynamics about upright straight running (central differences).

    Returns
    -------
    numpy.ndarray, shape (8, 8)
        A of x' = A x, x = (roll, steer, lateral velocity, yaw rate, roll rate, steer rate,
        F_y rear, F_y front): the in-plane motion decouples from these by symmetry.
    """
    x0 = np.array(upright_state(model, speed), dtype=float)
    inputs = Inputs()
    A = np.empty((8, 8))
    for j, index in enumerate(LATERAL):
        delta = 1e-6 * max(1.0, abs(x0[index]))
        dx = np.zeros(N_STATE)
        dx[index] = delta
        diff = _derivatives(model, x0 + dx, inputs) - _derivatives(model, x0 - dx, inputs)
        A[:, j] = diff[list(LATERAL)] / (2 * delta)
    return A


def lateral_system(model: TyredModel, speed: float) -> tuple[Array, Array]:
    """Linearised lateral dynamics about upright straight running, with the steer torque.

    Returns
    -------
    A : numpy.ndarray, shape (8, 8)
        :func:`lateral_matrix`.
    B : numpy.ndarray, shape (8,)
        The rates of the same states per unit steer torque [per N*m] (central differences).
    """
    x0 = np.array(upright_state(model, speed), dtype=float)
    torque = 1.0
    diff = _derivatives(model, x0, Inputs(steer_torque=torque)) - _derivatives(
        model, x0, Inputs(steer_torque=-torque)
    )
    return lateral_matrix(model, speed), diff[list(LATERAL)] / (2 * torque)


def sharp_machine(
    sharp: SharpParameters, *, radial_stiffness: float = 1.5e5, radial_damping: float = 1.5e3
) -> tuple[MultibodyParameters, LinearTyre, LinearTyre, float]:
    """Sharp's (1971) standard machine as multibody parameters with his linear tyres.

    Sharp's two bodies carry the wheels: the rear frame (with the rider, the rear wheel and
    the engine's flywheel) and the front frame (fork, handlebar, front wheel). Here the wheels
    are massless bodies at their centres with Sharp's spin inertias (i_Ry, i_fy) and half of
    them as diametral inertias, taken out of the frames' inertias so that each assembly keeps
    Sharp's inertia. The rear frame's pitch inertia is not in Sharp's lateral model; it is
    assumed 0.9 (I_Bxx + I_Bzz), a body thin across its plane.

    Parameters
    ----------
    sharp : SharpParameters
        Sharp's standard machine (the packaged ``sharp1971`` set).
    radial_stiffness, radial_damping : float, optional
        Both tyres' radial stiffness [N/m] and damping [N*s/m]: not in Sharp (rigid wheels);
        the defaults are of a motorcycle tyre's order.

    Returns
    -------
    params : MultibodyParameters
        Meijaard-style parameters: wheelbase b + l, trail t / cos(eps) on the ground, the
        mass centres at (b, -h) and (b + k, -j).
    rear, front : LinearTyre
        Sharp's cornering and camber stiffnesses per unit of the static loads of this
        geometry, his relaxation length; the longitudinal stiffness (not in Sharp) 20.
    steer_damping : float
        Sharp's steering damper K [N*m*s/rad].
    """
    geo = derived_geometry(sharp)
    eps = sharp.epsilon
    ce, se = math.cos(eps), math.sin(eps)
    half_r, half_f = sharp.i_Ry / 2, sharp.i_fy / 2
    i1, i3 = sharp.I_fx - half_f, sharp.I_fz - half_f
    bxx, bzz = sharp.I_rx - half_r, sharp.I_rz - half_r
    params = MultibodyParameters(
        w=geo["wheelbase"],
        c=sharp.t / ce,
        lam=eps,
        g=9.80665,
        r_R=sharp.R_r,
        m_R=0.0,
        I_Rxx=half_r,
        I_Ryy=sharp.i_Ry,
        x_B=sharp.b,
        z_B=-sharp.h,
        m_B=sharp.m_r,
        I_Bxx=bxx,
        I_Byy=0.9 * (bxx + bzz),
        I_Bzz=bzz,
        I_Bxz=-sharp.C_rxz,
        x_H=sharp.b + geo["k"],
        z_H=-geo["j"],
        m_H=sharp.m_f,
        I_Hxx=i1 * ce**2 + i3 * se**2,
        I_Hyy=i1,
        I_Hzz=i1 * se**2 + i3 * ce**2,
        I_Hxz=(i3 - i1) * se * ce,
        r_F=sharp.R_f,
        m_F=0.0,
        I_Fxx=half_f,
        I_Fyy=sharp.i_fy,
        t_R=0.0,
        t_F=0.0,
    )
    x_G, _ = params.mass_centre
    weight = params.mass * params.g
    load_f = weight * x_G / params.w
    load_r = weight - load_f

    def tyre(cornering: float, camber: float, load: float) -> LinearTyre:
        return LinearTyre(
            cornering=cornering / load,
            camber=camber / load,
            longitudinal=20.0,
            relaxation_length=sharp.sigma,
            radial_stiffness=radial_stiffness,
            radial_damping=radial_damping,
        )

    return (
        params,
        tyre(sharp.C_r1, sharp.C_r2, load_r),
        tyre(sharp.C_f1, sharp.C_f2, load_f),
        sharp.K,
    )


def sharp_modes(sharp: SharpParameters, speeds: ArrayLike) -> ModeTable:
    """Capsize, weave and wobble of Sharp's machine through the multibody model on tyres.

    The machine of :func:`sharp_machine` (Sharp's bodies, tyres and steering damper),
    linearised about upright straight running at each speed (:func:`lateral_matrix`) and
    classified as :func:`motosim.model.sharp.modes` classifies Sharp's own model.

    Parameters
    ----------
    sharp : SharpParameters
        Sharp's machine.
    speeds : array_like
        Forward speeds [m/s].

    Returns
    -------
    ModeTable
    """
    params, rear, front, damper = sharp_machine(sharp)
    model = make_model(params, rear, front, steer_damping=damper)

    def spectrum(at: Array) -> npt.NDArray[np.complex128]:
        out = np.empty((len(at), 8), dtype=complex)
        for i, speed in enumerate(at):
            ev = np.linalg.eigvals(lateral_matrix(model, float(speed)))
            out[i] = ev[np.lexsort((ev.imag, ev.real))]
        return out

    return modes(sharp, speeds, spectrum=spectrum)


def linearised_tyre(tyre: TyreParameters, load: float, speed: float) -> LinearTyre:
    """The linear relaxing tyre that matches a Magic Formula tyre at zero slip and camber.

    Parameters
    ----------
    tyre : TyreParameters
        The MF-MC tyre.
    load : float
        The normal load at which the stiffnesses are taken [N] (the static load).
    speed : float
        The speed at which the lateral relaxation length is taken [m/s].

    Returns
    -------
    LinearTyre
        The MF-MC's cornering, camber and slip stiffnesses at ``load`` per unit load
        (:func:`motosim.model.tyres.cornering_stiffness` and its siblings), its lateral
        relaxation length at ``load`` and ``speed``, its radial stiffness and damping.
    """
    from motosim.model import tyres

    check_number(load, where="linearised tyre: load", lower=0.0, upper=1e5, unit="N")
    check_number(speed, where="linearised tyre: speed", lower=0.0, upper=150.0, unit="m/s")
    c = tyres.tyre_coefficients(tyre)
    _, sigma_y = tyres.relaxation_lengths(c, load, speed)
    return LinearTyre(
        cornering=tyres.cornering_stiffness(c, load, 0.0) / load,
        camber=tyres.camber_stiffness(c, load) / load,
        longitudinal=tyres.slip_stiffness(c, load) / load,
        relaxation_length=sigma_y,
        radial_stiffness=tyre.k_z,
        radial_damping=tyre.c_z,
    )


def load_model(name_or_path: str, *, tyres: str = "magic", speed: float = 20.0) -> TyredModel:
    """The tyred model of a parameter set, by name or TOML path.

    A ``sharp`` set is Sharp's machine of :func:`sharp_machine` (his linear relaxing tyres,
    knife-edge wheels, his steering damper). A ``multibody`` set that names its tyres
    (``front_tyre``, ``rear_tyre`` in its ``[set]``) runs on its toroidal wheels with those
    Magic Formula tyres (``tyres="magic"``) or with the linear relaxing tyres that match them
    at the static loads (``tyres="linear"``: :func:`linearised_tyre`, the relaxation length
    at ``speed`` [m/s]).

    Raises
    ------
    MotosimError
        If the set is unknown, of another kind, a multibody set without tyres, or ``tyres``
        is neither ``"magic"`` nor ``"linear"``.
    """
    if tyres not in ("magic", "linear"):
        raise MotosimError(f"tyred model: tyres = {tyres!r}; expected 'magic' or 'linear'")
    pset = load_parameter_set(name_or_path)
    if isinstance(pset.values, SharpParameters):
        params, rear, front, damper = sharp_machine(pset.values)
        return make_model(params, rear, front, steer_damping=damper)
    if not isinstance(pset.values, MultibodyParameters):
        raise MotosimError(
            f"parameter set {name_or_path!r}: is a {pset.model} parameter set; expected a "
            "sharp or multibody set"
        )
    missing = [key for key in ("front_tyre", "rear_tyre") if key not in pset.tyres]
    if missing:
        raise MotosimError(
            f"parameter set {name_or_path!r}: names no {missing[0]}; expected a multibody set "
            "with tyres (e.g. sel2004_motorcycle)"
        )
    params = pset.values
    front_mf = load_parameters(pset.tyres["front_tyre"], "tyre")
    rear_mf = load_parameters(pset.tyres["rear_tyre"], "tyre")
    if tyres == "magic":
        return make_model(params, rear_mf, front_mf)
    x_G, _ = params.mass_centre
    weight = params.mass * params.g
    load_f = weight * x_G / params.w
    front = linearised_tyre(front_mf, load_f, speed)
    rear = linearised_tyre(rear_mf, weight - load_f, speed)
    return make_model(params, rear, front)


def lateral_modes(model: TyredModel, speeds: ArrayLike) -> ModeTable:
    """Capsize, weave and wobble of a tyred model about upright straight running.

    The eigenvalues of :func:`lateral_matrix` at each speed (the lateral states only: the
    heading and the lateral position, which add two zero eigenvalues, are left out, and the
    in-plane motion decouples by symmetry), classified and followed over speed by
    :func:`motosim.model.sharp.track_modes`. On a model whose tyres are Magic Formula tyres
    the linearisation is that of the MF-MC at zero slip and camber at the static loads
    (cornering, camber and aligning stiffnesses, the lateral relaxation length at each speed).

    Parameters
    ----------
    model : TyredModel
        The model (:func:`make_model` or :func:`load_model`).
    speeds : array_like
        Forward speeds [m/s], within [:data:`motosim.model.sharp.MIN_SPEED`,
        :data:`motosim.model.sharp.MAX_SPEED`], in any order.

    Returns
    -------
    ModeTable

    Raises
    ------
    MotosimError
        If a speed is out of range or the modes cannot be identified.
    """
    from motosim.model.sharp import track_modes

    def spectrum(at: Array) -> npt.NDArray[np.complex128]:
        out = np.empty((len(at), 8), dtype=complex)
        for i, speed in enumerate(at):
            out[i] = np.linalg.eigvals(lateral_matrix(model, float(speed)))
        return out

    return track_modes(speeds, spectrum)
