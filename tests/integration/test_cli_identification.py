"""``motosim excite`` and ``motosim identify`` end to end."""

import json
import sys
import tomllib
from pathlib import Path

import pytest

from motosim.cli.main import main
from motosim.params import load_parameters


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as info:
        sys.exit(main(list(argv)))
    out, err = capsys.readouterr()
    return int(info.value.code or 0), out, err


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("runs")
    assert main(["excite", "--signal", "chirp", "--out", str(folder / "chirp.csv")]) == 0
    assert main(["excite", "--signal", "square", "--duration", "20", "--seed", "1",
                 "--out", str(folder / "square.csv")]) == 0  # fmt: skip
    return folder


def test_excite_writes_the_log_columns(runs: Path) -> None:
    lines = (runs / "chirp.csv").read_text().splitlines()
    assert lines[0] == "t,theta_h,i_m,u"
    assert len(lines) == 6002  # 60 s at 100 Hz, both ends


def test_identify_recovers_table1_and_writes_a_usable_file(
    capsys: pytest.CaptureFixture[str], runs: Path
) -> None:
    out_file = runs / "identified.toml"
    code, out, _ = _run(
        capsys, "identify", str(runs / "chirp.csv"), "--validate", str(runs / "square.csv"),
        "--json", "--out", str(out_file), "--plot", str(runs / "id.png"),
    )  # fmt: skip
    assert code == 0
    report = json.loads(out)
    # Table I (Nehaoua et al. 2012): beta_eq 13.956 N*m*s/rad, beta_s 1.734 N*m; the default
    # measurement model (0.05 A current noise) allows 3 % on the frictions
    assert report["beta_eq"] == pytest.approx(13.956, rel=0.03)
    assert report["beta_s"] == pytest.approx(1.734, rel=0.03)
    assert report["J_eq"] == pytest.approx(0.0415, rel=0.15)
    assert report["drive"] == "voltage_held"
    assert report["validation_nrmse"] < 0.1
    identified = load_parameters(out_file, "handlebar")
    assert identified.beta_eq == report["beta_eq"]
    assert "identified by motosim identify" in tomllib.loads(out_file.read_text())["set"]["source"]
    assert (runs / "id.png").stat().st_size > 10_000


def test_identify_with_other_motor_constants(
    capsys: pytest.CaptureFixture[str], runs: Path
) -> None:
    code, out, _ = _run(
        capsys, "identify", str(runs / "chirp.csv"), "--ratio", "6", "--torque-constant",
        "0.25", "--method", "lsq", "--json",
    )  # fmt: skip
    report = json.loads(out)
    assert code == 0
    assert report["torque_per_amp"] == 1.5
    # half the torque per ampere: every identified parameter halves
    assert report["beta_eq"] == pytest.approx(13.956 / 2, rel=0.05)
    assert {"J_eq_ci95", "beta_eq_ci95", "beta_s_ci95"} <= set(report)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("t,theta_h\n" + "".join(f"{k * 0.01},0\n" for k in range(60)), "no current column"),
        ("t,theta_h,i_cmd,u\n" + "".join(f"{k * 0.01},0,1,1\n" for k in range(60)), "--drive"),
        ("t,theta_h,i_m\n" + "".join(f"{k * 0.01},0,0\n" for k in range(5)), "5 samples"),
        ("t,theta_h,i_m\n" + "".join(f"{k * 0.01},0,nan\n" for k in range(50)), "nan"),
        (
            "t,theta_h,i_m\n" + "".join(f"{k * 0.01},0,1\n" for k in range(30)) + "0.1,0,1\n",
            "time goes back",
        ),
        ("t,theta_h,i_m\n" + "".join(f"{k * 0.01},0,1\n" for k in range(300)), "excit"),
    ],
)
def test_bad_logs(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, content: str, message: str
) -> None:
    log = tmp_path / "bad.csv"
    log.write_text(content)
    code, out, err = _run(capsys, "identify", str(log))
    assert code == 2 and out == ""
    assert message in err and err.count("\n") == 1


def test_bad_options(capsys: pytest.CaptureFixture[str], runs: Path) -> None:
    code, _, err = _run(capsys, "identify", str(runs / "chirp.csv"), "--ratio", "-2")
    assert code == 2 and "--ratio -2.0; expected a finite number > 0" in err
    code, _, err = _run(capsys, "identify", str(runs / "chirp.csv"), "--method", "magic")
    assert code == 2 and "invalid choice" in err
    code, _, err = _run(capsys, "excite", "--duration", "-1", "--out", "x.csv")
    assert code == 2 and "duration" in err
