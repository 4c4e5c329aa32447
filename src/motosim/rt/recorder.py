"""The recorder: a process that drains the loop's shared ring into the result files.

Writing files takes milliseconds with the interpreter lock held; in its own process the
recorder cannot delay the loop. :class:`Recorder` is the loop's side: it starts the process
with one :class:`RecorderSettings`, and the two talk over a pipe in the small typed messages
of this module:

- the recorder sends :class:`Ready` (the result opened; the live view's URL, if any) or
  :class:`Failed` (one line);
- the loop sends :class:`Close` (the run is over: complete or not, and its summary's extra
  values); the recorder writes the last rows, closes the files and sends :class:`Done` (the
  result's summary, where its rows are, the profile of the compute time, the state stream's
  figures) or :class:`Failed`;
- the loop sends :class:`Release` once it has written its own files beside the rows: the
  recorder holds the folder's lock (:class:`~motosim.io.files.FolderLock`) until then, so
  that a concurrent ``--overwrite`` of the folder is refused meanwhile.

The recorder drains the ring every 0.1 s (every 5 ms with a live view), publishes the state
stream from the ring's newest row every 1 ms in a thread (:class:`~motosim.rt.telemetry.StateRelay`,
with ``telemetry``), and feeds a :class:`LiveSink` (the rider's view and the dashboard, which
a later layer provides).
"""

import enum
import threading
from collections.abc import Callable
from contextlib import ExitStack, suppress
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple, Protocol

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError, RunFailedError

__all__ = [
    "Close",
    "Control",
    "Done",
    "Failed",
    "LiveSink",
    "Ready",
    "Recorder",
    "RecorderSettings",
    "Release",
    "recorder_main",
]

Array = NDArray[np.float64]

ANSWER_TIMEOUT = 120.0
"""How long the loop waits for the recorder's :class:`Ready` or :class:`Done` [s]."""

_STAMPS = ("compute", "done_read", "done_control", "done_send", "stack")


class Ready(NamedTuple):
    """The result is open and the ring is read; ``url``: the live view's, or None."""

    url: str | None


class Failed(NamedTuple):
    """The recorder could not open, write or close the result: one line saying why."""

    reason: str


class Close(NamedTuple):
    """The run is over: write the last rows and close the result.

    ``complete``: the run reached its duration; ``extra``: values added to the summary
    (the loop's timing, a fall's ``failure``).
    """

    complete: bool
    extra: dict[str, Any]


class Done(NamedTuple):
    """The result is closed: its summary, where its rows are (the folder, or the staging
    folder of a result that could not be published), the compute time's profile
    (:func:`~motosim.rt.run.profile_stats`) and the state stream's figures."""

    summary: dict[str, Any]
    location: str
    profile: dict[str, dict[str, float]]
    stream: dict[str, float]


class Release(NamedTuple):
    """The loop's files beside the rows are written: the folder's lock may go."""


class Control(enum.Enum):
    """A live view's button, sent to the loop's process."""

    ARM = "arm"
    """Start the torque (a fade-in through the safety stage)."""
    STOP = "stop"
    """Stop as Ctrl-C does: the torque fades out and the run ends."""


class LiveSink(Protocol):
    """A live view fed by the recorder (picklable: it is sent to the recorder's process)."""

    def start(self, names: tuple[str, ...], controls: Any) -> str:
        """Start serving rows of the loop's columns ``names``; its URL. ``controls``: the
        sending end of a pipe to the loop's process, for :class:`Control` values."""
        ...

    def push(self, rows: Array, block: Array) -> None:
        """The loop's ``rows`` drained, and their result rows ``block``."""
        ...

    def stop(self) -> None:
        """Stop serving."""
        ...


@dataclass(frozen=True)
class RecorderSettings:
    """What the recorder process needs (picklable): the shared ring's handle
    (:attr:`motosim.rt.ring.SampleRing.handle`) and columns
    (:attr:`motosim.rt.run.RealtimeRunner.names`); the result's folder, metadata and
    ``overwrite`` (:class:`~motosim.rt.session.SessionConfig`'s); the handlebar's motor torque
    per ampere [N*m/A] (the result's motor torque); the control rate [Hz] (the state
    stream's pace); where to publish the state stream (None: nowhere); the live view to feed
    every 5 ms (None: none) and, with it, the sending end of the pipe its buttons go to."""

    ring: Any
    names: tuple[str, ...]
    folder: Path
    metadata: dict[str, Any] = field(repr=False)
    overwrite: bool
    torque_per_amp: float
    rate: float
    telemetry: tuple[str, int] | None = None
    live: LiveSink | None = None
    controls: Any = None


class Recorder:
    """The loop's side of the recorder process.

    Parameters
    ----------
    settings : RecorderSettings
        The recorder's settings.

    Raises
    ------
    MotosimError
        From :meth:`start` and :meth:`close`: the recorder's :class:`Failed` line, or its end
        without an answer.
    """

    def __init__(self, settings: RecorderSettings) -> None:
        import multiprocessing

        self.settings = settings
        ctx = multiprocessing.get_context("spawn")
        self._conn, theirs = ctx.Pipe()
        self._process = ctx.Process(
            target=recorder_main, args=(theirs, settings), name="motosim-writer", daemon=True
        )
        self._theirs = theirs
        self._closed = False

    def start(self) -> str | None:
        """Start the process; the live view's URL once the result is open (or None)."""
        self._process.start()
        self._theirs.close()  # the recorder holds its copy: EOF here if it ends without a word
        answer = self._answer(Ready, "start")
        assert isinstance(answer, Ready)
        return answer.url

    def close(self, complete: bool, extra: dict[str, Any]) -> Done:
        """Ask the recorder to close the result; its :class:`Done`."""
        with suppress(OSError):  # it has ended (a write failed): its answer is read below
            self._conn.send(Close(complete, extra))
        answer = self._answer(Done, "finish")
        assert isinstance(answer, Done)
        self._closed = True
        return answer

    def release(self) -> None:
        """Let the recorder release the folder's lock (after :meth:`close`; before it, the
        end of the pipe closes the result partial), then join it; killed if it has not ended
        within 10 s."""
        if self._closed:
            with suppress(OSError):  # it has ended
                self._conn.send(Release())
        self._conn.close()
        if self._process.pid is None:  # never started
            return
        self._process.join(timeout=10.0)
        if self._process.is_alive():
            self._process.kill()
            self._process.join()

    def _answer(self, kind: type[Ready] | type[Done], what: str) -> Ready | Done:
        try:
            if self._conn.poll(ANSWER_TIMEOUT):
                answer = self._conn.recv()
                if isinstance(answer, Failed):
                    raise MotosimError(answer.reason)
                if isinstance(answer, kind):
                    return answer
        except (EOFError, OSError):
            pass
        raise MotosimError(f"{self.settings.folder}: the result writer did not {what}")


def recorder_main(conn: Any, settings: RecorderSettings) -> None:
    """The recorder process (see the module docstring).

    Ctrl-C, SIGTERM and SIGHUP, which a terminal or a service manager sends the whole
    process group, are the loop's to handle: the loop fades the torque out and then sends
    :class:`Close`; this process ignores them.
    """
    import signal

    from motosim.errors import stop_signals
    from motosim.io.files import FolderLock

    for sig in (signal.SIGINT, *stop_signals()):
        signal.signal(sig, signal.SIG_IGN)
    with ExitStack() as held:
        try:
            lock = held.enter_context(FolderLock(settings.folder))
        except MotosimError as err:
            conn.send(Failed(str(err)))
            return
        if _record(conn, settings, lock):
            with suppress(EOFError, OSError):
                conn.recv()  # Release: the loop has written its files, or has ended


class _Drain:
    """The rows drained from the ring: the result's blocks, the safety states and the
    profile's stamps, kept for the summary; the blocks not yet written."""

    def __init__(self, ring: Any, settings: RecorderSettings) -> None:
        names = settings.names
        self.ring = ring
        self.names = names
        self.torque_per_amp = settings.torque_per_amp
        self.blocks: list[Array] = []
        self.states: list[Array] = []
        self.stamps: list[Array] = []
        self.pending: list[Array] = []
        self.stamp_cols = [names.index(n) for n in _STAMPS] if set(_STAMPS) <= set(names) else []
        self.state_col = names.index("state")

    def drain(self, live: LiveSink | None) -> None:
        """Take the rows waiting in the ring (and feed ``live``)."""
        from motosim.rt.stack import result_block

        rows = self.ring.drain()
        if not rows.shape[0]:
            return
        block = result_block(rows, self.names, self.torque_per_amp)
        self.blocks.append(block)
        self.states.append(rows[:, self.state_col])
        if self.stamp_cols:
            self.stamps.append(rows[:, self.stamp_cols])
        self.pending.append(block)
        if live is not None:
            live.push(rows, block)

    def write(self, writer: Any) -> None:
        """Append the blocks not yet written."""
        if self.pending:
            writer.append(np.vstack(self.pending))
            self.pending.clear()

    def summary(self, complete: bool) -> dict[str, Any]:
        """The run's metrics on every row drained."""
        from motosim.rt.safety import State
        from motosim.rt.stack import RESULT_SIGNALS
        from motosim.sim.metrics import run_metrics

        width = len(RESULT_SIGNALS)
        rows = np.vstack(self.blocks) if self.blocks else np.zeros((0, width))
        col = {name: j for j, name in enumerate(RESULT_SIGNALS)}
        running = np.concatenate(self.states) == State.RUNNING if self.states else None
        return run_metrics(
            rows[:, col["t"]],
            lambda n: rows[:, col[n]] if n in col else None,
            complete=complete,
            running=running,
        )

    def profile(self) -> dict[str, dict[str, float]]:
        """Where the compute time went (:func:`~motosim.rt.run.profile_stats`)."""
        from motosim.rt.run import profile_stats

        return profile_stats(np.vstack(self.stamps), _STAMPS) if self.stamps else {}


def _record(conn: Any, settings: RecorderSettings, lock: Any) -> bool:
    """:func:`recorder_main` under the folder's ``lock`` (held, handed to the writer): False
    once :class:`Failed` is sent, True once :class:`Done` is."""
    from motosim.io.results import ResultWriter
    from motosim.rt.ring import SampleRing
    from motosim.rt.stack import RESULT_SIGNALS

    ring = SampleRing.attach(settings.ring)
    live = settings.live
    try:
        url = None if live is None else live.start(settings.names, settings.controls)
        writer = ResultWriter(
            settings.folder,
            RESULT_SIGNALS,
            settings.metadata,
            overwrite=settings.overwrite,
            lock=lock,
        )
    except MotosimError as err:
        conn.send(Failed(str(err)))
        ring.close()
        if live is not None:
            live.stop()
        return False
    stop_relay = _start_relay(ring, settings)
    conn.send(Ready(url))
    drain = _Drain(ring, settings)
    try:
        summary = _write(conn, writer, drain, live)
    except MotosimError as err:
        # a write failed (a full disk) or the folder gained files of another kind while the
        # run went: the message says where the rows are
        conn.send(Failed(str(err)))
        return False
    finally:
        stream = stop_relay()
        ring.close()
        if live is not None:
            live.stop()
    summary["ring_dropped"] = float(ring.dropped)
    try:
        conn.send(Done(summary, str(writer.location), drain.profile(), stream))
    except OSError:  # the loop has ended without waiting for it
        return False
    return True


class _IncompleteError(RunFailedError):
    """The run ended before its duration (a stop or a fault): the result is closed partial."""


def _write(conn: Any, writer: Any, drain: _Drain, live: LiveSink | None) -> dict[str, Any]:
    """Drain the ring into ``writer`` until :class:`Close`; close the result; its summary.

    A run that ended before its duration (stopped or faulted) is closed marked incomplete,
    through the writer's exit on an exception that says so (a fall is closed whole and
    flagged with its ``failure``, as offline).
    """
    period = 0.1 if live is None else 0.005  # the view is at most 5 ms behind the loop
    every = round(0.1 / period)
    summary: dict[str, Any] = {}
    try:
        with writer:
            k = 0
            while not conn.poll(period):
                k += 1
                drain.drain(live)
                if k % every == 0:
                    drain.write(writer)
            try:
                close = conn.recv()
            except (EOFError, OSError):  # the loop ended without a word: closed partial
                close = Close(False, {})
            if not isinstance(close, Close):
                raise MotosimError(f"the result writer was sent {close!r}; expected Close")
            drain.drain(live)
            drain.write(writer)
            summary = drain.summary(close.complete) | close.extra
            if not close.complete and "failure" not in close.extra:
                raise _IncompleteError("the run ended before its duration")
            writer.close(summary)
    except _IncompleteError:
        pass
    return summary


def _start_relay(ring: Any, settings: RecorderSettings) -> Callable[[], dict[str, float]]:
    """Start the state stream's relay thread (none without ``telemetry``); the function that
    stops it and gives its figures (datagrams sent and dropped, the lag after the loop's row
    [s])."""
    address = settings.telemetry
    if address is None:
        return dict
    from motosim.rt.stack import STACK_SIGNALS
    from motosim.rt.telemetry import StateRelay, StateSender

    names = settings.names
    sender = StateSender(address, width=len(STACK_SIGNALS))
    buffer, counters = ring.arrays
    relay = StateRelay(
        buffer, counters, names, names.index(STACK_SIGNALS[0]), sender.send, rate=settings.rate
    )
    stop = threading.Event()
    thread = threading.Thread(target=relay.run, args=(stop,), name="motosim-state", daemon=True)
    thread.start()

    def finish() -> dict[str, float]:
        stop.set()
        thread.join(timeout=1.0)
        sender.close()
        lags = {f"lag_{k}": v for k, v in relay.lag_stats().items()}
        return {"sent": float(relay.sent), "dropped": float(sender.dropped)} | lags

    return finish
