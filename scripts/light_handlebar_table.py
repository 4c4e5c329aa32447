"""What the lighter handlebar's lane-change tracking error is made of, one change at a time.

    .venv/bin/python scripts/light_handlebar_table.py [--rows NAME ...] [--handlebar FILE]

The training lane change (``scenarios/lane_change_20.toml``, 1 kHz) on the lighter handlebar
of the unseen checks (``bench/scenarios/handlebars/light_handlebar.toml``, true = nominal;
``--handlebar`` another, ``--handlebar simacom_handlebar`` the packaged one) with the
controller designed at 10 Hz, as every handlebar's was before
:func:`motosim.control.torque_feedback.handlebar_bandwidth`, then varied one thing at a time:
an exact angle, the dry friction off (true and nominal handlebar), the motorcycle driven by
the true rider torque, the plain cancellation, the packaged handlebar's controller, other
bandwidths, twice the integral corner, and the default design of now. The scenario has no
current noise. One Markdown row each: tracking RMS as a fraction of the peak steer angle,
split into the share before the manoeuvre (0-2.2 s), in it (2.2-6 s) and in the hold after
(6-10 s) (square roots of each span's part of the mean square, so that their squares add up),
the share of time the handlebar is stuck (theta_h' = 0) and of the squared error
there, and the estimate RMS as a fraction of the peak rider torque.

(The guide's row with the true rider torque as the cancellation was measured with the
stack's cancellation reading the true torque, a change of :func:`motosim.sim.stack.step`
made for that measurement only.)
"""

import argparse
import dataclasses
from collections.abc import Callable
from pathlib import Path

import numpy as np

from motosim.control.torque_feedback import synthesize_controller
from motosim.io.runs import load_scenario, resolve
from motosim.params import load_parameters
from motosim.sim import RunInputs, simulate
from motosim.sim.scenario import Handlebar, Scenario

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "lane_change_20.toml"
LIGHT = ROOT / "bench" / "scenarios" / "handlebars" / "light_handlebar.toml"
SPANS = ((0.0, 2.2), (2.2, 6.0), (6.0, 10.0))


def _with(sc: Scenario, **tables: dict[str, object]) -> Scenario:
    for table, changes in tables.items():
        sc = dataclasses.replace(sc, **{table: dataclasses.replace(getattr(sc, table), **changes)})
    return sc


def _rows(handlebar: str) -> dict[str, Callable[[], RunInputs]]:
    base = dataclasses.replace(load_scenario(SCENARIO), handlebar=Handlebar(true=handlebar))
    ten = _with(base, controller={"bandwidth": 10.0})

    def run(sc: Scenario) -> Callable[[], RunInputs]:
        return lambda: resolve(sc, SCENARIO.parent)

    def packaged_controller() -> RunInputs:
        simacom = load_parameters("simacom_handlebar", "handlebar")
        K = synthesize_controller(simacom, rng=np.random.default_rng(0), n_starts=4)
        return dataclasses.replace(resolve(ten, SCENARIO.parent), controller=K)

    return {
        "10 Hz": run(ten),
        "exact angle": run(_with(ten, measurement={"encoder_bits": 0})),
        "dry friction off": run(_with(ten, handlebar={"friction": False})),
        "exact angle, dry friction off": run(
            _with(ten, measurement={"encoder_bits": 0}, handlebar={"friction": False})
        ),
        "motorcycle on the true torque": run(_with(ten, motorcycle={"input": "true"})),
        "plain cancellation": run(_with(ten, controller={"prediction": False})),
        "the packaged handlebar's controller": packaged_controller,
        "11 Hz": run(_with(base, controller={"bandwidth": 11.0})),
        "12 Hz": run(_with(base, controller={"bandwidth": 12.0})),
        "15 Hz": run(_with(base, controller={"bandwidth": 15.0})),
        "integral corner 0.2": run(_with(ten, controller={"integral_corner": 0.2})),
        "default": run(base),
    }


def main() -> int:
    """Print the Markdown table."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rows", nargs="*", help="names of the rows to run (default: all)")
    parser.add_argument("--handlebar", default=str(LIGHT), help="handlebar (true and nominal)")
    args = parser.parse_args()
    rows = _rows(args.handlebar)
    print(
        "| run | tracking RMS / peak steer | before, manoeuvre, hold | stuck: time, error^2 "
        "| estimate RMS / peak rider torque |"
    )
    print("|---|---|---|---|---|")
    for name in args.rows or rows:
        inputs = rows[name]()
        run = simulate(inputs, rng=np.random.default_rng(inputs.scenario.seed))
        theta, delta, tau, tau_hat, rate = (
            np.asarray(run.get(name), dtype=float)
            for name in ("theta_h", "delta", "tau_r", "tau_r_hat", "theta_h_dot")
        )
        t, e = run.t, theta - delta
        peak = float(np.max(np.abs(delta)))
        spans = [np.sqrt(np.sum(e[(t >= a) & (t < b)] ** 2) / e.size) / peak for a, b in SPANS]
        stuck = np.abs(rate) < 1e-9  # exact stick-slip: the rate is zero while stuck
        estimate = np.sqrt(np.mean((tau_hat - tau) ** 2)) / np.max(np.abs(tau))
        print(
            f"| {name} | {100 * np.sqrt(np.mean(e**2)) / peak:.1f} % | "
            f"{', '.join(f'{100 * s:.1f}' for s in spans)} % | {100 * np.mean(stuck):.0f} %, "
            f"{100 * np.sum(e[stuck] ** 2) / np.sum(e**2):.0f} % | {100 * estimate:.1f} % |",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
