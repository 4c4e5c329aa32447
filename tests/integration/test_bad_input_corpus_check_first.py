"""The bad-input corpus, checked before the work: each class refused in one line, early.

Every command checks the files it reads and writes, and its options, before it imports SciPy,
numba, h5py or the compiled stack: each case here runs the command in a fresh interpreter and
asserts the exit code, that the message is one line naming the value, and that none of those
modules was imported (so the answer does not wait for them; the time to the line is measured
in ``bench/bench_cli.py``). A scenario's values are checked by its model, which imports the
numerical stack, but before any design or run. Then the numerical failures (exit 3, not 2 and
not an internal error), the messages of a campaign, and the warnings of legal but suspect logs
and parameters.
"""

import errno
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from motosim.cli.main import main
from motosim.errors import MotosimError

ROOT = Path(__file__).parents[2]
SCENARIO = ROOT / "scenarios" / "lane_change_20.toml"
HEAVY = ("scipy", "numba", "h5py", "matplotlib", "motosim.sim.stack")
_CODE = (
    "import json, sys\n"
    "from motosim.cli.main import main\n"
    "code = main(json.loads(sys.argv[1]))\n"
    f"heavy = sorted(m for m in sys.modules if m.split('.')[0] in {HEAVY!r} or m in {HEAVY!r})\n"
    "print('HEAVY=' + json.dumps(heavy), file=sys.stderr)\n"
    "sys.exit(code)\n"
)


def _motosim(argv: list[str], cwd: Path) -> tuple[int, str, list[str]]:
    """Exit code, standard error (without the probe's line) and the heavy modules imported."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    done = subprocess.run(
        [sys.executable, "-c", _CODE, json.dumps(argv)],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=env,
        check=False,
        timeout=120,
    )
    lines = done.stderr.splitlines()
    heavy = [json.loads(x[6:]) for x in lines if x.startswith("HEAVY=")]
    err = "".join(x + "\n" for x in lines if not x.startswith("HEAVY="))
    return done.returncode, err, heavy[0] if heavy else ["(no probe: the process died)"]


def _refused_early(argv: list[str], cwd: Path, *named: str) -> str:
    code, err, heavy = _motosim(argv, cwd)
    assert code == 2, err
    assert err.startswith("motosim: error: ") and err.count("\n") == 1, err
    for text in named:
        assert text in err, err
    assert heavy == [], f"{argv}: imported {heavy} before refusing"
    return err


@pytest.fixture
def files(tmp_path: Path) -> Path:
    """A folder with a symbolic link loop, a binary log and a scenario naming a missing design."""
    (tmp_path / "loop_a.toml").symlink_to("loop_b.toml")
    (tmp_path / "loop_b.toml").symlink_to("loop_a.toml")
    (tmp_path / "binary.csv").write_bytes(b"t,theta_h,i_m\n\x00\x01\x02\xff")
    text = SCENARIO.read_text(encoding="utf-8")
    (tmp_path / "s.toml").write_text(text, encoding="utf-8")
    (tmp_path / "nodesign.toml").write_text(
        text + '\n[controller]\ndesign = "nope.toml"\n', encoding="utf-8"
    )
    (tmp_path / "nohb.toml").write_text(
        text + '\n[handlebar]\ntrue = "gone_hb.toml"\n', encoding="utf-8"
    )
    (tmp_path / "c.toml").write_text(
        '[campaign]\nscenario = "gone.toml"\nruns = 4\n[factors]\n'
        '"handlebar.inertia_factor" = { distribution = "uniform", low = 0.5, high = 1.5 }\n',
        encoding="utf-8",
    )
    return tmp_path


# --- 1. every command: a misspelt file, before any heavy import -----------------------------

MISSPELT = [
    ["params", "show", "nope.toml"],
    ["modes", "--params", "nope.toml"],
    ["excite", "--handlebar", "nope.toml", "--out", "x.csv"],
    ["identify", "nope.csv"],
    ["estimate", "nope.csv", "--out", "x.csv"],
    ["design", "--handlebar", "nope.toml"],
    ["simulate", "nope.toml", "--out", "r"],
    ["report", "nope"],
    ["view", "nope"],
    ["telemetry", "nope", "--mcap", "x.mcap"],
    ["campaign", "nope.toml", "--out", "c"],
    ["fidelity", "nope.toml"],
    ["cueing", "nope", "--out", "q"],
    ["run", "nope.toml", "--bus", "virtual", "--out", "r"],
    ["rig", "nope.toml", "--bus", "virtual"],
]


@pytest.mark.parametrize("argv", MISSPELT, ids=[a[0] for a in MISSPELT])
def test_a_misspelt_file_is_refused_before_any_heavy_import(argv: list[str], files: Path) -> None:
    _refused_early(argv, files, "nope", "no such")


def test_paper_and_rt_check_refuse_early_too(files: Path) -> None:
    # the two commands that read no file: an output that takes none, an option out of range
    _refused_early(["paper", "--out", "/proc/p"], files, "/proc", "cannot write")
    _refused_early(["rt-check", "--rate", "abc"], files, "'abc'")
    # an option checked deeper in the library is checked before it is imported too
    _refused_early(["fidelity", "--band", "3:1"], files, "--band '3:1'", "<= 20 Hz")


@pytest.mark.parametrize("command", ["run", "rig"])
def test_a_bad_bus_is_refused_before_the_can_codec_is_compiled(command: str, files: Path) -> None:
    scenario = str(Path(__file__).parents[2] / "scenarios" / "realtime_square.toml")
    argv = [command, scenario, "--bus", "nope", *(["--out", "r"] if command == "run" else [])]
    _refused_early(argv, files, "--bus 'nope'", "INTERFACE[:CHANNEL]")  # numba not imported


# --- 1. paths: outputs that cannot be written, inputs that cannot be read -------------------


@pytest.mark.parametrize(
    "argv",
    [
        ["excite", "--out", "/proc/o.csv"],
        ["design", "--out", "/proc/d.toml"],
        ["estimate", "binary.csv", "--out", "/proc/e.csv"],
        ["simulate", "s.toml", "--out", "/proc/r"],
        ["campaign", "c.toml", "--out", "/proc/c"],
    ],
    ids=["excite", "design", "estimate", "simulate", "campaign"],
)
def test_an_output_in_proc_is_refused_before_the_work(argv: list[str], files: Path) -> None:
    if argv[0] == "estimate":  # the log is checked first: give it a readable one
        (files / "binary.csv").write_text("t,theta_h,i_m\n0,0,0\n0.01,0,0\n", encoding="utf-8")
    if argv[0] == "campaign":
        (files / "gone.toml").write_text(SCENARIO.read_text(encoding="utf-8"), encoding="utf-8")
    _refused_early(argv, files, "/proc", "cannot write in the folder /proc")


@pytest.mark.parametrize(
    "argv",
    [
        ["excite", "--out", "newdir/"],
        ["estimate", "log.csv", "--out", "e/"],
        ["design", "--out", "d/"],
    ],
    ids=["excite", "estimate", "design"],
)
def test_a_trailing_slash_names_a_folder_never_a_file(argv: list[str], files: Path) -> None:
    (files / "log.csv").write_text("t,theta_h,i_m\n0,0,0\n0.01,0,0\n", encoding="utf-8")
    name = argv[-1]
    _refused_early(argv, files, name, "names a folder")
    assert not (files / name.rstrip("/")).exists()


def test_unreadable_inputs_are_named_for_what_they_are(files: Path) -> None:
    _refused_early(
        ["simulate", "loop_a.toml", "--out", "r"], files, "loop_a.toml", "symbolic link loop"
    )
    _refused_early(["design", "--handlebar", "loop_a.toml"], files, "symbolic link loop")
    _refused_early(["identify", "binary.csv"], files, "binary.csv", "binary")
    _refused_early(["simulate", ".", "--out", "r"], files, "is a directory")
    _refused_early(
        ["simulate", "nodesign.toml", "--out", "r"], files, "nope.toml", "no such design file"
    )
    _refused_early(
        ["rig", "nohb.toml", "--bus", "virtual"], files, "gone_hb.toml", "no such parameter file"
    )
    _refused_early(
        ["campaign", "c.toml", "--out", "out"], files, "gone.toml", "no such scenario file"
    )


# --- 2. a scenario's values, before any design or run ---------------------------------------


def _scenario(folder: Path, extra_motorcycle: str = "", tail: str = "") -> Path:
    text = SCENARIO.read_text(encoding="utf-8")
    text = text.replace("speed = 20.0", "speed = 20.0\n" + extra_motorcycle) + tail
    path = folder / "v.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("line", "named"),
    [
        ('drive_torque = { kind = "constant", value = 1e6 }', "drive_torque reaches 1e+06 N*m"),
        ('wind_force = { kind = "constant", value = 1e9 }', "wind_force reaches 1e+09 N"),
        ('brake_torque = { kind = "constant", value = -50.0 }', "brake_torque reaches -50 N*m"),
        (
            'side_wind = { kind = "square", low = 0.0, high = 2e4, period = 2.0 }',
            "side_wind reaches 20000 N",
        ),
    ],
    ids=["drive", "wind", "negative_brake", "side_wind"],
)
def test_a_scenario_value_out_of_its_range_is_bad_input_not_a_failed_run(
    line: str, named: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["simulate", str(_scenario(tmp_path, line)), "--out", str(tmp_path / "r")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert named in err and "; expected " in err and " to " in err, err
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize(
    ("old", "new", "named"),
    [
        ("offset = 3.5", "offset = 3500.0", "offset = 3500.0; expected a finite number >= -100"),
        ("length = 60.0", "length = 1e9", "length = 1000000000.0; expected"),
        (
            'kind = "virtual"',
            'kind = "torque"\nprofile = { kind = "square", low = 0.0, high = '
            "5.0, period = 2.0, start = 1e9 }",
            "start = 1000000000.0; expected",
        ),
    ],
    ids=["lane_offset", "lane_length", "profile_start"],
)
def test_a_path_or_profile_far_beyond_any_ride_is_refused(
    old: str, new: str, named: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = SCENARIO.read_text(encoding="utf-8").replace(old, new)
    if "square" in new:
        text = text.replace(
            'path = { kind = "lane_change", offset = 3.5, length = 60.0, start = 50.0 }\n', ""
        )
    (tmp_path / "v.toml").write_text(text, encoding="utf-8")
    assert main(["simulate", str(tmp_path / "v.toml"), "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and named in err, err


def test_a_huge_csv_rider_torque_is_refused_before_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], recwarn: pytest.WarningsRecorder
) -> None:
    (tmp_path / "huge.csv").write_text("t,tau_r\n0,0\n1,1e300\n5,0\n", encoding="utf-8")
    path = tmp_path / "csv.toml"
    path.write_text(
        '[scenario]\nname = "csv"\nduration = 2.0\n[rider]\nkind = "torque"\n'
        'profile = { kind = "csv", file = "huge.csv", column = "tau_r" }\n',
        encoding="utf-8",
    )
    code = main(["simulate", str(path), "--out", str(tmp_path / "r")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert "huge.csv: column 'tau_r'" in err and "1e+300 N*m" in err and "-1000 to 1000" in err
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_a_design_file_with_the_papers_controller_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "d.toml").write_text("# a design\n", encoding="utf-8")
    path = _scenario(tmp_path, tail='\n[controller]\nkind = "paper"\ndesign = "d.toml"\n')
    code = main(["simulate", str(path), "--out", str(tmp_path / "r")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert "design = 'd.toml' with kind = 'paper'" in err
    # the same scenario with the file missing: refused before the scenario model is imported
    (tmp_path / "d.toml").unlink()
    _refused_early(["simulate", str(path), "--out", "r"], tmp_path, "d.toml", "no such")


# --- 3. absurd options are bad input; a numerical failure of checked inputs a failed run ---


@pytest.mark.parametrize("bandwidth", ["1e-320", "1e-300", "1e-12", "0.05", "1e6"])
def test_an_absurd_design_bandwidth_is_refused_naming_the_range(
    bandwidth: str, tmp_path: Path
) -> None:
    _refused_early(
        ["design", "--bandwidth", bandwidth],
        tmp_path,
        f"--bandwidth {float(bandwidth)!r} Hz; expected 0.1 to 200 Hz",
    )


def test_a_linear_algebra_failure_is_a_failed_run_in_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def singular(name: str) -> None:
        raise np.linalg.LinAlgError("Singular matrix")

    monkeypatch.setattr("motosim.cli.params.load_parameter_set", singular)
    assert main(["params", "show", "sharp1971"]) == 3
    err = capsys.readouterr().err
    assert err.startswith("motosim: run failed: ") and err.count("\n") == 1, err
    assert "LinAlgError: Singular matrix" in err and "internal error" not in err


def test_a_synthesis_that_fails_on_checked_options_is_a_failed_design(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # the search's own refusal (its start points all unstable) on a plausible bandwidth
    def unstable(*args: object, **kwargs: object) -> None:
        raise MotosimError("no stabilising controller of order 1 was found; try order + 1")

    monkeypatch.setattr("motosim.control.torque_feedback.design_torque_feedback", unstable)
    assert main(["design", "--bandwidth", "10", "--json"]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("motosim: run failed: the design for "), err
    assert "10 Hz bandwidth, order 1 failed: no stabilising controller" in err


def test_a_scenarios_absurd_bandwidth_is_bad_input_and_a_failing_synthesis_a_failed_run(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _scenario(tmp_path, tail="\n[controller]\nbandwidth = 1e-12\n")
    assert main(["simulate", str(path), "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "[controller]: bandwidth = 1e-12; expected" in err, err
    assert ">= 0.1 and <= 1000 [Hz]" in err

    def unstable(*args: object, **kwargs: object) -> None:
        raise MotosimError("no stabilising controller of order 1 was found; try order + 1")

    monkeypatch.setattr("motosim.control.torque_feedback.synthesize_controller", unstable)
    path = _scenario(tmp_path, tail="\n[controller]\nbandwidth = 10.0\n")
    assert main(["simulate", str(path), "--out", str(tmp_path / "r")]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("motosim: run failed: lane_change_20: "), err
    assert "the controller's design failed ([controller] order 1): no stabilising" in err


# --- 4. messages -----------------------------------------------------------------------------


def test_a_campaign_of_zero_runs_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "s.toml").write_text(SCENARIO.read_text(encoding="utf-8"), encoding="utf-8")
    (tmp_path / "c.toml").write_text(
        '[campaign]\nscenario = "s.toml"\nruns = 0\n[factors]\n'
        '"handlebar.inertia_factor" = { distribution = "uniform", low = 0.5, high = 1.5 }\n',
        encoding="utf-8",
    )
    assert main(["campaign", str(tmp_path / "c.toml"), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "runs = 0; expected 1 to" in err and "missing" not in err


def test_a_campaign_on_a_full_disk_names_its_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "s.toml").write_text(SCENARIO.read_text(encoding="utf-8"), encoding="utf-8")
    (tmp_path / "c.toml").write_text(
        '[campaign]\nscenario = "s.toml"\nruns = 4\n[factors]\n'
        '"handlebar.inertia_factor" = { distribution = "uniform", low = 0.5, high = 1.5 }\n',
        encoding="utf-8",
    )

    def full(*args: object, **kwargs: object) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")  # as a Parquet writer raises it

    monkeypatch.setattr("motosim.campaign.run_campaign", full)
    out = tmp_path / "out"
    assert main(["campaign", str(tmp_path / "c.toml"), "--out", str(out), "--no-report"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(out) in err and "No space left on device" in err, err


# --- 5. legal but suspect: one warning line each ---------------------------------------------


def test_a_jittered_log_is_warned_about(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rng = np.random.default_rng(0)
    t = np.arange(400) * 0.01 + rng.uniform(-0.002, 0.002, 400)  # +/-2 ms on a 10 ms log
    rows = np.column_stack([t, 0.1 * np.sin(2 * np.pi * t), np.cos(2 * np.pi * t)])
    np.savetxt(tmp_path / "log.csv", rows, delimiter=",", header="t,theta_h,i_m", comments="")
    assert main(["estimate", str(tmp_path / "log.csv"), "--out", str(tmp_path / "e.csv")]) == 0
    warnings = [x for x in capsys.readouterr().err.splitlines() if "warning" in x]
    assert len(warnings) == 1 and "log.csv: the sample periods deviate by up to" in warnings[0]
    assert "10 ms period" in warnings[0]


def test_a_down_chirp_is_warned_about(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    argv = [
        "excite",
        "--f0",
        "5",
        "--f1",
        "1",
        "--duration",
        "10",
        "--out",
        str(tmp_path / "x.csv"),
    ]
    assert main(argv) == 0
    warnings = [x for x in capsys.readouterr().err.splitlines() if "warning" in x]
    assert warnings == [
        "motosim: warning: --f0 5 Hz is above --f1 1 Hz: a down-chirp, from high to low "
        "frequencies; legal, but an identification run usually sweeps up (swap them if that is "
        "what was meant)"
    ]


@pytest.mark.parametrize(
    ("packaged", "key", "value", "why"),
    [
        ("simacom_handlebar", "beta_s", "1e-12", "at least the hundredths of N*m"),
        ("sharp1971", "epsilon", "1e-09", "17 to 37 deg of caster"),
    ],
)
def test_a_tiny_friction_or_caster_is_warned_about_with_why(
    packaged: str,
    key: str,
    value: str,
    why: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    text = (ROOT / "src" / "motosim" / "params" / "data" / f"{packaged}.toml").read_text(
        encoding="utf-8"
    )
    head, rest = text.split(f"[parameters.{key}]\nvalue = ", 1)
    path = tmp_path / "p.toml"
    path.write_text(f"{head}[parameters.{key}]\nvalue = {value}{rest[rest.index(chr(10)) :]}")
    assert main(["params", "show", str(path)]) == 0
    warnings = [x for x in capsys.readouterr().err.splitlines() if "warning" in x]
    assert len(warnings) == 1 and f"{key} = {value}" in warnings[0] and why in warnings[0]


@pytest.mark.parametrize(
    ("table", "key"),
    [
        ("motorcycle", "front_brake_torque"),
        ("motorcycle", "rear_brake_torque"),
        ("road", "friction"),
    ],
)
def test_the_multibody_profiles_csv_is_checked_first(tmp_path: Path, table: str, key: str) -> None:
    """A CSV profile of the multibody motorcycle's brakes or the road's friction that names a
    missing file is refused before the numerical stack is imported, as the others are."""
    model = '[motorcycle]\nmodel = "multibody"\n' if table == "road" else ""
    (tmp_path / "mb.toml").write_text(
        f'[scenario]\nname = "mb"\n{model}[{table}]\n'
        + ('model = "multibody"\n' if table == "motorcycle" else "")
        + f'{key} = {{ kind = "csv", file = "nope.csv", column = "x" }}\n'
        '[rider]\nkind = "virtual"\n'
    )
    _refused_early(["simulate", "mb.toml", "--out", "r"], tmp_path, "nope.csv")
