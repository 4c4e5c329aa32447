"""The rider's view and the dashboard in a real headless Chromium, on a replay and a live run.

Each test loads a page served by :mod:`motosim.view.app`, checks what is on it (a rendered
WebGL canvas, plots that grow, buttons that act) and saves a screenshot next to its
temporary files (also to ``$MOTOSIM_SCREENSHOTS`` when set).
"""

import dataclasses
import os
import shutil
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("uvicorn", reason="the view server is in the optional group view")
pytest.importorskip("websockets", reason="the DevTools client needs websockets (group view)")

from browser import CANVAS_PIXELS, CHROMIUM, Browser

from motosim.io.results import SimResult, load_result
from motosim.io.runs import load_run, run_to_folder
from motosim.view.app import ServerThread, create_app
from motosim.view.feeds import ReplayFeed, road_from_xy
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


def test_the_dashboard_plots_and_its_buttons_act(
    replay: tuple[ReplayFeed, str], tmp_path: Path
) -> None:
    feed, url = replay
    browser = Browser(f"{url}/dashboard?token={TOKEN}", tmp_path / "profile")
    try:
        browser.wait_for("window.motosimDash && motosimDash.messages > 2")
        assert browser.evaluate("document.querySelectorAll('#plots canvas').length") >= 5
        browser.evaluate("document.getElementById('arm').click()")
        browser.wait_for("motosimDash.lastControl && motosimDash.lastControl.status === 200")
        assert feed.state() == "playing"
        rows = browser.wait_for("motosimDash.rows > 200 && motosimDash.rows")
        time.sleep(0.5)
        assert browser.evaluate("motosimDash.rows") > rows  # still growing
        pixels = browser.evaluate(f"{CANVAS_PIXELS}('#plots canvas')")
        assert pixels["colours"] >= 3 and pixels["top"] < 0.99, pixels
        _save(browser, tmp_path, "dashboard.png")
        browser.evaluate("document.getElementById('stop').click()")
        browser.wait_for("motosimDash.state === 'paused'")
        assert feed.state() == "paused"
    finally:
        browser.close()


def test_without_the_token_the_buttons_do_nothing(
    replay: tuple[ReplayFeed, str], tmp_path: Path
) -> None:
    feed, url = replay
    browser = Browser(f"{url}/dashboard", tmp_path / "profile")
    try:
        browser.wait_for("window.motosimDash && motosimDash.messages > 0")
        browser.evaluate("document.getElementById('arm').click()")
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
            _save(view, tmp_path, "live_view.png")
            _save(dash, tmp_path, "live_dashboard.png")
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
