"""The handlebar frames: the fast codec against cantools, the CRC-8, the python-can link."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motosim.errors import MotosimError
from motosim.io.can import (
    DatagramKind,
    FrameCodec,
    SignalLayout,
    codec_table,
    crc8_sae_j1850,
    datagrams_to_frames,
    decode_frame,
    encode_frame,
    handlebar_codecs,
    load_dbc,
    open_link,
    platform_codecs,
    unpack_frame,
)

pytest.importorskip("cantools", reason="cantools is in the rt and dev dependency groups")

CODECS = handlebar_codecs()
DB = load_dbc()
PLATFORM = platform_codecs()
FRAMES = {
    c.frame_id: c
    for c in (
        CODECS.status,
        CODECS.command,
        CODECS.estop,
        CODECS.heartbeat,
        CODECS.torque,
        PLATFORM.command,
        PLATFORM.status,
    )
    if c is not None
}


def test_crc8_check_values() -> None:
    # Catalogue of parametrised CRC algorithms (Greg Cook, "CRC-8/SAE-J1850"): check 0x4B,
    # residue 0xC4; and the all-zero four-byte example of the AUTOSAR CRC library
    # specification (SWS_CRCLibrary, table of SAE-J1850 results): 00 00 00 00 -> 0x59.
    assert crc8_sae_j1850(b"123456789") == 0x4B
    assert crc8_sae_j1850(b"\x00\x00\x00\x00") == 0x59
    assert crc8_sae_j1850(b"\xf2\x01\x83") == 0x37


def _physical(message: object, draw: st.DrawFn) -> dict[str, float]:
    values = {}
    for s in message.signals:  # type: ignore[attr-defined]
        lo = -(1 << (s.length - 1)) if s.is_signed else 0
        hi = (1 << (s.length - 1)) - 1 if s.is_signed else (1 << s.length) - 1
        values[s.name] = draw(st.integers(lo, hi)) * s.scale + s.offset
    return values


@settings(max_examples=200, deadline=None)
@given(st.data())
def test_codec_agrees_with_cantools_both_ways(data: st.DataObject) -> None:
    message = data.draw(st.sampled_from(DB.messages))
    codec = FRAMES[message.frame_id]
    values = _physical(message, data.draw)
    ours = codec.encode([values[n] for n in codec.names])
    # cantools knows nothing of the CRC: give it ours, then the bytes must be the same.
    values["CHECKSUM"] = ours[0]
    assert ours == message.encode(values, scaling=True, strict=True)
    out = np.zeros(len(codec.names))
    assert codec.decode(ours, out)
    theirs = message.decode(ours, decode_choices=False)
    for name, value in zip(codec.names, out, strict=True):
        assert value == pytest.approx(theirs[name], rel=1e-12, abs=1e-12)


@settings(max_examples=200, deadline=None)
@given(st.data())
def test_compiled_codec_agrees_with_cantools_both_ways(data: st.DataObject) -> None:
    # the compiled codec as the fused period calls it, on a codec table's copy and at an
    # offset in a longer buffer, against cantools' reading of the DBC
    message = data.draw(st.sampled_from(DB.messages))
    codec = FRAMES[message.frame_id]
    table = codec_table(codec)
    values = _physical(message, data.draw)
    frame = np.zeros(3 + codec.length, dtype=np.uint8)
    encode_frame(table, np.array([values[n] for n in codec.names]), frame, 3)
    ours = frame[3:].tobytes()
    values["CHECKSUM"] = ours[0]
    assert ours == message.encode(values, scaling=True, strict=True)
    out = np.zeros(len(codec.names))
    assert decode_frame(table, frame, 3, codec.length, out)
    theirs = message.decode(ours, decode_choices=False)
    for name, value in zip(codec.names, out, strict=True):
        assert value == pytest.approx(theirs[name], rel=1e-12, abs=1e-12)


@settings(max_examples=100, deadline=None)
@given(
    st.integers(0, 0x7FF),
    st.binary(max_size=8),
    st.booleans(),
    st.floats(0.0, 1e9),
    st.sampled_from([None, "can0", 3]),
)
def test_udp_multicast_datagrams_are_read_as_python_can_packs_them(
    frame_id: int, payload: bytes, error: bool, stamp: float, channel: object
) -> None:
    can = pytest.importorskip("can", reason="python-can is in the rt and dev dependency groups")
    pytest.importorskip("msgpack", reason="python-can's udp_multicast needs msgpack")
    from can.interfaces.udp_multicast.utils import pack_message

    message = can.Message(
        arbitration_id=frame_id,
        data=payload,
        is_extended_id=False,
        is_error_frame=error,
        timestamp=stamp,
        channel=channel,
    )
    datagram = np.frombuffer(b"xx" + pack_message(message), dtype=np.uint8)
    kind, got, start, length = unpack_frame(datagram, 2, datagram.size - 2)
    assert (kind, got, datagram[start : start + length].tobytes()) == (
        DatagramKind.FLAGGED if error else DatagramKind.DATA,
        frame_id,
        payload,
    )
    assert unpack_frame(datagram, 2, datagram.size - 3)[0] == DatagramKind.NOT_A_FRAME  # cut
    not_a_map = np.frombuffer(b"\x93\x01\x02\x03", np.uint8)
    assert unpack_frame(not_a_map, 0, 4)[0] == DatagramKind.NOT_A_FRAME


def test_datagrams_become_frames_in_order_and_the_rest_is_counted() -> None:
    """What a ``udp_multicast`` read leaves to the period: frames only (python-can's own
    ``pack_message`` makes the datagrams), the error frame dropped, bytes that are no
    datagram counted, the frames moved to the first rows in their order."""
    can = pytest.importorskip("can", reason="python-can is in the rt and dev dependency groups")
    pytest.importorskip("msgpack", reason="python-can's udp_multicast needs msgpack")
    from can.interfaces.udp_multicast.utils import pack_message

    def packed(frame_id: int, data: bytes, error: bool = False) -> bytes:
        message = can.Message(
            arbitration_id=frame_id, data=data, is_extended_id=False, is_error_frame=error
        )
        return bytes(pack_message(message))

    datagrams = [
        b"\x93\x01\x02\x03",  # no python-can map
        packed(0x101, bytes(range(8))),
        packed(0x180, b"\x01", error=True),
        packed(0x100, b"\xaa\x55"),
    ]
    rx = np.zeros((6, 512), dtype=np.uint8)  # rows as long as the loop's (fused.RX_BYTES)
    lengths = np.zeros(6, dtype=np.int64)
    ids = np.full(6, -1, dtype=np.int64)
    for j, datagram in enumerate(datagrams, start=1):  # from row 1: a read's ``start``
        rx[j, : len(datagram)] = np.frombuffer(datagram, dtype=np.uint8)
        lengths[j] = len(datagram)
    end, bad = datagrams_to_frames(rx, lengths, ids, 1, 1 + len(datagrams))
    assert (end, bad) == (3, 1)
    assert ids[1:3].tolist() == [0x101, 0x100] and lengths[1:3].tolist() == [8, 2]
    assert rx[1, :8].tobytes() == bytes(range(8)) and rx[2, :2].tobytes() == b"\xaa\x55"
    assert ids[0] == -1 and not rx[0].any()  # the rows before ``start`` untouched


def test_every_frame_of_the_dbc_has_a_codec() -> None:
    # the handlebar's four frames, the optional torque sensor's HB_TORQUE (0x102) and the
    # platform's PF_COMMAND (0x200) and PF_STATUS (0x201)
    expected = {16, 128, 256, 257, 258, 512, 513}
    assert {m.frame_id for m in DB.messages} == set(FRAMES) == expected


def test_platform_angles_are_quantised_at_1e4_rad() -> None:
    codec = PLATFORM.command
    values = np.zeros(len(codec.names))
    values[list(PLATFORM.command_angles)] = (0.123456, -0.2, 4.0)  # 4 rad saturates at 3.2767
    out = np.zeros_like(values)
    assert codec.decode(codec.encode(values), out)
    assert out[list(PLATFORM.command_angles)] == pytest.approx([0.1235, -0.2, 3.2767])


def test_quantisation_and_saturation_follow_the_dbc_scaling() -> None:
    codec = CODECS.status
    angle, current = codec.index("ANGLE"), codec.index("CURRENT")
    values = np.zeros(len(codec.names))
    values[angle], values[current] = 0.123456789, 99.0  # the DBC: 1e-5 rad, 0.001 A, +-32.767
    out = np.zeros_like(values)
    assert codec.decode(codec.encode(values), out)
    assert out[angle] == pytest.approx(0.12346) and out[current] == pytest.approx(32.767)
    values[current] = float("nan")
    codec.decode(codec.encode(values), out)
    assert out[current] == 0.0


@pytest.mark.parametrize("bit", range(64))
def test_any_flipped_bit_fails_the_checksum(bit: int) -> None:
    codec = CODECS.status
    frame = bytearray(codec.encode(np.linspace(0.1, 0.7, len(codec.names))))
    frame[bit // 8] ^= 1 << (bit % 8)
    assert not codec.decode(bytes(frame), np.zeros(len(codec.names)))


def test_a_frame_of_another_id_or_length_fails() -> None:
    status, command = CODECS.status, CODECS.command
    frame = command.encode(np.zeros(len(command.names)))
    assert len(frame) == status.length
    assert not status.decode(frame, np.zeros(len(status.names)))  # the id is in the CRC
    assert not status.decode(frame[:4], np.zeros(len(status.names)))


def test_bad_layouts_and_names_are_refused() -> None:
    with pytest.raises(MotosimError, match="within 64 bits"):
        SignalLayout("X", 60, 8, False, 1.0, 0.0)
    with pytest.raises(MotosimError, match="has 16 bits"):
        FrameCodec(1, 2, [SignalLayout("X", 8, 16, False, 1.0, 0.0)])
    with pytest.raises(MotosimError, match="no signal 'Y'"):
        CODECS.status.index("Y")
    with pytest.raises(MotosimError, match="no such DBC"):
        load_dbc("/nonexistent.dbc")


def test_the_virtual_link_carries_frames_both_ways() -> None:
    pytest.importorskip("can", reason="python-can is in the rt and dev dependency groups")
    with open_link("virtual:test_link") as a, open_link("virtual:test_link") as b:
        assert a.send(0x101, b"\x01\x02") and b.receive() == (0x101, b"\x01\x02")
        assert b.receive() is None and a.receive() is None


def test_an_unknown_interface_is_one_line() -> None:
    pytest.importorskip("can", reason="python-can is in the rt and dev dependency groups")
    with pytest.raises(MotosimError, match=r"expected INTERFACE.*with a python-can interface"):
        open_link("nosuchinterface:x")  # refused before python-can is asked
