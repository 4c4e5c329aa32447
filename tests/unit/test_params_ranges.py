"""Physical ranges: every value in range gives a usable model, every value out of it is refused."""

import math
from dataclasses import fields, replace

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.model import sharp as model
from motosim.model.handlebar import matrices
from motosim.params import HandlebarParameters, SharpParameters, load_parameters


def _random_in_range(
    cls: type[SharpParameters] | type[HandlebarParameters], rng: np.random.Generator
) -> dict[str, float]:
    values = {}
    for name, spec in cls.SPECS.items():
        lo, hi = spec.lower, spec.upper
        # log-uniform over positive ranges reaches both ends; uniform otherwise
        if lo > 0:
            values[name] = float(math.exp(rng.uniform(math.log(lo), math.log(hi))))
        else:
            values[name] = float(rng.uniform(lo, hi))
    return values


def test_every_spec_has_bounds_and_a_reason() -> None:
    for cls in (SharpParameters, HandlebarParameters):
        for name, spec in cls.SPECS.items():
            assert math.isfinite(spec.lower) and math.isfinite(spec.upper), name
            assert spec.reason, name


def test_packaged_sets_are_inside_their_ranges() -> None:
    for pset, cls in (("sharp1971", SharpParameters), ("simacom_handlebar", HandlebarParameters)):
        values = load_parameters(pset)
        for f in fields(values):
            assert cls.SPECS[f.name].admits(getattr(values, f.name)), f.name


def test_random_sharp_in_range_is_refused_or_gives_a_finite_model() -> None:
    """Any motorcycle the ranges admit has a positive definite mass matrix and finite modes."""
    rng = np.random.default_rng(16)
    built = 0
    messages = []
    for _ in range(300):
        values = _random_in_range(SharpParameters, rng)
        # half the draws made consistent (front load below the weight, inertia definite)
        if rng.uniform() < 0.5:
            weight = (values["m_f"] + values["m_r"]) * values["g"]
            values["Z_f"] = max(-rng.uniform(0.05, 0.95) * weight, -2e4)
            values["C_rxz"] = rng.uniform(-0.5, 0.5) * min(values["I_rx"], values["I_rz"])
        try:
            p = SharpParameters(**values)
        except MotosimError as err:
            messages.append(str(err))
            continue
        built += 1
        assert np.linalg.eigvalsh(model.mass_matrix(p)).min() > 0.0
        assert np.isfinite(model.eigenvalues(p, [1.0, 10.0, 60.0])).all()
    assert built > 30
    assert not [m for m in messages if "\n" in m]


def test_random_handlebar_in_range_is_refused_or_gives_finite_matrices() -> None:
    rng = np.random.default_rng(16)
    messages = []
    for _ in range(300):
        try:
            hb = HandlebarParameters(**_random_in_range(HandlebarParameters, rng))
        except MotosimError as err:
            messages.append(str(err))
            continue
        m = matrices(hb)
        assert np.isfinite(m.A).all() and np.isfinite(m.B).all()
    assert not [m for m in messages if "\n" in m]


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"R_r": 1e-9}, "R_r = 1e-09; expected a finite number >= 0.1 and <= 0.6 [m]"),
        ({"m_r": 1e300}, "m_r = 1e+300; expected a finite number >= 10 and <= 1000 [kg]"),
        ({"m_f": 10**400}, "m_f = an integer of 401 digits"),
        ({"C_rxz": 40.0}, "has a principal moment of"),
        ({"Z_f": -5000.0}, "front load -Z_f = 5000 N is not below the total weight"),
        ({"t": 0.3, "a": 0.2}, "expected the front contact ahead of G_r"),
        ({"g": 1.62}, "g = 1.62; expected a finite number >= 9.7 and <= 9.9 [m/s^2]"),
    ],
)
def test_out_of_range_refused(
    sharp: SharpParameters, changes: dict[str, float], message: str
) -> None:
    with pytest.raises(MotosimError) as info:
        replace(sharp, **changes)
    assert message in str(info.value) and "\n" not in str(info.value)
