"""A live feed without hardware: a simulated run paced to the wall clock, written to a ring.

:class:`SimulatedRig` stands in for the real-time loop: it runs
:func:`motosim.sim.simulate` in a thread, sleeps after each block until the wall clock has
caught up with the simulated time, and pushes every row into a
:class:`~motosim.io.telemetry.TelemetryRing`; it implements
:class:`~motosim.view.feeds.RunControl` (arm starts the run, stop ends it). The real-time
loop does the same three things from its own thread: push each period's row into the ring,
and answer ``arm``/``stop``/``state``.
"""

from __future__ import annotations

import math
import threading
import time

import numpy as np

from motosim.errors import MotosimError
from motosim.io.telemetry import TelemetryRing
from motosim.sim import SIGNALS, RunInputs, simulate
from motosim.view.feeds import LiveFeed, Road, road_from_xy

__all__ = ["LOOP_VIEW_SIGNALS", "LoopRows", "SimulatedRig"]

LOOP_VIEW_SIGNALS = ("state", "fault", "t_clock", "wake", "compute", "period", "missed")
"""The real-time loop's columns the view adds to a run's: safety state and fault codes, the
period's deadline on the loop's clock [s], its wake-up latency, compute time and the time
since the previous wake-up [s], and the deadlines missed so far."""


class LoopRows:
    """The real-time loop's rows as the view's: the result's columns plus the loop's own.

    Parameters
    ----------
    loop_names : tuple of str
        Columns of the loop's rows (:attr:`motosim.rt.run.RealtimeRunner.names`).
    result_names : tuple of str
        Columns of the result block made from the same rows (``"t"`` first).

    Attributes
    ----------
    names : tuple of str
        ``result_names`` then :data:`LOOP_VIEW_SIGNALS`: the columns of :meth:`rows`.

    Examples
    --------
    >>> rows = LoopRows(("t", "state", "fault", "t_clock", "wake", "compute", "missed"), ("t",))
    >>> loop = np.array([[0.001, 2, 0, 10.001, 1e-5, 2e-5, 0],
    ...                  [0.002, 2, 0, 10.002, 3e-5, 2e-5, 0]])
    >>> rows.rows(loop, loop[:, :1])[:, -2].round(6).tolist()
    [nan, 0.00102]
    """

    def __init__(self, loop_names: tuple[str, ...], result_names: tuple[str, ...]) -> None:
        missing = [n for n in LOOP_VIEW_SIGNALS if n != "period" and n not in loop_names]
        if missing:
            raise MotosimError(f"loop rows without {', '.join(missing)}; expected the loop's")
        self.names = (*result_names, *LOOP_VIEW_SIGNALS)
        self._cols = [loop_names.index(n) for n in LOOP_VIEW_SIGNALS if n != "period"]
        self._clock = loop_names.index("t_clock")
        self._wake = loop_names.index("wake")
        self._last = math.nan  # the previous row's wake-up time on the loop's clock [s]

    def rows(self, loop: np.ndarray, block: np.ndarray) -> np.ndarray:
        """``block`` (rows of ``result_names``) with the loop's columns of ``loop`` appended."""
        woke = loop[:, self._clock] + loop[:, self._wake]
        period = np.diff(woke, prepend=self._last)
        if woke.size:
            self._last = float(woke[-1])
        extra = loop[:, self._cols]
        return np.column_stack([block, extra[:, :5], period, extra[:, 5:]])


class _StoppedError(Exception):
    """Raised from ``on_block`` to end a run that was stopped."""


class SimulatedRig:
    """A scenario simulated in real time into a ring buffer, armed and stopped from outside.

    Parameters
    ----------
    inputs : RunInputs
        The resolved run (:func:`motosim.io.runs.load_run`).
    rate : float
        Simulated seconds per wall-clock second (1 is real time).
    chunk : float
        Simulated time per block [s]; the feed advances in these steps.
    capacity : int
        Rows the ring keeps.

    Attributes
    ----------
    ring : TelemetryRing
        Every row of :data:`motosim.sim.SIGNALS`, as the run goes, and ``t_clock``: the
        monotonic clock time [s] at which the row is due (``time.monotonic``, the clock of
        the real-time loop).
    error : BaseException or None
        Why the run failed, if it did.
    """

    def __init__(
        self, inputs: RunInputs, *, rate: float = 1.0, chunk: float = 0.02, capacity: int = 1 << 15
    ) -> None:
        if not (math.isfinite(rate) and rate > 0.0):
            raise MotosimError(f"SimulatedRig rate = {rate!r}; expected a finite number > 0")
        if not (math.isfinite(chunk) and chunk > 0.0):
            raise MotosimError(f"SimulatedRig chunk = {chunk!r} s; expected a finite number > 0")
        self.inputs = inputs
        self.ring = TelemetryRing((*SIGNALS, "t_clock"), capacity)
        self.error: BaseException | None = None
        self._rate = rate
        self._chunk = chunk
        self._state = "idle"
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()

    def feed(self) -> LiveFeed:
        """The ring as a feed for the view, with this rig as its control."""
        return LiveFeed(self.ring, self, self.inputs.scenario.duration)

    def road(self) -> Road:
        """The road along the scenario's path (straight ahead when the rider has none)."""
        sc = self.inputs.scenario
        length = sc.duration * sc.motorcycle.speed
        if sc.rider.path is not None:
            built = sc.rider.path.build(length)
            return road_from_xy(built.x, built.y)
        return road_from_xy(np.array([0.0, length]), np.zeros(2))

    # RunControl -------------------------------------------------------------------------
    def arm(self) -> None:
        """Start the run (once; a finished or stopped rig stays so)."""
        with self._lock:
            if self._state != "idle":
                return
            self._state = "running"
            self._thread = threading.Thread(target=self._run, name="motosim-rig", daemon=True)
            self._thread.start()

    def stop(self) -> None:
        """End the run after the current block."""
        with self._lock:
            if self._state == "idle":
                self._state = "stopped"
        self._stop.set()

    def state(self) -> str:
        """``idle``, ``running``, ``stopped``, ``done`` or ``failed``."""
        return self._state

    def join(self, timeout: float | None = None) -> None:
        """Wait for the run's thread to end."""
        if self._thread is not None:
            self._thread.join(timeout)

    def _run(self) -> None:
        start = time.monotonic()

        def on_block(block: np.ndarray) -> None:
            self.ring.push_block(np.column_stack([block, start + block[:, 0] / self._rate]))
            if self._stop.is_set():
                raise _StoppedError
            ahead = start + float(block[-1, 0]) / self._rate - time.monotonic()
            if ahead > 0.0 and self._stop.wait(ahead):
                raise _StoppedError

        try:
            simulate(
                self.inputs,
                rng=np.random.default_rng(self.inputs.scenario.seed),
                on_block=on_block,
                chunk=self._chunk,
                keep=False,
            )
            self._state = "done"
        except _StoppedError:
            self._state = "stopped"
        except Exception as err:  # reported through state() and .error
            self.error = err
            self._state = "failed"
