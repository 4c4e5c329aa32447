"""Parameter files: packaged sets, validation and round trip."""

import math
import re
from dataclasses import replace
from pathlib import Path

import pytest

from motosim.errors import MotosimError
from motosim.params import (
    HandlebarParameters,
    SharpParameters,
    dump_parameter_set,
    list_parameter_sets,
    load_parameter_set,
    load_parameters,
)


def test_packaged_sets_load() -> None:
    assert {"sharp1971", "simacom_handlebar"} <= set(list_parameter_sets())
    for name in list_parameter_sets():
        pset = load_parameter_set(name)
        assert pset.name == name
        # every packaged value names its source
        assert all(pset.sources[k] for k in type(pset.values).SPECS)


def test_table_one_values(handlebar: HandlebarParameters) -> None:
    # Nehaoua, Arioui & Mammar 2012, Table I
    assert (handlebar.J_eq, handlebar.beta_eq, handlebar.beta_s) == (0.0415, 13.956, 1.734)
    # Remark 3.3: a peak rider torque of about 70 N*m must be within the motor's reach
    assert 70.0 / handlebar.torque_per_amp < 30.0
    assert handlebar.J_h > 0 and handlebar.beta_vh > 0


def test_round_trip(tmp_path: Path) -> None:
    for name in list_parameter_sets():
        pset = load_parameter_set(name)
        path = tmp_path / f"{name}.toml"
        path.write_text(dump_parameter_set(pset))
        again = load_parameter_set(path)
        assert again.values == pset.values
        assert dict(again.sources) == dict(pset.sources)


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "p.toml"
    path.write_text(text)
    return path


def _handlebar_text(**overrides: str) -> str:
    values = {
        "J_eq": "0.05",
        "beta_eq": "10.0",
        "beta_s": "1.0",
        "N": "10.0",
        "k_t": "0.2",
        "J_m": "1e-4",
        "beta_vm": "1e-3",
        "R": "1.0",
        "L": "1e-3",
        "k_e": "0.2",
    }
    values.update(overrides)
    body = "\n".join(f"{k} = {v}" for k, v in values.items() if v != "")
    return f'[set]\nname = "x"\nmodel = "handlebar"\n\n[parameters]\n{body}\n'


def test_plain_numbers_accepted(tmp_path: Path) -> None:
    values = load_parameters(_write(tmp_path, _handlebar_text()), "handlebar")
    assert values.J_eq == 0.05


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"J_eq": "nan"}, "parameters.J_eq = nan; expected a finite number"),
        ({"J_eq": "-0.05"}, "J_eq = -0.05; expected a finite number >= 0.0001 and <= 10 [kg*m^2]"),
        ({"beta_s": "-1.0"}, "beta_s = -1.0; expected a finite number >= 0 and <= 200 [N*m]"),
        ({"R": "0.0"}, "R = 0.0; expected a finite number >= 0.001 and <= 100 [ohm]"),
        ({"k_t": '"fast"'}, "k_t = 'fast' is a string; expected a finite number >= 0.001"),
        ({"k_e": ""}, "missing parameter k_e"),
        ({"J_m": "0.01"}, "N^2 J_m = 1 kg*m^2 is not below J_eq = 0.05"),
        ({"zeta": "1.0"}, "unknown handlebar parameter 'zeta' (expected one of J_eq,"),
    ],
)
def test_bad_values(tmp_path: Path, overrides: dict[str, str], message: str) -> None:
    path = _write(tmp_path, _handlebar_text(**overrides))
    with pytest.raises(MotosimError, match=None) as info:
        load_parameter_set(path)
    text = str(info.value)
    assert message in text and str(path) in text and "\n" not in text


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[set]\nname='x'\nmodel='car'\n[parameters]\n", "model = 'car' (expected one of sharp"),
        ("[set]\nmodel='handlebar'\ncolour='red'\n", "unknown key 'colour' (expected"),
        ("[sett]\n", "unknown table 'sett'; did you mean 'set'?"),
        ("[parameters]\n", "missing table [set]"),
        ("[set\n", "not valid TOML"),
        (
            "[set]\nmodel='handlebar'\n[parameters.J_eq]\nvalue=1.0\nunit='g*cm^2'\n",
            "parameter J_eq has unit 'g*cm^2'; expected 'kg*m^2'",
        ),
        (
            "[set]\nmodel='handlebar'\n[parameters.J_eq]\nunit='kg*m^2'\n",
            "parameter J_eq has no value",
        ),
        (
            "[set]\nmodel='handlebar'\n[parameters.J_eq]\nvalue=1.0\nsauce='x'\n",
            "parameter J_eq: unknown key 'sauce'; did you mean 'source'?",
        ),
        ("[set]\nmodel=['sharp']\n", "[set] model = ['sharp'] is a list; expected a string"),
        ("[set]\nmodel='sharpp'\n", "model = 'sharpp'; did you mean 'sharp'?"),
        ("[set]\nmodel='sharp'\nname={a=1}\n", "[set] name = {'a': 1} is a table"),
        ("set = 3\n", "set = 3 is a number; expected a table"),
        ("[set]\nmodel='sharp'\n[parameter]\n", "unknown table 'parameter'; did you mean"),
        ("[set]\nmodel='handlebar'\n[parameters]\nJ_eg=1\n", "'J_eg'; did you mean 'J_eq'?"),
        ("[set]\nmodel='handlebar'\n[parameters]\nJ_eq=[1]\n", "J_eq = [1] is a list"),
        ("[set]\nmodel='handlebar'\n[parameters]\nJ_eq=1e-300\n", "J_eq = 1e-300; expected"),
    ],
)
def test_bad_files(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(MotosimError) as info:
        load_parameter_set(_write(tmp_path, text))
    assert message in str(info.value)


def test_missing_file_and_wrong_model(tmp_path: Path) -> None:
    with pytest.raises(MotosimError, match="no such parameter file or packaged set"):
        load_parameter_set(tmp_path / "none.toml")
    with pytest.raises(MotosimError, match="did you mean 'sharp1971'"):
        load_parameter_set("sharp1917")
    with pytest.raises(MotosimError, match="is a handlebar parameter set; expected a sharp"):
        load_parameters("simacom_handlebar", "sharp")


def test_dataclass_validation(sharp: SharpParameters) -> None:
    with pytest.raises(
        MotosimError, match=re.escape("m_f = -1.0; expected a finite number >= 2 and <= 150 [kg]")
    ):
        replace(sharp, m_f=-1.0)
    with pytest.raises(MotosimError, match=re.escape("I_fz = 0.0")):
        replace(sharp, I_fz=0.0)
    with pytest.raises(MotosimError, match=re.escape("Z_f = 10.0")):
        replace(sharp, Z_f=10.0)
    with pytest.raises(MotosimError, match="sigma = inf"):
        replace(sharp, sigma=math.inf)
