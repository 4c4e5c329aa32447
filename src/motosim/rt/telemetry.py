"""The run's state stream: the stack's row each period, as UDP datagrams.

``motosim run`` publishes, every control period, the period's index, its time [s] and the
stack's row (:data:`motosim.rt.stack.STACK_SIGNALS`: the torque estimate, the measurement,
the command and the virtual motorcycle's states, SI units) as one little-endian datagram
``<Q d 16d`` to a UDP address (localhost by default). It is what a visual or a telemetry
display reads, and what the virtual rig's virtual rider steers by, as a person steers by the
visual. Sending is one non-blocking ``sendto`` (a few microseconds); a datagram that cannot
be sent is dropped and counted, never waited for.
"""

import ipaddress
import re
import socket
import struct

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError

__all__ = ["DEFAULT_ADDRESS", "StateReceiver", "StateSender", "is_host", "parse_address"]

DEFAULT_ADDRESS = ("127.0.0.1", 47474)
"""Where the state stream goes when nothing else is asked."""

_WIDTH = 16


def _format(width: int) -> struct.Struct:
    return struct.Struct(f"<Qd{width}d")


_HOSTNAME = re.compile(
    r"(?=.{1,253}$)[A-Za-z0-9_]([A-Za-z0-9_-]{0,61}[A-Za-z0-9_])?"
    r"(\.[A-Za-z0-9_]([A-Za-z0-9_-]{0,61}[A-Za-z0-9_])?)*\.?"
)


def is_host(text: str) -> bool:
    """Whether ``text`` is an IP address or a syntactically valid host name (no lookup).

    Examples
    --------
    >>> is_host("127.0.0.1"), is_host("lab-pc.local"), is_host("a b"), is_host("")
    (True, True, False, False)
    """
    try:
        ipaddress.ip_address(text.strip("[]"))
    except ValueError:
        return _HOSTNAME.fullmatch(text) is not None
    return True


def parse_address(text: str) -> tuple[str, int]:
    """``HOST:PORT`` as a (host, port) pair.

    Examples
    --------
    >>> parse_address("127.0.0.1:47474")
    ('127.0.0.1', 47474)
    """
    host, _, port = text.rpartition(":")
    if not is_host(host) or not port.isdigit() or len(port) > 5 or not 0 < int(port) < 65536:
        raise MotosimError(f"--telemetry {text!r}; expected HOST:PORT such as 127.0.0.1:47474")
    return host, int(port)


class StateSender:
    """Send ``(index, t, row)`` datagrams to ``address``; never blocks.

    The socket is connected to ``address`` once (a host name is looked up there, not on
    every datagram) and each datagram is written into one preallocated little-endian buffer
    (the layout of ``struct`` format ``<Qd`` and ``width`` doubles) and sent as it is.
    """

    def __init__(self, address: tuple[str, int], *, width: int = _WIDTH) -> None:
        self._format = _format(width)
        self._address = address
        self._socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._socket.setblocking(False)
        try:
            self._socket.connect(address)
        except OSError as err:
            self._socket.close()
            raise MotosimError(
                f"--telemetry {address[0]}:{address[1]}: cannot send there: {err}"
            ) from None
        self._buffer = np.zeros(2 + width, dtype="<f8")
        self._index = self._buffer[:1].view("<u8")
        self._bytes = self._buffer.data.cast("B")
        self._send = self._socket.send
        self.dropped = 0

    def send(self, index: int, t: float, row: NDArray[np.float64]) -> None:
        """Publish one period's row (``width`` values)."""
        buffer = self._buffer
        self._index[0] = index
        buffer[1] = t
        buffer[2:] = row
        try:
            self._send(self._bytes)
        except OSError:  # nobody listening (ICMP refused), buffer full: drop, count
            self.dropped += 1

    def close(self) -> None:
        """Close the socket."""
        self._socket.close()


class StateReceiver:
    """Receive the latest ``(index, t, row)`` published to ``address`` (bound here; port 0
    picks a free port, see :attr:`address`)."""

    def __init__(self, address: tuple[str, int], *, width: int = _WIDTH) -> None:
        self._format = _format(width)
        self._socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self._socket.bind(address)
        except OSError as err:
            self._socket.close()
            raise MotosimError(
                f"--telemetry {address[0]}:{address[1]}: cannot listen there: {err.strerror}"
            ) from None
        self._socket.setblocking(False)
        self.address: tuple[str, int] = self._socket.getsockname()
        self.row = np.zeros(width)
        self.index = -1
        self.t = float("nan")

    def poll(self) -> bool:
        """Read every datagram waiting; keep the newest. True if a new one came."""
        got = False
        for _ in range(10_000):
            try:
                data = self._socket.recv(65536)
            except (BlockingIOError, InterruptedError):
                break
            if len(data) != self._format.size:
                continue
            index, t, *row = self._format.unpack(data)
            if index > self.index or index == 0:  # newest; a restarted run begins at 0
                self.index, self.t = index, t
                self.row[:] = row
                got = True
        return got

    def close(self) -> None:
        """Close the socket."""
        self._socket.close()
