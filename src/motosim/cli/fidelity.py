"""``motosim fidelity``: the steering feel a design renders, against the virtual motorcycle."""

import argparse
import math
from typing import Any

from motosim.cli._common import (
    check_figure_path,
    check_scenario_inputs,
    deferred_warnings,
    print_json,
    save_figure,
    warn_atypical,
)
from motosim.cli.cache import add_cache_option, design_cache
from motosim.errors import MotosimError

EXCITATIONS = ("multisine", "chirp")  # motosim.sim.fidelity.EXCITATIONS, without importing SciPy

__all__ = ["register"]

_TARGET_BAND = (0.1, 3.0)  # Hz, where the rendered feel is judged


def register(sub: Any) -> None:
    """Add ``fidelity`` to the subcommands."""
    parser = sub.add_parser(
        "fidelity",
        help="the steering feel a design renders, against the virtual motorcycle's",
        description=(
            "Simulate a feel measurement (the virtual rider holds a straight while a probe "
            "torque is added to the rider's) with the handlebar, estimator, controller and "
            "rates of SCENARIO (the defaults without one), and compare the rendered response "
            "theta_h / tau_r with the motorcycle's delta / tau_r at the speed: magnitude "
            "error [dB] and phase error [deg] over frequency. The probe is a periodic "
            "multisine averaged over whole periods (default), or a linear chirp analysed by "
            "Welch's method, which is biased below 0.3 Hz."
        ),
    )
    parser.add_argument("scenario", nargs="?", help="scenario TOML file (default: built-in)")
    parser.add_argument("--speed", type=float, default=20.0, help="speed [m/s] (default 20)")
    parser.add_argument(
        "--excitation",
        default=EXCITATIONS[0],
        help="probe torque: multisine (periodic, averaged) or chirp (default multisine)",
    )
    parser.add_argument(
        "--amplitude", type=float, default=10.0, help="probe's peak torque [N*m] (default 10)"
    )
    parser.add_argument("--band", default="0.1:5", help="probe band LOW:HIGH [Hz] (default 0.1:5)")
    parser.add_argument(
        "--period",
        type=float,
        default=20.0,
        help="multisine's period [s], at least 1/LOW (default 20: lines every 0.05 Hz)",
    )
    parser.add_argument(
        "--periods",
        type=int,
        default=4,
        help="multisine periods averaged, after one that settles (default 4)",
    )
    parser.add_argument(
        "--duration", type=float, default=None, help="length of the chirp [s] (default 60)"
    )
    parser.add_argument(
        "--radius",
        type=float,
        default=None,
        help="measure in a right-hand turn of this radius [m] (default: a straight)",
    )
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.add_argument(
        "--plot", metavar="FILE", help="save the Bode figure (.png, .svg, .pdf; default: none)"
    )
    parser.add_argument(
        "--overwrite", action="store_true", help="replace the --plot file if it exists"
    )
    add_cache_option(parser)
    parser.set_defaults(func=run)


def _band(text: str) -> tuple[float, float]:
    try:
        low, high = (float(x) for x in text.split(":"))
    except ValueError:
        raise MotosimError(f"--band {text!r}; expected LOW:HIGH in Hz, e.g. 0.1:5") from None
    # the band motosim.sim.fidelity.feel_scenario admits, checked before it is imported
    if not (math.isfinite(low) and math.isfinite(high) and 0 < low < high <= 20.0):
        raise MotosimError(f"--band {text!r}; expected LOW:HIGH with 0 < LOW < HIGH <= 20 Hz")
    return low, high


def run(args: argparse.Namespace) -> int:
    """Simulate the feel measurement and print the comparison."""
    if args.scenario:
        check_scenario_inputs(args.scenario)
    if not (math.isfinite(args.speed) and 3.0 <= args.speed <= 60.0):
        raise MotosimError(
            f"--speed {args.speed!r}; expected 3 to 60 m/s (the virtual rider's schedule)"
        )
    if args.excitation not in EXCITATIONS:
        raise MotosimError(
            f"--excitation {args.excitation!r}; expected one of {', '.join(EXCITATIONS)}"
        )
    chirp = args.excitation == "chirp"
    if not chirp and args.duration is not None:
        raise MotosimError(
            f"--duration {args.duration!r} is the chirp's length; expected --period and "
            "--periods with --excitation multisine (it lasts (periods + 1) x period)"
        )
    duration = 60.0 if args.duration is None else args.duration
    if not (math.isfinite(duration) and 10.0 <= duration <= 600.0):
        raise MotosimError(f"--duration {duration!r}; expected 10 to 600 s")
    if not (math.isfinite(args.period) and 1.0 <= args.period <= 300.0):
        raise MotosimError(f"--period {args.period!r}; expected 1 to 300 s")
    if not 1 <= args.periods <= 100:
        raise MotosimError(f"--periods {args.periods!r}; expected 1 to 100")
    if not chirp and (args.periods + 1) * args.period > 1800.0:
        raise MotosimError(
            f"--period {args.period:g} x (--periods {args.periods} + 1) = "
            f"{(args.periods + 1) * args.period:g} s; expected a run of at most 1800 s"
        )
    if not (math.isfinite(args.amplitude) and 0.01 <= args.amplitude <= 200.0):
        raise MotosimError(
            f"--amplitude {args.amplitude!r}; expected a probe torque of 0.01 to 200 N*m"
        )
    if args.radius is not None and not (math.isfinite(args.radius) and 10.0 <= args.radius <= 1e4):
        raise MotosimError(f"--radius {args.radius!r}; expected a turn of 10 to 10000 m")
    if args.radius is not None and args.speed**2 / (9.81 * args.radius) > 0.85:
        raise MotosimError(
            f"--radius {args.radius:g} at --speed {args.speed:g}: "
            f"{args.speed**2 / (9.81 * args.radius):.2f} g of lateral acceleration; expected "
            "at most 0.85 g, what a dry road's tyres hold"
        )
    if args.plot is not None:
        check_figure_path(args.plot, overwrite=args.overwrite)
    band = _band(args.band)
    if not chirp and band[0] > 0 and args.period * band[0] < 1.0 - 1e-9:
        raise MotosimError(
            f"--period {args.period:g} with --band {args.band}; expected a period of at least "
            f"1 / LOW = {1.0 / band[0]:g} s (the lowest line is 1 / period)"
        )
    from pathlib import Path

    import numpy as np

    from motosim.cli.simulate import resolve_cached
    from motosim.io.runs import load_scenario
    from motosim.sim import simulate
    from motosim.sim.fidelity import feel_scenario, periodic_feel, rendered_feel
    from motosim.sim.scenario import MultisineProfile, Scenario

    with deferred_warnings():  # the scenario's, once the files it names are read too
        base = load_scenario(args.scenario) if args.scenario else Scenario(name="default")
        folder = Path(args.scenario).parent if args.scenario else Path(".")
        scenario = feel_scenario(
            base,
            speed=args.speed,
            amplitude=args.amplitude,
            band=band,
            duration=duration,
            excitation="chirp" if chirp else "multisine",
            period=args.period,
            periods=args.periods,
            radius=args.radius,
        )
        cache = design_cache(args, quiet=getattr(args, "json", False))
        inputs, stack = resolve_cached(scenario, folder, cache)
    for option in ("--speed", "--duration", "--amplitude"):
        warn_atypical("fidelity", option, getattr(args, option[2:]))
    result = simulate(inputs, rng=np.random.default_rng(scenario.seed), stack=stack, keep=True)
    # the multibody motorcycle's reference is its own response in the run (no linear model)
    reference = inputs.sharp if inputs.multibody is None else None
    signals = (result.t, result["tau_r"], result["theta_h"], result["delta"], reference)
    probe = scenario.rider.probe
    if isinstance(probe, MultisineProfile):
        feel = periodic_feel(*signals, args.speed, probe=probe, band=band)
    else:
        feel = rendered_feel(*signals, args.speed, band=band)
    if not np.all(np.abs(feel.rendered) > 0.0):
        friction = inputs.true_handlebar.beta_s if scenario.handlebar.friction else 0.0
        raise MotosimError(
            f"--amplitude {args.amplitude:g}: the handlebar did not move, held by its dry "
            f"friction ({friction:.3g} N*m) with the rider's torque unobservable; expected a "
            "probe that breaks it away"
        )
    low, high = max(band[0], _TARGET_BAND[0]), min(band[1], _TARGET_BAND[1])
    magnitude, phase = feel.worst(low, high)
    median = feel.median(low, high)
    payload: dict[str, Any] = {
        "scenario": args.scenario or "",
        "speed": args.speed,
        "radius": args.radius,
        "reference": "linear model" if reference is not None else "the run's delta / tau_r",
        "excitation": probe.kind if probe is not None else "",
        "amplitude": args.amplitude,
        "band_hz": list(band),
        # the probe's run: a chirp over its duration, or periods averaged after one to settle
        "duration": scenario.duration,
        **({} if chirp else {"period": args.period, "periods": args.periods}),
        "worst_in": [low, high],
        "worst_magnitude_error_db": magnitude,
        "worst_phase_error_deg": phase,
        "median_magnitude_error_db": median[0],
        "median_phase_error_deg": median[1],
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
    where = "" if args.radius is None else f" in a {args.radius:g} m turn"
    print(
        f"rendered steering feel at {args.speed:g} m/s{where}: theta_h / tau_r against "
        f"delta / tau_r ({payload['reference']})"
    )
    print(
        f"  {payload['excitation']} of {args.amplitude:g} N*m peak over {band[0]:g}-{band[1]:g} Hz"
    )
    print(f"  worst over {low:g}-{high:g} Hz: {magnitude:.2f} dB, {phase:.1f} deg")
    print(f"  median over {low:g}-{high:g} Hz: {median[0]:.2f} dB, {median[1]:.1f} deg")
    title = "coherence" if chirp else "periodic"
    print(f"  {'f [Hz]':>7} {'error [dB]':>11} {'error [deg]':>12} {title:>10}")
    for k in range(0, feel.frequency.size, max(1, feel.frequency.size // 12)):
        print(
            f"  {feel.frequency[k]:7.2f} {feel.magnitude_error_db[k]:11.2f} "
            f"{feel.phase_error_deg[k]:12.1f} {feel.coherence[k]:10.3f}"
        )
    if "plot" in payload:
        print(f"wrote {payload['plot']}")
    return 0
