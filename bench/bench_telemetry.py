"""Telemetry and the view: what the loop pays per period, how late the pose is, how fast it draws.

- ``ring_push_us``: one row of every recorded signal into :class:`TelemetryRing` (the only
  thing the loop does for telemetry; target <= 5 us), against the baselines of sending that
  row from inside the loop: an esmini UDP packet, a PlotJuggler JSON datagram, a
  ``foxglove-sdk`` JSON message.
- ``pose_latency_ms``: a thread writes rows stamped with the clock into a ring at 1 kHz (the
  loop); a WebSocket client of ``/ws/pose`` measures how old each pose is when it arrives
  (the server sends the newest row at 60 Hz, so about half a period on average).
- ``view_fps``: requestAnimationFrame count of the rider's view over a wall-clock window
  (``performance.now()``) in headless Chromium (SwiftShader, software WebGL, on this
  machine's 2 shared cores), when chromium is there: fixed scales (``scale=1``,
  ``scale=0.5``), each also with ``sync=1`` (one pixel read back after each frame, so only
  finished frames count: close to the plain figure, the count is honest), and the default,
  measured once it has adapted (``_adaptive``, with the scale it settled on,
  ``_adaptive_scale``); ``load1``: the load average meanwhile.
"""

import json
import os
import socket
import sys
import threading
import time
from pathlib import Path

import numpy as np

from motosim.io.telemetry import (
    PlotJugglerUdp,
    TelemetryRing,
    esmini_packet,
    pose_of,
)
from motosim.signals import RECORDED
from motosim.timeseries import TimeSeries
from timing import best

N = 20_000


def _per_row_us(fn: object, rows: np.ndarray) -> float:
    def loop() -> None:
        for row in rows:
            fn(row)  # type: ignore[operator]

    return 1e6 * best(loop, repeat=5) / rows.shape[0]


def _loop_costs() -> dict[str, float]:
    rows = np.random.default_rng(0).normal(size=(N, len(RECORDED)))
    ring = TelemetryRing(RECORDED, 4096)
    out: dict[str, float] = {"ring_push_us": _per_row_us(ring.push, rows)}
    block = rows[:20]

    def blocks() -> None:
        for _ in range(N // 20):
            ring.push_block(block)

    out["ring_push_block_of_20_us_per_row"] = 1e6 * best(blocks, repeat=5) / N
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sink:
        sink.bind(("127.0.0.1", 0))
        port = sink.getsockname()[1]
        udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        address = ("127.0.0.1", port)
        out["inline_esmini_udp_us"] = _per_row_us(
            lambda row: udp.sendto(esmini_packet(0, pose_of(RECORDED, row)), address), rows[:2000]
        )
        pj = PlotJugglerUdp("127.0.0.1", port, every=1)
        out["inline_plotjuggler_udp_us"] = _per_row_us(
            lambda row: pj.send(RECORDED, row[None, :]), rows[:2000]
        )
        pj.close()
        udp.close()
    try:
        import foxglove

        channel = foxglove.Channel("/bench", schema={"type": "object"})
        out["inline_foxglove_json_us"] = _per_row_us(
            lambda row: channel.log(dict(zip(RECORDED, row.tolist(), strict=True))), rows[:2000]
        )
    except ImportError:
        pass
    return out


def _fake_run() -> TimeSeries:
    t = np.arange(0.0, 30.0, 0.001)
    names = ("x", "y", "psi", "phi", "delta", "v_x", "theta_h")
    wave = np.sin(t)
    data = np.column_stack(
        [20 * t, 2 * np.sin(0.3 * t), 0.03 * np.cos(0.3 * t), 0.2 * wave, 0.01 * wave, 20 + 0 * t]
    )
    data = np.column_stack([data, 0.01 * wave])
    return TimeSeries(t, data, names)


def _pose_latency() -> dict[str, float]:
    from websockets.sync.client import connect

    from motosim.view.app import ServerThread, create_app
    from motosim.view.feeds import LiveFeed, road_from_xy

    class Control:
        def arm(self) -> None: ...

        def stop(self) -> None: ...

        def state(self) -> str:
            return "running"

    names = ("t", "x", "y", "psi", "phi", "delta", "v_x")
    ring = TelemetryRing(names, 4096)
    t0 = time.monotonic()
    stop = threading.Event()

    def writer() -> None:  # the loop: 1 kHz rows stamped with the clock
        next_time = time.monotonic()
        while not stop.is_set():
            ring.push(np.array([time.monotonic() - t0, 0, 0, 0, 0, 0, 20.0]))
            next_time += 1e-3
            time.sleep(max(0.0, next_time - time.monotonic()))

    thread = threading.Thread(target=writer, daemon=True)
    thread.start()
    app = create_app(
        LiveFeed(ring, Control()),
        road_from_xy(np.array([0.0, 10]), np.zeros(2)),
        token="bench-token",
    )
    ages = []
    with ServerThread(app) as server, connect(f"ws://127.0.0.1:{server.port}/ws/pose") as ws:
        for _ in range(300):
            message = json.loads(ws.recv(timeout=5))
            ages.append(time.monotonic() - t0 - message["pose"]["t"])
    stop.set()
    thread.join()
    a = 1e3 * np.array(ages[30:])
    return {
        "pose_latency_ms_mean": float(a.mean()),
        "pose_latency_ms_p99": float(np.percentile(a, 99)),
    }


def _fps() -> dict[str, float]:
    sys.path.insert(0, str(Path(__file__).parents[1] / "tests" / "integration"))
    import tempfile

    from browser import CHROMIUM, Browser

    from motosim.view.app import ServerThread, create_app
    from motosim.view.feeds import ReplayFeed, road_from_xy

    if CHROMIUM is None:
        return {}
    run = _fake_run()
    feed = ReplayFeed(run)
    app = create_app(feed, road_from_xy(run["x"], run["y"]), token="bench-token")
    out = {}
    with ServerThread(app) as server, tempfile.TemporaryDirectory() as profile:
        feed.arm()
        for width, height, query in (
            (1280, 720, "scale=1"),
            (1280, 720, "scale=1&sync=1"),  # each frame waited for: finished frames only
            (1280, 720, "scale=0.5"),
            (1280, 720, "scale=0.5&sync=1"),
            (1280, 720, ""),  # the default: no antialiasing, the scale adapts
        ):
            url = f"{server.url}/?{query}"
            browser = Browser(url, Path(profile) / f"{len(query)}", (width, height))
            try:
                browser.wait_for("window.motosimStats && motosimStats.frames > 5")
                time.sleep(8.0 if not query else 1.0)  # the default adapts within ~6 s
                f0, t0 = browser.evaluate("[motosimStats.frames, performance.now()]")
                time.sleep(5.0)
                f1, t1 = browser.evaluate("[motosimStats.frames, performance.now()]")
                key = f"view_fps_{width}x{height}" + (f"_{query}" if query else "_adaptive")
                out[key] = 1e3 * (f1 - f0) / (t1 - t0)
                if not query:
                    out[f"{key}_scale"] = float(browser.evaluate("motosimStats.scale"))
                    out["load1"] = os.getloadavg()[0]
            finally:
                browser.close()
    return out


def run() -> dict[str, float]:
    """The loop's cost per period, the pose's age on arrival, the view's frame rate."""
    out = _loop_costs()
    try:
        out.update(_pose_latency())
        out.update(_fps())
    except ImportError:  # the optional group view is not installed
        pass
    return out


if __name__ == "__main__":
    for key, value in run().items():
        print(f"{key:<40} {value:.4g}")
