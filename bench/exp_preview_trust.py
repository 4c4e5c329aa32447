"""The road preview trusted by the lean the road asks for, or by the distance to its line.

Reproduce: simulate the scenarios of ``bench_cueing.py`` and ``bench/scenarios/avoidance_35.toml``
into RUNS (``motosim simulate ... --out RUNS/NAME``), then ``python bench/exp_preview_trust.py
RUNS [NAME]``: on each run the largest steady-turn lean the road asks for over the horizon
(:func:`motosim.cueing.preview.preview_trust`), the lean ridden and the largest distance to the
line; then on NAME (default avoidance_35) the washout, the MPC from the present motion, with
the preview trusted throughout (as before the trust), faded by the distance ``e`` to the line
(``clip(2 - e / d, 0, 1)``, d = 0.5 m, above the training runs' 0.47 m, and 1 m) and as
:func:`motosim.cueing.cue` does (by the lean), and where the lateral force's false cues are, in
% of each 0.5 s.
"""

import sys
from pathlib import Path
from typing import Any

import numpy as np

import motosim.cueing.pipeline as pipeline
from bench_cueing import OTHERS, TRAINING
from motosim.cueing import TELBAN_CARDULLO_2005, cue, load_platform
from motosim.cueing.preview import LEAD_DISTANCE, arc_length
from motosim.io.results import load_result
from motosim.sim.road import result_road
from motosim.timeseries import TimeSeries

LEAN = pipeline.preview_trust


def main(runs: str, name: str = "avoidance_35") -> None:
    deg = 180 / np.pi
    for other in (*TRAINING, *OTHERS, "avoidance_35"):
        folder = Path(runs) / other
        if not folder.is_dir():
            continue
        r = load_result(folder)
        road = result_road(r.metadata, origin=other)
        if road is None:
            continue
        x, y, v, phi = (r.data[:, r.names.index(c)] for c in ("x", "y", "v_x", "phi"))
        arc = arc_length(road, x, y)
        k = np.clip(np.rint(arc / road.ds).astype(int), 0, road.x.size - 1)
        s = road.ds * np.arange(road.kappa.size)
        ahead = arc[:, None] + LEAD_DISTANCE + v[:, None] * np.linspace(0.0, 1.0, 41)
        asked = np.arctan(v[:, None] ** 2 * np.interp(ahead, s, road.kappa) / 9.81)
        print(
            f"{other}: lean asked up to {np.max(np.abs(asked)) * deg:.1f} deg, ridden "
            f"{np.max(np.abs(phi)) * deg:.1f} deg; largest distance to the line "
            f"{np.max(np.hypot(x - road.x[k], y - road.y[k])):.2f} m"
        )
    r = load_result(Path(runs) / name)
    series = TimeSeries(r.t, r.data, r.names)
    road = result_road(r.metadata, origin=name)
    cfg = load_platform("simacom_platform")
    thr = TELBAN_CARDULLO_2005.thresholds[4]
    xy = np.column_stack([r["x"], r["y"]])[:: round(0.01 / float(r.t[1] - r.t[0]))]

    def by_distance(d: float) -> Any:
        def trust(road: Any, arc: Any, speed: Any, **_: Any) -> Any:
            k = np.clip(np.rint(arc / road.ds).astype(int), 0, road.x.size - 1)
            e = np.hypot(xy[:, 0] - road.x[k], xy[:, 1] - road.y[k])
            return np.clip(2.0 - e / d, 0.0, 1.0)

        return trust

    cases = [
        ("washout", "washout", None, LEAN),
        ("mpc", "mpc", None, LEAN),
        (
            "mpc, road preview trusted throughout",
            "mpc",
            road,
            lambda road, arc, speed, **_: np.ones(arc.size),
        ),
        ("mpc, faded by distance, d = 0.5 m", "mpc", road, by_distance(0.5)),
        ("mpc, faded by distance, d = 1 m", "mpc", road, by_distance(1.0)),
        ("mpc, road preview (trusted by the lean)", "mpc", road, LEAN),
    ]
    for label, algorithm, preview, trust in cases:
        pipeline.preview_trust = trust  # type: ignore[assignment]
        run = cue(
            cfg,
            series,
            TELBAN_CARDULLO_2005,
            algorithm=algorithm,
            rate=100.0,  # type: ignore[arg-type]
            road=preview,
        )
        ch = run.score.channels
        false = 100 * np.mean([c.false_cue_share for c in ch.values()])
        v, p = run.perceived_vehicle["sway"], run.perceived_platform["sway"]
        felt_v = np.where(np.abs(v) > thr, np.sign(v), 0.0)
        felt_p = np.where(np.abs(p) > thr, np.sign(p), 0.0)
        sway = (felt_p != 0) & (felt_p != felt_v)
        bins = " ".join(f"{round(100 * sway[k : k + 50].mean())}" for k in range(0, sway.size, 50))
        print(
            f"{name} | {label} | violations {run.score.violations} | false cues "
            f"{false:.1f} % | roll {ch['roll'].rms_error * deg:.2f} | pitch "
            f"{ch['pitch'].rms_error * deg:.2f} deg/s | sway false per 0.5 s: {bins}"
        )
    pipeline.preview_trust = LEAN


if __name__ == "__main__":
    main(*sys.argv[1:])
