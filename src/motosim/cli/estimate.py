"""``motosim estimate``: the rider's torque from a log of handlebar angle and motor current."""

import argparse
from typing import Any

from motosim.choices import ESTIMATOR_NAMES, SENSOR_ESTIMATOR
from motosim.cli._common import check_input, check_output, print_json
from motosim.params import load_parameters
from motosim.params.checks import check_number

__all__ = ["ESTIMATORS", "register"]

ESTIMATORS = (*ESTIMATOR_NAMES, SENSOR_ESTIMATOR)
"""The choices of ``--estimator``, the default first: the registry's estimators and the torque
sensor's, from :mod:`motosim.choices` (light: the parser is built without SciPy)."""


def register(sub: Any) -> None:
    """Add ``estimate`` to the subcommands."""
    parser = sub.add_parser(
        "estimate",
        help="estimate the rider torque from a log of theta_h and i_m",
        description=(
            "Reconstruct the rider's torque offline from a CSV log with columns t [s], "
            "theta_h [rad] and i_m [A] (units in the header or --columns are converted; jittered "
            "or gappy time stamps are resampled); writes t, theta_h_dot_hat "
            "[rad/s] and tau_r_hat [N*m]. A tau_r column in the log, if present, is taken as "
            "the truth and the error is reported. --estimator torque_sensor reads the torque "
            "sensor's column tau_r_meas [N*m] instead."
        ),
    )
    parser.add_argument("log", help="CSV log")
    parser.add_argument(
        "--handlebar", default="simacom_handlebar", help="nominal handlebar set or TOML file"
    )
    parser.add_argument(
        "--estimator",
        choices=ESTIMATORS,
        default=ESTIMATORS[0],
        help="estimator (default: the paper's Walcott-Zak observer)",
    )
    parser.add_argument(
        "--no-friction-compensation",
        dest="compensation",
        action="store_false",
        help="do not subtract the nominal dry friction",
    )
    parser.add_argument(
        "--lipschitz",
        type=float,
        default=300.0,
        help="bound on |theta_h''| for the differentiator [rad/s^2] (300)",
    )
    parser.add_argument(
        "--columns",
        metavar="MAP",
        help=(
            "the log's columns with units, e.g. t=time:ms,theta_h=angle:deg,i_m=cur:mA "
            "(default: the columns t, theta_h, i_m in their header's units, else s, rad, A)"
        ),
    )
    parser.add_argument("--out", required=True, help="CSV file to write")
    parser.add_argument("--json", action="store_true", help="print a JSON summary")
    parser.add_argument(
        "--overwrite", action="store_true", help="replace the --out file if it exists"
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Read, estimate, write and summarise."""
    check_input(args.log, "log file (CSV)", text=True)
    check_output(args.out, overwrite=args.overwrite, reads=(("log", args.log),))
    check_number(args.lipschitz, where="--lipschitz", lower=1e-3, upper=1e7, unit="rad/s^2")
    hb = load_parameters(args.handlebar, "handlebar")
    from motosim.io import parse_columns, read_rig_log, write_log

    columns = parse_columns(args.columns) if args.columns else None
    import numpy as np

    from motosim.estimation import estimate
    from motosim.timeseries import TimeSeries

    sensed = args.estimator == "torque_sensor"
    required = ("theta_h", "i_m", "tau_r_meas") if sensed else ("theta_h", "i_m")
    rig = read_rig_log(args.log, required=required, columns=columns)
    log = rig.series
    rate, tau_hat = estimate(
        args.estimator,
        log.t,
        log["theta_h"],
        log["i_m"],
        hb,
        lipschitz=args.lipschitz,
        friction_compensation=args.compensation,
        torque=log["tau_r_meas"] if sensed else None,
    )
    path = write_log(
        args.out,
        TimeSeries(log.t, np.column_stack([rate, tau_hat]), ("theta_h_dot_hat", "tau_r_hat")),
    )
    summary: dict[str, Any] = {
        "out": str(path),
        "estimator": args.estimator,
        "samples": int(log.t.size),
        "timing": rig.timing.describe(),
        "sample_rate": float((log.t.size - 1) / (log.t[-1] - log.t[0])),
        "tau_r_hat": {
            "mean": float(np.mean(tau_hat)),
            "rms": float(np.sqrt(np.mean(tau_hat**2))),
            "min": float(np.min(tau_hat)),
            "max": float(np.max(tau_hat)),
        },
    }
    if "tau_r" in log.names:
        error = tau_hat - log["tau_r"]
        summary["error"] = {
            "rms": float(np.sqrt(np.mean(error**2))),
            "max_abs": float(np.max(np.abs(error))),
        }
    if args.json:
        print_json(summary)
    else:
        stats = summary["tau_r_hat"]
        print(
            f"wrote {path}: {log.t.size} samples at {summary['sample_rate']:.4g} Hz, "
            f"{args.estimator}; tau_r_hat from {stats['min']:.2f} to {stats['max']:.2f} N*m"
        )
        if "error" in summary:
            print(f"  error against the log's tau_r: RMS {summary['error']['rms']:.3f} N*m")
    return 0
