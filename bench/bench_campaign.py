"""Campaign throughput: runs per second, scheduler overhead, and the 10,000-run target.

The runs are those of ``bench_closed_loop``'s campaign (square rider torque, SIMACOM handlebar
with dry friction, Walcott-Zak observer, first-order H-infinity controller, Sharp motorcycle
at 20 m/s, 10 s at 1 kHz, plant sub-steps at 10 kHz), drawn by a Latin hypercube over J_eq
and beta_eq in [0.5, 1.5] x nominal, run by :func:`motosim.campaign.run_campaign` with joblib
on every core. Figures:

- one run's time in one process (the closed loop's compiled speed is the limit);
- a campaign of ``RUNS`` runs after a warm-up campaign (the loky workers are started and
  have loaded the compiled code): its runs per second, and the scheduler overhead, the
  fraction of the workers' time in the run phase not spent in a task;
- the same campaign on a cold pool (a fresh process): what the first call pays to start and
  warm the workers;
- the time 10,000 such runs would take at the measured rate, against the 60 s target.

``python bench/bench_campaign.py [RUNS]`` (default 1000); ``make bench`` runs it with the rest.
"""

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BASE = """
[scenario]
name = "bench"
duration = 10.0
[rider]
kind = "torque"
profile = { kind = "square", low = -10.0, high = 10.0, period = 2.0 }
"""

CAMPAIGN = """
[campaign]
name = "bench"
scenario = "base.toml"
sampling = "lhs"
runs = {runs}
seed = {seed}
metrics = ["rms_tau_r_error", "rms_tracking_error"]
[factors]
"handlebar.inertia_factor" = {{ distribution = "uniform", low = 0.5, high = 1.5 }}
"handlebar.damping_factor" = {{ distribution = "uniform", low = 0.5, high = 1.5 }}
"""


def _campaign(folder: Path, runs: int, seed: int) -> Path:
    (folder / "base.toml").write_text(BASE)
    path = folder / f"c{seed}.toml"
    path.write_text(CAMPAIGN.format(runs=runs, seed=seed))
    return path


def _measure(runs: int, *, warm: bool) -> dict[str, float]:
    from motosim.campaign import load_campaign, run_campaign

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        if warm:
            run_campaign(load_campaign(_campaign(folder, 8, 1)), folder / "warm")
        s = run_campaign(load_campaign(_campaign(folder, runs, 2)), folder / "out")
    run_phase = s.wall - s.design_time
    return {
        "runs": float(s.computed),
        "workers": float(s.workers),
        "tasks": float(s.tasks),
        "design [s]": s.design_time,
        "run phase [s]": run_phase,
        "runs/s": s.computed / run_phase,
        "scheduler overhead [%]": 100.0 * s.overhead,
        "mean run [ms]": 1e3 * s.compute / s.computed,
        "cpu per run [ms]": 1e3 * s.cpu / s.computed,
    }


def _one_run() -> float:
    """Seconds of one 10 s run in this process, compiled and designed beforehand."""
    import numpy as np

    from motosim.campaign import load_campaign, plan_campaign
    from motosim.campaign.execute import Task, design_for, run_task

    with tempfile.TemporaryDirectory() as tmp:
        plan = plan_campaign(load_campaign(_campaign(Path(tmp), 6, 3)))
    c = plan.campaign
    task = Task(design_for(plan, plan.runs[0].design), plan.base, c.factors, plan.runs, c.metrics)
    run_task(task)  # compile
    best = np.inf
    for _ in range(3):
        start = time.perf_counter()
        run_task(task)
        best = min(best, (time.perf_counter() - start) / len(plan.runs))
    return float(best)


def run(runs: int = 1000) -> dict[str, float]:
    """The figures of the module docstring."""
    single = _one_run()
    warm = _measure(runs, warm=True)
    code = (
        "import sys; sys.path.insert(0, sys.argv[1]); import bench_campaign as b; "
        "import json; print(json.dumps(b._measure(int(sys.argv[2]), warm=False)))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code, str(Path(__file__).parent), str(runs)],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    import json

    cold = json.loads(out.strip().splitlines()[-1])
    rate = warm["runs/s"]
    return {
        "one 10 s run at 1 kHz, one process [ms]": 1e3 * single,
        "single-core rate [runs/s]": 1.0 / single,
        f"{runs} runs, warm pool, {warm['workers']:.0f} workers [runs/s]": rate,
        "warm: scheduler overhead [%]": warm["scheduler overhead [%]"],
        "warm: tasks": warm["tasks"],
        "warm: mean run in a worker, wall [ms]": warm["mean run [ms]"],
        "warm: mean run in a worker, CPU [ms]": warm["cpu per run [ms]"],
        "cold pool (first call) [runs/s]": cold["runs/s"],
        "cold: scheduler overhead [%]": cold["scheduler overhead [%]"],
        "design (once) [s]": warm["design [s]"],
        "10,000 runs at the warm rate [s] (target 60)": 10_000 / rate,
        "10,000 runs on free cores, from the CPU per run [s]": 10_000
        * warm["cpu per run [ms]"]
        / 1e3
        / warm["workers"],
        "load average (1 min) during the bench": os.getloadavg()[0],
    }


if __name__ == "__main__":
    for key, value in run(int(sys.argv[1]) if len(sys.argv) > 1 else 1000).items():
        print(f"  {key:<52} {value:.4g}")
