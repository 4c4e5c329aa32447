"""Regenerate the closed-loop table of the simulate guide: every training scenario, the feel.

    .venv/bin/python scripts/closed_loop_table.py [SCENARIO.toml ...] [--rate HZ]
        [--handlebar FILE] [--no-prediction]

Each scenario (by default every file in ``scenarios/`` and the paper's riding run) is
simulated as ``motosim simulate`` would, and the run metrics of
:func:`motosim.sim.metrics.run_metrics` are printed as a Markdown table: roll, path error,
tracking and estimate errors as fractions of the peak steer angle and peak rider torque, the
share of time the handlebar sticks, the current's content above 3 Hz over the last 2 s (the
buzz) and the flags. ``--rate`` runs each at that control and measurement rate instead of its
own, ``--handlebar`` on another handlebar (a parameter file, the true and the nominal one:
the stack is designed for it), as the guide's unseen checks do; ``--no-prediction`` with the
plain rider-torque cancellation (``[controller] prediction = false``).
"""

import argparse
import dataclasses
import math
import sys
from pathlib import Path

import numpy as np

from motosim.io.runs import load_run, load_scenario, resolve
from motosim.sim import RunInputs, simulate
from motosim.sim.metrics import run_metrics
from motosim.sim.scenario import Handlebar

ROOT = Path(__file__).resolve().parents[1]


def _percent(metrics: dict[str, float], key: str) -> str:
    value = metrics.get(key)
    return "-" if value is None or not math.isfinite(value) else f"{100 * value:.1f} %"


def _inputs(
    path: Path, rate: float | None, handlebar: str | None, plain: bool = False
) -> RunInputs:
    """The scenario's run, at ``rate`` [Hz] and on ``handlebar`` where given; ``plain``: with
    the plain rider-torque cancellation."""
    if rate is None and handlebar is None and not plain:
        return load_run(path)
    sc = load_scenario(path)
    if plain:
        sc = dataclasses.replace(
            sc, controller=dataclasses.replace(sc.controller, prediction=False)
        )
    if rate is not None:
        sc = dataclasses.replace(
            sc, rates=dataclasses.replace(sc.rates, control=rate, measurement=rate)
        )
    if handlebar is not None:
        sc = dataclasses.replace(sc, handlebar=Handlebar(true=str(Path(handlebar).resolve())))
    return resolve(sc, path.parent)


def main() -> int:
    """Print the Markdown table."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("scenarios", nargs="*", help="scenario files (default: the examples)")
    parser.add_argument("--rate", type=float, help="control and measurement rate [Hz]")
    parser.add_argument("--handlebar", help="handlebar parameter file (true and nominal)")
    parser.add_argument("--no-prediction", action="store_true", help="the plain cancellation")
    args = parser.parse_args()
    suffix = f" ({Path(args.handlebar).stem})" if args.handlebar else ""
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
        inputs = _inputs(path, args.rate, args.handlebar, args.no_prediction)
        sc = inputs.scenario
        run = simulate(inputs, rng=np.random.default_rng(sc.seed))
        m = run_metrics(run.t, run.get, complete=True, max_current=sc.controller.max_current)
        flags = [k[5:] for k, v in m.items() if k.startswith("flag_") and v]
        path_error = f"{m['max_abs_e_y']:.2f} m" if "max_abs_e_y" in m else "-"
        buzz = f"{m['buzz_current_p2p']:.2f} A at {m['buzz_frequency']:.3g} Hz"
        print(
            f"| {path.stem}{suffix} | {sc.rates.measurement:g} Hz | "
            f"{math.degrees(m['max_abs_phi']):.1f} deg | {path_error} | "
            f"{_percent(m, 'tracking_rms_fraction')} | {_percent(m, 'estimate_rms_fraction')} | "
            f"{_percent(m, 'stick_share')} | {buzz} | {', '.join(flags) or '-'} |",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
