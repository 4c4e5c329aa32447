"""What a user sees of ``motosim run`` and ``motosim rig``: a line while the stack loads and
when it is ready, the rig's readiness and what it receives, exit 130 on Ctrl-C."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from motosim.cli.main import main

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"

pytest.importorskip("can", reason="motosim run and rig need the rt group (python-can)")


def test_run_says_the_stack_is_loading_and_when_it_is_ready(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # no drive on this process's own virtual bus: 0.5 s idle (under the 1 s NO_DRIVE
    # timeout), exit 0
    code = main(
        [
            "run",
            str(SCENARIOS / "realtime_square.toml"),
            "--bus",
            "virtual",
            "--out",
            str(tmp_path / "run"),
            "--duration",
            "0.5",
            "--telemetry",
            "off",
            "--no-report",
        ]
    )
    err = capsys.readouterr().err.splitlines()
    assert code == 0, err
    lines = [line for line in err if line.startswith("motosim run: ")]
    assert lines[0] == "motosim run: loading the compiled stack ..."
    assert lines[1].startswith("motosim run: the stack is ready (") and lines[1].endswith(" s)")
    assert lines[2] == "motosim run: 1000 Hz on virtual, paced by the clock, 0.5 s"


def test_rig_says_when_it_is_ready_and_exits_130_on_ctrl_c() -> None:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "motosim.cli.main",
            "rig",
            str(SCENARIOS / "realtime_square.toml"),
            "--bus",
            "virtual",
            "--duration",
            "300",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    assert proc.stderr is not None
    seen = []
    try:
        end = time.monotonic() + 240
        while time.monotonic() < end:
            line = proc.stderr.readline()
            if not line:
                break
            seen.append(line.strip())
            if line.startswith("motosim rig: ready"):
                break
        assert seen and seen[-1].startswith("motosim rig: ready on virtual ("), seen
        assert "1000 Hz ticks, status frames at 100 Hz; Ctrl-C stops" in seen[-1]
        assert seen[0] == "motosim rig: loading the virtual rig ..."
        time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 130
    assert out.startswith("rig: ") and "status frames sent" in out  # its summary, then 130


def test_the_rig_tells_its_first_command_then_a_count_every_few_seconds(
    capsys: pytest.CaptureFixture[str],
) -> None:
    from motosim.cli.rig import _Received

    rig = SimpleNamespace(t=0.0, commands=0, frames_sent=0)
    received = _Received(rig)
    for k in range(12_000):  # 12 s of 1 kHz ticks; the commands come from 1.5 s on
        rig.t = k / 1000.0
        rig.commands = max(0, k - 1500)
        rig.frames_sent = k // 10
        received.tick()
    err = capsys.readouterr().err.splitlines()
    assert err == [
        "motosim rig: first command frame at t = 1.501 s",
        "motosim rig: t = 5 s, 3500 commands received, 500 status frames sent",
        "motosim rig: t = 10 s, 8500 commands received, 1000 status frames sent",
    ]
