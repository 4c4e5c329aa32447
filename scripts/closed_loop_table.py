"""Regenerate the closed-loop table of the README: every training scenario, the stack's feel.

    .venv/bin/python scripts/closed_loop_table.py [SCENARIO.toml ...]

Each scenario (by default every file in ``scenarios/`` and the paper's riding run) is
simulated as ``motosim simulate`` would, and the run metrics of
:func:`motosim.sim.metrics.run_metrics` are printed as a Markdown table: roll, path error,
tracking and estimate errors as fractions of the peak steer angle and peak rider torque, the
share of time the handlebar sticks, the current's content above 3 Hz over the last 2 s (the
buzz) and the flags.
"""

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from motosim.io.runs import load_run
from motosim.sim import simulate
from motosim.sim.metrics import run_metrics

ROOT = Path(__file__).resolve().parents[1]


def _percent(metrics: dict[str, float], key: str) -> str:
    value = metrics.get(key)
    return "-" if value is None or not math.isfinite(value) else f"{100 * value:.1f} %"


def main() -> int:
    """Print the Markdown table."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("scenarios", nargs="*", help="scenario files (default: the examples)")
    args = parser.parse_args()
    paths = [Path(p) for p in args.scenarios] or [
        *sorted((ROOT / "scenarios").glob("*.toml")),
        ROOT / "scenarios" / "paper" / "fig15_riding.toml",
    ]
    print(
        "| scenario | rate | max roll | max path error | tracking RMS / peak steer "
        "| estimate RMS / peak rider torque | handlebar sticking | buzz (last 2 s) | flags |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for path in paths:
        inputs = load_run(path)
        sc = inputs.scenario
        run = simulate(inputs, rng=np.random.default_rng(sc.seed))
        m = run_metrics(run.t, run.get, complete=True, max_current=sc.controller.max_current)
        flags = [k[5:] for k, v in m.items() if k.startswith("flag_") and v]
        path_error = f"{m['max_abs_e_y']:.2f} m" if "max_abs_e_y" in m else "-"
        buzz = f"{m['buzz_current_p2p']:.2f} A at {m['buzz_frequency']:.3g} Hz"
        print(
            f"| {path.stem} | {sc.rates.measurement:g} Hz | "
            f"{math.degrees(m['max_abs_phi']):.1f} deg | {path_error} | "
            f"{_percent(m, 'tracking_rms_fraction')} | {_percent(m, 'estimate_rms_fraction')} | "
            f"{_percent(m, 'stick_share')} | {buzz} | {', '.join(flags) or '-'} |",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
