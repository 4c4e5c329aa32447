"""A scenario's ``[controller] integral_corner`` reaches the controller it runs with."""

import tomllib
from pathlib import Path

import numpy as np

from motosim.control.torque_feedback import INTEGRAL_CORNER, synthesize_controller
from motosim.io.runs import resolve
from motosim.params import load_parameters
from motosim.sim import parse_scenario

SCENARIO = """
[scenario]
name = "corner"
duration = 1.0
[rider]
kind = "torque"
profile = { kind = "constant", value = 1.0 }
hands = "off"    # the stack then designed for the handlebar alone, as synthesised below
[controller]
integral_corner = 0.2
"""


def test_the_scenario_key_designs_the_controller(tmp_path: Path) -> None:
    sc = parse_scenario(tomllib.loads(SCENARIO), origin="corner.toml")
    assert sc.controller.integral_corner == 0.2
    controller = resolve(sc, tmp_path).controller
    assert controller is not None
    hb = load_parameters("simacom_handlebar", "handlebar")
    want = synthesize_controller(hb, rng=np.random.default_rng(0), n_starts=4, integral_corner=0.2)
    default = synthesize_controller(
        hb, rng=np.random.default_rng(0), n_starts=4, integral_corner=INTEGRAL_CORNER
    )
    for name in ("A", "B", "C", "D"):
        np.testing.assert_allclose(getattr(controller, name), getattr(want, name), rtol=1e-12)
    assert not np.allclose(controller.C, default.C)
