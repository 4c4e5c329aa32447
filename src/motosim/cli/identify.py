"""``motosim identify``: J_eq, beta_eq and beta_s of the handlebar from an excitation log."""

import argparse
import dataclasses
import math
from datetime import date
from pathlib import Path
from typing import Any

from motosim.cli._common import (
    check_figure_path,
    check_input,
    check_output,
    print_json,
    save_figure,
    write_text,
)
from motosim.errors import MotosimError
from motosim.params import ParameterSet, dump_parameter_set, load_parameter_set
from motosim.params.checks import check_number
from motosim.params.handlebar import HandlebarParameters

__all__ = ["DRIVES", "METHODS", "register"]

METHODS = ("output_error", "lsq", "rls", "gradient")
"""The choices of ``--method``, the default first: :data:`motosim.identification.METHODS`,
written out so that the parser is built without importing SciPy (a unit test checks that they
are equal)."""

DRIVES = ("current_held", "voltage_held", "current_sampled")
"""The choices of ``--drive`` besides ``auto``:
:data:`motosim.identification.output_error.DRIVES`, written out likewise."""


def register(sub: Any) -> None:
    """Add ``identify`` to the subcommands."""
    parser = sub.add_parser(
        "identify",
        help="identify the handlebar's inertia and frictions from an excitation log",
        description=(
            "Identify J_eq, beta_eq and beta_s of eq. (5) from a CSV log with columns t [s], "
            "theta_h [rad] and a current: i_m [A] (measured, continuous), i_cmd [A] (a "
            "set-point held by a current drive) and/or u [V] (a voltage held by a voltage "
            "drive); rider hands off. Units in the header (t [ms], theta_h (deg)) are "
            "converted; a ';' or tab delimiter, a decimal comma and '#' comments are read."
        ),
    )
    parser.add_argument("log", help="CSV log, e.g. from motosim excite or the rig")
    parser.add_argument(
        "--handlebar",
        default="simacom_handlebar",
        help="handlebar set or TOML file giving the motor constants (simacom_handlebar)",
    )
    parser.add_argument("--ratio", type=float, help="belt ratio N (default: from --handlebar)")
    parser.add_argument(
        "--torque-constant", type=float, help="motor k_t [N*m/A] (default: from --handlebar)"
    )
    parser.add_argument(
        "--columns",
        metavar="MAP",
        help=(
            "the log's columns for motosim's signals, with units: e.g. "
            "t=time:ms,theta_h=angle_deg:deg,i_m=cur:A (units s, ms, us, rad, deg, A, mA, V, "
            "mV) (default: the columns t, theta_h, i_m in their header's units, else s, rad, A)"
        ),
    )
    parser.add_argument("--method", choices=METHODS, default="output_error")
    parser.add_argument(
        "--drive",
        choices=("auto", *DRIVES),
        default="auto",
        help=(
            "what the motor torque did between samples; auto (default) follows the columns: "
            "i_cmd -> current_held, u with i_m -> voltage_held, i_m only -> current_sampled"
        ),
    )
    parser.add_argument(
        "--current-delay",
        type=float,
        default=0.0,
        metavar="S",
        help="how late the logged current is [s], e.g. one sample of CAN latency (0)",
    )
    parser.add_argument(
        "--validate",
        metavar="LOG",
        help="a second run to replay the identified model on (default: none)",
    )
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.add_argument(
        "--out", metavar="PARAMS.toml", help="write a handlebar parameter file (default: none)"
    )
    parser.add_argument(
        "--overwrite", action="store_true", help="replace the --out and --plot files if they exist"
    )
    parser.add_argument(
        "--plot",
        metavar="FIG.png",
        help="fit, validation, input, residual and parameters (default: none)",
    )
    parser.set_defaults(func=run)


def _motor(args: argparse.Namespace) -> ParameterSet:
    base = load_parameter_set(args.handlebar)
    if base.model != "handlebar":
        raise MotosimError(f"{args.handlebar}: is a {base.model} set; expected a handlebar set")
    changes: dict[str, float] = {}
    for option, name, value in (
        ("--ratio", "N", args.ratio),
        ("--torque-constant", "k_t", args.torque_constant),
    ):
        if value is not None:
            if not (math.isfinite(value) and value > 0):
                raise MotosimError(f"{option} {value!r}; expected a finite number > 0")
            changes[name] = value
    if not changes:
        return base
    sources = dict(base.sources)
    sources.update(dict.fromkeys(changes, "given on the command line"))
    assert isinstance(base.values, HandlebarParameters)
    values = dataclasses.replace(base.values, **changes)
    return dataclasses.replace(base, values=values, sources=sources)


_NAMES = ("J_eq", "beta_eq", "beta_s")
_UNITS = {"J_eq": "kg*m^2", "beta_eq": "N*m*s/rad", "beta_s": "N*m"}


def run(args: argparse.Namespace) -> int:
    """Identify, report, and optionally write the parameter file and the figure."""
    check_input(args.log, "log file (CSV)", text=True)
    if args.validate:
        check_input(args.validate, "log file (CSV)", text=True)
    if args.plot:
        check_figure_path(args.plot, overwrite=args.overwrite)
    if args.out:
        check_output(args.out, overwrite=args.overwrite, suffixes=(".toml",))
    motor = _motor(args)
    hb = motor.values
    assert isinstance(hb, HandlebarParameters)
    from motosim.io import parse_columns, read_rig_log

    columns = parse_columns(args.columns) if args.columns else None
    # its bound by the log's length is checked once the log is read
    check_number(args.current_delay, where="--current-delay", lower=0.0, upper=1.0, unit="s")
    from motosim.identification import back_emf_damping, drive_from_columns, identify, validate

    rig = read_rig_log(args.log, required=("theta_h",), columns=columns)
    second = (
        read_rig_log(args.validate, required=("theta_h",), columns=columns)
        if args.validate
        else None
    )
    log = rig.series
    span = float(log.t[-1] - log.t[0])
    check_number(
        args.current_delay, where="--current-delay", lower=0.0, upper=min(1.0, span / 10), unit="s"
    )
    drive = args.drive if args.drive != "auto" else drive_from_columns(log.names)[0]
    est = identify(
        log,
        torque_per_amp=hb.torque_per_amp,
        method=args.method,
        drive=args.drive,
        back_emf_damping=back_emf_damping(hb) if drive == "voltage_held" else 0.0,
        current_delay=args.current_delay,
    )
    fit = validate(est, log, torque_per_amp=hb.torque_per_amp, current_delay=args.current_delay)
    replay = (
        validate(
            est, second.series, torque_per_amp=hb.torque_per_amp, current_delay=args.current_delay
        )
        if second is not None
        else None
    )
    report: dict[str, Any] = {name: getattr(est, name) for name in _NAMES}
    if est.confidence is not None:
        for name, (lo, hi) in zip(_NAMES, est.confidence, strict=True):
            report[f"{name}_ci95"] = [float(lo), float(hi)]
    report.update(
        {
            "units": dict(_UNITS),
            "method": est.method,
            "drive": est.drive,
            "drive_reason": est.drive_reason,
            "nrmse": est.nrmse,
            "segment_nrmse": est.segment_nrmse,
            "samples": int(log.t.size),
            "sample_rate": float(1.0 / rig.timing.period),
            "timing": rig.timing.describe(),
            "torque_per_amp": hb.torque_per_amp,
            "warnings": list(est.warnings),
        }
    )
    if replay is not None:
        report["validation_nrmse"] = replay.nrmse
        # a model that fits its own log much better than another run does not generalise
        if replay.nrmse > max(3.0 * est.nrmse, 0.05):
            report["warnings"].append(
                f"the model does not generalise: validation NRMSE {replay.nrmse:.3g} against "
                f"{est.nrmse:.3g} on the identification log; check the drive (--drive), the "
                "current delay (--current-delay) and that the two runs share the handlebar"
            )
    if args.out:
        report["out"] = str(_write(args, motor, est))
    if args.plot:
        from motosim.plotting import plot_identification

        fig = plot_identification(
            fit=fit,
            validation=replay,
            estimate=est.parameters,
            confidence=est.confidence,
            history_t=est.history_t,
            history=est.history,
            title=f"{Path(args.log).name}: method {est.method}, drive {est.drive}",
        )
        report["plot"] = str(save_figure(fig, args.plot))
    if args.json:
        print_json(report)
    else:
        _print(report)
    return 0


def _write(args: argparse.Namespace, motor: ParameterSet, est: Any) -> Path:
    from motosim.identification import identified_parameters

    hb = identified_parameters(est, motor.values)  # type: ignore[arg-type]
    note = (
        f"identified by motosim identify from {Path(args.log).name} on {date.today()} "
        f"(method {est.method}, drive {est.drive}, NRMSE {est.nrmse:.3g})"
    )
    sources = dict(motor.sources)
    for k, name in enumerate(_NAMES):
        interval = ""
        if est.confidence is not None:
            lo, hi = est.confidence[k]
            interval = f"; 95 % interval {lo:.4g} .. {hi:.4g} {_UNITS[name]}"
        sources[name] = note + interval
    pset = ParameterSet(
        name=Path(args.out).stem,
        model="handlebar",
        title=f"handlebar identified from {Path(args.log).name}",
        source=note,
        values=hb,
        sources=sources,
    )
    return write_text(args.out, dump_parameter_set(pset))


def _print(report: dict[str, Any]) -> None:
    print(
        f"{report['samples']} samples at {report['sample_rate']:.4g} Hz ({report['timing']}); "
        f"method {report['method']}, drive {report['drive']} ({report['drive_reason']})"
    )
    for name in _NAMES:
        key = f"{name}_ci95"
        interval = (
            f"  95 % interval {report[key][0]:.4g} .. {report[key][1]:.4g}" if key in report else ""
        )
        print(f"  {name:<8} {report[name]:10.5g} {_UNITS[name]:<10}{interval}")
    print(
        "  NRMSE = RMS(simulated - measured angle) / RMS(measured angle - its mean); "
        "0 is a perfect fit, 1 no better than the mean"
    )
    if report["segment_nrmse"] is not None and math.isfinite(report["segment_nrmse"]):
        print(
            f"  fit NRMSE {report['segment_nrmse']:.4f} (the fit's criterion: restarted from "
            "the measured angle every second)"
        )
    print(
        f"  replay NRMSE {report['nrmse']:.4f} (one open-loop run of the identification log: "
        "a small torque offset or stick-slip position error accumulates over its length)"
    )
    if "validation_nrmse" in report:
        print(
            f"  validation NRMSE {report['validation_nrmse']:.4f} (one open-loop run of --validate)"
        )
    for warning in report["warnings"]:
        print(f"  warning: {warning}")
    for key in ("out", "plot"):
        if key in report:
            print(f"  wrote {report[key]}")
