"""Campaign throughput, measured on the ``motosim campaign`` command itself.

Two campaigns of perturbed 10 s runs at 1 kHz (plant sub-steps at 10 kHz), each planned with
10,000 runs and shortened with ``--runs``:

- ``handlebar``: a square rider torque on the SIMACOM handlebar with dry friction, Walcott-Zak
  observer, first-order H-infinity controller, Sharp motorcycle at 20 m/s; a Latin
  hypercube over J_eq and beta_eq in [0.5, 1.5] x nominal (the rig is built once per worker
  and perturbed);
- ``robustness``: the shipped ``campaigns/paper_robustness.toml`` (virtual rider, a lane
  change whose length is drawn per run, so its path is built per run; two measurement rates,
  two designs).

Each is run by ``motosim campaign FILE --out DIR --jobs 2 --runs N --json --no-report`` in a
new process, first 20 runs with the design cache cold (the planning and design) and then the
measured runs into a new folder (the design cache warm, as a lab's second campaign): all
10,000 of ``handlebar``, 2000 of ``robustness`` by default. The figures are from outside (the
process's wall time and ``RUSAGE_CHILDREN`` CPU time, the workers included), beside the
command's own (the wall time it prints, the CPU time of its workers) and the load average;
the 10,000-run figure of a shortened campaign is projected from its CPU time per run on two
free cores.

``python bench/bench_campaign.py [RUNS_HANDLEBAR [RUNS_ROBUSTNESS]]``; ``make bench`` runs it
with the rest.
"""

import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

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
name = "bench_handlebar"
scenario = "base.toml"
sampling = "lhs"
runs = 10000
seed = 2
metrics = ["rms_tau_r_error", "rms_tracking_error"]
[factors]
"handlebar.inertia_factor" = { distribution = "uniform", low = 0.5, high = 1.5 }
"handlebar.damping_factor" = { distribution = "uniform", low = 0.5, high = 1.5 }
"""


def _robustness(folder: Path) -> Path:
    shipped = ROOT / "campaigns"
    (folder / "paper_robustness_base.toml").write_text(
        (shipped / "paper_robustness_base.toml").read_text()
    )
    text = (shipped / "paper_robustness.toml").read_text().replace("runs = 1000", "runs = 10000")
    path = folder / "robustness.toml"
    path.write_text(text)
    return path


def _command(campaign: Path, out: Path, runs: int, env: dict[str, str]) -> dict[str, float]:
    args = [sys.executable, "-m", "motosim", "campaign", str(campaign), "--out", str(out)]
    args += ["--jobs", "2", "--runs", str(runs), "--json", "--no-report"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(args, env=env, check=True, capture_output=True, text=True, cwd=ROOT)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    summary = json.loads(done.stdout)
    computed = summary["computed"]
    return {
        "runs": float(computed),
        "command, from outside: wall [s]": wall,
        "command, from outside: CPU of all its processes [s]": (after.ru_utime - before.ru_utime)
        + (after.ru_stime - before.ru_stime),
        "command's own printed wall [s]": summary["command_wall"],
        "planning and design [s]": summary["design_time"],
        "run phase [s]": summary["wall"] - summary["design_time"],
        "runs/s in the run phase": computed / (summary["wall"] - summary["design_time"]),
        "CPU per run in the workers [ms]": 1e3 * summary["cpu"] / computed,
        "scheduler overhead [%]": 100.0 * summary["overhead"],
        "10,000 runs on 2 free cores, from the CPU per run [s] (target 60)": 10_000
        * summary["cpu"]
        / computed
        / 2,
    }


def run(runs: int = 10_000, robustness_runs: int = 2000) -> dict[str, float]:
    """The figures of the module docstring, for ``runs`` runs of ``handlebar`` and
    ``robustness_runs`` of ``robustness``."""
    figures: dict[str, float] = {"load average (1 min) before": os.getloadavg()[0]}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "base.toml").write_text(BASE)
        handlebar = folder / "handlebar.toml"
        handlebar.write_text(CAMPAIGN)
        env = {**os.environ, "MOTOSIM_CACHE_DIR": str(folder / "designs")}
        plan = (
            ("handlebar", handlebar, runs),
            ("robustness", _robustness(folder), robustness_runs),
        )
        for name, path, count in plan:
            cold = _command(path, folder / f"{name}-cold", 20, env)
            warm = _command(path, folder / f"{name}-warm", count, env)
            figures[f"{name}: design cache cold, command wall [s]"] = cold[
                "command, from outside: wall [s]"
            ]
            figures[f"{name}: design cache cold, planning and design [s]"] = cold[
                "planning and design [s]"
            ]
            for key, value in warm.items():
                figures[f"{name}: {key}"] = value
            figures[f"{name}: load average (1 min) after"] = os.getloadavg()[0]
    return figures


if __name__ == "__main__":
    counts = [int(arg) for arg in sys.argv[1:3]]
    for key, value in run(*counts).items():
        print(f"  {key:<80} {value:.4g}")
