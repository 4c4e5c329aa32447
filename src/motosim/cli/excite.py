"""``motosim excite``: simulate an identification run of the handlebar and log it as CSV."""

import argparse
from typing import Any

import numpy as np

from motosim.cli._common import print_json
from motosim.identification import MeasurementModel, excitation_run
from motosim.io import write_log
from motosim.params import load_parameters

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
    parser.add_argument("--out", required=True, help="CSV log to write")
    parser.add_argument("--json", action="store_true", help="print a JSON summary")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Simulate, measure and write the run."""
    hb = load_parameters(args.handlebar, "handlebar")
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
    columns = ("theta_h", "i_m", "u")
    log = type(log)(log.t, np.column_stack([log[c] for c in columns]), columns)
    path = write_log(args.out, log)
    summary = {
        "out": str(path),
        "samples": int(log.t.size),
        "sample_rate": args.rate,
        "signal": args.signal,
        "theta_h_range": [float(log["theta_h"].min()), float(log["theta_h"].max())],
        "i_m_peak": float(np.abs(log["i_m"]).max()),
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
