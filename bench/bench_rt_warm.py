"""What makes the stack's step slower inside the real-time loop than step after step.

Controlled experiments on the stack's period as ``motosim run`` calls it (the fused period,
:func:`motosim.rt.fused.context_period`, on a :class:`~motosim.rt.run.RealtimeRunner`'s
context, the stack timed from compiled code as in every run: the ``stack`` column), paced
at 1 kHz on absolute deadlines, in one process under the loop's privileges (SCHED_FIFO 80,
CPU 1, mlockall; refused and reported without root), each variant in three rounds of
``--periods`` periods, p50 and p99 of each round [us]:

- ``offline``: the stack's period in a compiled loop, step after step (the baseline of
  ``bench/bench_rt.py``, measured in the same run);
- ``compiled wait``: the fused period in a compiled loop, a compiled busy wait between two
  periods (no interpreter, no system call): with no warm-up; with one warm-up
  ``WARM_LEAD`` before the deadline; with warm-ups until the deadline
  (:func:`~motosim.rt.fused.context_warm_until`);
- ``python wait``: the loop as ``motosim run`` waits (:class:`~motosim.rt.clock.MonotonicClock`:
  a sleep, then a spin in Python, :meth:`RealtimeRunner.warm` called ``WARM_LEAD`` before
  the deadline), the period called from Python: no warm-up, one warm-up (before this
  work), warm-ups until the deadline (after); each also with the bus read of
  ``motosim run`` between the wake-up and the period (a datagram sent over loopback at the
  start of the period, read by ``poll``/``recv_into``/``poll`` as
  :meth:`~motosim.io.can.UdpMulticastLink.receive_into` does);
- ``compiled cycle``: the loop as ``motosim run`` waits since the compiled wait
  (``--wait compiled``, :meth:`RealtimeRunner.wait_period`): the sleep and Python's spin
  until ``WARM_LEAD`` before the deadline, then one compiled call
  (:func:`~motosim.rt.fused.context_cycle`): warm-ups until about 2 us before the deadline,
  a compiled spin to it, the status frame read from a loopback socket by ``recv`` from
  compiled code (sent at the start of the period), the period;
- ``cycle variant``: the same compiled cycle with its warm-ups replaced by none, the
  loop's, their copies of the stack's data only (no step: the step's code left cold), or
  their step only (the copy stepped on its own state: the stack's own data left cold); the
  frame read by ``recv`` or given (no system call between the last warm-up and the step).

``--poll-idle`` holds a CPU latency request of 0 us (``/dev/cpu_dma_latency``, as
``cyclictest`` does) during the measurement: an idle CPU then polls instead of halting (in a
VM: no exit to the host while the loop sleeps).

Run: ``python bench/bench_rt_warm.py [--periods 2000] [--only TEXT] [--poll-idle]``
(``--only``: the variants whose name has one of the comma-separated TEXTs, and the offline
baseline).
"""

import argparse
import os
import select
import socket
from typing import Any

import numpy as np
from numba import njit

from bench_rt import _steps, _us, bench_setup, replay_period
from motosim.io.can import recv_frames
from motosim.rt import fused
from motosim.rt.clock import MonotonicClock
from motosim.rt.fused import context_period, context_warm, context_warm_until, monotonic_ns
from motosim.rt.loop import WARM_LEAD
from motosim.rt.privileges import apply_privileges
from motosim.rt.safety import safety_scale
from motosim.rt.stack import CompiledStack, LoopState, compiled, stack_period


@njit(cache=False)
def _compiled_loop(
    c: Any, frames: Any, status_id: int, out: Any, gap_ns: int, lead_ns: int, mode: int
) -> None:
    """The fused period at ``gap_ns`` on absolute deadlines, a compiled busy wait between
    two: ``mode`` 0 no warm-up, 1 one warm-up ``lead_ns`` before the deadline, 2 warm-ups
    from then until the deadline; the stack's time of each period into ``out`` [s]."""
    a = c.arrays
    due = monotonic_ns() + gap_ns
    for k in range(out.size):
        if mode > 0:
            while monotonic_ns() < due - lead_ns:
                pass
            context_period(c, 0, 0, 0.0, 0.0, 0.0, 0 if mode == 1 else due)
        while monotonic_ns() < due:
            pass
        replay_period(c, frames, status_id, k)
        out[k] = a.runner.stack_time
        due += gap_ns


@njit(cache=False)
def _decay(c: Any, frames: Any, status_id: int, out: Any, gap_ns: int, warm: int) -> None:
    """The fused period again and again, ``gap_ns`` of busy wait before each: ``warm`` 1,
    after one warm-up through :func:`context_period`; 2, then warm-ups for 50 us until the
    period; the stack's time of each period into ``out`` [s]."""
    a = c.arrays
    for k in range(out.size):
        if warm == 1:
            context_period(c, 0, 0, 0.0, 0.0, 0.0, 0)
        due = monotonic_ns() + gap_ns
        while monotonic_ns() < due:
            pass
        if warm == 2:
            context_period(c, 0, 0, 0.0, 0.0, 0.0, monotonic_ns() + 50_000)
        replay_period(c, frames, status_id, k)
        out[k] = a.runner.stack_time


@njit(cache=False)
def _copy_only(c: Any) -> None:
    """What a warm-up reads and writes of the stack's data without its step: the copies of
    :func:`~motosim.rt.fused.stack_warm` (the real data read, the copy's written)."""
    d, shadow = c.stack.data, c.shadow.data
    shadow.estimator[:] = d.estimator
    shadow.differentiator[:] = d.differentiator
    shadow.controller[:] = d.controller
    shadow.motorcycle[:] = d.motorcycle
    shadow.held[:] = d.held
    shadow.periods[:] = d.periods
    c.shadow.state[:] = c.stack.state


@njit(cache=False)
def _step_only(c: Any) -> None:
    """A warm-up's step without its copies: the copy of the stack stepped on its own state
    (the stack's code, its model and the copy's data warmed; the stack's own data not)."""
    r = c.arrays.runner
    if c.shadow.state[LoopState.period] == 0.0:  # the copy starts from the stack once
        _copy_only(c)
    scale = safety_scale(c.arrays.safety, c.arrays.limits)
    stack_period(c.shadow, c.shadow_row, r.theta, r.current, r.fresh, scale, r.torque)


def _udp_multicast(frame_id: int, data: bytes) -> bytes:
    """The frame as python-can's udp_multicast bus sends it (its ``pack_message``)."""
    import can
    from can.interfaces.udp_multicast.utils import pack_message

    message = can.Message(arbitration_id=frame_id, data=data, is_extended_id=False)
    return bytes(pack_message(message))


@njit(cache=False)
def _cycle_variant(c: Any, fd: int, k: int, t: float, mode: int) -> Any:
    """:func:`~motosim.rt.fused.context_cycle` with its warm-ups replaced by ``mode``'s:
    0 none (a spin only), 1 the warm-ups (the loop's), 2 the warm-ups' copies of the stack's
    data only (no step: its code cold), 3 their step only (the copy stepped on its own
    state: the stack's own data cold); until about 2 us before ``t`` [s]. ``fd`` < 0: no
    socket read (no system call), the frame already in the period's arrays."""
    r = c.arrays.runner
    due = max(0, int(t * 1e9))
    if mode == 1:
        fused.context_warm_until(c, due)
    elif mode > 1 and r.started:
        start = monotonic_ns()
        while True:
            if mode == 2:
                _copy_only(c)
            else:
                _step_only(c)
            end = monotonic_ns()
            if end + (end - start) + fused.WARM_MARGIN_NS >= due:
                break
            start = end
    woke = monotonic_ns() / 1e9
    while woke < t:
        woke = monotonic_ns() / 1e9
    a = c.arrays
    frames = recv_frames(fd, a.rx, a.rx_length, a.rx_id)[0] if fd >= 0 else 1
    done_read = monotonic_ns() / 1e9
    return fused.fused_period(c.stack, c.arrays, frames, k, t, woke, done_read)


def main(periods: int, only: str = "", poll_idle: bool = False) -> None:
    """Measure and print; ``poll_idle``: hold a CPU latency request of 0 us
    (``/dev/cpu_dma_latency``) meanwhile."""
    if poll_idle:
        qos = os.open("/dev/cpu_dma_latency", os.O_WRONLY)
        os.write(qos, (0).to_bytes(4, "little"))  # held until the process ends
        print("CPU latency request: 0 us (idle CPUs poll instead of halting)")
    privileges = apply_privileges(priority=80, cpus=[1], mlock=True)
    print(
        "privileges:",
        ", ".join(f"{p.name} {'applied' if p.applied else 'refused'}" for p in privileges),
    )
    n = periods
    b = bench_setup(n)
    model, theta, frames, runner, st = b.model, b.theta, b.frames, b.runner, b.codecs.status
    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    rx.bind(("127.0.0.1", 0))
    rx.setblocking(False)
    tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    target = rx.getsockname()
    poll = select.poll()
    poll.register(rx, select.POLLIN)
    datagram = bytes(72)  # about a python-can udp_multicast frame
    packed = [_udp_multicast(st.frame_id, frame.tobytes()) for frame in frames]
    buffer = memoryview(bytearray(512))
    clock = MonotonicClock()
    lead = WARM_LEAD

    def python_loop(warm: int, read: bool, entry: str = "period") -> np.ndarray:
        r = runner()
        a, kernel, context = r._arrays, r._kernel, r._context
        assert kernel is not None
        if entry == "period":  # the warm-ups through the period's own function (this work)
            warm_up = r.warm
        else:  # through functions of their own (before): another copy of the step's code
            once = compiled(context_warm, context)
            until = compiled(context_warm_until, context, 0)

            def warm_up(deadline: float | None) -> int:
                if deadline is None:
                    once(context)
                    return 1
                n: int = until(context, int(deadline * 1e9))
                return n

        out = np.empty(n)
        t0 = clock.now() + 1e-3
        for k in range(n):
            deadline = t0 + k * 1e-3
            if read:
                tx.sendto(datagram, target)  # the drive's frame, waiting at the wake-up
            if warm:
                clock.sleep_until(deadline - lead)
                warm_up(deadline if warm == 2 else None)
            clock.sleep_until(deadline)
            if read:
                got = 0
                while poll.poll(0):
                    try:
                        got += rx.recv_into(buffer)
                    except BlockingIOError:
                        break
            a.rx[0, : st.length] = frames[k]
            a.rx_length[0] = st.length
            a.rx_id[0] = st.frame_id
            kernel(context, 1, k, deadline, float("nan"), float("nan"), -1)
            a.ring_head[0] += 1
            out[k] = fused.runner_counts(a.runner).stack_time
        return out

    def cycle_loop() -> np.ndarray:
        r = runner()
        a, context = r._arrays, r._context
        fd = rx.fileno()
        cycle = compiled(fused.context_cycle, context, fd, 0, 0.0)
        out = np.empty(n)
        t0 = clock.now() + 1e-3
        for k in range(n):
            deadline = t0 + k * 1e-3
            tx.sendto(packed[k], target)  # the drive's frame, waiting at the wake-up
            clock.sleep_until(deadline - lead)
            cycle(context, fd, k, deadline)
            a.ring_head[0] += 1
            out[k] = fused.runner_counts(a.runner).stack_time
        return out

    wakes: dict[tuple[int, bool], list[np.ndarray]] = {}  # the cycle variants' wake-ups

    def variant_loop(mode: int, read: bool) -> np.ndarray:
        """The compiled cycle of ``motosim run`` with the warm-ups of ``mode``
        (:func:`_cycle_variant`), the frame read from a loopback socket or given."""
        r = runner()
        a, context = r._arrays, r._context
        fd = rx.fileno() if read else -1
        out, late = np.empty(n), np.empty(n)
        t0 = clock.now() + 1e-3
        for k in range(n):
            deadline = t0 + k * 1e-3
            if read:
                tx.sendto(packed[k], target)  # waiting at the wake-up
            else:
                a.rx[0, : st.length] = frames[k]
                a.rx_length[0] = st.length
                a.rx_id[0] = st.frame_id
            clock.sleep_until(deadline - lead)
            end = _cycle_variant(context, fd, k, deadline, mode)
            a.ring_head[0] += 1
            out[k] = fused.runner_counts(a.runner).stack_time
            late[k] = end[4] - deadline  # its PeriodEnd's wake-up
        wakes.setdefault((mode, read), []).append(late[20:].copy())
        return out

    def compiled_loop(mode: int) -> np.ndarray:
        r = runner()
        out = np.empty(n)
        _compiled_loop(r._context, frames, st.frame_id, out, 1_000_000, int(lead * 1e9), mode)
        return out

    def offline() -> np.ndarray:
        s = CompiledStack(model)
        out = np.empty(n)
        args = (s.model, s.data, s.force, s.side_force, s.state, s.row())
        _steps(*args, theta[:n], out, 0, np.zeros(0))
        return out

    def decay(gap_us: float, warm: int) -> np.ndarray:
        r = runner()
        out = np.empty(n)
        _decay(r._context, frames, st.frame_id, out, int(gap_us * 1e3), warm)
        return out

    variants = {
        "offline, step after step": offline,
        "fused period after period": lambda: decay(0, 0),
        **{
            f"fused period, {g:g} us busy wait before": (lambda g=g: decay(g, 0))
            for g in (3, 30, 100, 300, 950)
        },
        "fused period after a warm-up, no wait": lambda: decay(0, 1),
        **{
            f"fused period after a warm-up, then {g:g} us busy wait": (lambda g=g: decay(g, 1))
            for g in (3, 30, 100)
        },
        **{
            f"fused period, {g:g} us busy wait, then warm-ups for 50 us": (lambda g=g: decay(g, 2))
            for g in (0, 30, 100, 300, 950)
        },
        "compiled wait, no warm-up": lambda: compiled_loop(0),
        "compiled wait, one warm-up 50 us before": lambda: compiled_loop(1),
        "compiled wait, warm-ups until the deadline": lambda: compiled_loop(2),
        "python wait, no warm-up": lambda: python_loop(0, False),
        "python wait, warm-ups until the deadline": lambda: python_loop(2, False),
        "python wait + bus read, no warm-up": lambda: python_loop(0, True),
        "python wait + bus read, one warm-up 50 us before, own function (before)": lambda: (
            python_loop(1, True, "own")
        ),
        "python wait + bus read, warm-ups until the deadline, own function": lambda: python_loop(
            2, True, "own"
        ),
        "python wait + bus read, one warm-up 50 us before, the period's function": lambda: (
            python_loop(1, True)
        ),
        "python wait + bus read, warm-ups until the deadline, the period's function (now)": (
            lambda: python_loop(2, True)
        ),
        "compiled cycle: warm-ups, spin, recv and the period in one compiled call": cycle_loop,
        **{
            f"cycle variant: {what}, {how}": (lambda m=m, read=read: variant_loop(m, read))
            for m, what in enumerate(("no warm-up", "warm-ups", "data only", "code only"))
            for read, how in ((True, "recv"), (False, "frame given"))
        },
    }
    if only:
        parts = only.split(",")
        variants = {
            k: v
            for k, v in variants.items()
            if k.startswith("offline") or any(p in k for p in parts)
        }
    small = n
    n = 20
    for run in variants.values():  # compile everything
        run()
    n = small
    results: dict[str, list[str]] = {name: [] for name in variants}
    for _ in range(3):
        for name, run in variants.items():
            t = run()
            t = t[20:][np.isfinite(t[20:])]  # the stack's first periods left out
            results[name].append(f"{_us(float(np.median(t)))}/{_us(float(np.percentile(t, 99)))}")
    load = " ".join(f"{x:.1f}" for x in os.getloadavg())
    print(f"stack step p50/p99 us, three rounds; load {load}")
    for name, rounds in results.items():
        print(f"  {name:<80} {'  '.join(rounds)}")
    if wakes:
        print("the cycle variants' wake-up after the deadline p50/p99/p99.9/max us, three rounds")
        what = ("no warm-up", "warm-ups", "data only", "code only")
        for (mode, read), rounds_w in wakes.items():
            figures = "  ".join(
                "/".join(str(_us(float(x))) for x in (*np.percentile(w, (50, 99, 99.9)), w.max()))
                for w in rounds_w[-3:]
            )
            print(f"  {what[mode]}, {'recv' if read else 'frame given':<12} {figures}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--periods", type=int, default=2000, help="periods per variant")
    parser.add_argument(
        "--only", default="", help="only the variants whose name has one of these (comma-separated)"
    )
    parser.add_argument(
        "--poll-idle", action="store_true", help="hold /dev/cpu_dma_latency at 0 us meanwhile"
    )
    args = parser.parse_args()
    main(args.periods, args.only, args.poll_idle)
