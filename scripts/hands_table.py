"""Regenerate the hands table of the simulate guide: the loop with a rider's hands on it.

    .venv/bin/python scripts/hands_table.py [SCENARIO.toml ...] [--rates HZ ...]
        [--off-from SECONDS] [--quiet cell,friction,stick] [--stack-grip off]

Each scenario (by default the lane change at 20 m/s, the crosswind at 30 m/s and the
obstacle avoidance at 15 m/s) is simulated at each rate (control and measurement; 1 kHz and
100 Hz by default) with no hands (``hands = "off"``, a pure torque source: the row
``none``), with the ``relaxed`` (the default) and the ``firm`` grips of
:data:`motosim.sim.hands.GRIPS`, and with the relaxed grip let go from ``--off-from`` [s] (6
by default) to the end (``[rider] hands_off``), and with the relaxed grip read by an ideal
torque sensor (``[estimator] name = "torque_sensor"``) instead of the observer. Printed as a
Markdown table from :func:`motosim.sim.metrics.run_metrics`: tracking RMS / peak steer,
estimate RMS / peak rider torque (the rider's torque is the hands' whole torque, active and
passive), the motor current's content above 3 Hz over the last 2 s (peak to peak, after the
manoeuvre) and its strongest frequency, and the current's plain peak to peak over the last
2 s.

``--quiet`` runs every row with the stack's settings against the buzz
(:class:`motosim.sim.stack.Quiet`, the values of :func:`quiet`): ``cell`` the differentiator
that knows the encoder's count, ``friction`` the Dahl friction term, ``stick`` the
controller and the estimate held while the handlebar sticks; ``--presliding`` sets the Dahl
term's x_0.
"""

import argparse
import dataclasses
import math
import sys
from pathlib import Path

import numpy as np

from motosim.estimation.registry import SENSOR_ESTIMATOR
from motosim.io.runs import load_scenario, resolve
from motosim.sim import RunInputs, simulate
from motosim.sim.closed_loop import build_stack
from motosim.sim.metrics import run_metrics
from motosim.sim.stack import Quiet

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ("lane_change_20.toml", "crosswind_30.toml", "obstacle_avoidance_15.toml")
GRIPS = ("none", "relaxed", "firm", "relaxed, off", "relaxed, sensor")


def _inputs(
    path: Path, rate: float, grip: str, off_from: float, stack_grip: str | None = None
) -> RunInputs:
    """The scenario at ``rate`` [Hz] with the hands of ``grip``, its stack designed for
    ``stack_grip`` (``[controller] grip``; None: the scenario's default, the rider's)."""
    sc = load_scenario(path)
    sc = dataclasses.replace(
        sc,
        rates=dataclasses.replace(sc.rates, control=rate, measurement=rate),
        controller=dataclasses.replace(sc.controller, grip=stack_grip),
    )
    if grip == "none":
        sc = dataclasses.replace(sc, rider=dataclasses.replace(sc.rider, hands="off"))
    else:
        rider = dataclasses.replace(sc.rider, hands=grip.split(",")[0])
        if grip.endswith("off"):
            rider = dataclasses.replace(rider, hands_off=((off_from, sc.duration + 1.0),))
        sc = dataclasses.replace(sc, rider=rider)
        if grip.endswith("sensor"):  # an ideal torque sensor instead of the observer
            estimator = dataclasses.replace(sc.estimator, name=SENSOR_ESTIMATOR)
            sc = dataclasses.replace(sc, estimator=estimator)
    return resolve(sc, path.parent)


def quiet(parts: set[str], rate: float, bits: int, presliding: float = 1e-3) -> Quiet:
    """The settings against the buzz that ``parts`` names, as measured in the simulate guide
    for a ``bits``-bit encoder read at ``rate`` [Hz]: the cell's gains a = 0.8, b = 0.4
    from 1 kHz (an alpha-beta pair near 1000 rad/s), 1 and 1 at lower rates (the same
    bandwidth is then beyond the sample: the step's plain difference, kept to the cell);
    the Dahl term's x_0 ``presliding`` [rad]; stuck after 20 ms on one count."""
    q = 2.0 * math.pi / 2**bits if bits else 0.0
    fast = rate >= 1000.0
    return Quiet(
        quantum=q if "cell" in parts else 0.0,
        position_gain=0.8 if fast else 1.0,
        rate_gain=0.4 if fast else 1.0,
        presliding=presliding if "friction" in parts else 0.0,
        release=0.0,
        stick_samples=max(1, round(0.02 * rate)) if "stick" in parts else 0,
    )


def _percent(value: float | None) -> str:
    return "-" if value is None or not math.isfinite(value) else f"{100 * value:.1f} %"


def main() -> int:
    """Print the Markdown table."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("scenarios", nargs="*", help="scenario files (default: three)")
    parser.add_argument("--rates", type=float, nargs="+", default=[1000.0, 100.0])
    parser.add_argument("--off-from", type=float, default=6.0, help="hands off from [s]")
    parser.add_argument("--quiet", default="", help="cell,friction,stick (default: none)")
    parser.add_argument("--presliding", type=float, default=1e-3, help="Dahl x_0 [rad]")
    parser.add_argument(
        "--stack-grip",
        choices=("relaxed", "firm", "off"),
        default=None,
        help="the grip the stack is designed for (default: the rider's, as a scenario's)",
    )
    args = parser.parse_args()
    parts = {p for p in args.quiet.split(",") if p}
    if parts - {"cell", "friction", "stick"}:
        parser.error(f"--quiet {args.quiet!r}; expected names among cell, friction, stick")
    paths = [Path(p) for p in args.scenarios] or [ROOT / "scenarios" / s for s in SCENARIOS]
    print(
        "| scenario | rate | hands | tracking RMS / peak steer | estimate RMS / peak rider "
        "torque | current > 3 Hz, last 2 s | its frequency | current p-p, last 2 s |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for path in paths:
        for rate in args.rates:
            for grip in GRIPS:
                inputs = _inputs(path, rate, grip, args.off_from, args.stack_grip)
                sc = inputs.scenario
                settings = quiet(parts, rate, sc.measurement.encoder_bits, args.presliding)
                stack = build_stack(inputs)._replace(quiet=settings) if parts else None
                run = simulate(inputs, rng=np.random.default_rng(sc.seed), stack=stack)
                complete = bool(run.t.size == round(sc.duration * sc.rates.control))
                m = run_metrics(
                    run.t,
                    lambda name, r=run: r[name] if name in r.names else None,
                    complete=complete,
                    max_current=sc.controller.max_current,
                )
                tail = run.t >= run.t[-1] - 2.0
                p2p = float(np.ptp(run["i_m"][tail]))
                print(
                    f"| {sc.name} | {rate:g} Hz | {grip} | "
                    f"{_percent(m.get('tracking_rms_fraction'))} | "
                    f"{_percent(m.get('estimate_rms_fraction'))} | "
                    f"{m.get('buzz_current_p2p', math.nan):.2f} A | "
                    f"{m.get('buzz_frequency', math.nan):.1f} Hz | {p2p:.2f} A |",
                    flush=True,
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())
