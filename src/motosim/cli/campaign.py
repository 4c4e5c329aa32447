"""``motosim campaign``: run a campaign file, resume it, report it, re-run one of its runs."""

import argparse
import math
import os
import re
import sys
from pathlib import Path
from typing import Any

from motosim.cli._common import check_folder_target, check_output, print_json
from motosim.errors import MotosimError
from motosim.params.checks import short_repr

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
    parser.set_defaults(func=run)


def _progress_bar(enabled: bool) -> Any:
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(unit=" runs", file=sys.stderr, leave=False, dynamic_ncols=True)


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


def _check_options(args: argparse.Namespace) -> None:
    """Refuse absurd options before the campaign is planned."""
    out = check_folder_target(args.out, "--out", "a result folder")
    if args.rerun is None and out.is_dir() and any(out.iterdir()):  # before the base scenario
        from motosim.campaign.results import check_store_folder

        check_store_folder(out)
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
    if args.write_scenario:  # it replaced an existing file (the base scenario) silently
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


def run(args: argparse.Namespace) -> int:
    """Run (or resume) the campaign, then write its report."""
    if args.write_scenario and not args.rerun:
        raise MotosimError("--write-scenario is for --rerun RUN_ID")
    _check_options(args)
    if args.rerun:
        return _rerun(args)
    from motosim.campaign import load_campaign, run_campaign

    campaign = load_campaign(args.campaign)
    bar = _progress_bar(not args.json and sys.stderr.isatty())

    def progress(done: int, total: int, failed: int) -> None:
        if bar is not None:
            bar.total = total
            bar.n = done
            bar.set_postfix_str(f"{failed} failed", refresh=False)
            bar.refresh()

    from motosim.io.results import folder_lock

    # the folder stays locked until its report is written (run_campaign's lock joins this one)
    with folder_lock(args.out, shared=True):
        try:
            summary = run_campaign(
                campaign,
                args.out,
                backend=args.backend,
                scheduler=args.scheduler,
                jobs=args.jobs,
                on_progress=progress,
            )
        except KeyboardInterrupt:
            print(
                f"motosim: interrupted; the runs written are in {args.out}: run the same command "
                "to resume",
                file=sys.stderr,
            )
            return 130
        finally:
            if bar is not None:
                bar.close()
        report = None
        if args.report:
            from motosim.report.campaign import build_campaign_report

            report = build_campaign_report(args.out)
    if args.json:
        import dataclasses

        print_json({**dataclasses.asdict(summary), "report": str(report) if report else None})
        return 0
    s = summary
    print(
        f"{s.name}: {s.runs} runs in {s.folder} ({s.skipped} already there, {s.computed} run "
        f"now, {s.failed} failed); {s.designs} design(s), {s.tasks} tasks on {s.workers} workers"
    )
    rate = s.computed / (s.wall - s.design_time) if s.computed and s.wall > s.design_time else 0
    print(
        f"  wall {s.wall:.2f} s (planning and design {s.design_time:.2f} s), {rate:.1f} runs/s, "
        f"scheduler overhead {100 * s.overhead:.1f} % of the workers' time"
    )
    if report:
        print(f"  report {report}")
    return 0
