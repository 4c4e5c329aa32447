"""The dashboard and the rider's view of a real-time run, in headless Chromium.

``motosim rig`` and ``motosim run --view`` run as two processes (:mod:`live_rig`); the
dashboard must plot the loop's timing, its missed deadlines and the safety stage's state as
they come, its Arm and Stop buttons must act through the safety stage, and the rider's view
must report the frames it draws (the lag itself is measured by ``bench/bench_view_lag.py``).
"""

import json
import math
import os
import shutil
import time
import urllib.request
from pathlib import Path

import pytest

pytest.importorskip("uvicorn", reason="the view server is in the optional group view")
pytest.importorskip("websockets", reason="the DevTools client needs websockets (group view)")
pytest.importorskip("can", reason="python-can is in the rt and dev dependency groups")
pytest.importorskip("cantools", reason="cantools is in the rt and dev dependency groups")

from browser import CHROMIUM, Browser
from live_rig import live_run

from motosim.errors import MotosimError

pytestmark = pytest.mark.skipif(
    CHROMIUM is None, reason="no chromium on PATH (Debian package chromium; .ci/run installs it)"
)


def _save(browser: Browser, tmp_path: Path, name: str) -> None:
    path = browser.screenshot(tmp_path / name)
    if os.environ.get("MOTOSIM_SCREENSHOTS"):
        target = Path(os.environ["MOTOSIM_SCREENSHOTS"])
        target.mkdir(parents=True, exist_ok=True)
        shutil.copy(path, target / name)


def test_the_dashboard_plots_the_loop_and_its_buttons_go_through_the_safety_stage(
    tmp_path: Path,
) -> None:
    try:
        context = live_run(tmp_path / "live", duration=60.0)
        live = context.__enter__()
    except MotosimError as err:
        pytest.skip(f"udp_multicast is not available here: {err}")
    dash = view = None
    try:
        dash = Browser(f"{live.url}/dashboard?token={live.token}", tmp_path / "dash")
        view = Browser(f"{live.url}/?token={live.token}", tmp_path / "view")
        # the loop runs and records with the torque off until Arm
        dash.wait_for("window.motosimDash && motosimDash.safety && motosimDash.panels.timing")
        assert dash.evaluate("motosimDash.safety") == {
            "state": "idle",
            "fault": "NONE",
            "reason": "no fault",
        }
        dash.wait_for("motosimDash.panels.timing.points > 100")
        before = dash.evaluate("motosimDash.panels")
        time.sleep(1.0)
        after = dash.evaluate("motosimDash.panels")
        assert after["timing"]["lines"] == ["period", "compute", "wake"]
        assert after["safety"]["lines"] == ["state", "fault"]
        for panel in ("timing", "missed", "safety", "torque", "steer", "roll", "speed"):
            assert after[panel]["points"] > 50, (panel, after[panel])
            assert after[panel]["lastT"] > before[panel]["lastT"], panel
        assert after["platform"]["lines"] == []  # the loop computes no platform commands
        assert "missed" in dash.evaluate("document.getElementById('loop').textContent")
        # the rider's view draws the live pose and reports each frame it drew
        try:
            view.wait_for("window.motosimStats && motosimStats.reported > 20", 60.0)
        except TimeoutError:
            keys = "frames fps poses offset rtt reported ready status".split()
            raise AssertionError(view.evaluate(f"JSON.stringify(motosimStats, {keys})")) from None
        with urllib.request.urlopen(f"{live.url}/api/lag", timeout=10) as answer:
            lag = json.load(answer)
        assert lag["frames"] > 20 and math.isfinite(lag["p50_ms"]) and lag["fps"] > 0
        # Arm: the safety stage fades the torque in
        dash.evaluate("document.getElementById('arm').click()")
        dash.wait_for("motosimDash.lastControl && motosimDash.lastControl.status === 200")
        dash.wait_for("motosimDash.safety.state !== 'idle'")
        assert dash.evaluate("motosimDash.safety.state") in ("fade_in", "running")
        _save(dash, tmp_path, "live_rt_dashboard.png")
        _save(view, tmp_path, "live_rt_view.png")
        # Stop at once (the loop misses deadlines on a busy machine: a long armed run could end
        # on a safety fault): as Ctrl-C, the torque fades out and the run ends (exit 130)
        dash.evaluate("document.getElementById('stop').click()")
        live.process.wait(timeout=60)
        end = time.monotonic() + 10.0  # its last messages, read by another thread
        while "torque faded out" not in "".join(live.log) and time.monotonic() < end:
            time.sleep(0.1)
        assert live.process.returncode == 130, "".join(live.log)
        assert "torque faded out" in "".join(live.log)
    finally:
        for browser in (dash, view):
            if browser is not None:
                browser.close()
        context.__exit__(None, None, None)
