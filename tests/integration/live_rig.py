"""A live real-time run with the view: ``motosim rig`` and ``motosim run --view`` as two
processes on python-can's ``udp_multicast`` bus, for the browser tests and the lag bench."""

import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from rt_tables import safety_table

# the bus: a multicast group of this module's own, away from python-can's default one that
# other runs on the machine may use
BUS = "udp_multicast:239.74.163.14"

SCENARIO = """
[scenario]
name = "live_view"
description = "a gentle square rider torque at the handlebar; the paper's K(s)"
duration = {duration}

[rider]
kind = "torque"
profile = {{ kind = "square", low = -1.0, high = 1.0, period = 2.0, start = 0.5 }}

[controller]
kind = "paper"

""" + safety_table(100)  # 0.1 s: a busy machine without SCHED_FIFO


@dataclass
class LiveRun:
    """The run's view address and token, and its process."""

    url: str
    token: str
    process: subprocess.Popen[str]
    log: list[str]


def _motosim(*argv: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "motosim.cli.main", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )


def free_udp_port() -> int:
    """A UDP port of 127.0.0.1 free now (for a telemetry address)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def wait_for_status(bus: str, seconds: float) -> None:
    """Return once a rig's status frame (0x101) is heard on ``bus``; TimeoutError after
    ``seconds``."""
    from motosim.io.can import open_link

    with open_link(bus) as link:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            frame = link.receive(0.1)
            if frame is not None and frame[0] == 0x101:
                return
    raise TimeoutError("the rig sent no status frame")


def _end(process: subprocess.Popen[str], reader: threading.Thread | None = None) -> None:
    """Ctrl-C, wait (kill after 30 s), and close its pipes."""
    if process.poll() is None:
        process.send_signal(signal.SIGINT)
    try:
        process.wait(timeout=30.0)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
    if reader is not None:
        reader.join(10.0)
    for pipe in (process.stdout, process.stderr):
        if pipe is not None:
            pipe.close()


@contextmanager
def live_run(folder: Path, duration: float = 60.0) -> Iterator[LiveRun]:
    """Start the rig, then ``motosim run --view`` on it; yield once the view serves."""
    from motosim.io.can import open_link

    open_link(BUS).close()  # MotosimError here if udp_multicast is not available
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "live.toml"
    path.write_text(SCENARIO.format(duration=duration), encoding="utf-8")
    telemetry = f"127.0.0.1:{free_udp_port()}"
    rig = _motosim(
        "rig", str(path), "--bus", BUS, "--duration", str(duration + 60), "--telemetry", telemetry
    )
    run = reader = None
    try:
        wait_for_status(BUS, 60.0)
        run = _motosim(
            "run",
            str(path),
            "--bus",
            BUS,
            "--out",
            str(folder / "run"),
            "--no-report",
            "--telemetry",
            telemetry,
            "--view",
            "--view-port",
            "0",
        )
        assert run.stderr is not None
        log: list[str] = []
        match = None
        while match is None:
            line = run.stderr.readline()
            if not line:
                raise RuntimeError("motosim run ended before serving the view:\n" + "".join(log))
            log.append(line)
            match = re.search(r"rider's view (http://127\.0\.0\.1:\d+)/\?token=(\S+)", line)
        # keep reading its messages (a full pipe would block the writer process)
        stream = run.stderr
        reader = threading.Thread(target=lambda: log.extend(stream), daemon=True)
        reader.start()
        yield LiveRun(match.group(1), match.group(2), run, log)
    finally:
        if run is not None:
            _end(run, reader)
        _end(rig)
