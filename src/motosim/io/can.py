"""The handlebar drive's CAN frames: the DBC, a fast codec for the loop, and the bus link.

The frames are described in a DBC file shipped with the package (``io/data/handlebar.dbc``):
``HB_STATUS`` (drive -> host: handlebar angle [rad], motor current [A], enabled and fault
flags), ``HB_COMMAND`` (host -> drive: current command [A], enable), ``HB_HEARTBEAT`` (host
state and fault reason) and ``HB_ESTOP`` (a button box's emergency stop), and the motion
platform's ``PF_COMMAND`` (host -> platform: roll, pitch, yaw [rad], a live flag) and
``PF_STATUS`` (the platform's achieved angles, a watchdog flag). Every frame
carries a 4-bit alive counter and a CRC-8/SAE-J1850 checksum (polynomial 0x1D, initial value
0xFF, final XOR 0xFF; check value 0x4B on ``b"123456789"``, as in the AUTOSAR E2E profile 1
and the SAE J1850 standard) computed over the frame id's two bytes (little-endian) followed
by the frame with its checksum bits set to zero.

cantools reads the DBC once, outside the loop (:func:`load_dbc`); from it
:func:`handlebar_codecs` builds one :class:`FrameCodec` per frame, plain shifts and masks on
a Python integer, checked against cantools in the tests. A lab whose drive uses other frames
edits the DBC and, if the names differ, a :class:`HandlebarMapping`; not the code. Signals
must be little-endian (Intel byte order).

python-can (LGPL-3.0, the ``rt`` dependency group) carries the frames: :func:`open_link`
opens any of its interfaces (``socketcan:can0`` in a lab, ``virtual`` and ``udp_multicast``
in tests) and is imported only there. Every link is a :class:`Link`. On ``udp_multicast``
it is by default a :class:`UdpMulticastLink`: python-can opens and configures the multicast
socket, and the frames go through it in python-can's own wire format (a msgpack map per
frame) without a ``can.Message`` per frame; processes using python-can on the same group see
the same frames.
"""

import contextlib
import ctypes
import errno
import importlib.resources
import math
import os
import select
import socket
import struct
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import IntEnum
from pathlib import Path
from typing import Any, Self

import numpy as np
from llvmlite import ir
from numba import njit
from numba.core import types
from numba.extending import intrinsic
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.io.bus_spec import check_bus

__all__ = [
    "FRAME_ROW",
    "RECV_AVAILABLE",
    "CanLink",
    "DatagramKind",
    "FrameCodec",
    "FrameColumn",
    "HandlebarCodecs",
    "HandlebarMapping",
    "Link",
    "PlatformCodecs",
    "SignalColumn",
    "SignalLayout",
    "UdpMulticastLink",
    "codec_table",
    "crc8_sae_j1850",
    "datagrams_to_frames",
    "decode_frame",
    "encode_frame",
    "handlebar_codecs",
    "load_dbc",
    "open_link",
    "packaged_dbc",
    "platform_codecs",
    "recv_frames",
    "unpack_frame",
]


def _crc_table() -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
        table.append(crc)
    return tuple(table)


_CRC8 = _crc_table()
_CRC8_TABLE = np.array(_CRC8, dtype=np.uint8)


def crc8_sae_j1850(data: bytes | bytearray, crc: int = 0xFF) -> int:
    """CRC-8/SAE-J1850 of ``data`` (polynomial 0x1D, init 0xFF, final XOR 0xFF).

    ``crc`` continues a running value (its internal form, before the final XOR) when given.

    Examples
    --------
    >>> hex(crc8_sae_j1850(b"123456789"))    # the catalogued check value
    '0x4b'
    """
    table = _CRC8
    for byte in data:
        crc = table[crc ^ byte]
    return crc ^ 0xFF


@dataclass(frozen=True, slots=True)
class SignalLayout:
    """One signal of a frame: little-endian bits ``start`` .. ``start + length - 1``.

    The physical value is ``raw * scale + offset``, ``raw`` two's complement when
    ``is_signed``.
    """

    name: str
    start: int
    length: int
    is_signed: bool
    scale: float
    offset: float

    def __post_init__(self) -> None:
        if not (0 <= self.start and 1 <= self.length and self.start + self.length <= 64):
            raise MotosimError(
                f"signal {self.name}: bits {self.start}+{self.length}; expected within 64 bits"
            )
        if not (math.isfinite(self.scale) and self.scale != 0.0 and math.isfinite(self.offset)):
            raise MotosimError(
                f"signal {self.name}: scale {self.scale!r}, offset {self.offset!r}; "
                "expected a finite non-zero scale and a finite offset"
            )


class FrameColumn(IntEnum):
    """The columns of a codec table's first row, the frame's (:func:`codec_table`)."""

    frame_id = 0
    length = 1
    """[bytes]."""
    checksum_index = 2
    """The checksum signal's index (-1: none)."""
    checksum_shift = 3
    """The checksum's first bit."""
    id_crc = 4
    """The CRC of the frame id's two bytes."""
    counter_index = 5
    """The counter signal's index (-1: none)."""


class SignalColumn(IntEnum):
    """The columns of a codec table's signal rows (:func:`codec_table`)."""

    start = 0
    """Start bit."""
    bits = 1
    """Length [bits]."""
    signed = 2
    """1 for a signed signal, else 0."""
    scale = 3
    offset = 4
    low = 5
    """Lowest raw value."""
    high = 6
    """Highest raw value."""


FRAME_ROW = 0
"""The row of the frame's columns in a codec table; the signals' rows follow it."""


class FrameCodec:
    """Encode and decode one frame: a table of shifts, masks and scalings built once, read by
    the compiled :func:`encode_frame` and :func:`decode_frame` (the real-time period's codec).

    Parameters
    ----------
    frame_id : int
        The 11-bit identifier.
    length : int
        Data length [bytes], 1..8.
    signals : sequence of SignalLayout
        The signals, in the order of the values given to :meth:`encode` and returned by
        :meth:`decode`; at most 63 bits each.
    checksum, counter : str or None
        The names of the CRC-8 and alive-counter signals, if the frame has them.

    Examples
    --------
    >>> codec = FrameCodec(
    ...     0x101, 2, [SignalLayout("A", 0, 8, False, 1.0, 0.0),
    ...                SignalLayout("X", 8, 8, True, 0.5, 0.0)], checksum="A")
    >>> frame = codec.encode([0.0, -1.5])
    >>> out = np.zeros(2)
    >>> codec.decode(frame, out), float(out[1])
    (True, -1.5)
    """

    __slots__ = ("checksum_index", "counter_index", "frame_id", "length", "names", "table")

    def __init__(
        self,
        frame_id: int,
        length: int,
        signals: Sequence[SignalLayout],
        *,
        checksum: str | None = None,
        counter: str | None = None,
    ) -> None:
        if not 0 <= frame_id < 0x800:
            raise MotosimError(f"frame id {frame_id!r}: expected a standard 11-bit id")
        if not 1 <= length <= 8:
            raise MotosimError(f"frame 0x{frame_id:x}: length {length!r}; expected 1..8 bytes")
        self.frame_id = frame_id
        self.length = length
        self.names = tuple(s.name for s in signals)
        self.checksum_index = self.index(checksum) if checksum is not None else -1
        self.counter_index = self.index(counter) if counter is not None else -1
        table = np.zeros((len(signals) + 1, max(len(FrameColumn), len(SignalColumn))))
        for i, s in enumerate(signals):
            if s.start + s.length > 8 * length:
                raise MotosimError(
                    f"signal {s.name} ends at bit {s.start + s.length}; frame 0x{frame_id:x} "
                    f"has {8 * length} bits"
                )
            if s.length > 63:
                raise MotosimError(f"signal {s.name}: {s.length} bits; expected at most 63")
            sign = 1 << (s.length - 1) if s.is_signed else 0
            row = table[FRAME_ROW + 1 + i]
            row[SignalColumn.start], row[SignalColumn.bits] = s.start, s.length
            row[SignalColumn.signed] = 1.0 if s.is_signed else 0.0
            row[SignalColumn.scale], row[SignalColumn.offset] = s.scale, s.offset
            row[SignalColumn.low] = -sign
            row[SignalColumn.high] = sign - 1 if sign else (1 << s.length) - 1
        frame = table[FRAME_ROW]
        frame[FrameColumn.frame_id], frame[FrameColumn.length] = frame_id, length
        frame[FrameColumn.checksum_index] = self.checksum_index
        frame[FrameColumn.counter_index] = self.counter_index
        frame[FrameColumn.id_crc] = crc8_sae_j1850(frame_id.to_bytes(2, "little")) ^ 0xFF
        if self.checksum_index >= 0:
            layout = signals[self.checksum_index]
            if layout.length != 8 or layout.is_signed:
                raise MotosimError(f"checksum {checksum}: expected an unsigned 8-bit signal")
            frame[FrameColumn.checksum_shift] = layout.start
        table.flags.writeable = False
        self.table = table
        """The codec as :func:`encode_frame` and :func:`decode_frame` read it
        (:func:`codec_table`), read-only."""

    def index(self, name: str) -> int:
        """The position of signal ``name`` in the value order."""
        try:
            return self.names.index(name)
        except ValueError:
            raise MotosimError(
                f"frame 0x{self.frame_id:x} has no signal {name!r}; it has {', '.join(self.names)}"
            ) from None

    def encode(self, values: Sequence[float] | NDArray[np.float64]) -> bytes:
        """The frame's bytes for physical ``values`` (saturated to each signal's range).

        The checksum signal's value is ignored and computed; NaN encodes as raw 0.
        """
        given = np.asarray(values, dtype=np.float64)
        if given.shape != (len(self.names),):
            raise MotosimError(
                f"frame 0x{self.frame_id:x}: {given.shape} values; expected {len(self.names)}"
            )
        out = np.zeros(self.length, dtype=np.uint8)
        encode_frame(self.table, given, out, 0)
        return out.tobytes()

    def decode(self, data: bytes | bytearray, out: NDArray[np.float64]) -> bool:
        """Write the physical values of ``data`` into ``out``; False if length or CRC is wrong.

        On a wrong length ``out`` is left unchanged.
        """
        frame = np.frombuffer(bytearray(data), dtype=np.uint8)
        return bool(decode_frame(self.table, frame, 0, frame.size, out))


def codec_table(codec: FrameCodec) -> NDArray[np.float64]:
    """The codec as the array the compiled :func:`encode_frame` and :func:`decode_frame` read,
    a copy the caller may change.

    Row :data:`FRAME_ROW` holds the frame's values (:class:`FrameColumn`), then one row per
    signal holds its values (:class:`SignalColumn`).
    """
    return codec.table.copy()


@njit(cache=True)
def _table_crc(table: NDArray[np.float64], raw: np.uint64) -> int:
    """CRC-8/SAE-J1850 of the frame id and the frame ``raw`` (checksum bits zeroed)."""
    crc = int(table[FRAME_ROW, FrameColumn.id_crc])
    for b in range(int(table[FRAME_ROW, FrameColumn.length])):
        byte = int((raw >> np.uint64(8 * b)) & np.uint64(0xFF))
        crc = int(_CRC8_TABLE[crc ^ byte])
    return crc ^ 0xFF


@njit(cache=True)
def decode_frame(
    table: NDArray[np.float64],
    data: NDArray[np.uint8],
    start: int,
    length: int,
    out: NDArray[np.float64],
) -> bool:
    """:meth:`FrameCodec.decode`, compiled: the frame ``data[start:start + length]``.

    ``table`` is :func:`codec_table`'s; False (``out`` unchanged) on a wrong length, False
    (``out`` written) on a wrong checksum.
    """
    if length != int(table[FRAME_ROW, FrameColumn.length]):
        return False
    raw = np.uint64(0)
    for b in range(length):
        raw |= np.uint64(data[start + b]) << np.uint64(8 * b)
    for i in range(table.shape[0] - 1):
        f = table[FRAME_ROW + 1 + i]
        bits = int(f[SignalColumn.bits])
        mask = (np.uint64(1) << np.uint64(bits)) - np.uint64(1)
        r = np.int64((raw >> np.uint64(int(f[SignalColumn.start]))) & mask)
        if f[SignalColumn.signed] != 0.0 and (r >> np.int64(bits - 1)) & np.int64(1):
            r -= np.int64(1) << np.int64(bits)
        out[i] = r * f[SignalColumn.scale] + f[SignalColumn.offset]
    if table[FRAME_ROW, FrameColumn.checksum_index] < 0.0:
        return True
    shift = np.uint64(int(table[FRAME_ROW, FrameColumn.checksum_shift]))
    keep = ~(np.uint64(0xFF) << shift)
    return _table_crc(table, raw & keep) == int((raw >> shift) & np.uint64(0xFF))


@njit(cache=True)
def encode_frame(
    table: NDArray[np.float64], values: NDArray[np.float64], out: NDArray[np.uint8], start: int
) -> None:
    """:meth:`FrameCodec.encode`, compiled: the frame's bytes into ``out[start:]``.

    Values saturate to each signal's range and round half to even, as Python's ``round``;
    NaN encodes as raw 0; the checksum is computed.
    """
    raw = np.uint64(0)
    for i in range(table.shape[0] - 1):
        f = table[FRAME_ROW + 1 + i]
        v = (values[i] - f[SignalColumn.offset]) / f[SignalColumn.scale]
        r = np.int64(0)
        if v == v:
            r = np.int64(np.rint(min(max(v, f[SignalColumn.low]), f[SignalColumn.high])))
        bits = np.int64(f[SignalColumn.bits])
        mask = (np.int64(1) << bits) - np.int64(1)
        raw |= np.uint64(r & mask) << np.uint64(int(f[SignalColumn.start]))
    if table[FRAME_ROW, FrameColumn.checksum_index] >= 0.0:
        shift = np.uint64(int(table[FRAME_ROW, FrameColumn.checksum_shift]))
        keep = ~(np.uint64(0xFF) << shift)
        raw = (raw & keep) | (np.uint64(_table_crc(table, raw & keep)) << shift)
    for b in range(int(table[FRAME_ROW, FrameColumn.length])):
        out[start + b] = np.uint8((raw >> np.uint64(8 * b)) & np.uint64(0xFF))


_KEY_ID = tuple(b"arbitration_id")
_KEY_ERROR = tuple(b"is_error_frame")
_KEY_REMOTE = tuple(b"is_remote_frame")
_KEY_DATA = tuple(b"data")


@njit(cache=True)
def _byte(buf: NDArray[np.uint8], at: int) -> int:
    """The byte at ``at`` as a signed integer (numba's ``int`` of a uint8 is unsigned)."""
    return int(np.int64(buf[at]))


@njit(cache=True)
def _is_key(buf: NDArray[np.uint8], pos: int, length: int, key: tuple[int, ...]) -> bool:
    if length != len(key):
        return False
    for j in range(length):
        if buf[pos + j] != key[j]:
            return False
    return True


@njit(cache=True)
def _msgpack_size(buf: NDArray[np.uint8], pos: int, end: int) -> tuple[int, int]:
    """(header size, payload size) of the msgpack scalar at ``pos`` (-1, 0: not one)."""
    c = _byte(buf, pos)
    if c < 0x80 or c >= 0xE0 or c == 0xC0 or c == 0xC2 or c == 0xC3:
        return 1, 0
    if 0xA0 <= c <= 0xBF:  # fixstr
        return 1, c & 0x1F
    if c == 0xCC or c == 0xD0:
        return 1, 1
    if c == 0xCD or c == 0xD1:
        return 1, 2
    if c == 0xCE or c == 0xD2 or c == 0xCA:
        return 1, 4
    if c == 0xCF or c == 0xD3 or c == 0xCB:
        return 1, 8
    if (c == 0xD9 or c == 0xC4) and pos + 1 < end:  # str8, bin8
        return 2, _byte(buf, pos + 1)
    if (c == 0xDA or c == 0xC5) and pos + 2 < end:  # str16, bin16
        return 3, (_byte(buf, pos + 1) << 8) | _byte(buf, pos + 2)
    return -1, 0


class DatagramKind(IntEnum):
    """What a ``udp_multicast`` datagram holds (:func:`unpack_frame`)."""

    NOT_A_FRAME = -1
    """Bytes that are no python-can datagram."""
    FLAGGED = 0
    """An error or a remote frame, to ignore."""
    DATA = 1
    """A data frame."""


_NOT_A_FRAME = int(DatagramKind.NOT_A_FRAME)
_FLAGGED = int(DatagramKind.FLAGGED)
_DATA = int(DatagramKind.DATA)


@njit(cache=True)
def unpack_frame(buf: NDArray[np.uint8], start: int, length: int) -> tuple[int, int, int, int]:
    """A python-can ``udp_multicast`` datagram (its ``pack_message``'s msgpack map), compiled.

    Returns ``(kind, frame_id, data_start, data_length)``, ``kind`` a :class:`DatagramKind`
    code.
    """
    end = start + length
    pos = start
    if length < 1:
        return _NOT_A_FRAME, 0, 0, 0
    c = _byte(buf, pos)
    if 0x80 <= c <= 0x8F:
        entries = c & 0x0F
        pos += 1
    elif c == 0xDE and length >= 3:
        entries = (_byte(buf, pos + 1) << 8) | _byte(buf, pos + 2)
        pos += 3
    else:
        return _NOT_A_FRAME, 0, 0, 0
    frame_id, data_start, data_length = -1, 0, -1
    flagged = False
    for _ in range(entries):
        if pos >= end:
            return _NOT_A_FRAME, 0, 0, 0
        head, size = _msgpack_size(buf, pos, end)
        c = _byte(buf, pos)
        if head < 0 or not (0xA0 <= c <= 0xBF or c == 0xD9):  # keys are strings
            return _NOT_A_FRAME, 0, 0, 0
        key, key_length = pos + head, size
        pos = key + key_length
        if pos >= end:
            return _NOT_A_FRAME, 0, 0, 0
        head, size = _msgpack_size(buf, pos, end)
        if head < 0 or pos + head + size > end:
            return _NOT_A_FRAME, 0, 0, 0
        c = _byte(buf, pos)
        value = pos + head
        if _is_key(buf, key, key_length, _KEY_ID):
            if c < 0x80:
                frame_id = c
            elif 0xCC <= c <= 0xCF:
                frame_id = 0
                for j in range(size):
                    frame_id = (frame_id << 8) | _byte(buf, value + j)
            else:
                return _NOT_A_FRAME, 0, 0, 0
        elif _is_key(buf, key, key_length, _KEY_ERROR) or _is_key(
            buf, key, key_length, _KEY_REMOTE
        ):
            flagged = flagged or c == 0xC3
        elif _is_key(buf, key, key_length, _KEY_DATA):
            if c != 0xC4 and c != 0xC5:
                return _NOT_A_FRAME, 0, 0, 0
            data_start, data_length = value, size
        pos = value + size
    if frame_id < 0 or data_length < 0:
        return _NOT_A_FRAME, 0, 0, 0
    return _FLAGGED if flagged else _DATA, frame_id, data_start, data_length


@dataclass(frozen=True, slots=True)
class HandlebarMapping:
    """Which DBC message and signal plays which part (the names of the shipped DBC)."""

    status: str = "HB_STATUS"
    angle: str = "ANGLE"
    current: str = "CURRENT"
    enabled: str = "ENABLED"
    drive_fault: str = "DRIVE_FAULT"
    command: str = "HB_COMMAND"
    current_command: str = "CURRENT_COMMAND"
    enable: str = "ENABLE"
    estop: str = "HB_ESTOP"
    estop_signal: str = "ESTOP"
    heartbeat: str = "HB_HEARTBEAT"
    state: str = "STATE"
    fault: str = "FAULT"
    torque: str = "HB_TORQUE"
    rider_torque: str = "RIDER_TORQUE"
    counter: str = "COUNTER"
    checksum: str = "CHECKSUM"


@dataclass(frozen=True, slots=True)
class HandlebarCodecs:
    """The four frames' codecs and the positions of the signals the loop and the rig use;
    ``torque``, the optional torque sensor's frame (None when the DBC has none)."""

    status: FrameCodec
    command: FrameCodec
    estop: FrameCodec
    heartbeat: FrameCodec
    mapping: HandlebarMapping
    torque: FrameCodec | None = None

    def position(self, frame: FrameCodec, part: str) -> int:
        """Where the signal playing ``part`` (a :class:`HandlebarMapping` field) sits."""
        return frame.index(getattr(self.mapping, part))


def packaged_dbc() -> Path:
    """The DBC shipped with motosim (``motosim/io/data/handlebar.dbc``)."""
    return Path(str(importlib.resources.files("motosim.io") / "data" / "handlebar.dbc"))


def load_dbc(path: str | Path | None = None) -> Any:
    """Read a DBC with cantools (the packaged one by default): a ``cantools`` Database."""
    try:
        import cantools
    except ImportError:
        raise MotosimError(
            "cantools is not installed; install motosim's rt group: pip install 'motosim[rt]'"
        ) from None
    source = packaged_dbc() if path is None else Path(path)
    try:
        return cantools.database.load_file(str(source), database_format="dbc")
    except FileNotFoundError:
        raise MotosimError(f"{source}: no such DBC file") from None
    except Exception as err:  # cantools raises several parser errors
        raise MotosimError(f"{source}: not a readable DBC file: {err}") from None


def _codec(db: Any, name: str, mapping: HandlebarMapping) -> FrameCodec:
    try:
        message = db.get_message_by_name(name)
    except KeyError:
        raise MotosimError(f"the DBC has no message {name!r}") from None
    layouts = []
    for s in message.signals:
        if s.byte_order != "little_endian" and s.length > 1:
            raise MotosimError(
                f"signal {name}.{s.name} is big-endian; expected little-endian (Intel) signals"
            )
        layouts.append(
            SignalLayout(s.name, s.start, s.length, s.is_signed, float(s.scale), float(s.offset))
        )
    names = {s.name for s in layouts}
    return FrameCodec(
        message.frame_id,
        message.length,
        layouts,
        checksum=mapping.checksum if mapping.checksum in names else None,
        counter=mapping.counter if mapping.counter in names else None,
    )


def handlebar_codecs(
    path: str | Path | None = None, *, mapping: HandlebarMapping | None = None
) -> HandlebarCodecs:
    """Codecs of the handlebar frames from a DBC (the packaged one by default).

    Examples
    --------
    >>> codecs = handlebar_codecs()
    >>> hex(codecs.status.frame_id), codecs.status.names[codecs.position(codecs.status, "angle")]
    ('0x101', 'ANGLE')
    >>> t = codecs.torque
    >>> values = np.zeros(len(t.names)); values[codecs.position(t, "rider_torque")] = -12.34
    >>> out = np.zeros(len(t.names)); t.decode(t.encode(values), out)
    True
    >>> round(float(out[codecs.position(t, "rider_torque")]), 2)
    -12.34
    """
    mapping = mapping or HandlebarMapping()
    db = load_dbc(path)
    names = {message.name for message in db.messages}
    codecs = HandlebarCodecs(
        status=_codec(db, mapping.status, mapping),
        command=_codec(db, mapping.command, mapping),
        estop=_codec(db, mapping.estop, mapping),
        heartbeat=_codec(db, mapping.heartbeat, mapping),
        mapping=mapping,
        torque=_codec(db, mapping.torque, mapping) if mapping.torque in names else None,
    )
    if codecs.torque is not None:
        for part in ("rider_torque", "counter", "checksum"):
            codecs.position(codecs.torque, part)
    for frame, parts in (
        (codecs.status, ("angle", "current", "enabled", "drive_fault", "counter", "checksum")),
        (codecs.command, ("current_command", "enable", "counter", "checksum")),
        (codecs.estop, ("estop_signal", "counter", "checksum")),
        (codecs.heartbeat, ("state", "fault", "counter", "checksum")),
    ):
        for part in parts:
            codecs.position(frame, part)  # every signal the loop needs is there
    return codecs


@dataclass(frozen=True, slots=True)
class PlatformCodecs:
    """The motion platform's frames: ``PF_COMMAND`` (host -> platform) and ``PF_STATUS``.

    Both carry ``ROLL``, ``PITCH``, ``YAW`` [rad], a 4-bit ``COUNTER`` and the ``CHECKSUM``
    of the handlebar frames; the command has a ``LIVE`` flag (0: go to neutral), the status a
    ``WATCHDOG`` flag. ``angles`` are the positions of roll, pitch and yaw in each.
    """

    command: FrameCodec
    status: FrameCodec
    command_angles: tuple[int, int, int]
    status_angles: tuple[int, int, int]
    live: int
    watchdog: int


def platform_codecs(path: str | Path | None = None) -> PlatformCodecs:
    """Codecs of the platform frames from a DBC (the packaged one by default).

    Raises
    ------
    MotosimError
        If the DBC lacks ``PF_COMMAND`` or ``PF_STATUS`` or one of their signals.

    Examples
    --------
    >>> codecs = platform_codecs()
    >>> hex(codecs.command.frame_id), codecs.command.names[codecs.command_angles[1]]
    ('0x200', 'PITCH')
    """
    mapping = HandlebarMapping()
    db = load_dbc(path)
    command = _codec(db, "PF_COMMAND", mapping)
    status = _codec(db, "PF_STATUS", mapping)
    for frame in (command, status):
        if frame.checksum_index < 0 or frame.counter_index < 0:
            raise MotosimError(
                f"frame 0x{frame.frame_id:x}: expected the {mapping.checksum} and "
                f"{mapping.counter} signals"
            )

    def angles(frame: FrameCodec) -> tuple[int, int, int]:
        return frame.index("ROLL"), frame.index("PITCH"), frame.index("YAW")

    live, watchdog = command.index("LIVE"), status.index("WATCHDOG")
    return PlatformCodecs(command, status, angles(command), angles(status), live, watchdog)


Rows = NDArray[np.uint8]
"""Rows of one frame each: a C-contiguous ``uint8`` array of shape (frames, bytes)."""

Ints = NDArray[np.int64]


class Link:
    """A CAN link to the drive, whatever its transport: what the real-time runner and the
    virtual rig use of it.

    A transport gives :meth:`send` and :meth:`receive`; the other methods work frame by frame
    from those two, and a transport with a faster path overrides them in its own class
    (:class:`UdpMulticastLink`: python-can's datagrams sent and read whole, its socket read
    from compiled code by :func:`recv_frames`). Whatever the transport, what is read is
    frames: each one's data bytes, length and id. A link is a context manager that closes
    it.
    """

    errors = 0
    """Frames that could not be sent or read, and reads that were no frame."""
    label = "python-can"
    """How a run's timing report names the link."""

    def send(self, frame_id: int, data: bytes) -> bool:
        """Send one standard frame; False if the bus refused it."""
        raise NotImplementedError

    def receive(self, timeout: float = 0.0) -> tuple[int, bytes] | None:
        """The next frame ``(frame_id, data)``, or None if none came within ``timeout`` [s]."""
        raise NotImplementedError

    def frame_buffer(self, frame_id: int, length: int) -> tuple[NDArray[np.uint8], int]:
        """The bytes to send for a frame of ``length`` data bytes, data zero, and where its
        data starts in them (the period encodes the frame in place)."""
        return np.zeros(length, dtype=np.uint8), 0

    def sender(self, frame_id: int, buffer: NDArray[np.uint8]) -> Callable[[], bool]:
        """A function sending ``buffer`` (made by :meth:`frame_buffer`) as it is when it is
        called; False if refused."""
        send = self.send
        return lambda: send(frame_id, buffer.tobytes())

    def receive_into(
        self, rows: Rows, lengths: Ints, ids: Ints, start: int, timeout: float = 0.0
    ) -> int:
        """Read the frames waiting into ``rows[start:]`` (their data bytes from each row's
        start, their sizes into ``lengths``, their ids into ``ids``); the index after the
        last one. With ``timeout`` > 0, at most one, waiting up to ``timeout`` [s] for it.
        Here by :meth:`receive`, a frame's data cut to its row."""
        receive = self.receive
        n = start
        while n < rows.shape[0]:  # bounded: a flooded bus cannot hold the loop
            frame = receive(timeout)
            if frame is None:
                break
            data = frame[1][: rows.shape[1]]
            ids[n] = frame[0]
            lengths[n] = len(data)
            rows[n, : len(data)] = np.frombuffer(data, dtype=np.uint8)
            n += 1
            if timeout > 0.0:
                break
        return n

    def compiled_fd(self) -> int:
        """A non-blocking socket whose frames compiled code may read with ``recv``
        (:func:`recv_frames`), or -1 (here: none)."""
        return -1

    def close(self) -> None:
        """Close the link (here: nothing to close)."""

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class CanLink(Link):
    """A python-can bus carrying raw frames: non-blocking receive, send that reports failure.

    Made by :func:`open_link`; ``bus`` is any ``can.BusABC``.
    """

    __slots__ = ("_bus", "_message", "_messages", "errors", "spec")

    def __init__(self, bus: Any, spec: str) -> None:
        import can

        self._bus = bus
        self._message = can.Message
        self._messages: dict[int, Any] = {}
        self.spec = spec
        self.errors = 0

    def send(self, frame_id: int, data: bytes) -> bool:
        """Send one standard frame; False (and ``errors`` + 1) if the bus refused it.

        One ``can.Message`` per frame id is made on its first send and reused, its data and
        length replaced (python-can's interfaces copy the message's fields when they send).
        """
        msg = self._messages.get(frame_id)
        if msg is None:
            msg = self._messages[frame_id] = self._message(
                arbitration_id=frame_id, data=data, is_extended_id=False
            )
        else:
            msg.data = bytearray(data)
            msg.dlc = len(data)
        try:
            self._bus.send(msg, timeout=0.0)
        except Exception:  # can.CanError (bus-off, buffer full) or an OS error
            self.errors += 1
            return False
        return True

    def receive(self, timeout: float = 0.0) -> tuple[int, bytes] | None:
        """The next received frame as ``(frame_id, data)``, or None if none came in ``timeout``."""
        try:
            msg = self._bus.recv(timeout)
        except Exception:
            self.errors += 1
            return None
        if msg is None or msg.is_error_frame or msg.is_remote_frame:
            return None
        return msg.arbitration_id, bytes(msg.data)

    def close(self) -> None:
        """Shut the bus down."""
        self._bus.shutdown()


RECV_AVAILABLE = sys.platform == "linux"
"""Whether :func:`recv_frames` can read a socket from compiled code here (Linux: the C
library's ``recv`` with ``MSG_DONTWAIT`` and its ``errno`` through ``__errno_location``)."""

_MSG_DONTWAIT = getattr(socket, "MSG_DONTWAIT", 0)
_EAGAIN, _EWOULDBLOCK, _EINTR = errno.EAGAIN, errno.EWOULDBLOCK, errno.EINTR


@intrinsic
def _recv(typingctx: Any, fd: Any, buffer: Any, size: Any) -> Any:
    """``recv(fd, buffer, size, MSG_DONTWAIT)`` called from compiled code: the bytes read,
    or minus ``errno`` where it failed (``-EAGAIN``: nothing waiting). ``buffer`` is a
    C-contiguous ``uint8`` array of at least ``size`` bytes (Linux only)."""
    if not (
        isinstance(fd, types.Integer)
        and isinstance(size, types.Integer)
        and isinstance(buffer, types.Array)
        and buffer.dtype == types.uint8
        and buffer.layout == "C"
    ):
        return None

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        i32, i64 = ir.IntType(32), ir.IntType(64)
        i8p = ir.IntType(8).as_pointer()
        fd_type, buffer_type, size_type = signature.args
        handle = context.cast(builder, args[0], fd_type, types.int64)
        count = context.cast(builder, args[2], size_type, types.int64)
        data = builder.bitcast(context.make_array(buffer_type)(context, builder, args[1]).data, i8p)
        module = builder.module
        recv = module.globals.get("recv") or ir.Function(
            module, ir.FunctionType(i64, [i32, i8p, i64, i32]), "recv"
        )
        where = module.globals.get("__errno_location") or ir.Function(
            module, ir.FunctionType(i32.as_pointer(), []), "__errno_location"
        )
        got = builder.call(
            recv, [builder.trunc(handle, i32), data, count, ir.Constant(i32, _MSG_DONTWAIT)]
        )
        failed = builder.icmp_signed("<", got, ir.Constant(i64, 0))
        code = builder.sext(builder.load(builder.call(where, [])), i64)
        return builder.select(failed, builder.neg(code), got)

    return types.int64(fd, buffer, size), codegen


_read: Any = _recv
""":func:`_recv` as compiled code calls it (numba's typing context fills ``typingctx``)."""


@njit(cache=True)
def datagrams_to_frames(
    rx: Rows, lengths: Ints, ids: Ints, first: int, end: int
) -> tuple[int, int]:
    """python-can ``udp_multicast`` datagrams in ``rx[first:end]`` (their sizes in
    ``lengths``) turned into frames in place: each data frame's bytes moved to the start of
    a row, in order from ``rx[first]``, its length into ``lengths`` and its id into ``ids``;
    error and remote frames dropped. Returns the index after the last frame and the number
    of datagrams that were no frame."""
    n, bad = first, 0
    for j in range(first, end):
        kind, frame_id, start, length = unpack_frame(rx[j], 0, lengths[j])
        if kind == _NOT_A_FRAME:
            bad += 1
        elif kind == _DATA:
            row, datagram = rx[n], rx[j]
            for b in range(length):  # each byte to an index no later than its own
                row[b] = datagram[start + b]
            ids[n], lengths[n] = frame_id, length
            n += 1
    return n, bad


@njit(cache=True)
def recv_frames(fd: int, rx: Rows, lengths: Ints, ids: Ints) -> tuple[int, int, int]:
    """Read the frames waiting on the ``udp_multicast`` socket ``fd`` (non-blocking) into
    ``rx``'s rows (:func:`datagrams_to_frames`), at most a datagram a row; the frames read,
    the reads that failed otherwise than "nothing waiting" and the datagrams that were no
    frame.

    The compiled twin of :meth:`UdpMulticastLink.receive_into`: a datagram longer than a
    row is cut to it, as ``recv_into`` cuts it; an interrupted read is tried again (as
    Python does, PEP 475); "nothing waiting" (``EAGAIN``) ends the read, any other error
    too. Linux only (:data:`RECV_AVAILABLE`).
    """
    size = rx.shape[1]
    n, errors = 0, 0
    while n < rx.shape[0]:
        got = _read(fd, rx[n], size)
        if got >= 0:
            lengths[n] = got
            n += 1
        elif got != -_EINTR:
            errors = 0 if got == -_EAGAIN or got == -_EWOULDBLOCK else 1
            break
    frames, bad = datagrams_to_frames(rx, lengths, ids, 0, n)
    return frames, errors, bad


class UdpMulticastLink(Link):
    """python-can's ``udp_multicast`` frames on its own socket, without a message per frame.

    python-can's ``UdpMulticastBus`` packs each frame as a msgpack map of the fields of
    ``can.Message`` and unpacks each received one into a new, checked ``can.Message``. This
    link keeps the bus (for its socket's set-up and for :meth:`close`), sends the bytes
    python-can's ``pack_message`` gives for the frame (built once per frame id and length,
    only the data bytes changing), and reads datagrams with a non-blocking ``recv`` decoded
    by msgpack's C unpacker. On Linux the socket takes only its own group's datagrams
    (``IP_MULTICAST_ALL`` and ``IPV6_MULTICAST_ALL`` off; by default a socket bound to the
    port gets every group joined on the machine), so two rigs on one PC on different groups
    (``udp_multicast:GROUP``) do not hear each other. Made by :func:`open_link`.

    Multicast on one PC loops every datagram back to every socket of the group, the
    sender's own included, and python-can's sockets all send from the group's port. So this
    link sends from a socket of its own (an ephemeral port, the bus's hop limit and
    interface) and, on Linux, gives its receiving socket a classic BPF filter
    (``SO_ATTACH_FILTER``, the kernel's ``Documentation/networking/filter.rst``) that drops
    the datagrams whose UDP source port is that one, in the kernel, before they are queued.
    :attr:`own_filtered` says whether the filter is on (elsewhere the frames are read back
    and ignored).

    Parameters
    ----------
    bus : can.interfaces.udp_multicast.UdpMulticastBus
        An open bus.
    group : str
        Its multicast group (the bus's channel).
    port : int
        Its UDP port.
    spec : str
        The ``--bus`` text it was opened from.
    """

    __slots__ = (
        "_bus",
        "_dest",
        "_out",
        "_poll",
        "_sock",
        "_templates",
        "_unpack",
        "errors",
        "own_filtered",
        "spec",
    )
    label = "fast"

    def __init__(self, bus: Any, group: str, port: int, spec: str) -> None:
        import msgpack  # type: ignore[import-untyped]  # python-can[multicast] brings it

        self._bus = bus
        self._sock = socket.socket(fileno=os.dup(bus.fileno()))
        self._sock.setblocking(False)
        # IP_MULTICAST_ALL and IPV6_MULTICAST_ALL off (Linux): only this group's frames
        for level, option in ((socket.IPPROTO_IP, 49), (socket.IPPROTO_IPV6, 29)):
            with contextlib.suppress(OSError):
                self._sock.setsockopt(level, option, 0)
        self._dest = (group, port)
        self._out = _sender_like(self._sock)
        self.own_filtered = _drop_source_port(self._sock, self._out.getsockname()[1])
        self._poll = select.poll()
        self._poll.register(self._sock.fileno(), select.POLLIN)
        self._unpack = msgpack.unpackb
        self._templates: dict[tuple[int, int], tuple[bytes, bytes]] = {}
        self.spec = spec
        self.errors = 0

    @staticmethod
    def _template(frame_id: int, length: int) -> tuple[bytes, bytes]:
        """python-can's packed bytes of this frame around its data: (before, after)."""
        import can
        from can.interfaces.udp_multicast.utils import pack_message

        def packed(fill: int) -> bytes:
            data = bytes([fill]) * length
            return pack_message(
                can.Message(arbitration_id=frame_id, data=data, is_extended_id=False)
            )

        zeros, ones = packed(0x00), packed(0xFF)
        start = next(i for i, (a, b) in enumerate(zip(zeros, ones, strict=True)) if a != b)
        return zeros[:start], zeros[start + length :]

    def send(self, frame_id: int, data: bytes) -> bool:
        """Send one standard frame; False (and ``errors`` + 1) if the socket refused it."""
        key = (frame_id, len(data))
        template = self._templates.get(key)
        if template is None:
            template = self._templates[key] = self._template(frame_id, len(data))
        return self._send(template[0] + data + template[1])

    def _send(self, datagram: Any) -> bool:
        try:
            self._out.sendto(datagram, self._dest)
        except OSError:
            self.errors += 1
            return False
        return True

    def frame_buffer(self, frame_id: int, length: int) -> tuple[NDArray[np.uint8], int]:
        """python-can's packed bytes of a frame, data zero, and where its data bytes start."""
        before, after = self._template(frame_id, length)
        packed = np.frombuffer(before + bytes(length) + after, dtype=np.uint8).copy()
        return packed, len(before)

    def sender(self, frame_id: int, buffer: NDArray[np.uint8]) -> Callable[[], bool]:
        """A function sending ``buffer`` as one datagram; False (``errors`` + 1) if refused."""
        view = memoryview(buffer)  # type: ignore[arg-type]
        return lambda: self._send(view)

    def receive_into(
        self, rows: Rows, lengths: Ints, ids: Ints, start: int, timeout: float = 0.0
    ) -> int:
        """:meth:`Link.receive_into`: whole datagrams read, then turned into frames in place
        (:func:`datagrams_to_frames`; a datagram that is no frame counts in :attr:`errors`)."""
        limit = rows.shape[0]
        if timeout > 0.0:
            if not self.readable(timeout):
                return start
            limit = min(limit, start + 1)
        poll = self._poll.poll
        recv_into = self._sock.recv_into
        n = start
        while n < limit and poll(0):
            try:
                lengths[n] = recv_into(rows[n])
            except BlockingIOError:
                break
            except OSError:
                self.errors += 1
                break
            n += 1
        end, bad = datagrams_to_frames(rows, lengths, ids, start, n)
        self.errors += bad
        return end

    def compiled_fd(self) -> int:
        """The receiving socket's file descriptor (non-blocking), or -1 where compiled code
        cannot read it (:data:`RECV_AVAILABLE`)."""
        fd: int = self._sock.fileno()
        return fd if RECV_AVAILABLE else -1

    def readable(self, timeout: float) -> bool:
        """Wait up to ``timeout`` [s] for a datagram; whether one is waiting."""
        return bool(select.select([self._sock], (), (), timeout)[0])

    def receive(self, timeout: float = 0.0) -> tuple[int, bytes] | None:
        """The next received frame as ``(frame_id, data)``, or None if none came in ``timeout``.

        Error and remote frames, and datagrams that are not python-can frames, give None
        (and the latter count in ``errors``).
        """
        # poll first: it is cheaper than an empty non-blocking recv, which raises; a timed
        # wait uses select, whose timeout is not rounded to milliseconds
        if not (self._poll.poll(0) if timeout <= 0.0 else self.readable(timeout)):
            return None
        try:
            raw = self._sock.recv(4096)
        except BlockingIOError:
            return None
        except OSError:
            self.errors += 1
            return None
        try:
            m = self._unpack(raw)
            if m["is_error_frame"] or m["is_remote_frame"]:
                return None
            return int(m["arbitration_id"]), bytes(m["data"])
        except Exception:  # not a python-can frame
            self.errors += 1
            return None

    def close(self) -> None:
        """Close the sockets and shut the bus down."""
        self._out.close()
        self._sock.close()
        self._bus.shutdown()


def _sender_like(sock: Any) -> Any:
    """A non-blocking UDP socket on an ephemeral port that sends to the multicast group as
    ``sock`` does (its hop limit and interface)."""
    v6 = sock.family == socket.AF_INET6
    level = socket.IPPROTO_IPV6 if v6 else socket.IPPROTO_IP
    hops = socket.IPV6_MULTICAST_HOPS if v6 else socket.IP_MULTICAST_TTL
    out = socket.socket(sock.family, socket.SOCK_DGRAM)
    out.bind(("::", 0) if v6 else ("0.0.0.0", 0))
    out.setsockopt(level, hops, sock.getsockopt(level, hops))
    with contextlib.suppress(OSError):  # the interface, where the bus chose one
        option = socket.IPV6_MULTICAST_IF if v6 else socket.IP_MULTICAST_IF
        chosen = sock.getsockopt(level, option) if v6 else sock.getsockopt(level, option, 4)
        out.setsockopt(level, option, chosen)
    out.setblocking(False)
    return out


def _drop_source_port(sock: Any, port: int) -> bool:
    """Attach to ``sock`` a classic BPF filter that drops UDP datagrams from ``port``; False
    where the system has no such filter (not Linux).

    The program (``struct sock_filter`` instructions, BPF_LD|BPF_H|BPF_ABS and so on) sees
    a UDP socket's datagram from its UDP header, whose first 16 bits are the source port.
    """
    program = (
        (0x28, 0, 0, 0),  # ldh [0]: the source port
        (0x15, 0, 1, port),  # jeq #port, next, skip one
        (0x06, 0, 0, 0),  # ret #0: drop
        (0x06, 0, 0, 0xFFFFFFFF),  # ret #-1: keep the whole datagram
    )
    code = ctypes.create_string_buffer(b"".join(struct.pack("HBBI", *i) for i in program))
    fprog = struct.pack("HL", len(program), ctypes.addressof(code))
    try:
        sock.setsockopt(socket.SOL_SOCKET, getattr(socket, "SO_ATTACH_FILTER", 26), fprog)
    except OSError:
        return False
    return True


_DEFAULT_CHANNELS = {"virtual": "motosim", "udp_multicast": None}


def open_link(spec: str, *, fast: bool = True) -> Link:
    """Open a python-can bus from ``INTERFACE[:CHANNEL]``.

    Examples: ``socketcan:can0`` (a lab; set the bitrate with ``ip link``), ``virtual``
    (in-process, channel ``motosim``), ``udp_multicast`` (between processes on one machine,
    python-can's default group). With ``fast`` (the default) a ``udp_multicast`` bus is a
    :class:`UdpMulticastLink` (the same frames on the wire); else every bus is a
    :class:`CanLink`.
    """
    interface, channel = check_bus(spec)
    import can

    kwargs: dict[str, Any] = {"interface": interface}
    chosen = channel or _DEFAULT_CHANNELS.get(interface)
    if chosen is not None:
        kwargs["channel"] = chosen
    try:
        bus = can.Bus(**kwargs)
    except Exception as err:  # unknown interface, missing device, no permission
        first = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise MotosimError(f"--bus {spec!r}: cannot open the CAN bus: {first}") from None
    if fast and interface == "udp_multicast":
        from can.interfaces.udp_multicast import UdpMulticastBus

        group = chosen or UdpMulticastBus.DEFAULT_GROUP_IPv6
        return UdpMulticastLink(bus, group, 43113, spec)  # python-can's default port
    return CanLink(bus, spec)
