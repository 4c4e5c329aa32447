"""Why the MPC with the road preview misses issue 13's target on two unseen scenarios.

Reproduce: simulate the scenarios of ``bench_cueing.py`` into RUNS (``motosim simulate
... --out RUNS/NAME``), then

- ``python bench/exp_unseen_misses.py RUNS budget NAME``: per second of the run, the
  motorcycle's lean and perceived roll rate and lateral force, and for the washout, the MPC
  from the present motion and the MPC with the road preview: the platform's roll command,
  the RMS of the perceived roll-rate error and the platform's perceived lateral force (where
  a roll error comes from, docs/guide/cueing.md);
- ``python bench/exp_unseen_misses.py RUNS front NAME,NAME``: the MPC with the road preview
  at the preview's force band weights 3.0, 1.5 (the design), 1.0, 0.5 and 0.2, and given the
  motorcycle's true future motion at the head as its preview (a foresight no rider model
  has: a diagnosis only), against the washout: violations, false cues %, roll and pitch
  rate RMS [deg/s].
"""

import dataclasses
import sys
from pathlib import Path
from typing import Any

import numpy as np

import motosim.cueing.pipeline as pipeline
from motosim.cueing import TELBAN_CARDULLO_2005, cue, load_platform
from motosim.cueing.head import vehicle_motion
from motosim.cueing.preview import SWAY_HEIGHT, SWAY_X
from motosim.io.results import load_result
from motosim.sim.road import result_road
from motosim.timeseries import TimeSeries

MODEL = TELBAN_CARDULLO_2005
WEIGHTS = (3.0, 1.5, 1.0, 0.5, 0.2)


def _load(runs: str, name: str) -> tuple[TimeSeries, Any]:
    r = load_result(Path(runs) / name)
    return TimeSeries(r.t, r.data, r.names), result_road(r.metadata, origin=name)


def _figures(run: Any) -> str:
    ch = run.score.channels
    false = 100 * np.mean([c.false_cue_share for c in ch.values()])
    roll, pitch = np.degrees(ch["roll"].rms_error), np.degrees(ch["pitch"].rms_error)
    return f"{run.score.violations} | {false:.2f} | {roll:.2f} | {pitch:.2f}"


def budget(runs: str, name: str) -> str:
    """Per-second table of where the roll error and the lateral force come from."""
    cfg = load_platform("simacom_platform")
    series, road = _load(runs, name)
    runs_ = [
        cue(cfg, series, MODEL, algorithm=a, rate=100.0, road=rd)  # type: ignore[arg-type]
        for a, rd in (("washout", None), ("mpc", None), ("mpc", road))
    ]
    t = runs_[0].commands.t
    lean = np.interp(t, series.t, series["phi"])
    pv = runs_[0].perceived_vehicle
    lines = [
        "| t [s] | lean [deg] | perceived roll rate [deg/s] | lateral force [m/s^2] | "
        "washout: roll [deg], roll error [deg/s], lateral force | MPC | MPC, road preview |",
        "|---|---|---|---|---|---|---|",
    ]
    for a in np.arange(0.0, t[-1], 1.0):
        m = (t >= a) & (t < a + 1.0)
        cells = []
        for run in runs_:
            pp = run.perceived_platform
            e = np.degrees(pp["roll"][m] - pv["roll"][m])
            cells.append(
                f"{np.degrees(np.mean(run.commands['phi_s'][m])):+.1f}, "
                f"{np.sqrt(np.mean(e**2)):.2f}, {np.mean(pp['sway'][m]):+.2f}"
            )
        lines.append(
            f"| {a:.0f}-{a + 1:.0f} | {np.degrees(np.mean(lean[m])):+.1f} | "
            f"{np.degrees(np.mean(pv['roll'][m])):+.2f} | {np.mean(pv['sway'][m]):+.2f} | "
            + " | ".join(cells)
            + " |"
        )
    return "\n".join(lines)


def _foresight(series: TimeSeries, cfg: Any) -> Any:
    """A stand-in for :func:`road_preview` that returns the motorcycle's true future roll
    rate and lateral force at the head over the horizon, less the part the MPC holds."""
    original = pipeline.road_preview

    def preview(road: Any, arc: Any, speed: Any, *, horizon: int, step: float) -> Any:
        run = pipeline.decimate(series, 100.0)
        vm = vehicle_motion(run, cfg.rider)
        dt = float(run.t[1] - run.t[0])
        p, r, f = vm["omega_x"], vm["omega_z"], vm["f_y"]
        alpha = np.concatenate([[0.0], np.diff(p) / dt])
        yaw_accel = np.concatenate([[0.0], np.diff(r) / dt])
        held = f - SWAY_HEIGHT * alpha - SWAY_X * yaw_accel  # what the plan holds
        j = np.minimum(
            np.arange(p.size)[:, None] + round(step / dt) * np.arange(horizon + 1), p.size - 1
        )
        return np.stack([p[j], f[j] - held[:, None]], axis=-1)

    pipeline.road_preview = preview  # type: ignore[assignment]
    return original


def front(runs: str, names: str) -> str:
    """The preview's force band weight and the foresight against the washout."""
    cfg = load_platform("simacom_platform")
    lines = [
        "| scenario | algorithm | violations | false cues % | roll rate RMS | pitch rate RMS |",
        "|---|---|---|---|---|---|",
    ]
    for name in names.split(","):
        series, road = _load(runs, name)
        run = cue(cfg, series, MODEL, algorithm="washout", rate=100.0)
        lines.append(f"| {name} | washout | {_figures(run)} |")
        for w in WEIGHTS:
            tuned = dataclasses.replace(
                cfg, mpc=dataclasses.replace(cfg.mpc, preview_force_false_cue_weight=w)
            )
            run = cue(tuned, series, MODEL, algorithm="mpc", rate=100.0, road=road)
            lines.append(f"| {name} | mpc, road preview, weight {w:g} | {_figures(run)} |")
        original = _foresight(series, cfg)
        try:
            run = cue(cfg, series, MODEL, algorithm="mpc", rate=100.0, road=road)
        finally:
            pipeline.road_preview = original
        lines.append(f"| {name} | mpc, true future motion as preview | {_figures(run)} |")
    return "\n".join(lines)


if __name__ == "__main__":
    runs, what, names = sys.argv[1:4]
    print(budget(runs, names) if what == "budget" else front(runs, names))
