"""The multibody parameter kind: the packaged benchmark set, the tyre keys, the validation."""

import dataclasses

import pytest

from motosim.errors import MotosimError
from motosim.params import (
    MultibodyParameters,
    dump_parameter_set,
    list_parameter_sets,
    load_parameter_set,
    load_parameters,
    parse_parameter_set,
)
from motosim.params.toml import parse_toml


def test_benchmark_set_is_meijaard_table_1() -> None:
    p = load_parameters("benchmark_bicycle", "multibody")
    assert "benchmark_bicycle" in list_parameter_sets()
    # Meijaard et al. 2007, Table 1: total mass 94 kg, mass centre of the whole bicycle
    assert p.mass == pytest.approx(94.0)
    assert (p.w, p.c, p.r_R, p.r_F, p.I_Bxz, p.I_Hxz) == (1.02, 0.08, 0.3, 0.35, 2.4, -0.00756)
    assert p.t_R == p.t_F == 0.0


def _text(extra_set: str = "", **overrides: float) -> str:
    text = dump_parameter_set(load_parameter_set("benchmark_bicycle"))
    text = text.replace('model = "multibody"', f'model = "multibody"\n{extra_set}')
    for name, value in overrides.items():
        head = f"[parameters.{name}]\nvalue = "
        start = text.index(head) + len(head)
        end = text.index("\n", start)
        text = text[:start] + repr(value) + text[end:]
    return text


def test_tyre_set_keys_are_kept_and_round_trip() -> None:
    text = _text('front_tyre = "mf_120_70"\nrear_tyre = "mf_180_55"')
    pset = parse_parameter_set(parse_toml(text, origin="t"), origin="t")
    assert dict(pset.tyres) == {"front_tyre": "mf_120_70", "rear_tyre": "mf_180_55"}
    again = parse_parameter_set(parse_toml(dump_parameter_set(pset), origin="u"), origin="u")
    assert again.tyres == pset.tyres


def test_tyre_keys_only_for_multibody_sets() -> None:
    text = dump_parameter_set(load_parameter_set("sharp1971"))
    text = text.replace('model = "sharp"', 'model = "sharp"\nfront_tyre = "x"')
    with pytest.raises(MotosimError, match="front_tyre"):
        parse_parameter_set(parse_toml(text, origin="t"), origin="t")


@pytest.mark.parametrize(
    ("overrides", "match"),
    [
        ({"I_Bxz": 6.0}, "positive definite"),
        ({"I_Byy": 13.0}, "triangle inequality"),
        ({"I_Ryy": 0.2}, "twice its diametral inertia"),
        ({"t_R": 0.3}, "crown radius"),
        ({"z_B": 0.1}, "z_B"),
    ],
)
def test_unphysical_values_are_refused(overrides: dict[str, float], match: str) -> None:
    with pytest.raises(MotosimError, match=match):
        parse_parameter_set(parse_toml(_text(**overrides), origin="t"), origin="t")


def test_dataclass_is_frozen() -> None:
    p = load_parameters("benchmark_bicycle", "multibody")
    assert isinstance(p, MultibodyParameters)
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.w = 2.0  # type: ignore[misc]
