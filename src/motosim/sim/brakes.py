"""The virtual rider's brake controller: each wheel held at a slip target, the rear on the ground.

The rider's demand (front and rear brake torques, profiles of a scenario) is what a rider
squeezes; the controller, an anti-lock system, passes it unless a wheel's longitudinal slip
would pass the target or the rear wheel would lift, and then applies the torque that holds
the slip at the target. It works per wheel on the wheel's spin equation (Savaresi & Tanelli
2010, ch. 2; Corno, Savaresi, Tanelli & Fabbri 2008 for the motorcycle),

    I omega' = r |F_x| - T_b,        kappa = (r omega - u) / u,

so that, the vehicle's deceleration aside, the braking slip s = -kappa changes as
s' = r (T_b - r |F_x|) / (I u). The torque

    T_slip = r |F_x| + I u (s* - s) / (r tau) + T_i,   T_i' = I u (s* - s) / (r tau tau_i)

(the tyre's torque on the wheel, measured in the simulator where an ABS estimates it from the
wheel's deceleration, plus a correction) therefore brings the slip to its target s* with the
time constant tau, before, at and beyond the tyre's peak alike: a feedback linearisation of
the wheel. The integral T_i, over tau_i = 5 tau, takes up what the lever r misses (the loaded
tyre's rolling radius is shorter than the axle height r), which the proportional term alone
would leave as a slip error growing as 1 / u while the machine slows; it integrates only
while the slip torque is the one applied, within +-r |F_x|. The front torque also keeps the
rear wheel on the ground: braking moves load to
the front in proportion to the deceleration, h / w per unit braking force (Cossalter 2006,
*Motorcycle Dynamics*, ch. 7), and on the tyres' stiff, lightly damped radial springs the
machine's pitch overshoots that share when the force rises quickly. The rear load is therefore
read a lead time ahead from its rate, F_zr + t_lead F_zr', and as it falls into a band above
its floor F_zr,min the front torque is cut to

    T_lift = r_f |F_xf| m,        m = (F_zr + t_lead F_zr' - F_zr,min) / band in [0, 1),

below the tyre's torque, so that the wheel spins up, its slip falls off the tyre's plateau and
the front force, with the load transfer, drops within milliseconds (as an ABS dumps pressure).
The applied torque is the least of the demand, T_slip and (at the front) T_lift, never below
0, rising at most at the brakes' rate; the controller acts above a speed (the slips lose their
meaning at a standstill, where the demand holds the machine).

The target's default, s* = 0.1, is where the Magic Formula motorcycle tyres of the
``sel2004`` set give the road's full friction mu F_z within the friction ellipse at every
mu from 0.3 to 1 (their unsaturated peak is near kappa = -0.13 at mu = 1, scaled by mu below:
:func:`motosim.model.tyres.tyre_curves`), and where a locked wheel's force, and above all its
side force, is not yet lost.

Without the controller (``enabled`` false, or a demand at or beyond ``override_torque``) the
torques pass as demanded, so that a front-wheel lock ending in a fall can be scripted.

References
----------
Savaresi, S. M., Tanelli, M. (2010). *Active Braking Control Systems Design for Vehicles*.
Springer.
Corno, M., Savaresi, S. M., Tanelli, M., Fabbri, L. (2008). On optimal motorcycle braking.
*Control Engineering Practice* 16(6), 644-657.
Cossalter, V. (2006). *Motorcycle Dynamics*, 2nd ed. Lulu.
"""

import math
from enum import IntEnum
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from motosim.model import _generated_tyred as gen
from motosim.model.tyred import ContactLoads, Index, TyredModel
from motosim.params.checks import check_number

__all__ = ["BrakeSettings", "BrakeState", "brake_torques", "design_brakes", "new_brake_state"]

Array = NDArray[np.float64]


class BrakeState(IntEnum):
    """Position of each value of the controller's state array (what it applied last)."""

    front_brake_torque = 0
    rear_brake_torque = 1
    F_zr = 2
    """The rear normal load of the last period [N], for its rate."""
    front_slip_integral = 3
    """The integral term of the front wheel's slip torque [N*m]."""
    rear_slip_integral = 4
    """The rear wheel's [N*m]."""


class BrakeSettings(NamedTuple):
    """The brake controller's constants (build them with :func:`design_brakes`)."""

    enabled: bool
    """Whether the controller modulates (else the torques pass as demanded)."""
    slip_target: float
    """The braking slip s* = -kappa held [1], > 0."""
    time_constant: float
    """How fast the slip is brought to the target [s]."""
    radius_front: float
    """The front wheel's rolling radius, axle height upright [m]."""
    radius_rear: float
    inertia_front: float
    """The front wheel's spin inertia [kg*m^2]."""
    inertia_rear: float
    min_rear_load: float
    """The rear normal load's floor [N]."""
    rear_load_band: float
    """The rear load above the floor over which the front's slip target grows from 0 to
    ``slip_target`` [N]."""
    load_lead: float
    """How far ahead the rear load is extrapolated from its rate [s]."""
    min_speed: float
    """Below this forward speed the demand passes [m/s]."""
    override_torque: float
    """A demand at or beyond this passes as demanded [N*m]."""
    rise_rate: float
    """The fastest an applied torque rises [N*m/s]."""


def design_brakes(
    model: TyredModel,
    *,
    enabled: bool = True,
    slip_target: float = 0.1,
    time_constant: float = 0.02,
    min_rear_load_share: float = 0.05,
    rear_load_band_share: float = 0.15,
    load_lead: float = 0.05,
    min_speed: float = 2.0,
    override_torque: float = math.inf,
    rise_rate: float = 1e5,
) -> BrakeSettings:
    """The brake controller for the tyred motorcycle ``model``.

    Parameters
    ----------
    model : TyredModel
        The machine (its wheels' radii, crown radii and spin inertias, its static loads).
    enabled : bool, optional
        Whether the controller modulates the demand.
    slip_target : float, optional
        The braking slip held, -kappa [1], in (0, 0.5).
    time_constant : float, optional
        The slip loop's time constant [s], 1 ms to 1 s.
    min_rear_load_share : float, optional
        The rear load's floor as a share of its static load [1], in [0, 1).
    rear_load_band_share : float, optional
        The band of rear load over which the front's slip target grows from 0 at the floor
        to ``slip_target``, as a share of the static rear load [1], in (0, 1].
    load_lead : float, optional
        How far ahead the rear load is extrapolated from its rate [s], 0 to 0.5.
    min_speed : float, optional
        The forward speed below which the demand passes [m/s], 0.5 to 20.
    override_torque : float, optional
        A demand at or beyond this passes unmodulated [N*m] (never, by default).
    rise_rate : float, optional
        The fastest an applied torque rises [N*m/s].

    Returns
    -------
    BrakeSettings

    Raises
    ------
    MotosimError
        Naming the first setting out of its range.

    Examples
    --------
    >>> from motosim.model.tyred import load_model
    >>> settings = design_brakes(load_model("sel2004_motorcycle"))
    >>> settings.slip_target, round(settings.min_rear_load)  # 5 % of the static rear load [N]
    (0.1, 65)
    """
    check_number(
        slip_target,
        where="brakes: slip_target",
        lower=0.0,
        upper=0.5,
        lower_closed=False,
        upper_closed=False,
    )
    check_number(time_constant, where="brakes: time_constant", lower=1e-3, upper=1.0, unit="s")
    check_number(
        min_rear_load_share,
        where="brakes: min_rear_load_share",
        lower=0.0,
        upper=1.0,
        upper_closed=False,
    )
    check_number(
        rear_load_band_share,
        where="brakes: rear_load_band_share",
        lower=0.0,
        upper=1.0,
        lower_closed=False,
    )
    check_number(load_lead, where="brakes: load_lead", lower=0.0, upper=0.5, unit="s")
    check_number(min_speed, where="brakes: min_speed", lower=0.5, upper=20.0, unit="m/s")
    if override_torque != math.inf:
        check_number(
            override_torque,
            where="brakes: override_torque",
            lower=0.0,
            lower_closed=False,
            unit="N*m",
        )
    check_number(
        rise_rate, where="brakes: rise_rate", lower=0.0, lower_closed=False, upper=1e9, unit="N*m/s"
    )
    from motosim.model.tyred import observe, upright_state

    p = dict(zip(gen.PARAMETERS, (float(v) for v in model.p), strict=True))
    static_rear = observe(model, np.array(upright_state(model, 1.0), dtype=float), 1.0).F_zr
    return BrakeSettings(
        enabled=bool(enabled),
        slip_target=float(slip_target),
        time_constant=float(time_constant),
        radius_front=float(p["rF"] + p["tF"]),
        radius_rear=float(p["rR"] + p["tR"]),
        inertia_front=float(model.spin_inertia[1]),
        inertia_rear=float(model.spin_inertia[0]),
        min_rear_load=float(min_rear_load_share * static_rear),
        rear_load_band=float(rear_load_band_share * static_rear),
        load_lead=float(load_lead),
        min_speed=float(min_speed),
        override_torque=float(override_torque),
        rise_rate=float(rise_rate),
    )


def new_brake_state() -> Array:
    """The controller's state at the start: nothing applied (:class:`BrakeState`)."""
    return np.zeros(len(BrakeState))


_INTEGRAL_TIME = 5.0
"""tau_i / tau, the slip torque's integral time per its time constant."""


@njit(cache=True)
def _wheel(
    demand: float,
    applied: float,
    integral: float,
    slip: float,
    force: float,
    speed: float,
    radius: float,
    inertia: float,
    target: float,
    settings: BrakeSettings,
    dt: float,
) -> tuple[float, float]:
    """One wheel's torque, the least of the demand and T_slip, rate-limited [N*m], and the
    slip torque's integral term after this period [N*m]."""
    torque = demand
    if speed >= settings.min_speed:
        correction = inertia * speed * (target - slip) / (radius * settings.time_constant)
        lever = radius * max(force, 0.0)
        held = lever + correction + integral
        if held < demand:
            step = correction * dt / (_INTEGRAL_TIME * settings.time_constant)
            integral = min(max(integral + step, -lever), lever)
        torque = min(torque, held)
    else:
        integral = 0.0
    return _rise(max(torque, 0.0), applied, settings, dt), integral


@njit(cache=True)
def _rise(torque: float, applied: float, settings: BrakeSettings, dt: float) -> float:
    return min(torque, applied + settings.rise_rate * dt)


@njit(cache=True)
def brake_torques(
    settings: BrakeSettings,
    state: Array,
    x: Array,
    demand_front: float,
    demand_rear: float,
    loads: ContactLoads,
    dt: float,
) -> tuple[float, float]:
    """The brake torques to apply this period (compiled; ``state`` updated in place).

    Parameters
    ----------
    settings : BrakeSettings
        The controller.
    state : ndarray, shape (2,)
        What it applied last period (:class:`BrakeState`), from :func:`new_brake_state`.
    x : ndarray, shape (20,)
        The tyred model's compiled state (its forward speed is read).
    demand_front, demand_rear : float
        The rider's demands [N*m], >= 0.
    loads : ContactLoads
        The contacts of ``x`` (:func:`motosim.model.tyred.observe`): slips, longitudinal
        forces, the rear normal load.
    dt : float
        The period [s].

    Returns
    -------
    front, rear : float
        The torques for :class:`motosim.model.tyred.Inputs` [N*m], >= 0.
    """
    demand_front = max(demand_front, 0.0)
    demand_rear = max(demand_rear, 0.0)
    applied_front = state[BrakeState.front_brake_torque]
    applied_rear = state[BrakeState.rear_brake_torque]
    if not settings.enabled:
        front, rear = demand_front, demand_rear
    else:
        speed = x[Index.forward]
        front = demand_front
        if demand_front < settings.override_torque:
            front, state[BrakeState.front_slip_integral] = _wheel(
                demand_front,
                applied_front,
                state[BrakeState.front_slip_integral],
                -loads.kappa_f,
                -loads.F_xf,
                speed,
                settings.radius_front,
                settings.inertia_front,
                settings.slip_target,
                settings,
                dt,
            )
            # the rear load a lead time ahead, from its rate
            last = state[BrakeState.F_zr]
            rate = (loads.F_zr - last) / dt if last > 0.0 else 0.0
            ahead = loads.F_zr + settings.load_lead * rate
            margin = (ahead - settings.min_rear_load) / settings.rear_load_band
            if margin < 1.0:
                lift = settings.radius_front * max(-loads.F_xf, 0.0) * max(margin, 0.0)
                front = min(front, lift)
        rear = demand_rear
        if demand_rear < settings.override_torque:
            rear, state[BrakeState.rear_slip_integral] = _wheel(
                demand_rear,
                applied_rear,
                state[BrakeState.rear_slip_integral],
                -loads.kappa_r,
                -loads.F_xr,
                speed,
                settings.radius_rear,
                settings.inertia_rear,
                settings.slip_target,
                settings,
                dt,
            )
    state[BrakeState.F_zr] = loads.F_zr
    state[BrakeState.front_brake_torque] = front
    state[BrakeState.rear_brake_torque] = rear
    return front, rear
