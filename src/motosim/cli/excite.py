"""``motosim excite``: simulate an identification run of the handlebar and log it as CSV."""

import argparse
import math
from typing import Any

from motosim.cli._common import check_output, print_json, warn_atypical
from motosim.errors import MotosimError, warn
from motosim.params import HandlebarParameters, load_parameters
from motosim.params.checks import check_number, short_repr

__all__ = ["register"]


def register(sub: Any) -> None:
    """Add ``excite`` to the subcommands."""
    parser = sub.add_parser(
        "excite",
        help="simulate an open-loop excitation run of the handlebar (section II.D)",
        description=(
            "Drive the simulated handlebar with a chirp or bipolar rectangular voltage (rider "
            "torque zero), measure it like the rig (sampling, encoder quantisation, current "
            "noise) and write t [s], theta_h [rad], i_m [A], u [V] as CSV."
        ),
    )
    parser.add_argument("--signal", choices=("chirp", "square"), default="chirp")
    parser.add_argument("--duration", type=float, default=60.0, help="length [s] (60)")
    parser.add_argument("--rate", type=float, default=100.0, help="sample rate [Hz] (100)")
    parser.add_argument("--amplitude", type=float, default=3.0, help="voltage amplitude [V] (3)")
    parser.add_argument("--f0", type=float, default=0.1, help="chirp start [Hz] (0.1)")
    parser.add_argument("--f1", type=float, default=2.0, help="chirp end [Hz] (2)")
    parser.add_argument("--frequency", type=float, default=0.5, help="rectangle [Hz] (0.5)")
    parser.add_argument(
        "--counts", type=int, default=2048, help="encoder counts per revolution (2048)"
    )
    parser.add_argument(
        "--pulley-ratio", type=float, default=12.0, help="encoder turns per handlebar turn (12)"
    )
    parser.add_argument(
        "--current-noise", type=float, default=0.05, help="current-sensor noise std [A] (0.05)"
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the noise (0)")
    parser.add_argument(
        "--handlebar", default="simacom_handlebar", help="handlebar set name or TOML file"
    )
    parser.add_argument(
        "--out", help="CSV log to write (with --plan: the current command; default: none)"
    )
    parser.add_argument("--json", action="store_true", help="print a JSON summary")
    parser.add_argument(
        "--overwrite", action="store_true", help="replace the --out file if it exists"
    )
    plan = parser.add_argument_group(
        "planning an identification run on the rig (--plan)",
        "recommend the current chirp that makes J_eq, beta_eq and beta_s identifiable, from "
        "rough values (--handlebar, or the three options below), the rig's --rate and its "
        "current limit; --out then writes the command t [s], i_cmd [A]",
    )
    plan.add_argument("--plan", action="store_true", help="recommend instead of simulating")
    plan.add_argument(
        "--max-current",
        type=float,
        help="current limit of the drive [A] (required with --plan; no default)",
    )
    plan.add_argument(
        "--inertia", type=float, help="rough J_eq [kg*m^2] (default: from --handlebar)"
    )
    plan.add_argument(
        "--damping", type=float, help="rough beta_eq [N*m*s/rad] (default: from --handlebar)"
    )
    plan.add_argument(
        "--dry-friction", type=float, help="rough beta_s [N*m] (default: from --handlebar)"
    )
    plan.add_argument("--ratio", type=float, help="belt ratio N (default: from --handlebar)")
    plan.add_argument(
        "--torque-constant", type=float, help="k_t [N*m/A] (default: from --handlebar)"
    )
    plan.add_argument(
        "--angle-limit", type=float, default=0.5, help="largest angle from the start [rad] (0.5)"
    )
    parser.set_defaults(func=run)


def _plan(args: argparse.Namespace) -> int:
    """Recommend the chirp, print it, optionally write the current command."""
    if args.max_current is None:
        raise MotosimError("--plan needs --max-current A; expected the drive's current limit")
    if args.out:
        check_output(
            args.out, overwrite=args.overwrite, reads=(("handlebar file", args.handlebar),)
        )
    hb = load_parameters(args.handlebar, "handlebar")
    given = {
        "J_eq": args.inertia,
        "beta_eq": args.damping,
        "beta_s": args.dry_friction,
        "N": args.ratio,
        "k_t": args.torque_constant,
    }
    options = {
        "J_eq": "--inertia",
        "beta_eq": "--damping",
        "beta_s": "--dry-friction",
        "N": "--ratio",
        "k_t": "--torque-constant",
    }
    for name, value in given.items():
        if value is not None:
            spec = HandlebarParameters.SPECS[name]
            check_number(
                value,
                where=options[name],
                lower=spec.lower,
                upper=spec.upper,
                lower_closed=spec.lower_closed,
                upper_closed=spec.upper_closed,
                unit=spec.unit,
            )
    check_number(args.max_current, where="--max-current", lower=0.01, upper=1000.0, unit="A")
    check_number(args.angle_limit, where="--angle-limit", lower=1e-3, upper=math.pi, unit="rad")
    rough = {name: getattr(hb, name) if value is None else value for name, value in given.items()}
    import numpy as np

    from motosim.identification import plan_excitation
    from motosim.io import write_log
    from motosim.timeseries import TimeSeries

    plan = plan_excitation(
        J_eq=rough["J_eq"],
        beta_eq=rough["beta_eq"],
        beta_s=rough["beta_s"],
        torque_per_amp=rough["N"] * rough["k_t"],
        sample_rate=args.rate,
        max_current=args.max_current,
        angle_limit=args.angle_limit,
        encoder_counts=round(args.counts * args.pulley_ratio),
    )
    summary: dict[str, Any] = {
        "f0": plan.f0,
        "f1": plan.f1,
        "amplitude": plan.amplitude,
        "duration": plan.duration,
        "sample_rate": args.rate,
        "inertia_share": plan.inertia_share,
        "counts_at_f1": plan.counts_at_f1,
        "notes": list(plan.notes),
    }
    if args.out:
        t = np.arange(round(plan.duration * args.rate) + 1) / args.rate
        phase = plan.f0 * t + 0.5 * (plan.f1 - plan.f0) / plan.duration * t**2
        command = plan.amplitude * np.sin(2.0 * np.pi * phase)
        summary["out"] = str(write_log(args.out, TimeSeries(t, command[:, None], ("i_cmd",))))
    warn_atypical("excite", "--rate", args.rate)
    if args.json:
        print_json(summary)
        return 0
    print(
        f"chirp {plan.f0:.3g}-{plan.f1:.3g} Hz, {plan.amplitude:.3g} A, {plan.duration:.3g} s at "
        f"{args.rate:g} Hz: J theta'' reaches {100 * plan.inertia_share:.2g} % of beta theta' "
        f"at the top, where the angle moves {plan.counts_at_f1:.3g} encoder counts"
    )
    for note in plan.notes:
        print(f"  note: {note}")
    if "out" in summary:
        print(f"  wrote the current command to {summary['out']}")
    return 0


_MAX_SAMPLES = 10_000_000  # samples of one excitation log (a few hundred MB at most)


def _check_options(args: argparse.Namespace) -> None:
    """Refuse absurd options in one line before any work or allocation."""
    check_number(args.rate, where="--rate", lower=1.0, upper=1e5, unit="Hz")
    check_number(
        args.duration, where="--duration", lower=0.0, lower_closed=False, upper=3600.0, unit="s"
    )
    if args.duration * args.rate > _MAX_SAMPLES:
        raise MotosimError(
            f"--duration x --rate = {args.duration * args.rate:.3g} samples; expected at most "
            f"{_MAX_SAMPLES:.0e}"
        )
    check_number(args.amplitude, where="--amplitude", lower=1e-3, upper=100.0, unit="V")
    check_number(args.f0, where="--f0", lower=1e-3, upper=args.rate / 2, unit="Hz")
    check_number(args.f1, where="--f1", lower=1e-3, upper=args.rate / 2, unit="Hz")
    check_number(args.frequency, where="--frequency", lower=1e-3, upper=args.rate / 2, unit="Hz")
    check_number(args.counts, where="--counts", lower=1.0, upper=2.0**32)
    check_number(args.pulley_ratio, where="--pulley-ratio", lower=1e-3, upper=1000.0)
    check_number(args.current_noise, where="--current-noise", lower=0.0, upper=100.0, unit="A")
    if not 0 <= args.seed < 2**63:
        raise MotosimError(f"--seed {short_repr(args.seed)}; expected an integer 0 to 2^63 - 1")


def run(args: argparse.Namespace) -> int:
    """Simulate, measure and write the run (or, with --plan, recommend one)."""
    _check_options(args)
    if args.plan:
        return _plan(args)
    if not args.out:
        raise MotosimError("excite needs --out RUN.csv; expected the log file to write")
    check_output(args.out, overwrite=args.overwrite, reads=(("handlebar file", args.handlebar),))
    hb = load_parameters(args.handlebar, "handlebar")
    if args.signal == "chirp" and args.f0 > args.f1:
        warn(
            f"--f0 {args.f0:g} Hz is above --f1 {args.f1:g} Hz: a down-chirp, from high to low "
            "frequencies; legal, but an identification run usually sweeps up (swap them if "
            "that is what was meant)"
        )
    import numpy as np

    from motosim.identification import MeasurementModel, excitation_run
    from motosim.io import write_log

    measurement = MeasurementModel(
        sample_rate=args.rate,
        counts_per_revolution=args.counts,
        pulley_ratio=args.pulley_ratio,
        current_noise=args.current_noise,
    )
    log = excitation_run(
        hb,
        args.signal,
        args.duration,
        measurement,
        np.random.default_rng(args.seed),
        amplitude=args.amplitude,
        f0=args.f0,
        f1=args.f1,
        frequency=args.frequency,
    )
    for option in ("--duration", "--rate", "--current-noise", "--amplitude", "--counts"):
        warn_atypical("excite", option, getattr(args, option[2:].replace("-", "_")))
    columns = ("theta_h", "i_m", "u")
    log = type(log)(log.t, np.column_stack([log[c] for c in columns]), columns)
    path = write_log(args.out, log)
    # the excitation's settings, as --plan names them: what made the log, to run it again
    frequencies = (
        {"f0": args.f0, "f1": args.f1} if args.signal == "chirp" else {"frequency": args.frequency}
    )
    summary = {
        "out": str(path),
        "samples": int(log.t.size),
        "sample_rate": args.rate,
        "signal": args.signal,
        "amplitude": args.amplitude,
        **frequencies,
        "duration": args.duration,
        "seed": args.seed,
        "theta_h_range": [float(log["theta_h"].min()), float(log["theta_h"].max())],
        "i_m_peak": float(np.abs(log["i_m"]).max()),
        "units": {"sample_rate": "Hz", "amplitude": "V"}
        | dict.fromkeys(frequencies, "Hz")
        | {"duration": "s", "theta_h_range": "rad", "i_m_peak": "A"},
    }
    if args.json:
        print_json(summary)
    else:
        print(
            f"wrote {path}: {log.t.size} samples at {args.rate:g} Hz, theta_h in "
            f"[{summary['theta_h_range'][0]:.3f}, {summary['theta_h_range'][1]:.3f}] rad, "
            f"peak current {summary['i_m_peak']:.2f} A"
        )
    return 0
