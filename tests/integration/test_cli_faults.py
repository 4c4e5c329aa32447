"""The faults of issue 16 re-run through the command line.

SIGTERM during ``motosim simulate``, a second ``--overwrite`` run on a folder being written, a
full disk, a run that falls and then diverges, a lane change outside the virtual rider's
speeds. Each ends with its exit code and one line; no result is lost or left unreadable.
"""

import csv
import os
import signal
import subprocess
import sys
import time
import unittest.mock
from collections.abc import Callable
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pytest

from motosim.cli.main import main
from motosim.errors import RunFailedError
from motosim.io.files import FolderLock, lock_file
from motosim.io.results import load_result, partial_folder
from motosim.sim import SIGNALS

ROOT = Path(__file__).parents[2]


def _long_scenario(tmp_path: Path, duration: float = 200.0) -> Path:
    text = (ROOT / "scenarios" / "paper" / "fig11_nominal.toml").read_text(encoding="utf-8")
    path = tmp_path / "long.toml"
    path.write_text(text.replace("duration = 8.0", f"duration = {duration}"), encoding="utf-8")
    return path


def _start(scenario: Path, out: Path, *extra: str) -> subprocess.Popen[str]:
    """``motosim simulate`` in a child process, returned once its first rows are written."""
    child = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "motosim",
            "simulate",
            str(scenario),
            "--out",
            str(out),
            "--no-report",
            *extra,
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 120.0
    rows = partial_folder(out) / "result.partial.csv"
    while time.monotonic() < deadline and child.poll() is None:
        if rows.exists() and rows.stat().st_size > 50_000:
            return child
        time.sleep(0.1)
    child.kill()
    raise AssertionError(f"the run did not start: {child.communicate()}")


def _upright(tmp_path: Path, control: float = 1000.0) -> Path:
    """Upright for 600 s (no torque, the paper's controller): a run that writes for minutes."""
    path = tmp_path / "still.toml"
    path.write_text(
        f'[scenario]\nname = "still"\nduration = 600.0\n[rates]\ncontrol = {control}\n'
        f'measurement = {control}\n[rider]\nkind = "torque"\n'
        'profile = { kind = "constant", value = 0.0 }\n[controller]\nkind = "paper"\n',
        encoding="utf-8",
    )
    return path


def test_sigterm_during_simulate_keeps_a_plainly_readable_partial_result(tmp_path: Path) -> None:
    out = tmp_path / "run"
    child = _start(_upright(tmp_path), out)
    child.send_signal(signal.SIGTERM)
    _, err = child.communicate(timeout=60)
    assert child.returncode == 130, err
    assert err.count("\n") == 1 and err.startswith("motosim: interrupted; the partial result is")
    with h5py.File(out / "result.h5", "r") as h5:  # plain h5py, no SWMR
        rows = h5["signals"].shape[0]
        assert rows > 0 and not h5.attrs["complete"]
    with (out / "result.partial.csv").open(newline="") as handle:  # the name says partial
        table = list(csv.reader(handle))
    assert table[0] == list(SIGNALS) and len(table) - 1 == rows
    assert load_result(out).t.size == rows
    # nothing blocks a rerun
    assert (
        main(
            [
                "simulate",
                str(_long_scenario(tmp_path, 0.5)),
                "--out",
                str(out),
                "--no-report",
                "--overwrite",
            ]
        )
        == 0
    )


def test_a_second_overwrite_run_on_a_folder_being_written_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    scenario = _upright(tmp_path)
    child = _start(scenario, out)
    try:
        code = main(["simulate", str(scenario), "--out", str(out), "--overwrite", "--no-report"])
        err = capsys.readouterr().err
    finally:
        child.send_signal(signal.SIGTERM)
        child.communicate(timeout=60)
    assert code == 2 and err.count("\n") == 1
    assert f"another run (pid {child.pid}) is writing this result" in err
    assert load_result(out).t.size > 0  # the first run's rows, not interleaved


def test_a_full_disk_is_one_line_and_keeps_the_rows(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import shutil

    real = shutil.disk_usage
    calls = {"n": 0}

    def filling(path: Any) -> Any:  # plenty of space at the start, 1 MB after a few blocks
        calls["n"] += 1
        usage = real(path)
        return usage if calls["n"] < 4 else usage._replace(free=1_000_000)

    monkeypatch.setattr(shutil, "disk_usage", filling)
    out = tmp_path / "run"
    code = main(["simulate", str(_long_scenario(tmp_path, 20.0)), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "the disk is full" in err, err
    assert "rows (t <= " in err and f"kept in {out}" in err
    assert load_result(out).t.size > 0 and not load_result(out).complete


def test_the_paper_run_lengthened_to_600_s_stops_at_the_fall(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # The case: fig11_nominal's square rider torque with nobody balancing the machine
    # passes 45 deg of roll near 53 s; the run stops there instead of integrating on to a
    # divergence, keeps its rows, closes its files with the flag, and its report says so.
    out = tmp_path / "run"
    code = main(["simulate", str(_long_scenario(tmp_path, 600.0)), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 3 and err.count("\n") == 1, err
    assert err.startswith("motosim: run failed: fig11_nominal: the motorcycle fell at t = ")
    assert "deg, beyond 45 deg" in err and "the run stopped there" in err
    result = load_result(out)
    fell = float(err.split("fell at t = ")[1].split(" s")[0])
    assert 20.0 < fell < 100.0 and result.t[-1] == pytest.approx(fell, abs=1e-3)
    assert abs(result["phi"][-1]) > np.radians(45.0) > np.max(np.abs(result["phi"][:-1]))
    assert result.summary["flag_fall"] == 1.0 and result.summary["complete"] == 0.0
    assert "fell at t" in result.summary["failure"]
    with h5py.File(out / "result.h5", "r") as h5:  # closed: plain h5py reads it
        assert h5["signals"].shape[0] == result.t.size
    assert "run failed: the motorcycle fell" in (out / "report.html").read_text(encoding="utf-8")


def _diverging(inputs: Any, *, rng: Any, on_block: Callable[..., None], **_: Any) -> Any:
    """Stands in for the simulation: 100 rows, then a divergence at t = 0.1 s."""
    block = np.zeros((100, len(SIGNALS)))
    block[:, 0] = np.arange(100) * 1e-3
    on_block(block)
    raise RunFailedError("the simulation diverged at t = 0.1 s (phi not finite)", time=0.1)


def test_a_divergence_is_exit_3_naming_the_time_with_the_rows_kept(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    with unittest.mock.patch("motosim.io.runs.simulate", _diverging):
        code = main(["simulate", str(_long_scenario(tmp_path, 1.0)), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 3 and err.count("\n") == 1, err
    assert err.startswith("motosim: run failed: fig11_nominal: the simulation diverged at t = 0.1")
    assert f"the 100 rows computed are kept in {out}, marked partial" in err
    assert load_result(out).t.size == 100 and not load_result(out).complete


def _variant(tmp_path: Path, name: str, old: str, new: str) -> Path:
    text = (ROOT / "scenarios" / name).read_text(encoding="utf-8")
    assert old in text
    path = tmp_path / name
    path.write_text(text.replace(old, new), encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("name", "old", "new", "expected"),
    [
        # braking at 0.5 g from 25 m/s for 10 s: below 3 m/s after about 4.5 s of braking
        ("emergency_braking.toml", "duration = 6.0", "duration = 12.0", "2.99"),
        # a drive torque that takes the virtual rider above 60 m/s, its highest scheduled speed
        (
            "straight_50_gust.toml",
            'drive_torque = { kind = "steps", times = [5.0], values = [150.0] }',
            'drive_torque = { kind = "constant", value = 1500.0 }',
            "60.0",
        ),
    ],
)
def test_a_run_that_leaves_the_models_speeds_stops_with_exit_3(
    name: str,
    old: str,
    new: str,
    expected: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    out = tmp_path / "run"
    code = main(["simulate", str(_variant(tmp_path, name, old, new)), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 3 and err.count("\n") == 1, err
    assert "the speed left the model's range at t = " in err
    assert f": {expected}" in err and "outside 3 to 60 m/s" in err
    result = load_result(out)
    assert result.summary["flag_out_of_range"] == 1.0 and result.t.size < 7000  # of 8000 or 12000
    assert "run failed: the speed left" in (out / "report.html").read_text(encoding="utf-8")


def test_a_motor_saturated_most_of_the_run_is_exit_3(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # a 0.2 A current limit against a +-20 N*m square: the motor at its limit most of the time
    path = tmp_path / "saturated.toml"
    path.write_text(
        '[scenario]\nname = "saturated"\nduration = 4.0\n[rider]\nkind = "torque"\n'
        'profile = { kind = "square", low = -20.0, high = 20.0, period = 2.0 }\n'
        'hands = "off"\n'  # the square alone against the limit, no arms' spring to help
        '[controller]\nkind = "paper"\nmax_current = 0.2\n',
        encoding="utf-8",
    )
    out = tmp_path / "run"
    code = main(["simulate", str(path), "--out", str(out), "--no-report"])
    err = capsys.readouterr().err
    assert code == 3 and err.count("\n") == 1, err
    assert "the motor current was at its limit" in err and "% of the time" in err
    result = load_result(out)
    assert result.complete and result.summary["flag_saturation"] == 1.0
    assert result.t.size == 4000  # saturation does not stop a run: it is judged at the end


@pytest.mark.parametrize("speed", ["1.0", "100.0"])
def test_a_lane_change_outside_the_riders_speeds_is_refused(
    speed: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (ROOT / "scenarios" / "lane_change_20.toml").read_text(encoding="utf-8")
    path = tmp_path / "lc.toml"
    path.write_text(text.replace("speed = 20.0", f"speed = {speed}"), encoding="utf-8")
    assert main(["simulate", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "expected 3 to 60 m/s with the virtual rider" in err
    assert not os.path.exists(tmp_path / "out")


def _second_run(argv: list[str]) -> tuple[int, str]:
    """``motosim argv`` in another process, as a second user starts it: its code and stderr."""
    done = subprocess.run(
        [sys.executable, "-m", "motosim", *argv], capture_output=True, text=True, timeout=300
    )
    return done.returncode, done.stderr


def test_simulate_holds_the_folder_until_its_report_is_written(tmp_path: Path) -> None:
    # the report was written after the lock was released: a concurrent --overwrite of the
    # same folder could replace the result under the report being built from it
    import motosim.report

    out = tmp_path / "run"
    scenario = _long_scenario(tmp_path, 0.2)
    second = ["simulate", str(scenario), "--out", str(out), "--overwrite", "--no-report"]
    seen: list[tuple[int, str]] = []
    real = motosim.report.build_report

    def build_report(folder: Path, **options: Any) -> Path:
        seen.append(_second_run(second))  # while the first writes its report
        return real(folder, **options)

    with unittest.mock.patch.object(motosim.report, "build_report", build_report):
        assert main(["simulate", str(scenario), "--out", str(out)]) == 0
    [(code, err)] = seen
    assert code == 2 and err.count("\n") == 1, err
    assert f"another run (pid {os.getpid()}) is writing this result" in err
    assert (out / "report.html").is_file() and load_result(out).complete
    code, err = _second_run(second)  # once the first has ended
    assert code == 0, err


def test_cueing_holds_the_folder_until_its_figures_are_written(tmp_path: Path) -> None:
    # the same for cueing's figures, written beside its commands
    import motosim.cli.cueing

    out = tmp_path / "cue"
    simulated = tmp_path / "run"
    assert (
        main(
            ["simulate", str(_long_scenario(tmp_path, 1.0)), "--out", str(simulated), "--no-report"]
        )
        == 0
    )
    second = ["cueing", str(simulated), "--out", str(out), "--overwrite"]
    seen: list[tuple[int, str]] = []
    real = motosim.cli.cueing.save_figure

    def save_figure(figure: Any, path: str) -> Any:
        if not seen:
            seen.append(_second_run(second))  # while the first writes its figures
        return real(figure, path)

    with unittest.mock.patch.object(motosim.cli.cueing, "save_figure", save_figure):
        assert main(["cueing", str(simulated), "--out", str(out)]) == 0
    [(code, err)] = seen
    assert code == 2 and err.count("\n") == 1, err
    assert f"another run (pid {os.getpid()}) is writing this result" in err
    assert (out / "perception.png").is_file() and (out / "commands.png").is_file()


def test_a_campaign_stopped_by_a_full_disk_is_read_as_stopped_and_resumes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # the manifest said "running" after a full disk stopped the campaign: its last write
    # fails on the same full disk. "running" is true only while a process holds the folder's
    # lock: read with read_manifest (as the report and a resume read it), it says "stopped".
    # The disk here is --out itself: it fills up as the second part is written (the series,
    # another program); a write that takes more than there is fails with ENOSPC, and
    # deleting a file frees its size
    import errno
    import json

    import motosim.campaign.results
    from motosim.campaign import load_results, read_manifest

    (tmp_path / "base.toml").write_text(
        '[scenario]\nname = "base"\nduration = 0.2\n[rider]\nkind = "torque"\n'
        'profile = { kind = "constant", value = 1.0 }\n[controller]\nkind = "paper"\n',
        encoding="utf-8",
    )
    values = ", ".join(f"{0.8 + 0.01 * k:.2f}" for k in range(40))
    campaign = tmp_path / "c.toml"
    campaign.write_text(
        '[campaign]\nname = "c"\nscenario = "base.toml"\nsampling = "grid"\nseed = 1\n'
        f'task_seconds = 0.01\n[factors]\n"handlebar.inertia_factor" = [{values}]\n',
        encoding="utf-8",
    )
    out = tmp_path / "out"

    def used() -> int:
        return sum(p.stat().st_size for p in out.rglob("*") if p.is_file())

    capacity = [float("inf")]
    parts = [0]
    real = motosim.campaign.results.write_whole

    def on_the_disk(path: Path, write: Callable[[Path], object]) -> Path:
        def write_within(temporary: Path) -> None:
            if Path(path).name.startswith("part-"):
                parts[0] += 1
                if parts[0] == 2:
                    capacity[0] = used()  # full from here on
            write(temporary)
            if used() > capacity[0]:
                raise OSError(errno.ENOSPC, "No space left on device")

        return real(path, write_within)

    argv = ["campaign", str(campaign), "--out", str(out), "--no-report", "--jobs", "1"]
    with unittest.mock.patch.object(motosim.campaign.results, "write_whole", on_the_disk):
        code = main(argv)
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "No space left on device" in err, err
    in_file = json.loads((out / "manifest.json").read_text(encoding="utf-8"))
    assert in_file["status"] == "running"  # its last write failed on the full disk
    assert read_manifest(out)["status"] == "stopped"  # no process holds the lock
    assert 0 < len(load_results(out)["run_id"]) < 40  # the parts written before the disk filled
    assert not [p.name for p in out.iterdir() if p.name.startswith(".")]  # no cut file
    assert main(argv) == 0  # resumed once there is room: complete
    manifest = read_manifest(out)
    assert manifest["status"] == "complete" and "error" not in manifest
    assert manifest["written"] == 40


def test_run_holds_the_folder_until_its_timing_and_report_are_written(tmp_path: Path) -> None:
    # the writer process released the lock when it closed the result; timing.json and the
    # report came after, in motosim run's process: a concurrent --overwrite of the same
    # folder could replace the result under them. The virtual bus is this process's own
    # (no drive answers on it: 0.5 s idle, exit 0)
    pytest.importorskip("can", reason="motosim run needs the rt group (python-can)")
    import motosim.cli.run
    import motosim.report

    out = tmp_path / "run"
    second = [
        "simulate",
        str(_long_scenario(tmp_path, 0.2)),
        "--out",
        str(out),
        "--overwrite",
        "--no-report",
    ]
    seen: dict[str, tuple[int, str]] = {}
    real_write = motosim.cli.run.write_text
    real_report = motosim.report.build_report

    def write_text(path: Path, text: str) -> Any:
        if path.name == "timing.json":
            seen["timing.json"] = _second_run(second)  # the first file beside the rows
        return real_write(path, text)

    def build_report(folder: Path) -> Path:
        seen["report"] = _second_run(second)  # the last
        return real_report(folder)

    with (
        unittest.mock.patch.object(motosim.cli.run, "write_text", write_text),
        unittest.mock.patch.object(motosim.report, "build_report", build_report),
    ):
        code = main(
            [
                "run",
                str(ROOT / "scenarios" / "realtime_square.toml"),
                "--bus",
                "virtual",
                "--out",
                str(out),
                "--duration",
                "0.5",
                "--telemetry",
                "off",
            ]
        )
    assert code == 0
    assert list(seen) == ["timing.json", "report"]
    for what, (code, err) in seen.items():
        assert code == 2 and err.count("\n") == 1, (what, err)
        assert "another run (pid " in err and "is writing this result" in err, (what, err)
    assert (out / "timing.json").is_file() and (out / "report.html").is_file()
    assert load_result(out).metadata["realtime"]["bus"] == "virtual"  # the run's, not replaced
    assert not lock_file(out).exists()
    with FolderLock(out):  # released once the report is written
        pass


def test_run_ends_at_once_when_its_folder_gains_a_file_of_another_kind(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    # a file dropped into the result folder while run writes it: the writer process's close
    # refuses to replace the folder; motosim run says so at once, in one line naming where
    # the rows are, without waiting for the writer or printing its traceback (capfd: the
    # writer's stderr too)
    pytest.importorskip("can", reason="motosim run needs the rt group (python-can)")
    import threading

    out = tmp_path / "run"
    staging = partial_folder(out)
    ended = threading.Event()

    def drop() -> None:  # once the writer has opened the result (the loop starts then)
        while not ended.is_set():
            if staging.is_dir():
                out.mkdir(exist_ok=True)
                (out / "notes.txt").write_text("mine\n", encoding="utf-8")
                return
            time.sleep(0.005)

    thread = threading.Thread(target=drop)
    thread.start()
    begun = time.monotonic()
    try:
        code = main(
            [
                "run",
                str(ROOT / "scenarios" / "realtime_square.toml"),
                "--bus",
                "virtual",
                "--out",
                str(out),
                "--duration",
                "0.9",
                "--telemetry",
                "off",
            ]
        )
    finally:
        ended.set()
        thread.join()
    took = time.monotonic() - begun
    err = capfd.readouterr().err
    assert code == 2, err
    lines = [line for line in err.splitlines() if line.startswith("motosim: error")]
    assert len(lines) == 1 and "Traceback" not in err, err
    assert "holds files that are not a motosim result" in lines[0], err
    assert f"the complete result is in {staging}" in lines[0], err
    assert took < 60.0, took  # not the 120 s wait for an answer that never came
    assert (out / "notes.txt").read_text(encoding="utf-8") == "mine\n"  # left as it is
    result = load_result(staging)  # the rows where the line says
    assert result.complete and result.t.size > 100
    assert result.metadata["realtime"]["bus"] == "virtual"
    assert not lock_file(out).exists()
