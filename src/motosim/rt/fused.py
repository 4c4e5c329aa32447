"""The control period compiled: frames decoded, stack, safety stage, command encoded, row kept.

:class:`~motosim.rt.run.RealtimeRunner` does in Python only what needs the interpreter: it
reads the waiting frames' raw bytes from the socket, makes one call of :func:`fused_period`
(compiled with numba, on arrays allocated before the first deadline) and sends the command
frame's bytes that the call wrote. The call does, in order, what each period of the runner
does (see :mod:`motosim.rt.run`):

1. :func:`take_frames`: each frame read (a python-can ``udp_multicast`` datagram read by
   :func:`~motosim.io.can.unpack_frame`, or a frame's id, length and bytes), the status frames
   decoded (:func:`~motosim.io.can.decode_frame`) and checked by the safety stage, the E-stop
   frames too;
2. :func:`begin`: the first period's time, the ``NO_DRIVE`` timeout, the start on the first
   valid status frame, an arm request;
3. the stack (:func:`~motosim.rt.stack.stack_reset` on the start,
   :func:`~motosim.rt.stack.stack_period`);
4. :func:`finish`: the virtual motorcycle's range (a fall, a speed outside the model's: the
   torque fades out and the run ends, as offline), the safety stage
   (:func:`~motosim.rt.safety.safety_step`), the command frame and, in the first period
   served of every ``heartbeat_every``, the heartbeat frame encoded
   (:func:`~motosim.io.can.encode_frame`) in place in the bytes to send; the row written into
   the ring's next slot (its head is advanced by the runner once the time stamps of the
   send are in the row).

The runner holds every argument of :func:`fused_period` in one :class:`PeriodContext` (a
numba ``structref`` built before the first deadline) and calls :func:`context_period` on it:
numba unboxes one pointer per call instead of the stack's model and data records and every
array of :class:`PeriodArrays` (about 20 arrays; the cost of both in ``docs/performance.md``).

On the clock with the fast ``udp_multicast`` link (Linux), the runner's
:meth:`~motosim.rt.run.RealtimeRunner.wait_period` calls :func:`context_cycle` instead,
which also ends the loop's wait and reads the socket (:func:`receive_datagrams`: the C
library's ``recv`` called from compiled code) before the period: no interpreter between the
stack's last warm-up and its step.

A runner whose stack is not a :class:`~motosim.rt.stack.CompiledStack` (a test double in
Python) calls :func:`take_frames`, :func:`begin` and :func:`finish` one by one around its
stack's ``step``: the same compiled functions, so both ways behave the same.

All the runner's state is in the arrays of :class:`PeriodArrays`; ``R_*`` are the positions
in its ``runner`` array, ``Q_*`` those in ``positions``.
"""

import errno
import math
import socket
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

from motosim.io.can import decode_frame, encode_frame, unpack_frame
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
from motosim.rt.stack import stack_period, stack_reset

__all__ = [
    "RECV_AVAILABLE",
    "RUNNER_STATE_SIZE",
    "WARM_MARGIN_NS",
    "LoopColumn",
    "PeriodArrays",
    "PeriodContext",
    "begin",
    "context_cycle",
    "context_period",
    "context_warm",
    "context_warm_until",
    "finish",
    "fused_period",
    "monotonic_ns",
    "receive_datagrams",
    "stack_warm",
    "take_frames",
]

Array = NDArray[np.float64]
Bytes = NDArray[np.uint8]
Ints = NDArray[np.int64]

(
    R_T0, R_THETA, R_CURRENT, R_PREV_THETA, R_STARTED, R_FRESH, R_STOP, R_FINISHING, R_ARMED,
    R_ARM_REQUEST, R_AFTER_FAULT, R_SENT, R_CALLS, R_STATUS_FRAMES, R_BAD, R_LINGER,
    R_START_TIMEOUT, R_HEARTBEAT_EVERY, R_DT, R_S_TAU, R_S_RATE, R_DATAGRAMS, R_ROLL,
    R_SPEED_LOW, R_SPEED_HIGH, R_S_PHI, R_S_SPEED, R_LEFT, R_LEFT_T, R_LEFT_PHI, R_LEFT_SPEED,
    R_STACK_TIME, R_WOKE, R_RECV_ERRORS, R_WARM, R_FRESH_AT, R_OMEGA, R_BEATS, R_K_BASE,
    R_K_LAST, R_HEARTBEAT_DUE, R_SLOT,
) = range(42)  # fmt: skip
RUNNER_STATE_SIZE = 42
"""The runner's state: the first deadline [s], the last valid angle [rad] and current [A],
the angle of the last fresh status frame, flags (started, a fresh status frame, stop requested,
finishing, armed, arm requested), periods since a fault, command frames sent, periods run,
status frames received, datagrams that were no frames; then its settings: periods to linger
after a fault, the ``NO_DRIVE`` timeout [periods], periods between heartbeats, the period
[s], where the stack's row holds the torque estimate and the handlebar rate (-1: nowhere),
whether the received frames are python-can datagrams (1) or id, length and bytes (0); the
virtual motorcycle's range (largest roll [rad], lowest and highest speed [m/s]), where the
stack's row holds its roll and speed (-1: nowhere); and whether, when (since the first
deadline [s]), at which roll [rad] and speed [m/s] the motorcycle left that range; the
stack's time this period [s] (:func:`monotonic_ns` around it; NaN where it did not step);
the wake-up of the last :func:`context_cycle` on :func:`monotonic_ns`'s clock [s] and the
errors of its socket reads other than "nothing waiting" (:func:`receive_datagrams`);
whether the stack is warmed before each deadline (1, :func:`context_warm_until`) or not (0);
for a stack without a rate in its row, the deadline of the period that read the last fresh
status frame [s] and the handlebar's rate between the last two [rad/s]; and the heartbeat
due next (its index: the period's index on the loop's time since the first deadline, over
``heartbeat_every``); the loop's deadlines before its current run (its ``k`` of the runs
before, each run's last ``k`` plus one) and its ``k`` of the last period (-1 before the
first: :func:`begin` takes a ``k`` not above it for a new run of the loop); what the last
:func:`finish` left to the runner: whether the heartbeat frame is to be sent this period (1)
and the ring's slot the row went to."""

(
    Q_ANGLE, Q_CURRENT, Q_COUNTER, Q_DRIVE_FAULT, Q_ESTOP, Q_COMMAND_CURRENT, Q_ENABLE,
    Q_COMMAND_COUNTER, Q_STATE, Q_FAULT, Q_HEARTBEAT_COUNTER, Q_COMMAND_AT, Q_HEARTBEAT_AT,
    Q_LOOP_COLUMNS,
) = range(14)  # fmt: skip
POSITIONS_SIZE = 14
"""Where the loop's signals sit in the frames' values (status: angle, current, counter,
drive fault; E-stop: its signal; command: current, enable, counter; heartbeat: state, fault,
counter), where the command and heartbeat frames' data bytes start in the bytes to send,
and the number of the loop's own columns in a row."""

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
    ``time.monotonic``: one ``clock_gettime`` call, about 20-40 ns, no interpreter); -1 where
    the C library has none (Windows).

    Examples
    --------
    >>> import time
    >>> a = time.monotonic_ns(); b = monotonic_ns(); c = time.monotonic_ns()
    >>> a <= b <= c or b == -1
    True
    """
    return _clock_gettime_ns()  # type: ignore[call-arg]  # numba's typing context


RECV_AVAILABLE = sys.platform == "linux"
"""Whether :func:`receive_datagrams` can read a socket from compiled code here (Linux: the C
library's ``recv`` with ``MSG_DONTWAIT`` and its ``errno`` through ``__errno_location``)."""

_MSG_DONTWAIT = getattr(socket, "MSG_DONTWAIT", 0)
_EAGAIN, _EWOULDBLOCK, _EINTR = errno.EAGAIN, errno.EWOULDBLOCK, errno.EINTR


@intrinsic
def _recv(typingctx: Any, fd: Any, buffer: Any, size: Any) -> Any:
    """``recv(fd, buffer, size, MSG_DONTWAIT)`` called from compiled code: the bytes read,
    or minus ``errno`` where it failed (``-EAGAIN``: nothing waiting). ``buffer`` is a
    C-contiguous ``uint8`` array of at least ``size`` bytes (Linux only)."""
    if not (
        isinstance(fd, types.Integer)
        and isinstance(size, types.Integer)
        and isinstance(buffer, types.Array)
        and buffer.dtype == types.uint8
        and buffer.layout == "C"
    ):
        return None

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        i32, i64 = ir.IntType(32), ir.IntType(64)
        i8p = ir.IntType(8).as_pointer()
        fd_type, buffer_type, size_type = signature.args
        handle = context.cast(builder, args[0], fd_type, types.int64)
        count = context.cast(builder, args[2], size_type, types.int64)
        data = builder.bitcast(context.make_array(buffer_type)(context, builder, args[1]).data, i8p)
        module = builder.module
        recv = module.globals.get("recv") or ir.Function(
            module, ir.FunctionType(i64, [i32, i8p, i64, i32]), "recv"
        )
        where = module.globals.get("__errno_location") or ir.Function(
            module, ir.FunctionType(i32.as_pointer(), []), "__errno_location"
        )
        got = builder.call(
            recv, [builder.trunc(handle, i32), data, count, ir.Constant(i32, _MSG_DONTWAIT)]
        )
        failed = builder.icmp_signed("<", got, ir.Constant(i64, 0))
        code = builder.sext(builder.load(builder.call(where, [])), i64)
        return builder.select(failed, builder.neg(code), got)

    return types.int64(fd, buffer, size), codegen


_read: Any = _recv
""":func:`_recv` as compiled code calls it (numba's typing context fills ``typingctx``)."""


class PeriodArrays(NamedTuple):
    """Every array one period reads or writes, allocated before the first deadline."""

    runner: Array
    """The runner's state (``R_*``)."""
    positions: Ints
    """Signal and byte positions (``Q_*``)."""
    safety: Any
    """The safety stage's state, a :class:`~motosim.rt.safety.SafetyState`
    (:func:`motosim.rt.safety.new_safety_state`)."""
    limits: SafetyParams
    """Its limits (:func:`motosim.rt.safety.safety_params`)."""
    status: Array
    """The status frame's codec (:func:`motosim.io.can.codec_table`)."""
    estop: Array
    """The E-stop frame's codec."""
    command: Array
    """The command frame's codec."""
    heartbeat: Array
    """The heartbeat frame's codec."""
    status_values: Array
    """The last status frame's values."""
    estop_values: Array
    """The last E-stop frame's values."""
    command_values: Array
    """The command frame's values."""
    heartbeat_values: Array
    """The heartbeat frame's values."""
    rx: Bytes
    """The frames read this period, one per row (``RX_FRAMES`` x ``RX_BYTES``)."""
    rx_length: Ints
    """Their lengths [bytes]."""
    rx_id: Ints
    """Their ids (frames given as id, length and bytes)."""
    command_frame: Bytes
    """The command frame's bytes to send (its data from ``positions[Q_COMMAND_AT]``)."""
    heartbeat_frame: Bytes
    """The heartbeat frame's bytes to send."""
    stack_row: Array
    """The stack's row after its last step."""
    ring: Array
    """The ring's rows (:attr:`motosim.rt.ring.SampleRing.arrays`)."""
    ring_head: Ints
    """The ring's counters: rows written, rows read."""


@njit(cache=True)
def take_frames(a: PeriodArrays, first: int, end: int, t: float) -> int:
    """Handle the frames ``first`` .. ``end - 1`` of ``a.rx``, read by the period whose
    deadline (or, paced by the bus, the wait's time) is ``t`` [s]; the number of status
    frames.

    A status frame is decoded and checked by the safety stage (checksum, alive counter, the
    drive's fault flag); if valid and fresh, its angle and current are kept. An E-stop frame
    pressed, or unreadable, trips the emergency stop. Other frames are ignored; datagrams
    that are no python-can frames are counted (``R_BAD``).
    """
    r, q, s = a.runner, a.positions, a.safety
    status_id = int(a.status[0, 0])
    estop_id = int(a.estop[0, 0])
    count = 0
    for j in range(first, end):
        if r[R_DATAGRAMS] != 0.0:
            kind, frame_id, start, length = unpack_frame(a.rx[j], 0, a.rx_length[j])
            if kind < 0:
                r[R_BAD] += 1.0
                continue
            if kind == 0:  # an error or remote frame
                continue
        else:
            frame_id, start, length = a.rx_id[j], 0, a.rx_length[j]
        if frame_id == status_id:
            r[R_STATUS_FRAMES] += 1.0
            values = a.status_values
            ok = decode_frame(a.status, a.rx[j], start, length, values)
            fault = values[q[Q_DRIVE_FAULT]] > 0.5
            # the safety stage's time: the loop's since the first deadline (NaN before it)
            if safety_status_frame(s, a.limits, ok, values[q[Q_COUNTER]], fault, t - r[R_T0]):
                r[R_THETA] = values[q[Q_ANGLE]]
                r[R_CURRENT] = values[q[Q_CURRENT]]
                r[R_FRESH] = 1.0
            count += 1
        elif frame_id == estop_id:
            values = a.estop_values
            ok = decode_frame(a.estop, a.rx[j], start, length, values)
            safety_estop_frame(s, ok, values[q[Q_ESTOP]] > 0.5)
    return count


@njit(cache=True)
def receive_datagrams(fd: int, a: PeriodArrays) -> int:
    """Read the datagrams waiting on socket ``fd`` (non-blocking) into ``a.rx``'s rows and
    their sizes into ``a.rx_length``, at most ``RX_FRAMES``; the number read.

    The compiled twin of :meth:`motosim.io.can.UdpMulticastLink.receive_datagrams` (what
    :class:`~motosim.rt.run.RealtimeRunner` calls otherwise): a datagram longer than a row
    is cut to it, as ``recv_into`` cuts it; an interrupted read is tried again (as Python
    does, PEP 475); "nothing waiting" (``EAGAIN``) ends the read, any other error too, and
    counts in the runner's ``R_RECV_ERRORS`` (the link's ``errors`` in the Python path).
    Linux only (:data:`RECV_AVAILABLE`).
    """
    rx, lengths = a.rx, a.rx_length
    size = rx.shape[1]
    n = 0
    while n < rx.shape[0]:
        got = _read(fd, rx[n], size)
        if got >= 0:
            lengths[n] = got
            n += 1
        elif got == -_EINTR:
            continue
        else:
            if got != -_EAGAIN and got != -_EWOULDBLOCK:
                a.runner[R_RECV_ERRORS] += 1.0
            break
    return n


@njit(cache=True)
def begin(a: PeriodArrays, k: int, t: float) -> bool:
    """After the frames of period ``k`` (deadline ``t`` [s]): True if the stack must be
    reset now (the first valid status frame came), at ``R_THETA`` and ``R_CURRENT``."""
    r, s = a.runner, a.safety
    if r[R_T0] != r[R_T0]:
        r[R_T0] = t
    if k <= r[R_K_LAST]:  # a new run of the loop (motosim run's fade-out): k from 0 again
        r[R_K_BASE] += r[R_K_LAST] + 1.0
    r[R_K_LAST] = k
    fresh = r[R_FRESH] != 0.0  # cleared by finish: the stack reads it in between
    started = r[R_STARTED] != 0.0
    if not started and k >= r[R_START_TIMEOUT]:
        safety_trip(s, Fault.NO_DRIVE)
    reset = False
    if fresh and not started:
        r[R_STARTED] = 1.0
        started = True
        reset = True
        r[R_PREV_THETA] = r[R_THETA]
        r[R_FRESH_AT] = t
        r[R_OMEGA] = 0.0
        if r[R_STOP] == 0.0 and r[R_ARMED] != 0.0:
            safety_enable(s)
    if r[R_ARM_REQUEST] != 0.0 and started:
        r[R_ARM_REQUEST] = 0.0
        if r[R_ARMED] == 0.0 and r[R_STOP] == 0.0:
            r[R_ARMED] = 1.0
            safety_enable(s)
    return reset


@njit(cache=True)
def finish(a: PeriodArrays, command: float, t: float, woke: float, done_read: float) -> bool:
    """The safety stage on the stack's ``command`` [A], the frames to send, the row.

    The stack's estimate of the rider's torque (its row's ``tau_r_hat``) NaN trips
    ``NON_FINITE`` as an inf does (the stage takes NaN for "no estimate": a stack without
    one).

    ``t`` is the period's deadline [s]: the heartbeat's period index is taken on the loop's
    time since the first deadline, not from the loop's ``k``, which a second run of the loop
    (motosim run's fade-out after the duration) counts from 0 again; the row's count of
    deadlines skipped is the loop's own (its ``k`` as :func:`begin` carries it across the
    runs), which the time between two runs does not add to. ``woke`` and
    ``done_read`` are the period's wake-up and the end of the bus read on the loop's clock
    [s] (NaN without one). Returns whether the run goes on; leaves in the runner's state
    whether the heartbeat frame is to be sent this period (``R_HEARTBEAT_DUE``) and the
    ring's slot the row went to (``R_SLOT``: the runner writes the send's time stamps there,
    then advances the ring's head).
    """
    r, q, s = a.runner, a.positions, a.safety
    fresh = r[R_FRESH] != 0.0
    r[R_FRESH] = 0.0
    started = r[R_STARTED] != 0.0
    theta_now = r[R_THETA]
    rate_at, tau_at = int(r[R_S_RATE]), int(r[R_S_TAU])
    if started and rate_at >= 0:
        omega = a.stack_row[rate_at]
    elif started:  # the angle's change between the last two fresh frames over their interval
        # (with frames slower than the loop, not one period's: a rate ten times too high),
        # on the loop's time: the deadlines a late loop skipped count (not the periods
        # served: the rate read too high), and a second run (the fade-out) goes on from it
        if fresh and t > r[R_FRESH_AT]:
            r[R_OMEGA] = (theta_now - r[R_PREV_THETA]) / (t - r[R_FRESH_AT])
            r[R_PREV_THETA] = theta_now
            r[R_FRESH_AT] = t
        omega = r[R_OMEGA]
    else:
        omega = 0.0
    tau_hat = a.stack_row[tau_at] if started and tau_at >= 0 else math.nan
    if started and tau_at >= 0 and tau_hat != tau_hat:  # NaN: no estimate only without one
        safety_trip(s, Fault.NON_FINITE)
    phi_at, speed_at = int(r[R_S_PHI]), int(r[R_S_SPEED])
    if started and phi_at >= 0 and speed_at >= 0 and r[R_LEFT] == 0.0:
        phi, speed = a.stack_row[phi_at], a.stack_row[speed_at]
        if abs(phi) > r[R_ROLL] or speed < r[R_SPEED_LOW] or speed > r[R_SPEED_HIGH]:
            # the motorcycle fell or left the model's speeds: the run ends as offline, the
            # torque faded out as at the end of its duration
            r[R_LEFT] = 1.0
            r[R_LEFT_T] = t - r[R_T0]
            r[R_LEFT_PHI] = phi
            r[R_LEFT_SPEED] = speed
            r[R_FINISHING] = 1.0
            safety_request_stop(s)
    theta = theta_now if started else 0.0
    out = safety_step(s, a.limits, command, theta, omega, tau_hat, t - r[R_T0])
    state = s.state
    values = a.command_values
    values[q[Q_COMMAND_CURRENT]] = out
    live = state == State.FADE_IN or state == State.RUNNING or state == State.STOPPING
    values[q[Q_ENABLE]] = 1.0 if live else 0.0
    sent = int(r[R_SENT])
    values[q[Q_COMMAND_COUNTER]] = sent & 0xF
    r[R_SENT] = sent + 1
    encode_frame(a.command, values, a.command_frame, q[Q_COMMAND_AT])
    n = math.floor((t - r[R_T0]) / r[R_DT] + 0.5)  # the period's index on the loop's time
    every = int(r[R_HEARTBEAT_EVERY])
    beat = n // every >= r[R_BEATS]  # the first period of its heartbeat period served
    if beat:  # (n % every == 0 missed the heartbeat whose period's first deadline was skipped)
        r[R_BEATS] = n // every + 1
        values = a.heartbeat_values
        values[q[Q_STATE]] = state
        values[q[Q_FAULT]] = s.fault
        values[q[Q_HEARTBEAT_COUNTER]] = (n // every) & 0xF
        encode_frame(a.heartbeat, values, a.heartbeat_frame, q[Q_HEARTBEAT_AT])
    slot = int(a.ring_head[0] % a.ring.shape[0])
    row = a.ring[slot]
    row[LoopColumn.t] = t - r[R_T0]
    row[LoopColumn.theta_h_meas] = theta_now
    row[LoopColumn.i_m_meas] = r[R_CURRENT]
    row[LoopColumn.i_cmd] = command
    row[LoopColumn.i_safe] = out
    row[LoopColumn.state] = state
    row[LoopColumn.fault] = s.fault
    row[LoopColumn.t_clock] = t
    row[LoopColumn.wake] = woke - t
    # compute, done_control, done_send: by the runner after the send
    row[LoopColumn.compute] = math.nan
    # deadlines the loop skipped before this one, by its own count (its k, the runs before
    # included), not on its time: the time between two runs skipped none
    row[LoopColumn.missed] = r[R_K_BASE] + r[R_K_LAST] - r[R_CALLS]
    row[LoopColumn.done_read] = done_read - woke
    row[LoopColumn.done_control] = math.nan
    row[LoopColumn.done_send] = math.nan
    row[LoopColumn.stack] = r[R_STACK_TIME]
    r[R_CALLS] += 1.0
    n_loop = q[Q_LOOP_COLUMNS]
    for j in range(a.stack_row.size):  # before the stack starts: its initial row
        row[n_loop + j] = a.stack_row[j]
    if state == State.FAULT:
        r[R_AFTER_FAULT] += 1.0
        carry_on = r[R_AFTER_FAULT] < r[R_LINGER]
    else:
        carry_on = not ((r[R_STOP] != 0.0 or r[R_FINISHING] != 0.0) and state == State.IDLE)
    r[R_HEARTBEAT_DUE] = 1.0 if beat else 0.0
    r[R_SLOT] = slot
    return bool(carry_on)


@njit(cache=True)
def fused_period(
    model: Any,
    data: Any,
    force: Array,
    side_force: Array,
    stack_state: Array,
    a: PeriodArrays,
    frames: int,
    k: int,
    t: float,
    woke: float,
    done_read: float,
) -> int:
    """One whole period of a runner whose stack is compiled: :func:`take_frames` of the
    ``frames`` read, :func:`begin`, the stack (:func:`~motosim.rt.stack.stack_reset`,
    :func:`~motosim.rt.stack.stack_period`, with ``model``, ``data``, the forces and the
    stack's ``stack_state`` of :class:`~motosim.rt.stack.CompiledStack`), :func:`finish`;
    1 if the run goes on, else 0."""
    r = a.runner
    take_frames(a, 0, frames, t)
    if begin(a, k, t):
        stack_reset(model, data, force, side_force, stack_state, r[R_THETA], r[R_CURRENT])
    command = 0.0
    r[R_STACK_TIME] = math.nan
    if r[R_STARTED] != 0.0:
        start = monotonic_ns()
        command = stack_period(
            model, data, force, side_force, stack_state, a.stack_row, r[R_THETA], r[R_CURRENT],
            r[R_FRESH] != 0.0, safety_scale(a.safety, a.limits),
        )  # fmt: skip
        if start >= 0:
            r[R_STACK_TIME] = (monotonic_ns() - start) * 1e-9
    return 1 if finish(a, command, t, woke, done_read) else 0


@njit(cache=True)
def stack_warm(
    model: Any, data: Any, shadow: Any, force: Array, side_force: Array, stack_state: Array,
    shadow_state: Array, shadow_row: Array, theta: float, current: float, fresh: bool,
    scale: float,
) -> None:  # fmt: skip
    """One stack period on ``shadow``, a copy of the stack's ``data`` and ``stack_state``
    made now, whose result is thrown away: the stack's code and data are then in the CPU's
    caches for the next period's real step. ``fresh`` and ``scale`` are computed as the
    period computes them (constants would be typed apart and compile another copy of the
    step)."""
    shadow.estimator[:] = data.estimator
    shadow.differentiator[:] = data.differentiator
    shadow.controller[:] = data.controller
    shadow.motorcycle[:] = data.motorcycle
    shadow.multibody[:] = data.multibody
    shadow.inputs[:] = data.inputs
    shadow.held[:] = data.held
    shadow.periods[:] = data.periods
    shadow_state[:] = stack_state
    stack_period(
        model, shadow, force, side_force, shadow_state, shadow_row, theta, current, fresh, scale
    )


@structref.register
class PeriodContextType(types.StructRef):
    """numba's type of :class:`PeriodContext` (one per set of field types)."""

    def preprocess_fields(self, fields: Any) -> tuple[tuple[str, Any], ...]:
        """The fields' types without literal values."""
        return tuple((name, types.unliteral(typ)) for name, typ in fields)  # type: ignore[no-untyped-call]


class PeriodContext(structref.StructRefProxy):
    """Every argument of :func:`fused_period` but the period's own, in one numba object.

    Passing it to a compiled function unboxes one pointer; the fields are the very objects
    given (the arrays are shared, not copied: what Python writes into them, the period reads).

    Parameters
    ----------
    model, data, force, side_force, stack_state
        Those of :class:`~motosim.rt.stack.CompiledStack` (its ``model``, ``data``,
        ``force``, ``side_force``, ``state``).
    arrays : PeriodArrays
        The period's arrays.
    shadow, shadow_state, shadow_row
        A second :class:`~motosim.sim.stack.StackData` of the same model, state and row:
        where :func:`context_warm` steps a copy of the stack (:func:`stack_warm`).
    """

    def __new__(
        cls,
        model: Any,
        data: Any,
        force: Array,
        side_force: Array,
        stack_state: Array,
        arrays: PeriodArrays,
        shadow: Any,
        shadow_state: Array,
        shadow_row: Array,
    ) -> "PeriodContext":
        made: PeriodContext = structref.StructRefProxy.__new__(  # type: ignore[no-untyped-call]
            cls, model, data, force, side_force, stack_state, arrays, shadow, shadow_state,
            shadow_row,
        )  # fmt: skip
        return made


structref.define_proxy(  # type: ignore[no-untyped-call]
    PeriodContext,
    PeriodContextType,
    ["model", "data", "force", "side_force", "stack_state", "arrays", "shadow", "shadow_state",
     "shadow_row"],
)  # fmt: skip


@njit(cache=True)
def context_warm(c: Any) -> None:
    """:func:`stack_warm` at the last valid measurement, once the stack has started."""
    r = c.arrays.runner
    if r[R_STARTED] != 0.0:
        stack_warm(
            c.model, c.data, c.shadow, c.force, c.side_force, c.stack_state, c.shadow_state,
            c.shadow_row, r[R_THETA], r[R_CURRENT], r[R_FRESH] != 0.0,
            safety_scale(c.arrays.safety, c.arrays.limits),
        )  # fmt: skip


@njit(cache=True)
def context_warm_until(c: Any, due_ns: int) -> int:
    """:func:`context_warm` again and again until ``due_ns`` on :func:`monotonic_ns`'s clock
    [ns]; the number of warm-ups run (0 before the stack has started).

    The spin phase of the loop's wait, spent keeping the stack hot: one warm-up always, then
    another as long as it should end ``WARM_MARGIN_NS`` before ``due_ns`` (the last one's
    time taken as the next's), so that the last one ends 2-4 us before the deadline (the
    return to the interpreter and its last clock reads fit in the margin: the wake-up is not
    delayed). Each warm-up steps a fresh copy of the stack's state: the stack itself is not
    changed. A time already past (or no clock: :func:`monotonic_ns` -1) gives one warm-up.
    The loop calls it through :func:`context_period` (its ``warm_until``), so that the
    warm-ups run the very machine code of the step that follows.
    """
    r = c.arrays.runner
    if r[R_STARTED] == 0.0 or r[R_WARM] == 0.0:
        return 0
    n = 0
    start = monotonic_ns()
    while True:
        context_warm(c)
        n += 1
        end = monotonic_ns()
        if start < 0 or end + (end - start) + WARM_MARGIN_NS >= due_ns:
            return n
        start = end


@njit(cache=True)
def context_period(
    c: Any, frames: int, k: int, t: float, woke: float, done_read: float, warm_until: int
) -> int:
    """:func:`fused_period` with the arguments held by ``c``, a :class:`PeriodContext`; or,
    with ``warm_until`` >= 0, no period but the stack's warm-ups until then
    (:func:`context_warm_until`, ``warm_until`` [ns] on :func:`monotonic_ns`'s clock; their
    number is returned).

    Why both in one function: numba compiles, into each function called from Python, its own
    copy of every compiled function it calls (the stack's step included); warm-ups called
    through another function would warm another copy of the step's machine code (other
    addresses in the instruction cache and the branch predictors) and only the data the step
    shares. Through this one, the warm-ups and the period run the same copy.
    """
    if warm_until >= 0:
        return context_warm_until(c, warm_until)
    return fused_period(
        c.model, c.data, c.force, c.side_force, c.stack_state, c.arrays, frames, k, t, woke,
        done_read,
    )  # fmt: skip


@njit(cache=True)
def context_cycle(c: Any, fd: int, k: int, t: float) -> int:
    """The wait's end, the bus read and the period, in one compiled call: :func:`fused_period`
    of the datagrams waiting on socket ``fd`` at the deadline ``t`` [s] of period ``k`` (on
    the clock of :func:`monotonic_ns`, ``time.monotonic``'s), returning its value.

    In order, without returning to the interpreter: the stack's warm-ups until about 2 us
    before ``t`` (:func:`context_warm_until`, none before the stack has started or with the
    warm-ups off), a spin on
    the clock until ``t`` has passed (the test of
    :meth:`motosim.rt.clock.MonotonicClock.sleep_until`, on the same ``float`` seconds), the
    wake-up kept in the runner's ``R_WOKE`` [s], the datagrams read
    (:func:`receive_datagrams`), the period. The caller sleeps until shortly before ``t``
    (:class:`~motosim.rt.loop.RateLoop` with ``woke``) and sends the frames after. A ``t``
    already past (a simulated clock's) neither waits nor warms more than once.
    """
    r = c.arrays.runner
    context_warm_until(c, max(0, int(t * 1e9)))
    woke = monotonic_ns() / 1e9
    while woke < t:
        woke = monotonic_ns() / 1e9
    r[R_WOKE] = woke
    frames = receive_datagrams(fd, c.arrays)
    done_read = monotonic_ns() / 1e9
    return fused_period(
        c.model, c.data, c.force, c.side_force, c.stack_state, c.arrays, frames, k, t, woke,
        done_read,
    )  # fmt: skip
