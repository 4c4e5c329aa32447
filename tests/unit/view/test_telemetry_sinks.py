"""The telemetry ring and its sinks: layout of the esmini packet, PlotJuggler JSON, MCAP."""

import json
import math
import socket
import struct
from pathlib import Path

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.io.telemetry import (
    ESMINI_FORMAT,
    EsminiUdp,
    PlotJugglerUdp,
    TelemetryPump,
    TelemetryRing,
    esmini_packet,
    pose_of,
    write_mcap,
)
from motosim.timeseries import TimeSeries

NAMES = ("t", "x", "y", "psi", "phi", "delta", "v_x")


def _run(n: int = 50) -> TimeSeries:
    t = np.arange(n) * 0.01
    data = np.column_stack([20 * t, 0.1 * t, 0.01 * t, 0.02 * np.sin(t), 0.005 + 0 * t, 20 + 0 * t])
    return TimeSeries(t, data, NAMES[1:])


def _listener() -> tuple[socket.socket, int]:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.settimeout(5.0)
    return sock, int(sock.getsockname()[1])


def test_ring_returns_rows_in_order_across_the_wrap() -> None:
    ring = TelemetryRing(("t", "a"), capacity=8)
    cursor = 0
    seen = []
    for k in range(40):
        ring.push(np.array([k, 2.0 * k]))
        if k % 3 == 0:
            rows, cursor = ring.read_since(cursor)
            seen.extend(rows[:, 0].tolist())
    rows, cursor = ring.read_since(cursor)
    seen.extend(rows[:, 0].tolist())
    assert seen == list(range(40)) and cursor == 40
    assert ring.latest() is not None and ring.latest()[1] == 78.0  # type: ignore[index]


def test_ring_push_block_equals_pushing_rows() -> None:
    block = np.column_stack([np.arange(13.0), -np.arange(13.0)])
    one, many = TelemetryRing(("t", "a"), 5), TelemetryRing(("t", "a"), 5)
    one.push_block(block[:3])
    one.push_block(block[3:])
    for row in block:
        many.push(row)
    assert np.array_equal(one.read_since(0)[0], many.read_since(0)[0])
    assert one.read_since(0)[0][:, 0].tolist() == [9.0, 10.0, 11.0, 12.0]


def test_a_reader_left_behind_gets_the_newest_rows() -> None:
    ring = TelemetryRing(("t",), capacity=4)
    ring.push_block(np.arange(100.0)[:, None])
    rows, cursor = ring.read_since(10)
    assert rows[:, 0].tolist() == [97.0, 98.0, 99.0] and cursor == 100


@pytest.mark.parametrize(("names", "capacity"), [(("x", "t"), 8), (("t", "t"), 8), (("t", "x"), 1)])
def test_ring_rejects_bad_layouts(names: tuple[str, ...], capacity: int) -> None:
    with pytest.raises(MotosimError, match="TelemetryRing"):
        TelemetryRing(names, capacity)


def test_esmini_packet_follows_the_udp_driver_layout() -> None:
    # esmini ControllerUDPDriver.hpp: DMHeader {version, inputMode, objectId, frameNumber} as
    # unsigned int, then DMMSGVehicleStateXYZHPR {x, y, z, h, p, r, speed, wheelAngle} as
    # double and deadReckon as unsigned char; UDP_DRIVER_MESSAGE_VERSION = 1 and
    # InputMode::VEHICLE_STATE_XYZHPR = 2.
    pose = {"t": 1.0, "x": 10.0, "y": 2.0, "psi": 0.3, "phi": 0.2, "delta": 0.01, "v_x": 15.0}
    packet = esmini_packet(42, pose, object_id=3, dead_reckon=True)
    assert len(packet) == 4 * 4 + 8 * 8 + 1 == struct.calcsize(ESMINI_FORMAT)
    version, mode, obj, frame, x, y, z, h, p, r, speed, wheel, dead = struct.unpack(
        ESMINI_FORMAT, packet
    )
    assert (version, mode, obj, frame, dead) == (1, 2, 3, 42, 1)
    # y right / z down (motosim) to OpenDRIVE's y left / z up: y, heading, wheel flip sign
    assert (x, y, z, h, p, r, speed, wheel) == (10.0, -2.0, 0.0, -0.3, 0.0, 0.2, 15.0, -0.01)


def test_udp_sinks_send_what_they_promise() -> None:
    run = _run()
    rows = np.column_stack([run.t, run.data])
    pj_sock, pj_port = _listener()
    es_sock, es_port = _listener()
    with pj_sock, es_sock:
        pj = PlotJugglerUdp("127.0.0.1", pj_port, every=10)
        es = EsminiUdp("127.0.0.1", port=es_port)
        pj.send(NAMES, rows)
        es.send(NAMES, rows)
        messages = [json.loads(pj_sock.recv(65536)) for _ in range(5)]
        packet = es_sock.recv(1024)
        pj.close()
        es.close()
    assert [m["timestamp"] for m in messages] == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4])
    assert messages[1]["x"] == pytest.approx(2.0) and set(messages[0]) == {"timestamp", *NAMES[1:]}
    assert struct.unpack(ESMINI_FORMAT, packet)[4] == pytest.approx(rows[-1, 1])


def test_pump_moves_new_rows_and_drops_a_broken_sink() -> None:
    class Keep:
        def __init__(self) -> None:
            self.t: list[float] = []

        def send(self, names: tuple[str, ...], rows: np.ndarray) -> None:
            self.t.extend(rows[:, 0].tolist())

    class Broken:
        def send(self, names: tuple[str, ...], rows: np.ndarray) -> None:
            raise OSError("gone")

    ring = TelemetryRing(("t",), 64)
    keep = Keep()
    pump = TelemetryPump(ring, [Broken(), keep])
    ring.push_block(np.arange(5.0)[:, None])
    assert pump.pump() == 5
    ring.push(np.array([5.0]))
    assert pump.pump() == 1 and pump.pump() == 0
    assert keep.t == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
    assert len(pump.errors) == 1 and isinstance(pump.errors[0], OSError)


def test_pump_thread_starts_and_stops() -> None:
    ring = TelemetryRing(("t",), 64)
    got: list[int] = []

    class Count:
        def send(self, names: tuple[str, ...], rows: np.ndarray) -> None:
            got.append(rows.shape[0])

    pump = TelemetryPump(ring, [Count()], rate=200.0).start()
    ring.push_block(np.arange(7.0)[:, None])
    pump.stop()
    assert sum(got) == 7


def test_pose_of_names_what_is_missing() -> None:
    with pytest.raises(MotosimError, match="without psi"):
        pose_of(("t", "x", "y"), np.zeros(3))


def test_mcap_round_trip(tmp_path: Path) -> None:
    from mcap.reader import make_reader

    run = _run()
    count = write_mcap(run, tmp_path / "run.mcap", every=2)
    assert count == 2 * 25
    with (tmp_path / "run.mcap").open("rb") as stream:
        reader = make_reader(stream)
        messages = list(reader.iter_messages())
    signals = [json.loads(m.data) for s, c, m in messages if c.topic == "/motosim/signals"]
    poses = [json.loads(m.data) for s, c, m in messages if c.topic == "/motosim/pose"]
    assert len(signals) == len(poses) == 25
    assert [s["t"] for s in signals] == pytest.approx(run.t[::2])
    assert [s["x"] for s in signals] == pytest.approx(run["x"][::2])
    schemas = {c.topic: s.name for s, c, m in messages}
    assert schemas == {
        "/motosim/signals": "motosim.Signals",
        "/motosim/pose": "foxglove.PoseInFrame",
    }
    # the pose quaternion is a unit quaternion of yaw -psi then roll phi
    q = poses[-1]["pose"]["orientation"]
    assert math.hypot(q["x"], q["y"], q["z"], q["w"]) == pytest.approx(1.0)
    assert poses[-1]["pose"]["position"]["y"] == pytest.approx(-run["y"][-2])
    assert messages[-1][2].log_time == round(run.t[-2] * 1e9)


def test_mcap_refuses_an_unwritable_path(tmp_path: Path) -> None:
    with pytest.raises(MotosimError, match="cannot write"):
        write_mcap(_run(), tmp_path / "no" / "such" / "run.mcap")


def test_foxglove_live_server_starts_logs_and_stops() -> None:
    pytest.importorskip("foxglove", reason="foxglove-sdk is in the optional group view")
    from motosim.io.telemetry import FoxgloveLive

    live = FoxgloveLive("127.0.0.1", port=0, every=5)
    try:
        assert live.port > 0
        run = _run()
        live.send(NAMES, np.column_stack([run.t, run.data]))
    finally:
        live.close()
