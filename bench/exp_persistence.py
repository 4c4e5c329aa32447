"""The force band's weight scheduled by the persistence of the curve ahead: a grid.

Reproduce: simulate the scenarios of ``bench_cueing.py`` into RUNS (``motosim simulate ...
--out RUNS/NAME``), then ``python bench/exp_persistence.py RUNS NAMES [SUSTAINED] [TRANSIENT]
[WINDOW]``: for each comma-separated scenario the washout and the MPC with the road preview
at each comma-separated sustained weight (``sustained_force_false_cue_weight``), transient
weight (``preview_force_false_cue_weight``) and persistence window [s] (default: the design's
values), with violations, false cues %, roll and pitch rate RMS [deg/s], the target met
(``ok``: fewer false cues and lower roll and pitch errors than the washout, no violation)
and the share of samples whose persistence is above 0.5.
"""

import dataclasses
import sys
from pathlib import Path
from typing import Any

import numpy as np

import motosim.cueing.pipeline as pipeline
from motosim.cueing import TELBAN_CARDULLO_2005, cue, load_platform
from motosim.io.results import load_result
from motosim.sim.road import result_road
from motosim.timeseries import TimeSeries

MODEL = TELBAN_CARDULLO_2005


def _figures(run: Any) -> tuple[int, float, float, float]:
    ch = run.score.channels
    false = 100 * float(np.mean([c.false_cue_share for c in ch.values()]))
    roll, pitch = np.degrees(ch["roll"].rms_error), np.degrees(ch["pitch"].rms_error)
    return run.score.violations, false, float(roll), float(pitch)


def grid(runs: str, names: str, sustained: str, transient: str, window: str) -> str:
    """The table of the module docstring."""
    cfg = load_platform("simacom_platform")
    lines = [
        "| scenario | sustained | transient | window [s] | violations | false cues % | "
        "roll RMS | pitch RMS | ok | persistence > 0.5 |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    original = pipeline.curve_persistence
    for name in names.split(","):
        r = load_result(Path(runs) / name)
        series = TimeSeries(r.t, r.data, r.names)
        road = result_road(r.metadata, origin=name)
        base = _figures(cue(cfg, series, MODEL, algorithm="washout", rate=100.0))
        lines.append(
            f"| {name} | washout | | | {base[0]} | {base[1]:.2f} | {base[2]:.2f} | "
            f"{base[3]:.2f} | | |"
        )
        for ws in sustained.split(","):
            for wt in transient.split(","):
                for win in window.split(","):
                    tuned = dataclasses.replace(
                        cfg,
                        mpc=dataclasses.replace(
                            cfg.mpc,
                            sustained_force_false_cue_weight=float(ws),
                            preview_force_false_cue_weight=float(wt),
                        ),
                    )
                    share: list[float] = []

                    def persistence(
                        road: Any,
                        arc: Any,
                        speed: Any,
                        *,
                        ahead: float,
                        behind: float,
                        _w: str = win,
                        _s: list[float] = share,
                    ) -> Any:
                        w = float(_w) if _w else ahead
                        p = original(road, arc, speed, ahead=w, behind=w)
                        _s.append(float(np.mean(p > 0.5)))
                        return p

                    pipeline.curve_persistence = persistence  # type: ignore[assignment]
                    try:
                        f = _figures(
                            cue(tuned, series, MODEL, algorithm="mpc", rate=100.0, road=road)
                        )
                    finally:
                        pipeline.curve_persistence = original
                    ok = (
                        f[0] == 0
                        and f[1] < base[1]
                        and f[2] <= base[2] + 1e-9
                        and (f[3] <= base[3] + 1e-9)
                    )
                    lines.append(
                        f"| {name} | {ws} | {wt} | {win or 'design'} | {f[0]} | {f[1]:.2f} | "
                        f"{f[2]:.2f} | {f[3]:.2f} | {'yes' if ok else 'NO'} | "
                        f"{share[0] if share else 0:.2f} |"
                    )
        print(lines[-1], file=sys.stderr, flush=True)
    return "\n".join(lines)


if __name__ == "__main__":
    cfg0 = load_platform("simacom_platform").mpc
    args = sys.argv[1:] + [""] * 5
    runs_, names_ = args[0], args[1]
    print(
        grid(
            runs_,
            names_,
            args[2] or str(cfg0.sustained_force_false_cue_weight),
            args[3] or str(cfg0.preview_force_false_cue_weight),
            args[4],
        )
    )
