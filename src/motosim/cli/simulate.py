"""``motosim simulate`` and ``motosim report``: run a scenario, write and report its result."""

import argparse
import sys
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from motosim.cli._common import print_json
from motosim.control.statespace import StateSpace
from motosim.control.torque_feedback import PAPER_CONTROLLER, design_torque_feedback
from motosim.errors import MotosimError
from motosim.io import read_log
from motosim.io.design_file import read_design
from motosim.io.results import ResultWriter, SimResult
from motosim.params import HandlebarParameters, load_parameters
from motosim.sim import (
    SIGNALS,
    RunInputs,
    Scenario,
    parse_scenario,
    prepare,
    run_metadata,
    simulate,
)

__all__ = ["load_scenario", "register", "resolve", "run_scenario"]

_DESIGNS: dict[tuple[HandlebarParameters, float, int], StateSpace] = {}


def register(sub: Any) -> None:
    """Add ``simulate`` and ``report`` to the subcommands."""
    parser = sub.add_parser(
        "simulate",
        help="simulate a scenario in closed loop (Fig. 7) and write its result",
        description=(
            "Simulate a scenario file and write DIR/result.h5 (every signal and the metadata "
            "that produced it) and DIR/result.csv as the run goes, then DIR/report.html."
        ),
    )
    parser.add_argument("scenario", help="scenario TOML file")
    parser.add_argument("--out", required=True, help="folder for the result")
    parser.add_argument("--json", action="store_true", help="print the metrics as JSON")
    parser.add_argument(
        "--overwrite", action="store_true", help="replace a result already in the folder"
    )
    parser.add_argument(
        "--no-report", dest="report", action="store_false", help="skip the HTML report"
    )
    parser.set_defaults(func=run)
    report = sub.add_parser("report", help="build the HTML report of a result folder")
    report.add_argument("folder", help="a result folder written by motosim simulate")
    report.set_defaults(func=run_report)


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file (one-line :class:`MotosimError` otherwise)."""
    source = Path(path)
    if not source.is_file():
        raise MotosimError(f"{path}: no such scenario file")
    try:
        data = tomllib.loads(source.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as err:
        raise MotosimError(f"{path}: not valid TOML: {err}") from None
    return parse_scenario(data, origin=str(path))


def _relative(name: str, base: Path) -> str | Path:
    candidate = base / name
    return candidate if candidate.suffix == ".toml" and candidate.is_file() else name


def _controller(scenario: Scenario, nominal: HandlebarParameters, base: Path) -> StateSpace | None:
    c = scenario.controller
    if c.kind == "none" or scenario.architecture == "open_loop":
        return None
    if c.kind == "paper":
        return PAPER_CONTROLLER
    if c.design is not None:
        return read_design(_relative(c.design, base)).controller
    key = (nominal, c.bandwidth, c.order)
    if key not in _DESIGNS:
        _DESIGNS[key] = design_torque_feedback(
            nominal, rng=np.random.default_rng(0), bandwidth=c.bandwidth, order=c.order,
            rate=scenario.rates.measurement, n_starts=4,
        ).controller  # fmt: skip
    return _DESIGNS[key]


def resolve(scenario: Scenario, base: Path) -> RunInputs:
    """Load what the scenario names (parameter sets, design, CSV profiles), relative to ``base``."""
    hb = scenario.handlebar
    true = load_parameters(_relative(hb.true, base), "handlebar")
    nominal = load_parameters(_relative(hb.nominal, base), "handlebar")
    tables = {}
    profiles = [
        scenario.motorcycle.drive_torque,
        scenario.motorcycle.brake_torque,
        scenario.motorcycle.wind_force,
    ]
    if scenario.rider.profile is not None:
        profiles.append(scenario.rider.profile)
    for profile in profiles:
        if profile.kind == "csv":
            name = profile.settings["file"]
            tables[name] = read_log(
                base / name, required=(profile.settings["column"],), min_samples=2
            )
    return prepare(
        scenario,
        sharp=load_parameters(_relative(scenario.motorcycle.params, base), "sharp"),
        true_handlebar=true,
        nominal_handlebar=nominal,
        controller=_controller(scenario, nominal, base),
        tables=tables,
    )


def run_scenario(
    inputs: RunInputs, folder: Path, *, progress: bool, overwrite: bool = False
) -> dict[str, Any]:
    """Simulate into ``folder`` with a progress bar; returns the metrics written."""
    from motosim.report import metrics

    sc = inputs.scenario
    n = round(sc.duration * sc.rates.control)
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(
            total=n, unit=" steps", desc=sc.name, file=sys.stderr, leave=False, unit_scale=True
        )
    metadata = run_metadata(inputs)
    with ResultWriter(folder, SIGNALS, metadata, overwrite=overwrite) as writer:

        def on_block(block: np.ndarray) -> None:
            writer.append(block)
            if bar is not None:
                bar.update(block.shape[0])

        try:
            run = simulate(inputs, rng=np.random.default_rng(sc.seed), on_block=on_block)
        finally:
            if bar is not None:
                bar.close()
        summary = metrics(SimResult(run.t, run.data, run.names, metadata, {}, True))
        writer.close(summary)
    return summary


def run(args: argparse.Namespace) -> int:
    """Simulate the scenario, write the result and the report."""
    scenario = load_scenario(args.scenario)
    folder = Path(args.out)
    if (folder / "result.h5").exists() and not args.overwrite:
        raise MotosimError(f"{folder}: already holds a result; give --overwrite or another --out")
    inputs = resolve(scenario, Path(args.scenario).parent)
    try:
        summary = run_scenario(inputs, folder, progress=not args.json, overwrite=args.overwrite)
    except KeyboardInterrupt:
        print(f"motosim: interrupted; the partial result is in {folder}", file=sys.stderr)
        return 130
    report = None
    if args.report:
        from motosim.report import build_report

        report = build_report(folder)
    if args.json:
        print_json(
            {
                "out": str(folder),
                "report": str(report) if report else None,
                "metrics": summary,
            }
        )
    else:
        print(f"{scenario.name}: result in {folder}" + (f", report {report}" if report else ""))
        for key, value in summary.items():
            print(
                f"  {key:<32} {value:.4g}" if isinstance(value, float) else f"  {key:<32} {value}"
            )
    return 0


def run_report(args: argparse.Namespace) -> int:
    """Build the report of a result folder."""
    from motosim.report import build_report

    print(f"wrote {build_report(Path(args.folder))}")
    return 0
