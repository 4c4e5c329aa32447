"""``motosim identify``: J_eq, beta_eq and beta_s of the handlebar from an excitation log."""

import argparse
import dataclasses
from datetime import date
from pathlib import Path
from typing import Any

import numpy as np

from motosim.cli._common import check_figure_path, print_json, save_figure, write_text
from motosim.errors import MotosimError
from motosim.identification import (
    METHODS,
    back_emf_damping,
    identified_parameters,
    identify,
    is_voltage_driven,
    validate,
)
from motosim.identification.output_error import DRIVES
from motosim.io import read_log
from motosim.params import ParameterSet, dump_parameter_set, load_parameter_set
from motosim.params.handlebar import HandlebarParameters

__all__ = ["register"]

_COLUMNS = ("theta_h", "i_m")


def register(sub: Any) -> None:
    """Add ``identify`` to the subcommands."""
    parser = sub.add_parser(
        "identify",
        help="identify the handlebar's inertia and frictions from an excitation log",
        description=(
            "Identify J_eq, beta_eq and beta_s of eq. (5) from a CSV log with columns t [s], "
            "theta_h [rad] and i_m [A], uniformly sampled, rider hands off."
        ),
    )
    parser.add_argument("log", help="CSV log, e.g. from motosim excite")
    parser.add_argument(
        "--handlebar",
        default="simacom_handlebar",
        help="handlebar set or TOML file giving the motor constants (simacom_handlebar)",
    )
    parser.add_argument("--ratio", type=float, help="belt ratio N (default: from --handlebar)")
    parser.add_argument(
        "--torque-constant", type=float, help="motor k_t [N*m/A] (default: from --handlebar)"
    )
    parser.add_argument("--method", choices=METHODS, default="output_error")
    parser.add_argument(
        "--drive",
        choices=("auto", *DRIVES),
        default="auto",
        help=(
            "what the motor torque did between samples; auto: the best fitting drive, "
            "voltage_held among them (and preferred in a tie) when the log's current follows "
            "its voltage u by eq. (7)"
        ),
    )
    parser.add_argument(
        "--validate", metavar="LOG", help="a second run to replay the identified model on"
    )
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.add_argument("--out", metavar="PARAMS.toml", help="write a handlebar parameter file")
    parser.add_argument("--plot", metavar="FIG.png", help="convergence and validation figure")
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
            if not (np.isfinite(value) and value > 0):
                raise MotosimError(f"{option} {value!r}; expected a finite number > 0")
            changes[name] = value
    if not changes:
        return base
    sources = dict(base.sources)
    sources.update(dict.fromkeys(changes, "given on the command line"))
    assert isinstance(base.values, HandlebarParameters)
    values = dataclasses.replace(base.values, **changes)
    return dataclasses.replace(base, values=values, sources=sources)


def run(args: argparse.Namespace) -> int:
    """Identify, report, and optionally write the parameter file and the figure."""
    for path in (args.plot,):
        if path:
            check_figure_path(path)
    motor = _motor(args)
    hb = motor.values
    assert isinstance(hb, HandlebarParameters)
    log = read_log(args.log, required=_COLUMNS)
    second = read_log(args.validate, required=_COLUMNS) if args.validate else None
    # a log whose current follows its voltage by eq. (7) may come from a voltage command: that
    # drive is tried too, and taken when the fits cannot tell the drives apart
    voltage = is_voltage_driven(log, torque_per_amp=hb.torque_per_amp)
    est = identify(
        log,
        torque_per_amp=hb.torque_per_amp,
        method=args.method,
        drive=args.drive,
        back_emf_damping=back_emf_damping(hb) if voltage or args.drive == "voltage_held" else 0.0,
        tie_preference="voltage_held" if voltage else "current_sampled",
    )
    replay = validate(est, second or log, torque_per_amp=hb.torque_per_amp)
    report: dict[str, Any] = {
        "J_eq": est.J_eq,
        "beta_eq": est.beta_eq,
        "beta_s": est.beta_s,
        "method": est.method,
        "drive": est.drive,
        "nrmse": est.nrmse,
        "samples": int(log.t.size),
        "sample_rate": float((log.t.size - 1) / (log.t[-1] - log.t[0])),
        "torque_per_amp": hb.torque_per_amp,
    }
    if est.confidence is not None:
        report["confidence_95"] = {
            name: [float(lo), float(hi)]
            for name, (lo, hi) in zip(("J_eq", "beta_eq", "beta_s"), est.confidence, strict=True)
        }
    if second is not None:
        report["validation_nrmse"] = replay.nrmse
    if args.out:
        report["out"] = str(_write(args, motor, est))
    if args.plot:
        from motosim.plotting import plot_identification

        fig = plot_identification(
            t=replay.t,
            measured=replay.theta_h_measured,
            simulated=replay.theta_h,
            estimate=est.parameters,
            history_t=est.history_t,
            history=est.history,
            title=f"{Path(args.validate or args.log).name}: replay, NRMSE {replay.nrmse:.3f}",
        )
        report["plot"] = str(save_figure(fig, args.plot))
    if args.json:
        print_json(report)
    else:
        _print(report)
    return 0


def _write(args: argparse.Namespace, motor: ParameterSet, est: Any) -> Path:
    hb = identified_parameters(est, motor.values)  # type: ignore[arg-type]
    note = (
        f"identified by motosim identify from {Path(args.log).name} on {date.today()} "
        f"(method {est.method}, drive {est.drive}, NRMSE {est.nrmse:.3g})"
    )
    sources = dict(motor.sources)
    sources.update(dict.fromkeys(("J_eq", "beta_eq", "beta_s"), note))
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
    ci = report.get("confidence_95", {})
    print(
        f"{report['samples']} samples at {report['sample_rate']:.4g} Hz, method "
        f"{report['method']}, drive {report['drive']}"
    )
    for name, unit in (("J_eq", "kg*m^2"), ("beta_eq", "N*m*s/rad"), ("beta_s", "N*m")):
        interval = f"  (95 %: {ci[name][0]:.4g} .. {ci[name][1]:.4g})" if name in ci else ""
        print(f"  {name:<8} {report[name]:10.5g} {unit:<10}{interval}")
    print(f"  fit NRMSE {report['nrmse']:.4f}")
    if "validation_nrmse" in report:
        print(f"  validation NRMSE {report['validation_nrmse']:.4f}")
    for key in ("out", "plot"):
        if key in report:
            print(f"  wrote {report[key]}")
