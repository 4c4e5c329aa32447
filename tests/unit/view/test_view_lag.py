"""The dashboard's loop and safety columns, and the path of the view's lag reports.

No timing is asserted here (the lag and frame rate are measured by ``bench/bench_view_lag.py``):
these tests check that the numbers go where they should and are summed up right.
"""

import math

import numpy as np
import pytest

pytest.importorskip("starlette", reason="the view server is in the optional group view")
pytest.importorskip("httpx2", reason="starlette's TestClient needs httpx2 (group dev)")

from starlette.testclient import TestClient

from motosim.errors import MotosimError
from motosim.io.telemetry import TelemetryRing
from motosim.rt.safety import Fault, State
from motosim.view.app import LagLog, _decimate, create_app
from motosim.view.feeds import LiveFeed, road_from_xy
from motosim.view.live import LOOP_VIEW_SIGNALS, LoopRows

NAMES = ("t", "x", "y", "psi", "phi", "delta", "v_x", *LOOP_VIEW_SIGNALS)


class Control:
    def arm(self) -> None: ...

    def stop(self) -> None: ...

    def state(self) -> str:
        return "fault"


def _ring(state: State = State.RUNNING, fault: Fault = Fault.NONE) -> TelemetryRing:
    ring = TelemetryRing(NAMES, 64)
    for k in range(10):
        t = 1e-3 * k
        ring.push(np.array([t, 20 * t, 0, 0, 0, 0, 20, state, fault, 500 + t, 2e-5, 3e-5, 1e-3, 0]))
    return ring


def test_lag_log_sums_up_the_reported_frames() -> None:
    log = LagLog()
    # 61 frames at 60 Hz, each drawn 10 ms after its sample except one at 40 ms
    drawn = 100.0 + np.arange(61) / 60.0
    lag = np.full(61, 0.010)
    lag[30] = 0.040
    frames = np.column_stack([drawn - lag, drawn]).tolist()
    assert log.add([*frames, [1.0, math.nan], "x", [1.0]]) == 61  # bad items dropped
    s = log.summary()
    assert s["frames"] == 61 and s["fps"] == pytest.approx(60.0)
    assert s["p50_ms"] == pytest.approx(10.0) and s["max_ms"] == pytest.approx(40.0)
    assert 10.0 < s["p99_ms"] < 40.0
    assert log.summary(window=0.5)["frames"] == 31  # the last half second only
    assert LagLog().summary()["p50_ms"] is None


def test_timing_columns_are_decimated_by_their_peak() -> None:
    rows = np.zeros((10, 2))
    rows[:, 0] = np.arange(10)
    rows[3, 1] = 7.0  # a spike between two kept rows
    out = _decimate(rows, 1, 5, peaks=[1])
    # feed rows 1..10: kept 5 and 10; the first kept row stands for rows 1..9
    assert out[:, 0].tolist() == [4.0, 9.0] and out[:, 1].tolist() == [7.0, 0.0]


def test_loop_rows_add_the_period_and_refuse_rows_without_the_loops_columns() -> None:
    loop_names = ("t", "state", "fault", "t_clock", "wake", "compute", "missed")
    rows = LoopRows(loop_names, ("t",))
    loop = np.array([[0.0, 2, 0, 10.0, 1e-4, 1e-5, 0], [0.001, 2, 0, 10.001, 3e-4, 1e-5, 0]])
    first = rows.rows(loop[:1], loop[:1, :1])
    second = rows.rows(loop[1:], loop[1:, :1])  # the period spans two drains
    col = rows.names.index("period")
    assert math.isnan(first[0, col]) and second[0, col] == pytest.approx(1.2e-3)
    with pytest.raises(MotosimError, match="without wake"):
        LoopRows(("t", "state", "fault", "t_clock", "compute", "missed"), ("t",))


def test_live_status_names_the_safety_state_and_the_fault() -> None:
    feed = LiveFeed(_ring(State.FAULT, Fault.WATCHDOG), Control(), watchdog_periods=5)
    status = feed.status()
    assert status["safety"] == {
        "state": "fault",
        "fault": "WATCHDOG",
        "reason": "communication watchdog: no valid status frame for 5 periods",
    }
    assert status["missed"] == 0


def test_the_page_pings_and_reports_frames_and_api_lag_sums_them() -> None:
    road = road_from_xy(np.array([0.0, 40.0]), np.zeros(2))
    client = TestClient(create_app(LiveFeed(_ring(), Control()), road, token="token-1234"))
    info = client.get("/api/info").json()
    assert {"period", "compute", "wake", "missed", "state", "fault"} <= set(info["dashboard"])
    assert info["units"]["compute"] == "s"
    with client.websocket_connect("/ws/pose") as ws:
        pose = ws.receive_json()
        # written at the deadline plus the wake-up latency and the compute time
        assert pose["deadline"] == pytest.approx(500.009, abs=1e-9)
        assert pose["clock"] == pytest.approx(500.009 + 2e-5 + 3e-5, abs=1e-9)
        assert pose["pose"]["t"] == 0.009
        assert pose["status"]["safety"]["fault"] == "NONE"
        ws.send_json({"ping": 1234.5})
        while "pong" not in (answer := ws.receive_json()):
            pass
        assert answer["pong"] == 1234.5 and math.isfinite(answer["server"])
        ws.send_json({"frames": [[500.009, 500.029], [500.009, 500.045]]})
        ws.send_json({"ping": 1.0})  # answered after the frames are logged
        while "pong" not in ws.receive_json():
            pass
    lag = client.get("/api/lag").json()
    assert lag["frames"] == 2 and lag["p50_ms"] == pytest.approx(28.0)
    assert lag["fps"] == pytest.approx(1 / 0.016)
    assert client.get("/api/lag?window=-1").status_code == 400
