"""The state stream of ``motosim run``: the datagram's layout and its reader."""

import struct
import time

import numpy as np

from motosim.rt.telemetry import StateReceiver, StateSender


def test_a_datagram_is_the_documented_struct_and_is_read_back() -> None:
    # the layout is struct's "<Qd" then the row's doubles (the view and the rig read it so)
    receiver = StateReceiver(("127.0.0.1", 0), width=3)
    sender = StateSender(receiver.address, width=3)
    try:
        sender.send(7, 0.5, np.array([1.0, -2.0, 3.5]))
        assert bytes(sender._bytes) == struct.pack("<Qd3d", 7, 0.5, 1.0, -2.0, 3.5)
        end = time.monotonic() + 5.0
        while receiver.index < 0 and time.monotonic() < end:
            receiver.poll()
            time.sleep(0.01)
        assert receiver.index == 7 and receiver.t == 0.5
        assert receiver.row.tolist() == [1.0, -2.0, 3.5]
    finally:
        sender.close()
        receiver.close()


def test_the_relay_sends_the_newest_row_of_the_ring_once_the_stack_started() -> None:
    # motosim run's state stream from outside the loop: the newest row of the ring, its
    # stack columns, the period's index from its time; rows without a valid angle yet (the
    # stack not started) are not sent, as the loop did not send them
    from motosim.rt.ring import SampleRing
    from motosim.rt.telemetry import StateRelay

    names = ("t", "theta_h_meas", "t_clock", "wake", "compute", "a", "b")
    ring = SampleRing(8, len(names))
    buffer, counters = ring.arrays
    sent: list[tuple[int, float, list[float]]] = []
    relay = StateRelay(
        buffer,
        counters,
        names,
        5,
        lambda k, t, row: sent.append((k, t, row.tolist())),
        rate=1000.0,
        now=lambda: 10.0,
    )
    assert not relay.poll()  # nothing written yet
    ring.push(np.array([0.0, np.nan, 9.0, 0.0, 0.0, 0.0, 0.0]))
    assert not relay.poll() and sent == []  # no valid angle yet
    ring.push(np.array([0.001, 0.1, 9.5, 1e-5, 1e-4, 1.0, 2.0]))
    ring.push(np.array([0.002, 0.2, 9.9, 1e-5, 1e-4, 3.0, 4.0]))
    assert relay.poll()
    assert not relay.poll()  # nothing new
    assert sent == [(2, 0.002, [3.0, 4.0])]  # the newest only
    assert relay.sent == 1
    assert relay.lag_stats()["p50"] == np.float64(10.0 - (9.9 + 1e-5 + 1e-4))
