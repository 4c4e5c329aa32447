"""The rider's view and the dashboard in a real headless Chromium, on a replay and a live run.

Each test loads a page served by :mod:`motosim.view.app`, checks what is on it (a rendered
WebGL canvas, plots that grow, buttons that act) and saves a screenshot next to its
temporary files (also to ``$MOTOSIM_SCREENSHOTS`` when set).
"""

import dataclasses
import json
import math
import os
import shutil
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("uvicorn", reason="the view server is in the optional group view")
pytest.importorskip("websockets", reason="the DevTools client needs websockets (group view)")

from browser import CANVAS_PIXELS, CHROMIUM, Browser

from motosim.io.results import SimResult, load_result
from motosim.io.runs import load_run, run_to_folder
from motosim.timeseries import TimeSeries
from motosim.view.app import ServerThread, create_app
from motosim.view.feeds import ReplayFeed, merge_signals, road_from_xy
from motosim.view.live import SimulatedRig

pytestmark = pytest.mark.skipif(
    CHROMIUM is None, reason="no chromium on PATH (Debian package chromium; .ci/run installs it)"
)

ROOT = Path(__file__).parents[2]
TOKEN = "browser-test-token"


def _save(browser: Browser, tmp_path: Path, name: str) -> Path:
    path = browser.screenshot(tmp_path / name)
    if os.environ.get("MOTOSIM_SCREENSHOTS"):
        target = Path(os.environ["MOTOSIM_SCREENSHOTS"])
        target.mkdir(parents=True, exist_ok=True)
        shutil.copy(path, target / name)
    return path


def _inputs(duration: float) -> object:
    inputs = load_run(ROOT / "scenarios" / "lane_change_20.toml")
    return dataclasses.replace(
        inputs, scenario=dataclasses.replace(inputs.scenario, duration=duration)
    )


@pytest.fixture(scope="module")
def result(tmp_path_factory: pytest.TempPathFactory) -> SimResult:
    # the lane change of 3.5 m starting 50 m down the road: at 20 m/s it is under way at 3 s
    folder = tmp_path_factory.mktemp("run")
    run_to_folder(_inputs(5.0), folder)  # type: ignore[arg-type]
    return load_result(folder)


@pytest.fixture
def replay(result: SimResult) -> Iterator[tuple[ReplayFeed, str]]:
    feed = ReplayFeed(result)
    road = road_from_xy(result["x"], result["y"])
    with ServerThread(create_app(feed, road, token=TOKEN, title="lane change")) as server:
        yield feed, server.url


def test_the_view_renders_the_road_and_rides_the_replay(
    replay: tuple[ReplayFeed, str], tmp_path: Path
) -> None:
    feed, url = replay
    browser = Browser(f"{url}/?token={TOKEN}&readback=1", tmp_path / "profile")
    try:
        browser.wait_for("window.motosimStats && motosimStats.ready && motosimStats.poses > 3")
        # the page is cross-origin isolated: the pose socket runs in a worker
        assert browser.evaluate("[crossOriginIsolated, motosimStats.worker]") == [True, True]
        pixels = browser.evaluate(f"{CANVAS_PIXELS}('#scene')")
        # sky, grass, asphalt, lines, posts, trees: many colours, none covering most of it
        assert pixels["colours"] >= 8 and pixels["top"] < 0.6, pixels
        _save(browser, tmp_path, "view_start.png")
        feed.seek(2.5)
        browser.evaluate("document.getElementById('play').click()")
        browser.wait_for("motosimStats.status && motosimStats.status.state === 'playing'")
        assert feed.state() == "playing"
        x0 = browser.evaluate("motosimStats.lastPose.x")
        time.sleep(1.0)
        x1 = browser.evaluate("motosimStats.lastPose.x")
        assert x1 - x0 > 10.0  # 20 m/s
        _save(browser, tmp_path, "view_lane_change.png")
        # the horizon toggle and the dash follow the pose
        assert float(browser.evaluate("document.getElementById('speed').textContent")) > 60
        browser.evaluate("document.getElementById('play').click()")
        browser.wait_for("motosimStats.status.state === 'paused'")
    finally:
        browser.close()


@pytest.fixture
def cued(result: SimResult) -> Iterator[tuple[ReplayFeed, str]]:
    """The replay with the platform commands of the washout at 100 Hz (motosim cueing)."""
    from motosim.cueing import TELBAN_CARDULLO_2005, cue, load_platform

    series = TimeSeries(result.t, result.data, result.names)
    commands = cue(load_platform("simacom_platform"), series, TELBAN_CARDULLO_2005, rate=100.0)
    feed = ReplayFeed(merge_signals(result, commands.commands))
    road = road_from_xy(result["x"], result["y"])
    with ServerThread(create_app(feed, road, token=TOKEN, title="lane change")) as server:
        yield feed, server.url


def _panels(browser: Browser) -> dict[str, dict[str, object]]:
    panels: dict[str, dict[str, object]] = browser.evaluate("motosimDash.panels")
    return panels


def test_the_dashboard_of_a_replay_plots_the_run_and_has_replay_controls(
    cued: tuple[ReplayFeed, str], tmp_path: Path
) -> None:
    feed, url = cued
    browser = Browser(f"{url}/dashboard?token={TOKEN}", tmp_path / "profile")
    try:
        browser.wait_for("window.motosimDash && motosimDash.messages > 2")
        assert browser.evaluate("document.querySelectorAll('#plots canvas').length") >= 8
        # a recording cannot be armed: Play/Pause and a position instead of Arm and Stop
        hidden = "[...document.querySelectorAll('#arm, #stop, #play, #position')]"
        shown = browser.evaluate(f"{hidden}.map((e) => e.offsetParent !== null)")
        assert shown == [False, False, True, True]
        # paused at the start, the panels already hold the whole run (5 s), not nothing
        assert feed.state() == "paused"
        browser.wait_for("motosimDash.panels.torque.points > 100")
        paused = _panels(browser)
        drawn = ("torque", "steer", "roll", "speed", "platform")
        for panel in drawn:
            assert paused[panel]["points"] > 100, (panel, paused[panel])
        assert paused["torque"]["lines"] == ["tau_r", "tau_r_hat"]
        assert paused["platform"]["lines"] == ["phi_s", "theta_s", "psi_s", "phi_vis"]
        # a simulated run has no real-time loop: its panels say so instead of plotting
        for panel in ("timing", "missed", "safety"):
            assert paused[panel]["lines"] == [] and paused[panel]["points"] == 0
        safety = browser.evaluate("document.getElementById('safety').textContent")
        assert "no safety stage" in safety
        pixels = browser.evaluate(f"{CANVAS_PIXELS}('#plots canvas[data-panel=platform]')")
        assert pixels["colours"] >= 3 and pixels["top"] < 0.99, pixels
        _save(browser, tmp_path, "dashboard_replay_paused.png")
        browser.evaluate("document.getElementById('play').click()")
        browser.wait_for("motosimDash.lastControl && motosimDash.lastControl.status === 200")
        assert feed.state() == "playing"
        browser.wait_for("document.getElementById('play').textContent === 'Pause'")
        before = browser.wait_for("motosimDash.cursor > 0 && motosimDash.cursor")
        time.sleep(1.0)
        after = browser.evaluate("motosimDash.cursor")
        assert after > before + 0.5  # the cursor moves with the replay
        assert _panels(browser)["torque"]["lastT"] == pytest.approx(after, abs=0.2)
        _save(browser, tmp_path, "dashboard_replay_playing.png")
        browser.evaluate("document.getElementById('play').click()")
        browser.wait_for("motosimDash.state === 'paused'")
        assert feed.state() == "paused"
        # the position slider seeks
        browser.evaluate(
            "(() => { const p = document.getElementById('position'); p.value = 4;"
            " p.dispatchEvent(new Event('change')); })()"
        )
        browser.wait_for("motosimDash.cursor > 3.9")
        assert feed.status()["t"] == pytest.approx(4.0, abs=0.01)
    finally:
        browser.close()


def test_without_the_token_the_buttons_do_nothing(
    replay: tuple[ReplayFeed, str], tmp_path: Path
) -> None:
    feed, url = replay
    browser = Browser(f"{url}/dashboard", tmp_path / "profile")
    try:
        browser.wait_for("window.motosimDash && motosimDash.messages > 0")
        browser.evaluate("document.getElementById('play').click()")
        browser.wait_for("motosimDash.lastControl")
        assert browser.evaluate("motosimDash.lastControl.status") == 403
        assert feed.state() == "paused"
    finally:
        browser.close()


def test_a_live_simulated_run_drives_the_view_and_the_dashboard(tmp_path: Path) -> None:
    rig = SimulatedRig(_inputs(6.0))  # type: ignore[arg-type]
    app = create_app(rig.feed(), rig.road(), token=TOKEN, title="live")
    with ServerThread(app) as server:
        view = Browser(f"{server.url}/?token={TOKEN}", tmp_path / "view")
        dash = Browser(f"{server.url}/dashboard?token={TOKEN}", tmp_path / "dash")
        try:
            dash.wait_for("window.motosimDash && motosimDash.state === 'idle'")
            view.wait_for("window.motosimStats && motosimStats.ready")
            dash.evaluate("document.getElementById('arm').click()")
            dash.wait_for("motosimDash.lastControl")
            assert rig.state() == "running"  # the run lasts 6 s of wall-clock time
            view.wait_for("motosimStats.lastPose && motosimStats.lastPose.t > 1.0")
            dash.wait_for("motosimDash.rows > 100")
            shown = dash.evaluate(
                "[...document.querySelectorAll('#arm, #stop, #play')]"
                ".map((e) => e.offsetParent !== null)"
            )
            assert shown == [True, True, False]  # a live run is armed and stopped
            dash.wait_for("motosimDash.panels.torque.points > 50")
            for panel in ("torque", "steer", "roll", "speed"):
                assert dash.evaluate(f"motosimDash.panels.{panel}.points") > 50, panel
            _save(view, tmp_path, "live_view.png")
            _save(dash, tmp_path, "live_dashboard.png")
            # the lag report path: the rig stamps its rows with the monotonic clock, the page
            # reports the frames it drew (the figures are bench/bench_view_lag.py's)
            view.wait_for("motosimStats.offset !== null && motosimStats.reported > 10")
            lag = json.loads(urllib.request.urlopen(f"{server.url}/api/lag").read())
            assert lag["frames"] > 10 and math.isfinite(lag["p50_ms"]) and lag["fps"] > 0
            dash.wait_for("motosimDash.state === 'done'", timeout=40.0)
            # the view's last pose is the run's last row (6 s at 1 kHz)
            assert view.wait_for("motosimStats.lastPose.t >= 5.99 && motosimStats.lastPose.t")
            assert view.evaluate("motosimStats.lastPose.t") == pytest.approx(6.0, abs=0.01)
        finally:
            view.close()
            dash.close()
            rig.stop()
            rig.join(5.0)
    assert rig.error is None


def test_the_render_scale_steps_down_on_a_slow_renderer_unless_fixed(
    replay: tuple[ReplayFeed, str], tmp_path: Path
) -> None:
    _, url = replay
    slow = "for (let i = 0; i < 8; i++) motosimStats.adapt(10); motosimStats.scale"
    browser = Browser(f"{url}/?token={TOKEN}", tmp_path / "adaptive")
    try:
        browser.wait_for("window.motosimStats && motosimStats.ready")
        assert browser.evaluate("[motosimStats.antialias, motosimStats.adaptive]") == [False, True]
        # two slow seconds in a row per step, 1 -> 0.75 -> 0.5, never below 0.5
        assert browser.evaluate(slow) == 0.5
        browser.wait_for(
            "document.querySelector('#scene').width"
            " === Math.round(document.querySelector('#scene').clientWidth * 0.5)"
        )
    finally:
        browser.close()
    browser = Browser(f"{url}/?token={TOKEN}&scale=1&antialias=1", tmp_path / "fixed")
    try:
        browser.wait_for("window.motosimStats && motosimStats.ready")
        assert browser.evaluate("[motosimStats.antialias, motosimStats.adaptive]") == [True, False]
        assert browser.evaluate(slow) == 1
    finally:
        browser.close()


def test_the_riders_view_has_the_cockpit_turning_and_leaning_with_the_motorcycle(
    replay: tuple[ReplayFeed, str], tmp_path: Path
) -> None:
    feed, url = replay
    browser = Browser(f"{url}/?token={TOKEN}&readback=1", tmp_path / "cockpit")
    try:
        browser.wait_for("window.motosimStats && motosimStats.ready && motosimStats.poses > 0")
        # in the lane change: the handlebar turned and the motorcycle leaning
        feed.seek(3.6)
        browser.wait_for("motosimStats.lastPose && motosimStats.lastPose.t > 3.5")
        time.sleep(0.3)  # a frame drawn with that pose
        pose = browser.evaluate("motosimStats.lastPose")
        assert abs(pose["theta_h"]) > math.radians(0.2) and abs(pose["phi"]) > math.radians(2)
        turned = browser.evaluate("motosimStats.bars.rotation.y")
        assert turned == pytest.approx(-pose["theta_h"], abs=1e-9)  # turns with theta_h
        # the horizon rolls: the camera leans with the motorcycle and the cockpit with it
        lean = "[motosimStats.camera.rotation.z, motosimStats.cockpit.rotation.z]"
        assert browser.evaluate(lean) == pytest.approx([-pose["phi"], 0.0], abs=1e-9)
        meshes = "(() => { let k = 0; motosimStats.cockpit.traverse((o) => { if (o.isMesh) k++; });"
        assert browser.evaluate(meshes + " return k; })()") >= 10
        # the tank's red and the instruments' black fill the bottom of the picture
        bottom = """
        (() => {
          const s = document.querySelector('#scene');
          const c = document.createElement('canvas'); c.width = 160; c.height = 90;
          const g = c.getContext('2d'); g.drawImage(s, 0, 0, 160, 90);
          const d = g.getImageData(40, 60, 80, 30).data;
          let red = 0, dark = 0;
          for (let i = 0; i < d.length; i += 4) {
            if (d[i] > 140 && d[i + 1] < 80 && d[i + 2] < 80) red++;
            if (d[i] < 60 && d[i + 1] < 60 && d[i + 2] < 60) dark++;
          }
          return [red, dark];
        })()
        """
        red, dark = browser.evaluate(bottom)
        _save(browser, tmp_path, "view_cockpit.png")
        assert red > 50 and dark > 20, (red, dark)
        # the horizon held level: the view does not roll, the cockpit leans in it
        browser.evaluate("document.getElementById('roll-toggle').click()")
        time.sleep(0.3)
        assert browser.evaluate(lean) == pytest.approx([0.0, -pose["phi"]], abs=1e-9)
        _save(browser, tmp_path, "view_cockpit_level_horizon.png")
    finally:
        browser.close()
