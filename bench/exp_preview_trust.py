"""The road preview faded by the distance to the road's line: measured on the runs.

Reproduce: simulate the scenarios of ``bench_cueing.py`` and ``bench/scenarios/avoidance_35.toml``
into RUNS (``motosim simulate ... --out RUNS/NAME``), then ``python bench/exp_preview_trust.py
RUNS [NAME]``: the largest distance to the line on each run, then on NAME (default
avoidance_35) the washout, the MPC from the present motion, with the preview trusted
throughout, and with the preview faded (``cue(..., trust_distance=d)``, d = 0.5 and 1 m), and
where the lateral force's false cues are, in % of each 0.5 s.
"""

import sys
from pathlib import Path

import numpy as np

from bench_cueing import OTHERS, TRAINING
from motosim.cueing import TELBAN_CARDULLO_2005, cue, load_platform
from motosim.cueing.preview import TRUST_DISTANCE, arc_length
from motosim.io.results import load_result
from motosim.sim.road import result_road
from motosim.timeseries import TimeSeries


def main(runs: str, name: str = "avoidance_35") -> None:
    for other in (*TRAINING, *OTHERS, "avoidance_35"):
        folder = Path(runs) / other
        if not folder.is_dir():
            continue
        r = load_result(folder)
        road = result_road(r.metadata, origin=other)
        if road is None:
            continue
        x, y = r.data[:, r.names.index("x")], r.data[:, r.names.index("y")]
        k = np.clip(np.rint(arc_length(road, x, y) / road.ds).astype(int), 0, road.x.size - 1)
        print(f"{other}: largest distance to the line "
              f"{np.max(np.hypot(x - road.x[k], y - road.y[k])):.2f} m")  # fmt: skip
    r = load_result(Path(runs) / name)
    series = TimeSeries(r.t, r.data, r.names)
    road = result_road(r.metadata, origin=name)
    cfg = load_platform("simacom_platform")
    deg = 180 / np.pi
    thr = TELBAN_CARDULLO_2005.thresholds[4]
    cases = [("washout", "washout", None, None), ("mpc", "mpc", None, None),
             ("mpc, road preview", "mpc", road, None)]  # fmt: skip
    cases += [(f"mpc, preview faded d = {d:g} m", "mpc", road, d) for d in (TRUST_DISTANCE, 1.0)]
    for label, algorithm, preview, d in cases:
        run = cue(cfg, series, TELBAN_CARDULLO_2005, algorithm=algorithm, rate=100.0,  # type: ignore[arg-type]
                  road=preview, trust_distance=d)  # fmt: skip
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


if __name__ == "__main__":
    main(*sys.argv[1:])
