"""``motosim modes --model multibody`` and ``motosim params`` on the multibody sets."""

import json
import sys

import pytest

from motosim.cli.main import main


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as info:
        sys.exit(main(list(argv)))
    out, err = capsys.readouterr()
    return int(info.value.code or 0), out, err


def test_modes_through_the_multibody_model_keep_the_json(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, out, _ = _run(capsys, "modes", "--speeds", "10,30", "--json")
    linear = json.loads(out)
    assert code == 0
    code, out, _ = _run(capsys, "modes", "--speeds", "10,30", "--json", "--model", "multibody")
    multibody = json.loads(out)
    assert code == 0
    assert multibody.keys() == linear.keys()
    assert multibody["modes"].keys() == linear["modes"].keys()
    for name in ("weave", "wobble"):
        for ours, theirs in zip(
            multibody["modes"][name]["eigenvalue"], linear["modes"][name]["eigenvalue"], strict=True
        ):
            assert complex(*ours) == pytest.approx(complex(*theirs), rel=0.02)


@pytest.mark.parametrize(
    ("name", "units"),
    [
        ("sharp1971", ["m", "m", "m", "m", "kg", "kg*m^2", "m", "kg"]),
        ("simacom_handlebar", ["kg*m^2", "N*m*s/rad", "N*m/A"]),
    ],
)
def test_params_show_writes_the_unit_of_every_derived_value(
    capsys: pytest.CaptureFixture[str], name: str, units: list[str]
) -> None:
    code, out, _ = _run(capsys, "params", "show", name)
    derived = [line for line in out.split("derived:")[1].splitlines() if line.strip()]
    assert code == 0 and [line.split()[-1] for line in derived] == units


def test_modes_refuse_a_multibody_set_in_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = _run(capsys, "modes", "--params", "benchmark_bicycle")
    assert code == 2
    assert "benchmark_bicycle" in err and "multibody" in err and len(err.splitlines()) == 1


def test_params_show_a_multibody_set(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _run(capsys, "params", "show", "benchmark_bicycle")
    assert code == 0 and "Table 1" in out and "x_G" in out
    derived = out.split("derived:")[1].splitlines()[1:]
    assert [line.split()[0] for line in derived] == ["mass", "x_G", "z_G"]
    assert [line.split()[-1] for line in derived] == ["kg", "m", "m"]  # each with its unit
    code, out, _ = _run(capsys, "params", "list", "--json")
    assert {"name": "benchmark_bicycle", "model": "multibody"}.items() <= next(
        s for s in json.loads(out) if s["name"] == "benchmark_bicycle"
    ).items()
