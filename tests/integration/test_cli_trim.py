"""``motosim trim``: the steady turn and the handling sweep at the command line."""

import json
import math
import sys
from pathlib import Path

import pytest

from motosim.cli.main import main


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as info:
        sys.exit(main(list(argv)))
    out, err = capsys.readouterr()
    return int(info.value.code or 0), out, err


def test_trim_json_is_si_and_balances_the_turn(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _run(capsys, "trim", "--speed", "20", "--radius", "50", "--json")
    assert code == 0
    turn = json.loads(out)
    for key in ("phi", "delta", "tau_r", "F_xf", "F_xr", "F_yf", "F_yr", "F_zf", "F_zr"):
        assert math.isfinite(turn[key]), key
    for key in ("kappa_f", "kappa_r", "alpha_f", "alpha_r", "camber_f", "camber_r"):
        assert math.isfinite(turn[key]), key
    assert 0.7 < turn["phi"] < 0.9  # radians: atan(0.815) = 0.684 plus the crowns and spin
    assert turn["F_zf"] + turn["F_zr"] > 2000.0


def test_trim_prints_degrees_with_units(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _run(capsys, "trim", "--speed", "20", "--radius", "50")
    assert code == 0
    phi = next(line for line in out.splitlines() if line.split()[:1] == ["phi"])
    assert phi.split()[-1] == "deg" and 40.0 < float(phi.split()[1]) < 50.0
    assert any(line.split()[:1] == ["tau_r"] and line.endswith("N*m") for line in out.splitlines())


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["--speed", "2", "--radius", "50"], ["--speed", "3", "60"]),
        (["--speed", "61", "--radius", "50"], ["--speed", "60"]),
        (["--speed", "20", "--radius", "0"], ["--radius", "2"]),
        (["--speed", "20", "--radius", "nan"], ["--radius"]),
        (["--speed", "20"], ["--radius", "missing"]),
        (["--params", "nosuch", "--speed", "20", "--radius", "50"], ["nosuch"]),
        (["--params", "sel2004_front_120_70_zr17", "--speed", "20", "--radius", "50"], ["tyre"]),
        (["--params", "benchmark_bicycle", "--speed", "20", "--radius", "50"], ["front_tyre"]),
        (["--handling", "--speeds", "10,100"], ["--speeds", "60"]),
        (["--speed", "20", "--radius", "50", "--plot", "x.png"], ["--plot", "--handling"]),
    ],
)
def test_bad_input_exits_2_in_one_line(
    capsys: pytest.CaptureFixture[str], argv: list[str], words: list[str]
) -> None:
    code, out, err = _run(capsys, "trim", *argv)
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1, err
    for word in words:
        assert word in err


def test_no_steady_turn_exits_3_in_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = _run(capsys, "trim", "--speed", "20", "--radius", "30")
    assert code == 3
    assert len(err.strip().splitlines()) == 1 and "friction" in err


def test_handling_sweep_writes_the_figure(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    figure = tmp_path / "handling.png"
    code, out, _ = _run(
        capsys, "trim", "--handling", "--speeds", "10,30", "--plot", str(figure), "--json"
    )
    assert code == 0 and figure.stat().st_size > 10_000
    curves = json.loads(out)["curves"]
    assert set(curves) == {"10", "30"}
    for turns in curves.values():
        lateral = [t["lateral_g"] for t in turns]
        assert lateral == sorted(lateral) and lateral[-1] > 0.85
        rolls = [t["phi"] for t in turns]
        assert rolls == sorted(rolls)


def test_help_states_the_defaults(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _run(capsys, "trim", "--help")
    assert code == 0
    text = " ".join(out.split())
    assert "(default sel2004_motorcycle)" in text and "(default 10,20,30)" in text
    assert "3 to 60" in text
