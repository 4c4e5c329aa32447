"""Legal but implausible input: accepted, with one warning line each (MotosimWarning)."""

import unittest.mock
import warnings
from importlib import resources
from pathlib import Path

import pytest

from motosim.cli.main import main
from motosim.errors import MotosimError, MotosimWarning
from motosim.io.runs import load_scenario
from motosim.params import (
    HandlebarParameters,
    SharpParameters,
    list_parameter_sets,
    load_parameters,
)
from motosim.sim.scenario import Motorcycle, Scenario, implausible

ROOT = Path(__file__).parents[2]


def _handlebar_file(tmp_path: Path, name: str, value: str) -> Path:
    text = (resources.files("motosim.params") / "data" / "simacom_handlebar.toml").read_text()
    start = text.index(f"[parameters.{name}]")
    line = text.index("value = ", start)
    end = text.index("\n", line)
    path = tmp_path / "hb.toml"
    path.write_text(text[:line] + f"value = {value}" + text[end:], encoding="utf-8")
    return path


def test_typical_ranges_lie_inside_the_legal_ones() -> None:
    for cls in (HandlebarParameters, SharpParameters):
        for name, (low, high, why) in cls.TYPICAL.items():
            spec = cls.SPECS[name]
            assert spec.lower <= low < high <= spec.upper, name
            assert why, name


def test_packaged_sets_and_scenarios_are_typical() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", MotosimWarning)
        for name in list_parameter_sets():
            load_parameters(name)
        for file in sorted((ROOT / "scenarios").rglob("*.toml")):
            load_scenario(file)


def test_an_atypical_handlebar_is_loaded_with_a_warning(tmp_path: Path) -> None:
    # 5 kg*m^2: legal (a handlebar up to 10), but a hundred times Table I's 0.0415
    path = _handlebar_file(tmp_path, "J_eq", "5.0")
    with pytest.warns(MotosimWarning, match=r"J_eq = 5 kg\*m\^2 is legal but outside the typical"):
        assert load_parameters(path, "handlebar").J_eq == 5.0


def test_the_cli_prints_one_warning_line_and_goes_on(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _handlebar_file(tmp_path, "J_eq", "5.0")
    assert main(["params", "show", str(path)]) == 0
    out, err = capsys.readouterr()
    assert err.count("\n") == 1 and err.startswith("motosim: warning: ")
    assert "J_eq" in err and "0.01 to 1 kg*m^2" in err
    assert "J_eq" in out


def test_a_librarys_warning_is_one_line_too(capsys: pytest.CaptureFixture[str]) -> None:
    # NumPy's and SciPy's warnings printed Python's two lines (the file, then its source line)
    from motosim.cli import main as cli

    for _ in range(2):  # once
        cli._show_warning(
            RuntimeWarning("overflow encountered\nin multiply"), RuntimeWarning, "/a/b/_core.py", 7
        )
    assert capsys.readouterr().err == (
        "motosim: warning: RuntimeWarning in _core.py:7: overflow encountered in multiply\n"
    )


@pytest.mark.parametrize(
    ("table", "expected"),
    [
        ("[motorcycle]\nspeed = 1.0\n", "speed = 1 m/s is legal but outside the 3 to 55 m/s"),
        ("[motorcycle]\nspeed = 100.0\n", "speed = 100 m/s is legal"),
        ("[measurement]\ncurrent_noise = 40.0\n", "the noise swamps the signal"),
        ("[measurement]\nencoder_bits = 4\n", "encoder_bits = 4 is legal but coarser"),
    ],
)
def test_implausible_scenarios_warn_once(
    table: str, expected: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "s.toml"
    path.write_text(
        '[scenario]\nname = "s"\nduration = 700.0\n[rates]\nplant = 1000.0\ncontrol = 100.0\n'
        'measurement = 100.0\n[rider]\nkind = "torque"\n'
        'profile = { kind = "constant", value = 200.0 }\n' + table,
        encoding="utf-8",
    )
    with unittest.mock.patch("motosim.io.runs.resolve", side_effect=KeyboardInterrupt):
        assert main(["simulate", str(path), "--out", str(tmp_path / "out")]) == 130
    lines = capsys.readouterr().err.splitlines()
    warned = [line for line in lines if line.startswith("motosim: warning: ")]
    assert any(expected in line for line in warned), lines
    assert any("duration = 700 s is legal" in line for line in warned)
    assert any("profile reaches 200 N*m" in line for line in warned)
    assert len(warned) == len(set(warned)) == 3


def test_implausible_lists_nothing_for_a_default_scenario() -> None:
    assert implausible(Scenario(name="x")) == []
    assert len(implausible(Scenario(name="x", motorcycle=Motorcycle(speed=60.0)))) == 1


def test_a_turn_of_more_than_a_full_circle_warns_that_the_angle_is_in_radians() -> None:
    # an angle written in degrees: more than a full circle in radians
    from motosim.sim.scenario import Rider, TurnPath

    def turn(angle: float) -> Scenario:
        path = TurnPath(radius=-60.0, angle=angle, start=30.0, transition=20.0)
        return Scenario(name="x", rider=Rider(kind="virtual", path=path))

    lines = implausible(turn(45.0))  # 45 deg written as radians: seven circles, warned
    assert len(lines) == 1 and "angle = 45 rad" in lines[0] and "radians" in lines[0]
    assert implausible(turn(3.14159 / 2)) == [] and implausible(turn(-6.0)) == []
    with pytest.raises(MotosimError, match=r"angle = 90\.0; expected .* <= 62\.83"):
        turn(90.0)  # ten circles and more are refused (scenario's legal range)
