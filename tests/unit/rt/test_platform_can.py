"""Platform commands as CAN frames: the host's sender, the platform twin's side and status."""

import math

import numpy as np
import pytest

from motosim.cueing import load_platform
from motosim.rt.platform import PlatformCanSender, PlatformTee, PlatformTwin, PlatformValue
from motosim.rt.safety import State

pytest.importorskip("cantools", reason="cantools is in the rt and dev dependency groups")

from motosim.io.can import load_dbc, platform_codecs

CODECS = platform_codecs()
PLATFORM = load_platform("simacom_platform").platform


class _Bus:
    """A link that keeps what is sent."""

    def __init__(self) -> None:
        self.frames: list[tuple[int, bytes]] = []

    def send(self, frame_id: int, data: bytes) -> bool:
        self.frames.append((frame_id, data))
        return True


def _send(sender: PlatformCanSender, k: int, live: bool, roll: float) -> None:
    values = np.array([roll, -0.5 * roll, 0.25 * roll, 0.0, 0.0, 0.0, 0.0])
    sender.send_command(k, 0.01 * k, State.RUNNING, 0, live, values)


def test_the_command_frame_is_the_dbcs_pf_command() -> None:
    bus = _Bus()
    _send(PlatformCanSender(bus, CODECS), 21, True, 0.1)
    ((frame_id, data),) = bus.frames
    message = load_dbc().get_message_by_name("PF_COMMAND")
    assert frame_id == message.frame_id == 0x200
    decoded = message.decode(data)  # cantools, independently of our codec
    assert decoded["COUNTER"] == 21 % 16 and decoded["LIVE"] == 1
    assert (decoded["ROLL"], decoded["PITCH"], decoded["YAW"]) == pytest.approx(
        (0.1, -0.05, 0.025), abs=5e-5
    )


def test_the_twin_follows_can_commands_counts_losses_and_answers() -> None:
    bus = _Bus()
    sender = PlatformCanSender(bus, CODECS)
    twin = PlatformTwin(PLATFORM, 0.001, codecs=CODECS)
    for k in range(200):  # 2 s at 100 Hz, frame 50 lost
        _send(sender, k, True, math.radians(5.0))
        frame_id, data = bus.frames.pop()
        if k != 50:
            assert twin.receive_frame(frame_id, data)
        twin.advance_to(0.01 * (k + 1))
    assert twin.frames == 199 and twin.lost == 1 and twin.bad == 0
    assert twin.receive_frame(frame_id, data) and twin.late == 1  # the last one again
    assert twin.frames == 199
    assert twin.achieved[0] == pytest.approx(math.radians(5.0), abs=1e-4)
    frame_id, data = twin.status_frame()
    status = load_dbc().get_message_by_name("PF_STATUS").decode(data)
    assert frame_id == 0x201 and status["WATCHDOG"] == 0
    assert status["ROLL"] == pytest.approx(math.radians(5.0), abs=2e-4)
    # a frame with a flipped bit is bad; another id is not the twin's
    bad = bytearray(CODECS.command.encode(np.zeros(len(CODECS.command.names))))
    bad[3] ^= 0x10
    assert twin.receive_frame(0x200, bytes(bad)) and twin.bad == 1
    assert not twin.receive_frame(0x101, bytes(8))


def test_not_live_and_silence_send_the_twin_to_neutral() -> None:
    bus = _Bus()
    sender = PlatformCanSender(bus, CODECS)
    twin = PlatformTwin(PLATFORM, 0.001, codecs=CODECS, watchdog=0.1)
    _send(sender, 0, False, 0.2)
    twin.receive_frame(*bus.frames.pop())
    assert np.all(twin.command == 0.0)  # LIVE 0: neutral
    _send(sender, 1, True, 0.2)
    twin.receive_frame(*bus.frames.pop())
    assert twin.command[PlatformValue.roll] == pytest.approx(0.2, abs=1e-4)
    twin.advance_to(0.5)  # no frame for 0.5 s: the watchdog
    assert twin.timeouts == 1 and np.all(twin.command == 0.0)
    _, data = twin.status_frame()
    assert load_dbc().get_message_by_name("PF_STATUS").decode(data)["WATCHDOG"] == 1


def test_a_tee_sends_through_every_link() -> None:
    a, b = _Bus(), _Bus()
    tee = PlatformTee(PlatformCanSender(a, CODECS), PlatformCanSender(b, CODECS))
    tee.send_command(3, 0.03, State.RUNNING, 0, True, np.zeros(7))
    tee.close()
    assert a.frames == b.frames and len(a.frames) == 1
