"""``motosim fidelity``: the steering feel a design renders, against the virtual motorcycle."""

import argparse
import math
from typing import Any

from motosim.cli._common import check_figure_path, print_json, save_figure, warn_atypical
from motosim.errors import MotosimError

__all__ = ["register"]

_TARGET_BAND = (0.1, 3.0)  # Hz, where the rendered feel is judged


def register(sub: Any) -> None:
    """Add ``fidelity`` to the subcommands."""
    parser = sub.add_parser(
        "fidelity",
        help="the steering feel a design renders, against the virtual motorcycle's",
        description=(
            "Simulate a feel measurement (the virtual rider holds a straight while a chirp "
            "torque is added to the rider's) with the handlebar, estimator, controller and "
            "rates of SCENARIO (the defaults without one), and compare the rendered response "
            "theta_h / tau_r with the motorcycle's delta / tau_r at the speed: magnitude "
            "error [dB] and phase error [deg] over frequency."
        ),
    )
    parser.add_argument("scenario", nargs="?", help="scenario TOML file (default: built-in)")
    parser.add_argument("--speed", type=float, default=20.0, help="speed [m/s] (default 20)")
    parser.add_argument(
        "--amplitude", type=float, default=3.0, help="chirp torque amplitude [N*m] (default 3)"
    )
    parser.add_argument("--band", default="0.1:5", help="chirp band LOW:HIGH [Hz] (default 0.1:5)")
    parser.add_argument(
        "--duration", type=float, default=60.0, help="length of the chirp [s] (default 60)"
    )
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.add_argument("--plot", metavar="FILE", help="save the Bode figure (.png, .svg, .pdf)")
    parser.add_argument(
        "--overwrite", action="store_true", help="replace the --plot file if it exists"
    )
    parser.set_defaults(func=run)


def _band(text: str) -> tuple[float, float]:
    try:
        low, high = (float(x) for x in text.split(":"))
    except ValueError:
        raise MotosimError(f"--band {text!r}; expected LOW:HIGH in Hz, e.g. 0.1:5") from None
    return low, high


def run(args: argparse.Namespace) -> int:
    """Simulate the feel measurement and print the comparison."""
    from pathlib import Path

    import numpy as np

    from motosim.io.runs import load_scenario, resolve
    from motosim.sim import simulate
    from motosim.sim.fidelity import feel_scenario, rendered_feel
    from motosim.sim.scenario import Scenario

    if not (math.isfinite(args.speed) and 3.0 <= args.speed <= 60.0):
        raise MotosimError(
            f"--speed {args.speed!r}; expected 3 to 60 m/s (the virtual rider's schedule)"
        )
    if not (math.isfinite(args.duration) and 10.0 <= args.duration <= 600.0):
        raise MotosimError(f"--duration {args.duration!r}; expected 10 to 600 s")
    if not (math.isfinite(args.amplitude) and 0.01 <= args.amplitude <= 200.0):
        raise MotosimError(
            f"--amplitude {args.amplitude!r}; expected a chirp torque of 0.01 to 200 N*m"
        )
    if args.plot is not None:
        check_figure_path(args.plot, overwrite=args.overwrite)
    band = _band(args.band)
    base = load_scenario(args.scenario) if args.scenario else Scenario(name="default")
    folder = Path(args.scenario).parent if args.scenario else Path(".")
    scenario = feel_scenario(
        base, speed=args.speed, amplitude=args.amplitude, band=band, duration=args.duration
    )
    for option in ("--speed", "--duration", "--amplitude"):
        warn_atypical("fidelity", option, getattr(args, option[2:]))
    inputs = resolve(scenario, folder)
    result = simulate(inputs, rng=np.random.default_rng(scenario.seed), keep=True)
    feel = rendered_feel(
        result.t, result["tau_r"], result["theta_h"], result["delta"], inputs.sharp,
        args.speed, band=band,
    )  # fmt: skip
    low, high = max(band[0], _TARGET_BAND[0]), min(band[1], _TARGET_BAND[1])
    magnitude, phase = feel.worst(low, high)
    payload = {
        "speed": args.speed,
        "band_hz": list(band),
        "worst_in": [low, high],
        "worst_magnitude_error_db": magnitude,
        "worst_phase_error_deg": phase,
        "frequency_hz": feel.frequency.tolist(),
        "magnitude_error_db": feel.magnitude_error_db.tolist(),
        "phase_error_deg": feel.phase_error_deg.tolist(),
        "coherence": feel.coherence.tolist(),
    }
    if args.plot is not None:
        from motosim.plotting.closed_loop import plot_feel

        payload["plot"] = str(save_figure(plot_feel(feel, speed=args.speed), args.plot))
    if args.json:
        print_json(payload)
        return 0
    print(f"rendered steering feel at {args.speed:g} m/s: theta_h / tau_r against delta / tau_r")
    print(f"  worst over {low:g}-{high:g} Hz: {magnitude:.2f} dB, {phase:.1f} deg")
    print(f"  {'f [Hz]':>7} {'error [dB]':>11} {'error [deg]':>12} {'coherence':>10}")
    for k in range(0, feel.frequency.size, max(1, feel.frequency.size // 12)):
        print(
            f"  {feel.frequency[k]:7.2f} {feel.magnitude_error_db[k]:11.2f} "
            f"{feel.phase_error_deg[k]:12.1f} {feel.coherence[k]:10.3f}"
        )
    if "plot" in payload:
        print(f"wrote {payload['plot']}")
    return 0
