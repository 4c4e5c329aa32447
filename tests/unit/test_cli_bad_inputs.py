"""Bad inputs found by a sweep of every command (s20): each refused in one line, exit 2.

Each test gives the input a new user tried and checks the one line ``motosim: error: ...``
naming the value and what was expected, and that nothing was written.
"""

from pathlib import Path

import pytest

from motosim.cli.main import main

ROOT = Path(__file__).parents[2]
REALTIME = ROOT / "scenarios" / "realtime_square.toml"


def _refused(capsys: pytest.CaptureFixture[str], *expected: str) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("motosim: error: "), err
    for text in expected:
        assert text in err, err
    return err


@pytest.mark.parametrize("kind", ["missing parent", "a file"])
def test_run_refuses_an_out_folder_it_cannot_use_before_the_bus(
    kind: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # it created the missing parent (simulate and campaign refuse it), and a file was
    # refused only after the --duration warning, in two lines
    out = tmp_path / "no" / "run" if kind == "missing parent" else tmp_path / "x.csv"
    if kind == "a file":
        out.write_text("t\n", encoding="utf-8")
    argv = ["run", str(REALTIME), "--bus", "virtual", "--out", str(out), "--duration", "0.2"]
    assert main(argv) == 2
    if kind == "missing parent":
        _refused(capsys, f"--out {out}: the folder {out.parent} does not exist")
        assert not out.parent.exists()
    else:
        _refused(capsys, f"--out {out} is a file; expected a result folder")


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["simulate", "{dir}", "--out", "{tmp}/o"], "is a directory; expected a scenario file"),
        (["campaign", "{dir}", "--out", "{tmp}/o"], "is a directory; expected a campaign file"),
        (["identify", "{dir}"], "is a directory; expected a log file (CSV)"),
        (["estimate", "{dir}", "--out", "{tmp}/o.csv"], "is a directory; expected a log file"),
        (["run", "{dir}", "--bus", "virtual", "--out", "{tmp}/o"], "expected a scenario file"),
        (["cueing", "{tmp}", "--platform", "{dir}", "--out", "{tmp}/o"], "expected a platform"),
        (["simulate", "/dev/zero", "--out", "{tmp}/o"], "is a device, a pipe or a socket"),
        (["identify", "/dev/zero"], "/dev/zero: is a device, a pipe or a socket; expected a log"),
    ],
)
def test_a_folder_or_a_device_given_as_an_input_file_is_named_as_such(
    argv: list[str], expected: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # they said "no such scenario file" (or campaign, log, platform file) of a path that is there
    folder = tmp_path / "runs"
    folder.mkdir()
    words = [w.format(dir=folder, tmp=tmp_path) for w in argv]
    assert main(words) == 2
    _refused(capsys, expected)


def test_view_refuses_a_cueing_folder_that_motosim_cueing_did_not_write(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # a simulate result given as --cueing was merged as nothing: the view served no platform
    # commands, silently
    pytest.importorskip("starlette")
    import numpy as np

    from motosim.io.results import ResultWriter

    run = tmp_path / "run"
    with ResultWriter(run, ("t", "theta_h", "x", "y"), {"scenario": {"name": "r"}}) as writer:
        writer.append(np.array([[0.0, 0.0, 0.0, 0.0], [0.01, 0.1, 0.2, 0.0]]))
        writer.close({})
    assert main(["view", str(run), "--cueing", str(run)]) == 2
    _refused(capsys, f"--cueing {run}: a result without phi_s, theta_s, psi_s, phi_vis")


def test_design_refuses_an_integral_corner_below_a_millionth(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # 1e-300 went to the search: SciPy's RuntimeWarnings (four lines), then "no stabilising
    # controller of order 1 was found", where 0 is refused at once
    assert main(["design", "--integral-corner", "1e-300"]) == 2
    _refused(capsys, "integral_corner = 1e-300; expected a fraction of the bandwidth from 1e-06")


def test_campaign_refuses_an_out_folder_holding_another_commands_result(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # it wrote its parts, manifest and report.html into a simulate result's folder
    (tmp_path / "base.toml").write_text(
        '[scenario]\nname = "b"\nduration = 0.2\n[rider]\nkind = "torque"\n'
        'profile = { kind = "constant", value = 1.0 }\n[controller]\nkind = "paper"\n',
        encoding="utf-8",
    )
    campaign = tmp_path / "c.toml"
    campaign.write_text(
        '[campaign]\nscenario = "base.toml"\nruns = 2\n[factors]\n'
        '"handlebar.inertia_factor" = [0.9, 1.1]\n',
        encoding="utf-8",
    )
    out = tmp_path / "run"
    out.mkdir()
    for name in ("result.h5", "result.csv", "report.html"):
        (out / name).write_text("kept", encoding="utf-8")
    assert main(["campaign", str(campaign), "--out", str(out), "--jobs", "1"]) == 2
    _refused(capsys, f"{out}: holds report.html, result.h5, result.csv but no campaign's results")
    assert sorted(p.name for p in out.iterdir()) == ["report.html", "result.csv", "result.h5"]
    assert (out / "report.html").read_text(encoding="utf-8") == "kept"
    # its own campaign and scenario files may share the folder with its results, as before
    for name in ("result.h5", "result.csv", "report.html"):
        (out / name).unlink()
    for path in (campaign, tmp_path / "base.toml"):
        path.rename(out / path.name)
    (out / ".gitkeep").touch()
    assert main(["campaign", str(out / "c.toml"), "--out", str(out), "--jobs", "1"]) == 0
    capsys.readouterr()
    assert (out / "manifest.json").is_file() and (out / "c.toml").is_file()


def test_a_design_file_for_another_rate_whose_observer_fails_there_is_refused_before_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # the observer of a 1 kHz design, sampled at 100 Hz, failed inside the run: two lines
    # naming neither the file nor the rates, and an empty DIR.partial left behind
    design = ROOT / "tests" / "data" / "design_simacom.toml"
    scenario = tmp_path / "s.toml"
    scenario.write_text(
        '[scenario]\nname = "s"\nduration = 0.2\n[rates]\ncontrol = 100.0\nmeasurement = 100.0\n'
        '[rider]\nkind = "torque"\nprofile = { kind = "constant", value = 1.0 }\n'
        f"[controller]\ndesign = {str(design)!r}\n",
        encoding="utf-8",
    )
    out = tmp_path / "out"
    assert main(["simulate", str(scenario), "--out", str(out)]) == 2
    _refused(
        capsys,
        f"{design}: a design for 1000 Hz whose observer, sampled at the scenario's",
        "expected a design for 100 Hz (motosim design --rate 100)",
    )
    assert not any(p.name.startswith("out") for p in tmp_path.iterdir())


def test_excite_warns_for_an_encoder_of_one_count(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # --counts 1 wrote a log whose angle never left 0 (12 counts a handlebar turn), silently
    out = tmp_path / "x.csv"
    assert main(["excite", "--duration", "10", "--counts", "1", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("motosim: warning: --counts 1 is legal but")
    assert out.is_file()


@pytest.mark.parametrize(
    ("options", "expected"),
    [
        # python-can half opened the bus: the error, then "UdpMulticastBus was not properly
        # shut down", after the --duration warning (three lines)
        (["--bus", "udp_multicast:notanip"], "expected a multicast group address"),
        (["--bus", "udp_multicast:8.8.8.8"], "'udp_multicast:8.8.8.8'; expected a multicast"),
        # 256.1.1.1 read as a host name: accepted, the platform's datagrams lost silently
        (["--platform-udp", "256.1.1.1:9"], "--platform-udp '256.1.1.1:9'; expected HOST:PORT"),
        # after the --duration warning (two lines)
        (["--platform-can", "--platform", "{dir}"], "is a directory; expected a platform file"),
        (["--pace", "bus"], "--pace bus with control = 1000 Hz and measurement = 100 Hz"),
    ],
)
def test_run_refuses_bus_and_platform_options_in_one_line_before_any_warning(
    options: list[str], expected: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["run", str(REALTIME), "--bus", "virtual", "--out", str(tmp_path / "o")]
    argv += [o.format(dir=tmp_path) for o in options] + ["--duration", "0.2"]
    assert main(argv) == 2
    _refused(capsys, expected)


def test_rig_refuses_a_rate_above_its_plant_rate_before_opening_the_bus(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # refused after the bus was opened
    import unittest.mock

    with unittest.mock.patch("motosim.io.can.open_link", side_effect=AssertionError("opened")):
        assert main(["rig", str(REALTIME), "--bus", "virtual", "--rate", "20000"]) == 2
    _refused(capsys, "--rate 20000.0; expected a rate from 1 to 10000 Hz (the rig's plant_rate)")


@pytest.mark.parametrize("command", ["simulate", "fidelity", "run", "rig"])
def test_a_scenario_refused_after_its_warnings_prints_only_the_error(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # the warning of the speed (58 m/s) was printed, then the missing design file refused it:
    # two lines, where a refused command prints only its error (the design file is now looked
    # for before the scenario is read, the safety table of run after)
    scenario = tmp_path / "s.toml"
    scenario.write_text(
        '[scenario]\nname = "s"\nduration = 0.2\n[motorcycle]\nspeed = 58.0\n[rider]\n'
        'kind = "virtual"\n[controller]\ndesign = "nofile.toml"\n',
        encoding="utf-8",
    )
    argv = {
        "simulate": ["simulate", str(scenario), "--out", str(tmp_path / "o")],
        "fidelity": ["fidelity", str(scenario)],
        "run": ["run", str(scenario), "--bus", "virtual", "--out", str(tmp_path / "o")],
        "rig": ["rig", str(scenario), "--bus", "virtual"],
    }[command]
    assert main(argv) == 2
    _refused(capsys, "no such design")


def test_a_complete_result_without_its_csv_is_not_replaced_without_overwrite(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # with result.csv deleted (the larger file), the next simulate into the folder replaced
    # result.h5, marked complete, without --overwrite
    import numpy as np

    from motosim.io.results import ResultWriter, load_result

    run = tmp_path / "run"
    with ResultWriter(run, ("t", "theta_h"), {"seed": 1}) as writer:
        writer.append(np.array([[0.0, 0.1], [0.01, 0.2]]))
        writer.close({"rms": 0.5})
    (run / "result.csv").unlink()
    scenario = tmp_path / "s.toml"
    scenario.write_text(
        '[scenario]\nname = "s"\nduration = 0.2\n[rider]\nkind = "torque"\n'
        'profile = { kind = "constant", value = 1.0 }\n[controller]\nkind = "paper"\n',
        encoding="utf-8",
    )
    assert main(["simulate", str(scenario), "--out", str(run), "--no-report"]) == 2
    _refused(capsys, f"{run}: already holds a result; give --overwrite or another --out")
    assert load_result(run).summary == {"rms": 0.5}


@pytest.mark.parametrize("command", ["cueing", "simulate", "run", "estimate", "excite", "design"])
def test_an_output_that_is_or_holds_the_input_is_refused_even_with_overwrite(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # an output that would replace its own input: cueing RUN --out RUN (the run by its
    # platform commands), simulate runs/s.toml --out runs (the scenario with the old
    # result), estimate LOG --out LOG, excite and design --handlebar HB --out HB (the
    # parameter file by a log or a design file). Without --overwrite the same refusal comes
    # first, not advice to give --overwrite
    import numpy as np

    from motosim.io.results import ResultWriter

    run = tmp_path / "run"
    with ResultWriter(run, ("t", "theta_h"), {"seed": 1}) as writer:
        writer.append(np.array([[0.0, 0.1], [0.01, 0.2]]))
        writer.close({})
    scenario = run / "s.toml"
    scenario.write_text("[scenario]\n", encoding="utf-8")
    log = tmp_path / "log.csv"
    log.write_text("t,theta_h,i_m\n" + "".join(f"{k / 100},0,0\n" for k in range(20)))
    hb = tmp_path / "hb.toml"
    hb.write_bytes(
        (ROOT / "src" / "motosim" / "params" / "data" / "simacom_handlebar.toml").read_bytes()
    )
    argv, expected = {
        "cueing": (["cueing", str(run), "--out", str(run)], f"--out {run} is the result {run}"),
        "simulate": (
            ["simulate", str(scenario), "--out", str(run)],
            f"--out {run} holds the scenario {scenario} it reads; expected another result folder",
        ),
        "run": (
            ["run", str(scenario), "--bus", "virtual", "--out", str(run)],
            f"--out {run} holds the scenario {scenario} it reads; expected another result folder",
        ),
        "estimate": (["estimate", str(log), "--out", str(log)], f"is the log {log} it reads"),
        "excite": (
            ["excite", "--handlebar", str(hb), "--duration", "10", "--out", str(hb)],
            f"--out {hb} is the handlebar file {hb} it reads; expected another file",
        ),
        "design": (["design", "--handlebar", str(hb), "--out", str(hb)], "the handlebar file"),
    }[command]
    for extra in ([], ["--overwrite"]):
        assert main([*argv, *extra]) == 2
        _refused(capsys, expected)
    assert scenario.is_file() and (run / "result.h5").is_file() and log.is_file()
    assert "[set]" in hb.read_text(encoding="utf-8")  # still the parameter file


@pytest.mark.parametrize("existing", ["base.toml", "base_true_handlebar.toml"])
def test_campaign_write_scenario_never_replaces_a_file(
    existing: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # --write-scenario base.toml replaced the campaign's own base scenario, silently (the
    # command has no --overwrite), and its true handlebar file beside it
    (tmp_path / existing).write_text("kept", encoding="utf-8")
    target = tmp_path / "base.toml"
    argv = ["campaign", str(tmp_path / "c.toml"), "--out", str(tmp_path / "k")]
    assert main([*argv, "--rerun", "abc", "--write-scenario", str(target)]) == 2
    _refused(capsys, f"{tmp_path / existing} exists; expected a new file name")
    assert (tmp_path / existing).read_text(encoding="utf-8") == "kept"
