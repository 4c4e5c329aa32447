"""``motosim paper``: regenerate the figures of the paper's section V from scratch."""

import argparse
import html
from collections.abc import Callable
from functools import partial
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

from motosim.cli._common import check_output_folder, print_json, show_progress, write_text
from motosim.cli.cache import add_cache_option, design_cache
from motosim.cli.simulate import resolve_cached, run_scenario
from motosim.errors import MotosimError
from motosim.params.toml import parse_toml

if TYPE_CHECKING:
    from motosim.io.results import SimResult
    from motosim.sim import Scenario

__all__ = ["paper_scenarios", "register"]


def register(sub: Any) -> None:
    """Add ``paper`` to the subcommands."""
    parser = sub.add_parser(
        "paper",
        help="regenerate every figure of the paper's section V",
        description=(
            "Simulate the paper's section V runs (square rider torque, nominal and perturbed "
            "handlebar, dry friction with and without compensation, a rider on a trajectory "
            "over the 100 Hz CAN link), write each result with its report, the paper's "
            "figures and DIR/index.html."
        ),
    )
    parser.add_argument("--out", required=True, help="folder for the runs and figures")
    parser.add_argument("--json", action="store_true", help="print the metrics as JSON")
    parser.add_argument(
        "--overwrite", action="store_true", help="replace what an existing --out folder holds"
    )
    add_cache_option(parser)
    parser.set_defaults(func=run)


def paper_scenarios() -> list["Scenario"]:
    """The packaged scenarios of section V, in figure order."""
    from motosim.sim import parse_scenario

    folder = resources.files("motosim.sim") / "data" / "paper"
    out = []
    for entry in sorted(folder.iterdir(), key=lambda p: p.name):
        if entry.name.endswith(".toml"):
            data = parse_toml(entry.read_text(encoding="utf-8"), origin=f"packaged {entry.name}")
            out.append(parse_scenario(data, origin=f"packaged {entry.name}"))
    return out


def _figures(runs: dict[str, "SimResult"], out: Path) -> list[tuple[str, str]]:
    from motosim.plotting.closed_loop import (
        plot_comparison,
        plot_motor_torque,
        plot_motorcycle,
        plot_rate,
        plot_torque,
        plot_tracking,
    )

    riding = runs["fig15_riding"]
    specs: list[tuple[str, str, Callable[[], Any]]] = [
        (
            "fig11_torque_estimation.png",
            "Fig. 11: rider torque and its estimate, nominal handlebar and one whose true "
            "J_eq and beta_eq are 50 % above the nominal ones",
            lambda: plot_comparison(
                {
                    "nominal handlebar": runs["fig11_nominal"],
                    "true J_eq, beta_eq +50 %": runs["fig11_perturbed"],
                },
                [("tau_r", "tau_r_hat")],
                title="Fig. 11: rider torque and its estimate",
            ),
        ),
        (
            "fig13_tracking.png",
            "Fig. 13 (left): the robust controller: handlebar angle against the virtual steer "
            "angle (Fig. 12, the observer's own state estimate, is not recorded by the runs)",
            lambda: plot_tracking(
                runs["fig11_nominal"], title="Fig. 13 (left): handlebar angle and steer angle"
            ),
        ),
        (
            "fig13_differentiator.png",
            "Fig. 13 (right): handlebar rate and the robust differentiator's, against the "
            "encoder's resolution",
            lambda: plot_rate(
                runs["fig11_nominal"], title="Fig. 13 (right): handlebar rate, differentiated"
            ),
        ),
        (
            "fig14_friction_compensation.png",
            "Fig. 14: dry friction, with and without its compensation: the rider-torque "
            "estimate (top) and the handlebar against the steer angle (bottom)",
            lambda: plot_comparison(
                {
                    "friction compensated": runs["fig14_compensated"],
                    "not compensated": runs["fig14_uncompensated"],
                },
                [("tau_r", "tau_r_hat"), ("theta_h", "delta")],
                title="Fig. 14: compensation of the dry friction",
            ),
        ),
        (
            "fig15_tracking.png",
            "Fig. 15: the riding run: handlebar angle against the virtual steer angle",
            lambda: plot_tracking(riding, title="Fig. 15: riding run, handlebar and steer"),
        ),
        (
            "fig16_torque_estimation.png",
            "Fig. 16: the riding run: rider torque and its Walcott-Zak estimate",
            lambda: plot_torque(riding, title="Fig. 16: riding run, rider torque estimate"),
        ),
        (
            "fig17_differentiator.png",
            "Fig. 17: the riding run: handlebar rate and the differentiator's (100 Hz CAN)",
            lambda: plot_rate(riding, title="Fig. 17: riding run, handlebar rate"),
        ),
        (
            "fig18_motor_torque.png",
            "Fig. 18: estimated rider torque against the motor torque N k_t i_m",
            lambda: plot_motor_torque(riding, title="Fig. 18: estimate and motor torque"),
        ),
        (
            "riding_motorcycle.png",
            "The riding run's virtual motorcycle: path, roll angle, speed (no figure of the paper)",
            lambda: plot_motorcycle(riding, title="Riding run: path, roll, speed"),
        ),
    ]
    from motosim.io.files import write_whole

    written = []
    for name, caption, make in specs:
        fig = make()
        write_whole(out / name, partial(fig.savefig, dpi=110, format="png"))
        written.append((name, caption))
    return written


def _index(out: Path, figures: list[tuple[str, str]], summaries: dict[str, dict[str, Any]]) -> Path:
    from motosim.report.units import METRICS, shown

    keys = ["rms_tau_r_error", "rms_tracking_error", "rms_rate_error", "max_abs_phi", "max_abs_e_y"]
    rows = "".join(
        f"<tr><td><a href='{html.escape(name)}/report.html'>{html.escape(name)}</a></td>"
        + "".join(f"<td>{shown(k, summary.get(k, float('nan')))[0]}</td>" for k in keys)
        + "</tr>"
        for name, summary in summaries.items()
    )
    header = "".join(
        f"<th>{html.escape(METRICS[k].label)} [{html.escape(METRICS[k].display_unit)}]</th>"
        for k in keys
    )
    figs = "".join(
        f"<figure><img src='{html.escape(f)}' alt='{html.escape(c)}'><figcaption>{html.escape(c)}"
        "</figcaption></figure>"
        for f, c in figures
    )
    page = f"""<!doctype html><html><head><meta charset="utf-8">
<title>motosim: the paper's section V</title>
<style>body{{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}}
table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;padding:4px 8px;text-align:right}}
td:first-child{{text-align:left}}img{{max-width:100%}}figure{{margin:2em 0}}</style></head><body>
<h1>Nehaoua, Arioui &amp; Mammar (2012), section V, regenerated by motosim</h1>
<p>Each run has its own report (click its name). Angles in degrees; the result files and
<code>--json</code> keep SI units (rad, rad/s).</p>
<table><tr><th>run</th>{header}</tr>{rows}</table>
{figs}</body></html>"""
    return write_text(out / "index.html", page)


def run(args: argparse.Namespace) -> int:
    """Simulate every run of section V, then the figures and the index."""
    out = check_output_folder(args.out, overwrite=args.overwrite)
    try:
        out.mkdir(exist_ok=True)
    except OSError as err:
        raise MotosimError(f"cannot create {args.out}: {err.strerror}") from None
    from motosim.io.files import FolderLock
    from motosim.io.results import load_result
    from motosim.report import build_report  # matplotlib: seconds, only once the output is fine

    cache = design_cache(args, quiet=args.json)
    summaries: dict[str, dict[str, Any]] = {}
    runs: dict[str, SimResult] = {}
    scenarios = paper_scenarios()
    for k, scenario in enumerate(scenarios, 1):
        folder = out / scenario.name
        if not args.json:
            print(f"[{k}/{len(scenarios)}] {scenario.name}: {scenario.description}")
        with FolderLock(folder) as lock:  # until its report is written (as simulate)
            inputs, stack = resolve_cached(scenario, Path("."), cache)
            summaries[scenario.name] = run_scenario(
                inputs,
                folder,
                progress=show_progress(args.json),
                overwrite=True,
                stack=stack,
                lock=lock,
            )
            build_report(folder)
            runs[scenario.name] = load_result(folder)
    figures = _figures(runs, out)
    index = _index(out, figures, summaries)
    if args.json:
        print_json({"index": str(index), "figures": [f for f, _ in figures], "metrics": summaries})
    else:
        print(f"report: {index}")
    return 0
