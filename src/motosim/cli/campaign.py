"""``motosim campaign``: run a campaign file, resume it, report it, re-run one of its runs."""

import argparse
import math
import os
import re
import sys
import time
from pathlib import Path
from typing import Any

from motosim.cli._common import (
    check_folder_target,
    check_input,
    check_output,
    check_scenario_inputs,
    check_scenario_values,
    print_json,
)
from motosim.cli.cache import add_cache_option, design_cache
from motosim.errors import MotosimError
from motosim.params.checks import path_problem, short_repr

__all__ = ["register"]


def register(sub: Any) -> None:
    """Add ``campaign`` to the subcommands."""
    parser = sub.add_parser(
        "campaign",
        help="run many perturbed runs of a scenario (grid, Latin hypercube, random draws)",
        description=(
            "Run a campaign file into DIR: one Parquet part per batch of runs in DIR/parts, "
            "DIR/manifest.json, DIR/report.html and, with series = [...] in the campaign, "
            "each run's time series in DIR/series.zarr. Running it again resumes: the runs "
            "already in DIR are skipped. --rerun RUN_ID runs one run again and compares it "
            "with the stored one."
        ),
    )
    parser.add_argument("campaign", help="campaign TOML file")
    parser.add_argument("--out", required=True, help="result folder")
    parser.add_argument("--backend", choices=("joblib", "dask"), help="joblib (default) or dask")
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="a running Dask scheduler (tcp://host:8786; default: a local cluster)",
    )
    parser.add_argument(
        "--jobs", type=int, metavar="N", help="local worker processes (default: every core)"
    )
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.add_argument(
        "--no-report", dest="report", action="store_false", help="skip DIR/report.html"
    )
    parser.add_argument(
        "--runs",
        type=int,
        metavar="N",
        help="run only the first N runs of the plan (a shortened campaign, said so in its "
        "manifest and report; run again without --runs to complete it; default: every run)",
    )
    parser.add_argument(
        "--rerun",
        metavar="RUN_ID",
        help="run one run again and compare it (default: run the campaign)",
    )
    parser.add_argument(
        "--write-scenario",
        metavar="FILE",
        help=(
            "with --rerun: also write the run as a scenario file for motosim simulate "
            "(default: none written)"
        ),
    )
    add_cache_option(parser)
    parser.set_defaults(func=run)


def _process_age() -> float:
    """Seconds since this process started (Linux: ``/proc``), 0 where it cannot be read: the
    interpreter's start and the imports before the command's clock started."""
    try:
        with open("/proc/self/stat", encoding="ascii") as stat:
            started = int(stat.read().rsplit(")", 1)[1].split()[19])  # field 22: clock ticks
        with open("/proc/uptime", encoding="ascii") as uptime:
            now = float(uptime.read().split()[0])
        return max(0.0, now - started / os.sysconf("SC_CLK_TCK"))
    except (OSError, ValueError, IndexError):
        return 0.0


def _progress_bar(enabled: bool, total: int, initial: int) -> Any:
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(
        total=total,
        initial=initial,
        unit=" runs",
        file=sys.stderr,
        leave=False,
        dynamic_ncols=True,
    )


def _same_series(out: str, run_id: str, series: dict[str, Any]) -> bool:
    """Whether the stored series of a run equal ``series`` bit for bit (none: none stored)."""
    import numpy as np

    from motosim.campaign.series import SERIES, load_series

    if not series:
        return not (Path(out) / SERIES / run_id).is_dir()
    stored = load_series(out, run_id)
    return stored.keys() == series.keys() and all(
        np.array_equal(stored[k], series[k]) for k in series
    )


def _rerun(args: argparse.Namespace) -> int:
    import numpy as np

    from motosim.campaign import load_campaign, load_results, plan_campaign, rerun
    from motosim.campaign.export import export_run

    plan = plan_campaign(load_campaign(args.campaign))
    series: dict[str, Any] = {}
    if plan.campaign.series:
        from motosim.campaign import rerun_series

        row, series = rerun_series(plan, args.rerun)
    else:
        row = rerun(plan, args.rerun)
    stored = load_results(args.out) if Path(args.out).is_dir() else {}
    match: bool | None = None
    if stored and args.rerun in set(stored["run_id"].tolist()):
        j = int(np.flatnonzero(stored["run_id"] == args.rerun)[0])
        match = (
            all(
                row[m] == stored[m][j] or (math.isnan(row[m]) and math.isnan(stored[m][j]))
                for m in plan.campaign.metrics
            )
            and row["status"] == stored["status"][j]
            and _same_series(args.out, args.rerun, series)
        )
    written = export_run(plan, args.rerun, args.write_scenario) if args.write_scenario else []
    if args.json:
        print_json({"run": row, "identical_to_stored": match, "written": [str(p) for p in written]})
        return 0
    print(f"run {args.rerun}: {row['status']}" + (f" ({row['reason']})" if row["reason"] else ""))
    from motosim.report.units import summary_lines

    shown = {k: v for k, v in row.items() if k not in ("run_id", "status", "reason")}
    print("\n".join(summary_lines(shown)))  # degrees and per cent; --json is SI
    if match is None:
        print(f"  not in {args.out}: nothing to compare with")
    else:
        print(
            "  identical to the stored run (every metric and kept series bit for bit): "
            + ("yes" if match else "NO")
        )
    for path in written:
        print(f"wrote {path}")
    return 0 if match is not False else 1


def _check_inputs(path: str) -> None:
    """Check the campaign file and its base scenario's files before anything heavy is imported.

    The campaign's values are checked by :func:`motosim.campaign.load_campaign`, after.
    """
    from motosim.params.toml import read_toml

    source = check_input(path, "campaign file", text=True)
    head = read_toml(source, what="campaign file").get("campaign")
    if isinstance(head, dict) and isinstance(head.get("scenario"), str):
        base = source.parent / head["scenario"]
        problem = path_problem(base, "scenario file")
        if problem is not None:
            raise MotosimError(f"{path} [campaign] scenario: {problem}")
        check_scenario_inputs(base)
        check_scenario_values(base)


def _check_options(args: argparse.Namespace) -> None:
    """Refuse absurd options before the campaign is planned, then unreadable inputs."""
    out = check_folder_target(args.out, "--out", "a result folder")
    if args.rerun is None and out.is_dir() and any(out.iterdir()):  # before the base scenario
        from motosim.campaign.results import check_store_folder

        check_store_folder(out)
    if args.runs is not None and not 1 <= args.runs <= 10_000_000:
        raise MotosimError(f"--runs {short_repr(args.runs)}; expected 1 to 10000000 runs")
    if args.runs is not None and args.rerun is not None:
        raise MotosimError("--runs is for running a campaign, not with --rerun")
    if args.jobs is not None and not 1 <= args.jobs <= 4096:
        raise MotosimError(f"--jobs {short_repr(args.jobs)}; expected 1 to 4096 worker processes")
    address = re.fullmatch(
        r"(?:(?:tcp|tls|ucx|ws|wss)://)?([\w.\-]+|\[[0-9a-fA-F:]+\]):(\d{1,5})",
        args.scheduler or "",
    )
    if args.scheduler is not None and not (address and 0 < int(address.group(2)) < 65536):
        raise MotosimError(
            f"--scheduler {short_repr(args.scheduler)}; expected a Dask scheduler address such "
            "as tcp://host:8786"
        )
    if args.write_scenario:  # an existing file (the base scenario, say) is not replaced
        target = check_output(
            args.write_scenario, overwrite=True, option="--write-scenario", suffixes=(".toml",)
        )
        beside = target.with_name(f"{target.stem}_true_handlebar.toml")  # campaign.export
        for path in (target, beside):
            if os.path.lexists(path):
                raise MotosimError(
                    f"--write-scenario {args.write_scenario}: {path} exists; expected a new file "
                    "name (the scenario and its true handlebar file are never replaced)"
                )
    _check_inputs(args.campaign)


def run(args: argparse.Namespace) -> int:
    """Run (or resume) the campaign, then write its report."""
    if args.write_scenario and not args.rerun:
        raise MotosimError("--write-scenario is for --rerun RUN_ID")
    _check_options(args)
    if args.rerun:
        return _rerun(args)
    from motosim.campaign import load_campaign, run_campaign

    start = time.perf_counter() - _process_age()  # the printed wall time is the command's
    campaign = load_campaign(args.campaign)
    bars: list[Any] = []  # drawn from the first call on, once planned and designed

    def progress(done: int, total: int, failed: int) -> None:
        if not bars:
            # the runs already in the folder are not counted in the rate, nor the design
            bars.append(_progress_bar(not args.json and sys.stderr.isatty(), total, done))
        bar = bars[0]
        if bar is not None:
            bar.update(done - bar.n)
            bar.set_postfix_str(f"{failed} failed", refresh=False)
            bar.refresh()

    from motosim.io.files import FolderLock

    # the folder stays locked until its report is written (run_campaign is handed the lock)
    with FolderLock(args.out) as lock:
        try:
            summary = run_campaign(
                campaign,
                args.out,
                backend=args.backend,
                scheduler=args.scheduler,
                jobs=args.jobs,
                on_progress=progress,
                runs=args.runs,
                cache=design_cache(args, quiet=args.json),
                lock=lock,
            )
        except KeyboardInterrupt:
            print(
                f"motosim: interrupted; the runs written are in {args.out}: run the same command "
                "to resume",
                file=sys.stderr,
            )
            return 130
        except OSError as err:  # a full disk, a folder gone: name where, if the error does not
            if err.filename is not None:
                raise
            raise MotosimError(
                f"{args.out}: cannot write the campaign's results ({err.strerror or err}); the "
                "runs written are kept there: free space and run the same command to resume"
            ) from None
        finally:
            if bars and bars[0] is not None:
                bars[0].close()
        report = None
        report_start = time.perf_counter()
        if args.report:
            from motosim.report.campaign import build_campaign_report

            report = build_campaign_report(args.out)
    end = time.perf_counter()
    if args.json:
        import dataclasses

        print_json(
            {
                **dataclasses.asdict(summary),
                "report": str(report) if report else None,
                "command_wall": end - start,
                "report_time": end - report_start,
            }
        )
        return 0
    s = summary
    shortened = (
        f" (--runs {s.shortened_to}: the first {s.shortened_to} of the plan's {s.runs})"
        if s.shortened_to is not None
        else ""
    )
    planned = s.runs if s.shortened_to is None else s.shortened_to
    print(
        f"{s.name}: {planned} runs{shortened} in {s.folder} ({s.skipped} already there, "
        f"{s.computed} run now, {s.failed} failed); {s.designs} design(s), {s.tasks} tasks on "
        f"{s.workers} workers"
    )
    run_phase = s.wall - s.design_time
    rate = s.computed / run_phase if s.computed and run_phase > 0 else 0.0
    per_run = f", {1e3 * s.cpu / s.computed:.1f} ms of CPU per run" if s.computed else ""
    print(
        f"  wall {end - start:.2f} s: planning and design {s.design_time:.2f} s, runs "
        f"{run_phase:.2f} s ({rate:.1f} runs/s{per_run}), report {end - report_start:.2f} s; "
        f"scheduler overhead {100 * s.overhead:.1f} % of the workers' time"
    )
    if report:
        print(f"  report {report}")
    return 0
