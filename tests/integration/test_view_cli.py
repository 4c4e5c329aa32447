"""``motosim telemetry`` and ``motosim view`` from the command line."""

import json
import socket
import struct
import subprocess
import sys
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from motosim.cli.main import main
from motosim.io.results import ResultWriter
from motosim.io.telemetry import ESMINI_FORMAT

pytest.importorskip("mcap", reason="MCAP export is in the optional group view")

NAMES = ("t", "x", "y", "psi", "phi", "delta", "v_x", "tau_r")


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    """A small result folder (0.5 s at 100 Hz, riding straight at 20 m/s)."""
    t = np.arange(51) * 0.01
    rows = np.column_stack([t, 20 * t, 0 * t, 0 * t, 0.01 * t, 0 * t, 20 + 0 * t, np.sin(t)])
    out = tmp_path / "run"
    with ResultWriter(out, NAMES, {"scenario": {"name": "straight"}}) as writer:
        writer.append(rows)
        writer.close({})
    return out


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as info:
        sys.exit(main(list(argv)))
    out, err = capsys.readouterr()
    return int(info.value.code or 0), out, err


def test_telemetry_writes_an_mcap_the_reader_opens(
    capsys: pytest.CaptureFixture[str], folder: Path, tmp_path: Path
) -> None:
    from mcap.reader import make_reader

    code, out, _ = _run(capsys, "telemetry", str(folder), "--mcap", str(tmp_path / "r.mcap"))
    assert code == 0 and "102 messages" in out
    with (tmp_path / "r.mcap").open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        assert summary.statistics.message_count == 102
        rows = [json.loads(m.data) for _, c, m in reader.iter_messages(topics=["/motosim/signals"])]
    assert rows[-1]["tau_r"] == pytest.approx(np.sin(0.5))


def test_telemetry_keeps_one_row_in_every(
    capsys: pytest.CaptureFixture[str], folder: Path, tmp_path: Path
) -> None:
    from mcap.reader import make_reader

    # --every 10 of the 51 rows: rows 0, 10, ..., 50, each a signals and a pose message
    code, out, _ = _run(
        capsys, "telemetry", str(folder), "--mcap", str(tmp_path / "r.mcap"), "--every", "10"
    )
    assert code == 0 and "12 messages" in out
    with (tmp_path / "r.mcap").open("rb") as stream:
        reader = make_reader(stream)
        rows = [json.loads(m.data) for _, c, m in reader.iter_messages(topics=["/motosim/signals"])]
    assert [row["tau_r"] for row in rows] == pytest.approx(np.sin(np.arange(6) * 0.1))


def test_telemetry_streams_plotjuggler_json(
    capsys: pytest.CaptureFixture[str], folder: Path
) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        sock.settimeout(5.0)
        port = sock.getsockname()[1]
        code, out, _ = _run(
            capsys, "telemetry", str(folder), "--plotjuggler", f"127.0.0.1:{port}", "--rate", "10"
        )
        first = json.loads(sock.recv(65536))
    # one JSON object per row, its time as PlotJuggler's "timestamp", every signal by name
    assert code == 0 and "streamed 51 rows" in out
    assert first["timestamp"] == 0.0 and set(NAMES) - {"t"} <= set(first)


def test_telemetry_streams_esmini_packets(capsys: pytest.CaptureFixture[str], folder: Path) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        sock.settimeout(5.0)
        port = sock.getsockname()[1]
        code, out, _ = _run(
            capsys, "telemetry", str(folder), "--esmini", f"127.0.0.1:{port}", "--rate", "10"
        )
        packets = [sock.recv(1024) for _ in range(3)]
    assert code == 0 and "streamed 51 rows" in out
    assert [struct.unpack(ESMINI_FORMAT, p)[3] for p in packets] == [0, 1, 2]  # frame numbers


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (("telemetry", "{folder}"), "nothing to do"),
        (("telemetry", "{folder}", "--esmini", ":12"), "expected HOST"),
        (("telemetry", "{folder}/nope", "--mcap", "x.mcap"), "no such result folder"),
        (("view", "{folder}", "--port", "70000"), "--port 70000"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    capsys: pytest.CaptureFixture[str], folder: Path, argv: tuple[str, ...], message: str
) -> None:
    code, _, err = _run(capsys, *(a.format(folder=folder) for a in argv))
    assert code == 2 and message in err and err.count("\n") == 1


def test_view_serves_the_result_until_interrupted(folder: Path, tmp_path: Path) -> None:
    pytest.importorskip("uvicorn", reason="the view server is in the optional group view")
    # the platform commands of motosim cueing (at 50 Hz) and what motosim run records
    cueing = tmp_path / "cueing"
    t = np.arange(26) * 0.02
    with ResultWriter(cueing, ("t", "phi_s", "theta_s", "psi_s", "phi_vis"), {}) as writer:
        writer.append(np.column_stack([t, 0.1 * t, 0 * t, 0 * t, 0 * t]))
        writer.close({})
    timing = {
        "timing": {"served": 51, "missed": 0},
        "state": "IDLE",
        "fault": "NONE",
        "fault_reason": "no fault",
    }
    (folder / "timing.json").write_text(json.dumps(timing), encoding="utf-8")
    argv = ["view", str(folder), "--port", "0", "--cueing", str(cueing)]
    with subprocess.Popen(
        [sys.executable, "-m", "motosim.cli.main", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    ) as process:
        try:
            assert process.stdout is not None
            line = process.stdout.readline()
            assert line.startswith("rider's view: http://127.0.0.1:") and "?token=" in line
            base, token = line.split()[-1].split("/?token=")
            with urllib.request.urlopen(f"{base}/api/info") as answer:
                info = json.load(answer)
            assert info["title"] == "straight" and info["status"]["state"] == "paused"
            assert {"phi_s", "theta_s", "psi_s", "phi_vis"} <= set(info["dashboard"])
            assert info["recorded"] == timing
            request = urllib.request.Request(
                f"{base}/api/control",
                data=b'{"action": "arm"}',
                headers={"X-Motosim-Token": token, "Content-Type": "application/json"},
            )
            with urllib.request.urlopen(request) as answer:
                assert json.load(answer)["status"]["state"] in ("playing", "ended")
        finally:
            process.terminate()
            process.communicate(timeout=10)
