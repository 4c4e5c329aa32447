"""Replay against a clock, the live feed over a ring, and the road."""

import math

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.io.telemetry import TelemetryRing
from motosim.timeseries import TimeSeries
from motosim.view.feeds import LiveFeed, ReplayFeed, Road, road_from_xy

POSE = ("x", "y", "psi", "phi", "delta", "v_x")


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def _run(duration: float = 2.0, dt: float = 0.01) -> TimeSeries:
    t = np.arange(round(duration / dt) + 1) * dt
    return TimeSeries(t, np.column_stack([20 * t] + [0 * t] * 4 + [20 + 0 * t]), POSE)


def test_replay_follows_the_clock_pauses_and_seeks() -> None:
    clock = Clock()
    feed = ReplayFeed(_run(), now=clock)
    assert feed.state() == "paused" and feed.latest()[0] == 0.0  # type: ignore[index]
    feed.arm()
    clock.now += 0.505
    assert feed.latest()[0] == pytest.approx(0.5)  # type: ignore[index]
    rows, cursor = feed.read_since(0)
    assert rows.shape[0] == 51 and cursor == 51
    feed.stop()
    clock.now += 10.0
    assert feed.state() == "paused" and feed.status()["t"] == pytest.approx(0.505)
    feed.seek(1.5)
    assert feed.status()["epoch"] == 1 and feed.latest()[1] == pytest.approx(30.0)  # type: ignore[index]
    rows, cursor = feed.read_since(cursor)
    assert rows[0, 0] == pytest.approx(0.51) and rows[-1, 0] == pytest.approx(1.5)
    rows, _ = feed.read_since(10_000)  # a cursor ahead starts over
    assert rows[0, 0] == 0.0


def test_replay_rate_and_the_end() -> None:
    clock = Clock()
    feed = ReplayFeed(_run(), now=clock)
    feed.set_rate(4.0)
    feed.arm()
    clock.now += 0.25
    assert feed.status()["t"] == pytest.approx(1.0)
    clock.now += 5.0
    assert feed.state() == "ended" and feed.status()["t"] == pytest.approx(2.0)
    feed.arm()  # plays again from the start
    assert feed.state() == "playing" and feed.status()["t"] == pytest.approx(0.0)


def test_replay_loops_when_asked() -> None:
    clock = Clock()
    feed = ReplayFeed(_run(), now=clock, loop=True)
    feed.arm()
    clock.now += 2.5
    assert feed.state() == "playing" and feed.status()["t"] < 2.0


@pytest.mark.parametrize("rate", [0.0, -1.0, math.nan, 1000.0])
def test_replay_rejects_bad_rates(rate: float) -> None:
    with pytest.raises(MotosimError, match="rate"):
        ReplayFeed(_run()).set_rate(rate)


def test_replay_needs_the_pose() -> None:
    t = np.arange(3.0)
    with pytest.raises(MotosimError, match="without"):
        ReplayFeed(TimeSeries(t, t[:, None], ("x",)))


def test_live_feed_reads_the_ring_and_reports_the_control() -> None:
    class Control:
        def arm(self) -> None: ...

        def stop(self) -> None: ...

        def state(self) -> str:
            return "running"

    ring = TelemetryRing(("t", *POSE), 16)
    feed = LiveFeed(ring, Control())
    assert feed.latest() is None and feed.status()["duration"] is None
    ring.push_block(np.column_stack([np.arange(3.0), np.ones((3, 6))]))
    rows, cursor = feed.read_since(0)
    assert rows.shape == (3, 7) and cursor == 3
    assert feed.status() == {
        "mode": "live",
        "state": "running",
        "t": 2.0,
        "duration": None,
        "rate": 1.0,
        "epoch": 0,
    }


def test_road_follows_and_extends_the_path() -> None:
    # a quarter circle of radius 50 m: the extension continues along the last heading
    a = np.linspace(0.0, math.pi / 2, 200)
    road = road_from_xy(50 * np.sin(a), 50 * (1 - np.cos(a)), spacing=1.0, before=10, after=20)
    assert road.x[0] == pytest.approx(-10.0, abs=0.01) and road.y[0] == pytest.approx(0.0, abs=0.2)
    # (the last partial spacing of the 78.5 m arc is dropped: the end is within half a metre)
    assert road.x[-1] == pytest.approx(50.0, abs=0.5) and road.y[-1] == pytest.approx(70.0, abs=0.6)
    steps = np.hypot(np.diff(road.x), np.diff(road.y))
    assert np.all(steps < 1.0 + 1e-9) and np.all(steps > 0.95)


def test_road_rejects_what_is_not_a_road() -> None:
    with pytest.raises(MotosimError, match="covering"):
        road_from_xy(np.zeros(5), np.zeros(5))
    with pytest.raises(MotosimError, match="width"):
        Road(np.arange(3.0), np.zeros(3), width=0.0)
