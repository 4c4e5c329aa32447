"""The Dahl friction term in the closed loop, on the run the simulate guide measures it on.

What it promises: on the lane change at 20 m/s, 1 kHz, with the relaxed grip and the stack
designed for the handlebar alone (``[controller] grip = "off"``: on the stack designed for
the hands the same term leaves 1.7 A, in the guide), the reference
feedforward's friction term no longer flips with the virtual motorcycle's wobble, and the
motor current after the manoeuvre falls well below the tanh term's (1.9-2.0 A), with the
tracking and the estimate within their targets; let go from 6 s, the current stays below
1 A peak to peak. (It does not hold on every run: the
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
def test_the_dahl_term_quiets_the_lane_change(hands_off: bool) -> None:
    """The Dahl term leaves at most 3/4 of the tanh term's buzz on the same run, held or let
    go, and below 1 A let go, with tracking and estimate within their 5 % targets. Held, the
    0.16 A it reaches on this machine's BLAS kernels is 1.28 A on OpenBLAS's Prescott
    kernels (the wobble it leaves is that sensitive): the guide's figure, not a promise."""
    m = _buzz(PRESLIDING, hands_off)
    tanh = _buzz(0.0, hands_off)["buzz_current_p2p"]
    assert m["buzz_current_p2p"] < 0.75 * tanh
    if hands_off:
        assert m["buzz_current_p2p"] < 1.0
    assert m["tracking_rms_fraction"] <= 0.05
    assert m["estimate_rms_fraction"] <= 0.05
    assert math.isfinite(m["buzz_frequency"])
