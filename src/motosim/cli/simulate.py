"""``motosim simulate`` and ``motosim report``: run a scenario, write and report its result."""

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from motosim.cli._common import (
    check_result_folder,
    check_result_input,
    check_scenario_inputs,
    check_scenario_values,
    deferred_warnings,
    finish_files_on_stop,
    print_json,
    show_progress,
)
from motosim.cli.cache import add_cache_option, design_cache
from motosim.errors import RunFailedError

if TYPE_CHECKING:
    from motosim.io.cache import DesignCache
    from motosim.io.files import FolderLock
    from motosim.report.figures import FigureWorkers
    from motosim.sim import RunInputs, Scenario
    from motosim.sim.stack import StackModel

__all__ = ["register", "resolve_cached", "run_scenario"]


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
    add_cache_option(parser)
    parser.set_defaults(func=run)
    report = sub.add_parser("report", help="build the HTML report of a result folder")
    report.add_argument("folder", help="a result folder written by motosim simulate")
    report.set_defaults(func=run_report)


def resolve_cached(
    scenario: "Scenario", base: Path, cache: "DesignCache"
) -> tuple["RunInputs", "StackModel"]:
    """The run of ``scenario`` (files relative to ``base``) and its stack, designed through
    ``cache``: one line on stderr when something is designed, with its time."""
    from motosim.io.cache import cached_stack
    from motosim.io.runs import resolve

    with cache.designing(scenario.name):
        inputs = resolve(scenario, base, cache=cache)
        return inputs, cached_stack(cache, inputs)


def run_scenario(
    inputs: "RunInputs",
    folder: Path,
    *,
    progress: bool,
    overwrite: bool = False,
    stack: "StackModel | None" = None,
    lock: "FolderLock | None" = None,
) -> dict[str, Any]:
    """Simulate into ``folder``, with a progress bar on a terminal; returns the metrics.

    ``stack`` is the run's designed stack (:func:`resolve_cached`); by default it is
    designed here. ``lock`` is the caller's held lock of ``folder``. SIGTERM, SIGHUP and
    Ctrl-C stop the run after the block being written, the result closed and marked partial.
    """
    from motosim.io.runs import run_to_folder

    sc = inputs.scenario
    with finish_files_on_stop() as stop:
        if not progress:
            return run_to_folder(
                inputs, folder, overwrite=overwrite, stack=stack, lock=lock, stop=stop
            )
        from tqdm import tqdm

        n = round(sc.duration * sc.rates.control)
        with tqdm(
            total=n, unit=" steps", desc=sc.name, file=sys.stderr, leave=False, unit_scale=True
        ) as bar:
            return run_to_folder(
                inputs,
                folder,
                overwrite=overwrite,
                on_rows=bar.update,
                stack=stack,
                lock=lock,
                stop=stop,
            )


def run(args: argparse.Namespace) -> int:
    """Simulate the scenario, write the result and the report."""
    check_scenario_inputs(args.scenario)
    folder = check_result_folder(args.out, args.scenario, overwrite=args.overwrite)
    check_scenario_values(args.scenario)  # before the numerical stack is imported
    from motosim.report.figures import FigureWorkers

    # the report's figures are drawn by processes that load matplotlib while the run goes on
    workers = FigureWorkers() if args.report else None
    try:
        return _simulate(args, folder, workers)
    finally:
        if workers is not None:
            workers.close()


def _simulate(args: argparse.Namespace, folder: Path, workers: "FigureWorkers | None") -> int:
    """:func:`run` once its inputs are checked: ``workers`` draw the report's figures."""
    from motosim.io.files import FolderLock
    from motosim.io.results import is_complete_result, partial_folder
    from motosim.io.runs import load_scenario
    from motosim.sim.metrics import warnings

    cache = design_cache(args, quiet=args.json)
    with deferred_warnings():  # shown once the files it names are read too
        scenario = load_scenario(args.scenario)
        inputs, stack = resolve_cached(scenario, Path(args.scenario).parent, cache)
    # the folder stays locked until its report is written: a concurrent --overwrite of the
    # same folder is refused until then, not let in between the result and its report
    with FolderLock(folder) as lock:
        try:
            summary = run_scenario(
                inputs,
                folder,
                progress=show_progress(args.json),
                overwrite=args.overwrite,
                stack=stack,
                lock=lock,
            )
        except KeyboardInterrupt:
            staged = partial_folder(folder)
            kept = staged if staged.is_dir() else folder
            print(f"motosim: interrupted; the partial result is in {kept}", file=sys.stderr)
            return 130
        except RunFailedError:
            report = None
            if is_complete_result(folder):  # written whole, flagged: its report and metrics
                if args.report:
                    from motosim.report import build_report

                    report = build_report(folder, workers=workers)
                if args.json:  # what a script reads, failure included; the reason on stderr
                    from motosim.io.results import load_result

                    summary = load_result(folder).summary
                    print_json(
                        {
                            "out": str(folder),
                            "report": str(report) if report else None,
                            "metrics": summary,
                        }
                    )
            raise
        for line in warnings(summary):
            print(f"motosim: warning: {line}", file=sys.stderr)
        report = None
        if args.report:
            from motosim.report import build_report

            report = build_report(folder, workers=workers)
    if args.json:
        print_json(
            {
                "out": str(folder),
                "report": str(report) if report else None,
                "metrics": summary,
            }
        )
    else:
        from motosim.report.units import summary_lines

        print(f"{scenario.name}: result in {folder}" + (f", report {report}" if report else ""))
        print("\n".join(summary_lines(dict(summary))))  # degrees and per cent; --json is SI
    return 0


def run_report(args: argparse.Namespace) -> int:
    """Build the report of a result folder."""
    check_result_input(args.folder)
    from motosim.report import build_report

    print(f"wrote {build_report(Path(args.folder))}")
    return 0
