"""A preallocated ring of samples: the loop writes rows, a reader outside the loop drains them.

The real-time loop must neither allocate nor write files; it copies each period's row of
signals into a ring preallocated before the first deadline, and a writer thread (or the main
thread after the loop) drains the rows into the result files. One producer and one consumer:
the producer only advances ``head``, the consumer only ``tail`` (under the GIL each update is
atomic). A consumer that falls more than ``capacity`` rows behind loses the oldest rows; they
are counted in :attr:`SampleRing.dropped`, never silently.
"""

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError

__all__ = ["SampleRing"]


class SampleRing:
    """A fixed ring of ``capacity`` rows of ``width`` float64 signals.

    Examples
    --------
    >>> ring = SampleRing(4, 2)
    >>> for k in range(6):
    ...     ring.push(np.array([k, 10.0 * k]))
    >>> ring.drain()[:, 0].tolist(), ring.dropped
    ([2.0, 3.0, 4.0, 5.0], 2)
    """

    __slots__ = ("_buf", "_dropped", "_head", "_tail")

    def __init__(self, capacity: int, width: int) -> None:
        if capacity < 1 or width < 1:
            raise MotosimError(
                f"ring of {capacity!r} rows x {width!r} signals: expected at least 1 x 1"
            )
        self._buf = np.zeros((capacity, width))
        self._head = 0  # rows written so far (producer)
        self._tail = 0  # rows read so far (consumer)
        self._dropped = 0

    @property
    def dropped(self) -> int:
        """Rows overwritten before the consumer read them."""
        return self._dropped

    def push(self, row: NDArray[np.float64]) -> None:
        """Copy ``row`` (``width`` values) into the next slot (the loop's side)."""
        buf = self._buf
        buf[self._head % buf.shape[0]] = row
        self._head += 1

    def drain(self) -> NDArray[np.float64]:
        """The rows written since the last drain, oldest first, as a new array (reader's side)."""
        head = self._head
        cap = self._buf.shape[0]
        tail = self._tail
        if head - tail > cap:
            self._dropped += head - tail - cap
            tail = head - cap
        idx = np.arange(tail, head) % cap
        self._tail = head
        return self._buf[idx].copy()
