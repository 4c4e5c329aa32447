"""The stack's step where the offline simulator runs it, beside step after step and the loop.

Issue 12's target, "the stack step inside the loop within 10 % of its offline speed", has two
readings of "offline speed": the step called back to back on its own (*step after step*),
and the step where the offline simulator runs it (``motosim simulate``: each control period
the stack's step interleaved with the plant: the true handlebar over the period, the rider,
the recorded row), where it also finds the CPU's caches partly taken by the plant's code and
data. This bench measures the second beside the first, on the training scenarios, with the
clock of the real-time loop's own figure, so that the three compare:

- **inside the offline simulator**: a copy of the simulator's compiled loop
  (:func:`motosim.sim.closed_loop._run_chunk`: the same statements, run block by block as
  :func:`motosim.sim.simulate` runs it) with :func:`~motosim.rt.fused.monotonic_ns` (one
  ``clock_gettime`` from compiled code, as the fused period times the step in ``motosim
  run``) read around the call of :func:`motosim.sim.stack.step`; its rows are checked equal,
  bit for bit, to the simulator's own loop's: what the simulator computes is not changed;
- **differential** (a check without a clock inside the loop): the simulator's own compiled
  loop timed whole, against the same loop with the stack's step replaced by a replay of its
  recorded outputs (the command, the held measurement, rate and estimate, the virtual
  motorcycle's states: what the rig and the row read), its rows also checked equal; the
  difference per period is the step's mean cost inside the loop (with whatever it does to
  the plant's caches), less the replay's few writes;
- **step after step**: the same :func:`~motosim.sim.stack.step` on the same inputs (the
  measured angle, the current-sensor error, the rider torque, the forces the simulator gave
  it), called back to back in a compiled loop and timed the same way, its commands checked
  equal to the simulator's;
- **inside ``motosim run``** (1 kHz, the rig in another process over ``udp_multicast``, the
  fast link, the compiled wait, the warm-ups on: the defaults): the machinery of
  ``bench/bench_rt.py`` on its own scenario (a square rider torque at 8 m/s, the paper's
  controller), whose offline figures are measured here the same way: its stack period
  (:func:`motosim.rt.stack.stack_period`, what the loop times) step after step, and its
  scenario inside the offline simulator.

The training scenarios (``scenarios/lane_change_20.toml``, ``scenarios/crosswind_30.toml``,
``scenarios/paper/fig15_riding.toml``) run at their own rates (1 kHz; Fig. 15's run measures
at 100 Hz under a 1 kHz control period) and with ``[rates] control = measurement = 100``.
Each round measures every case (the order turned round from round to round) and, with
``--seconds`` > 0, one ``motosim run``; the load average is printed at each round's start.
Per-period figures are p50 and p99 over a run's periods [us] (the clock's own read, about
20-40 ns, is in every figure alike); each round's figures and the range and median over the
rounds are printed.

Run: ``python bench/bench_step_inside.py [--rounds 3] [--seconds 30] [--repeats 3]``
(``--seconds 0``: the offline figures only; the real-time run takes SCHED_FIFO, CPU 1 and
mlockall as ``bench/bench_rt.py`` does, refused and reported without root: do not run it
while another real-time run uses the machine).
"""

import argparse
import dataclasses
import math
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numba import njit

import bench_rt
from bench_rt import _run_against_rig, _steps, bench_setup
from motosim.io.runs import load_run, load_scenario, resolve
from motosim.model.handlebar import step_exact
from motosim.rt.fused import monotonic_ns
from motosim.rt.stack import CompiledStack
from motosim.sim import RunInputs, build_stack
from motosim.sim.closed_loop import _COL, SIGNALS, RigData, _run_chunk, build_rig
from motosim.sim.rider import rider_torque
from motosim.sim.stack import new_data, reset, step

ROOT = Path(__file__).resolve().parents[1]
TRAINING = (
    ROOT / "scenarios" / "lane_change_20.toml",
    ROOT / "scenarios" / "crosswind_30.toml",
    ROOT / "scenarios" / "paper" / "fig15_riding.toml",
)
BUS = "udp_multicast:239.74.163.137"  # a group of its own (bench_rt.py's runs use another)
RIG_BUS = """
[realtime.rig]
latency = 0.0003
jitter = 0.0001
"""
"""The rig's bus in the real-time runs of a training scenario (``bench/bench_rt.py``'s)."""


def _us(seconds: float) -> float:
    return round(seconds * 1e6, 2)


def _make_chunk(kind: str) -> Any:
    """A compiled copy of :func:`motosim.sim.closed_loop._run_chunk` (keep it the same
    statements: the rows are checked equal to the original's): ``kind`` "timed", the step
    timed by :func:`monotonic_ns` [ns] into ``times``; "replay", the step replaced by its
    recorded outputs ``rec`` (command, held angle, rate and estimate, the motorcycle's 12
    states after the step). ``kind`` is a constant of the compiled code: no branch on it
    runs in the loop."""
    timed, replay = kind == "timed", kind == "replay"

    @njit(cache=False)
    def chunk(
        k0: int, out: Any, stack: Any, data: Any, rig: Any, world: Any, limits: Any,
        times: Any, rec: Any,
    ) -> int:  # fmt: skip
        J, beta, beta_s, nkt = (
            rig.handlebar[0], rig.handlebar[1], rig.handlebar[2], rig.handlebar[3]
        )  # fmt: skip
        n_sub = rig.plant_substeps
        h = stack.dt
        hb = world.handlebar
        z = data.motorcycle
        for row in range(out.shape[0]):
            k = k0 + row
            q = rig.quantum
            theta_meas = math.floor(hb[0] / q + 0.5) * q if q > 0.0 else hb[0]
            e_y = 0.0
            if rig.virtual_rider:
                tau_rider, idx, e_y = rider_torque(
                    z[:8], z[8], z[9], z[10], z[11], int(world.path_index[0]), rig.path,
                    rig.path_ds, rig.rider_speeds, rig.rider_K, rig.rider_x_ss,
                    rig.rider_tau_ss, rig.rider_limits[0], rig.rider_limits[1],
                )  # fmt: skip
                world.path_index[0] = idx
                tau_rider += rig.rider_probe[k]
            else:
                tau_rider = rig.rider_profile[k * n_sub]
            o = out[row]
            o[_COL.t] = k * h
            o[_COL.tau_r] = tau_rider
            o[_COL.tau_p] = -beta_s if hb[1] > 0.0 else (beta_s if hb[1] < 0.0 else 0.0)
            o[_COL.theta_h] = hb[0]
            o[_COL.theta_h_dot] = hb[1]
            o[_COL.v_y], o[_COL.psi_dot], o[_COL.phi_dot], o[_COL.delta_dot] = (
                z[0], z[1], z[2], z[3],
            )  # fmt: skip
            o[_COL.phi], o[_COL.delta], o[_COL.F_yr], o[_COL.F_yf] = z[4], z[5], z[6], z[7]
            o[_COL.v_x], o[_COL.psi], o[_COL.x], o[_COL.y] = z[8], z[9], z[10], z[11]
            o[_COL.e_y] = e_y
            if replay:
                i_cmd = rec[k, 0]
                data.held[0] = rec[k, 1]
                data.held[2] = rec[k, 2]
                data.held[3] = rec[k, 3]
                for j in range(12):
                    z[j] = rec[k, 4 + j]
            elif timed:
                start = monotonic_ns()
                i_cmd = step(
                    stack, data, theta_meas, rig.current_noise[k], tau_rider, rig.force[k],
                    rig.side_force[k],
                )  # fmt: skip
                times[k] = monotonic_ns() - start
            else:
                i_cmd = step(
                    stack, data, theta_meas, rig.current_noise[k], tau_rider, rig.force[k],
                    rig.side_force[k],
                )  # fmt: skip
            o[_COL.theta_h_meas] = data.held[0]
            o[_COL.theta_h_dot_hat] = data.held[2]
            o[_COL.tau_r_hat] = data.held[3]
            o[_COL.i_m] = i_cmd
            o[_COL.tau_m] = nkt * i_cmd
            steady = rig.virtual_rider
            if not steady:
                steady = True
                for j in range(1, n_sub):
                    if rig.rider_profile[k * n_sub + j] != tau_rider:
                        steady = False
                        break
            if steady:
                hb[0], hb[1] = step_exact(hb[0], hb[1], tau_rider + nkt * i_cmd, J, beta, beta_s, h)
            else:
                for j in range(n_sub):
                    tr = rig.rider_profile[k * n_sub + j]
                    hb[0], hb[1] = step_exact(
                        hb[0], hb[1], tr + nkt * i_cmd, J, beta, beta_s, h / n_sub
                    )
            if abs(o[_COL.phi]) > limits[0] or not limits[1] <= o[_COL.v_x] <= limits[2]:
                return row + 1
        return len(out)

    return chunk


_TIMED = _make_chunk("timed")
_REPLAY = _make_chunk("replay")


def _original(
    k0: int, out: Any, stack: Any, data: Any, rig: Any, world: Any, limits: Any,
    times: Any, rec: Any,
) -> int:  # fmt: skip
    """The simulator's own compiled loop (its cached machine code), the same arguments."""
    done: int = _run_chunk(k0, out, stack, data, rig, world, limits)
    return done


@njit(cache=False)
def _step_after_step(
    stack: Any, data: Any, theta: Any, noise: Any, tau: Any, force: Any, side: Any,
    times: Any, commands: Any,
) -> None:  # fmt: skip
    """The stack's step on recorded inputs, back to back, each timed by :func:`monotonic_ns`
    [ns]: the measured angle (read on measurement periods only, so the held one does), the
    current-sensor error, the rider torque, the forces."""
    for k in range(theta.size):
        start = monotonic_ns()
        commands[k] = step(stack, data, theta[k], noise[k], tau[k], force[k], side[k])
        times[k] = monotonic_ns() - start


class Case:
    """One scenario at one rate: its inputs, designed stack and world, and a recorded run."""

    def __init__(self, name: str, inputs: RunInputs) -> None:
        self.name = name
        self.inputs = inputs
        sc = inputs.scenario
        self.model = build_stack(inputs)
        self.rig = build_rig(inputs, rng=np.random.default_rng(sc.seed))
        self.n = self.rig.current_noise.size
        self.block = max(1, round(sc.rates.control))  # simulate's 1 s blocks
        self.rec = np.zeros((self.n, 16))  # the step's outputs, for the replay
        self.rows, _, z_end = self.run(_original)
        col = {s: j for j, s in enumerate(SIGNALS)}
        z_cols = [col[s] for s in ("v_y", "psi_dot", "phi_dot", "delta_dot", "phi", "delta",
                                   "F_yr", "F_yf", "v_x", "psi", "x", "y")]  # fmt: skip
        r = self.rows
        self.rec[:, 0] = r[:, col["i_m"]]
        self.rec[:, 1] = r[:, col["theta_h_meas"]]
        self.rec[:, 2] = r[:, col["theta_h_dot_hat"]]
        self.rec[:, 3] = r[:, col["tau_r_hat"]]
        self.rec[:-1, 4:] = r[1:, z_cols]  # the motorcycle after step k: row k + 1's
        self.rec[-1, 4:] = z_end
        self.inputs_of_step = (
            r[:, col["theta_h_meas"]].copy(), self.rig.current_noise, r[:, col["tau_r"]].copy(),
            self.rig.force, self.rig.side_force,
        )  # fmt: skip

    def run(self, chunk: Callable[..., int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The run as :func:`motosim.sim.simulate` runs it (a fresh stack and world, blocks
        of 1 s of rows), with ``chunk`` as its compiled loop: the rows, the step's times
        [ns] (timed loop only) and the motorcycle's states at the end."""
        data = new_data(self.model)
        world = RigData(np.zeros(3), np.zeros(1, dtype=np.int64))
        reset(self.model, data, 0.0, 0.0)
        limits = np.array((math.inf, -math.inf, math.inf))
        times = np.zeros(self.n, dtype=np.int64)
        blocks = []
        for k0 in range(0, self.n, self.block):
            out = np.full((min(self.block, self.n - k0), len(SIGNALS)), np.nan)
            done = chunk(k0, out, self.model, data, self.rig, world, limits, times, self.rec)
            assert done == out.shape[0], f"{self.name}: the run stopped at row {k0 + done}"
            blocks.append(out)
        return np.vstack(blocks), times, data.motorcycle.copy()

    def wall(self, chunk: Callable[..., int]) -> float:
        """The whole run's wall-clock time per period [s]."""
        start = time.perf_counter()
        self.run(chunk)
        return (time.perf_counter() - start) / self.n

    def after(self) -> tuple[np.ndarray, np.ndarray]:
        """Step after step on the run's recorded inputs: the times [ns] and the commands."""
        data = new_data(self.model)
        reset(self.model, data, 0.0, 0.0)
        times = np.zeros(self.n, dtype=np.int64)
        commands = np.zeros(self.n)
        _step_after_step(self.model, data, *self.inputs_of_step, times, commands)
        return times, commands

    def check(self) -> None:
        """The timed and replayed loops give the simulator's rows, step after step its
        commands, bit for bit (the run compiles them, too)."""
        for chunk in (_TIMED, _REPLAY):
            rows = self.run(chunk)[0]
            assert np.array_equal(rows, self.rows, equal_nan=True), f"{self.name}: rows differ"
        assert np.array_equal(self.after()[1], self.rows[:, SIGNALS.index("i_m")]), self.name

    def measure(self, repeats: int) -> dict[str, float]:
        """One round: per-period p50 and p99 inside the simulator and step after step [us],
        the means, and the differential (whole runs, the best of ``repeats``)."""
        inside = np.concatenate([self.run(_TIMED)[1] for _ in range(repeats)]) * 1e-9
        alone = np.concatenate([self.after()[0] for _ in range(repeats)]) * 1e-9
        full = replay = math.inf
        for _ in range(repeats):  # interleaved, the least disturbed of each
            full = min(full, self.wall(_original))
            replay = min(replay, self.wall(_REPLAY))
        return {
            "after p50": _us(float(np.median(alone))),
            "after p99": _us(float(np.percentile(alone, 99))),
            "after mean": _us(float(np.mean(alone))),
            "inside p50": _us(float(np.median(inside))),
            "inside p99": _us(float(np.percentile(inside, 99))),
            "inside mean": _us(float(np.mean(inside))),
            "period (simulate) us": _us(full),
            "differential": round((full - replay) * 1e6, 2),
        }


def cases() -> list[Case]:
    """The training scenarios at their own rates and at 100 Hz, and ``bench_rt.py``'s run."""
    out = []
    for path in TRAINING:
        own = load_run(path)
        sc = load_scenario(path)
        sc = dataclasses.replace(
            sc, rates=dataclasses.replace(sc.rates, control=100.0, measurement=100.0)
        )
        rates = own.scenario.rates
        out.append(Case(f"{path.stem} {rates.control:g}/{rates.measurement:g} Hz", own))
        out.append(Case(f"{path.stem} 100/100 Hz", resolve(sc, path.parent)))
    out.append(Case("bench_rt (motosim run's) 1000/1000 Hz", bench_setup(10).inputs))
    return out


KEYS = ("after p50", "after p99", "inside p50", "inside p99", "inside / after p50",
        "after mean", "inside mean", "differential", "period (simulate) us")  # fmt: skip


def _spread(values: list[float]) -> str:
    return f"{min(values):g}-{max(values):g} ({float(np.median(values)):.3g})"


def _stack_periods(model: Any, theta: np.ndarray) -> dict[str, float]:
    """The stack's period as ``motosim run`` times it (:func:`motosim.rt.stack.stack_period`,
    a fresh :class:`~motosim.rt.stack.CompiledStack`) on the angles ``theta`` [rad], step
    after step and paced at 1 kHz by a compiled busy wait (``bench/bench_rt.py``'s
    references): p50 and p99 [us]."""
    stack = CompiledStack(model)
    args = (stack.compiled_parts, stack.row())
    out: dict[str, float] = {}
    for name, n, gap in (("period after", theta.size, 0), ("period paced", 3000, 1_000_000)):
        times = np.empty(n)
        stack.reset(0.0, 0.0)
        _steps(*args, theta[:n], times, gap, np.zeros(0))
        out[f"{name} p50"] = _us(float(np.median(times)))
        out[f"{name} p99"] = _us(float(np.percentile(times, 99)))
    return out


def _realtime(case: Case, text: str, seconds: float) -> dict[str, float]:
    """``motosim run`` at 1 kHz against the rig (``bench/bench_rt.py``'s machinery): the
    bench's scenario for ``seconds`` (``text`` empty) or the scenario ``text`` as it is; the
    stack's step in the loop, p50 and p99 [us], printed with the load and the misses."""
    loop = _run_against_rig(1000.0, seconds, text=text)
    if "error" in loop:
        print(f"  motosim run {case.name}: failed: {loop['error']}", flush=True)
        return {}
    print(f"  motosim run {case.name}: step p50 {loop['stack step in the loop, p50 us']}, "
          f"p99 {loop['stack step in the loop, p99 us']}, missed {loop['missed_percent']} %, "
          f"load {loop['load average (1, 5, 15 min) at the start']}, {loop['privileges']}",
          flush=True)  # fmt: skip
    return {
        "loop p50": float(loop["stack step in the loop, p50 us"]),  # type: ignore[arg-type]
        "loop p99": float(loop["stack step in the loop, p99 us"]),  # type: ignore[arg-type]
        "missed %": float(loop["missed_percent"]),  # type: ignore[arg-type]
    }


def run(rounds: int = 1, seconds: float = 30.0, repeats: int = 3) -> dict[str, object]:
    """Measure ``rounds`` rounds; return the range and median of each figure [us]."""
    bench_rt.BUS = BUS
    all_cases = cases()
    for case in all_cases:
        case.check()
    square = next(c for c in all_cases if c.name.startswith("bench_rt"))
    lane = all_cases[0]
    realtime = (  # (case, scenario text: empty for bench_rt.py's own, at --seconds)
        (square, ""),
        (lane, TRAINING[0].read_text() + RIG_BUS),
    )
    figures: dict[str, dict[str, list[float]]] = {}
    for j in range(rounds):
        load = " ".join(f"{x:.1f}" for x in os.getloadavg())
        print(f"round {j + 1}: load {load}", flush=True)
        order = all_cases if j % 2 == 0 else all_cases[::-1]
        for case in order:
            f = case.measure(repeats)
            if case.model.measure_every == 1 and case.model.dt == 1e-3:  # as motosim run's
                f |= _stack_periods(case.model, case.inputs_of_step[0])
            f["inside / after p50"] = round(f["inside p50"] / f["after p50"], 2)
            for key, value in f.items():
                figures.setdefault(case.name, {}).setdefault(key, []).append(value)
            print(f"  {case.name}: {f}", flush=True)
        if seconds > 0:
            for case, text in realtime if j % 2 == 0 else realtime[::-1]:
                for key, value in _realtime(case, text, seconds).items():
                    figures[case.name].setdefault(key, []).append(value)
    return _table(figures, rounds)


COLUMNS = (  # (heading, p50 key, p99 key)
    ("step after step", "after p50", "after p99"),
    ("inside the offline simulator", "inside p50", "inside p99"),
    ("differential (mean)", "differential", ""),
    ("stack period after step (motosim run's)", "period after p50", "period after p99"),
    ("paced at 1 kHz", "period paced p50", "period paced p99"),
    ("inside motosim run", "loop p50", "loop p99"),
)


def _table(figures: dict[str, dict[str, list[float]]], rounds: int) -> dict[str, object]:
    """Print the figures as a Markdown table (range over the rounds and median, p50 then
    p99) with the ratios of the medians; return them."""
    print(f"\nstack step p50 / p99 [us], range over {rounds} rounds (median):\n")
    print("| run | " + " | ".join(c[0] for c in COLUMNS) + " | ratios of the p50 medians |")
    print("|---" * (len(COLUMNS) + 2) + "|")
    summary: dict[str, object] = {}
    for name, values in figures.items():
        med = {k: float(np.median(v)) for k, v in values.items() if v}
        cells = []
        for _, p50, p99 in COLUMNS:
            cell = _spread(values[p50]) if values.get(p50) else ""
            if cell and p99 and values.get(p99):
                cell += " / " + _spread(values[p99])
            cells.append(cell)
        ratios = [f"inside / after {med['inside p50'] / med['after p50']:.2f}"]
        for top, label in (("after p50", "after"), ("inside p50", "inside"),
                           ("period after p50", "period after")):  # fmt: skip
            if "loop p50" in med and top in med:
                ratios.append(f"loop / {label} {med['loop p50'] / med[top]:.2f}")
        if "missed %" in med:
            ratios.append(f"missed {_spread(values['missed %'])} %")
        print(f"| {name} | " + " | ".join(cells) + " | " + ", ".join(ratios) + " |")
        summary[name] = {k: _spread(v) for k, v in values.items() if v}
    return summary


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3, help="interleaved rounds")
    parser.add_argument(
        "--seconds", type=float, default=30.0, help="motosim run's length [s] (0: none)"
    )
    parser.add_argument("--repeats", type=int, default=3, help="runs of each case per round")
    parser.add_argument("--bus", default=BUS, help=f"the real-time run's bus (default {BUS})")
    args = parser.parse_args()
    BUS = args.bus
    run(args.rounds, args.seconds, args.repeats)
    sys.exit(0)
