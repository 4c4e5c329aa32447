"""The multibody motorcycle on tyres against Sharp (1971) and hand statics.

With Sharp's standard machine (``sharp_machine``: his bodies, his linear relaxing tyres with
his cornering and camber stiffnesses at the static loads, his steering damper, knife-edge
wheels) the tyred multibody model linearised about upright straight running must have
Sharp's weave and wobble: ``motosim.model.sharp`` is the reference (itself checked against
Sharp's Tables 1-3). The terms that differ: the tyres' radial compliance (the machine sits
about 9 mm lower on its tyres, the contact points are below the wheels' undeformed lowest
points, and the front load is the geometry's, 1005.7 N, against Sharp's tabulated 1005.3 N);
the exact kinematics of the multibody model where Sharp keeps first-order terms. The
differences are below 1 % of each eigenvalue's modulus; 2 % is the requirement.
"""

import dataclasses
import math

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.model import sharp as sharp_model
from motosim.model import tyred
from motosim.params import MultibodyParameters, SharpParameters, load_parameters


@pytest.fixture(scope="module")
def machine() -> tuple[SharpParameters, MultibodyParameters, tyred.TyredModel]:
    sharp = load_parameters("sharp1971", "sharp")
    params, rear, front, damper = tyred.sharp_machine(sharp)
    return sharp, params, tyred.make_model(params, rear, front, steer_damping=damper)


def _oscillatory(A: np.ndarray) -> list[complex]:
    ev = np.linalg.eigvals(A)
    return sorted((complex(e) for e in ev if e.imag > 1e-6), key=lambda e: e.imag)


@pytest.mark.parametrize("speed", [10.0, 20.0, 30.0, 40.0, 50.0])
def test_weave_and_wobble_match_sharp_1971(machine: tuple, speed: float) -> None:
    sharp, _, model = machine
    table = sharp_model.modes(sharp, [speed])
    osc = _oscillatory(tyred.lateral_matrix(model, speed))
    for name, reference in (("weave", table.weave[0]), ("wobble", table.wobble[0])):
        got = min(osc, key=lambda e, r=reference: abs(e - r))
        assert abs(got - reference) < 0.02 * abs(reference), (name, got, reference)
        assert abs(got.real - reference.real) < 0.05, (name, got, reference)


def test_upright_running_is_an_equilibrium_with_the_static_loads(machine: tuple) -> None:
    _, params, model = machine
    state = tyred.upright_state(model, 20.0)
    rates = np.array(tyred.derivatives(model, state, tyred.Inputs()))
    np.testing.assert_allclose(rates[9:], 0.0, atol=1e-9)  # no acceleration, no tyre lag
    loads = tyred.contact_loads(model, state, tyred.Inputs())
    x_G, _ = params.mass_centre
    weight = params.mass * params.g
    # statics of the rigid geometry: the loads share the weight by the mass centre's position
    assert loads["F_zf"] == pytest.approx(weight * x_G / params.w, rel=1e-3)
    assert loads["F_zr"] == pytest.approx(weight * (params.w - x_G) / params.w, rel=1e-3)
    assert loads["F_zf"] + loads["F_zr"] == pytest.approx(weight, rel=1e-12)
    assert tyred.domain(model, state) is tyred.Domain.INSIDE


def test_braking_transfers_load_forward_and_pitches_nose_down(machine: tuple) -> None:
    """Steady braking: the load moves to the front by (m h + I_Ryy/r_R + I_Fyy/r_F) a / w,
    the rigid-body moment balance about the mass centre (m a h / w and the wheels' spin
    momentum, 4 % here); the tyres' compliance changes it by less than 2 %."""
    _, params, model = machine
    state = tyred.upright_state(model, 20.0)
    static = tyred.contact_loads(model, state, tyred.Inputs())
    braking = tyred.Inputs(front_brake_torque=400.0, rear_brake_torque=150.0)
    for _ in range(1000):  # 1 s at 1 kHz: the pitch transient has settled
        state = tyred.step(model, state, braking, 1e-3)
    loads = tyred.contact_loads(model, state, braking)
    deceleration = -tyred.derivatives(model, state, braking).forward
    _, z_G = params.mass_centre
    arm = params.mass * -z_G + params.I_Ryy / params.r_R + params.I_Fyy / params.r_F
    transfer = loads["F_zf"] - static["F_zf"]
    assert deceleration > 0.6 * params.g
    assert transfer == pytest.approx(arm * deceleration / params.w, rel=0.02)
    assert loads["F_zr"] == pytest.approx(static["F_zr"] - transfer, rel=0.01)
    assert state.pitch < tyred.upright_state(model, 20.0).pitch - 1e-3  # nose down
    assert loads["kappa_f"] < 0.0 and loads["kappa_r"] < 0.0


def test_domain_names_why_a_state_is_outside(machine: tuple) -> None:
    _, _, model = machine
    state = tyred.upright_state(model, 10.0)
    assert tyred.domain(model, state._replace(roll=1.4)) is tyred.Domain.FALLEN
    assert tyred.domain(model, state._replace(z=state.z - 0.1)) is tyred.Domain.REAR_LIFTED
    assert tyred.domain(model, state._replace(pitch=state.pitch + 0.1)) is tyred.Domain.FRONT_LIFTED
    assert tyred.domain(model, state._replace(steer=math.nan)) is tyred.Domain.NOT_FINITE


def test_friction_ellipse_limits_the_tyre_force() -> None:
    tyre = tyred.LinearTyre(12.0, 1.0, 20.0, 0.2, 1.5e5, 1e3).as_array()
    kin = np.array([0.0, 0.0, 0.01, 0.0, 5.0, -3.0, 20.0, 0.0])  # skidding: kappa = -0.25
    fx, fy, fz, _, kappa, _ = tyred.linear_tyre_forces(tyre, kin, 800.0, 0.8)
    assert fz == pytest.approx(1500.0)
    assert kappa == pytest.approx(-0.25)
    assert math.hypot(fx, fy) == pytest.approx(0.8 * fz)
    assert fx < 0.0 and fy > 0.0


@pytest.mark.parametrize("crowns", [(0.0, 0.0), (0.08, 0.06)])
def test_contact_jacobian_is_the_contact_velocity(
    machine: tuple, crowns: tuple[float, float]
) -> None:
    """J u is the material contact point's velocity (so J^T F is the force's generalised
    force, by virtual power), and its downward part the depth's rate (the torus's lowest
    point), in a general state: leaning, steered, pitching, sliding; knife edges and tori."""
    from motosim.model import _generated_tyred as gen

    _, params, _ = machine
    params = dataclasses.replace(params, t_R=crowns[0], t_F=crowns[1])
    tyre = tyred.LinearTyre(12.0, 1.0, 20.0, 0.2, 1.5e5, 1e3)
    model = tyred.make_model(params, tyre, tyre)
    rng = np.random.default_rng(7)
    q = np.array([1.0, -2.0, -0.29, 0.3, 0.4, params.lam + 0.02, 1.0, 0.3, 2.0])
    u = rng.normal(size=9)
    u[0] = 15.0
    kr, kf, Jr, Jf = gen.contacts(model.p, q, u)
    for kin, J in ((kr, Jr), (kf, Jf)):
        velocity = J @ u
        assert velocity[0] == pytest.approx(kin[4], abs=1e-12)
        assert velocity[1] == pytest.approx(kin[5], abs=1e-12)
        assert velocity[2] == pytest.approx(kin[3], abs=1e-12)


def test_a_torus_contact_moves_sideways_with_camber(machine: tuple) -> None:
    """Leaning a torus (crown radius t) right by gamma puts its lowest point (r - t) sin(gamma)
    to the left of the wheel centre and (r - t) cos(gamma) + t below it: t sin(gamma) towards
    the lean from a knife edge's contact."""
    from motosim.model import _generated_tyred as gen

    _, params, _ = machine
    roll = 0.5
    for crown in (0.0, 0.08):
        torus = dataclasses.replace(params, t_R=crown)
        tyre = tyred.LinearTyre(12.0, 1.0, 20.0, 0.2, 1.5e5, 1e3)
        model = tyred.make_model(torus, tyre, tyre)
        q = np.zeros(9)
        q[4], q[5] = roll, params.lam
        kr, _, _, _ = gen.contacts(model.p, q, np.zeros(9))
        assert kr[1] == pytest.approx(-(params.r_R - crown) * math.sin(roll), abs=1e-12)
        assert kr[2] == pytest.approx(crown + (params.r_R - crown) * math.cos(roll), abs=1e-12)
        assert math.asin(kr[7]) == pytest.approx(roll)


@pytest.mark.parametrize(
    ("inputs", "match"),
    [
        (tyred.Inputs(front_brake_torque=-1.0), "front_brake_torque"),
        (tyred.Inputs(friction=0.0), "friction"),
        (tyred.Inputs(steer_torque=math.nan), "steer_torque"),
    ],
)
def test_bad_inputs_are_refused_at_the_edge(inputs: tyred.Inputs, match: str) -> None:
    from motosim.errors import MotosimError

    with pytest.raises(MotosimError, match=match):
        tyred.validate_inputs(inputs)
    assert tyred.validate_inputs(tyred.Inputs(rear_brake_torque=100.0, friction=0.4))


def test_a_bad_speed_is_refused_in_one_line(machine: tuple) -> None:
    from motosim.errors import MotosimError

    _, _, model = machine
    with pytest.raises(MotosimError, match="speed"):
        tyred.upright_state(model, math.inf)


# Sharp's lateral state order from the tyred model's LATERAL order (roll, steer, lateral,
# yaw rate, roll rate, steer rate, F_y rear, F_y front)
_TO_SHARP = [2, 3, 4, 5, 0, 1, 6, 7]


@pytest.mark.parametrize("speed", [10.0, 30.0])
def test_the_arms_on_the_front_frame_are_sharps_held_steering(machine: tuple, speed: float) -> None:
    """tyred.held adds the arms' inertia to the mass matrix's steer entry and their damping
    to the steering damper; sharp.held_steering eliminates the same torque from the steer
    equation (Sherman-Morrison). Both linearisations agree, and the held machine's weave
    and wobble match Sharp 1971's held model as the bare ones do (arms of 0.05 kg*m^2 and
    2 N*m*s/rad, within the grips' range of motosim.sim.grips)."""
    sharp, _, model = machine
    inertia, damping = 0.05, 2.0
    A, B = tyred.lateral_system(model, speed)
    A, B = A[np.ix_(_TO_SHARP, _TO_SHARP)], B[_TO_SHARP]
    A_h, B_h, _ = sharp_model.held_steering(A, B, inertia, damping, 0.0)
    A_t, B_t = tyred.lateral_system(tyred.held(model, inertia, damping), speed)
    A_t, B_t = A_t[np.ix_(_TO_SHARP, _TO_SHARP)], B_t[_TO_SHARP]
    scale = np.max(np.abs(A_h))
    np.testing.assert_allclose(A_t, A_h, rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(B_t, B_h, rtol=0, atol=1e-6 * np.max(np.abs(B_h)))
    bare = _oscillatory(A)
    held = _oscillatory(A_t)
    lin = sharp_model.linearize(sharp, speed)
    reference = _oscillatory(
        sharp_model.held_steering(lin.A, lin.B[:, 0], inertia, damping, 0.0)[0]
    )
    wobble = max(held, key=lambda e: e.imag)
    assert abs(wobble - max(reference, key=lambda e: e.imag)) < 0.02 * abs(wobble)
    # the arms' inertia lowers the wobble's frequency, their damping damps it
    assert wobble.imag < max(bare, key=lambda e: e.imag).imag
    assert wobble.real < max(bare, key=lambda e: e.imag).real


def test_held_refuses_negative_arms(machine: tuple) -> None:
    with pytest.raises(MotosimError, match=r"held: inertia = -0\.1"):
        tyred.held(machine[2], -0.1, 0.0)
