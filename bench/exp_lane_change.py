"""Experiments on the lane change's false lateral-force cues (the hooks ``_EXP`` of mpc.py).

Not a product: this script and the hooks were committed once and reverted in the next commit
(docs/guide/cueing.md quotes its figures). Usage::

    python bench/exp_lane_change.py RUNS SCENARIOS [EXP] [TUNING] [FORESIGHT]

``SCENARIOS`` comma-separated folder names of ``RUNS`` (``motosim simulate`` results),
``EXP`` a Python dict of hooks (``{'sign': 0.2, 'sign_return': 1}``: the sign constraint on
the platform's lateral force, its slack weight, only while the platform returns;
``{'consistent': 1, 'tau': 0.15}``: the roll acceleration's force as the derivative of the
faded roll rate; ``{'cap': 1.0}``: the platform's perceived force at most that many times the
motorcycle's where that is felt; ``{'oto': 'free'|'fade'|'held'}``: the lateral force's
prediction; ``{'scale': 1.3}``: the roll reference scaled), ``TUNING`` a dict of
:class:`~motosim.cueing.platform.MpcTuning` fields, ``FORESIGHT`` ``full`` (the plan given
the motorcycle's true future perceived roll rate and lateral force, not causal), ``sway``,
``canal`` (only that one), ``felt`` (only the direction of the perceived lateral force), or
``sway:T`` (the true lateral force over the first T seconds only).
"""

import dataclasses
import sys

import numpy as np

from motosim.cueing import TELBAN_CARDULLO_2005, cue, load_platform, perceive
from motosim.cueing import mpc as mpc_module
from motosim.cueing.head import vehicle_motion
from motosim.cueing.pipeline import decimate
from motosim.io.results import load_result
from motosim.timeseries import TimeSeries


def main(runs: str, names: str, exp: str = "{}", tuning: str = "{}", foresight: str = "") -> None:
    """Print the MPC's false cues and perceived roll-rate error per scenario."""
    cfg = load_platform("simacom_platform")
    cfg = dataclasses.replace(cfg, mpc=dataclasses.replace(cfg.mpc, **eval(tuning)))
    for name in names.split(","):
        r = load_result(f"{runs}/{name}")
        series = TimeSeries(r.t, r.data, r.names)
        mpc_module._EXP.clear()
        mpc_module._EXP.update(eval(exp))
        mpc_module._EXP["k"] = 0
        if foresight:
            truth = perceive(
                TELBAN_CARDULLO_2005, vehicle_motion(decimate(series, 100.0), cfg.rider)
            )
            kind, _, ahead = foresight.partition(":")
            if kind == "felt":
                mpc_module._EXP["oracle"] = truth["sway"]
            else:
                mpc_module._EXP["full"] = (truth["roll"], truth["sway"])
                if kind != "full":
                    mpc_module._EXP["only"] = kind
                if ahead:
                    mpc_module._EXP["ahead"] = float(ahead)
        run = cue(cfg, series, TELBAN_CARDULLO_2005, algorithm="mpc", rate=100.0)
        ch = run.score.channels
        false = 100 * np.mean([c.false_cue_share for c in ch.values()])
        print(
            f"{name:22s} violations {run.score.violations} false cues {false:.2f} % "
            f"(lateral {100 * ch['sway'].false_cue_share:.1f} %) roll RMS "
            f"{np.degrees(ch['roll'].rms_error):.2f} deg/s"
        )


if __name__ == "__main__":
    main(*sys.argv[1:])
