"""A real-time run, owned by one object: read -> update -> write -> record.

:class:`RealtimeSession` is what ``motosim run`` builds from a :class:`SessionConfig` (the
checked options and the scenario's ``[realtime]`` settings) and runs:

1. :meth:`~RealtimeSession.prepare` loads the compiled stack, opens the bus and builds the
   :class:`~motosim.rt.run.RealtimeRunner`;
2. :meth:`~RealtimeSession.open` starts the recorder process
   (:class:`~motosim.rt.recorder.Recorder`), which drains the runner's ring into the result
   files;
3. :meth:`~RealtimeSession.run` applies the privileges, runs the rate loop once (at the
   duration the runner fades the torque out, as on a stop request, and ends the run once it
   is zero) and returns the :class:`Outcome`;
4. :meth:`~RealtimeSession.close` lets the recorder release the result folder (after the
   caller has written its own files beside the rows) and frees the shared ring.

The session installs no signal handler: the command turns Ctrl-C into
:meth:`~RealtimeSession.request_stop` (a second one into
:meth:`~RealtimeSession.emergency_stop`).
"""

import enum
import math
import threading
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, Self

from motosim.choices import SENSOR_ESTIMATOR
from motosim.errors import MotosimError
from motosim.rt.clock import Clock
from motosim.rt.loop import TimingStats
from motosim.rt.privileges import Privilege
from motosim.rt.recorder import Control, Done, LiveSink, Recorder, RecorderSettings

if TYPE_CHECKING:
    from motosim.cueing import CueingConfig
    from motosim.rt.run import RealtimeRunner, RunCounters
    from motosim.rt.safety import SafetyLimits
    from motosim.sim import RunInputs
    from motosim.sim.stack import StackModel

__all__ = [
    "Ending",
    "Outcome",
    "PrivilegeRequest",
    "RealtimeSession",
    "RunOptions",
    "SessionConfig",
]

Pace = Literal["clock", "bus"]
Wait = Literal["compiled", "python"]


@dataclass(frozen=True, slots=True)
class PrivilegeRequest:
    """The real-time privileges asked for (:func:`~motosim.rt.privileges.apply_privileges`):
    the SCHED_FIFO priority (None: the normal scheduler), the CPUs to pin to (None: any),
    whether to lock the memory."""

    priority: int | None = None
    cpus: tuple[int, ...] | None = None
    mlock: bool = False

    @property
    def all_given(self) -> bool:
        """Whether every privilege that helps a loop's timing was asked for."""
        return self.priority is not None and self.cpus is not None and self.mlock


@dataclass(frozen=True, slots=True)
class RunOptions:
    """How a real-time run runs and what it sends beside the drive's frames.

    Attributes
    ----------
    pace : {"clock", "bus"}
        What starts each period: the clock's deadlines or the drive's status frame.
    wait : {"compiled", "python"}
        How a clock-paced loop ends its wait (the compiled wait only where the runner
        offers it: :meth:`~motosim.rt.run.RealtimeRunner.compile_wait`).
    fast_link : bool
        The fast udp_multicast link (on that bus; python-can's bus elsewhere).
    warm : bool
        Warm the stack before each deadline.
    overwrite : bool
        Replace a complete result already in the folder.
    telemetry : (str, int) or None
        Where the recorder publishes the state stream.
    platform : CueingConfig or None
        The motion platform's file, when its commands are sent.
    platform_udp : (str, int) or None
        Where the platform's datagrams go.
    platform_can : bool
        Send the platform's commands as frames on the run's bus too.
    privileges : PrivilegeRequest
        The real-time privileges asked for.
    """

    pace: Pace = "clock"
    wait: Wait = "compiled"
    fast_link: bool = True
    warm: bool = True
    overwrite: bool = False
    telemetry: tuple[str, int] | None = None
    platform: "CueingConfig | None" = None
    platform_udp: tuple[str, int] | None = None
    platform_can: bool = False
    privileges: PrivilegeRequest = field(default_factory=PrivilegeRequest)

    def __post_init__(self) -> None:
        if self.pace not in ("clock", "bus"):
            raise MotosimError(f"pace = {self.pace!r}; expected 'clock' or 'bus'")
        if self.wait not in ("compiled", "python"):
            raise MotosimError(f"wait = {self.wait!r}; expected 'compiled' or 'python'")


@dataclass(frozen=True)
class SessionConfig:
    """A real-time run: what :class:`RealtimeSession` builds and runs.

    Attributes
    ----------
    inputs : RunInputs
        The resolved run (its controller's current limit within the safety clamp:
        :func:`~motosim.rt.config.within_safety`).
    model : StackModel
        The designed stack, the status frames' age accounted for
        (:func:`~motosim.sim.stack.account_for_delay`).
    limits : SafetyLimits
        The safety stage's limits.
    bus : str
        python-can's ``INTERFACE[:CHANNEL]``.
    folder : Path
        The result folder.
    metadata : dict
        The result's metadata.
    duration : float
        How long the run lasts before its torque fades out [s], (0, 86400].
    options : RunOptions
        How the run runs and what it sends beside the drive's frames.
    live : LiveSink or None
        The rider's view and the dashboard, fed by the recorder; with it the torque stays
        off until the view's Arm.
    """

    inputs: "RunInputs" = field(repr=False)
    model: "StackModel" = field(repr=False)
    limits: "SafetyLimits"
    bus: str
    folder: Path
    metadata: dict[str, Any] = field(repr=False)
    duration: float
    options: RunOptions = field(default_factory=RunOptions)
    live: LiveSink | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.duration) and 0.0 < self.duration <= 86_400.0):
            raise MotosimError(f"duration = {self.duration!r} s; expected seconds in (0, 86400]")

    @property
    def rate(self) -> float:
        """The control rate [Hz]."""
        return float(self.inputs.scenario.rates.control)

    @property
    def periods(self) -> int:
        """The control periods of the duration."""
        return round(self.duration * self.rate)


class Ending(enum.Enum):
    """Why a run ended."""

    COMPLETED = "completed"
    """It reached its duration; the torque faded out."""
    STOPPED = "stopped"
    """The user stopped it: the torque faded out (Ctrl-C, the view's Stop) or was zeroed at
    once (a second Ctrl-C, Enter: the emergency stop)."""
    FAULT = "fault"
    """The safety stage tripped: the torque zeroed at once."""
    FELL = "fell"
    """The virtual motorcycle fell or left its model's speeds: the torque faded out."""


@dataclass(frozen=True)
class Outcome:
    """How a real-time run ended and what it measured.

    Attributes
    ----------
    ending : Ending
        Why it ended.
    reason : str
        One line: the safety stage's state or fault, or why the motorcycle left its range.
    time : float
        When a fault tripped or the motorcycle left its range [s since the first deadline];
        NaN otherwise.
    folder : Path
        Where the result's rows are.
    stats : TimingStats
        The loop's timing.
    counters : RunCounters
        The bus's and the safety stage's counters.
    privileges : tuple of Privilege
        The privileges applied or refused.
    report : dict
        The figures of ``timing.json``: the link, pace, wait, timing, profile of the compute
        time, state stream, privileges, counters, the safety stage's state and fault.
    """

    ending: Ending
    reason: str
    time: float
    folder: Path
    stats: TimingStats
    counters: "RunCounters"
    privileges: tuple[Privilege, ...]
    report: dict[str, Any] = field(repr=False)


class RealtimeSession:
    """A real-time run (see the module docstring); a context manager that closes it.

    Parameters
    ----------
    config : SessionConfig
        The run.
    clock : Clock
        The loop's clock (:class:`~motosim.rt.clock.MonotonicClock` in a lab).
    """

    def __init__(self, config: SessionConfig, clock: Clock) -> None:
        self.config = config
        self.clock = clock
        self._runner: RealtimeRunner | None = None
        self._link: Any = None
        self._platform: Any = None
        self._closers: list[Callable[[], None]] = []
        self._recorder: Recorder | None = None
        self._buttons: Any = None
        self._stop_asked = self._estop_asked = False  # before the runner was built

    @property
    def runner(self) -> "RealtimeRunner":
        """The period's runner (after :meth:`prepare`)."""
        if self._runner is None:
            raise MotosimError("the session is not prepared: call prepare() first")
        return self._runner

    # --- operator ---------------------------------------------------------------------
    def request_stop(self) -> None:
        """Fade the torque out and end the run (safe from a signal handler)."""
        if self._runner is None:
            self._stop_asked = True
        else:
            self._runner.request_stop()

    def emergency_stop(self) -> None:
        """Zero the torque now and end the run (safe from a signal handler)."""
        if self._runner is None:
            self._estop_asked = True
        else:
            self._runner.emergency_stop()

    # --- the run ----------------------------------------------------------------------
    def prepare(self) -> None:
        """Load the compiled stack, open the bus, build the runner (seconds: the stack's
        compiled code is loaded, or compiled the first time)."""
        import numpy as np

        from motosim.io.can import handlebar_codecs, open_link
        from motosim.rt import run
        from motosim.rt.stack import CompiledStack
        from motosim.sim import build_rig
        from motosim.sim.metrics import validity_limits

        c = self.config
        sc = c.inputs.scenario
        world = build_rig(c.inputs, rng=np.random.default_rng(sc.seed))
        stack = CompiledStack(c.model, force=world.force, side_force=world.side_force)
        if c.options.telemetry is not None:  # sent by the recorder, refused here rather than there
            from motosim.rt.telemetry import StateSender

            StateSender(c.options.telemetry, width=len(stack.names)).close()
        platform = self._platform_output(tuple(stack.names))
        self._link = open_link(c.bus, fast=c.options.fast_link)
        self._closers.append(self._link.close)
        if platform is not None and c.options.platform_can:
            self._platform_can(platform)
        rate = c.rate
        settings = run.RunSettings(
            c.limits,
            rate,
            duration=c.periods / rate,
            periods_per_frame=c.model.measure_every,
            capacity=max(1 << 14, round(5.0 * rate)),  # 5 s of rows between two drains
            shared_ring=True,
            wait_for_arm=c.live is not None,
            warm=c.options.warm,
            handlebar=c.inputs.nominal_handlebar,
            torque_sensor=sc.estimator.name == SENSOR_ESTIMATOR,
            validity=validity_limits(sc.motorcycle.speed),
        )
        self._runner = run.RealtimeRunner(
            stack,
            self._link,
            handlebar_codecs(),
            settings,
            platform=platform,
            clock=self.clock,
            now=self.clock.now,
        )
        if self._estop_asked:  # asked for while the runner was built
            self.emergency_stop()
        elif self._stop_asked:
            self.request_stop()

    def _platform_output(self, names: tuple[str, ...]) -> Any:
        """The motion platform's stage (None without a platform file)."""
        c = self.config
        if c.options.platform is None:
            return None
        from motosim.rt.platform import PlatformOutput, PlatformSender

        sender = None if c.options.platform_udp is None else PlatformSender(c.options.platform_udp)
        platform = PlatformOutput(
            c.options.platform,
            1.0 / c.rate,
            names,
            sender=sender,
            send_every=max(1, round(c.rate / 100.0)),
        )
        self._platform = platform
        self._closers.append(lambda: _close_sender(platform))
        return platform

    def _platform_can(self, platform: Any) -> None:
        """The platform's commands as frames on the run's bus (beside its datagrams)."""
        from motosim.io.can import platform_codecs
        from motosim.rt.platform import PlatformCanSender, PlatformTee

        can = PlatformCanSender(self._link, platform_codecs())
        platform.sender = can if platform.sender is None else PlatformTee(platform.sender, can)

    def open(self) -> str | None:
        """Start the recorder (the result opened, its folder locked); the live view's URL."""
        import multiprocessing

        c, runner = self.config, self.runner
        controls = None
        if c.live is not None:
            self._buttons, controls = multiprocessing.get_context("spawn").Pipe(duplex=False)
        realtime = c.metadata.get("realtime", {}) | {"link": self._link.label}
        settings = RecorderSettings(
            runner.ring.handle,
            runner.names,
            c.folder,
            c.metadata | {"realtime": realtime},
            c.options.overwrite,
            c.inputs.nominal_handlebar.torque_per_amp,
            c.rate,
            c.options.telemetry,
            c.live,
            controls,
        )
        self._recorder = Recorder(settings)
        url = self._recorder.start()
        if controls is not None:
            controls.close()  # the recorder holds its copy: EOF here once it ends
            threading.Thread(target=self._controls, daemon=True).start()
        return url

    def _controls(self) -> None:
        """The view's buttons: blocked on their pipe until one is pressed."""
        runner = self.runner
        while True:
            try:
                control = self._buttons.recv()
            except (EOFError, OSError):
                return
            if control is Control.STOP:
                runner.request_stop()  # as Ctrl-C: the torque fades out, then the run ends
            elif control is Control.ARM:
                runner.arm()

    def run(self) -> Outcome:
        """Run the loop once, close the result; the outcome (after :meth:`open`)."""
        from motosim.rt.privileges import apply_privileges, freeze_gc, thaw_gc

        runner, recorder = self.runner, self._recorder
        if recorder is None:
            raise MotosimError("the session's recorder is not started: call open() first")
        asked = self.config.options.privileges
        privileges = apply_privileges(priority=asked.priority, cpus=asked.cpus, mlock=asked.mlock)
        loop, step = self._loop()
        freeze_gc()
        runner.discard_pending()  # frames queued while the recorder started are stale
        try:
            loop.run(step, periods=runner.max_periods)
        finally:
            thaw_gc()
        stats = loop.stats()
        fault = runner.safety.fault.name
        complete = runner.reached_end and fault == "NONE" and runner.left_range is None
        extra: dict[str, Any] = {f"rt_{k}": float(v) for k, v in stats.as_dict().items()}
        if runner.left_range is not None and fault == "NONE":
            extra["failure"] = runner.left_range  # the motorcycle fell: flagged, as offline
        done = recorder.close(complete, extra)
        counters = runner.counters()
        bus_errors = int(runner.link.errors)
        self._close_link()
        return self._outcome(stats, counters, privileges, done, bus_errors)

    def _loop(self) -> tuple[Any, Callable[[int, float], bool]]:
        """The rate loop and its step (the runner's period: it ends the run once the torque
        has faded out after the duration or a stop request)."""
        from motosim.rt.loop import FramePacedLoop, RateLoop

        c, runner, clock = self.config, self.runner, self.clock
        rate = c.rate
        capacity = max(1, min(runner.max_periods, 1 << 22))
        inner = runner.period
        loop: RateLoop
        if c.options.pace == "bus":
            loop = FramePacedLoop(
                rate,
                clock,
                runner.wait_status,
                timeout=runner.watchdog_time,
                first_timeout=runner.first_timeout,
                capacity=capacity,
                received=lambda: runner.status_frames,
            )
        elif c.options.wait == "compiled" and runner.compile_wait():
            # the wait's end, the bus read and the period in one compiled call
            loop = RateLoop(rate, clock, capacity=capacity, woke=runner.woke)
            inner = runner.wait_period
        else:  # the stack warmed in the caches just before each deadline
            loop = RateLoop(
                rate, clock, capacity=capacity, warm=runner.warm if runner.warms else None
            )
        return loop, inner

    def _outcome(
        self,
        stats: TimingStats,
        counters: "RunCounters",
        privileges: tuple[Privilege, ...],
        done: Done,
        bus_errors: int,
    ) -> Outcome:
        """The :class:`Outcome` of the loop's end."""
        runner, c = self.runner, self.config
        left = runner.left_range
        if counters.fault == "NONE" and left is not None:
            ending, reason, time = Ending.FELL, left, runner.left_range_time
        elif counters.fault == "ESTOP_KEY" or (counters.fault == "NONE" and runner.stop_requested):
            ending, reason, time = Ending.STOPPED, counters.fault_reason, counters.fault_time
        elif counters.fault != "NONE":
            ending, reason, time = Ending.FAULT, counters.fault_reason, counters.fault_time
        else:
            ending, reason, time = Ending.COMPLETED, counters.fault_reason, math.nan
        platform = self._platform
        report = {
            "link": self._link.label,
            "pace": c.options.pace,
            "wait": "compiled" if runner.waits_compiled else "python",
            "warm": runner.warms and c.options.pace == "clock",
            "timing": stats.as_dict(),
            "profile": done.profile,
            "state_stream": done.stream,
            "units": "s",
            "privileges": [asdict(p) for p in privileges],
            "counters": {
                "status_frames": counters.status_frames,
                "torque_frames": counters.torque_frames,
                "frames_lost": counters.frames_lost,
                "frames_stale": counters.frames_stale,
                "send_errors": counters.send_errors,
                "bus_errors": bus_errors,
                "ring_dropped": int(done.summary.get("ring_dropped", 0)),
                "platform_datagrams": 0 if platform is None else platform.sequence,
                "platform_can": c.options.platform_can,
            },
            "state": counters.state,
            "fault": counters.fault,
            "fault_reason": counters.fault_reason,
            "ending": ending.value,
        }
        return Outcome(
            ending, reason, time, Path(done.location), stats, counters, privileges, report
        )

    def _close_link(self) -> None:
        """Close the bus and the platform's senders."""
        closers, self._closers = self._closers, []
        for close in reversed(closers):
            close()

    def close(self) -> None:
        """Let the recorder release the result folder and end; free the bus and the ring."""
        recorder, self._recorder = self._recorder, None
        try:
            if recorder is not None:
                recorder.release()
        finally:
            self._close_link()
            if self._runner is not None:
                self._runner.ring.close()
            if self._buttons is not None:
                self._buttons.close()
                self._buttons = None

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _close_sender(platform: Any) -> None:
    """Close the platform's sender, if it has one."""
    if platform.sender is not None:
        platform.sender.close()
