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
