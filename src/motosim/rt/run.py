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
fades the torque out and ends the run once it is zero (so does :meth:`RealtimeRunner.finish`
at the end of the run's duration); a fault zeroes the command at once and ends the run
``linger`` seconds later, the zero command still sent meanwhile.
"""

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.io.can import HandlebarCodecs, UdpMulticastLink, codec_table
from motosim.params.handlebar import HandlebarParameters
from motosim.rt import fused
from motosim.rt.clock import Clock
from motosim.rt.fused import PeriodArrays
from motosim.rt.ring import SampleRing
from motosim.rt.safety import Fault, SafetyLimits, SafetyStage, State, safety_scale
from motosim.rt.stack import CompiledStack, compiled
from motosim.sim.metrics import range_reason
from motosim.sim.stack import new_data

if TYPE_CHECKING:
    from motosim.rt.platform import PlatformOutput

__all__ = [
    "LOOP_SIGNALS",
    "FrameLink",
    "RealtimeRunner",
    "RunCounters",
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

    def step(self, theta_meas: float, i_meas: float, fresh: bool, scale: float) -> float:
        """One control period: the motor current command [A]; ``fresh``: the measurement
        came in a new status frame this period (the last valid one is given otherwise);
        ``scale``: the share of the command the safety stage will pass
        (:func:`~motosim.rt.safety.safety_scale`)."""
        ...

    def row(self) -> Array:
        """The values of :attr:`names` after the last step (read, not kept, by the loop)."""
        ...


class FrameLink(Protocol):
    """A CAN link: :class:`~motosim.io.can.CanLink` or a test double."""

    def send(self, frame_id: int, data: bytes) -> bool:
        """Send one frame; False if the bus refused it."""
        ...

    def receive(self, timeout: float = 0.0) -> tuple[int, bytes] | None:
        """The next frame ``(frame_id, data)`` or None."""
        ...


@dataclass(frozen=True, slots=True)
class RunCounters:
    """What happened on the bus and in the safety stage during a run."""

    status_frames: int
    frames_lost: int
    frames_stale: int
    send_errors: int
    state: str
    fault: str
    fault_reason: str
    fault_time: float


class RealtimeRunner:
    """The control period of ``motosim run`` (see the module docstring).

    Parameters
    ----------
    stepper : StackStepper
        The stack.
    link : FrameLink
        The CAN link to the drive.
    codecs : HandlebarCodecs
        The frames (from the DBC).
    limits : SafetyLimits
        The safety stage's limits.
    rate : float
        The control rate [Hz].
    capacity : int
        Rows the ring holds before the oldest are lost (the reader drains it meanwhile).
    linger : float
        How long the zero command is still sent after a fault before the run ends [s].
    periods_per_frame : int
        Control periods per status frame of the drive (the watchdog counts frame periods).
    start_timeout : float
        How long to wait for the drive's first valid status frame [s] before the
        ``NO_DRIVE`` fault.
    shared_ring : bool
        Put the ring in shared memory, for a writer process (:meth:`SampleRing.attach`).
    telemetry : callable, optional
        ``telemetry(k, t, row)`` publishes each period's stack row (a
        :class:`~motosim.rt.telemetry.StateSender`'s ``send``), in the period: for a
        lock-step run; ``motosim run`` gives none and publishes the ring's newest row from
        its writer process (:class:`~motosim.rt.telemetry.StateRelay`).
    wait_for_arm : bool
        Keep the torque off (safety stage IDLE) after the drive's first status frame until
        :meth:`arm` is called (the view's Arm button); the loop runs and records meanwhile.
    platform : PlatformOutput, optional
        The motion platform's stage (:mod:`motosim.rt.platform`), stepped every period after
        the safety stage with its state and envelope.
    now : callable, optional
        The loop's clock (``Clock.now``) [s], read twice per period for the ``wake`` and
        ``compute`` columns; without it they are NaN.
    clock : Clock, optional
        The loop's clock, needed by :meth:`wait_status` (a bus-paced loop).
    handlebar : HandlebarParameters, optional
        The nominal handlebar, for the safety stage's frozen-sensor monitor (off without it).
    validity : tuple of float, optional
        The virtual motorcycle's range (largest roll [rad], lowest and highest speed [m/s]:
        :func:`motosim.sim.metrics.validity_limits`), read from the stack's ``phi`` and
        ``v_x``: beyond it the torque fades out and the run ends, as offline ``simulate``
        stops there; :attr:`left_range` says why. Without it the run goes on.
    warm : bool
        Warm the stack before each deadline (:meth:`warm`, and the compiled wait of
        :meth:`wait_period`): True by default; False, the wait only spins (``motosim run
        --warm off``). The rows are the same either way.
    """

    def __init__(
        self,
        stepper: StackStepper,
        link: FrameLink,
        codecs: HandlebarCodecs,
        limits: SafetyLimits,
        *,
        rate: float,
        capacity: int = 1 << 16,
        linger: float = 0.2,
        periods_per_frame: int = 1,
        start_timeout: float = 1.0,
        shared_ring: bool = False,
        telemetry: Callable[[int, float, Array], None] | None = None,
        wait_for_arm: bool = False,
        platform: "PlatformOutput | None" = None,
        now: Callable[[], float] | None = None,
        clock: Clock | None = None,
        handlebar: HandlebarParameters | None = None,
        validity: tuple[float, float, float] | None = None,
        warm: bool = True,
    ) -> None:
        if not (math.isfinite(rate) and rate > 0.0):
            raise MotosimError(f"rate = {rate!r} Hz: expected a positive rate")
        self.stepper = stepper
        self._now = now
        self.clock = clock
        self.telemetry = telemetry
        self.platform = platform
        self.link = link
        self.codecs = codecs
        self.dt = 1.0 / rate
        self.safety = SafetyStage(
            limits, dt=self.dt, periods_per_frame=periods_per_frame, handlebar=handlebar
        )
        self.names = LOOP_SIGNALS + tuple(stepper.names)
        self.ring = SampleRing(capacity, len(self.names), shared=shared_ring)
        self._arrays = self._allocate(stepper, link, codecs, rate, linger, start_timeout)
        self._r = self._arrays.runner
        self._r[fused.R_ARMED] = 0.0 if wait_for_arm else 1.0
        self._r[fused.R_WARM] = 1.0 if warm else 0.0
        self._validity = validity
        if validity is not None:
            self._r[[fused.R_ROLL, fused.R_SPEED_LOW, fused.R_SPEED_HIGH]] = validity
        self._views = [memoryview(row) for row in self._arrays.rx]
        self._datagrams = isinstance(link, UdpMulticastLink)
        self._fused = isinstance(stepper, CompiledStack)
        self._bad_reported = 0
        self.send_errors = 0
        self._compile()

    def _allocate(
        self,
        stepper: StackStepper,
        link: FrameLink,
        codecs: HandlebarCodecs,
        rate: float,
        linger: float,
        start_timeout: float,
    ) -> PeriodArrays:
        """Every array of the period (:class:`~motosim.rt.fused.PeriodArrays`)."""
        st, cmd, es, hb = codecs.status, codecs.command, codecs.estop, codecs.heartbeat
        if isinstance(link, UdpMulticastLink):
            command_frame, command_at = link.datagram(cmd.frame_id, cmd.length)
            heartbeat_frame, heartbeat_at = link.datagram(hb.frame_id, hb.length)
        else:
            command_frame, command_at = np.zeros(cmd.length, dtype=np.uint8), 0
            heartbeat_frame, heartbeat_at = np.zeros(hb.length, dtype=np.uint8), 0
        positions = np.zeros(fused.POSITIONS_SIZE, dtype=np.int64)
        position = codecs.position
        positions[:] = (
            position(st, "angle"), position(st, "current"), position(st, "counter"),
            position(st, "drive_fault"), position(es, "estop_signal"),
            position(cmd, "current_command"), position(cmd, "enable"), position(cmd, "counter"),
            position(hb, "state"), position(hb, "fault"), position(hb, "counter"),
            command_at, heartbeat_at, len(LOOP_SIGNALS),
        )  # fmt: skip
        names = tuple(stepper.names)
        r = np.zeros(fused.RUNNER_STATE_SIZE)
        r[[fused.R_T0, fused.R_THETA, fused.R_CURRENT, fused.R_PREV_THETA]] = math.nan
        r[fused.R_STACK_TIME] = math.nan  # measured by the fused period only
        r[fused.R_K_LAST] = -1.0  # no period yet
        r[fused.R_LINGER] = max(1, round(linger * rate))
        r[fused.R_START_TIMEOUT] = max(1, round(start_timeout * rate))
        r[fused.R_HEARTBEAT_EVERY] = max(1, round(0.1 * rate))
        r[fused.R_DT] = self.dt
        r[fused.R_S_TAU] = names.index("tau_r_hat") if "tau_r_hat" in names else -1
        r[fused.R_S_RATE] = names.index("theta_h_dot_hat") if "theta_h_dot_hat" in names else -1
        r[fused.R_DATAGRAMS] = 1.0 if isinstance(link, UdpMulticastLink) else 0.0
        r[[fused.R_ROLL, fused.R_SPEED_LOW, fused.R_SPEED_HIGH]] = (math.inf, -math.inf, math.inf)
        r[fused.R_S_PHI] = names.index("phi") if "phi" in names else -1
        r[fused.R_S_SPEED] = names.index("v_x") if "v_x" in names else -1
        safety, limits = self.safety.compiled_parts
        ring, head = self.ring.arrays
        if isinstance(stepper, CompiledStack):
            stack_row = stepper.row()  # the stack writes its row where the period reads it
        else:
            stack_row = np.zeros(len(names))
        return PeriodArrays(
            runner=r, positions=positions, safety=safety, limits=limits,
            status=codec_table(st), estop=codec_table(es), command=codec_table(cmd),
            heartbeat=codec_table(hb), status_values=np.zeros(len(st.names)),
            estop_values=np.zeros(len(es.names)), command_values=np.zeros(len(cmd.names)),
            heartbeat_values=np.zeros(len(hb.names)),
            rx=np.zeros((fused.RX_FRAMES, fused.RX_BYTES), dtype=np.uint8),
            rx_length=np.zeros(fused.RX_FRAMES, dtype=np.int64),
            rx_id=np.zeros(fused.RX_FRAMES, dtype=np.int64), command_frame=command_frame,
            heartbeat_frame=heartbeat_frame, stack_row=stack_row, ring=ring, ring_head=head,
        )  # fmt: skip

    def _compile(self) -> None:
        """Compile (or load) every function of the period for its arrays' types, and keep
        their compiled overloads (called without numba's dispatch): before the first
        deadline, nothing is compiled inside the loop."""
        a = self._arrays
        self._take = compiled(fused.take_frames, a, 0, 0, 0.0)
        self._begin = compiled(fused.begin, a, 0, 0.0)
        self._finish = compiled(fused.finish, a, 0.0, 0.0, 0.0, 0.0)
        self._kernel: Callable[..., int] | None = None
        self._context: object = None
        self._warms = False  # whether the kernel warms (compiled, its stack compiled)
        self._shadow: tuple[object, Array, Array] | None = None  # what the warm-ups step
        if isinstance(self.stepper, CompiledStack):
            st = self.stepper
            stack_args = (st.model, st.data, st.force, st.side_force, st.state)
            if hasattr(fused.context_period, "compile"):  # one argument unboxed per call
                shadow = (new_data(st.model), st.state.copy(), a.stack_row.copy())
                self._shadow = shadow
                self._context = fused.PeriodContext(*stack_args, a, *shadow)
                self._kernel = compiled(
                    fused.context_period, self._context, 0, 0, 0.0, 0.0, 0.0, -1
                )
                self._warms = True
            else:  # without numba's JIT: the plain function on the arrays
                self._context = (*stack_args, a)
                self._kernel = lambda c, *rest: fused.fused_period(*c, *rest[:-1])
        self._cycle: Callable[..., int] | None = None
        self._fd = -1
        self._send_command = self._sender(a.command_frame, self.codecs.command.frame_id)
        self._send_heartbeat = self._sender(a.heartbeat_frame, self.codecs.heartbeat.frame_id)

    def warm(self, until: float | None = None) -> int:
        """Bring the stack's code and data into the CPU's caches for the next period: stack
        steps on a copy of its state, thrown away (a fused runner only; nothing changes).

        The loop calls it in the spin phase of its wait, ``WARM_LEAD`` before each deadline
        (:meth:`~motosim.rt.loop.RateLoop.run`'s ``warm``), with the deadline: between two
        periods the interpreter's wait and the system calls evict the stack from the caches,
        and its step would run several times slower than in a compiled loop.

        Parameters
        ----------
        until : float, optional
            Keep warming, one copy of the stack's step after the other in one compiled call
            (:func:`~motosim.rt.fused.context_period`'s ``warm_until``: the period's own
            machine code), until this time on the machine's
            monotonic clock [s] (:class:`~motosim.rt.clock.MonotonicClock`'s, i.e.
            ``time.monotonic``): the last warm-up then ends within about one step's time of
            it. None, or a time already past (a simulated clock's): one warm-up.

        Returns
        -------
        int
            The warm-ups run (0 before the stack has started, for a stack in Python, or with
            the warm-ups off: :attr:`warms`).
        """
        if not self.warms:
            return 0
        assert self._kernel is not None
        due = 0 if until is None else max(0, int(until * 1e9))  # 0: in the past, one warm-up
        n: int = self._kernel(self._context, 0, 0, 0.0, 0.0, 0.0, due)
        return n

    def compile_wait(self) -> bool:
        """Make :meth:`wait_period` available: the wait's end, the bus read and the period
        in one compiled call (:func:`~motosim.rt.fused.context_cycle`, compiled, or loaded
        from numba's cache, now: before the first deadline).

        Only a runner whose stack is compiled, on a
        :class:`~motosim.io.can.UdpMulticastLink` (its socket read by
        :func:`~motosim.rt.fused.receive_datagrams`), with numba's JIT on, on Linux; the
        others keep :meth:`period`, which does the same in Python.

        Returns
        -------
        bool
            Whether :meth:`wait_period` can be used.
        """
        if self._cycle is not None:
            return True
        link = self.link
        if not (self._warms and fused.RECV_AVAILABLE and isinstance(link, UdpMulticastLink)):
            return False
        self._fd = link.fileno()
        self._cycle = compiled(fused.context_cycle, self._context, self._fd, 0, 0.0)
        return True

    @property
    def warms(self) -> bool:
        """Whether :meth:`warm` (and :meth:`wait_period`) warm the stack: a compiled stack
        with its warm-ups on."""
        return self._warms and bool(self._r[fused.R_WARM])

    @property
    def waits_compiled(self) -> bool:
        """Whether :meth:`compile_wait` made :meth:`wait_period` available."""
        return self._cycle is not None

    def _sender(self, frame: NDArray[np.uint8], frame_id: int) -> Callable[[], bool]:
        """A function sending ``frame``'s bytes as they are when it is called."""
        link = self.link
        if isinstance(link, UdpMulticastLink):
            view = memoryview(frame)  # type: ignore[arg-type]
            send_datagram = link.send_datagram
            return lambda: send_datagram(view)
        send = link.send
        return lambda: send(frame_id, frame.tobytes())

    @property
    def fused(self) -> bool:
        """Whether each period is one compiled call, stack included (a
        :class:`~motosim.rt.stack.CompiledStack`), or three around the stack's ``step``."""
        return self._fused

    @property
    def status_frames(self) -> int:
        """Status frames received (valid or not)."""
        return int(self._r[fused.R_STATUS_FRAMES])

    @property
    def first_timeout(self) -> float:
        """How long a bus-paced loop waits for the drive's first frame [s]: one period past
        ``start_timeout``, so that the ``NO_DRIVE`` fault trips on that wait's timeout."""
        return float(self._r[fused.R_START_TIMEOUT] + 1) * self.dt

    @property
    def watchdog_time(self) -> float:
        """The watchdog's time [s]: ``watchdog_periods`` status frame periods."""
        return self.safety.watchdog_periods * self.dt

    # --- operator ----------------------------------------------------------------------
    def request_stop(self) -> None:
        """Fade the torque out and end the run (safe from a signal handler)."""
        self._r[fused.R_STOP] = 1.0
        self.safety.request_stop()

    def arm(self) -> None:
        """Start the torque (a fade-in through the safety stage) in the next period.

        Only a request: the loop's own thread enables the safety stage, so this is safe from
        another thread. Ignored after a stop request or a fault.
        """
        self._r[fused.R_ARM_REQUEST] = 1.0

    @property
    def left_range(self) -> str | None:
        """Why the run stopped early because the virtual motorcycle fell or its speed left the
        model's (one line, with the time), or None."""
        r = self._r
        if not r[fused.R_LEFT] or self._validity is None:
            return None
        return range_reason(
            float(r[fused.R_LEFT_T]), float(r[fused.R_LEFT_PHI]), float(r[fused.R_LEFT_SPEED]),
            self._validity,
        )  # fmt: skip

    @property
    def left_range_time(self) -> float:
        """When the motorcycle left its range [s since the first deadline] (NaN if not)."""
        r = self._r
        return float(r[fused.R_LEFT_T]) if r[fused.R_LEFT] else math.nan

    @property
    def stop_requested(self) -> bool:
        """Whether :meth:`request_stop` was called."""
        return bool(self._r[fused.R_STOP])

    def finish(self) -> int:
        """End a run that reached its duration: fade the torque out like a stop request
        (without counting as one); the most periods the fade-out needs (the fade, then the
        slew-rate limit's way down from the clamp; 0 when the torque is already off).
        :meth:`period` returns False once the torque is off, in the same run of the loop
        (its ``k`` going on; a new run of the loop, its ``k`` from 0 again, is carried on
        by the period itself)."""
        r = self._r
        if self.safety.state in (State.FADE_IN, State.RUNNING, State.STOPPING):
            r[fused.R_FINISHING] = 1.0
            self.safety.request_stop()
            limits = self.safety.limits
            fade = math.ceil(self.safety.envelope * limits.fade_in / self.dt)
            slew = math.ceil(limits.max_current / (limits.max_slew * self.dt))
            return fade + slew + 2
        return 0

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
        if self._datagrams:
            link: UdpMulticastLink = self.link  # type: ignore[assignment]
            if timeout > 0.0:
                if not link.readable(timeout):
                    return start
                one = self._views[start : start + 1]
                return start + link.receive_datagrams(one, a.rx_length[start:], 0)
            return link.receive_datagrams(self._views, a.rx_length, start)
        receive = self.link.receive
        n = start
        while n < fused.RX_FRAMES:  # bounded: a flooded bus cannot hold the loop
            frame = receive(timeout)
            if frame is None:
                break
            data = frame[1][: fused.RX_BYTES]
            a.rx_id[n] = frame[0]
            a.rx_length[n] = len(data)
            a.rx[n, : len(data)] = np.frombuffer(data, dtype=np.uint8)
            n += 1
            if timeout > 0.0:
                break
        return n

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
                if self._r[fused.R_STARTED]:
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
            goes_on: int = self._kernel(self._context, frames, k, t, woke, done_read, -1)
        else:
            goes_on = self._stack_period(self._arrays, frames, k, t, woke, done_read)
        return self._send(goes_on, k, t, woke)

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
        goes_on: int = self._cycle(self._context, self._fd, k, t)
        return self._send(goes_on, k, t, self._r[fused.R_WOKE])

    def woke(self) -> float:
        """When the last :meth:`wait_period` woke up [s on the monotonic clock]."""
        return float(self._r[fused.R_WOKE])

    def _send(self, goes_on: int, k: int, t: float, woke: float) -> bool:
        """The end of a period: the frames sent, the telemetry, the row's stamps; whether
        the run goes on (``goes_on``: the compiled period's value)."""
        now = self._now
        a = self._arrays
        r = self._r
        done_control = now() if now is not None else math.nan
        if not self._send_command():
            self.send_errors += 1
        if r[fused.R_HEARTBEAT_DUE] != 0.0 and not self._send_heartbeat():
            self.send_errors += 1
        done_send = now() if now is not None else math.nan
        if self.telemetry is not None or self.platform is not None:
            self._publish(k, t)
        slot, ring = int(r[fused.R_SLOT]), a.ring
        ring[slot, _DONE_CONTROL] = done_control - woke
        ring[slot, _DONE_SEND] = done_send - woke
        ring[slot, _COMPUTE] = (now() - woke) if now is not None else math.nan
        a.ring_head[0] += 1
        return bool(goes_on)

    def _stack_period(
        self, a: PeriodArrays, frames: int, k: int, t: float, woke: float, done_read: float
    ) -> int:
        """A period around a stack in Python: the compiled steps one by one."""
        self._take(a, 0, frames, t)
        r = self._r
        if self._begin(a, k, t):
            self.stepper.reset(float(r[fused.R_THETA]), float(r[fused.R_CURRENT]))
        command = 0.0
        if r[fused.R_STARTED]:
            command = self.stepper.step(
                float(r[fused.R_THETA]), float(r[fused.R_CURRENT]), bool(r[fused.R_FRESH]),
                float(safety_scale(a.safety, a.limits)),
            )  # fmt: skip
            a.stack_row[:] = self.stepper.row()
        goes_on: bool = self._finish(a, float(command), t, woke, done_read)
        return int(goes_on)

    def _publish(self, k: int, t: float) -> None:
        """The stack's row to the telemetry (after the command, which thus leaves a datagram
        sooner) and the platform's stage."""
        started = bool(self._r[fused.R_STARTED])
        elapsed = t - self._r[fused.R_T0]
        row = self._arrays.stack_row if started else None
        if row is not None and self.telemetry is not None:
            self.telemetry(k, elapsed, row)
        if self.platform is not None:
            self.platform.step(k, elapsed, row, *self.safety.brief())

    def counters(self) -> RunCounters:
        """What happened on the bus and in the safety stage so far."""
        # datagrams that were no frames, and the compiled reads' socket errors: the link's
        bad = int(self._r[fused.R_BAD] + self._r[fused.R_RECV_ERRORS])
        if bad > self._bad_reported and hasattr(self.link, "errors"):
            self.link.errors += bad - self._bad_reported
            self._bad_reported = bad
        s = self.safety
        return RunCounters(
            status_frames=self.status_frames,
            frames_lost=s.frames_lost,
            frames_stale=s.frames_stale,
            send_errors=self.send_errors,
            state=s.state.name,
            fault=s.fault.name,
            fault_reason=s.describe(),
            fault_time=s.fault_time,
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
