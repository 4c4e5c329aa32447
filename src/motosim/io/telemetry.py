"""Telemetry out of a run: a ring buffer the loop writes, and the sinks that read it elsewhere.

The loop (a real-time loop, or :func:`motosim.sim.simulate` through ``on_block``) only copies
each row of signals into a preallocated :class:`TelemetryRing`; everything else (the browser
view, the MCAP file, the UDP streams) runs in another thread or process and reads the ring
with its own cursor, so the loop's timing does not depend on who watches. The sinks:

- :func:`write_mcap`: an MCAP file (https://mcap.dev) with JSON messages, one channel of
  every recorded signal and one ``foxglove.PoseInFrame`` channel, which Foxglove and
  Lichtblick open as they are (the ``mcap`` package, optional group ``view``).
- :class:`FoxgloveLive`: the same channels served live to Foxglove/Lichtblick by the
  ``foxglove-sdk`` WebSocket server (https://docs.foxglove.dev/docs/sdk).
- :class:`PlotJugglerUdp`: one JSON object per datagram, the input of PlotJuggler's
  "UDP server" streamer (JSON protocol, default port 9870).
- :class:`EsminiUdp`: the pose in the binary layout of esmini's ``ControllerUDPDriver``
  (https://github.com/esmini/esmini, ``ControllerUDPDriver.hpp``), see :func:`esmini_packet`.
- :class:`TelemetryPump`: a thread that moves new rows of a ring to such sinks.
"""

from __future__ import annotations

import json
import math
import socket
import struct
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any, Final, Protocol

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.io.files import write_whole
from motosim.timeseries import TimeSeries

__all__ = [
    "ESMINI_FORMAT",
    "ESMINI_PORT",
    "PLOTJUGGLER_PORT",
    "EsminiUdp",
    "FoxgloveLive",
    "PlotJugglerUdp",
    "Sink",
    "TelemetryPump",
    "TelemetryRing",
    "esmini_packet",
    "pose_of",
    "write_mcap",
]

Array = NDArray[np.float64]

PLOTJUGGLER_PORT: Final = 9870
"""PlotJuggler's default port for its UDP streamer."""

ESMINI_PORT: Final = 49950
"""esmini's ``DEFAULT_UDP_DRIVER_PORT``; the object ``id`` listens on ``ESMINI_PORT + id``."""

ESMINI_FORMAT: Final = "<4I8dB"
"""The :func:`esmini_packet` layout (``struct`` notation, little-endian, no padding, 81 bytes):
header ``uint32`` version (1), inputMode (2 = ``VEHICLE_STATE_XYZHPR``), objectId, frameNumber;
then ``double`` x, y, z [m], h, p, r [rad], speed [m/s], wheelAngle [rad]; ``uchar``
deadReckon."""

_ESMINI_VERSION: Final = 1
_ESMINI_XYZHPR: Final = 2

POSE_SIGNALS: Final = ("t", "x", "y", "psi", "phi", "delta", "v_x")
"""The signals a pose needs (:func:`pose_of`)."""


class TelemetryRing:
    """A preallocated ring of rows: one writer (the loop), any number of readers.

    The writer copies a row into the next slot and then advances a counter; nothing is
    allocated or locked on its side. A reader keeps its own cursor (the number of rows it has
    read) and gets the rows written since. The slot the writer fills next is never read, so
    a reader sees at most ``capacity - 1`` rows; one that fell further behind loses the
    oldest ones.

    Parameters
    ----------
    names : sequence of str
        Column names, ``"t"`` first (for example :data:`motosim.signals.RECORDED`).
    capacity : int
        Rows kept; at 1 kHz, 4096 rows are four seconds.

    Examples
    --------
    >>> ring = TelemetryRing(("t", "phi"), capacity=4)
    >>> for k in range(6):
    ...     ring.push(np.array([0.1 * k, -k]))
    >>> rows, cursor = ring.read_since(0)
    >>> rows[:, 1], cursor
    (array([-3., -4., -5.]), 6)
    """

    def __init__(self, names: Sequence[str], capacity: int = 4096) -> None:
        self.names: tuple[str, ...] = tuple(names)
        if self.names[:1] != ("t",) or len(set(self.names)) != len(self.names):
            raise MotosimError(
                f"TelemetryRing names {self.names[:3]}...; expected unique names, 't' first"
            )
        if capacity < 2:
            raise MotosimError(f"TelemetryRing capacity = {capacity}; expected >= 2 rows")
        self.capacity = int(capacity)
        self._rows: Array = np.full((self.capacity, len(self.names)), np.nan)
        self._count = 0

    @property
    def count(self) -> int:
        """Rows written since creation."""
        return self._count

    def push(self, row: Array) -> None:
        """Copy one row into the ring (the loop's side: no allocation, no lock).

        Parameters
        ----------
        row : ndarray, shape (k,)
            Values in the order of :attr:`names`.
        """
        self._rows[self._count % self.capacity] = row
        self._count += 1

    def push_block(self, block: Array) -> None:
        """Copy rows into the ring, oldest first (for example a block of ``on_block``).

        Parameters
        ----------
        block : ndarray, shape (m, k)
            Rows in the order of :attr:`names`.
        """
        skipped = max(0, block.shape[0] - self.capacity)
        block = block[skipped:]
        m = block.shape[0]
        start = (self._count + skipped) % self.capacity
        first = min(m, self.capacity - start)
        self._rows[start : start + first] = block[:first]
        self._rows[: m - first] = block[first:]
        self._count += skipped + m

    def read_since(self, cursor: int) -> tuple[Array, int]:
        """Rows written after ``cursor`` rows, and the new cursor.

        Parameters
        ----------
        cursor : int
            Rows already read (0 at first).

        Returns
        -------
        rows : ndarray, shape (m, k)
            A copy of the rows still in the ring, oldest first.
        cursor : int
            The cursor to pass next time (the number of rows written when read).
        """
        end = self._count
        start = max(cursor, end - self.capacity, 0)
        index = np.arange(start, end) % self.capacity
        rows = self._rows[index]
        # Rows the writer may have overwritten while they were copied are dropped.
        lapped = self._count - self.capacity + 1 - start
        if lapped > 0:
            rows = rows[lapped:]
        return rows, end

    def latest(self) -> Array | None:
        """A copy of the last row written, or None before the first."""
        if self._count == 0:
            return None
        row: Array = self._rows[(self._count - 1) % self.capacity].copy()
        return row


def pose_of(names: Sequence[str], row: Array) -> dict[str, float]:
    """The pose and speed of a row: t, x, y, psi, phi, delta, v_x (SI, rad).

    Parameters
    ----------
    names : sequence of str
        Column names of ``row``; each of :data:`POSE_SIGNALS` must be there.
    row : ndarray, shape (k,)
        One row of signals.

    Returns
    -------
    dict
        Signal name to value.

    Raises
    ------
    MotosimError
        If a pose signal is missing.
    """
    index = {name: j for j, name in enumerate(names)}
    missing = [name for name in POSE_SIGNALS if name not in index]
    if missing:
        raise MotosimError(f"signals without {', '.join(missing)}; a pose needs {POSE_SIGNALS}")
    return {name: float(row[index[name]]) for name in POSE_SIGNALS}


def esmini_packet(
    frame: int, pose: dict[str, float], *, object_id: int = 0, dead_reckon: bool = False
) -> bytes:
    """Pack a pose as esmini's ``ControllerUDPDriver`` XYZHPR message.

    The layout is :data:`ESMINI_FORMAT` (``DMHeader`` then ``DMMSGVehicleStateXYZHPR`` of
    esmini's ``ControllerUDPDriver.hpp``, without the C struct's trailing padding). esmini's
    frame is OpenDRIVE's (x forward, y left, z up, heading counter-clockwise) while motosim's
    ground frame has y to the right and z down (:mod:`motosim.signals`), so y, heading and
    wheel angle change sign; roll (right side down) keeps its sign; z and pitch are zero.

    Parameters
    ----------
    frame : int
        Frame number, counting up from 0.
    pose : dict
        From :func:`pose_of`.
    object_id : int
        esmini object id.
    dead_reckon : bool
        Let esmini extrapolate between packets.

    Returns
    -------
    bytes
        81 bytes.

    Examples
    --------
    >>> pose = dict(t=0.0, x=1.0, y=2.0, psi=0.1, phi=0.2, delta=0.05, v_x=20.0)
    >>> packet = esmini_packet(7, pose)
    >>> len(packet), struct.unpack(ESMINI_FORMAT, packet)[:6]
    (81, (1, 2, 0, 7, 1.0, -2.0))
    """
    header = (_ESMINI_VERSION, _ESMINI_XYZHPR, object_id, frame & 0xFFFFFFFF)
    # x, y, z, heading, pitch, roll, speed, wheel angle in esmini's frame
    state = (
        pose["x"],
        -pose["y"],
        0.0,
        -pose["psi"],
        0.0,
        pose["phi"],
        pose["v_x"],
        -pose["delta"],
    )
    return struct.pack(ESMINI_FORMAT, *header, *state, 1 if dead_reckon else 0)


class Sink(Protocol):
    """Something that takes rows of named signals (outside the loop)."""

    def send(self, names: tuple[str, ...], rows: Array) -> None:
        """Take new rows (oldest first) of the columns ``names``."""


def _udp(host: str, port: int, what: str) -> tuple[socket.socket, tuple[str, int]]:
    if not 0 < port < 65536:
        raise MotosimError(f"{what} port = {port}; expected 1..65535")
    try:
        address = socket.getaddrinfo(host, port, socket.AF_INET, socket.SOCK_DGRAM)[0][4]
    except OSError as err:
        raise MotosimError(f"{what} host {host!r}: {err}") from None
    return socket.socket(socket.AF_INET, socket.SOCK_DGRAM), (str(address[0]), int(address[1]))


class PlotJugglerUdp:
    """Send rows to PlotJuggler's UDP streamer as JSON: ``{"timestamp": t, name: value...}``.

    Parameters
    ----------
    host : str
        Where PlotJuggler runs.
    port : int
        Its UDP port (PlotJuggler's default :data:`PLOTJUGGLER_PORT`).
    every : int
        Send one row in ``every`` (PlotJuggler needs far less than 1 kHz).
    """

    def __init__(self, host: str = "127.0.0.1", port: int = PLOTJUGGLER_PORT, every: int = 10):
        if every < 1:
            raise MotosimError(f"PlotJugglerUdp every = {every}; expected >= 1")
        self._socket, self._address = _udp(host, port, "PlotJuggler")
        self._kept = _OneIn(every)

    def send(self, names: tuple[str, ...], rows: Array) -> None:
        """Send one datagram per kept row."""
        for row in self._kept.rows(rows):
            values = zip(names[1:], row[1:], strict=True)
            finite = {n: float(v) for n, v in values if math.isfinite(v)}
            message = {"timestamp": float(row[0]), **finite}
            self._socket.sendto(json.dumps(message).encode(), self._address)

    def close(self) -> None:
        """Close the socket."""
        self._socket.close()


class _OneIn:
    """Keeps one row in ``every`` of the rows a sink is sent, counted across its calls."""

    def __init__(self, every: int) -> None:
        self._every = every
        self._seen = 0

    def rows(self, rows: Array) -> Array:
        """The rows of ``rows`` kept."""
        first = -self._seen % self._every
        self._seen += len(rows)
        return rows[first :: self._every]


class EsminiUdp:
    """Send the latest pose of each batch as an esmini ``ControllerUDPDriver`` packet.

    Parameters
    ----------
    host : str
        Where esmini runs.
    object_id : int
        The esmini object; the packet goes to ``port + object_id`` like esmini's listener.
    port : int
        Base port (esmini's default :data:`ESMINI_PORT`).
    """

    def __init__(self, host: str = "127.0.0.1", object_id: int = 0, port: int = ESMINI_PORT):
        self._socket, self._address = _udp(host, port + object_id, "esmini")
        self._object_id = object_id
        self.frame = 0

    def send(self, names: tuple[str, ...], rows: Array) -> None:
        """Send the last row's pose (an image generator wants the newest, not every row)."""
        if rows.shape[0] == 0:
            return
        packet = esmini_packet(self.frame, pose_of(names, rows[-1]), object_id=self._object_id)
        self._socket.sendto(packet, self._address)
        self.frame += 1

    def close(self) -> None:
        """Close the socket."""
        self._socket.close()


def _object(properties: dict[str, Any], title: str | None = None) -> dict[str, Any]:
    """A JSON schema of an object with ``properties`` (titled when ``title`` is given)."""
    titled = {} if title is None else {"title": title}
    return {**titled, "type": "object", "properties": properties}


_NUMBER: Final = {"type": "number"}
_SIGNALS_TOPIC: Final = "/motosim/signals"
_POSE_TOPIC: Final = "/motosim/pose"
_POSE_SCHEMA: Final = _object(
    {
        "timestamp": _object({"sec": {"type": "integer"}, "nsec": {"type": "integer"}}),
        "frame_id": {"type": "string"},
        "pose": _object(
            {
                "position": _object(dict.fromkeys("xyz", _NUMBER)),
                "orientation": _object(dict.fromkeys("xyzw", _NUMBER)),
            }
        ),
    },
    title="foxglove.PoseInFrame",
)


def _signals_schema(names: Iterable[str]) -> dict[str, Any]:
    return _object(dict.fromkeys(names, _NUMBER), title="motosim.Signals")


def _stamp(t: float) -> dict[str, int]:
    sec = math.floor(t)
    return {"sec": sec, "nsec": min(999_999_999, round((t - sec) * 1e9))}


def _pose_message(pose: dict[str, float]) -> dict[str, Any]:
    # motosim's ground frame (x forward, y right, z down) as Foxglove's z-up frame: y and the
    # heading change sign; the orientation is yaw then roll (pitch is not modelled).
    h, r = -pose["psi"], pose["phi"]
    cy, sy, cr, sr = math.cos(h / 2), math.sin(h / 2), math.cos(r / 2), math.sin(r / 2)
    return {
        "timestamp": _stamp(pose["t"]),
        "frame_id": "world",
        "pose": {
            "position": {"x": pose["x"], "y": -pose["y"], "z": 0.0},
            "orientation": {"x": cy * sr, "y": sy * sr, "z": sy * cr, "w": cy * cr},
        },
    }


def _row_messages(names: tuple[str, ...], row: Array) -> Iterator[tuple[str, dict[str, Any]]]:
    """A row's messages by topic: its signals and, when it has them, its pose."""
    values = zip(names, row, strict=True)
    yield _SIGNALS_TOPIC, {n: (float(v) if math.isfinite(v) else None) for n, v in values}
    if all(n in names for n in POSE_SIGNALS):
        yield _POSE_TOPIC, _pose_message(pose_of(names, row))


def _nanoseconds(t: float) -> int:
    """A log time [ns] from a time [s] (0 before 0)."""
    return max(0, round(float(t) * 1e9))


def write_mcap(result: TimeSeries, path: str | Path, *, every: int = 1) -> int:
    """Write a result as an MCAP file that Foxglove, Lichtblick and ``mcap`` readers open.

    Two JSON channels: ``/motosim/signals`` (every signal of a row, ``t`` included, SI
    units) and ``/motosim/pose`` (``foxglove.PoseInFrame`` in a z-up ``world`` frame). Log
    time is the simulated time.

    Parameters
    ----------
    result : TimeSeries
        A result (for example :func:`motosim.io.results.load_result`).
    path : str or Path
        The ``.mcap`` file to write (replaced if there).
    every : int
        Keep one row in ``every``.

    Returns
    -------
    int
        Messages written.

    Raises
    ------
    MotosimError
        If ``mcap`` is not installed (``pip install 'motosim[view]'``), ``every`` < 1 or the
        file cannot be written.
    """
    if every < 1:
        raise MotosimError(f"write_mcap every = {every}; expected >= 1")
    try:
        from mcap.writer import Writer
    except ImportError:
        raise MotosimError("MCAP needs the mcap package: pip install 'motosim[view]'") from None
    names = ("t", *result.names)
    table = np.column_stack([result.t, result.data])[::every]
    counted: list[int] = []

    def write(temporary: Path) -> None:
        with temporary.open("wb") as stream:
            writer = Writer(stream)
            writer.start(profile="", library="motosim")
            counted.append(_write_messages(writer, names, table))
            writer.finish()  # type: ignore[no-untyped-call]

    write_whole(path, write)
    return counted[0]


def _write_messages(writer: Any, names: tuple[str, ...], table: Array) -> int:
    """Write each row of ``table`` to the signals channel and, if it has a pose, to the pose
    channel; the messages written."""
    schemas = {_SIGNALS_TOPIC: _signals_schema(names), _POSE_TOPIC: _POSE_SCHEMA}
    channels = {topic: _json_channel(writer, topic, schema) for topic, schema in schemas.items()}
    count = 0
    for sequence, row in enumerate(table):
        stamp = _nanoseconds(row[0])
        for topic, message in _row_messages(names, row):
            writer.add_message(
                channel_id=channels[topic],
                log_time=stamp,
                publish_time=stamp,
                sequence=sequence,
                data=json.dumps(message).encode(),
            )
            count += 1
    return count


def _json_channel(writer: Any, topic: str, schema: dict[str, Any]) -> int:
    """Register a JSON channel and its JSON schema (named by its title) with an MCAP writer;
    the channel's id."""
    data = json.dumps(schema).encode()
    schema_id = writer.register_schema(name=schema["title"], encoding="jsonschema", data=data)
    channel: int = writer.register_channel(
        topic=topic, message_encoding="json", schema_id=schema_id
    )
    return channel


class FoxgloveLive:
    """Serve rows live to Foxglove or Lichtblick through the ``foxglove-sdk`` WebSocket server.

    Open ``ws://HOST:PORT`` in the app's "Foxglove WebSocket" connection; the channels are
    those of :func:`write_mcap`.

    Parameters
    ----------
    host : str
        Address to bind; localhost unless the user asks otherwise.
    port : int
        TCP port (Foxglove's default 8765; 0 picks a free one).
    every : int
        Log one row in ``every``.

    Raises
    ------
    MotosimError
        If ``foxglove-sdk`` is not installed or the server cannot start.
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 8765, every: int = 10) -> None:
        try:
            import foxglove
        except ImportError:
            raise MotosimError(
                "the live Foxglove server needs foxglove-sdk: pip install 'motosim[view]'"
            ) from None
        if every < 1:
            raise MotosimError(f"FoxgloveLive every = {every}; expected >= 1")
        try:
            self._server = foxglove.start_server(name="motosim", host=host, port=port)
        except Exception as err:  # the SDK raises its own error types
            raise MotosimError(f"Foxglove server on {host}:{port}: {err}") from None
        self._kept = _OneIn(every)
        self._channels: dict[str, Any] = {}
        self._foxglove = foxglove

    @property
    def port(self) -> int:
        """The TCP port the server listens on."""
        return int(self._server.port)

    def _channel(self, topic: str, names: tuple[str, ...]) -> Any:
        if topic not in self._channels:
            schema = _signals_schema(names) if topic == _SIGNALS_TOPIC else _POSE_SCHEMA
            self._channels[topic] = self._foxglove.Channel(topic, schema=schema)
        return self._channels[topic]

    def send(self, names: tuple[str, ...], rows: Array) -> None:
        """Log one row in ``every`` on the signal and pose channels."""
        self._channel(_SIGNALS_TOPIC, names)  # advertised from the first call
        for row in self._kept.rows(rows):
            stamp = _nanoseconds(row[0])
            for topic, message in _row_messages(names, row):
                self._channel(topic, names).log(message, log_time=stamp)

    def close(self) -> None:
        """Stop the server."""
        self._server.stop()


class TelemetryPump:
    """A thread that reads new rows of a ring at a fixed rate and hands them to sinks.

    Parameters
    ----------
    ring : TelemetryRing
        Written by the loop.
    sinks : sequence of Sink
        Each gets every new batch of rows.
    rate : float
        Reads per second [Hz].
    on_error : callable, optional
        Called with a sink's exception (the pump drops that sink and goes on); by default
        the exception is kept in :attr:`errors`.
    """

    def __init__(
        self,
        ring: TelemetryRing,
        sinks: Sequence[Sink],
        *,
        rate: float = 60.0,
        on_error: Callable[[BaseException], None] | None = None,
    ) -> None:
        if not rate > 0.0:
            raise MotosimError(f"TelemetryPump rate = {rate} Hz; expected > 0")
        self._ring = ring
        self._sinks = list(sinks)
        self._period = 1.0 / rate
        self._on_error = on_error
        self.errors: list[BaseException] = []
        self._cursor = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="motosim-telemetry", daemon=True)

    def start(self) -> TelemetryPump:
        """Start the thread; returns self."""
        self._thread.start()
        return self

    def pump(self) -> int:
        """Move the rows written since the last call to every sink; returns their number."""
        rows, self._cursor = self._ring.read_since(self._cursor)
        if rows.shape[0]:
            for sink in list(self._sinks):
                try:
                    sink.send(self._ring.names, rows)
                except Exception as err:  # a broken sink must not stop the others
                    self._sinks.remove(sink)
                    if self._on_error is not None:
                        self._on_error(err)
                    else:
                        self.errors.append(err)
        return int(rows.shape[0])

    def _run(self) -> None:
        next_time = time.monotonic()
        while not self._stop.is_set():
            self.pump()
            next_time += self._period
            self._stop.wait(max(0.0, next_time - time.monotonic()))

    def stop(self) -> None:
        """Stop the thread after a last pump."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()
        self.pump()
