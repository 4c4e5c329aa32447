"""The tyred multibody model on the Magic Formula tyres of its parameter set.

The GSX-R1000 of Sharp, Evangelou & Limebeer (2004) (``sel2004_motorcycle``) on its MF-MC
tyres (``sel2004_front_120_70_zr17``, ``sel2004_rear_180_55_zr17``, Evangelou 2004, ch. 9).
References: the statics of the rigid geometry for the upright loads, and the tyre sets' own
cornering and camber stiffnesses (``motosim.model.tyres``, itself checked against Evangelou's
tables in ``tests/reference/tyres``) for the forces the model's tyre function gives at a
contact: the wiring of loads, slips and camber from the contact kinematics into the MF.
"""

import math

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.model import tyred, tyres
from motosim.params import load_parameter_set, load_parameters


@pytest.fixture(scope="module")
def model() -> tyred.TyredModel:
    return tyred.load_model("sel2004_motorcycle")


def test_upright_running_is_an_equilibrium_with_the_static_loads(
    model: tyred.TyredModel,
) -> None:
    params = load_parameter_set("sel2004_motorcycle").values
    assert model.magic
    state = tyred.upright_state(model, 20.0)
    rates = np.array(tyred.derivatives(model, state, tyred.Inputs()))
    np.testing.assert_allclose(rates[9:], 0.0, atol=1e-9)
    loads = tyred.contact_loads(model, state, tyred.Inputs())
    x_G, _ = params.mass_centre
    weight = params.mass * params.g
    assert loads["F_zf"] == pytest.approx(weight * x_G / params.w, rel=2e-3)
    assert loads["F_zf"] + loads["F_zr"] == pytest.approx(weight, rel=1e-12)
    for key in ("F_xf", "F_yf", "M_zf", "M_xf", "F_xr", "F_yr", "M_zr", "M_xr"):
        assert abs(loads[key]) < 1e-9, key


def _kinematics(load: float, k_z: float, lateral: float, camber: float) -> np.ndarray:
    """A contact rolling at 20 m/s without longitudinal slip, ``lateral`` [m/s] sideways."""
    return np.array([0.0, 0.0, load / k_z, 0.0, 0.0, lateral, 20.0, math.sin(camber)])


@pytest.mark.parametrize("name", ["sel2004_front_120_70_zr17", "sel2004_rear_180_55_zr17"])
def test_cornering_and_camber_stiffness_at_zero_slip_are_the_tyre_sets(name: str) -> None:
    tyre = load_parameters(name, "tyre")
    c = tyres.tyre_coefficients(tyre)
    load = tyre.F_z0
    d = 1e-6
    steady = [
        tyred.magic_tyre_forces(c, _kinematics(load, tyre.k_z, v, 0.0), 0.0, 1.0)[3]
        for v in (-20.0 * d, 20.0 * d)  # alpha = atan(-v_y / v) = -/+ d
    ]
    per_alpha = (steady[0] - steady[1]) / (2 * d)
    assert per_alpha == pytest.approx(tyres.cornering_stiffness(c, load, 0.0), rel=1e-6)
    cambered = [
        tyred.magic_tyre_forces(c, _kinematics(load, tyre.k_z, 0.0, g), 0.0, 1.0)[3]
        for g in (-d, d)
    ]
    per_gamma = (cambered[1] - cambered[0]) / (2 * d)
    assert per_gamma == pytest.approx(tyres.camber_stiffness(c, load), rel=1e-6)
    forces = tyred.magic_tyre_forces(c, _kinematics(load, tyre.k_z, 0.0, 0.0), 0.0, 1.0)
    assert forces[2] == pytest.approx(load, rel=1e-12)
    assert forces[8] == pytest.approx(tyres.relaxation_lengths(c, load, 20.0)[1], rel=1e-12)


def test_linearised_machine_has_the_tyre_sets_cornering_stiffness(
    model: tyred.TyredModel,
) -> None:
    """About upright running the side-force rows of the linearised MF machine are the tyre
    sets' cornering stiffness at the model's own static loads (relaxation: v / sigma K)."""
    state = tyred.upright_state(model, 20.0)
    loads = tyred.contact_loads(model, state, tyred.Inputs())
    linear = tyred.load_model("sel2004_motorcycle", tyres="linear")
    A_mf = tyred.lateral_matrix(model, 20.0)
    A_lin = tyred.lateral_matrix(linear, 20.0)
    assert np.max(np.abs(A_mf - A_lin)) < 0.02 * np.max(np.abs(A_lin))
    for suffix, c in (("r", model.mf_rear), ("f", model.mf_front)):
        stiffness = tyres.cornering_stiffness(c, loads[f"F_z{suffix}"], 0.0)
        assert stiffness > 10.0 * loads[f"F_z{suffix}"]  # of a motorcycle tyre, 11-17 /rad


def test_mixing_tyre_laws_is_refused() -> None:
    pset = load_parameter_set("sel2004_motorcycle")
    mf = load_parameters(pset.tyres["rear_tyre"], "tyre")
    linear = tyred.LinearTyre(15.0, 0.8, 20.0, 0.2, 1.5e5, 1.5e3)
    with pytest.raises(MotosimError, match="one kind"):
        tyred.make_model(pset.values, mf, linear)
    with pytest.raises(MotosimError, match="'magic' or 'linear'"):
        tyred.load_model("sel2004_motorcycle", tyres="pacejka")
