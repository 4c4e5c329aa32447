"""The steady turn of the multibody motorcycle on tyres.

A steady turn is an equilibrium of :mod:`motosim.model.tyred` in the yawing frame: the
machine yaws at a constant rate Omega = v / R, its roll, pitch, height and steer are constant,
the wheels spin at constant rates, the side forces have relaxed to their steady values, and
the rider holds the handlebar with the steer torque tau_r while the drive torque on the rear
wheel holds the speed. Here v and R are the speed and the path radius of the whole machine's
mass centre, so that the tyres' horizontal forces add up to m v^2 / R towards the centre.

:func:`steady_turn` solves the twelve conditions (the nine accelerations and the two side
forces' rates vanish, the mass centre moves at v) for the twelve unknowns (height, roll,
pitch, steer, the rear wheel centre's forward and lateral velocities, both wheels' spins,
both side forces, tau_r and the drive torque) with Powell's hybrid method
(``scipy.optimize.root``), started from the kinematic roll atan(v^2 / (g R)) corrected for
the tyres' crown radii (Cossalter 2006, *Motorcycle Dynamics*, 2nd ed., chapter 4) and the
kinematic steer w / R.

Only the yaw rate's vertical axis and the mass centre's path are prescribed; the turn's
direction follows the sign of the radius (R > 0 turns right, the machine leaning right).
"""

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from motosim.errors import MotosimError
from motosim.model import _generated_tyred as gen
from motosim.model.tyred import Inputs, State, TyredModel, _mass_forcing, contact_loads, derivatives
from motosim.model.tyred import upright_state as _upright_state
from motosim.params.checks import check_number

__all__ = [
    "NoSteadyTurnError",
    "Trim",
    "handling_curve",
    "horizontal_tyre_force",
    "kinematic_roll",
    "mass_centre",
    "steady_turn",
]

_ACCELERATIONS = slice(9, 18)
"""The accelerations' entries of the state's derivative (forward .. front wheel spin)."""
_TOLERANCE = 1e-13
_RESIDUAL = 1e-12
"""Largest residual of a solution: the generalised forces' imbalance M u' per unit weight
[1, m], the side forces' rates per unit weight and speed [1/m], the mass centre's speed
error [m/s]."""
_STEP_G = 0.1
"""The continuation's step in lateral acceleration [g]: each turn is reached from straight
running through turns of increasing lateral acceleration at the same speed."""


class NoSteadyTurnError(MotosimError):
    """The asked turn has no equilibrium (beyond the tyres' friction, a wheel off the ground)."""


class _Unknowns(NamedTuple):
    """What the steady turn solves for (SI units)."""

    z: float
    roll: float
    pitch: float
    steer: float
    forward: float
    lateral: float
    rear_spin: float
    front_spin: float
    Fy_r: float
    Fy_f: float
    steer_torque: float
    drive_torque: float


@dataclass(frozen=True, slots=True)
class Trim:
    """A steady turn of the tyred motorcycle (SI units, angles in radians).

    Attributes
    ----------
    speed, radius : float
        The mass centre's speed [m/s] and path radius [m] (> 0 turning right).
    yaw_rate : float
        v / R [rad/s].
    phi : float
        Roll of the rear frame [rad] (> 0 leaning right).
    delta : float
        Steer angle about the steering axis [rad] (> 0 steering right).
    tau_r : float
        The rider's steer torque that holds the turn [N*m] (> 0 steering right).
    drive_torque : float
        The rear wheel's drive torque that holds the speed [N*m].
    F_xf, F_xr, F_yf, F_yr, F_zf, F_zr : float
        The tyres' longitudinal and side forces (in each wheel's heading and across it, + to
        the right) and normal loads, front and rear [N].
    kappa_f, kappa_r : float
        Longitudinal slips [1].
    alpha_f, alpha_r : float
        Sideslips [rad].
    camber_f, camber_r : float
        The wheels' cambers [rad].
    phi_kinematic : float
        atan(v^2 / (g R)), the roll of a machine on knife-edge wheels without gyroscopic and
        steering terms [rad].
    state : State
        The model's state at the trim (position and yaw at zero).
    """

    speed: float
    radius: float
    yaw_rate: float
    phi: float
    delta: float
    tau_r: float
    drive_torque: float
    F_xf: float
    F_xr: float
    F_yf: float
    F_yr: float
    F_zf: float
    F_zr: float
    kappa_f: float
    kappa_r: float
    alpha_f: float
    alpha_r: float
    camber_f: float
    camber_r: float
    phi_kinematic: float
    state: State

    @property
    def lateral_acceleration(self) -> float:
        """v^2 / R [m/s^2]."""
        return self.speed**2 / self.radius

    @property
    def lateral_g(self) -> float:
        """v^2 / (g R), the lateral acceleration in units of gravity [1]."""
        return math.tan(self.phi_kinematic)


def _p(model: TyredModel, name: str) -> float:
    return float(model.p[gen.PARAMETERS.index(name)])


def kinematic_roll(model: TyredModel, speed: float, radius: float) -> float:
    """atan(v^2 / (g R)) [rad]: the roll at which gravity and the centrifugal force balance."""
    return math.atan(speed**2 / (_p(model, "g") * radius))


def _rotations(roll: float, pitch: float, steer: float) -> tuple[np.ndarray, np.ndarray]:
    """The rear (C) and front (E) frames' axes in the yaw frame's components (columns)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cs, ss = math.cos(steer), math.sin(steer)
    a_b = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    b_c = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    c_e = np.array([[cs, -ss, 0.0], [ss, cs, 0.0], [0.0, 0.0, 1.0]])
    a_c = a_b @ b_c
    return a_c, a_c @ c_e


def mass_centre(model: TyredModel, state: State) -> np.ndarray:
    """The whole machine's mass centre from the rear wheel centre, in the yaw frame [m].

    Returns
    -------
    numpy.ndarray, shape (3,)
        Forward, right and down components.
    """
    a_c, a_e = _rotations(state.roll, state.pitch, state.steer)
    cx, cz, ex, ez = a_c[:, 0], a_c[:, 2], a_e[:, 0], a_e[:, 2]
    co = _p(model, "l1") * cx + _p(model, "l2") * cz
    fo = _p(model, "d1") * cx + _p(model, "d2") * cz + _p(model, "d3") * ex
    eo = fo + _p(model, "l3") * ex + _p(model, "l4") * ez
    masses = [_p(model, name) for name in ("mC", "mD", "mE", "mF")]
    total = sum(masses)
    return (masses[0] * co + masses[2] * eo + masses[3] * fo) / total


def horizontal_tyre_force(model: TyredModel, state: State, loads: dict[str, float]) -> np.ndarray:
    """The tyres' horizontal force on the machine in the yaw frame (forward, right) [N]."""
    a_c, a_e = _rotations(state.roll, state.pitch, state.steer)
    total = np.zeros(2)
    for suffix, axle in (("r", a_c[:, 1]), ("f", a_e[:, 1])):
        heading = np.array([axle[1], -axle[0]]) / math.hypot(axle[0], axle[1])
        lateral = np.array([-heading[1], heading[0]])
        total += loads[f"F_x{suffix}"] * heading + loads[f"F_y{suffix}"] * lateral
    return total


def _state(unknowns: _Unknowns, yaw_rate: float) -> State:
    return State(
        x=0.0,
        y=0.0,
        z=unknowns.z,
        yaw=0.0,
        roll=unknowns.roll,
        pitch=unknowns.pitch,
        rear_angle=0.0,
        steer=unknowns.steer,
        front_angle=0.0,
        forward=unknowns.forward,
        lateral=unknowns.lateral,
        vertical=0.0,
        yaw_rate=yaw_rate,
        roll_rate=0.0,
        pitch_rate=0.0,
        rear_spin=unknowns.rear_spin,
        steer_rate=0.0,
        front_spin=unknowns.front_spin,
        Fy_r=unknowns.Fy_r,
        Fy_f=unknowns.Fy_f,
    )


def _inputs(unknowns: _Unknowns, friction: float) -> Inputs:
    return Inputs(
        steer_torque=unknowns.steer_torque, drive_torque=unknowns.drive_torque, friction=friction
    )


def _mass_centre_speed(model: TyredModel, state: State) -> float:
    """The mass centre's horizontal speed in the steady yawing motion [m/s]."""
    g = mass_centre(model, state)
    return math.hypot(state.forward - state.yaw_rate * g[1], state.lateral + state.yaw_rate * g[0])


def steady_turn(model: TyredModel, speed: float, radius: float, *, friction: float = 1.0) -> Trim:
    """The steady turn at ``speed`` on a path of ``radius`` (the mass centre's).

    Parameters
    ----------
    model : TyredModel
        The machine on its tyres (:func:`motosim.model.tyred.make_model`); its drag, if any,
        is held by the drive torque.
    speed : float
        The mass centre's speed [m/s], 1 to 100.
    radius : float
        Its path radius [m], > 0 turning right, < 0 turning left, |R| >= 2 m.
    friction : float, optional
        Road friction coefficient mu.

    Returns
    -------
    Trim

    Raises
    ------
    MotosimError
        If the speed, radius or friction is not a finite number in its range.
    NoSteadyTurnError
        If the turn has no equilibrium: the lateral acceleration beyond what the road's
        friction carries, a tyre saturated, a wheel off the ground or the machine beyond its
        roll limit.
    """
    check_number(speed, where="steady turn: speed", lower=1.0, upper=100.0, unit="m/s")
    check_number(radius, where="steady turn: radius", unit="m")
    if abs(radius) < 2.0:
        raise MotosimError(
            f"steady turn: radius = {radius:g} m; expected |radius| >= 2 m (a motorcycle turn)"
        )
    check_number(friction, where="steady turn: friction", lower=0.0, upper=3.0)
    g = _p(model, "g")
    weight = g * sum(_p(model, name) for name in ("mC", "mD", "mE", "mF"))
    lateral_g = speed**2 / (g * abs(radius))
    if lateral_g >= friction:
        raise NoSteadyTurnError(
            f"steady turn: {speed:g} m/s on a {abs(radius):g} m radius needs {lateral_g:.3f} g "
            f"of lateral acceleration, beyond the road's friction mu = {friction:g}"
        )
    yaw_rate = speed / radius
    phi_k = kinematic_roll(model, speed, radius)
    steps = max(1, math.ceil(lateral_g / _STEP_G))
    unknowns = _first_guess(model, speed, speed**2 / (radius * steps))
    for k in range(1, steps + 1):
        solved = _solve(model, speed, radius * steps / k, friction, weight, unknowns)
        if solved is None:
            raise NoSteadyTurnError(
                f"steady turn: no equilibrium at {speed:g} m/s on a {abs(radius):g} m radius "
                f"({lateral_g:.3f} g): none found beyond {lateral_g * (k - 1) / steps:.3f} g"
            )
        unknowns = solved
    state = _state(unknowns, yaw_rate)
    inputs = _inputs(unknowns, friction)
    loads = contact_loads(model, state, inputs)
    _check_inside(model, state, loads, friction, speed, radius)
    return Trim(
        speed=float(speed),
        radius=float(radius),
        yaw_rate=yaw_rate,
        phi=unknowns.roll,
        delta=unknowns.steer,
        tau_r=unknowns.steer_torque,
        drive_torque=unknowns.drive_torque,
        F_xf=loads["F_xf"],
        F_xr=loads["F_xr"],
        F_yf=loads["F_yf"],
        F_yr=loads["F_yr"],
        F_zf=loads["F_zf"],
        F_zr=loads["F_zr"],
        kappa_f=loads["kappa_f"],
        kappa_r=loads["kappa_r"],
        alpha_f=loads["alpha_f"],
        alpha_r=loads["alpha_r"],
        camber_f=loads["camber_f"],
        camber_r=loads["camber_r"],
        phi_kinematic=phi_k,
        state=state,
    )


def _first_guess(model: TyredModel, speed: float, lateral_acceleration: float) -> _Unknowns:
    """The kinematic turn at a small lateral acceleration, to start Newton's iteration."""
    upright = _upright_state(model, speed)
    static = contact_loads(model, upright, Inputs())
    g = _p(model, "g")
    phi_k = math.atan(lateral_acceleration / g)
    crown = 0.5 * (_p(model, "tR") + _p(model, "tF"))
    lever = max(-upright.z - crown, 0.1)
    roll = phi_k + math.asin(max(-1.0, min(1.0, crown * math.sin(phi_k) / lever)))
    t_r, r_r = _p(model, "tR"), float(model.radii[0])
    compression = upright.z + r_r
    radius = speed**2 / lateral_acceleration
    return _Unknowns(
        z=compression - (r_r - t_r) * math.cos(roll) - t_r,
        roll=roll,
        pitch=upright.pitch,
        steer=_wheelbase(model) / radius / math.cos(model.lam),
        forward=speed,
        lateral=0.0,
        rear_spin=-speed / r_r,
        front_spin=-speed / float(model.radii[1]),
        Fy_r=static["F_zr"] * math.tan(phi_k),
        Fy_f=static["F_zf"] * math.tan(phi_k),
        steer_torque=0.0,
        drive_torque=0.0,
    )


def _solve(
    model: TyredModel,
    speed: float,
    radius: float,
    friction: float,
    weight: float,
    guess: _Unknowns,
) -> _Unknowns | None:
    """Powell's hybrid method on the steady-turn conditions from ``guess`` (None: failed)."""
    from scipy.optimize import root

    yaw_rate = speed / radius
    force_rate = speed * weight

    def residual(x: np.ndarray) -> np.ndarray:
        unknowns = _Unknowns(*(float(v) for v in x))
        state = _state(unknowns, yaw_rate)
        rates = np.array(derivatives(model, state, _inputs(unknowns, friction)), dtype=float)
        x_state = np.array(state, dtype=float)
        mass, _ = _mass_forcing(model.p, x_state[:9], x_state[9:18], np.zeros(3))
        out = np.empty(len(_Unknowns._fields))
        out[:9] = mass @ rates[_ACCELERATIONS] / weight
        out[9] = rates[18] / force_rate
        out[10] = rates[19] / force_rate
        out[11] = _mass_centre_speed(model, state) - speed
        return out

    solution = root(residual, np.array(guess), method="hybr", options={"xtol": _TOLERANCE})
    if not solution.success or not np.all(np.abs(residual(solution.x)) < _RESIDUAL):
        return None
    return _Unknowns(*(float(v) for v in solution.x))


def _wheelbase(model: TyredModel) -> float:
    """The front wheel centre's distance ahead of the rear's, upright [m]."""
    upright = _rotations(0.0, model.lam, 0.0)[0]
    fo = (
        _p(model, "d1") * upright[:, 0]
        + _p(model, "d2") * upright[:, 2]
        + _p(model, "d3") * upright[:, 0]
    )
    return float(fo[0])


def _check_inside(
    model: TyredModel,
    state: State,
    loads: dict[str, float],
    friction: float,
    speed: float,
    radius: float,
) -> None:
    """Raise :class:`NoSteadyTurnError` when the equilibrium is not a ridable turn."""
    where = f"steady turn: {speed:g} m/s on a {abs(radius):g} m radius"
    if abs(state.roll) > model.roll_limit:
        raise NoSteadyTurnError(
            f"{where} leans {math.degrees(state.roll):.1f} deg, beyond the roll limit"
        )
    for suffix, wheel in (("f", "front"), ("r", "rear")):
        load = loads[f"F_z{suffix}"]
        if load <= 0.0:
            raise NoSteadyTurnError(f"{where} lifts the {wheel} wheel")
        used = math.hypot(loads[f"F_x{suffix}"], loads[f"F_y{suffix}"]) / (friction * load)
        if used > 1.0 - 1e-9:
            raise NoSteadyTurnError(
                f"{where}: the {wheel} tyre saturates (beyond the road's friction mu = "
                f"{friction:g})"
            )


def handling_curve(
    model: TyredModel,
    speed: float,
    *,
    max_lateral_g: float = 0.9,
    step_g: float = 0.05,
    friction: float = 1.0,
) -> list[Trim]:
    """Steady turns at one speed for lateral accelerations step_g, 2 step_g, ... [g].

    The sweep stops at ``max_lateral_g`` or at the first lateral acceleration the tyres
    cannot hold (no steady turn), whichever comes first.

    Parameters
    ----------
    model : TyredModel
        The machine.
    speed : float
        The mass centre's speed [m/s].
    max_lateral_g : float, optional
        The largest lateral acceleration asked for [g], 0.9 by default.
    step_g : float, optional
        The sweep's step [g].
    friction : float, optional
        Road friction coefficient mu.

    Returns
    -------
    list of Trim
        In increasing lateral acceleration (right turns); empty when even the first fails.

    Raises
    ------
    MotosimError
        If the speed, step or bound is out of range.
    """
    check_number(max_lateral_g, where="handling curve: max_lateral_g", lower=0.0, upper=3.0)
    check_number(step_g, where="handling curve: step_g", lower=1e-3, upper=1.0)
    g = _p(model, "g")
    turns: list[Trim] = []
    count = math.floor(max_lateral_g / step_g + 1e-9)
    for k in range(1, count + 1):
        radius = speed**2 / (k * step_g * g)
        try:
            turns.append(steady_turn(model, speed, radius, friction=friction))
        except NoSteadyTurnError:
            break
    return turns
