"""The run's state stream: the stack's row each period, as UDP datagrams.

``motosim run`` publishes, every control period, the period's index, its time [s] and the
stack's row (:data:`motosim.rt.stack.STACK_SIGNALS`: the torque estimate, the measurement,
the command and the virtual motorcycle's states, SI units) as one little-endian datagram
``<Q d 16d`` to a UDP address (localhost by default). It is what a visual or a telemetry
display reads, and what the virtual rig's virtual rider steers by, as a person steers by the
visual. Sending is one non-blocking ``sendto``; a datagram that cannot be sent is dropped
and counted, never waited for.

``motosim run`` sends it from outside the loop: a :class:`StateRelay` in the result writer's
process reads the newest row of the loop's shared ring every millisecond and publishes its
stack columns, so the loop's period has no ``sendto`` of its own. The state then reaches a
reader about a millisecond later (the relay's :meth:`StateRelay.lag_stats` measure it), as a
person sees the visual some tens of milliseconds after the event anyway. A
:class:`StateSender` can still be the runner's ``telemetry`` (called in the period: the
lock-step tests, where the rider must see the period's state at once).
"""

import ipaddress
import math
import re
import socket
import struct
import threading
import time
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.rt.ring import RingCounter

__all__ = ["StateReceiver", "StateRelay", "StateSender", "is_host", "parse_address"]

_WIDTH = 16


_DIGITS = re.compile(r"[0-9.]+")
_HOSTNAME = re.compile(
    r"(?=.{1,253}$)[A-Za-z0-9_]([A-Za-z0-9_-]{0,61}[A-Za-z0-9_])?"
    r"(\.[A-Za-z0-9_]([A-Za-z0-9_-]{0,61}[A-Za-z0-9_])?)*\.?"
)


def is_host(text: str) -> bool:
    """Whether ``text`` is an IP address or a syntactically valid host name (no lookup).

    Examples
    --------
    >>> is_host("127.0.0.1"), is_host("lab-pc.local"), is_host("a b"), is_host("256.1.1.1")
    (True, True, False, False)
    """
    try:
        ipaddress.ip_address(text.strip("[]"))
    except ValueError:  # digits and dots only: an IPv4 address out of range, not a name
        return _HOSTNAME.fullmatch(text) is not None and not _DIGITS.fullmatch(text)
    return True


def _socket(address: tuple[str, int], *, bind: bool) -> socket.socket:
    """A non-blocking UDP socket bound to ``address`` (else connected to it), or a one-line
    error saying why it cannot listen (send) there."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        (sock.bind if bind else sock.connect)(address)
    except OSError as err:
        sock.close()
        why = f"cannot listen there: {err.strerror}" if bind else f"cannot send there: {err}"
        raise MotosimError(f"--telemetry {address[0]}:{address[1]}: {why}") from None
    sock.setblocking(False)
    return sock


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
        self._socket = _socket(address, bind=False)
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
        self._format = struct.Struct(f"<Qd{width}d")
        self._socket = _socket(address, bind=True)
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


class StateRelay:
    """Publish, from outside the loop, the newest row of the loop's ring as the state stream.

    Each :meth:`poll` reads how many rows the loop has written; if a new one came, the
    newest (the row before the ring's head, complete: the loop advances the head after
    writing it) is sent with ``sender`` as ``(index, t, stack columns)``, ``index`` being
    the period's index ``round(t * rate)``. Rows before the stack started (no valid angle
    yet: ``theta_h_meas`` NaN) are not sent, as the loop did not send them. Older rows that
    came between two polls are skipped: a reader keeps only the newest anyway.

    Parameters
    ----------
    buffer : ndarray, shape (capacity, width)
        The ring's rows (:attr:`motosim.rt.ring.SampleRing.arrays`).
    counters : ndarray of int64
        The ring's counters (rows written first).
    names : tuple of str
        The ring's columns (:attr:`motosim.rt.run.RealtimeRunner.names`): the loop's own
        (``t``, ``theta_h_meas``, ``t_clock``, ``wake``, ``compute``) then the stack's.
    first : int
        The first of the stack's columns.
    send : callable
        ``send(index, t, row)`` (:meth:`StateSender.send`).
    rate : float
        The loop's rate [Hz].
    now : callable
        The loop's clock [s] (``time.monotonic``, the clock of ``motosim run``: one clock for
        every process of the machine), for the lag.
    """

    def __init__(
        self,
        buffer: NDArray[np.float64],
        counters: NDArray[np.int64],
        names: tuple[str, ...],
        first: int,
        send: Callable[[int, float, NDArray[np.float64]], None],
        *,
        rate: float,
        now: Callable[[], float] = time.monotonic,
    ) -> None:
        self._buffer = buffer
        self._counters = counters
        self._send = send
        self._rate = float(rate)
        self._now = now
        self._first = first
        self._cols = [names.index(n) for n in ("t", "theta_h_meas", "t_clock", "wake", "compute")]
        self._seen = 0
        self._lags = np.zeros(1 << 16)
        self.sent = 0
        """Datagrams sent."""

    def poll(self) -> bool:
        """Send the newest row if one came since the last poll; True if one was sent."""
        head = int(self._counters[RingCounter.written])
        if head <= self._seen:
            return False
        self._seen = head
        row = self._buffer[(head - 1) % self._buffer.shape[0]].copy()
        t, theta, t_clock, wake, compute = row[self._cols]
        if not math.isfinite(theta):
            return False
        self._send(round(t * self._rate), float(t), row[self._first :])
        lag = self._now() - (t_clock + wake + compute)  # since the loop finished the row
        if math.isfinite(lag):
            self._lags[self.sent % self._lags.size] = lag
        self.sent += 1
        return True

    def run(self, stop: threading.Event, interval: float = 1e-3) -> None:
        """:meth:`poll` every ``interval`` [s] until ``stop`` is set (a thread's target)."""
        while not stop.wait(interval):
            self.poll()
        self.poll()

    def lag_stats(self) -> dict[str, float]:
        """How long after the loop wrote a row it was sent: p50, p99 and max [s] (empty if
        nothing was sent)."""
        n = min(self.sent, self._lags.size)
        if n == 0:
            return {}
        lags = self._lags[:n]
        p50, p99 = np.percentile(lags, (50.0, 99.0))
        return {"p50": float(p50), "p99": float(p99), "max": float(lags.max())}
