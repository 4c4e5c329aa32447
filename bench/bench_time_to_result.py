"""Time to result: ``motosim simulate scenarios/lane_change_20.toml`` as a user runs it.

The whole command, timed from outside (a fresh process each time: imports, loading the
compiled code, designing, the 10 s run at 1 kHz, writing the result, the report), wall clock
and the CPU time of the command's processes (``resource.getrusage(RUSAGE_CHILDREN)``: the
command and the processes it waited for), beside the load average, in these states:

- nothing compiled, nothing designed: numba's cache empty (``NUMBA_CACHE_DIR`` a new
  folder) and the design cache empty (``MOTOSIM_CACHE_DIR`` a new folder), as after a
  ``pip install`` not followed by ``motosim cache warm``;
- the install's ``motosim cache warm`` (which ``make venv`` runs) on new caches, then the
  first run after it (the scenario's own rider schedule and stack still to design);
- the compiled code warm, the design cache empty (a new scenario's first run);
- both warm (every later run), with and without the HTML report.

Each warm figure is the best and the median of ``REPEAT`` runs (the CPU time's median taken
apart from the wall time's). With a baseline (``--baseline SRC``: the ``src`` folder of
another checkout, e.g. the previous release's), each state is measured for
it too, interleaved with ours (ours, baseline, ours, ...) in the same run, so that both see
the same load. ``python bench/bench_time_to_result.py [--baseline SRC]``; ``make bench``
runs it with the rest, without a baseline.
"""

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "lane_change_20.toml"
REPEAT = 9


def _simulate(out: Path, env: dict[str, str], *, report: bool) -> tuple[float, float]:
    """(wall [s], CPU [s]) of one ``motosim simulate`` in a new process."""
    args = ["simulate", str(SCENARIO), "--out", str(out), "--overwrite"]
    return _command(args + ([] if report else ["--no-report"]), env)


def _command(args: list[str], env: dict[str, str]) -> tuple[float, float]:
    """(wall [s], CPU [s]) of ``motosim ARGS`` in a new process."""
    args = [sys.executable, "-m", "motosim", *args]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(args, env=env, check=True, capture_output=True, cwd=ROOT)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def run(baseline: str | None = None) -> dict[str, float]:
    """The figures of the module docstring; ``baseline`` the other checkout's ``src``."""
    figures: dict[str, float] = {"load average (1 min) before": os.getloadavg()[0]}
    trees = {"": str(ROOT / "src")}
    if baseline:
        trees["baseline "] = str(Path(baseline).resolve())
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        envs = {
            who: {
                **os.environ,
                "PYTHONPATH": src,
                "NUMBA_CACHE_DIR": str(folder / f"numba{i}"),
                "MOTOSIM_CACHE_DIR": str(folder / f"designs{i}"),
            }
            for i, (who, src) in enumerate(trees.items())
        }

        def note(who: str, what: str, measured: tuple[float, float]) -> None:
            figures[f"{who}{what}: wall [s]"], figures[f"{who}{what}: CPU [s]"] = measured

        def record(what: str, *, report: bool, repeat: int) -> None:
            runs: dict[str, list[tuple[float, float]]] = {who: [] for who in envs}
            for _ in range(repeat):
                for who, env in envs.items():
                    runs[who].append(_simulate(folder / f"run-{len(who)}", env, report=report))
            for who, measured in runs.items():
                note(who, what, min(measured))
                if repeat > 1:
                    wall, cpu = (statistics.median(m) for m in zip(*measured, strict=True))
                    note(who, f"{what}, median", (wall, cpu))

        record("nothing compiled, nothing designed (no cache warm)", report=True, repeat=1)
        for i, (who, env) in enumerate(envs.items()):  # an install's new caches, warmed
            env["NUMBA_CACHE_DIR"] = str(folder / f"numba-install{i}")
            env["MOTOSIM_CACHE_DIR"] = str(folder / f"designs-install{i}")
            try:
                note(who, "install's motosim cache warm", _command(["cache", "warm"], env))
            except subprocess.CalledProcessError:  # a tree without the command
                pass
        record("first run after install (target 10 s wall)", report=True, repeat=1)
        for i, env in enumerate(envs.values()):
            env["MOTOSIM_CACHE_DIR"] = str(folder / f"designs-new{i}")
        record("compiled code warm, design cache empty", report=True, repeat=1)
        record("both warm, with the report (target 1.5 s wall)", report=True, repeat=REPEAT)
        record("both warm, --no-report", report=False, repeat=REPEAT)
    figures["load average (1 min) after"] = os.getloadavg()[0]
    return figures


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--baseline", help="the src folder of the checkout to compare with")
    options = parser.parse_args()
    for key, value in run(options.baseline).items():
        print(f"  {key:<75} {value:.3g}")
