"""The rider's hands (the arms' passive impedance) and the torque sensor's scenario keys.

The hands' torque on a handlebar held still is zero at the neutral angle and -k_a dtheta off
it; the scenario's keys refuse nonsense in one line. The closed loop with hands is in
``tests/integration/test_hands_loop.py``.
"""

import math

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.sim.hands import GRIPS, Hands, hands_torque, is_held
from motosim.sim.scenario import parse_scenario, scenario_dict, scenario_from_dict


@pytest.mark.parametrize("grip", ["relaxed", "firm"])
def test_hands_torque_on_a_still_handlebar_is_the_spring(grip: str) -> None:
    hands = GRIPS[grip]
    J, c, k = hands.inertia, hands.damping, hands.stiffness
    assert hands_torque(0.2, 0.0, 0.0, J, c, k, 0.2) == 0.0  # at the neutral angle
    for dtheta in (-0.05, 0.01, 0.3):
        assert hands_torque(0.2 + dtheta, 0.0, 0.0, J, c, k, 0.2) == pytest.approx(-k * dtheta)


def test_hands_off_phases() -> None:
    off = np.array([[1.0, 2.0], [5.0, 6.0]])
    assert [is_held(t, off) for t in (0.5, 1.0, 1.5, 2.0, 5.5, 7.0)] == [
        True,
        False,
        False,
        True,
        False,
        True,
    ]


@pytest.mark.parametrize(
    ("rider", "expected"),
    [
        ({"hands": {"inertia": -0.1}}, "inertia = -0.1"),
        ({"hands": {"damping": math.nan}}, "damping = nan"),
        ({"hands": {"stiffness": 1e6}}, "stiffness = 1000000.0"),
        ({"hands": {"stiffnes": 1.0}}, "did you mean 'stiffness'"),
        ({"hands": "loose"}, "hands = 'loose'; expected one of relaxed, firm, off"),
        ({"hands": 3}, "hands = 3"),
        ({"hands_off": [[2.0, 1.0]]}, "expected 0 <= t0 < t1"),
        ({"hands_off": [[1.0]]}, "expected [t0, t1] pairs"),
    ],
)
def test_hands_keys_refuse_nonsense_in_one_line(rider: dict, expected: str) -> None:
    doc = {"scenario": {"name": "x"}, "rider": {"kind": "torque", "profile": 0.0, **rider}}
    with pytest.raises(MotosimError) as err:
        parse_scenario(doc, origin="bad.toml")
    text = str(err.value)
    assert "\n" not in text and text.startswith("bad.toml")
    assert expected in text


@pytest.mark.parametrize(
    ("tables", "expected"),
    [
        (
            {"sensor": {"torque": {"noise": -1.0}}, "estimator": {"name": "torque_sensor"}},
            "noise = -1",
        ),
        (
            {"sensor": {"torque": {"offset": math.inf}}, "estimator": {"name": "torque_sensor"}},
            "offset = inf",
        ),
        ({"sensor": {"torque": {}}}, "[sensor] torque is read by [estimator] name"),
        ({"sensor": {"force": {}}}, "unknown key 'force'"),
    ],
)
def test_sensor_keys_refuse_nonsense_in_one_line(tables: dict, expected: str) -> None:
    doc = {"scenario": {"name": "x"}, "rider": {"kind": "torque", "profile": 0.0}, **tables}
    with pytest.raises(MotosimError) as err:
        parse_scenario(doc, origin="bad.toml")
    assert "\n" not in str(err.value) and expected in str(err.value)


def test_hands_table_round_trips() -> None:
    doc = {
        "scenario": {"name": "x"},
        "rider": {
            "kind": "torque",
            "profile": 0.0,
            "hands": {"inertia": 0.1, "damping": 2.0, "stiffness": 20.0},
            "hands_off": [[1.0, 1.5]],
        },
    }
    sc = parse_scenario(doc, origin="x")
    assert isinstance(sc.rider.hands, Hands)
    assert scenario_from_dict(scenario_dict(sc), origin="metadata") == sc


def test_estimate_with_a_torque_sensor_passes_it_through() -> None:
    from motosim.estimation import estimate
    from motosim.params import load_parameters

    hb = load_parameters("simacom_handlebar", "handlebar")
    t = np.arange(200) * 1e-3
    tau = np.cos(7.0 * t)
    _, out = estimate("torque_sensor", t, np.zeros_like(t), np.zeros_like(t), hb, torque=tau)
    np.testing.assert_array_equal(out, tau)
    with pytest.raises(MotosimError, match="needs it"):
        estimate("torque_sensor", t, np.zeros_like(t), np.zeros_like(t), hb)
    with pytest.raises(MotosimError, match="for 'torque_sensor' only"):
        estimate("kalman", t, np.zeros_like(t), np.zeros_like(t), hb, torque=tau)
