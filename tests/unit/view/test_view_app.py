"""The web application through Starlette's test client: pages, info, token, WebSockets."""

import numpy as np
import pytest

pytest.importorskip("starlette", reason="the view server is in the optional group view")
pytest.importorskip("httpx2", reason="starlette's TestClient needs httpx2 (group dev)")

from starlette.testclient import TestClient

from motosim.errors import MotosimError
from motosim.timeseries import TimeSeries
from motosim.view.app import create_app
from motosim.view.feeds import ReplayFeed, road_from_xy

TOKEN = "secret-token-123"


@pytest.fixture
def feed() -> ReplayFeed:
    t = np.arange(201) * 0.01
    data = np.column_stack([20 * t, 0 * t, 0 * t, 0.1 * t, 0 * t, 20 + 0 * t, 5 * t])
    return ReplayFeed(TimeSeries(t, data, ("x", "y", "psi", "phi", "delta", "v_x", "tau_r")))


@pytest.fixture
def client(feed: ReplayFeed) -> TestClient:
    road = road_from_xy(np.array([0.0, 40.0]), np.zeros(2))
    return TestClient(create_app(feed, road, token=TOKEN, title="test"))


def test_pages_and_vendored_three_are_served(client: TestClient) -> None:
    view = client.get("/")
    assert view.status_code == 200 and '"three": "/static/three.module.js"' in view.text
    assert "Arm" in client.get("/dashboard").text
    three = client.get("/static/three.module.js")
    assert three.status_code == 200 and "three.core.js" in three.text
    assert "MIT" in client.get("/static/three.LICENSE").text
    # cross-origin isolated pages (shared memory between the view and its pose worker)
    for response in (view, three, client.get("/static/pose_worker.js")):
        assert response.headers["cross-origin-opener-policy"] == "same-origin"
        assert response.headers["cross-origin-embedder-policy"] == "require-corp"


def test_info_lists_signals_units_and_road(client: TestClient) -> None:
    info = client.get("/api/info").json()
    assert info["names"][:2] == ["t", "x"] and info["units"]["phi"] == "rad"
    assert info["dashboard"] == ["t", "tau_r", "delta", "phi", "v_x"]
    assert info["replay"] is True and info["status"]["state"] == "paused"
    assert len(info["road"]["x"]) == len(info["road"]["y"]) > 10


def test_controls_need_the_token(client: TestClient, feed: ReplayFeed) -> None:
    assert client.post("/api/control", json={"action": "arm"}).status_code == 403
    bad = client.post("/api/control", json={"action": "arm"}, headers={"X-Motosim-Token": "x"})
    assert bad.status_code == 403 and feed.state() == "paused"
    ok = client.post("/api/control", json={"action": "arm"}, headers={"X-Motosim-Token": TOKEN})
    assert ok.status_code == 200 and ok.json()["status"]["state"] == "playing"
    head = {"X-Motosim-Token": TOKEN}
    assert client.post("/api/control", json={"action": "seek", "t": 1.0}, headers=head).is_success
    assert feed.status()["t"] == pytest.approx(1.0, abs=0.05)
    assert client.post("/api/control", json={"action": "stop"}, headers=head).is_success
    assert feed.state() == "paused"


@pytest.mark.parametrize(
    "body", [{"action": "fly"}, {"action": "seek", "t": "soon"}, {"action": "rate", "rate": -1}, []]
)
def test_bad_commands_are_400_with_a_message(client: TestClient, body: object) -> None:
    answer = client.post("/api/control", json=body, headers={"X-Motosim-Token": TOKEN})
    assert answer.status_code == 400 and answer.json()["error"]


def test_pose_websocket_streams_the_pose(client: TestClient, feed: ReplayFeed) -> None:
    feed.seek(1.0)
    with client.websocket_connect("/ws/pose") as ws:
        message = ws.receive_json()
    assert message["pose"]["x"] == pytest.approx(20.0) and message["pose"]["t"] == 1.0
    assert set(message["pose"]) == {"t", "x", "y", "psi", "phi", "delta", "v_x"}
    assert message["status"]["mode"] == "replay"


def test_signals_websocket_sends_decimated_rows(client: TestClient, feed: ReplayFeed) -> None:
    feed.seek(2.0)
    with client.websocket_connect("/ws/signals") as ws:
        message = ws.receive_json()
    assert message["names"] == ["t", "tau_r", "delta", "phi", "v_x"] and message["start_over"]
    t = [row[0] for row in message["rows"]]
    # 100 Hz rows, kept at most at 200 Hz: all of them
    assert t[0] == 0.0 and t[-1] == pytest.approx(2.0) and len(t) == 201


def test_a_short_token_is_refused(feed: ReplayFeed) -> None:
    road = road_from_xy(np.array([0.0, 40.0]), np.zeros(2))
    with pytest.raises(MotosimError, match="token"):
        create_app(feed, road, token="short")
