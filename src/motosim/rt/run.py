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
from motosim.io.can import HandlebarCodecs
from motosim.params.handlebar import HandlebarParameters
from motosim.rt.clock import Clock
from motosim.rt.ring import SampleRing
from motosim.rt.safety import Fault, SafetyLimits, SafetyStage, State

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

LOOP_SIGNALS = (
    "t", "theta_h_meas", "i_m_meas", "i_cmd", "i_safe", "state", "fault",
    "t_clock", "wake", "compute", "missed", "done_read", "done_control", "done_send",
)  # fmt: skip
"""The loop's own columns, before the stack's: time [s], the measured angle [rad] and current
[A] used this period, the stack's command and the one sent [A], the safety state and fault
codes (:class:`~motosim.rt.safety.State`, :class:`~motosim.rt.safety.Fault`); the period's
deadline on the loop's clock [s], its wake-up latency and compute time until the row is
written [s] (NaN without ``now``), and the deadlines missed before it; then where the compute
time went: the times [s] after the wake-up at which the bus was read, the stack and the
safety stage had run and the command frame was sent (NaN without ``now``;
:func:`profile_stats` summarises them; the rest, up to ``compute``, is the telemetry
datagram, the platform's stage and the row)."""


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

    def step(self, theta_meas: float, i_meas: float) -> float:
        """One control period: the motor current command [A]."""
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
        :class:`~motosim.rt.telemetry.StateSender`'s ``send``).
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
    ) -> None:
        if not (math.isfinite(rate) and rate > 0.0):
            raise MotosimError(f"rate = {rate!r} Hz: expected a positive rate")
        self.stepper = stepper
        self._now = now
        self._calls = 0
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
        self._row = np.zeros(len(self.names))
        self._n_loop = len(LOOP_SIGNALS)
        st, cmd, es, hb = codecs.status, codecs.command, codecs.estop, codecs.heartbeat
        self._status = np.zeros(len(st.names))
        self._estop = np.zeros(len(es.names))
        self._command = np.zeros(len(cmd.names))
        self._heartbeat = np.zeros(len(hb.names))
        self._ids = (st.frame_id, es.frame_id)
        self._i_angle = codecs.position(st, "angle")
        self._i_current = codecs.position(st, "current")
        self._i_counter = codecs.position(st, "counter")
        self._i_drive_fault = codecs.position(st, "drive_fault")
        self._i_estop = codecs.position(es, "estop_signal")
        self._c_current = codecs.position(cmd, "current_command")
        self._c_enable = codecs.position(cmd, "enable")
        self._c_counter = codecs.position(cmd, "counter")
        self._h_state = codecs.position(hb, "state")
        self._h_fault = codecs.position(hb, "fault")
        self._h_counter = codecs.position(hb, "counter")
        names = tuple(stepper.names)
        self._s_tau = names.index("tau_r_hat") if "tau_r_hat" in names else -1
        self._s_rate = names.index("theta_h_dot_hat") if "theta_h_dot_hat" in names else -1
        self._heartbeat_every = max(1, round(0.1 * rate))
        self._linger = max(1, round(linger * rate))
        self._start_timeout = max(1, round(start_timeout * rate))
        self._t0 = math.nan
        self._theta = math.nan
        self._current = math.nan
        self._prev_theta = math.nan
        self._started = False
        self._fresh = False
        self._stop = False
        self._finishing = False
        self._armed = not wait_for_arm
        self._arm_request = False
        self._after_fault = 0
        self._sent = 0
        self.status_frames = 0
        self.send_errors = 0

    @property
    def first_timeout(self) -> float:
        """How long a bus-paced loop waits for the drive's first frame [s]: one period past
        ``start_timeout``, so that the ``NO_DRIVE`` fault trips on that wait's timeout."""
        return (self._start_timeout + 1) * self.dt

    @property
    def watchdog_time(self) -> float:
        """The watchdog's time [s]: ``watchdog_periods`` status frame periods."""
        return self.safety.watchdog_periods * self.dt

    # --- operator ----------------------------------------------------------------------
    def request_stop(self) -> None:
        """Fade the torque out and end the run (safe from a signal handler)."""
        self._stop = True
        self.safety.request_stop()

    def arm(self) -> None:
        """Start the torque (a fade-in through the safety stage) in the next period.

        Only a request: the loop's own thread enables the safety stage, so this is safe from
        another thread. Ignored after a stop request or a fault.
        """
        self._arm_request = True

    @property
    def stop_requested(self) -> bool:
        """Whether :meth:`request_stop` was called."""
        return self._stop

    def finish(self) -> int:
        """End a run that reached its duration: fade the torque out like a stop request
        (without counting as one); the number of periods the fade-out needs (0 when the
        torque is already off); :meth:`period` returns False once the torque is off."""
        if self.safety.state in (State.FADE_IN, State.RUNNING, State.STOPPING):
            self._finishing = True
            self.safety.request_stop()
            return math.ceil(self.safety.envelope * self.safety.limits.fade_in / self.dt) + 2
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
    def _frame(self, frame_id: int, data: bytes) -> bool:
        """Handle one received frame; True if it is a status frame (valid or not)."""
        status_id, estop_id = self._ids
        if frame_id == status_id:
            self.status_frames += 1
            values = self._status
            ok = self.codecs.status.decode(data, values)
            if self.safety.status_frame(
                checksum_ok=ok,
                counter=values[self._i_counter],
                drive_fault=values[self._i_drive_fault] > 0.5,
            ):
                self._theta = float(values[self._i_angle])
                self._current = float(values[self._i_current])
                self._fresh = True
            return True
        if frame_id == estop_id:
            ok = self.codecs.estop.decode(data, self._estop)
            self.safety.estop_frame(checksum_ok=ok, pressed=self._estop[self._i_estop] > 0.5)
        return False

    def _read_bus(self) -> bool:
        receive = self.link.receive
        for _ in range(64):  # bounded: a flooded bus cannot hold the loop
            frame = receive()
            if frame is None:
                break
            self._frame(frame[0], frame[1])
        fresh = self._fresh
        self._fresh = False
        return fresh

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
        receive = self.link.receive
        now = clock.now
        while True:
            remaining = until - now()
            if remaining <= 0.0:
                if self._started:
                    self.safety.silent()
                return False
            frame = receive(remaining)
            if frame is not None and self._frame(frame[0], frame[1]):
                return True

    def period(self, k: int, t: float) -> bool:
        """Run one control period ``k`` (deadline ``t`` [s]); False when the run should end.

        The recorded time is ``t`` minus the first period's deadline.
        """
        woke = self._now() if self._now is not None else math.nan
        safety = self.safety
        if self._t0 != self._t0:
            self._t0 = t
        fresh = self._read_bus()
        done_read = self._now() if self._now is not None else math.nan
        if not self._started and k >= self._start_timeout:
            safety.trip(Fault.NO_DRIVE)
        if fresh and not self._started:
            self._started = True
            self.stepper.reset(self._theta, self._current)
            self._prev_theta = self._theta
            if not self._stop and self._armed:
                safety.enable()
        if self._arm_request and self._started:
            self._arm_request = False
            if not self._armed and not self._stop:
                self._armed = True
                safety.enable()
        command = 0.0
        stack_row = None
        if self._started:
            command = self.stepper.step(self._theta, self._current)
            stack_row = self.stepper.row()
        if stack_row is not None and self._s_rate >= 0:
            omega = stack_row[self._s_rate]
        else:
            omega = (self._theta - self._prev_theta) / self.dt if self._started else 0.0
        self._prev_theta = self._theta
        tau_hat = stack_row[self._s_tau] if stack_row is not None and self._s_tau >= 0 else math.nan
        theta = self._theta if self._started else 0.0
        out = safety.step(command, theta=theta, omega=omega, tau_hat=tau_hat, now=t - self._t0)
        state = safety.state
        done_control = self._now() if self._now is not None else math.nan
        self._send(out, state, k)
        done_send = self._now() if self._now is not None else math.nan
        if stack_row is not None and self.telemetry is not None:  # after the command, which
            self.telemetry(k, t - self._t0, stack_row)  # thus leaves a datagram sooner
        if self.platform is not None:
            self.platform.step(k, t - self._t0, stack_row, state, safety.fault, safety.envelope)
        row = self._row
        row[0] = t - self._t0
        row[1] = self._theta
        row[2] = self._current
        row[3] = command
        row[4] = out
        row[5] = state
        row[6] = safety.fault
        row[7] = t
        row[8] = woke - t
        row[10] = k - self._calls  # deadlines skipped before this one
        row[11] = done_read - woke
        row[12] = done_control - woke
        row[13] = done_send - woke
        self._calls += 1
        if stack_row is not None:
            row[self._n_loop :] = stack_row
        row[9] = (self._now() - woke) if self._now is not None else math.nan
        self.ring.push(row)
        if state == State.FAULT:
            self._after_fault += 1
            return self._after_fault < self._linger
        return not ((self._stop or self._finishing) and state == State.IDLE)

    def _send(self, current: float, state: State, k: int) -> None:
        cmd = self._command
        cmd[self._c_current] = current
        live = state in (State.FADE_IN, State.RUNNING, State.STOPPING)
        cmd[self._c_enable] = 1.0 if live else 0.0
        cmd[self._c_counter] = self._sent & 0xF
        self._sent += 1
        codecs = self.codecs
        if not self.link.send(codecs.command.frame_id, codecs.command.encode(cmd)):
            self.send_errors += 1
        if k % self._heartbeat_every == 0:
            hb = self._heartbeat
            hb[self._h_state] = state
            hb[self._h_fault] = self.safety.fault
            hb[self._h_counter] = (k // self._heartbeat_every) & 0xF
            if not self.link.send(codecs.heartbeat.frame_id, codecs.heartbeat.encode(hb)):
                self.send_errors += 1

    def counters(self) -> RunCounters:
        """What happened on the bus and in the safety stage so far."""
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
    stage (the bus read, the stack and safety stage, the send, the rest up to the row).

    Rows without the stamps (NaN, a loop without ``now``) are left out.

    Examples
    --------
    >>> names = ("compute", "done_read", "done_control", "done_send")
    >>> rows = np.array([[10e-6, 2e-6, 5e-6, 9e-6]] * 3)
    >>> {k: round(v["p50"] * 1e6, 3) for k, v in profile_stats(rows, names).items()}
    {'read': 2.0, 'control': 3.0, 'send': 4.0, 'rest': 1.0}
    """
    col = [names.index(n) for n in ("done_read", "done_control", "done_send", "compute")]
    stamps = rows[:, col]
    stamps = stamps[np.all(np.isfinite(stamps), axis=1)]
    if stamps.shape[0] == 0:
        return {}
    spans = np.diff(stamps, axis=1, prepend=0.0)
    q = np.percentile(spans, (50.0, 99.0), axis=0)
    top = spans.max(axis=0)
    return {
        stage: {"p50": float(q[0, j]), "p99": float(q[1, j]), "max": float(top[j])}
        for j, stage in enumerate(PROFILE_STAGES)
    }
