"""Platform output of the real-time loop: datagram layout, safety envelope, limits, twin."""

import socket
import struct

import numpy as np
import pytest

from motosim.cueing.platform import CueingConfig, load_platform
from motosim.errors import MotosimError
from motosim.rt.platform import (
    PLATFORM_FRAME,
    PlatformOutput,
    PlatformSender,
    PlatformTwin,
    PlatformValue,
    decode_platform,
    encode_platform,
)
from motosim.rt.safety import Fault, State

DT = 0.001
NAMES = ("tau_r_hat", "v_x", "v_y", "psi_dot", "phi")


@pytest.fixture(scope="module")
def config() -> CueingConfig:
    return load_platform("simacom_platform")


def _violations(x: np.ndarray, limit: float, rate: float, accel: float, dt: float) -> int:
    v = np.diff(np.concatenate([[0.0, 0.0], x])) / dt  # from neutral rest
    a = np.diff(v) / dt
    tol = 1e-9
    return int(
        np.sum(np.abs(x) > limit * (1 + tol))
        + np.sum(np.abs(v) > rate * (1 + tol))
        + np.sum(np.abs(a) > accel * (1 + tol) + 1e-6)
    )


def test_datagram_layout_is_the_documented_one() -> None:
    values = np.array([0.1, -0.05, 0.2, 0.3, -0.4, 0.5, 0.6])
    data = encode_platform(2**32 + 5, 12.5, State.RUNNING, Fault.NONE, True, values)
    assert len(data) == 48 == PLATFORM_FRAME.size
    # by hand from the module docstring's table: little-endian, magic, 4 bytes, u32, f64, 7 f32
    magic, version, state, fault, flags = struct.unpack_from("<4sBBBB", data, 0)
    assert (magic, version, state, fault, flags) == (b"MSPF", 1, 2, 0, 1)
    assert struct.unpack_from("<I", data, 8)[0] == 5  # wrapped at 2^32
    assert struct.unpack_from("<d", data, 12)[0] == 12.5
    np.testing.assert_allclose(struct.unpack_from("<7f", data, 20), values, rtol=1e-7)
    frame = decode_platform(data)
    assert frame.sequence == 5 and frame.live and frame.horizon == pytest.approx(0.6)
    with pytest.raises(MotosimError, match="expected 48"):
        decode_platform(data[:-1])
    with pytest.raises(MotosimError, match="magic"):
        decode_platform(b"XXXX" + data[4:])


def test_fades_in_with_the_envelope_and_back_to_neutral_on_a_fault(
    config: CueingConfig,
) -> None:
    out = PlatformOutput(config, DT, NAMES)
    row = np.array([0.0, 10.0, 0.0, 0.3, 0.35])  # a steady 20 deg lean turn
    rolls = []
    for k in range(6000):
        envelope = min(1.0, k * DT / 0.5) if k < 3000 else 0.0  # fade-in, then a fault
        out.step(k, k * DT, row, State.RUNNING if k < 3000 else State.FAULT, 0, envelope)
        rolls.append(out.values[PlatformValue.roll])
    roll = np.array(rolls)
    assert roll[0] == 0.0 and roll[2999] > np.radians(5.0)  # faded in, holding a roll
    assert abs(roll[-1]) < 1e-9  # back at neutral after the fault
    assert np.all(roll[3000:] >= -1e-12)  # and not carried across it
    axis = config.platform.axes[0]
    assert _violations(roll, axis.angle, axis.rate, axis.accel, DT) == 0


def test_zero_violations_on_wild_motion(config: CueingConfig) -> None:
    # lean, yaw rate and speed jumping about far beyond a motorcycle's, envelope toggling
    rng = np.random.default_rng(3)
    out = PlatformOutput(config, DT, NAMES)
    n = 5000
    rows = np.column_stack(
        [
            np.zeros(n),
            20 + 15 * rng.standard_normal(n),
            3 * rng.standard_normal(n),
            2 * rng.standard_normal(n),
            1.2 * np.sign(np.sin(np.arange(n) * DT * 7.0)),
        ]
    )
    values = np.empty((n, 3))
    for k in range(n):
        out.step(k, k * DT, rows[k], State.RUNNING, 0, float((k // 700) % 2))
        values[k] = out.values[:3]
    for j, axis in enumerate(config.platform.axes):
        assert _violations(values[:, j], axis.angle, axis.rate, axis.accel, DT) == 0


def test_missing_state_is_refused(config: CueingConfig) -> None:
    with pytest.raises(MotosimError, match="expected v_x, v_y, psi_dot and phi"):
        PlatformOutput(config, DT, ("v_x", "phi"))


def test_twin_follows_the_datagrams_over_udp_on_localhost(config: CueingConfig) -> None:
    twin = PlatformTwin(config.platform, DT, ("127.0.0.1", 0))
    address = twin.address
    assert address is not None
    sender = PlatformSender(address)
    out = PlatformOutput(config, DT, NAMES, sender=sender, send_every=10)
    row = np.array([0.0, 10.0, 0.0, 0.3, 0.35])
    try:
        for k in range(3000):
            out.step(k, k * DT, row, State.RUNNING, 0, min(1.0, k * DT / 0.5))
            twin.step()
        # a frame lost on purpose: the twin counts the gap
        out.sequence += 1
        for k in range(3000, 3020):
            out.step(k, k * DT, row, State.RUNNING, 0, 1.0)
            twin.step()
        twin.receive(b"garbage")
    finally:
        sender.close()
        twin.close()
    assert twin.frames == 302 and twin.lost == 1 and twin.bad == 1
    # the platform reached the command through its 5 Hz actuator loops
    np.testing.assert_allclose(twin.achieved, out.values[:3], atol=np.radians(0.05))


def test_twin_goes_to_neutral_when_not_live(config: CueingConfig) -> None:
    twin = PlatformTwin(config.platform, 0.01, watchdog=10.0)
    values = np.array([0.3, 0.1, 0.2, 0.0, 0.0, 0.0, 0.0])
    twin.receive(encode_platform(0, 0.0, State.RUNNING, 0, True, values))
    for _ in range(300):
        twin.step()
    np.testing.assert_allclose(twin.achieved, [0.3, 0.1, 0.2], atol=1e-3)
    twin.receive(encode_platform(1, 3.0, State.FAULT, Fault.WATCHDOG, False, values))
    for _ in range(300):
        twin.step()
    np.testing.assert_allclose(twin.achieved, 0.0, atol=1e-3)
    assert twin.lost == 0


def test_sender_never_raises_on_an_unreachable_port() -> None:
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    probe.bind(("127.0.0.1", 0))
    address = probe.getsockname()
    probe.close()  # nobody listens there any more
    sender = PlatformSender(address)
    for _ in range(5):
        sender.send(b"x" * 48)
    sender.close()


def test_twin_goes_to_neutral_when_the_datagrams_stop(config: CueingConfig) -> None:
    twin = PlatformTwin(config.platform, 0.01, watchdog=0.1)
    values = np.array([0.2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    twin.receive(encode_platform(0, 0.0, State.RUNNING, 0, True, values))
    for _ in range(5):  # within the watchdog: the command is held
        twin.step()
    assert twin.command[PlatformValue.roll] == pytest.approx(0.2)
    for _ in range(300):  # silence: back to neutral
        twin.step()
    np.testing.assert_allclose(twin.achieved, 0.0, atol=1e-3)
    assert twin.timeouts == 1


def test_twin_ignores_a_datagram_older_than_the_last(config: CueingConfig) -> None:
    # UDP may deliver out of order: an older datagram is counted late and not used (applied,
    # its sequence's wrap would count as 4 billion datagrams lost)
    twin = PlatformTwin(config.platform, 0.01, watchdog=10.0)
    values = np.array([0.2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    twin.receive(encode_platform(5, 0.05, State.RUNNING, 0, True, values))
    twin.receive(encode_platform(4, 0.04, State.RUNNING, 0, True, -values))
    twin.receive(encode_platform(5, 0.05, State.RUNNING, 0, True, -values))
    assert twin.late == 2 and twin.lost == 0 and twin.frames == 1
    np.testing.assert_allclose(twin.command, [0.2, 0.0, 0.0], atol=1e-6)
    twin.receive(encode_platform(8, 0.08, State.RUNNING, 0, True, values))
    assert twin.lost == 2 and twin.frames == 2


def test_twin_follows_the_next_run_from_sequence_zero(config: CueingConfig) -> None:
    # one rig, two runs: after the first run's stream ends (the watchdog's time without a
    # datagram) the second run's sequence starts at 0 again and is followed, not taken late
    twin = PlatformTwin(config.platform, 0.01, watchdog=0.1)
    values = np.array([0.2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    for k in range(50):
        twin.receive(encode_platform(k, 0.01 * k, State.RUNNING, 0, True, values))
        twin.step()
    for _ in range(20):  # 0.2 s without a datagram: neutral
        twin.step()
    twin.receive(encode_platform(0, 0.0, State.RUNNING, 0, True, -values))
    assert twin.late == 0 and twin.frames == 51
    np.testing.assert_allclose(twin.command, -values[:3], atol=1e-6)
