"""The real-time loop: wake-up latency, compute time and misses, the rig in another process.

Three measurements, each with the privileges this machine grants (SCHED_FIFO, CPU pinning,
mlockall: applied as root, refused otherwise, and reported):

1. ``rt-check``: an empty 1 kHz loop for 10 s (what the scheduler alone adds);
2. the period's compiled work called as the loop calls it, once per period from Python,
   against the same compiled work in a compiled loop over the same recorded status frames
   (the same commands sent, checked): the fused period (:func:`motosim.rt.fused.fused_period`:
   frame decoded, safety stage, stack, command encoded, row kept); what the ratio shows is
   the cost of calling compiled code from Python (the one
   :class:`~motosim.rt.fused.PeriodContext` unboxed); and the stack's step
   (:func:`motosim.rt.stack.stack_period`) in a compiled loop, each step timed from compiled
   code (:func:`motosim.rt.fused.monotonic_ns`) as the fused period times it in every run:
   the "offline" step that the step inside ``motosim run`` (3.) is compared with; with the
   offline closed loop's period (``motosim simulate``, plant included) for reference; and
   the machine's share: the offline step after a compiled busy wait of 0.1 to 3 ms and after
   a 64 MB read (what the step costs once the CPU's caches have lost it, whatever ran);
3. ``motosim run`` at 1 kHz (status frames at 1 kHz) against ``motosim rig`` in another
   process over ``udp_multicast`` for 60 s, and at 100 Hz (control and status) for 20 s,
   each with python-can's link (``--link python-can``: the "before") and with the fast link
   (``--link fast``, the default: the "after"), in the same run, and at 1 kHz paced by the
   rig's status frames (``--pace bus``), and at 1 kHz on the clock with the wait's end and
   the bus read in Python (``--wait python``: the "before" of the compiled wait, the
   default), reading each run's ``timing.json``; the load average at each run's start is
   printed with its figures.

Each run's ``timing.json`` also says where the compute time went (the loop's time stamps
in the ring: the bus read, the stack and safety stage, the send, the rest), printed as p50/p99.

Run alone: ``python bench/bench_rt.py [--seconds 60] [--quick]``; the machine's other load
shows in the figures (a 2-core VM shared with other work misses deadlines that a quiet lab
PC does not).

``python bench/bench_rt.py --ab ROUNDS [--seconds 30] [--wait python] [--ab-what poll-idle]``:
the stack's warm-ups before each deadline on and off (``motosim run --warm on|off``; or,
the warm-ups on, a 0 us CPU latency request held or not: idle CPUs polling), interleaved in the
same session (the order alternating from round to round): each round a 1 kHz clock-paced run
against the rig with each, the offline step (step after step, and paced at 1 kHz) measured
before each run; each run's step in the loop, wake-up, compute and misses, and the medians.
"""

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from motosim.control.torque_feedback import PAPER_CONTROLLER
from motosim.io.can import HandlebarCodecs, Link, handlebar_codecs
from motosim.params import load_parameters
from motosim.rt.check import check_timing
from motosim.rt.clock import MonotonicClock
from motosim.rt.config import parse_safety
from motosim.rt.fused import context_period, monotonic_ns
from motosim.rt.privileges import apply_privileges
from motosim.rt.run import RealtimeRunner, RunSettings
from motosim.rt.stack import CompiledStack, stack_period
from motosim.sim import build_stack, parse_scenario, prepare, simulate
from motosim.sim.closed_loop import RunInputs
from motosim.sim.stack import StackModel

sys.path.insert(0, str(Path(__file__).parents[1] / "tests" / "integration"))
from rt_tables import safety_table

SCENARIO = """
[scenario]
name = "bench_rt"
description = "square rider torque, the paper's K(s)"
duration = {duration}

[motorcycle]
speed = 8.0  # m/s: Sharp's motorcycle is self-stable there (capsize, weave, wobble damped),
             # so a minute of the square torque does not make it fall (which ends a run)

[rates]
control = {control}
measurement = {control}

[rider]
kind = "torque"
profile = {{ kind = "square", low = -5.0, high = 5.0, period = 4.0, start = 1.0 }}

[controller]
kind = "paper"

[realtime.rig]
latency = 0.0003
jitter = 0.0001
"""

RT = ["--fifo", "80", "--cpu", "1", "--mlock"]
RIG = ["--fifo", "70", "--cpu", "0", "--mlock"]


def _us(seconds: float) -> float:
    return round(seconds * 1e6, 1)


class _Quiet(Link):
    """A link that sends nowhere and receives nothing (the frames are given to the period)."""

    errors = 0

    def send(self, frame_id: int, data: bytes) -> bool:
        return True

    def receive(self, timeout: float = 0.0) -> tuple[int, bytes] | None:
        return None


@njit(cache=False, inline="always")
def replay_period(c: Any, frames: Any, status_id: int, k: int) -> None:
    """Period ``k`` of recorded status frames in a compiled loop: its frame put where the bus
    read puts it, the fused period (:func:`context_period`), the ring's row kept. Inlined,
    so each loop calls its own compiled copy of the period, as the loop does."""
    a = c.arrays
    a.rx[0, : frames.shape[1]] = frames[k]
    a.rx_length[0] = frames.shape[1]
    a.rx_id[0] = status_id
    context_period(c, 1, k, k * 1e-3, np.nan, np.nan, -1)
    a.ring_head[0] += 1


@njit(cache=False)
def _replay(c: Any, frames: Any, status_id: int, sent: Any, first: int, end: int) -> None:
    """The fused period over recorded status frames, in a compiled loop (the "offline" way):
    the same :func:`context_period` on the same :class:`PeriodContext` as the loop calls."""
    for k in range(first, end):
        replay_period(c, frames, status_id, k)
        sent[k] = c.arrays.command_frame


@njit(cache=False)
def _steps(parts: Any, row: Any, theta: Any, times: Any, gap_ns: int, sweep: Any) -> None:
    """The stack's period over recorded angles, in a compiled loop, each timed as the fused
    period times it in ``motosim run`` (:func:`monotonic_ns` around it) [s]; with ``gap_ns``
    > 0, a busy wait on the clock between two steps: the offline code at the loop's pace (no
    interpreter, no system call, nothing else run); with a non-empty ``sweep``, that array
    read through before each step (the CPU's caches emptied of the stack)."""
    due = monotonic_ns()
    total = 0.0
    for k in range(theta.size):
        due += gap_ns
        while monotonic_ns() < due:
            pass
        for j in range(0, sweep.size, 8):
            total += sweep[j]
        start = monotonic_ns()
        stack_period(parts, row, theta[k], 0.0, True, 1.0, 0.0)
        times[k] = (monotonic_ns() - start) * 1e-9
    if total < 0.0:  # the sweep's reads are used
        times[0] = total


CHUNK = 50
"""Periods timed together in the compiled loops (a period's own time is below the clock's
resolution and overhead)."""


class BenchSetup(NamedTuple):
    """The 1 kHz bench run of :func:`bench_setup`."""

    inputs: RunInputs
    model: StackModel
    codecs: HandlebarCodecs
    theta: np.ndarray  # the handlebar angle of each period [rad]
    frames: np.ndarray  # (n, status length) uint8: the drive's status frame of each period
    runner: Callable[[], RealtimeRunner]  # a fresh runner, each the same start


def bench_setup(n: int) -> BenchSetup:
    """The bench's 1 kHz run (the paper's controller on the packaged handlebar), its stack,
    and ``n`` status frames of a steered handlebar with its counter moving."""
    text = SCENARIO.format(duration=10.0, control=1000.0) + safety_table(3)
    data = {k: v for k, v in tomllib.loads(text).items() if k != "realtime"}
    sc = parse_scenario(data, origin="bench")
    hb = load_parameters("simacom_handlebar", "handlebar")
    inputs = prepare(
        sc,
        sharp=load_parameters("sharp1971", "sharp"),
        true_handlebar=hb,
        nominal_handlebar=hb,
        controller=PAPER_CONTROLLER,
    )
    model = build_stack(inputs)
    codecs = handlebar_codecs()
    limits = parse_safety(tomllib.loads(safety_table(3))["realtime"]["safety"], origin="bench")
    st = codecs.status
    values = np.zeros(len(st.names))
    theta = 0.01 * np.sin(np.arange(n) * 1e-3 * 6.0)
    frames = np.zeros((n, st.length), dtype=np.uint8)
    for k in range(n):
        values[codecs.position(st, "angle")] = theta[k]
        values[codecs.position(st, "counter")] = k & 0xF
        frames[k] = np.frombuffer(st.encode(values), dtype=np.uint8)

    def runner() -> RealtimeRunner:
        return RealtimeRunner(
            CompiledStack(model),
            _Quiet(),
            codecs,
            RunSettings(limits=limits, rate=1000.0, capacity=1 << 12, handlebar=hb),
        )

    return BenchSetup(inputs, model, codecs, theta, frames, runner)


def _stack_speed(n: int = 20_000) -> dict[str, float]:
    """The same compiled work called once per period from Python (as the loop does) and in
    a compiled loop over the same recorded inputs: the fused period (frame decoded, safety
    stage, stack, command encoded, row kept) and the stack's period alone; with the offline
    closed loop's period (``motosim simulate``, plant included) for reference."""
    b = bench_setup(n)
    model, theta, frames, runner, st = b.model, b.theta, b.frames, b.runner, b.codecs.status
    simulate(b.inputs, rng=np.random.default_rng(0))  # warm
    start = time.perf_counter()
    simulate(b.inputs, rng=np.random.default_rng(0))
    offline = (time.perf_counter() - start) / 10_000
    one, loop = runner(), runner()  # the same start
    kernel = one._kernel
    assert kernel is not None
    context, a = one._context, one._arrays
    times = np.empty(n)
    sent = np.zeros((n, a.command_frame.size), dtype=np.uint8)
    clock = time.perf_counter
    nan = float("nan")
    for k in range(n):
        a.rx[0, : st.length] = frames[k]
        a.rx_length[0] = st.length
        a.rx_id[0] = st.frame_id
        t0 = clock()
        kernel(context, 1, k, k * 1e-3, nan, nan, -1)
        times[k] = clock() - t0
        a.ring_head[0] += 1
        sent[k] = a.command_frame
    replayed = np.zeros_like(sent)
    _replay(loop._context, frames, st.frame_id, replayed, 0, 10)  # compile
    loop = runner()
    chunks = np.empty(n // CHUNK)  # per period, from the time of CHUNK periods in a row
    for j in range(chunks.size):
        t0 = clock()
        _replay(loop._context, frames, st.frame_id, replayed, j * CHUNK, (j + 1) * CHUNK)
        chunks[j] = (clock() - t0) / CHUNK
    assert np.array_equal(sent, replayed), "the two ways sent different commands"
    other = CompiledStack(model)
    args2 = (other.compiled_parts, other.row())
    step_times = np.empty(n)
    nothing = np.zeros(0)
    _steps(*args2, theta[:10], step_times[:10], 0, nothing)  # compile
    other.reset(0.0, 0.0)
    _steps(*args2, theta, step_times, 0, nothing)
    paced = np.empty(3000)
    other.reset(0.0, 0.0)
    _steps(*args2, theta[: paced.size], paced, 1_000_000, nothing)
    # the machine's share: the step after a busy wait of 0.1-3 ms (nothing else run) and
    # after a 64 MB read (caches emptied), in rounds so that the machine's load is shared
    gaps = {f"after a {ms:g} ms busy wait": int(ms * 1e6) for ms in (0.1, 0.3, 1.0, 3.0)}
    sweep = np.ones(8 << 20)
    share: dict[str, list[float]] = {}
    block = np.empty(200)
    for _ in range(3):
        for name, gap in (("step after step", 0), *gaps.items(), ("after a 64 MB read", 0)):
            other.reset(0.0, 0.0)
            _steps(
                *args2,
                theta[: block.size],
                block,
                gap,
                sweep if name == "after a 64 MB read" else nothing,
            )
            share.setdefault(name, []).append(_us(float(np.median(block))))
    p50, c50 = float(np.median(times)), float(np.median(chunks))
    return {
        "offline closed-loop period (simulate, plant included) us": _us(offline),
        "fused period from Python, per period p50 us": _us(p50),
        "fused period from Python, per period p99 us": _us(float(np.percentile(times, 99))),
        "fused period in a compiled loop, p50 us": _us(c50),
        "fused period: from Python / compiled loop, p50": round(p50 / c50, 2),
        "fused period: from Python / compiled loop, mean": round(
            float(np.mean(times) / np.mean(chunks)), 2
        ),
        "stack step in a compiled loop (offline), timed inside, p50 us": _us(
            float(np.median(step_times))
        ),
        "stack step in a compiled loop (offline), timed inside, p99 us": _us(
            float(np.percentile(step_times, 99))
        ),
        "stack step in a compiled loop paced at 1 kHz (busy wait), p50 us": _us(
            float(np.median(paced))
        ),
        **{
            f"stack step offline, {name}, p50 of three rounds us": ", ".join(map(str, v))
            for name, v in share.items()
        },
    }


def _motosim(*argv: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "motosim.cli.main", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )


BUS = "udp_multicast:239.74.163.131"  # a group of its own (other users of the machine)


def _run_against_rig(
    control: float,
    seconds: float,
    *,
    link: str = "fast",
    pace: str = "clock",
    wait: str = "",
    warm: str = "",
    text: str = "",
) -> dict[str, object]:
    """``motosim run`` against ``motosim rig`` in another process: the bench's scenario at
    ``control`` [Hz] for ``seconds``, or the scenario TOML ``text`` as it is (its rates and
    duration; its ``[realtime]`` tables, if any, followed by the bench's safety table)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench_rt.toml"
        # the watchdog is lenient here so that a VM stall shows up in the figures rather
        # than ending the run; the tests check the 3-period watchdog itself
        scenario = text or SCENARIO.format(duration=seconds, control=control)
        path.write_text(scenario + safety_table(1000))
        rig = _motosim(
            "rig",
            str(path),
            "--bus",
            BUS,
            "--duration",
            "36000",
            "--rate",
            f"{control:g}",
            "--link",
            link,
            *RIG,
        )
        time.sleep(5.0)
        load = os.getloadavg()
        run = _motosim(
            "run",
            str(path),
            "--bus",
            BUS,
            "--out",
            f"{tmp}/out",
            "--json",
            "--no-report",
            "--link",
            link,
            "--pace",
            pace,
            *RT,
            *(("--wait", wait) if wait else ()),
            *(("--warm", warm) if warm else ()),
        )
        out, err = run.communicate()
        rig.send_signal(signal.SIGINT)
        rig.communicate(timeout=30)
        if run.returncode != 0:
            return {"error": err.strip().splitlines()[-1] if err.strip() else run.returncode}
        payload = json.loads(out)
    t = payload["timing"]
    stream = payload.get("state_stream", {})
    stack = payload["profile"].get("stack", {})  # timed inside the compiled period
    return {
        "wake_p50_us": _us(t["wake_p50"]),
        "wake_p99_us": _us(t["wake_p99"]),
        "wake_p999_us": _us(t["wake_p999"]),
        "wake_max_us": _us(t["wake_max"]),
        "compute_p50_us": _us(t["compute_p50"]),
        "compute_p99_us": _us(t["compute_p99"]),
        "compute_p999_us": _us(t["compute_p999"]),
        "compute_max_us": _us(t["compute_max"]),
        "missed": t["missed"],
        "periods": t["periods"],
        "missed_percent": round(100.0 * t["miss_ratio"], 3),
        "frame periods without a frame (bus-paced: the rig's)": t.get("gaps", 0),
        "frames_lost": payload["counters"]["frames_lost"],
        "stack step in the loop, p50 us": _us(stack.get("p50", float("nan"))),
        "stack step in the loop, p99 us": _us(stack.get("p99", float("nan"))),
        "where the compute time went, p50/p99 us": ", ".join(
            f"{stage} {_us(v['p50'])}/{_us(v['p99'])}" for stage, v in payload["profile"].items()
        ),
        "state stream (writer process): sent, lag p50/p99/max us": (
            f"{stream.get('sent', 0):.0f}, {_us(stream.get('lag_p50', float('nan')))}/"
            f"{_us(stream.get('lag_p99', float('nan')))}/{_us(stream.get('lag_max', float('nan')))}"
        ),
        "load average (1, 5, 15 min) at the start": " ".join(f"{x:.1f}" for x in load),
        "privileges": ", ".join(
            f"{p['name']} {'applied' if p['applied'] else 'refused'}" for p in payload["privileges"]
        ),
    }


def _offline_steps(b: BenchSetup) -> dict[str, float]:
    """The offline references of the step in the loop, as :func:`_stack_speed` measures them:
    the stack's period in a compiled loop step after step, and paced at 1 kHz by a compiled
    busy wait (p50 and p99 [us])."""
    other = CompiledStack(b.model)
    args = (other.compiled_parts, other.row())
    nothing = np.zeros(0)
    out: dict[str, float] = {}
    for name, n, gap in (("step after step", 20_000, 0), ("paced at 1 kHz", 3000, 1_000_000)):
        times = np.empty(n)
        other.reset(0.0, 0.0)
        _steps(*args, b.theta[:n], times, gap, nothing)
        out[f"offline {name} p50 us"] = _us(float(np.median(times)))
        out[f"offline {name} p99 us"] = _us(float(np.percentile(times, 99)))
    return out


AB_KEYS = {
    "stack step in the loop, p50 us": "loop p50",
    "stack step in the loop, p99 us": "loop p99",
    "wake_p50_us": "wake p50",
    "wake_p99_us": "wake p99",
    "compute_p50_us": "compute p50",
    "compute_p99_us": "compute p99",
    "missed_percent": "missed %",
}


def ab(rounds: int, seconds: float, wait: str = "", what: str = "warm") -> None:
    """The warm-ups on and off (``motosim run --warm on|off``; ``what`` "poll-idle": the
    warm-ups on, and a CPU latency request of 0 us held by this process or not:
    ``/dev/cpu_dma_latency``, for the whole machine, as ``cyclictest`` holds it; idle CPUs
    then poll instead of halting), interleaved: ``rounds`` rounds of a 1 kHz
    clock-paced run against the rig over the fast link with each (the order alternating from
    round to round), the offline references measured in each round; each round's figures and
    the medians over the rounds are printed."""
    b = bench_setup(20_000)
    _offline_steps(b)  # compile
    rows: dict[str, list[dict[str, object]]] = {"on": [], "off": []}
    for j in range(rounds):
        order = ("on", "off") if j % 2 == 0 else ("off", "on")
        for warm in order:
            offline = _offline_steps(b)
            if what == "poll-idle":  # a 0 us CPU latency request held by this process
                qos = os.open("/dev/cpu_dma_latency", os.O_WRONLY) if warm == "on" else -1
                if qos >= 0:
                    os.write(qos, (0).to_bytes(4, "little"))  # for the whole machine
                try:
                    figures = _run_against_rig(1000.0, seconds, wait=wait)
                finally:
                    if qos >= 0:
                        os.close(qos)  # the request ends with the file
            else:
                figures = _run_against_rig(1000.0, seconds, wait=wait, warm=warm)
            figures |= offline
            rows[warm].append(figures)
            shown = {v: figures.get(k) for k, v in AB_KEYS.items()}
            load = figures.get("load average (1, 5, 15 min) at the start")
            given = figures.get("privileges")
            print(
                f"round {j + 1} {what} {warm}: {shown}; {offline}; load {load}; {given}", flush=True
            )
    print(
        f"medians over {rounds} rounds ({seconds:g} s runs, 1 kHz, fast link, "
        f"{wait or 'compiled'} wait):"
    )
    for warm, runs in rows.items():
        keys = [*AB_KEYS, *runs[0]] if runs else []
        med = {}
        for key in keys:
            values = [r[key] for r in runs if isinstance(r.get(key), (int, float))]
            if values and key not in med:
                med[AB_KEYS.get(key, key)] = round(float(np.median(values)), 3)
        loop, after = med.get("loop p50"), med.get("offline step after step p50 us")
        paced = med.get("offline paced at 1 kHz p50 us")
        if loop and after and paced:
            med["loop / step after step"] = round(loop / after, 2)
            med["loop / paced"] = round(loop / paced, 2)
        print(f"  {what} {warm}: {med}")


def run(seconds: float = 60.0, *, quick: bool = False) -> dict[str, object]:
    """Measure; return the figures (times in microseconds); ``quick``: only the 1 kHz runs
    with the fast link."""
    out: dict[str, object] = {}
    pid = os.fork()
    if pid == 0:  # rt-check under the privileges, in a child that exits afterwards
        apply_privileges(priority=80, cpus=[1], mlock=True)
        s = check_timing(1000.0, 10.0, clock=MonotonicClock())
        Path(f"/tmp/motosim_bench_rt_{os.getpid()}.json").write_text(json.dumps(s.as_dict()))
        os._exit(0)
    os.waitpid(pid, 0)
    check = json.loads(Path(f"/tmp/motosim_bench_rt_{pid}.json").read_text())
    Path(f"/tmp/motosim_bench_rt_{pid}.json").unlink()
    out |= {
        "rt-check 1 kHz wake p99 us": _us(check["wake_p99"]),
        "rt-check 1 kHz wake max us": _us(check["wake_max"]),
        "rt-check 1 kHz missed": check["missed"],
    }
    out |= {f"stack {k}": v for k, v in _stack_speed().items()}
    cases = [  # (rate, seconds, link, pace): python-can's link before, the fast link after;
        # "clock" ends each wait, reads the bus and runs the period in one compiled call
        # (--wait compiled, the default), "clock-python" in Python (--wait python, before)
        (1000.0, seconds, "python-can", "clock"),
        (1000.0, seconds, "fast", "clock"),
        (1000.0, seconds, "fast", "clock-python"),
        (1000.0, seconds, "fast", "bus"),
        (100.0, seconds / 3, "python-can", "clock"),
        (100.0, seconds / 3, "fast", "clock"),
    ]
    if quick:
        cases = [case for case in cases if case[0] == 1000.0 and case[2] == "fast"]
    for control, length, link, pace in cases:
        clock, _, wait = pace.partition("-")
        figures = _run_against_rig(control, length, link=link, pace=clock, wait=wait)
        out |= {f"run {control:g} Hz {link} {pace} {k}": v for k, v in figures.items()}
    inside = out.get("run 1000 Hz fast clock stack step in the loop, p50 us")
    before = out.get("run 1000 Hz fast clock-python stack step in the loop, p50 us")
    if isinstance(inside, float) and isinstance(before, float):
        out["stack step in the loop: compiled wait / Python wait, p50"] = round(inside / before, 2)
    for name, key in (
        ("offline", "stack step in a compiled loop (offline), timed inside, p50 us"),
        (
            "offline paced at 1 kHz",
            "stack step in a compiled loop paced at 1 kHz (busy wait), p50 us",
        ),
    ):
        offline = out[f"stack {key}"]
        if isinstance(inside, float) and isinstance(offline, float):
            out[f"stack step: in the loop / {name}, p50"] = round(inside / offline, 2)
    for control in (1000.0, 100.0):
        before, after = (
            out.get(f"run {control:g} Hz {x} clock compute_p50_us") for x in ("python-can", "fast")
        )
        if isinstance(before, float) and isinstance(after, float):
            out[f"run {control:g} Hz compute p50 fast/python-can"] = round(after / before, 2)
    return out


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="1 kHz run length [s]")
    parser.add_argument("--quick", action="store_true", help="only the fast link at 1 kHz")
    parser.add_argument("--bus", default=BUS, help=f"the bus of the runs (default {BUS})")
    parser.add_argument("--stack-only", action="store_true", help="only the in-loop/offline speed")
    parser.add_argument(
        "--ab",
        type=int,
        default=0,
        metavar="ROUNDS",
        help="the warm-ups on and off, interleaved, ROUNDS rounds of --seconds at 1 kHz",
    )
    parser.add_argument("--wait", default="", help="with --ab: motosim run's --wait")
    parser.add_argument(
        "--ab-what",
        choices=("warm", "poll-idle"),
        default="warm",
        help="with --ab: --warm on against off (default), or a 0 us CPU latency request "
        "(/dev/cpu_dma_latency: idle CPUs poll) held or not",
    )
    args = parser.parse_args()
    BUS = args.bus
    if args.ab:
        ab(args.ab, args.seconds, args.wait, args.ab_what)
        sys.exit(0)
    if args.stack_only:
        for key, value in _stack_speed().items():
            print(f"  {key:<52} {value}")
        sys.exit(0)
    for key, value in run(args.seconds, quick=args.quick).items():
        print(f"  {key:<52} {value}")
