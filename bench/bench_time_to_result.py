"""Time to result: ``motosim simulate scenarios/lane_change_20.toml`` as a user runs it.

The whole command, timed from outside (a fresh process each time: imports, loading the
compiled code, designing, the 10 s run at 1 kHz, writing the result, the report), wall clock
and the CPU time of the process (``resource.getrusage(RUSAGE_CHILDREN)``), beside the load
average, in three states:

- the first run after install: numba's cache empty (``NUMBA_CACHE_DIR`` a new folder) and
  the design cache empty (``MOTOSIM_CACHE_DIR`` a new folder);
- the compiled code warm, the design cache empty (a new scenario's first run);
- both warm (every later run), with and without the HTML report.

Each warm figure is the best of ``REPEAT`` runs. ``python bench/bench_time_to_result.py``;
``make bench`` runs it with the rest.
"""

import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "lane_change_20.toml"
REPEAT = 3


def _command(out: Path, env: dict[str, str], *, report: bool) -> tuple[float, float]:
    """(wall [s], CPU [s]) of one ``motosim simulate`` in a new process."""
    args = [sys.executable, "-m", "motosim", "simulate", str(SCENARIO), "--out", str(out)]
    args += ["--overwrite"] + ([] if report else ["--no-report"])
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(args, env=env, check=True, capture_output=True, cwd=ROOT)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def _best(out: Path, env: dict[str, str], *, report: bool) -> tuple[float, float]:
    runs = [_command(out, env, report=report) for _ in range(REPEAT)]
    return min(runs)


def run() -> dict[str, float]:
    """The figures of the module docstring."""
    figures: dict[str, float] = {"load average (1 min) before": os.getloadavg()[0]}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        env = {
            **os.environ,
            "NUMBA_CACHE_DIR": str(folder / "numba"),
            "MOTOSIM_CACHE_DIR": str(folder / "designs"),
        }
        out = folder / "run"

        def record(what: str, measured: tuple[float, float]) -> None:
            figures[f"{what}: wall [s]"], figures[f"{what}: CPU [s]"] = measured

        record("first run after install (nothing compiled, nothing designed)",
               _command(out, env, report=True))  # fmt: skip
        env["MOTOSIM_CACHE_DIR"] = str(folder / "designs-new")
        record("compiled code warm, design cache empty", _command(out, env, report=True))
        record("both warm, with the report (target 1.5 s wall)", _best(out, env, report=True))
        record("both warm, --no-report", _best(out, env, report=False))
    figures["load average (1 min) after"] = os.getloadavg()[0]
    return figures


if __name__ == "__main__":
    for key, value in run().items():
        print(f"  {key:<66} {value:.3g}")
