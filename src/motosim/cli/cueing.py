"""``motosim cueing``: platform commands for a recorded run, scored by the rider's perception."""

import argparse
import dataclasses
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from motosim.cli._common import (
    check_named_input,
    check_output_folder,
    check_result_input,
    finish_files_on_stop,
    print_json,
    save_figure,
    warn_atypical,
)
from motosim.errors import MotosimError

if TYPE_CHECKING:
    from motosim.cueing import CueingRun, CueingScore
    from motosim.io.files import FolderLock

__all__ = ["ALGORITHMS", "register", "score_summary"]

ALGORITHMS = ("washout", "mpc")
"""The choices of ``--algorithm``: :data:`motosim.cueing.ALGORITHMS`, written out so that the
parser is built without importing SciPy (a unit test checks that they are equal)."""
PREVIEWS = ("road", "none")
"""The choices of ``--preview``: the MPC plans with the road ahead of the run's virtual rider
(:mod:`motosim.cueing.preview`), or from the present motion only."""


def register(sub: Any) -> None:
    """Add ``cueing`` to the subcommands."""
    parser = sub.add_parser(
        "cueing",
        help="platform roll/pitch/yaw commands for a run, scored by what the rider perceives",
        description=(
            "Compute the motion at the rider's head from a result folder written by "
            "`motosim simulate`, cue the platform (classical washout or MPC), apply the limit "
            "manager, and score the platform's perceived motion against the motorcycle's "
            "(Telban & Cardullo 2005 vestibular models). Writes the commands to "
            "OUT/result.h5 and OUT/result.csv (t, phi_s, theta_s, psi_s, phi_vis [rad]) and "
            "the figures OUT/perception.png and OUT/commands.png."
        ),
    )
    parser.add_argument("result", help="result folder of `motosim simulate`")
    parser.add_argument(
        "--platform", default="simacom_platform", help="packaged platform or TOML file"
    )
    parser.add_argument("--algorithm", choices=ALGORITHMS, default="washout")
    parser.add_argument(
        "--preview",
        choices=PREVIEWS,
        default="road",
        help="the MPC's prediction: the road ahead of the run's virtual rider (when the run "
        "has a path), or none (the present motion only)",
    )
    parser.add_argument(
        "--rate", type=float, default=100.0, help="loop rate [Hz], divides the run's (100)"
    )
    parser.add_argument("--out", required=True, help="folder to write")
    parser.add_argument("--overwrite", action="store_true", help="replace a result in --out")
    parser.add_argument("--json", action="store_true", help="print the scores as JSON")
    parser.set_defaults(func=run)


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


def score_summary(score: "CueingScore") -> dict[str, Any]:
    """Flat JSON-ready summary of a score (NaN as None), angles and rates in SI."""
    out: dict[str, Any] = {"violations": score.violations}
    for name, cs in score.channels.items():
        for key, value in dataclasses.asdict(cs).items():
            out[f"{name}_{key}"] = _finite(float(value))
    for key, values in score.margins.items():
        for axis, value in zip(("roll", "pitch", "yaw"), values, strict=True):
            out[f"margin_{key}_{axis}"] = float(value)
    return out


def _write(run: "CueingRun", lock: "FolderLock", metadata: dict[str, Any], overwrite: bool) -> None:
    import numpy as np

    from motosim.cueing import COMMAND_SIGNALS
    from motosim.io.results import ResultWriter

    names = ("t", *COMMAND_SIGNALS)
    rows = run.commands.t.size
    with (
        finish_files_on_stop() as stop,
        ResultWriter(
            lock.folder,
            names,
            metadata,
            overwrite=overwrite,
            expected_rows=rows,
            lock=lock,
            stop=stop,
        ) as writer,
    ):
        writer.append(np.column_stack([run.commands.t, run.commands.data]))
        writer.close(score_summary(run.score))


def run(args: argparse.Namespace) -> int:
    """Cue, write, plot and summarise."""
    if not (math.isfinite(args.rate) and 1.0 <= args.rate <= 10_000.0):
        raise MotosimError(f"--rate {args.rate}; expected a loop rate from 1 to 10000 Hz")
    check_result_input(args.result)
    check_named_input(args.platform, "platform file")
    check_output_folder(args.out, overwrite=args.overwrite, reads=(("result", args.result),))
    import numpy as np

    from motosim.cueing import TELBAN_CARDULLO_2005, cue, load_platform
    from motosim.io.results import load_result
    from motosim.timeseries import TimeSeries

    config = load_platform(args.platform)
    result = load_result(args.result)
    steps = np.diff(result.t)
    if steps.size and steps.max() - steps.min() > 1e-6 * steps.max():
        raise MotosimError(
            f"{args.result}: sample period from {steps.min():g} to {steps.max():g} s; expected "
            "a constant rate (a result of motosim run skips its missed deadlines: its platform "
            "commands are those motosim run sends with --platform-udp or --platform-can)"
        )
    series = TimeSeries(result.t, result.data, result.names)
    model = TELBAN_CARDULLO_2005
    warn_atypical("cueing", "--rate", args.rate)
    road = None
    if args.algorithm == "mpc" and args.preview == "road":
        from motosim.sim.road import result_road

        road = result_road(result.metadata, origin=str(args.result))
    outcome = cue(config, series, model, algorithm=args.algorithm, rate=args.rate, road=road)
    preview = "road" if road is not None else "none"
    folder = Path(args.out)
    metadata = {
        "source": str(args.result),
        "algorithm": args.algorithm,
        "rate": args.rate,
        "preview": preview,
        "platform": config,
        "vestibular": model,
    }
    from motosim.io.files import FolderLock
    from motosim.plotting.cueing import plot_commands, plot_perception

    scenario = result.metadata.get("scenario")
    name = str(scenario.get("name")) if isinstance(scenario, dict) else Path(args.result).name
    title = f"{name}: {args.algorithm} on {config.platform.name}"
    limits = tuple(axis.angle for axis in config.platform.axes)
    # locked until the figures are written: a concurrent --overwrite of the folder is
    # refused until then, not let in between the commands and their figures
    with FolderLock(folder) as lock:
        _write(outcome, lock, metadata, args.overwrite)
        save_figure(
            plot_perception(outcome, thresholds=model.thresholds, title=title),
            str(folder / "perception.png"),
        )
        save_figure(
            plot_commands(outcome, limits=(limits[0], limits[1], limits[2]), title=title),
            str(folder / "commands.png"),
        )
    summary = score_summary(outcome.score)
    if args.json:
        print_json(
            {"out": str(folder), "algorithm": args.algorithm, "preview": preview, "score": summary}
        )
    else:
        how = f"{args.algorithm}, road preview" if road is not None else args.algorithm
        print(f"{name}: {how} commands in {folder} ({summary['violations']} violations)")
        # the perceived error: canal rates in deg/s, otolith specific forces in m/s^2
        units = {"roll": "deg/s", "pitch": "deg/s", "yaw": "deg/s"}
        print(
            f"  {'channel':<8} {'rms error':>10} {'unit':<6} {'corr':>6} {'lag [s]':>8} "
            f"{'false [%]':>10} {'missing [%]':>12}"
        )
        for channel, cs in outcome.score.channels.items():
            unit = units.get(channel, "m/s^2")
            rms = math.degrees(cs.rms_error) if unit == "deg/s" else cs.rms_error
            print(
                f"  {channel:<8} {rms:10.4f} {unit:<6} {cs.correlation:6.2f} {cs.lag:8.2f} "
                f"{100 * cs.false_cue_share:10.1f} {100 * cs.missing_cue_share:12.1f}"
            )
    return 0
