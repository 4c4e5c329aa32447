"""A preallocated ring of samples: the loop writes rows, a reader outside the loop drains them.

The real-time loop must neither allocate nor write files; it copies each period's row of
signals into a ring preallocated before the first deadline, and a reader drains the rows into
the result files. The reader should be another *process* (``shared=True`` puts the ring in
shared memory, :meth:`SampleRing.attach` opens it there): a thread of the loop's process
would take the interpreter lock for as long as a file write lasts, milliseconds, and the loop
would wait for it.

One producer and one consumer: the producer only advances ``head``, the consumer only
``tail``, each an aligned 64-bit word written after the rows it covers. A consumer that falls
more than ``capacity`` rows behind loses the oldest rows; they are counted in
:attr:`SampleRing.dropped`, never silently.
"""

from enum import IntEnum
from multiprocessing import shared_memory
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError

__all__ = ["RingCounter", "RingHandle", "SampleRing"]


class RingCounter(IntEnum):
    """The ring's two counters (:attr:`SampleRing.arrays`): rows written (the producer's
    head) and rows read (the consumer's tail)."""

    written = 0
    read = 1


class RingHandle(NamedTuple):
    """What another process needs to attach to a shared ring."""

    name: str
    capacity: int
    width: int


class SampleRing:
    """A fixed ring of ``capacity`` rows of ``width`` float64 signals.

    Parameters
    ----------
    capacity, width : int
        Rows and signals, each >= 1.
    shared : bool
        Put the ring in shared memory (see :attr:`handle` and :meth:`attach`); call
        :meth:`close` when done.

    Examples
    --------
    >>> ring = SampleRing(4, 2)
    >>> for k in range(6):
    ...     ring.push(np.array([k, 10.0 * k]))
    >>> ring.drain()[:, 0].tolist(), ring.dropped
    ([2.0, 3.0, 4.0, 5.0], 2)
    """

    __slots__ = ("_buf", "_counters", "_dropped", "_owner", "_shm")

    def __init__(self, capacity: int, width: int, *, shared: bool = False) -> None:
        if capacity < 1 or width < 1:
            raise MotosimError(
                f"ring of {capacity!r} rows x {width!r} signals: expected at least 1 x 1"
            )
        self._shm: shared_memory.SharedMemory | None = None
        self._owner = shared
        if shared:
            self._shm = shared_memory.SharedMemory(create=True, size=8 * (2 + capacity * width))
            self._setup(self._shm.buf, capacity, width)
            self._counters[:] = 0
            self._buf[:] = 0.0
        else:
            self._setup(bytearray(8 * (2 + capacity * width)), capacity, width)
        self._dropped = 0

    def _setup(self, memory: Any, capacity: int, width: int) -> None:
        self._counters = np.ndarray((2,), dtype=np.int64, buffer=memory)
        self._buf = np.ndarray((capacity, width), dtype=np.float64, buffer=memory, offset=16)

    @classmethod
    def attach(cls, handle: RingHandle) -> "SampleRing":
        """Open, in another process, the shared ring described by ``handle``."""
        ring = cls.__new__(cls)
        ring._shm = shared_memory.SharedMemory(name=handle.name)
        ring._owner = False
        ring._setup(ring._shm.buf, handle.capacity, handle.width)
        ring._dropped = 0
        return ring

    @property
    def handle(self) -> RingHandle:
        """The shared ring's name and shape (for :meth:`attach`)."""
        if self._shm is None:
            raise MotosimError("this ring is not in shared memory; create it with shared=True")
        return RingHandle(self._shm.name, self._buf.shape[0], self._buf.shape[1])

    @property
    def dropped(self) -> int:
        """Rows overwritten before this reader read them."""
        return self._dropped

    @property
    def arrays(self) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """The rows and the counters (rows written, rows read), for a producer that writes a
        row in place (the fused period of :mod:`motosim.rt.fused`): it writes the slot
        ``written % capacity``, then adds 1 to ``counters[RingCounter.written]``."""
        return self._buf, self._counters

    def push(self, row: NDArray[np.float64]) -> None:
        """Copy ``row`` (``width`` values) into the next slot (the loop's side)."""
        counters = self._counters
        head = counters[RingCounter.written]
        buf = self._buf
        buf[head % buf.shape[0]] = row
        counters[RingCounter.written] = head + 1

    def drain(self) -> NDArray[np.float64]:
        """The rows written since the last drain, oldest first, as a new array (reader's side)."""
        counters = self._counters
        head = int(counters[RingCounter.written])
        tail = int(counters[RingCounter.read])
        cap = self._buf.shape[0]
        if head - tail > cap:
            self._dropped += head - tail - cap
            tail = head - cap
        idx = np.arange(tail, head) % cap
        out: NDArray[np.float64] = self._buf[idx]  # a copy (fancy indexing)
        counters[RingCounter.read] = head
        return out

    def close(self) -> None:
        """Release the shared memory (and remove it, on the side that created it)."""
        if self._shm is None:
            return
        shm, self._shm = self._shm, None
        del self._counters, self._buf
        shm.close()
        if self._owner:
            shm.unlink()
