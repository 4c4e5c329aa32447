"""One control period over the bus: read the drive, step the stack, guard, send, record.

:class:`RealtimeRunner` is what ``motosim run`` drives with a :class:`~motosim.rt.loop.RateLoop`
(paced by the clock) or a :class:`~motosim.rt.loop.FramePacedLoop` (paced by the drive's
status frame, which :meth:`RealtimeRunner.wait_status` waits for). Each period it

1. reads every frame waiting on the bus (non-blocking): status frames are decoded with the
   precompiled codec and checked by the safety stage (checksum, alive counter, drive fault);
   E-stop frames trip the emergency stop;
2. steps the stack (anything with the :class:`StackStepper` protocol: the compiled stack of
   :mod:`motosim.sim` in ``motosim run``) with the last valid angle [rad] and current [A];
3. passes its command through the :class:`~motosim.rt.safety.SafetyStage`;
4. encodes and sends the command frame (and a heartbeat frame at about 10 Hz);
5. publishes the stack's row (``telemetry``) and steps the motion platform's stage;
6. copies one row of signals into a :class:`~motosim.rt.ring.SampleRing`, read outside the
   loop, with the times at which steps 1, 3 and 4 ended (:func:`profile_stats`).

The stack starts on the first valid status frame (reset at its angle and current) and the
safety stage is enabled then (or, with ``wait_for_arm``, when :meth:`RealtimeRunner.arm` is
called: the view's Arm button), so the torque fades in over 0.5 s. A stop request (Ctrl-C)
fades the torque out and ends the run once it is zero (so does the end of the run's
``duration``, inside the same run of the loop); a fault zeroes the command at once and ends the run
``linger`` seconds later, the zero command still sent meanwhile.
"""

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.io.can import FRAME_ROW, FrameColumn, HandlebarCodecs, Link, codec_table
from motosim.params.checks import check_number
from motosim.params.handlebar import HandlebarParameters
from motosim.rt import fused
from motosim.rt.clock import Clock
from motosim.rt.fused import PeriodArrays, PeriodEnd
from motosim.rt.ring import RingCounter, SampleRing
from motosim.rt.safety import Fault, SafetyLimits, SafetyStage
from motosim.rt.stack import StackParts, compiled
from motosim.sim.metrics import range_reason
from motosim.sim.stack import new_data

if TYPE_CHECKING:
    from motosim.rt.platform import PlatformOutput

__all__ = [
    "LOOP_SIGNALS",
    "RealtimeRunner",
    "RunCounters",
    "RunSettings",
    "StackStepper",
    "profile_stats",
]

Array = NDArray[np.float64]

LOOP_SIGNALS = tuple(column.name for column in fused.LoopColumn)
"""The loop's own columns, before the stack's: time [s], the measured angle [rad] and current
[A] used this period, the stack's command and the one sent [A], the safety state and fault
codes (:class:`~motosim.rt.safety.State`, :class:`~motosim.rt.safety.Fault`); the period's
deadline on the loop's clock [s], its wake-up latency and compute time until the row is
written [s] (NaN without ``now``), and the deadlines missed before it; then where the compute
time went: the times [s] after the wake-up at which the bus was read, the stack and the
safety stage had run and the command frame was sent (NaN without ``now``;
:func:`profile_stats` summarises them; the rest, up to ``compute``, is the telemetry
datagram, the platform's stage and the row); and the stack's own time [s], measured inside the
compiled period (NaN for a stack in Python)."""
_COMPUTE = int(fused.LoopColumn.compute)
_DONE_CONTROL = int(fused.LoopColumn.done_control)
_DONE_SEND = int(fused.LoopColumn.done_send)
_T = int(fused.LoopColumn.t)
_WRITTEN = int(RingCounter.written)
_ANY_RANGE = (math.inf, -math.inf, math.inf)
"""No range for the virtual motorcycle: any roll, any speed."""


def _row_positions(names: tuple[str, ...]) -> dict[str, int]:
    """Where the stack's row ``names`` holds what the period reads of it (-1: nowhere): the
    estimate of the rider's torque, the handlebar's rate, the roll and the speed."""
    signals = {
        "tau_at": "tau_r_hat",
        "rate_at": "theta_h_dot_hat",
        "phi_at": "phi",
        "speed_at": "v_x",
    }
    return {at: names.index(name) if name in names else -1 for at, name in signals.items()}


class StackStepper(Protocol):
    """What the loop needs of the stack: reset, one step, and the signals of the last step."""

    @property
    def names(self) -> tuple[str, ...]:
        """The signals of :meth:`row` (``tau_r_hat`` and ``theta_h_dot_hat`` are used when
        present: hands-off detection and the speed limiter)."""
        ...

    def reset(self, theta: float, current: float) -> None:
        """Start every state at the measured angle [rad] and current [A]."""
        ...

    def step(
        self, theta_meas: float, i_meas: float, fresh: bool, scale: float, torque: float
    ) -> float:
        """One control period: the motor current command [A]; ``fresh``: the measurement
        came in a new status frame this period (the last valid one is given otherwise);
        ``scale``: the share of the command the safety stage will pass
        (:func:`~motosim.rt.safety.safety_scale`); ``torque``: the torque sensor's last
        reading [N*m] (0 in a run that reads none, :attr:`RunSettings.torque_sensor`)."""
        ...

    def row(self) -> Array:
        """The values of :attr:`names` after the last step (read, not kept, by the loop)."""
        ...

    @property
    def compiled_parts(self) -> StackParts | None:
        """What the runner's compiled period steps itself (the stack's row then written
        where :meth:`row` reads it), or None: a stack in Python, whose :meth:`step` the
        runner calls between the compiled pieces."""
        ...


@dataclass(frozen=True, slots=True)
class RunCounters:
    """What happened on the bus and in the safety stage during a run."""

    status_frames: int
    torque_frames: int
    frames_lost: int
    frames_stale: int
    send_errors: int
    state: str
    fault: str
    fault_reason: str
    fault_time: float


@dataclass(frozen=True, slots=True)
class RunSettings:
    """What a real-time run is set to, checked once: :class:`RealtimeRunner`'s settings.

    Parameters
    ----------
    limits : SafetyLimits
        The safety stage's limits.
    rate : float
        The control rate [Hz], > 0.
    duration : float, optional
        The run's duration [s], >= 0: after its last period the torque fades out (as on a
        stop request) and :meth:`RealtimeRunner.period` returns False once it is off, in one
        run of the loop of :attr:`RealtimeRunner.max_periods`. Without it the run goes on
        until a stop request, a fault or the loop's end.
    linger : float
        How long the zero command is still sent after a fault before the run ends [s], >= 0.
    periods_per_frame : int
        Control periods per status frame of the drive (the watchdog counts frame periods),
        >= 1.
    start_timeout : float
        How long to wait for the drive's first valid status frame [s] before the
        ``NO_DRIVE`` fault, > 0.
    capacity : int
        Rows the ring holds before the oldest are lost (the reader drains it meanwhile), >= 1.
    shared_ring : bool
        Put the ring in shared memory, for a writer process (:meth:`SampleRing.attach`).
    wait_for_arm : bool
        Keep the torque off (safety stage IDLE) after the drive's first status frame until
        :meth:`RealtimeRunner.arm` is called (the view's Arm button); the loop runs and
        records meanwhile.
    warm : bool
        Warm the stack before each deadline (:meth:`RealtimeRunner.warm`, and in
        :meth:`RealtimeRunner.wait_period`); False: the wait only spins. The rows are the
        same either way.
    handlebar : HandlebarParameters, optional
        The nominal handlebar, for the safety stage's frozen-sensor monitor (off without it).
    torque_sensor : bool
        The stack reads a torque sensor (the estimator ``torque_sensor``): the drive's
        ``HB_TORQUE`` frames are taken, and their watchdog is on (the DBC must have the
        frame).
    validity : tuple of float, optional
        The virtual motorcycle's range (largest roll [rad], lowest and highest speed [m/s]:
        :func:`motosim.sim.metrics.validity_limits`), read from the stack's ``phi`` and
        ``v_x``: beyond it the torque fades out and the run ends, as offline ``simulate``
        stops there; :attr:`RealtimeRunner.left_range` says why. Without it the run goes on.

    Raises
    ------
    MotosimError
        On a value out of its range (one line naming it).
    """

    limits: SafetyLimits
    rate: float
    duration: float | None = None
    linger: float = 0.2
    periods_per_frame: int = 1
    start_timeout: float = 1.0
    capacity: int = 1 << 16
    shared_ring: bool = False
    wait_for_arm: bool = False
    warm: bool = True
    handlebar: HandlebarParameters | None = None
    torque_sensor: bool = False
    validity: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.rate) and self.rate > 0.0):
            raise MotosimError(f"rate = {self.rate!r} Hz: expected a positive rate")
        if self.duration is not None and not (
            math.isfinite(self.duration) and self.duration >= 0.0
        ):
            raise MotosimError(f"duration = {self.duration!r} s: expected a time >= 0")
        check_number(self.linger, where="linger", lower=0.0, unit="s")
        check_number(
            self.start_timeout, where="start_timeout", lower=0.0, lower_closed=False, unit="s"
        )
        for name in ("periods_per_frame", "capacity"):
            if getattr(self, name) < 1:
                raise MotosimError(f"{name} = {getattr(self, name)!r}: expected an integer >= 1")


class RealtimeRunner:
    """The control period of ``motosim run`` (see the module docstring).

    Parameters
    ----------
    stepper : StackStepper
        The stack.
    link : Link
        The CAN link to the drive (:func:`~motosim.io.can.open_link`).
    codecs : HandlebarCodecs
        The frames (from the DBC).
    settings : RunSettings
        The rate, the safety limits and the rest of the run's settings.
    telemetry : callable, optional
        ``telemetry(k, t, row)`` publishes each period's stack row (a
        :class:`~motosim.rt.telemetry.StateSender`'s ``send``), in the period: for a
        lock-step run; ``motosim run`` gives none and publishes the ring's newest row from
        its writer process (:class:`~motosim.rt.telemetry.StateRelay`).
    platform : PlatformOutput, optional
        The motion platform's stage (:mod:`motosim.rt.platform`), stepped every period after
        the safety stage with its state and envelope.
    clock : Clock, optional
        The loop's clock, needed by :meth:`wait_status` (a bus-paced loop).
    now : callable, optional
        The loop's clock (``Clock.now``) [s], read twice per period for the ``wake`` and
        ``compute`` columns; without it they are NaN.
    """

    def __init__(
        self,
        stepper: StackStepper,
        link: Link,
        codecs: HandlebarCodecs,
        settings: RunSettings,
        *,
        telemetry: Callable[[int, float, Array], None] | None = None,
        platform: "PlatformOutput | None" = None,
        clock: Clock | None = None,
        now: Callable[[], float] | None = None,
    ) -> None:
        rate = settings.rate
        if settings.torque_sensor and codecs.torque is None:
            raise MotosimError(
                "the run reads a torque sensor and the DBC has no torque frame "
                f"({codecs.mapping.torque}); expected a DBC with it"
            )
        self.stepper = stepper
        self._now = now
        self.clock = clock
        self.telemetry = telemetry
        self.platform = platform
        self.link = link
        self.codecs = codecs
        self.dt = 1.0 / rate
        self.safety = SafetyStage(
            settings.limits,
            dt=self.dt,
            periods_per_frame=settings.periods_per_frame,
            handlebar=settings.handlebar,
        )
        self.names = LOOP_SIGNALS + tuple(stepper.names)
        self.ring = SampleRing(settings.capacity, len(self.names), shared=settings.shared_ring)
        self._validity = settings.validity
        self._duration = -1 if settings.duration is None else round(settings.duration * rate)
        roll, speed_low, speed_high = settings.validity or _ANY_RANGE
        self._settings = fused.RunnerSettings(
            linger=max(1, round(settings.linger * rate)),
            start_timeout=max(1, round(settings.start_timeout * rate)),
            heartbeat_every=max(1, round(0.1 * rate)),
            dt=self.dt,
            duration=self._duration,
            **_row_positions(tuple(stepper.names)),
            roll=roll,
            speed_low=speed_low,
            speed_high=speed_high,
            armed=not settings.wait_for_arm,
            warm=settings.warm,
            sensed=settings.torque_sensor,
        )
        self._warm_on = settings.warm
        self._woke = math.nan
        self._arrays = self._allocate(stepper, link, codecs, fused.RunnerState(self._settings))
        self._r = self._arrays.runner
        self._bad_reported = 0
        self.send_errors = 0
        self._compile()

    def _allocate(
        self, stepper: StackStepper, link: Link, codecs: HandlebarCodecs, r: object
    ) -> PeriodArrays:
        """Every array of the period (:class:`~motosim.rt.fused.PeriodArrays`)."""
        st, cmd, es, hb = codecs.status, codecs.command, codecs.estop, codecs.heartbeat
        command_frame, command_at = link.frame_buffer(cmd.frame_id, cmd.length)
        heartbeat_frame, heartbeat_at = link.frame_buffer(hb.frame_id, hb.length)
        position = codecs.position
        tq = codecs.torque
        if tq is None:  # a frame no id matches, laid out as the status frame
            torque, torque_at = codec_table(st), (0, 0)
            torque[FRAME_ROW, FrameColumn.frame_id] = -1.0
        else:
            torque = codec_table(tq)
            torque_at = (position(tq, "rider_torque"), position(tq, "counter"))
        positions = fused.SignalPositions(
            position(st, "angle"),
            position(st, "current"),
            position(st, "counter"),
            position(st, "drive_fault"),
            position(es, "estop_signal"),
            position(cmd, "current_command"),
            position(cmd, "enable"),
            position(cmd, "counter"),
            position(hb, "state"),
            position(hb, "fault"),
            position(hb, "counter"),
            *torque_at,
            command_at,
            heartbeat_at,
            len(LOOP_SIGNALS),
        )
        safety, limits = self.safety.compiled_parts
        ring, head = self.ring.arrays
        if stepper.compiled_parts is not None:
            stack_row = stepper.row()  # the stack writes its row where the period reads it
        else:
            stack_row = np.zeros(len(stepper.names))
        return PeriodArrays(
            runner=r,
            positions=positions,
            safety=safety,
            limits=limits,
            status=codec_table(st),
            estop=codec_table(es),
            command=codec_table(cmd),
            heartbeat=codec_table(hb),
            torque=torque,
            status_values=np.zeros(len(st.names)),
            estop_values=np.zeros(len(es.names)),
            command_values=np.zeros(len(cmd.names)),
            heartbeat_values=np.zeros(len(hb.names)),
            torque_values=np.zeros(len((tq or st).names)),
            rx=np.zeros((fused.RX_FRAMES, fused.RX_BYTES), dtype=np.uint8),
            rx_length=np.zeros(fused.RX_FRAMES, dtype=np.int64),
            rx_id=np.zeros(fused.RX_FRAMES, dtype=np.int64),
            command_frame=command_frame,
            heartbeat_frame=heartbeat_frame,
            stack_row=stack_row,
            ring=ring,
            ring_head=head,
        )

    def _compile(self) -> None:
        """Compile (or load) every function of the period for its arrays' types, and keep
        their compiled overloads (called without numba's dispatch): before the first
        deadline, nothing is compiled inside the loop."""
        a = self._arrays
        self._take = compiled(fused.take_frames, a, 0, 0, 0.0)
        self._begin = compiled(fused.begin, a, 0, 0.0)
        self._finish = compiled(fused.finish, a, 0.0, 0.0, 0.0, 0.0)
        self._inputs = compiled(fused.stack_inputs, a)
        self._counts = compiled(fused.runner_counts, a.runner)
        self._request = compiled(fused.runner_request, a.runner, False, False)
        self._kernel: Callable[..., tuple[bool, bool, int, bool, float]] | None = None
        self._context: object = None
        self._warms = False  # whether the kernel warms (compiled, its stack compiled)
        self._shadow: tuple[object, Array, Array] | None = None  # what the warm-ups step
        stack = self.stepper.compiled_parts
        if stack is not None:
            if hasattr(fused.context_period, "compile"):  # one argument unboxed per call
                data, state, row = new_data(stack.model), stack.state.copy(), a.stack_row.copy()
                self._shadow = (data, state, row)
                shadow = stack._replace(data=data, state=state)
                self._context = fused.PeriodContext(stack, a, shadow, row)
                self._kernel = compiled(
                    fused.context_period, self._context, 0, 0, 0.0, 0.0, 0.0, -1
                )
                self._warms = True
            else:  # without numba's JIT: the plain function on the arrays
                self._context = (stack, a)
                self._kernel = lambda c, *rest: fused.fused_period(*c, *rest[:-1])
        self._cycle: Callable[..., tuple[bool, bool, int, bool, float]] | None = None
        self._fd = -1
        self._send_command = self.link.sender(self.codecs.command.frame_id, a.command_frame)
        self._send_heartbeat = self.link.sender(self.codecs.heartbeat.frame_id, a.heartbeat_frame)

    def warm(self, until: float | None = None) -> None:
        """Bring the stack's code and data into the CPU's caches for the next period: stack
        steps on a copy of its state, thrown away (a fused runner only; nothing changes),
        one after the other in one compiled call (:func:`~motosim.rt.fused.context_period`'s
        ``warm_until``) until ``until`` on ``time.monotonic``'s clock [s] (None, or a time
        already past: one warm-up).

        The loop calls it ``WARM_LEAD`` before each deadline, with the deadline
        (:meth:`~motosim.rt.loop.RateLoop.run`'s ``warm``): between two periods the
        interpreter's wait and the system calls evict the stack from the caches. The
        warm-ups are counted in :attr:`warm_ups` (none before the stack has started, for a
        stack in Python, or with the warm-ups off: :attr:`warms`).
        """
        if self.warms:
            assert self._kernel is not None
            due = 0 if until is None else max(0, int(until * 1e9))  # 0: past, one warm-up
            self._kernel(self._context, 0, 0, 0.0, 0.0, 0.0, due)

    @property
    def warm_ups(self) -> int:
        """The warm-ups run by the last :meth:`warm` or :meth:`wait_period`."""
        return int(self._counts(self._r).warm_ups)

    def compile_wait(self) -> bool:
        """Make :meth:`wait_period` available (:func:`~motosim.rt.fused.context_cycle`
        compiled, or loaded from numba's cache, now); whether it is. Only a runner whose stack
        is compiled, on a link that gives compiled code its socket
        (:meth:`~motosim.io.can.Link.compiled_fd`, on Linux), with numba's JIT on; the others
        keep :meth:`period`, which does the same in Python."""
        if self._cycle is not None:
            return True
        fd = self.link.compiled_fd() if self._warms else -1
        if fd < 0:
            return False
        self._fd = fd
        self._cycle = compiled(fused.context_cycle, self._context, self._fd, 0, 0.0)
        return True

    @property
    def warms(self) -> bool:
        """Whether :meth:`warm` (and :meth:`wait_period`) warm the stack: a compiled stack
        with its warm-ups on."""
        return self._warms and self._warm_on

    @property
    def waits_compiled(self) -> bool:
        """Whether :meth:`compile_wait` made :meth:`wait_period` available."""
        return self._cycle is not None

    @property
    def fused(self) -> bool:
        """Whether each period is one compiled call, stack included (a
        :class:`~motosim.rt.stack.CompiledStack`), or three around the stack's ``step``."""
        return self._kernel is not None

    @property
    def status_frames(self) -> int:
        """Status frames received (valid or not)."""
        return int(self._counts(self._r).status_frames)

    @property
    def first_timeout(self) -> float:
        """How long a bus-paced loop waits for the drive's first frame [s]: one period past
        ``start_timeout``, so that the ``NO_DRIVE`` fault trips on that wait's timeout."""
        return float(self._settings.start_timeout + 1) * self.dt

    @property
    def watchdog_time(self) -> float:
        """The watchdog's time [s]: ``watchdog_periods`` status frame periods."""
        return self.safety.watchdog_periods * self.dt

    # --- operator ----------------------------------------------------------------------
    def request_stop(self) -> None:
        """Fade the torque out and end the run (safe from a signal handler)."""
        self._request(self._r, True, False)
        self.safety.request_stop()

    @property
    def stop_requested(self) -> bool:
        """Whether :meth:`request_stop` was called."""
        return bool(self._counts(self._r).stop)

    def arm(self) -> None:
        """Start the torque (a fade-in through the safety stage) in the next period.

        Only a request: the loop's own thread enables the safety stage, so this is safe from
        another thread. Ignored after a stop request or a fault.
        """
        self._request(self._r, False, True)

    @property
    def left_range(self) -> str | None:
        """Why the run stopped early because the virtual motorcycle fell or its speed left the
        model's (one line, with the time), or None."""
        r = self._counts(self._r)
        if not r.left or self._validity is None:
            return None
        return range_reason(float(r.left_t), float(r.left_phi), float(r.left_speed), self._validity)

    @property
    def left_range_time(self) -> float:
        """When the motorcycle left its range [s since the first deadline] (NaN if not)."""
        r = self._counts(self._r)
        return float(r.left_t) if r.left else math.nan

    @property
    def max_periods(self) -> int:
        """The loop's periods to give a run with a ``duration``: the duration, then ten times
        the most the fade-out needs (the fade, then the slew-rate limit's way down from the
        clamp: missed deadlines do not shorten it) and the linger after a fault; the run ends
        before, once the torque is off. 0 without a ``duration``."""
        if self._duration < 0:
            return 0
        limits = self.safety.limits
        fade = math.ceil(limits.fade_in / self.dt)
        slew = math.ceil(limits.max_current / (limits.max_slew * self.dt))
        return self._duration + 10 * (fade + slew + 2) + self._settings.linger

    @property
    def reached_end(self) -> bool:
        """Whether the run reached its ``duration`` (the torque then fades out)."""
        return bool(self._counts(self._r).ended)

    def emergency_stop(self) -> None:
        """Zero the torque now and latch the keyboard E-stop (safe from a signal handler)."""
        self.safety.trip(Fault.ESTOP_KEY)

    def discard_pending(self) -> int:
        """Read and drop every frame already waiting (call just before the first period)."""
        dropped = 0
        while dropped < 100_000 and self.link.receive() is not None:
            dropped += 1
        return dropped

    # --- the period --------------------------------------------------------------------
    def _read_bus(self, start: int = 0, timeout: float = 0.0) -> int:
        """Read the frames waiting (one, waiting up to ``timeout`` [s], if ``timeout`` > 0)
        into the period's arrays from ``start``; the index after the last one."""
        a = self._arrays
        return self.link.receive_into(a.rx, a.rx_length, a.rx_id, start, timeout)

    def wait_status(self, until: float) -> bool:
        """Block on the bus until a status frame arrives or ``clock`` reaches ``until`` [s].

        The wait of a bus-paced loop (:class:`~motosim.rt.loop.FramePacedLoop`): every frame
        received meanwhile is handled as in a period (E-stop frames included); the frames
        behind the status frame are read by the next :meth:`period`. On a timeout the
        safety stage's watchdog trips (:meth:`~motosim.rt.safety.SafetyStage.silent`): the
        timeout is the watchdog's time. Needs the runner's ``clock``.
        """
        clock = self.clock
        if clock is None:
            raise MotosimError("wait_status needs the runner's clock (clock=...)")
        now = clock.now
        a = self._arrays
        while True:
            remaining = until - now()
            if remaining <= 0.0:
                started, *_ = self._inputs(a)
                if started:
                    self.safety.silent()
                return False
            if self._read_bus(0, remaining) and self._take(a, 0, 1, now()):
                return True

    def period(self, k: int, t: float) -> bool:
        """Run one control period ``k`` (deadline ``t`` [s]); False when the run should end.

        The recorded time is ``t`` minus the first period's deadline.
        """
        now = self._now
        woke = now() if now is not None else math.nan
        frames = self._read_bus()
        done_read = now() if now is not None else math.nan
        if self._kernel is not None:
            end = self._kernel(self._context, frames, k, t, woke, done_read, -1)
        else:
            end = self._stack_period(self._arrays, frames, k, t, woke, done_read)
        return self._send(end, k, t)

    def wait_period(self, k: int, t: float) -> bool:
        """:meth:`period` that waits for its deadline ``t`` [s] on the machine's monotonic
        clock itself (:class:`~motosim.rt.clock.MonotonicClock`'s): called shortly before
        it (:class:`~motosim.rt.loop.RateLoop` with ``woke=runner.woke``), it warms the
        stack, spins until ``t``, reads the bus and runs the period in one compiled call
        (:func:`~motosim.rt.fused.context_cycle`; :meth:`compile_wait` first), then sends
        the frames and stamps the row as :meth:`period` does. The rows are those of
        :meth:`period` (the time stamps aside); a socket error of the read counts in the
        link's ``errors`` (by :meth:`counters`), as there.
        """
        if self._cycle is None:
            raise MotosimError("wait_period needs compile_wait() first (and its True)")
        end = self._cycle(self._context, self._fd, k, t)
        *_, self._woke = end  # PeriodEnd.woke
        return self._send(end, k, t)

    def woke(self) -> float:
        """When the last :meth:`wait_period` woke up [s on the monotonic clock]."""
        return self._woke

    def _send(self, end: tuple[bool, bool, int, bool, float], k: int, t: float) -> bool:
        """The end of period ``k`` (deadline ``t`` [s]), given the compiled period's
        :class:`~motosim.rt.fused.PeriodEnd` (its fields): the frames sent, the telemetry,
        the row's stamps; whether the run goes on."""
        goes_on, beat, slot, started, woke = end
        now = self._now
        a = self._arrays
        done_control = now() if now is not None else math.nan
        if not self._send_command():
            self.send_errors += 1
        if beat and not self._send_heartbeat():
            self.send_errors += 1
        done_send = now() if now is not None else math.nan
        ring = a.ring
        if self.telemetry is not None or self.platform is not None:
            self._publish(k, float(ring[slot, _T]), started)
        ring[slot, _DONE_CONTROL] = done_control - woke
        ring[slot, _DONE_SEND] = done_send - woke
        ring[slot, _COMPUTE] = (now() - woke) if now is not None else math.nan
        a.ring_head[_WRITTEN] += 1
        return bool(goes_on)

    def _stack_period(
        self, a: PeriodArrays, frames: int, k: int, t: float, woke: float, done_read: float
    ) -> PeriodEnd:
        """A period around a stack in Python: the compiled steps one by one."""
        self._take(a, 0, frames, t)
        reset = self._begin(a, k, t)
        started, theta, current, fresh, scale, torque = self._inputs(a)
        if reset:
            self.stepper.reset(float(theta), float(current))
        command = 0.0
        if started:
            command = self.stepper.step(
                float(theta), float(current), bool(fresh), float(scale), float(torque)
            )
            a.stack_row[:] = self.stepper.row()
        end: PeriodEnd = self._finish(a, float(command), t, woke, done_read)
        return end

    def _publish(self, k: int, elapsed: float, started: bool) -> None:
        """The stack's row to the telemetry (after the command, which thus leaves a datagram
        sooner) and the platform's stage; ``elapsed``: the time since the first deadline
        [s]."""
        row = self._arrays.stack_row if started else None
        if row is not None and self.telemetry is not None:
            self.telemetry(k, elapsed, row)
        if self.platform is not None:
            self.platform.step(k, elapsed, row, *self.safety.brief())

    def counters(self) -> RunCounters:
        """What happened on the bus and in the safety stage so far."""
        # datagrams that were no frames, and the compiled reads' socket errors: the link's
        counts = self._counts(self._r)
        bad = int(counts.bad + counts.recv_errors)
        if bad > self._bad_reported:
            self.link.errors += bad - self._bad_reported
            self._bad_reported = bad
        s = self.safety
        return RunCounters(
            int(counts.status_frames),
            int(counts.torque_frames),
            s.frames_lost,
            s.frames_stale,
            self.send_errors,
            s.state.name,
            s.fault.name,
            s.describe(),
            s.fault_time,
        )


PROFILE_STAGES = ("read", "control", "send", "rest")


def profile_stats(rows: Array, names: tuple[str, ...]) -> dict[str, dict[str, float]]:
    """Where the compute time of the periods in ``rows`` went: p50, p99 and max [s] of each
    stage (the bus read, the stack and safety stage, the send, the rest up to the row); with
    a ``stack`` column, also the stack's own time inside the control stage (``"stack"``).

    Rows without the stamps (NaN, a loop without ``now``) are left out.

    Examples
    --------
    >>> names = ("compute", "done_read", "done_control", "done_send", "stack")
    >>> rows = np.array([[10e-6, 2e-6, 5e-6, 9e-6, 1e-6]] * 3)
    >>> {k: round(v["p50"] * 1e6, 3) for k, v in profile_stats(rows, names).items()}
    {'read': 2.0, 'control': 3.0, 'send': 4.0, 'rest': 1.0, 'stack': 1.0}
    """
    col = [names.index(n) for n in ("done_read", "done_control", "done_send", "compute")]
    stamps = rows[:, col]
    stamps = stamps[np.all(np.isfinite(stamps), axis=1)]
    spans = np.diff(stamps, axis=1, prepend=0.0)
    stages = {stage: spans[:, j] for j, stage in enumerate(PROFILE_STAGES)}
    if "stack" in names:
        stages["stack"] = rows[:, names.index("stack")]
    out = {}
    for stage, times in stages.items():
        times = times[np.isfinite(times)]
        if times.size:
            q = np.percentile(times, (50.0, 99.0))
            out[stage] = {"p50": float(q[0]), "p99": float(q[1]), "max": float(times.max())}
    return out
