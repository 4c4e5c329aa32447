"""How far the rider's view is behind the real-time loop, and how fast it draws, live.

Starts ``motosim rig`` and ``motosim run --view`` (two processes on python-can's
``udp_multicast`` bus, as a lab runs them without hardware), opens the rider's view in
headless Chromium (Debian's, SwiftShader software WebGL, the flags of
``tests/integration/browser.py``; the run is not armed: the loop steps the whole stack each
period and the virtual motorcycle rides on, the torque stays off) and records, for every
animation frame, the loop-clock time of the sample it drew and when it drew it
(``motosimStats.lags``): the loop stamps each row with its deadline on the machine's monotonic
clock, the page maps ``performance.now()`` onto that clock by the ping with the shortest round
trip over ``/ws/pose``.

- ``lag_ms_p50/p99/max``: drawn minus the time the loop wrote the sample (its deadline plus
  its wake-up latency and compute time), the frames of ``WINDOW`` seconds after a warm-up
  (target: at most one frame plus 20 ms, ``target_ms`` at the measured frame rate);
  ``lag_from_deadline_ms_*``: drawn minus the sample's deadline (adds the loop's own lateness);
- ``server_age_ms_p50/p99``: the part of it before the server sends the pose (loop -> shared
  ring -> writer process every 5 ms -> view ring -> ``/ws/pose``); ``delivery_ms_p50/p99``:
  from the server's send to the page's handling of the message (the rest, up to the frame
  drawn, is the wait for the next animation frame and the frame itself);
- ``fps``: requestAnimationFrame callbacks over the same wall-clock window (each shows the
  newest pose; ``rendered_fps``: those that rendered, the others had no new pose to show;
  ``poses_per_s``: the poses the page received);
- ``scale``: the render scale the view settled on; ``load1_before/after``: the load average;
- ``cpu_ms_per_frame_gpu/renderer/browser``: the CPU time Chromium's GPU process (SwiftShader
  and the display compositor), the page's renderer process and the browser process spent
  per frame over the window (from ``/proc``), the profile of what a frame costs.

Run: ``python bench/run.py view_lag`` (about a minute); skipped without chromium or
python-can. The machine's 2 cores are shared by the loop, the rig, the writer, the browser
and whatever else runs: read the figures with the load average.
"""

import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

WARM_UP = 8.0  # s after the page is up: the render scale settled
WINDOW = 15.0  # s measured


def _chromium_cpu(root: int) -> dict[str, float]:
    """CPU time [ms] of the processes under ``root`` by Chromium process type (Linux /proc)."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    parent = int(f.read().rsplit(")", 1)[1].split()[1])
            except OSError:
                continue
            children.setdefault(parent, []).append(int(entry))
    tick = 1e3 / os.sysconf("SC_CLK_TCK")
    out: dict[str, float] = {}
    todo = [root]
    while todo:
        pid = todo.pop()
        todo += children.get(pid, [])
        try:
            with open(f"/proc/{pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            with open(f"/proc/{pid}/cmdline") as f:
                words = f.read().replace("\0", " ").split()  # Chromium rewrites its titles
        except OSError:
            continue
        kind = next((w.split("=", 1)[1] for w in words if w.startswith("--type=")), "browser")
        out[kind] = out.get(kind, 0.0) + (int(fields[11]) + int(fields[12])) * tick
    return out


def _counters(view: Any) -> tuple[list[float], dict[str, float]]:
    """The page's frames, clock [ms], lags and ages recorded, frames rendered; Chromium's CPU."""
    counts = view.evaluate(
        "[motosimStats.frames, performance.now(), motosimStats.lags.length,"
        " motosimStats.ages.length, motosimStats.rendered]"
    )
    return counts, _chromium_cpu(view.process.pid)


def run() -> dict[str, float]:
    """Lag and frame rate of the rider's view of a live run (empty without the tools)."""
    sys.path.insert(0, str(Path(__file__).parents[1] / "tests" / "integration"))
    try:
        import can  # noqa: F401
        import uvicorn  # noqa: F401
        from browser import CHROMIUM, Browser
        from live_rig import live_run
    except ImportError:
        return {}
    if CHROMIUM is None:
        return {}
    import json
    import urllib.request

    out: dict[str, float] = {"load1_before": os.getloadavg()[0]}
    with tempfile.TemporaryDirectory() as folder:
        with live_run(Path(folder) / "live", duration=WARM_UP + WINDOW + 120.0) as live:
            view = Browser(f"{live.url}/?token={live.token}", Path(folder) / "view")
            try:
                view.wait_for("window.motosimStats && motosimStats.ready", timeout=60)
                time.sleep(WARM_UP)
                (f0, p0, n0, a0, r0), cpu0 = _counters(view)
                time.sleep(WINDOW)
                (f1, p1, n1, a1, r1), cpu1 = _counters(view)
                if live.process.poll() is not None:
                    raise RuntimeError("the run ended early:\n" + "".join(live.log))
                lags = np.array(view.evaluate(f"motosimStats.lags.slice({n0}, {n1})"))
                ages = np.array(view.evaluate(f"motosimStats.ages.slice({a0}, {a1})"))
                offset, rtt, scale = view.evaluate(
                    "[motosimStats.offset, motosimStats.rtt, motosimStats.scale]"
                )
                with urllib.request.urlopen(f"{live.url}/api/lag?window={WINDOW}") as answer:
                    reported = json.load(answer)
            finally:
                view.close()
    out["load1_after"] = os.getloadavg()[0]
    fps = 1e3 * (f1 - f0) / (p1 - p0)
    drawn = lags[:, 1] / 1e3 + offset
    lag = 1e3 * (drawn - lags[:, 0])
    behind_deadline = 1e3 * (drawn - lags[:, 2])
    age = 1e3 * (ages[:, 1] - ages[:, 0])  # written by the loop -> sent by the server
    delivery = 1e3 * (ages[:, 2] / 1e3 + offset - ages[:, 1])  # sent -> handled by the page
    out |= {
        "fps": fps,
        "rendered_fps": 1e3 * (r1 - r0) / (p1 - p0),
        "poses_per_s": 1e3 * (a1 - a0) / (p1 - p0),
        "scale": float(scale),
        "frames": float(lags.shape[0]),
        "lag_ms_p50": float(np.percentile(lag, 50)),
        "lag_ms_p99": float(np.percentile(lag, 99)),
        "lag_ms_max": float(lag.max()),
        "target_ms": 1e3 / fps + 20.0,
        "lag_from_deadline_ms_p50": float(np.percentile(behind_deadline, 50)),
        "lag_from_deadline_ms_p99": float(np.percentile(behind_deadline, 99)),
        "server_age_ms_p50": float(np.percentile(age, 50)),
        "server_age_ms_p99": float(np.percentile(age, 99)),
        "delivery_ms_p50": float(np.percentile(delivery, 50)),
        "delivery_ms_p99": float(np.percentile(delivery, 99)),
        "ping_rtt_ms": float(rtt),
        "reported_lag_ms_p50": float(reported["p50_ms"]),
        "reported_lag_ms_p99": float(reported["p99_ms"]),
    }
    for kind, name in (("gpu-process", "gpu"), ("renderer", "renderer"), ("browser", "browser")):
        spent = cpu1.get(kind, 0.0) - cpu0.get(kind, 0.0)
        out[f"cpu_ms_per_frame_{name}"] = spent / max(f1 - f0, 1)
    return out


if __name__ == "__main__":
    for key, value in run().items():
        print(f"{key:<28} {value:.4g}")
