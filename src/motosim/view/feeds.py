"""What the view shows: a feed of rows of named signals, a run control, and the road.

The browser side never touches a run directly. It reads a :class:`Feed` (the rows written
since a cursor, the latest row, a status) and sends commands to a :class:`RunControl`
(arm, stop). Two feeds exist: :class:`ReplayFeed` plays a saved result against the wall
clock (arm/stop resume/pause it, and it seeks), and :class:`LiveFeed` reads the
:class:`~motosim.io.telemetry.TelemetryRing` a loop writes, with the loop's own control.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.io.telemetry import POSE_SIGNALS, TelemetryRing
from motosim.rt.safety import Fault, State, fault_reason
from motosim.timeseries import TimeSeries

__all__ = [
    "Feed",
    "LiveFeed",
    "ReplayFeed",
    "Road",
    "RunControl",
    "merge_signals",
    "road_from_xy",
]

Array = NDArray[np.float64]


class RunControl(Protocol):
    """Commands that change a run; the real-time loop implements them through its safety stage."""

    def arm(self) -> None:
        """Arm (start or resume) the run."""

    def stop(self) -> None:
        """Stop (or pause) the run."""

    def state(self) -> str:
        """The run's state, one word (for example ``"idle"``, ``"running"``, ``"stopped"``)."""


class Feed(Protocol):
    """Rows of named signals, ``"t"`` first, as a run produces or replays them."""

    names: tuple[str, ...]
    control: RunControl

    def read_since(self, cursor: int) -> tuple[Array, int]:
        """Rows after ``cursor`` rows, and the next cursor (a cursor ahead means start over)."""

    def latest(self) -> Array | None:
        """The newest row, or None before the first."""

    def status(self) -> dict[str, Any]:
        """JSON-able status: at least ``state``, ``t`` [s], ``duration`` [s] (None if unknown)."""


@dataclass(frozen=True, slots=True)
class Road:
    """The road's centre line in motosim's ground frame, and its width.

    Attributes
    ----------
    x, y : ndarray, shape (n,)
        Centre-line points [m], in driving order, a few metres apart.
    width : float
        Paved width [m].
    """

    x: Array
    y: Array
    width: float = 7.0

    def __post_init__(self) -> None:
        if self.x.ndim != 1 or self.x.shape != self.y.shape or self.x.size < 2:
            raise MotosimError(
                f"Road x {self.x.shape}, y {self.y.shape}; expected two equal 1-D arrays of >= 2"
            )
        if not (np.all(np.isfinite(self.x)) and np.all(np.isfinite(self.y))):
            raise MotosimError("Road: a non-finite centre-line point; expected finite x, y [m]")
        if not (math.isfinite(self.width) and self.width > 0.0):
            raise MotosimError(f"Road width = {self.width!r}; expected a finite number > 0 [m]")

    def to_json(self) -> dict[str, Any]:
        """The road as plain lists (rounded to the centimetre)."""
        return {
            "x": np.round(self.x, 2).tolist(),
            "y": np.round(self.y, 2).tolist(),
            "width": self.width,
        }


def road_from_xy(
    x: Array, y: Array, *, spacing: float = 2.0, before: float = 50.0, after: float = 400.0
) -> Road:
    """A road along a trajectory or path, resampled and extended straight at both ends.

    Parameters
    ----------
    x, y : ndarray, shape (n,)
        The run's positions or the scenario's path [m].
    spacing : float
        Distance between centre-line points [m].
    before, after : float
        Straight road added before the start and past the end [m].

    Returns
    -------
    Road

    Raises
    ------
    MotosimError
        If the points are not finite or do not cover at least ``spacing``.

    Examples
    --------
    >>> road = road_from_xy(np.array([0.0, 10.0]), np.zeros(2), before=4.0, after=4.0)
    >>> road.x
    array([-4., -2.,  0.,  2.,  4.,  6.,  8., 10., 12., 14.])
    """
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    keep = np.isfinite(x) & np.isfinite(y)
    x, y = x[keep], y[keep]
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    if s.size < 2 or not s[-1] >= spacing:
        raise MotosimError(
            f"a road from {s.size} points covering {s[-1] if s.size else 0.0:.3g} m; "
            f"expected at least {spacing} m"
        )
    su = np.arange(0.0, s[-1] + 1e-9, spacing)
    xs, ys = np.interp(su, s, x), np.interp(su, s, y)

    def heading(i: int, j: int) -> tuple[float, float]:
        d = math.hypot(xs[j] - xs[i], ys[j] - ys[i])
        return (xs[j] - xs[i]) / d, (ys[j] - ys[i]) / d

    c0, s0 = heading(0, 1)
    c1, s1 = heading(-2, -1)
    back = np.arange(round(before / spacing), 0, -1) * spacing
    ahead = np.arange(1, round(after / spacing) + 1) * spacing
    return Road(
        np.concatenate([xs[0] - back * c0, xs, xs[-1] + ahead * c1]),
        np.concatenate([ys[0] - back * s0, ys, ys[-1] + ahead * s1]),
    )


def _table(result: TimeSeries) -> tuple[tuple[str, ...], Array]:
    names = ("t", *result.names)
    missing = [n for n in POSE_SIGNALS if n not in names]
    if missing:
        raise MotosimError(f"a result without {', '.join(missing)}; the view needs {POSE_SIGNALS}")
    if result.t.size < 2:
        raise MotosimError(f"a result of {result.t.size} rows; the view needs at least 2")
    return names, np.column_stack([result.t, result.data])


@dataclass
class _Clock:
    """Replay time: ``offset`` plus the wall time since ``since`` times ``rate`` when playing."""

    now: Callable[[], float]
    rate: float = 1.0
    playing: bool = False
    offset: float = 0.0
    since: float = 0.0
    epoch: int = 0  # changes on each seek, so the dashboard starts over

    def time(self) -> float:
        if not self.playing:
            return self.offset
        return self.offset + (self.now() - self.since) * self.rate


class ReplayFeed:
    """A saved result played against the wall clock; it is also its own :class:`RunControl`.

    Parameters
    ----------
    result : TimeSeries
        The run (:func:`motosim.io.results.load_result`); it needs the pose signals
        :data:`motosim.io.telemetry.POSE_SIGNALS`.
    rate : float
        Replay speed (1 is real time).
    loop : bool
        Start over at the end instead of stopping there.
    now : callable
        Wall clock [s] (a fake one in tests).

    Examples
    --------
    >>> t = np.arange(11) / 10
    >>> run = TimeSeries(t, np.column_stack([t, 0 * t, 0 * t, 0 * t, 0 * t, 20 + 0 * t]),
    ...                  ("x", "y", "psi", "phi", "delta", "v_x"))
    >>> clock = [0.0]
    >>> feed = ReplayFeed(run, now=lambda: clock[0])
    >>> feed.arm(); clock[0] = 0.35
    >>> feed.latest()[0], feed.read_since(0)[0][:, 0]
    (np.float64(0.3), array([0. , 0.1, 0.2, 0.3]))
    """

    def __init__(
        self,
        result: TimeSeries,
        *,
        rate: float = 1.0,
        loop: bool = False,
        now: Callable[[], float] = time.monotonic,
    ) -> None:
        self.names, self._table = _table(result)
        if not (math.isfinite(rate) and rate > 0.0):
            raise MotosimError(f"replay rate = {rate!r}; expected a finite number > 0")
        self._clock = _Clock(now, rate)
        self._loop = loop
        self.control: RunControl = self
        self.t0 = float(self._table[0, 0])
        self.duration = float(self._table[-1, 0] - self.t0)

    def _index(self) -> int:
        """Rows whose time has come."""
        t = self._clock.time()
        if t > self.duration:
            if self._loop:
                self.seek(0.0)
                self._clock.playing, self._clock.since = True, self._clock.now()
                t = 0.0
            else:
                self.seek(self.duration)
                t = self.duration
        return int(np.searchsorted(self._table[:, 0] - self.t0, t, side="right"))

    # RunControl -------------------------------------------------------------------------
    def arm(self) -> None:
        """Play (from the start again once at the end)."""
        if self._clock.playing:
            return
        if self._clock.offset >= self.duration:
            self.seek(0.0)
        self._clock.playing, self._clock.since = True, self._clock.now()

    def stop(self) -> None:
        """Pause."""
        self._clock.offset = self._clock.time()
        self._clock.playing = False

    def state(self) -> str:
        """``"playing"``, ``"paused"`` or ``"ended"``."""
        self._index()
        if self._clock.playing:
            return "playing"
        return "ended" if self._clock.offset >= self.duration else "paused"

    # Replay only ------------------------------------------------------------------------
    def seek(self, t: float) -> None:
        """Jump to ``t`` seconds after the start (clamped to the run)."""
        if not math.isfinite(t):
            raise MotosimError(f"seek to t = {t!r}; expected a finite time [s]")
        self._clock.offset = min(max(float(t), 0.0), self.duration)
        self._clock.since = self._clock.now()
        if self._clock.offset >= self.duration:
            self._clock.playing = False
        self._clock.epoch += 1

    def set_rate(self, rate: float) -> None:
        """Change the replay speed (1 is real time)."""
        if not (math.isfinite(rate) and 0.0 < rate <= 100.0):
            raise MotosimError(f"replay rate = {rate!r}; expected a number in (0, 100]")
        self._clock.offset = self._clock.time()
        self._clock.since = self._clock.now()
        self._clock.rate = float(rate)

    def rows(self) -> Array:
        """Every row of the run, ``names`` its columns (the dashboard of a replay plots them
        all, a cursor at the replay time)."""
        out: Array = self._table.copy()
        return out

    # Feed -------------------------------------------------------------------------------
    def read_since(self, cursor: int) -> tuple[Array, int]:
        """Rows from ``cursor`` to the replay time (from the start again if ``cursor`` is ahead)."""
        end = self._index()
        if cursor > end:
            cursor = 0
        return self._table[cursor:end].copy(), end

    def latest(self) -> Array | None:
        """The row at the replay time."""
        end = self._index()
        row: Array = self._table[max(end - 1, 0)].copy()
        return row

    def status(self) -> dict[str, Any]:
        """State, replay time and duration [s], rate, seek epoch."""
        return {
            "mode": "replay",
            "state": self.state(),
            "t": min(self._clock.time(), self.duration),
            "duration": self.duration,
            "rate": self._clock.rate,
            "epoch": self._clock.epoch,
        }


@dataclass
class LiveFeed:
    """A loop's ring buffer read from outside the loop, with the loop's run control.

    Attributes
    ----------
    ring : TelemetryRing
        Written by the loop.
    control : RunControl
        The loop's arm/stop.
    duration : float
        Planned run length [s] (NaN if open-ended).
    watchdog_periods : int
        The safety stage's watchdog (for the reason of a watchdog fault).
    """

    ring: TelemetryRing
    control: RunControl
    duration: float = math.nan
    watchdog_periods: int = 3
    names: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        self.names = self.ring.names
        missing = [n for n in POSE_SIGNALS if n not in self.names]
        if missing:
            raise MotosimError(
                f"a ring without {', '.join(missing)}; the view needs {POSE_SIGNALS}"
            )

    def read_since(self, cursor: int) -> tuple[Array, int]:
        """The ring's rows after ``cursor`` (from the oldest kept if ``cursor`` is ahead)."""
        if cursor > self.ring.count:
            cursor = 0
        return self.ring.read_since(cursor)

    def latest(self) -> Array | None:
        """The ring's last row."""
        return self.ring.latest()

    def status(self) -> dict[str, Any]:
        """The loop's state, the last row's time and the planned duration [s]."""
        row = self.ring.latest()
        status: dict[str, Any] = {
            "mode": "live",
            "state": self.control.state(),
            "t": float(row[0]) if row is not None else 0.0,
            "duration": self.duration if math.isfinite(self.duration) else None,
            "rate": 1.0,
            "epoch": 0,
        }
        names = self.names
        if row is not None and "state" in names and "fault" in names:
            state, fault = row[names.index("state")], row[names.index("fault")]
            if math.isfinite(state) and math.isfinite(fault):
                status["safety"] = {
                    "state": State(int(state)).name.lower(),
                    "fault": Fault(int(fault)).name,
                    "reason": fault_reason(int(fault), watchdog_periods=self.watchdog_periods),
                }
        if row is not None and "missed" in names:
            missed = row[names.index("missed")]
            status["missed"] = int(missed) if math.isfinite(missed) else None
        return status


def merge_signals(result: TimeSeries, other: TimeSeries) -> TimeSeries:
    """``result`` with the signals of ``other`` it lacks, linearly interpolated onto its time.

    Outside ``other``'s time span the added signals are NaN (for example platform commands
    of :mod:`motosim.cueing`, computed at a lower rate, added to the run they came from).

    Examples
    --------
    >>> run = TimeSeries(np.arange(4.0), np.zeros((4, 1)), ("phi",))
    >>> cue = TimeSeries(np.array([0.0, 2.0]), np.array([[0.0], [1.0]]), ("phi_s",))
    >>> merge_signals(run, cue)["phi_s"]
    array([0. , 0.5, 1. , nan])
    """
    new = [n for n in other.names if n not in result.names]
    if not new:
        return result
    added = np.column_stack(
        [np.interp(result.t, other.t, other[n], left=np.nan, right=np.nan) for n in new]
    )
    return TimeSeries(result.t, np.column_stack([result.data, added]), (*result.names, *new))


def names_index(names: Sequence[str]) -> dict[str, int]:
    """Column of each name."""
    return {name: j for j, name in enumerate(names)}
