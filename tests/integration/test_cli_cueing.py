"""`motosim cueing` end to end on a small recorded run."""

import json
from pathlib import Path

import numpy as np
import pytest

from motosim.cli.main import main
from motosim.io.results import ResultWriter, load_result


@pytest.fixture
def run_dir(tmp_path: Path) -> Path:
    t = np.arange(0.0, 4.0, 0.001)
    phi = np.radians(15.0) * np.sin(0.5 * np.pi * t)
    names = ("t", "v_x", "v_y", "psi_dot", "phi_dot", "phi")
    data = np.column_stack(
        [t, 15.0 + 0 * t, 0 * t, 9.81 * np.tan(phi) / 15.0, np.gradient(phi, t), phi]
    )
    folder = tmp_path / "run"
    with ResultWriter(folder, names, {"scenario": {"name": "weave"}}) as writer:
        writer.append(data)
        writer.close({})
    return folder


def test_cueing_writes_commands_figures_and_json(run_dir: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "cue"
    assert main(["cueing", str(run_dir), "--out", str(out), "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["score"]["violations"] == 0
    commands = load_result(out)
    assert commands.names == ("phi_s", "theta_s", "psi_s", "phi_vis")
    assert commands.t.size == 400  # 100 Hz
    assert (out / "perception.png").is_file() and (out / "commands.png").is_file()
    assert (out / "result.csv").read_text().startswith("t,phi_s,theta_s,psi_s,phi_vis\n")


def test_bad_platform_is_one_line_exit_2(run_dir: Path, tmp_path: Path, capsys) -> None:
    bad = tmp_path / "p.toml"
    bad.write_text("[platform]\nname = 'x'\n")
    assert main(["cueing", str(run_dir), "--platform", str(bad), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "missing table [axes]" in err


def test_a_run_with_skipped_periods_is_refused_naming_the_folder_and_why(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # motosim run records one row per period served: a missed deadline leaves a gap
    t = np.delete(np.arange(0.0, 2.0, 0.001), np.arange(500, 508))
    names = ("t", "v_x", "v_y", "psi_dot", "phi_dot", "phi")
    data = np.column_stack([t, 15.0 + 0 * t, 0 * t, 0 * t, 0 * t, 0 * t])
    folder = tmp_path / "rt"
    with ResultWriter(folder, names, {"scenario": {"name": "rt"}}) as writer:
        writer.append(data)
        writer.close({})
    assert main(["cueing", str(folder), "--out", str(tmp_path / "cue")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(folder) in err
    assert "0.009 s" in err and "missed deadlines" in err


def test_a_disk_too_full_for_the_commands_is_refused_before_writing(
    run_dir: Path, tmp_path: Path, capsys, monkeypatch: pytest.MonkeyPatch
) -> None:
    import shutil

    from motosim.io.results import RESERVE_BYTES

    real = shutil.disk_usage
    monkeypatch.setattr(  # the writer's reserve and 1 kB more: not the 400 rows' 67 kB
        shutil, "disk_usage", lambda path: real(path)._replace(free=RESERVE_BYTES + 1000)
    )
    out = tmp_path / "cue"
    assert main(["cueing", str(run_dir), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    # it said "a run of 0 rows" (the writer was not told the commands' length)
    assert err.count("\n") == 1 and "a run of 400 rows of 5 signals needs" in err, err
    assert not out.exists()
