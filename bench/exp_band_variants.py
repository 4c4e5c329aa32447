# Experiment of issue 13 (reverted): the MPC variants of mpc._EXP on RUNS=/tmp/runs42.
# python bench/exp_band_variants.py NAME,NAME "erode=4;rw=0.25;lift=1.5;cap=3;oracle=2;coast="
import sys, dataclasses, numpy as np
from pathlib import Path
import motosim.cueing.mpc as mpcmod
from motosim.cueing import cue, load_platform, TELBAN_CARDULLO_2005 as M
from motosim.io.results import load_result
from motosim.sim.road import result_road
from motosim.timeseries import TimeSeries
names = sys.argv[1].split(","); variants = sys.argv[2].split(";")
cfg0 = load_platform("simacom_platform")
deg = np.degrees
for name in names:
    r = load_result(Path("/tmp/runs42") / name); s = TimeSeries(r.t, r.data, r.names)
    road = result_road(r.metadata, origin=name)
    def fmt(run):
        ch = run.score.channels
        f = 100*np.mean([c.false_cue_share for c in ch.values()])
        return f"v={run.score.violations} false={f:.2f} roll={deg(ch['roll'].rms_error):.2f} pitch={deg(ch['pitch'].rms_error):.2f}"
    print(name, "washout", fmt(cue(cfg0, s, M, algorithm="washout", rate=100.0)), flush=True)
    for v in variants:
        kv = dict(x.split("=") for x in v.split(",") if x)
        tun = {}; mpcmod.COAST_TIMES = (0.5, 1.0, 2.0); mpcmod._EXP.update(lift=1.0, erode=0.0, oracle=0.0, rw=0.0, rwc=0.0, onesided=0.0, cap=0.0, capall=0.0)
        for k, val in kv.items():
            if k == "coast": mpcmod.COAST_TIMES = tuple(float(x) for x in val.split("/") if x)
            elif k in mpcmod._EXP: mpcmod._EXP[k] = float(val)
            else: tun[k] = type(getattr(cfg0.mpc, k))(val)
        cfg = dataclasses.replace(cfg0, mpc=dataclasses.replace(cfg0.mpc, **tun))
        print(name, "P", v or "base", fmt(cue(cfg, s, M, algorithm="mpc", rate=100.0, road=road)), flush=True)
