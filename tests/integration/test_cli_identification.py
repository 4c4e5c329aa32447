"""``motosim excite`` and ``motosim identify`` end to end."""

import json
import sys
import tomllib
from pathlib import Path

import numpy as np
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
    assert (
        main(
            [
                "excite",
                "--signal",
                "square",
                "--duration",
                "20",
                "--seed",
                "1",
                "--out",
                str(folder / "square.csv"),
            ]
        )
        == 0
    )
    return folder


def test_excite_writes_the_log_columns(runs: Path) -> None:
    lines = (runs / "chirp.csv").read_text().splitlines()
    assert lines[0] == "t,theta_h,i_m,u"
    assert len(lines) == 6002  # 60 s at 100 Hz, both ends


@pytest.mark.parametrize(
    ("options", "amplitude", "crossings"),
    [
        # a linear chirp of f0 to f1 over T changes sign (f0 + f1) T times: 55 in 10 s
        (["--signal", "chirp", "--f0", "0.5", "--f1", "5", "--amplitude", "6"], 6.0, 55),
        # a rectangle of f changes sign 2 f T times: 40 in 10 s
        (["--signal", "square", "--frequency", "2", "--amplitude", "1.5"], 1.5, 40),
    ],
)
def test_excite_drives_the_voltage_its_options_give(
    tmp_path: Path, options: list[str], amplitude: float, crossings: int
) -> None:
    from motosim.io import read_log

    out = tmp_path / "run.csv"
    assert main(["excite", *options, "--duration", "10", "--out", str(out)]) == 0
    u = read_log(out, required=("u",))["u"]
    assert float(np.max(np.abs(u))) == pytest.approx(amplitude, rel=1e-3)
    signs = np.sign(u[np.abs(u) > 1e-9])
    assert abs(int(np.count_nonzero(np.diff(signs))) - crossings) <= 1


@pytest.mark.parametrize(
    ("options", "settings"),
    [
        (
            ["--signal", "chirp", "--f0", "0.5", "--f1", "5", "--amplitude", "6"],
            {"amplitude": 6.0, "f0": 0.5, "f1": 5.0},
        ),
        (
            ["--signal", "square", "--frequency", "2", "--amplitude", "1.5"],
            {"amplitude": 1.5, "frequency": 2.0},
        ),
    ],
)
def test_excite_json_records_the_excitations_settings(
    tmp_path: Path, options: list[str], settings: dict[str, float]
) -> None:
    # the JSON said the signal's kind and rate only: not its amplitude and frequencies
    import subprocess

    from motosim.io import read_log

    out = tmp_path / "run.csv"
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "motosim",
            "excite",
            *options,
            "--duration",
            "10",
            "--seed",
            "3",
            "--json",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert {k: summary[k] for k in settings} == settings
    assert summary["duration"] == 10.0 and summary["seed"] == 3
    other = {"f0", "f1"} if "frequency" in settings else {"frequency"}
    assert not other & summary.keys()  # the other signal's frequencies are not its settings
    units = summary["units"]
    assert units["amplitude"] == "V" and all(units[k] == "Hz" for k in settings if k[0] == "f")
    u = read_log(out, required=("u",))["u"]  # the log read back: the amplitude driven
    assert float(np.max(np.abs(u))) == pytest.approx(summary["amplitude"], rel=1e-3)


def test_identify_recovers_table1_and_writes_a_usable_file(
    capsys: pytest.CaptureFixture[str], runs: Path
) -> None:
    out_file = runs / "identified.toml"
    code, out, _ = _run(
        capsys,
        "identify",
        str(runs / "chirp.csv"),
        "--validate",
        str(runs / "square.csv"),
        "--json",
        "--out",
        str(out_file),
        "--plot",
        str(runs / "id.png"),
    )
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
        capsys,
        "identify",
        str(runs / "chirp.csv"),
        "--ratio",
        "6",
        "--torque-constant",
        "0.25",
        "--method",
        "lsq",
        "--json",
    )
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


def test_intervals_printed_and_in_the_parameter_file(
    capsys: pytest.CaptureFixture[str], runs: Path
) -> None:
    out_file = runs / "noted.toml"
    code, out, _ = _run(capsys, "identify", str(runs / "chirp.csv"), "--out", str(out_file))
    assert code == 0
    assert "drive voltage_held (u: a voltage held by a voltage drive" in out
    assert out.count("95 % interval") >= 3
    assert "fit NRMSE" in out and "NRMSE = RMS(simulated - measured angle)" in out
    notes = tomllib.loads(out_file.read_text())
    for name in ("J_eq", "beta_eq", "beta_s"):
        assert "95 % interval" in json.dumps(notes), name


def test_drive_option_overrides_the_columns(
    capsys: pytest.CaptureFixture[str], runs: Path, tmp_path: Path
) -> None:
    # the same rows under a ';' delimiter, a decimal comma, units and other column names
    rows = (runs / "chirp.csv").read_text().splitlines()[1:]
    text = "time [s];angle [rad];current [A];volts\n" + "\n".join(
        row.replace(",", ";").replace(".", ",") for row in rows
    )
    log = tmp_path / "rig.csv"
    log.write_text(text)
    columns = "t=time,theta_h=angle,i_m=current"
    code, out, _ = _run(capsys, "identify", str(log), "--columns", columns, "--json")
    report = json.loads(out)
    assert code == 0 and report["drive"] == "current_sampled"  # no u column mapped
    code, out, _ = _run(capsys, "identify", str(log), "--columns", columns + ",u=volts", "--json")
    assert json.loads(out)["drive"] == "voltage_held"
    code, out, _ = _run(
        capsys, "identify", str(log), "--columns", columns, "--drive", "current_held", "--json"
    )
    report = json.loads(out)
    assert (report["drive"], report["drive_reason"]) == ("current_held", "given")


def test_validate_flags_a_model_that_does_not_generalise(
    capsys: pytest.CaptureFixture[str], runs: Path, tmp_path: Path
) -> None:
    # validated on a run whose angle is halved: another handlebar, or a wrong encoder scale
    assert (
        main(
            [
                "excite",
                "--signal",
                "square",
                "--duration",
                "20",
                "--out",
                str(tmp_path / "square.csv"),
            ]
        )
        == 0
    )
    capsys.readouterr()
    heavy = tmp_path / "heavy.csv"
    lines = (tmp_path / "square.csv").read_text().splitlines()
    # the same current, the angle halved: the handlebar moved half as far
    heavy.write_text(
        lines[0]
        + "\n"
        + "\n".join(
            ",".join([t, repr(float(th) * 0.5), i, u])
            for t, th, i, u in (row.split(",") for row in lines[1:])
        )
    )
    code, out, _ = _run(
        capsys, "identify", str(runs / "chirp.csv"), "--validate", str(heavy), "--json"
    )
    report = json.loads(out)
    assert code == 0
    assert any("does not generalise" in w for w in report["warnings"])
