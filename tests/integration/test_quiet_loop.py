"""The Dahl friction term in the closed loop, on the run the simulate guide measures it on.

What it promises: on the lane change at 20 m/s, 1 kHz, with the relaxed grip and the stack
designed for the handlebar alone (``[controller] grip = "off"``: on the stack designed for
the hands the same term leaves 1.7 A, in the guide), the reference
feedforward's friction term no longer flips with the virtual motorcycle's wobble, and the
motor current after the manoeuvre falls below the issue's 0.3 A peak to peak (from above
1.5 A with the tanh term), with the tracking and the estimate within their targets; let go
from 6 s, the current stays below 1 A peak to peak. (It does not hold on every run: the
crosswind's tracking is the price, in the guide's "The buzz, loop by loop".)
"""

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from motosim.io.runs import load_scenario, resolve
from motosim.sim import simulate
from motosim.sim.closed_loop import build_stack
from motosim.sim.metrics import run_metrics
from motosim.sim.stack import NO_QUIET

ROOT = Path(__file__).parents[2]
PRESLIDING = 1e-3  # rad, the guide's x_0


def _buzz(presliding: float, hands_off: bool) -> dict[str, float]:
    path = ROOT / "scenarios" / "lane_change_20.toml"
    sc = load_scenario(path)
    rider = dataclasses.replace(sc.rider, hands="relaxed")
    if hands_off:
        rider = dataclasses.replace(rider, hands_off=((6.0, sc.duration + 1.0),))
    controller = dataclasses.replace(sc.controller, grip="off")
    inputs = resolve(dataclasses.replace(sc, rider=rider, controller=controller), path.parent)
    stack = build_stack(inputs)._replace(quiet=NO_QUIET._replace(presliding=presliding))
    run = simulate(inputs, rng=np.random.default_rng(sc.seed), stack=stack)
    return run_metrics(
        run.t, lambda n: run[n] if n in run.names else None, complete=True, max_current=30.0
    )


@pytest.mark.parametrize("hands_off", [False, True], ids=["held", "let go"])
def test_the_dahl_term_takes_the_lane_change_buzz_below_the_target(hands_off: bool) -> None:
    m = _buzz(PRESLIDING, hands_off)
    assert m["buzz_current_p2p"] < (1.0 if hands_off else 0.3)
    assert m["tracking_rms_fraction"] <= 0.05
    assert m["estimate_rms_fraction"] <= 0.05
    if not hands_off:  # the tanh term buzzes on the same run
        assert _buzz(0.0, False)["buzz_current_p2p"] > 1.5
    assert math.isfinite(m["buzz_frequency"])
