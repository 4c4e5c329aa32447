"""The control period compiled: frames decoded, stack, safety stage, command encoded, row kept.

:class:`~motosim.rt.run.RealtimeRunner` does in Python only what needs the interpreter: it
reads the waiting frames' raw bytes from the socket, makes one call of :func:`fused_period`
(compiled with numba, on arrays allocated before the first deadline) and sends the command
frame's bytes that the call wrote. The call does, in order, what each period of the runner
does (see :mod:`motosim.rt.run`): :func:`take_frames` (the frames read, decoded and checked
by the safety stage), :func:`begin` (the first deadline, the ``NO_DRIVE`` timeout, the start,
an arm request), the stack (:func:`~motosim.rt.stack.stack_reset` on the start,
:func:`~motosim.rt.stack.stack_period`) and :func:`finish` (the virtual motorcycle's range,
the safety stage, the command and heartbeat frames encoded in place, the row written into the
ring's next slot; the runner advances the ring's head once the send's time stamps are in it).

The runner holds every argument of :func:`fused_period` in one :class:`PeriodContext` (a
numba ``structref`` built before the first deadline) and calls :func:`context_period` on it:
numba unboxes one pointer per call instead of the stack's model and data records and every
array of :class:`PeriodArrays` (the cost of both in ``docs/performance.md``). On the clock,
with a link whose socket compiled code can read, :func:`context_cycle` also ends the loop's
wait and reads the socket before the period. A stack in Python (a test double) is stepped
between :func:`take_frames` and :func:`begin`, and :func:`finish`: the same compiled
functions. The runner's state is a :class:`RunnerState` (a numba ``structref``, fields by
name).
"""

import math
import sys
from enum import IntEnum
from typing import Any, NamedTuple

import numpy as np
from llvmlite import ir
from numba import njit
from numba.core import types
from numba.experimental import structref
from numba.extending import intrinsic
from numpy.typing import NDArray

from motosim.io.can import (
    FRAME_ROW,
    RECV_AVAILABLE,
    FrameColumn,
    decode_frame,
    encode_frame,
    recv_frames,
)
from motosim.rt.e2e import FieldsStruct
from motosim.rt.ring import RingCounter
from motosim.rt.safety import (
    Fault,
    SafetyParams,
    State,
    safety_enable,
    safety_estop_frame,
    safety_request_stop,
    safety_scale,
    safety_status_frame,
    safety_step,
    safety_trip,
)
from motosim.rt.stack import StackParts, stack_period, stack_reset

__all__ = [
    "RECV_AVAILABLE",
    "WARM_MARGIN_NS",
    "LoopColumn",
    "PeriodArrays",
    "PeriodContext",
    "PeriodEnd",
    "RunnerCounts",
    "RunnerSettings",
    "RunnerState",
    "SignalPositions",
    "begin",
    "context_cycle",
    "context_period",
    "context_warm",
    "context_warm_until",
    "finish",
    "fused_period",
    "monotonic_ns",
    "runner_counts",
    "runner_request",
    "stack_inputs",
    "stack_warm",
    "take_frames",
]

Array = NDArray[np.float64]
Bytes = NDArray[np.uint8]
Ints = NDArray[np.int64]


@structref.register
class RunnerStateType(FieldsStruct):
    """numba's type of :class:`RunnerState`."""


class RunnerSettings(NamedTuple):
    """What a runner is given before its first deadline (:class:`RunnerState`'s first
    fields): periods the zero command is still sent after a fault (``linger``), the
    ``NO_DRIVE`` timeout and the periods between heartbeats [periods], the period ``dt``
    [s], the run's ``duration`` [periods] (the torque fades out from there; -1: no end);
    where the stack's row holds its estimate of the rider's torque, the handlebar's rate,
    the motorcycle's roll and speed (-1: nowhere); the motorcycle's range (largest
    ``roll`` [rad], lowest and highest speed [m/s]); whether the torque starts with
    the drive's first status frame (``armed``, else on an arm request); whether the stack is
    warmed before each deadline (:func:`context_warm_until`); whether the stack reads a
    torque sensor's ``HB_TORQUE`` frames (``sensed``)."""

    linger: int
    start_timeout: int
    heartbeat_every: int
    dt: float
    duration: int
    tau_at: int
    rate_at: int
    phi_at: int
    speed_at: int
    roll: float
    speed_low: float
    speed_high: float
    armed: bool
    warm: bool
    sensed: bool


_STATE_START: dict[str, float | int | bool] = {
    "t0": math.nan,
    "theta": math.nan,
    "current": math.nan,
    "prev_theta": math.nan,
    "fresh_at": 0.0,
    "omega": 0.0,
    "torque": 0.0,
    "torque_heard": math.nan,
    "torque_counter": -1,
    "torque_frames": 0,
    "started": False,
    "fresh": False,
    "stop": False,
    "finishing": False,
    "arm_request": False,
    "after_fault": 0,
    "sent": 0,
    "calls": 0,
    "status_frames": 0,
    "bad": 0,
    "recv_errors": 0,
    "left": False,
    "left_t": math.nan,
    "left_phi": math.nan,
    "left_speed": math.nan,
    "stack_time": math.nan,
    "woke": math.nan,
    "warm_ups": 0,
    "beats": 0,
    "k_last": -1,
    "ended": False,
}
"""Each field of the runner's own state (after :class:`RunnerSettings`') at the start."""
_STATE_FIELDS = tuple(_STATE_START)


class RunnerState(structref.StructRefProxy):
    """The runner's state, shared by :class:`~motosim.rt.run.RealtimeRunner` and the compiled
    period: the fields of :class:`RunnerSettings`, then

    ``t0`` the first deadline [s]; ``theta`` [rad] and ``current`` [A] the last valid
    measurement; ``prev_theta`` [rad] and ``fresh_at`` [s] the angle and deadline of the
    last fresh status frame, ``omega`` the handlebar's rate between the last two [rad/s]
    (for a stack without a rate in its row); ``torque`` the torque sensor's last reading
    [N*m], ``torque_heard`` the deadline it came in [s] and ``torque_counter`` its alive
    counter, ``torque_frames`` the valid ones taken; flags ``started``, ``fresh`` (a fresh status
    frame this period), ``stop`` (requested), ``finishing`` (the torque fades out: the
    duration is over or the motorcycle left its range), ``arm_request``; ``after_fault``
    periods since a fault; counts of command frames ``sent``, periods run (``calls``),
    ``status_frames`` received, and of the compiled socket reads, datagrams that were no
    frames (``bad``) and reads failed otherwise than "nothing waiting" (``recv_errors``);
    whether (``left``), when
    (``left_t``, since the first deadline [s]), at which roll [rad] and speed [m/s] the
    motorcycle left its range; ``stack_time`` the stack's time this period [s] (NaN where
    it did not step); ``woke`` the wake-up of the last :func:`context_cycle` [s];
    ``warm_ups`` those of the last :func:`context_warm_until`; ``beats`` the heartbeat due
    next (its index); ``k_last`` the loop's ``k`` of the last period (-1 before the first);
    ``ended`` whether the run reached its duration. Python reads them through
    :func:`runner_counts` and writes them through :func:`runner_request`; the loop's own
    path has what it needs returned by the period (:class:`PeriodEnd`).
    """

    def __new__(cls, settings: RunnerSettings) -> "RunnerState":
        made: RunnerState = structref.StructRefProxy.__new__(  # type: ignore[no-untyped-call]
            cls, *settings, *_STATE_START.values()
        )
        return made


structref.define_proxy(  # type: ignore[no-untyped-call]
    RunnerState, RunnerStateType, [*RunnerSettings._fields, *_STATE_FIELDS]
)


class RunnerCounts(NamedTuple):
    """What Python reads of a :class:`RunnerState` (:func:`runner_counts`)."""

    stop: bool
    status_frames: int
    torque_frames: int
    bad: int
    recv_errors: int
    left: bool
    left_t: float
    left_phi: float
    left_speed: float
    warm_ups: int
    ended: bool
    stack_time: float
    woke: float


@njit(cache=True)
def runner_counts(r: Any) -> RunnerCounts:
    """The fields of the runner's state Python reads, in one compiled call."""
    return RunnerCounts(
        r.stop,
        r.status_frames,
        r.torque_frames,
        r.bad,
        r.recv_errors,
        r.left,
        r.left_t,
        r.left_phi,
        r.left_speed,
        r.warm_ups,
        r.ended,
        r.stack_time,
        r.woke,
    )


@njit(cache=True)
def runner_request(r: Any, stop: bool, arm: bool) -> None:
    """An operator's request, from any thread or a signal handler: a stop (the torque fades
    out and the run ends) and an arm (the torque fades in in the next period, the loop's
    own thread enabling the safety stage)."""
    if stop:
        r.stop = True
    if arm:
        r.arm_request = True


class SignalPositions(NamedTuple):
    """Where the loop's signals sit in the frames' values (status: angle, current, alive
    counter, drive fault; E-stop: its signal; command: current, enable, counter; heartbeat:
    state, fault, counter; torque sensor: torque, counter), where the command and heartbeat
    frames' data bytes start in the bytes to send, and the number of the loop's own columns
    in a row."""

    angle: int
    current: int
    counter: int
    drive_fault: int
    estop: int
    command_current: int
    enable: int
    command_counter: int
    state: int
    fault: int
    heartbeat_counter: int
    rider_torque: int
    torque_counter: int
    command_at: int
    heartbeat_at: int
    loop_columns: int


class PeriodEnd(NamedTuple):
    """What a period leaves to the runner (:func:`finish`): whether the run goes on, whether
    the heartbeat frame is to be sent, the ring's slot the row went to (the runner writes
    the send's time stamps there, then advances the ring's head), whether the stack has
    started, and the period's wake-up [s] (NaN without a clock)."""

    goes_on: bool
    heartbeat: bool
    slot: int
    started: bool
    woke: float


RX_FRAMES = 64
"""The most frames read in one period (a flooded bus cannot hold the loop)."""
RX_BYTES = 512
"""The largest datagram kept [bytes] (python-can's frame of 8 data bytes takes about 170)."""


WARM_MARGIN_NS = 2000
"""How long before its time :func:`context_warm_until` ends its last warm-up, at the
latest [ns]."""

_CLOCK_MONOTONIC = {"linux": 1, "darwin": 6}.get(sys.platform)
"""``CLOCK_MONOTONIC``'s id in ``<time.h>`` (None: no ``clock_gettime`` here)."""


@intrinsic
def _clock_gettime_ns(typingctx: Any) -> tuple[Any, Any]:
    """``clock_gettime(CLOCK_MONOTONIC)`` in nanoseconds, called from compiled code (-1 where
    the C library has no ``clock_gettime``)."""

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        i32, i64 = ir.IntType(32), ir.IntType(64)
        if _CLOCK_MONOTONIC is None:
            return ir.Constant(i64, -1)
        timespec = ir.LiteralStructType([i64, i64])
        out = builder.alloca(timespec)
        module = builder.module
        fn = module.globals.get("clock_gettime") or ir.Function(
            module, ir.FunctionType(i32, [i32, timespec.as_pointer()]), "clock_gettime"
        )
        builder.call(fn, [ir.Constant(i32, _CLOCK_MONOTONIC), out])
        field = [builder.gep(out, [ir.Constant(i32, 0), ir.Constant(i32, j)]) for j in (0, 1)]
        seconds, nanoseconds = builder.load(field[0]), builder.load(field[1])
        return builder.add(builder.mul(seconds, ir.Constant(i64, 1_000_000_000)), nanoseconds)

    return types.int64(), codegen


class LoopColumn(IntEnum):
    """The loop's own columns of the ring's rows, before the stack's, in order (their names
    are the rows' signal names; :data:`motosim.rt.run.LOOP_SIGNALS`)."""

    t = 0
    theta_h_meas = 1
    i_m_meas = 2
    i_cmd = 3
    i_safe = 4
    state = 5
    fault = 6
    t_clock = 7
    wake = 8
    compute = 9
    missed = 10
    done_read = 11
    done_control = 12
    done_send = 13
    stack = 14


@njit(cache=True)
def monotonic_ns() -> int:
    """The machine's monotonic clock [ns], read from compiled code (the clock of
    ``time.monotonic``: one ``clock_gettime`` call, no interpreter); -1 where the C library
    has none (Windows).

    Examples
    --------
    >>> import time
    >>> a = time.monotonic_ns(); b = monotonic_ns(); c = time.monotonic_ns()
    >>> a <= b <= c or b == -1
    True
    """
    return _clock_gettime_ns()  # type: ignore[call-arg]  # numba's typing context


class PeriodArrays(NamedTuple):
    """Everything one period reads or writes, allocated before the first deadline: the
    runner's state (a :class:`RunnerState`), the frames' layout, the safety stage's state
    and limits (:meth:`motosim.rt.safety.SafetyStage.compiled_parts`); the status, E-stop,
    command, heartbeat and torque sensor's frames' codecs (:func:`motosim.io.can.codec_table`;
    the torque frame's id -1 where the DBC has none) and values;
    the frames read this period, one per row (``RX_FRAMES`` x ``RX_BYTES``), their lengths
    [bytes] and ids (frames given as id, length and bytes); the command and heartbeat
    frames' bytes to send (:meth:`motosim.io.can.Link.frame_buffer`); the stack's row after
    its last step; the ring's rows and counters (:attr:`motosim.rt.ring.SampleRing.arrays`).
    """

    runner: Any
    positions: SignalPositions
    safety: Any
    limits: SafetyParams
    status: Array
    estop: Array
    command: Array
    heartbeat: Array
    torque: Array
    status_values: Array
    estop_values: Array
    command_values: Array
    heartbeat_values: Array
    torque_values: Array
    rx: Bytes
    rx_length: Ints
    rx_id: Ints
    command_frame: Bytes
    heartbeat_frame: Bytes
    stack_row: Array
    ring: Array
    ring_head: Ints


@njit(cache=True)
def take_frames(a: PeriodArrays, first: int, end: int, t: float) -> int:
    """Handle the frames ``first`` .. ``end - 1`` of ``a.rx``, read by the period whose
    deadline (or, paced by the bus, the wait's time) is ``t`` [s]; the number of status
    frames.

    A status frame is decoded and checked by the safety stage (checksum, alive counter, the
    drive's fault flag); if valid and fresh, its angle and current are kept. An E-stop frame
    pressed, or unreadable, trips the emergency stop. A torque sensor's frame, read when the
    stack reads the sensor, is :func:`_torque_frame`. Other frames are ignored.
    """
    r, q, s = a.runner, a.positions, a.safety
    status_id = int(a.status[FRAME_ROW, FrameColumn.frame_id])
    estop_id = int(a.estop[FRAME_ROW, FrameColumn.frame_id])
    torque_id = int(a.torque[FRAME_ROW, FrameColumn.frame_id])
    count = 0
    for j in range(first, end):
        frame_id, length = a.rx_id[j], a.rx_length[j]
        if frame_id == status_id:
            r.status_frames += 1
            values = a.status_values
            ok = decode_frame(a.status, a.rx[j], 0, length, values)
            fault = values[q.drive_fault] > 0.5
            # the safety stage's time: the loop's since the first deadline (NaN before it)
            if safety_status_frame(s, a.limits, ok, values[q.counter], fault, t - r.t0):
                r.theta = values[q.angle]
                r.current = values[q.current]
                r.fresh = True
            count += 1
        elif frame_id == estop_id:
            values = a.estop_values
            ok = decode_frame(a.estop, a.rx[j], 0, length, values)
            safety_estop_frame(s, ok, values[q.estop] > 0.5)
        elif frame_id == torque_id and r.sensed:
            values = a.torque_values
            ok = decode_frame(a.torque, a.rx[j], 0, length, values)
            _torque_frame(a, ok, values[q.rider_torque], int(values[q.torque_counter]), t)
    return count


@njit(cache=True)
def _torque_frame(a: PeriodArrays, ok: bool, torque: float, counter: int, t: float) -> None:
    """A torque sensor's frame at ``t`` [s]: a wrong checksum trips ``CHECKSUM``; a valid
    frame whose alive counter moved gives the rider's torque [N*m] from this period on; the
    same counter again (a sensor's transmitter repeating itself) is not taken."""
    r = a.runner
    if not ok:
        safety_trip(a.safety, Fault.CHECKSUM)
        return
    if counter == r.torque_counter:
        return
    r.torque_counter = counter
    r.torque = torque
    r.torque_heard = t
    r.torque_frames += 1


@njit(cache=True)
def _watch_torque(a: PeriodArrays, t: float) -> None:
    """The torque sensor's watchdog at the deadline ``t`` [s] of a started run: as many
    periods without a torque taken as the status frames' watchdog waits trip
    ``TORQUE_SENSOR`` (counted from the start if none came before it)."""
    r, p = a.runner, a.limits
    if r.torque_heard != r.torque_heard:
        r.torque_heard = t
    if math.floor((t - r.torque_heard) / p.dt + 0.5) >= p.watchdog:
        safety_trip(a.safety, Fault.TORQUE_SENSOR)


@njit(cache=True)
def begin(a: PeriodArrays, k: int, t: float) -> bool:
    """After the frames of period ``k`` (deadline ``t`` [s]): True if the stack must be
    reset now (the first valid status frame came), at the runner's ``theta`` and
    ``current``."""
    r, s = a.runner, a.safety
    if r.t0 != r.t0:
        r.t0 = t
    r.k_last = k
    fresh = r.fresh  # cleared by finish: the stack reads it in between
    started = r.started
    if not started and k >= r.start_timeout:
        safety_trip(s, Fault.NO_DRIVE)
    reset = False
    if fresh and not started:
        r.started = True
        started = True
        reset = True
        r.prev_theta = r.theta
        r.fresh_at = t
        r.omega = 0.0
        if not r.stop and r.armed:
            safety_enable(s)
    if r.arm_request and started:
        r.arm_request = False
        if not r.armed and not r.stop:
            r.armed = True
            safety_enable(s)
    if r.sensed and started:
        _watch_torque(a, t)
    return reset


@njit(cache=True)
def stack_inputs(a: PeriodArrays) -> tuple[bool, float, float, bool, float, float]:
    """What a stack in Python is stepped with after :func:`begin`, in one compiled call:
    whether it has started, the last valid angle [rad] and current [A], whether they came
    fresh this period, the share of the command the safety stage will pass and the torque
    sensor's last reading [N*m]."""
    r = a.runner
    scale = safety_scale(a.safety, a.limits)
    return r.started, r.theta, r.current, r.fresh, scale, r.torque


@njit(cache=True)
def _handlebar_rate(a: PeriodArrays, t: float, fresh: bool) -> float:
    """The handlebar's rate [rad/s] for the safety stage: the stack's own, or for a stack
    without one, the angle's change between the last two fresh frames over their interval
    on the loop's time (with frames slower than the loop, not one period's, which reads a
    rate ten times too high; the deadlines a late loop skipped count)."""
    r = a.runner
    if not r.started:
        return 0.0
    if r.rate_at >= 0:
        return float(a.stack_row[r.rate_at])
    if fresh and t > r.fresh_at:
        r.omega = (r.theta - r.prev_theta) / (t - r.fresh_at)
        r.prev_theta = r.theta
        r.fresh_at = t
    return float(r.omega)


@njit(cache=True)
def _check_range(a: PeriodArrays, t: float) -> None:
    """The virtual motorcycle's range: past its roll or speeds (a fall, a speed outside the
    model's) the run ends as offline, the torque faded out as at the end of the duration."""
    r = a.runner
    if not r.started or r.phi_at < 0 or r.speed_at < 0 or r.left:
        return
    phi, speed = a.stack_row[r.phi_at], a.stack_row[r.speed_at]
    if abs(phi) > r.roll or speed < r.speed_low or speed > r.speed_high:
        r.left = True
        r.left_t = t - r.t0
        r.left_phi = phi
        r.left_speed = speed
        r.finishing = True
        safety_request_stop(a.safety)


@njit(cache=True)
def _encode(a: PeriodArrays, out: float, t: float) -> bool:
    """The command frame of the current ``out`` [A] and, in the first period served of
    every ``heartbeat_every``, the heartbeat frame, encoded in place in the bytes to send;
    whether the heartbeat is due.

    The heartbeat's period index is taken on the loop's time since the first deadline
    (``n % every == 0`` would miss the heartbeat whose period's first deadline was
    skipped)."""
    r, q, s = a.runner, a.positions, a.safety
    state = s.state
    values = a.command_values
    values[q.command_current] = out
    live = state == State.FADE_IN or state == State.RUNNING or state == State.STOPPING
    values[q.enable] = 1.0 if live else 0.0
    values[q.command_counter] = r.sent & 0xF
    r.sent += 1
    encode_frame(a.command, values, a.command_frame, q.command_at)
    n = math.floor((t - r.t0) / r.dt + 0.5)  # the period's index on the loop's time
    every = r.heartbeat_every
    beat = n // every >= r.beats
    if beat:
        r.beats = n // every + 1
        values = a.heartbeat_values
        values[q.state] = state
        values[q.fault] = s.fault
        values[q.heartbeat_counter] = (n // every) & 0xF
        encode_frame(a.heartbeat, values, a.heartbeat_frame, q.heartbeat_at)
    return bool(beat)


@njit(cache=True)
def _write_row(
    a: PeriodArrays, command: float, out: float, t: float, woke: float, done_read: float
) -> int:
    """The period's row into the ring's next slot, its index returned: the loop's columns
    (:class:`LoopColumn`; ``compute``, ``done_control`` and ``done_send`` NaN, stamped by
    the runner after the send), then the stack's row (its initial one before it starts).

    The deadlines skipped before this one are the loop's own count (its ``k`` less the
    periods run)."""
    r, s = a.runner, a.safety
    slot = int(a.ring_head[RingCounter.written] % a.ring.shape[0])
    row = a.ring[slot]
    row[LoopColumn.t] = t - r.t0
    row[LoopColumn.theta_h_meas] = r.theta
    row[LoopColumn.i_m_meas] = r.current
    row[LoopColumn.i_cmd] = command
    row[LoopColumn.i_safe] = out
    row[LoopColumn.state] = s.state
    row[LoopColumn.fault] = s.fault
    row[LoopColumn.t_clock] = t
    row[LoopColumn.wake] = woke - t
    row[LoopColumn.compute] = math.nan
    row[LoopColumn.missed] = r.k_last - r.calls
    row[LoopColumn.done_read] = done_read - woke
    row[LoopColumn.done_control] = math.nan
    row[LoopColumn.done_send] = math.nan
    row[LoopColumn.stack] = r.stack_time
    n_loop = a.positions.loop_columns
    for j in range(a.stack_row.size):
        row[n_loop + j] = a.stack_row[j]
    return slot


@njit(cache=True)
def _goes_on(a: PeriodArrays) -> bool:
    """Whether the run goes on after this period: at its duration's last period the torque
    fades out (a stop request, not counted as the operator's); the run ends once the stage
    is IDLE after a stop request or the fade-out, or ``linger`` periods after a fault."""
    r, s = a.runner, a.safety
    if r.duration >= 0 and r.k_last + 1 >= r.duration and not r.ended:
        r.ended = True
        r.finishing = True
        safety_request_stop(s)
    if s.state == State.FAULT:
        r.after_fault += 1
        return bool(r.after_fault < r.linger)
    return not ((r.stop or r.finishing) and s.state == State.IDLE)


@njit(cache=True)
def finish(a: PeriodArrays, command: float, t: float, woke: float, done_read: float) -> PeriodEnd:
    """The safety stage on the stack's ``command`` [A], the frames to send, the row.

    The stack's estimate of the rider's torque (its row's ``tau_r_hat``) NaN trips
    ``NON_FINITE`` as an inf does (the stage takes NaN for "no estimate": a stack without
    one). ``t`` is the period's deadline [s]; ``woke`` and ``done_read`` are the period's
    wake-up and the end of the bus read on the loop's clock [s] (NaN without one).
    """
    r, s = a.runner, a.safety
    fresh = r.fresh
    r.fresh = False
    started = r.started
    omega = _handlebar_rate(a, t, fresh)
    tau_at = r.tau_at
    tau_hat = a.stack_row[tau_at] if started and tau_at >= 0 else math.nan
    if started and tau_at >= 0 and tau_hat != tau_hat:  # NaN: no estimate only without one
        safety_trip(s, Fault.NON_FINITE)
    _check_range(a, t)
    theta = r.theta if started else 0.0
    out = safety_step(s, a.limits, command, theta, omega, tau_hat, t - r.t0)
    beat = _encode(a, out, t)
    slot = _write_row(a, command, out, t, woke, done_read)
    r.calls += 1
    return PeriodEnd(_goes_on(a), beat, slot, started, woke)


@njit(cache=True)
def _plain(end: PeriodEnd) -> tuple[bool, bool, int, bool, float]:
    """``end``'s fields as a plain tuple: what a compiled call returns to Python (a tuple
    is boxed without calling its class)."""
    return end.goes_on, end.heartbeat, end.slot, end.started, end.woke


@njit(cache=True)
def fused_period(
    stack: StackParts,
    a: PeriodArrays,
    frames: int,
    k: int,
    t: float,
    woke: float,
    done_read: float,
) -> tuple[bool, bool, int, bool, float]:
    """One whole period of a runner whose stack is compiled: :func:`take_frames` of the
    ``frames`` read, :func:`begin`, the stack (:func:`~motosim.rt.stack.stack_reset`,
    :func:`~motosim.rt.stack.stack_period` of ``stack``, a
    :class:`~motosim.rt.stack.CompiledStack`'s parts), :func:`finish`; its
    :class:`PeriodEnd`'s fields."""
    r = a.runner
    take_frames(a, 0, frames, t)
    if begin(a, k, t):
        stack_reset(stack, r.theta, r.current)
    command = 0.0
    r.stack_time = math.nan
    if r.started:
        start = monotonic_ns()
        scale = safety_scale(a.safety, a.limits)
        command = stack_period(stack, a.stack_row, r.theta, r.current, r.fresh, scale, r.torque)
        if start >= 0:
            r.stack_time = (monotonic_ns() - start) * 1e-9
    return _plain(finish(a, command, t, woke, done_read))


@njit(cache=True)
def stack_warm(
    stack: StackParts,
    shadow: StackParts,
    shadow_row: Array,
    theta: float,
    current: float,
    fresh: bool,
    scale: float,
    torque: float,
) -> None:
    """One stack period on ``shadow``, a copy of ``stack``'s data and state made now, whose
    result is thrown away: the stack's code and data are then in the CPU's caches. ``fresh``,
    ``scale`` and ``torque`` are the period's (constants would compile another copy of the
    step)."""
    data, copy = stack.data, shadow.data
    copy.estimator[:] = data.estimator
    copy.differentiator[:] = data.differentiator
    copy.controller[:] = data.controller
    copy.motorcycle[:] = data.motorcycle
    copy.multibody[:] = data.multibody
    copy.inputs[:] = data.inputs
    copy.held[:] = data.held
    copy.periods[:] = data.periods
    shadow.state[:] = stack.state
    stack_period(shadow, shadow_row, theta, current, fresh, scale, torque)


@structref.register
class PeriodContextType(FieldsStruct):
    """numba's type of :class:`PeriodContext` (one per set of field types)."""


class PeriodContext(structref.StructRefProxy):
    """Every argument of :func:`fused_period` but the period's own, in one numba object.

    Passing it to a compiled function unboxes one pointer; the fields are the very objects
    given (the arrays are shared, not copied: what Python writes into them, the period reads).

    Parameters
    ----------
    stack : StackParts
        The stack's (:attr:`~motosim.rt.stack.CompiledStack.compiled_parts`).
    arrays : PeriodArrays
        The period's arrays.
    shadow, shadow_row
        Parts of the same model with their own data and state, and a row: where
        :func:`context_warm` steps a copy of the stack (:func:`stack_warm`).
    """

    def __new__(
        cls, stack: StackParts, arrays: PeriodArrays, shadow: StackParts, shadow_row: Array
    ) -> "PeriodContext":
        made: PeriodContext = structref.StructRefProxy.__new__(  # type: ignore[no-untyped-call]
            cls, stack, arrays, shadow, shadow_row
        )
        return made


structref.define_proxy(  # type: ignore[no-untyped-call]
    PeriodContext, PeriodContextType, ["stack", "arrays", "shadow", "shadow_row"]
)


@njit(cache=True)
def context_warm(c: Any) -> None:
    """:func:`stack_warm` at the last valid measurement, once the stack has started."""
    r = c.arrays.runner
    if r.started:
        scale = safety_scale(c.arrays.safety, c.arrays.limits)
        stack_warm(c.stack, c.shadow, c.shadow_row, r.theta, r.current, r.fresh, scale, r.torque)


@njit(cache=True)
def context_warm_until(c: Any, due_ns: int) -> int:
    """:func:`context_warm` again and again until ``due_ns`` on :func:`monotonic_ns`'s clock
    [ns]; the number of warm-ups run (0 before the stack has started), also kept in the
    runner's ``warm_ups``.

    The spin phase of the loop's wait: one warm-up always, then another as long as it should
    end ``WARM_MARGIN_NS`` before ``due_ns`` (the last one's time taken as the next's), so
    that the return to the interpreter fits before the deadline. A time already past (or no
    clock: :func:`monotonic_ns` -1) gives one warm-up.
    """
    r = c.arrays.runner
    n = 0
    if r.started and r.warm:
        start = monotonic_ns()
        while True:
            context_warm(c)
            n += 1
            end = monotonic_ns()
            if start < 0 or end + (end - start) + WARM_MARGIN_NS >= due_ns:
                break
            start = end
    r.warm_ups = n
    return n


@njit(cache=True)
def context_period(
    c: Any, frames: int, k: int, t: float, woke: float, done_read: float, warm_until: int
) -> tuple[bool, bool, int, bool, float]:
    """:func:`fused_period` with the arguments held by ``c``, a :class:`PeriodContext`; or,
    with ``warm_until`` >= 0, no period but the stack's warm-ups until then
    (:func:`context_warm_until`, ``warm_until`` [ns] on :func:`monotonic_ns`'s clock; their
    number in the runner's ``warm_ups``; a :class:`PeriodEnd` that does not go on).

    Both in one function because numba compiles into each function called from Python its own
    copy of every compiled function it calls: through this one, the warm-ups and the period
    run the same copy of the step's machine code.
    """
    if warm_until >= 0:
        context_warm_until(c, warm_until)
        return _plain(PeriodEnd(False, False, -1, c.arrays.runner.started, math.nan))
    return fused_period(c.stack, c.arrays, frames, k, t, woke, done_read)


@njit(cache=True)
def context_cycle(c: Any, fd: int, k: int, t: float) -> tuple[bool, bool, int, bool, float]:
    """The wait's end, the bus read and the period, in one compiled call: :func:`fused_period`
    of the frames waiting on socket ``fd`` at the deadline ``t`` [s] of period ``k`` (on
    the clock of :func:`monotonic_ns`, ``time.monotonic``'s), returning its value.

    In order, without returning to the interpreter: the stack's warm-ups
    (:func:`context_warm_until`), a spin on the clock until ``t`` has passed (the test of
    :meth:`motosim.rt.clock.MonotonicClock.sleep_until`), the wake-up (the
    :class:`PeriodEnd`'s ``woke`` [s]), the frames read, the period. The caller sleeps
    until shortly before ``t`` and sends the frames after.
    """
    context_warm_until(c, max(0, int(t * 1e9)))
    woke = monotonic_ns() / 1e9
    while woke < t:
        woke = monotonic_ns() / 1e9
    c.arrays.runner.woke = woke
    a = c.arrays
    frames, errors, bad = recv_frames(fd, a.rx, a.rx_length, a.rx_id)
    a.runner.recv_errors += errors
    a.runner.bad += bad
    done_read = monotonic_ns() / 1e9
    return fused_period(c.stack, c.arrays, frames, k, t, woke, done_read)
