"""``motosim design``: the observer and the torque-feedback controller for a handlebar."""

import argparse
import math
import sys
import textwrap
from datetime import date
from typing import TYPE_CHECKING, Any

from motosim import __version__
from motosim.choices import GRIP_NAMES, INTEGRAL_CORNER, LOWEST_BANDWIDTH, MAX_ORDER
from motosim.cli._common import (
    check_output,
    parse_float_list,
    print_json,
    warn_atypical,
    write_text,
)
from motosim.errors import MotosimError, RunFailedError
from motosim.params import load_parameters
from motosim.params.checks import check_number, short_repr
from motosim.params.handlebar import HandlebarParameters

if TYPE_CHECKING:
    from motosim.control.statespace import StateSpace
    from motosim.control.torque_feedback import LoopAnalysis
    from motosim.estimation.walcott_zak import ObserverSettings
    from motosim.sim.grips import Hands
    from motosim.sim.loop_analysis import StackLoopAnalysis

MAX_SPEEDS = 20
"""Most speeds of the whole-stack analysis (each takes a 27-point grid)."""
SPEED_RANGE = (3.0, 60.0)
"""Speeds of Sharp's tables [m/s], where the analysis is meant."""

__all__ = ["INTEGRAL_CORNER", "MAX_ORDER", "MAX_STARTS", "register"]


MAX_STARTS = 32
"""Most random starts of the fixed-order search: a start at order 3 takes seconds, so 32
bound a run to minutes (the design guide gives the times)."""

MAX_SEED = 2**63 - 1
"""Largest seed (a 64-bit signed integer, as in a TOML file)."""

RATE_RANGE = (10.0, 100_000.0)
"""Control rates admitted [Hz]: a real-time loop runs at 100 Hz to tens of kHz."""


def register(sub: Any) -> None:
    """Add ``design`` to the subcommands."""
    parser = sub.add_parser(
        "design",
        help="design the rider-torque observer and the torque-feedback controller",
        description=(
            "Design the Walcott-Zak observer and the H-infinity loop-shaping controller of "
            "fixed order for a handlebar, analyse the loop (margins, tracking, rider-torque "
            "rejection, sampling, robustness over +/-50 % J_eq and beta_eq, +/-30 % N k_t) "
            "beside the paper's controller, and write one design file for the simulator and "
            "the real-time loop."
        ),
    )
    parser.add_argument(
        "--handlebar", default="simacom_handlebar", help="handlebar set or TOML file (identified)"
    )
    parser.add_argument(
        "--order", type=int, default=1, help=f"order of the tuned controller, 0-{MAX_ORDER} (1)"
    )
    parser.add_argument(
        "--bandwidth",
        type=float,
        default=None,
        help=(
            "tracking bandwidth [Hz] (default: 10; a fifth of --rate below 50 Hz; from 1 kHz up "
            "to 20 for a handlebar whose loop would be softer at 1 Hz than the packaged one's)"
        ),
    )
    parser.add_argument(
        "--integral-corner",
        type=float,
        default=INTEGRAL_CORNER,
        help=(
            "the loop-shaping weight's integral corner as a fraction of the bandwidth, "
            f"0-0.5 ({INTEGRAL_CORNER:g}; more tracks tighter below the bandwidth, with "
            "less phase margin)"
        ),
    )
    parser.add_argument("--rate", type=float, default=1000.0, help="control rate [Hz] (1000)")
    parser.add_argument(
        "--no-prediction",
        action="store_true",
        help=(
            "analyse the stack with the plain rider-torque cancellation (by default it is "
            "predicted over the estimate's lag from a 1 kHz rate and at 100 Hz, as a "
            "scenario's default)"
        ),
    )
    parser.add_argument(
        "--latency",
        type=float,
        default=0.0,
        help=(
            "age of the measurement when the stack reads it [s], 0 to one period of --rate "
            "(0): a status frame's latency on the bus; the stack is analysed accounting for "
            "it, beside the stack designed for a fresh sample read as old"
        ),
    )
    parser.add_argument(
        "--starts", type=int, default=8, help=f"starts of the search, 1-{MAX_STARTS} (8)"
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the starts (0)")
    parser.add_argument(
        "--speeds",
        default="10,20,30",
        help="speeds of the whole-stack analysis [m/s], comma-separated (10,20,30)",
    )
    parser.add_argument(
        "--grip",
        choices=GRIP_NAMES,
        default="off",
        help=(
            "the rider's grip to design for (off: the handlebar alone, what a design file "
            "holds); with a grip the observer, the controller and the stack model 0.4 of its "
            "inertia and damping, between holding and letting go, and the stack is analysed "
            "held and let go"
        ),
    )
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.add_argument(
        "--out", metavar="DESIGN.toml", help="write the design file (default: none)"
    )
    parser.add_argument(
        "--overwrite", action="store_true", help="replace the --out file if it exists"
    )
    parser.set_defaults(func=run)


def _analysis(a: "LoopAnalysis") -> dict[str, Any]:
    return {
        "four_block_gamma_unweighted": a.four_block_gamma,
        "closed_loop_poles": [[float(p.real), float(p.imag)] for p in a.closed_loop_poles],
        "gain_margin_db": a.gain_margin_db,
        "phase_margin_deg": a.phase_margin_deg,
        "crossover_rad_s": a.crossover,
        "tracking_bandwidth_hz": a.tracking_bandwidth,
        "stiffness_nm_per_rad": a.stiffness,
        "peak_compliance_rad_per_nm": a.peak_compliance,
        "tracking_error_1hz": a.tracking_error_1hz,
        "compliance_1hz_rad_per_nm": a.compliance_1hz,
        "discrete_spectral_radius": a.discrete_radius,
        "discrete_stable": {m: r < 1.0 for m, r in a.discrete_radius.items()},
        "robust_over_50_percent": a.robust_over_50_percent,
        "worst_perturbed_gamma_unweighted": a.worst_perturbed_gamma,
    }


def _stack(a: "StackLoopAnalysis") -> dict[str, Any]:
    return {
        "speed": a.speed,
        "stable": a.stable,
        "spectral_radius": a.spectral_radius,
        "gain_margin_db": a.gain_margin_db,
        "phase_margin_deg": a.phase_margin_deg,
        "modulus_margin": a.modulus_margin,
        "cancellation_gain_margin_db": a.cancellation_gain_margin_db,
        "cancellation_phase_margin_deg": a.cancellation_phase_margin_deg,
        "feel_error_db": a.feel_magnitude_db,
        "feel_error_deg": a.feel_phase_deg,
        "prediction_lead_s": a.prediction_lead,
        "measurement_delay_s": a.measurement_delay,
        "friction_limit_cycles": [
            {"frequency_hz": c.frequency, "amplitude_rad": c.amplitude} for c in a.limit_cycles
        ],
    }


def _stack_analysis(
    hb: HandlebarParameters,
    settings: "ObserverSettings",
    controller: "StateSpace",
    rate: float,
    speeds: list[float],
    prediction: bool | None,
    latency: float = 0.0,
    hands: "Hands | None" = None,
) -> list[dict[str, Any]]:
    """The whole sampled stack (observer, feedforward, motorcycle) at each speed, and its grid;
    with a ``latency`` [s], accounting for it, and (``unaccounted``) the stack designed for
    a fresh sample read as old; with ``hands``, the stack designed for them and held by
    them, and (``hands_off``) let go."""
    from motosim.estimation.walcott_zak import WalcottZakObserver, design_with
    from motosim.sim.grips import GRIPS, design_hands, held_handlebar
    from motosim.sim.loop_analysis import analyse_design

    designed = design_hands(hands)
    kernel = WalcottZakObserver(design_with(held_handlebar(hb, designed), settings), 1.0 / rate)
    sharp = load_parameters("sharp1971", "sharp")

    def analysed(account: bool, true_hands: "Hands | None" = hands) -> list[dict[str, Any]]:
        entries = []
        for nominal, grid in analyse_design(
            sharp,
            kernel.kernel,
            controller,
            hb,
            rate=rate,
            speeds=speeds,
            prediction=prediction,
            delay=latency,
            account=account,
            hands=designed,
            true_hands=true_hands,
        ):
            entry = _stack(nominal)
            entry["grid"] = {
                "points": grid.points,
                "unstable": grid.unstable,
                "with_margins": grid.with_margins,
                "worst_gain_margin_db": grid.gain_margin_db,
                "worst_phase_margin_deg": grid.phase_margin_deg,
                "worst_modulus_margin": grid.modulus_margin,
            }
            entries.append(entry)
        return entries

    out = analysed(True)
    if latency > 0.0:
        for entry, fresh in zip(out, analysed(False), strict=True):
            entry["unaccounted"] = fresh
    if hands is not None:
        for entry, off in zip(out, analysed(True, GRIPS["off"]), strict=True):
            entry["hands_off"] = off
    return out


def run(args: argparse.Namespace) -> int:
    """Design, report and optionally write the design file."""
    if not 0 <= args.order <= MAX_ORDER:
        raise MotosimError(
            f"--order {short_repr(args.order)}; expected an integer from 0 to {MAX_ORDER} "
            "(the shaped plant's order, which gives the full-order optimum)"
        )
    if not 1 <= args.starts <= MAX_STARTS:
        raise MotosimError(
            f"--starts {short_repr(args.starts)}; expected an integer from 1 to {MAX_STARTS}"
        )
    if not 0 <= args.seed <= MAX_SEED:
        raise MotosimError(
            f"--seed {short_repr(args.seed)}; expected an integer from 0 to 2^63 - 1"
        )
    check_number(args.rate, where="--rate", lower=RATE_RANGE[0], upper=RATE_RANGE[1], unit="Hz")
    check_number(args.latency, where="--latency", lower=0.0, upper=1.0 / args.rate, unit="s")
    if args.bandwidth is not None and not (
        math.isfinite(args.bandwidth) and LOWEST_BANDWIDTH <= args.bandwidth <= args.rate / 5
    ):
        raise MotosimError(
            f"--bandwidth {short_repr(args.bandwidth)} Hz; expected {LOWEST_BANDWIDTH:g} to "
            f"{args.rate / 5:g} Hz: at least the slowest of a rider's steering and at most a "
            f"fifth of the {args.rate:g} Hz control rate"
        )
    # the range of motosim.control.torque_feedback.check_options, before SciPy is imported
    if not (math.isfinite(args.integral_corner) and 1e-6 <= args.integral_corner <= 0.5):
        raise MotosimError(
            f"--integral-corner {short_repr(args.integral_corner)}: integral_corner = "
            f"{args.integral_corner!r}; expected a fraction of the bandwidth from 1e-06 to 0.5"
        )
    speeds = parse_float_list("--speeds", args.speeds, max_items=MAX_SPEEDS)
    for speed in speeds:
        check_number(
            speed, where="--speeds", lower=SPEED_RANGE[0], upper=SPEED_RANGE[1], unit="m/s"
        )
    if args.out is not None and args.grip != "off":
        raise MotosimError(
            f"--out with --grip {args.grip}: a design file holds the design for the handlebar "
            "alone; expected --grip off with --out (a scenario designs for its rider's grip "
            "itself: [controller] grip)"
        )
    if args.out is not None:
        check_output(
            args.out, overwrite=args.overwrite, reads=(("handlebar file", args.handlebar),)
        )
    from motosim.sim.grips import GRIPS, design_hands, held_handlebar

    bare = load_parameters(args.handlebar, "handlebar")
    hands = None if GRIPS[args.grip].is_off else GRIPS[args.grip]
    hb = held_handlebar(bare, design_hands(hands))  # what the observer and controller model
    import numpy as np

    from motosim.control.torque_feedback import (
        PAPER_CONTROLLER,
        PAPER_DEN,
        PAPER_NUM,
        analyse_loop,
        check_options,
        default_bandwidth,
        design_torque_feedback,
        handlebar_bandwidth,
    )
    from motosim.estimation.walcott_zak import design_with
    from motosim.io.design_file import dump_design
    from motosim.sim.closed_loop import observer_settings

    check_options(
        bandwidth=default_bandwidth(args.rate) if args.bandwidth is None else args.bandwidth,
        rate=args.rate,
        integral_corner=args.integral_corner,
    )
    warn_atypical("design", "--speeds", speeds)
    warn_atypical("design", "--rate", args.rate)
    if args.bandwidth is not None:
        warn_atypical("design", "--bandwidth", args.bandwidth)
    if not args.json:
        print(f"designing for {args.handlebar} ({args.starts} starts) ...", file=sys.stderr)
    bandwidth = args.bandwidth
    # every input is checked by now: the synthesis failing on them is a failed design (exit 3)
    try:
        if bandwidth is None:
            bandwidth, _ = handlebar_bandwidth(
                hb, rate=args.rate, n_starts=args.starts, seed=args.seed
            )
        ctrl = design_torque_feedback(
            hb,
            rng=np.random.default_rng(args.seed),
            bandwidth=bandwidth,
            order=args.order,
            rate=args.rate,
            n_starts=args.starts,
            integral_corner=args.integral_corner,
        )
    except MotosimError as err:
        raise RunFailedError(
            f"the design for {args.handlebar} at {args.rate:g} Hz"
            + ("" if bandwidth is None else f", {bandwidth:g} Hz bandwidth")
            + f", order {args.order} failed: {err}"
        ) from None
    settings = observer_settings(args.rate)
    obs = design_with(hb, settings)
    paper = analyse_loop(hb, PAPER_CONTROLLER, rate=args.rate)
    report: dict[str, Any] = {
        "handlebar": args.handlebar,
        "rate": args.rate,
        "controller": {
            "num": [float(v) for v in ctrl.num],
            "den": [float(v) for v in ctrl.den],
            "gamma": ctrl.gamma,
            "order": ctrl.order,
            "states": ctrl.controller.n_states,
            "bandwidth_hz": ctrl.bandwidth,
            "weight": {"gain": ctrl.weight_gain, "corner_rad_s": ctrl.weight_corner},
            "analysis": _analysis(ctrl.analysis),
        },
        "gamma_min": ctrl.gamma_min,
        "gamma_gap": ctrl.gamma / ctrl.gamma_min - 1.0,
        "paper_controller": {
            "num": list(PAPER_NUM),
            "den": list(PAPER_DEN),
            "gamma": paper.four_block_gamma,
            "analysis": _analysis(paper),
        },
        "grip": args.grip,
        "stack": _stack_analysis(
            bare,
            settings,
            ctrl.controller_zoh,
            args.rate,
            speeds,
            False if args.no_prediction else None,
            args.latency,
            hands,
        ),
        "observer": {
            "poles": list(settings.poles),
            "damping_factor": settings.damping_factor,
            "inertia_factor": settings.inertia_factor,
            "eta": obs.eta,
            "epsilon": obs.epsilon,
            "L": obs.L.tolist(),
            "P": obs.P.tolist(),
            "F": np.atleast_1d(obs.F).tolist(),
        },
    }
    if args.out is not None:
        text = dump_design(
            header={
                "version": __version__,
                "date": str(date.today()),
                "handlebar": args.handlebar,
                "rate": args.rate,
            },
            handlebar=hb,
            observer=settings,
            observer_matrices={"L": obs.L, "P": obs.P, "F": np.atleast_1d(obs.F)},
            controller={
                "bandwidth": ctrl.bandwidth,
                "order": ctrl.order,
                "gamma": ctrl.gamma,
                "gamma_min": ctrl.gamma_min,
                "weight_gain": ctrl.weight_gain,
                "weight_corner": ctrl.weight_corner,
                "num": ctrl.num,
                "den": ctrl.den,
            },
            continuous=ctrl.controller,
            discrete={"zoh": ctrl.controller_zoh, "tustin": ctrl.controller_tustin},
            paper_controller={
                "num": list(PAPER_NUM),
                "den": list(PAPER_DEN),
                "gamma": paper.four_block_gamma,
            },
        )
        report["out"] = str(write_text(args.out, text))
    if args.json:
        print_json(report)
    else:
        _print(report)
    return 0


def _poly(coefficients: list[float]) -> str:
    n = len(coefficients) - 1
    terms = [
        f"{c:.5g}" + (f" s^{n - k}" if n - k > 1 else " s" if n - k == 1 else "")
        for k, c in enumerate(coefficients)
        if c != 0.0
    ]
    return " + ".join(terms).replace("+ -", "- ")


def _show(value: float) -> str:
    return f"{value:.4g}"


def _print(report: dict[str, Any]) -> None:
    c = report["controller"]
    a = c["analysis"]
    p = report["paper_controller"]["analysis"]
    print(f"controller K(s) = ({_poly(c['num'])}) / ({_poly(c['den'])})  [A/rad]")
    print(
        f"  tuned order {c['order']} on the shaped plant at {c['bandwidth_hz']:.3g} Hz: gamma "
        f"{c['gamma']:.4f}, full-order optimum {report['gamma_min']:.4f} "
        f"(+{100 * report['gamma_gap']:.2f} %)"
    )
    print(
        "the controller alone on this handlebar (no observer, no motorcycle): ours, just\n"
        "designed, beside the paper's published eq. (26), K(s) = (-2.355 s - 613.7) / "
        "(s + 1445) A/rad"
    )
    print(f"{'':30}{'ours':>14}{'paper eq. (26)':>18}")
    rows = [
        ("phase margin [deg]", "phase_margin_deg", 1.0),
        ("crossover [Hz]", "crossover_rad_s", 1.0 / (2.0 * math.pi)),
        ("tracking bandwidth [Hz]", "tracking_bandwidth_hz", 1.0),
        ("tracking error at 1 Hz [1]", "tracking_error_1hz", 1.0),
        ("stiffness [N*m/rad]", "stiffness_nm_per_rad", 1.0),
        ("compliance at 1 Hz [rad/(N*m)]", "compliance_1hz_rad_per_nm", 1.0),
    ]
    for label, key, scale in rows:
        print(f"  {label:<28}{_show(scale * a[key]):>14}{_show(scale * p[key]):>18}")
    crossover = p["crossover_rad_s"] / (2.0 * math.pi)
    for text in (
        "tracking bandwidth: where theta_h / delta falls 3 dB; tracking error: "
        "|theta_h - delta| / |delta| for a 1 Hz steer; stiffness: the static rider torque per "
        "rad the handlebar yields (inf: integral action holds the angle against a steady "
        "torque); compliance: the angle a 1 Hz rider torque moves it.",
        f"The paper's controller is evaluated as published, not broken: its loop crosses over "
        f"at {_show(crossover)} Hz on this handlebar, so the handlebar follows the steer angle "
        f"only below {_show(p['tracking_bandwidth_hz'])} Hz and yields "
        f"{_show(p['stiffness_nm_per_rad'])} N*m/rad to a steady torque (its gamma* 2.5587 is "
        "set by its high-frequency gain alone, sqrt(1 + 2.355^2): docs/paper.md). motosim "
        'keeps it as [controller] kind = "paper"; ours is the default.',
    ):
        print(textwrap.fill(text, 100, initial_indent="  ", subsequent_indent="  "))
    print(
        f"  discrete loop at {report['rate']:g} Hz stable: {a['discrete_stable']}; "
        f"stable over +/-50 % J_eq, beta_eq: {a['robust_over_50_percent']}"
    )
    print(f"  paper controller four-block gamma (W = 1): {report['paper_controller']['gamma']:.4f}")
    latency = report["stack"][0]["measurement_delay_s"] if report["stack"] else 0.0
    read = f", the measurement read {1e3 * latency:.3g} ms old and accounted for" if latency else ""
    held = (
        f", designed for and held by the {report['grip']} grip (hands off: let go)"
        if report["grip"] != "off"
        else ""
    )
    print(
        f"whole stack at {report['rate']:g} Hz (observer, feedforward, motorcycle; sampled, "
        f"linearised without dry friction{read}{held}):"
    )
    print(
        f"  {'speed':>6} {'stable':>7} {'GM [dB]':>8} {'PM [deg]':>9} {'|1+L| min':>10} "
        f"{'feel dB':>8} {'feel deg':>9}  grid +/-50 % J, beta, +/-30 % N k_t"
    )
    for a in report["stack"]:
        g = a["grid"]
        print(
            f"  {a['speed']:6.3g} {a['stable']!s:>7} {a['gain_margin_db']:8.3g} "
            f"{a['phase_margin_deg']:9.3g} {a['modulus_margin']:10.3g} "
            f"{a['feel_error_db']:8.2g} {a['feel_error_deg']:9.2g}  "
            f"{g['points'] - g['unstable']}/{g['points']} stable "
            f"({g['with_margins']} with 6 dB, 45 deg), worst GM "
            f"{g['worst_gain_margin_db']:.3g} dB, PM {g['worst_phase_margin_deg']:.3g} deg"
        )
        lead = a["prediction_lead_s"]
        print(
            f"         the rider-torque cancellation's own loop (broken at the estimate"
            f"{f', predicted {1e3 * lead:.3g} ms ahead' if lead > 0 else ''}): "
            f"GM {a['cancellation_gain_margin_db']:.3g} dB, "
            f"PM {a['cancellation_phase_margin_deg']:.3g} deg"
        )
        for key, label in (
            ("hands_off", "hands off"),
            ("unaccounted", f"designed for a fresh sample, read {1e3 * latency:.3g} ms old"),
        ):
            other = a.get(key)
            if other is not None:
                g = other["grid"]
                print(
                    f"         {label}: stable {other['stable']}, GM "
                    f"{other['gain_margin_db']:.3g} dB, PM {other['phase_margin_deg']:.3g} deg; "
                    f"grid {g['points'] - g['unstable']}/{g['points']} stable "
                    f"({g['with_margins']} with 6 dB, 45 deg)"
                )
        for c in a["friction_limit_cycles"]:
            print(
                f"         dry friction can sustain a limit cycle at {c['frequency_hz']:.3g} Hz, "
                f"{1e3 * c['amplitude_rad']:.2g} mrad"
            )
    if "out" in report:
        print(f"wrote {report['out']}")
