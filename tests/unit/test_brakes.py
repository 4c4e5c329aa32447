"""The brake controller: braking at the tyres' limit without a lock, a lift or a fall.

Each run brakes the sel2004 machine (Sharp, Evangelou & Limebeer 2004, Magic Formula tyres)
straight from 25 m/s, the compiled ``tyred.step`` at 1 kHz in a Python loop, the multibody
rider steering (throttle closed) and ``brake_torques`` modulating the rider's demand.
"""

import math
from typing import NamedTuple

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.model import tyred
from motosim.model.tyred import Domain, Index, Inputs, State
from motosim.model.tyres import tyre_coefficients, tyre_curves
from motosim.params import load_parameters
from motosim.sim import paths
from motosim.sim.brakes import (
    BrakeSettings,
    BrakeState,
    brake_torques,
    design_brakes,
    new_brake_state,
)
from motosim.sim.multibody_rider import (
    MultibodyRider,
    design_multibody_rider,
    multibody_rider_torque,
)

G = 9.81  # the sel2004 set's gravity [m/s^2]
START = 25.0  # m/s
END = 5.0  # m/s: the run stops there, the rider's lowest design speed
BRAKE_AT = 0.2  # s


class Stop(NamedTuple):
    deceleration: float
    """Mean deceleration from the brakes' start to END [m/s^2]."""
    kappa_f: np.ndarray
    kappa_r: np.ndarray
    F_zr: np.ndarray
    roll: np.ndarray
    domain: Domain


@pytest.fixture(scope="module")
def model() -> tyred.TyredModel:
    return tyred.load_model("sel2004_motorcycle")


@pytest.fixture(scope="module")
def rider(model: tyred.TyredModel) -> MultibodyRider:
    return design_multibody_rider(model, speeds=(5.0, 10.0, 15.0, 20.0, 25.0), leans=(0.0, 10.0))


def brake(
    model: tyred.TyredModel,
    rider: MultibodyRider,
    settings: BrakeSettings,
    *,
    friction: float,
    front: float,
    rear: float,
    ramp: float,
    duration: float = 8.0,
) -> Stop:
    """Brake with the demands ``front``, ``rear`` [N*m] reached over ``ramp`` [s]."""
    route = paths.straight(300.0)
    path = np.vstack([route.x, route.y, route.psi, route.kappa])
    x = np.array(tyred.upright_state(model, START), dtype=float)
    x[Index.roll_rate] = 0.05  # a small disturbance the rider must ride out
    state = new_brake_state()
    k, h = 0, 1e-3
    rows = []
    domain = Domain.INSIDE
    for n in range(round(duration / h)):
        t = n * h
        loads = tyred.observe(model, x, friction)
        braking = t >= BRAKE_AT
        tau, drive, k, _ = multibody_rider_torque(
            rider, x, loads, k, path, route.ds, START, braking
        )
        share = min(max((t - BRAKE_AT) / ramp, 0.0), 1.0)
        f, r = brake_torques(settings, state, x, front * share, rear * share, loads, h)
        if braking:
            rows.append(
                (t, x[Index.forward], loads.kappa_f, loads.kappa_r, loads.F_zr, x[Index.roll])
            )
        inputs = Inputs(
            steer_torque=tau,
            drive_torque=drive,
            front_brake_torque=f,
            rear_brake_torque=r,
            friction=friction,
        )
        x = np.array(tyred.step(model, State(*x), inputs, h), dtype=float)
        domain = tyred.domain(model, State(*x))
        if domain != Domain.INSIDE or x[Index.forward] < END:
            break
    t, v, kappa_f, kappa_r, F_zr, roll = np.array(rows).T
    return Stop((v[0] - v[-1]) / (t[-1] - t[0]), kappa_f, kappa_r, F_zr, roll, domain)


def test_the_slip_target_is_where_the_tyres_give_the_road_s_friction() -> None:
    # the sel2004 tyre set's Magic Formula (motosim.model.tyres), longitudinal slip alone, at
    # the static loads (1153 N front, 1306 N rear at 20 m/s): at the default target the
    # unsaturated force reaches mu F_z at every mu from 0.3 to 1, so that the friction
    # ellipse's mu F_z is the force; on mu = 1 the curve's own peak is further, near
    # kappa = -0.13
    for name, load in (("sel2004_front_120_70_zr17", 1153.0), ("sel2004_rear_180_55_zr17", 1306.0)):
        c = tyre_coefficients(load_parameters(name, "tyre"))
        for mu in (0.3, 0.6, 1.0):
            at_target = tyre_curves(c, load=load, kappa=-0.1, mu=mu).F_x
            assert -at_target >= mu * load
        kappa = np.linspace(-0.5, 0.0, 5001)
        peak = kappa[np.argmin(tyre_curves(c, load=load, kappa=kappa).F_x)]
        assert -0.14 < peak < -0.12


@pytest.mark.parametrize("friction", [1.0, 0.6, 0.3])
def test_braking_at_the_limit_without_a_lock_a_lift_or_a_fall(
    model: tyred.TyredModel, rider: MultibodyRider, friction: float
) -> None:
    # issue 32's target: >= 0.85 mu g; the demand (3000 and 1000 N*m within 0.3 s) would lock
    # both wheels on any of these roads
    run = brake(
        model, rider, design_brakes(model), friction=friction, front=3000.0, rear=1000.0, ramp=0.3
    )
    assert run.domain == Domain.INSIDE
    assert run.deceleration >= 0.85 * friction * G
    assert np.max(np.abs(run.kappa_f)) < 0.5
    assert np.max(np.abs(run.kappa_r)) < 0.5
    assert np.min(run.F_zr) > 0.0
    assert math.degrees(np.max(np.abs(run.roll))) < 5.0


def test_without_the_controller_the_front_wheel_locks(
    model: tyred.TyredModel, rider: MultibodyRider
) -> None:
    # 1000 N*m on the front within 1 s, on mu = 0.3: far beyond r mu F_zf
    demand = {"friction": 0.3, "front": 1000.0, "rear": 0.0, "ramp": 1.0}
    locked = brake(model, rider, design_brakes(model, enabled=False), **demand)
    assert np.min(locked.kappa_f) < -0.9
    held = brake(model, rider, design_brakes(model), **demand)
    assert held.domain == Domain.INSIDE
    assert np.min(held.kappa_f) > -0.5
    # the front wheel alone: at least 0.85 of mu times its static share of the weight (1153 N
    # of 2459 N), the ramp's first second included
    assert held.deceleration >= 0.85 * 0.3 * G * 1153.0 / 2459.0


def test_the_demand_passes_when_the_controller_is_off_or_overridden(
    model: tyred.TyredModel,
) -> None:
    x = np.array(tyred.upright_state(model, 20.0), dtype=float)
    x[Index.front_spin] *= 0.5  # the front wheel at a slip of -0.5
    loads = tyred.observe(model, x, 1.0)
    assert loads.kappa_f < -0.4
    for settings in (
        design_brakes(model, enabled=False),
        design_brakes(model, override_torque=800.0),
    ):
        state = new_brake_state()
        assert brake_torques(settings, state, x, 900.0, 0.0, loads, 1e-3) == (900.0, 0.0)
        assert state[BrakeState.front_brake_torque] == 900.0
    # on, it releases the front (the slip is far beyond the target)
    state = new_brake_state()
    front, _ = brake_torques(design_brakes(model), state, x, 900.0, 0.0, loads, 1e-3)
    assert front == 0.0


@pytest.mark.parametrize(
    ("setting", "value"),
    [
        ("slip_target", 0.7),
        ("slip_target", 0.0),
        ("time_constant", 0.0),
        ("min_rear_load_share", 1.0),
        ("rear_load_band_share", 0.0),
        ("load_lead", -0.1),
        ("min_speed", float("nan")),
        ("override_torque", -1.0),
    ],
)
def test_bad_settings_are_refused_in_one_line(
    model: tyred.TyredModel, setting: str, value: float
) -> None:
    with pytest.raises(MotosimError, match=f"brakes: {setting}"):
        design_brakes(model, **{setting: value})  # type: ignore[arg-type]


def test_braking_in_a_turn_keeps_the_rider_on_its_path(model: tyred.TyredModel) -> None:
    # 20 m/s on a 25 deg (kinematic) turn, then 300 and 100 N*m within 0.5 s: the rider's
    # schedule follows the falling speed down to 10.5 m/s, the lean with it
    rider = design_multibody_rider(model, speeds=(10.0, 15.0, 20.0), leans=(0.0, 15.0, 30.0))
    radius = 20.0**2 / (G * math.tan(math.radians(25.0)))
    route = paths.constant_radius_turn(radius, angle=3.0, start=20.0, transition=25.0, total=400.0)
    path = np.vstack([route.x, route.y, route.psi, route.kappa])
    x = np.array(tyred.upright_state(model, 20.0), dtype=float)
    settings, state = design_brakes(model), new_brake_state()
    k, h, offsets = 0, 1e-3, []
    for n in range(9000):
        t = n * h
        loads = tyred.observe(model, x, 1.0)
        braking = t >= 4.0
        tau, drive, k, e_y = multibody_rider_torque(
            rider, x, loads, k, path, route.ds, 20.0, braking
        )
        share = min(max((t - 4.0) / 0.5, 0.0), 1.0)
        f, r = brake_torques(settings, state, x, 300.0 * share, 100.0 * share, loads, h)
        if braking:
            offsets.append(e_y)
        inputs = Inputs(
            steer_torque=tau,
            drive_torque=drive,
            front_brake_torque=f,
            rear_brake_torque=r,
            friction=1.0,
        )
        x = np.array(tyred.step(model, State(*x), inputs, h), dtype=float)
        assert tyred.domain(model, State(*x)) == Domain.INSIDE
        if x[Index.forward] < 10.5:
            break
    assert x[Index.forward] < 10.5
    assert route.kappa[k] == pytest.approx(1.0 / radius)  # still in the turn
    assert np.max(np.abs(offsets)) < 0.3
