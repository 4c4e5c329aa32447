"""Steady turns of the tyred multibody motorcycle against the toroidal-tyre kinematics.

Reference: Cossalter, V. (2006). *Motorcycle Dynamics*, 2nd ed., Lulu, chapter 4 (steady
turning, the effect of the tyres' thickness): a machine whose wheels are tori of crown radius
t, its mass centre at height h, turning at speed v on a radius R, rolls by

    phi = phi_k + asin(t sin(phi_k) / (h - t)),    phi_k = atan(v^2 / (g R)),

when the only moments are gravity's and the centrifugal force's (no gyroscopic moment of the
spinning wheels, no steering terms). The multibody model adds those: the wheels' spin
momentum precessing at the yaw rate asks for more roll, and the steered front frame shifts the
mass. The tests check that the trimmed roll is within 2 deg of the formula on the
Sharp-Evangelou-Limebeer (2004) GSX-R1000 at 20 m/s on a 50 m radius, and that the difference
vanishes as the spin inertias and the crown radii go to zero; the equilibrium itself (every
acceleration zero, the horizontal forces m v^2 / R) is checked at the same turns.
"""

import dataclasses
import math

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.model import trim, tyred
from motosim.params import load_parameter_set, load_parameters


def _cossalter(model: tyred.TyredModel, speed: float, radius: float) -> float:
    """Cossalter's roll [rad], t the crown radii weighted by the static load shares."""
    upright = tyred.upright_state(model, speed)
    loads = tyred.contact_loads(model, upright, tyred.Inputs())
    p = dict(zip(trim.gen.PARAMETERS, model.p, strict=True))
    share_f = loads["F_zf"] / (loads["F_zf"] + loads["F_zr"])
    t = p["tF"] * share_f + p["tR"] * (1 - share_f)
    h = -(upright.z + trim.mass_centre(model, upright)[2])
    phi_k = math.atan(speed**2 / (p["g"] * radius))
    return phi_k + math.asin(t * math.sin(phi_k) / (h - t))


@pytest.fixture(scope="module")
def sel2004() -> tyred.TyredModel:
    return tyred.load_model("sel2004_motorcycle")


def _thin(spin: float, crown: float) -> tyred.TyredModel:
    """The GSX-R1000 on its MF tyres, its wheels' spin inertias and crown radii scaled."""
    pset = load_parameter_set("sel2004_motorcycle")
    params = dataclasses.replace(
        pset.values,
        I_Ryy=pset.values.I_Ryy * spin,
        I_Fyy=pset.values.I_Fyy * spin,
        t_R=pset.values.t_R * crown,
        t_F=pset.values.t_F * crown,
    )
    rear = load_parameters(pset.tyres["rear_tyre"], "tyre")
    front = load_parameters(pset.tyres["front_tyre"], "tyre")
    return tyred.make_model(params, rear, front)


def _assert_equilibrium(model: tyred.TyredModel, turn: trim.Trim) -> None:
    inputs = tyred.Inputs(steer_torque=turn.tau_r, drive_torque=turn.drive_torque)
    rates = tyred.derivatives(model, turn.state, inputs)
    accelerations = np.array(rates[9:18])
    assert np.max(np.abs(accelerations)) < 1e-8, accelerations
    weight = turn.F_zf + turn.F_zr
    assert abs(rates.Fy_r) < 1e-8 * weight * turn.speed
    assert abs(rates.Fy_f) < 1e-8 * weight * turn.speed
    # Newton in the horizontal plane: the tyres' forces are the mass centre's m v^2 / R
    loads = tyred.contact_loads(model, turn.state, inputs)
    force = trim.horizontal_tyre_force(model, turn.state, loads)
    mass = weight / float(model.p[trim.gen.PARAMETERS.index("g")])
    assert float(np.hypot(*force)) == pytest.approx(mass * turn.speed**2 / turn.radius, rel=1e-6)


def test_roll_within_two_degrees_of_cossalter_at_20_m_s_on_50_m(
    sel2004: tyred.TyredModel,
) -> None:
    turn = trim.steady_turn(sel2004, 20.0, 50.0)
    _assert_equilibrium(sel2004, turn)
    reference = _cossalter(sel2004, 20.0, 50.0)
    assert turn.phi > reference  # the wheels' spin momentum asks for more roll
    assert abs(turn.phi - reference) < math.radians(2.0)
    assert turn.phi_kinematic == pytest.approx(math.atan(400.0 / (9.81 * 50.0)), rel=1e-12)


def test_difference_shrinks_with_the_gyroscopic_terms_and_the_crowns() -> None:
    """The roll tends to the kinematic roll as the spin inertias and crown radii vanish.

    On the GSX-R1000 at 20 m/s on 50 m the wheels' spin momentum adds about 1.1 deg of roll
    over the formula; without it (spin inertias x 1e-3) and on thin tyres (crowns x 1e-6) the
    roll is within 0.2 deg of atan(v^2 / (g R)): what remains is the steered front frame's
    mass offset and the frames' own inertia in yaw (the steering terms).
    """
    full = _thin(1.0, 1.0)
    turn = trim.steady_turn(full, 20.0, 50.0)
    gyroscopic = turn.phi - _cossalter(full, 20.0, 50.0)
    assert gyroscopic > math.radians(0.5)
    bare = _thin(1e-3, 1e-6)
    turn = trim.steady_turn(bare, 20.0, 50.0)
    assert abs(turn.phi - turn.phi_kinematic) < math.radians(0.2)
    assert abs(turn.phi - turn.phi_kinematic) < 0.2 * gyroscopic
    thin = _thin(1.0, 1e-6)  # knife edges, spinning wheels: only the gyroscopic roll is left
    turn = trim.steady_turn(thin, 20.0, 50.0)
    assert turn.phi - turn.phi_kinematic > math.radians(0.5)


def test_difference_shrinks_with_speed_at_the_same_lateral_acceleration(
    sel2004: tyred.TyredModel,
) -> None:
    """At 0.6 g the gyroscopic roll moment grows with the spin rate and the yaw rate (~ v^0)
    times the spin (~ v): slower turns are closer to the kinematics."""
    differences = []
    for speed in (10.0, 20.0, 30.0):
        radius = speed**2 / (0.6 * 9.81)
        turn = trim.steady_turn(sel2004, speed, radius)
        _assert_equilibrium(sel2004, turn)
        differences.append(turn.phi - _cossalter(sel2004, speed, radius))
    assert 0.0 < differences[0] < differences[1] < differences[2]


def test_left_turn_mirrors_right_turn(sel2004: tyred.TyredModel) -> None:
    """Mirror images, up to the MF-MC's combined slip: its weighting of the side force by the
    longitudinal slip, B_yk = r_By1 cos(atan(r_By2 (tan(alpha) - r_By3))) with r_By3 = -0.059
    in Evangelou's fit, is not even in sideslip, so with the drive's slip the small steer
    angle differs slightly between the two directions; the linear tyres mirror exactly."""
    right = trim.steady_turn(sel2004, 20.0, 80.0)
    left = trim.steady_turn(sel2004, 20.0, -80.0)
    assert left.phi == pytest.approx(-right.phi, rel=1e-5)
    assert left.delta == pytest.approx(-right.delta, rel=1e-2)
    assert left.tau_r == pytest.approx(-right.tau_r, rel=1e-2)
    assert left.F_zf == pytest.approx(right.F_zf, rel=1e-5)
    linear = tyred.load_model("sel2004_motorcycle", tyres="linear")
    right = trim.steady_turn(linear, 20.0, 80.0)
    left = trim.steady_turn(linear, 20.0, -80.0)
    assert left.phi == pytest.approx(-right.phi, rel=1e-7)
    assert left.delta == pytest.approx(-right.delta, rel=1e-6)
    assert left.tau_r == pytest.approx(-right.tau_r, rel=1e-6)


def test_sharp_machine_turn_is_an_equilibrium() -> None:
    model = tyred.load_model("sharp1971")
    turn = trim.steady_turn(model, 20.0, 100.0)
    _assert_equilibrium(model, turn)
    # knife-edge wheels: only the gyroscopic and steering terms separate it from phi_k
    assert turn.phi > turn.phi_kinematic
    assert turn.phi - turn.phi_kinematic < math.radians(1.5)


def test_beyond_the_friction_has_no_steady_turn(sel2004: tyred.TyredModel) -> None:
    with pytest.raises(trim.NoSteadyTurnError, match="beyond the road's friction"):
        trim.steady_turn(sel2004, 20.0, 40.0)
    with pytest.raises(trim.NoSteadyTurnError):
        trim.steady_turn(sel2004, 20.0, 50.0, friction=0.6)


@pytest.mark.parametrize(
    ("speed", "radius", "match"),
    [
        (0.5, 50.0, "speed"),
        (math.nan, 50.0, "speed"),
        (20.0, 1.0, "radius"),
        (20.0, math.inf, "radius"),
    ],
)
def test_bad_input_names_the_value(
    sel2004: tyred.TyredModel, speed: float, radius: float, match: str
) -> None:
    with pytest.raises(MotosimError, match=match):
        trim.steady_turn(sel2004, speed, radius)


def test_linearised_tyre_matches_the_magic_formula_at_zero_slip() -> None:
    from motosim.model import tyres

    tyre = load_parameters("sel2004_front_120_70_zr17", "tyre")
    linear = tyred.linearised_tyre(tyre, 1100.0, 20.0)
    c = tyres.tyre_coefficients(tyre)
    d = 1e-6
    F_plus = tyres.steady_forces(c, 1100.0, 0.0, d, 0.0, 1.0)[1]
    F_minus = tyres.steady_forces(c, 1100.0, 0.0, -d, 0.0, 1.0)[1]
    assert linear.cornering * 1100.0 == pytest.approx((F_plus - F_minus) / (2 * d), rel=1e-6)
