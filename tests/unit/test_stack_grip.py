"""The hands a scenario's stack is designed for (``[controller] grip``, Scenario.stack_hands)
and the rider's default grip (Scenario.rider_hands)."""

import pytest

from motosim.errors import MotosimError
from motosim.sim import parse_scenario
from motosim.sim.grips import DEFAULT_GRIP, DESIGN_SHARE, GRIPS, design_hands
from motosim.sim.scenario import Scenario

_RIDER = {"kind": "torque", "profile": {"kind": "constant", "value": 0.0}}


def _scenario(rider: dict | None = None, **tables: dict):
    return parse_scenario(
        {"scenario": {"name": "grip"}, "rider": _RIDER | (rider or {}), **tables}, origin="test"
    )


def test_the_stack_is_designed_for_a_share_of_the_riders_grip() -> None:
    """By default the stack models DESIGN_SHARE of the rider's grip's inertia and damping,
    none of its stiffness; none without hands, and `grip` chooses another grip or none."""
    assert _scenario({"hands": "off"}).stack_hands is None
    held = _scenario({"hands": "relaxed"}).stack_hands
    relaxed = GRIPS["relaxed"]
    assert held is not None and held == design_hands(relaxed)
    assert held.inertia == pytest.approx(DESIGN_SHARE * relaxed.inertia)
    assert held.damping == pytest.approx(DESIGN_SHARE * relaxed.damping)
    assert held.stiffness == 0.0
    assert _scenario({"hands": "relaxed"}, controller={"grip": "off"}).stack_hands is None
    firm = _scenario(controller={"grip": "firm"}).stack_hands
    assert firm == design_hands(GRIPS["firm"])
    own = _scenario({"hands": {"inertia": 0.2, "damping": 2.0, "stiffness": 5.0}}).stack_hands
    assert own is not None and own.inertia == pytest.approx(DESIGN_SHARE * 0.2)


def test_a_torque_sensor_designs_for_no_hands() -> None:
    """A torque sensor measures the arms' whole torque: the stack models none of it."""
    sensed = _scenario({"hands": "relaxed"}, estimator={"name": "torque_sensor"})
    assert sensed.stack_hands is None


@pytest.mark.parametrize(
    ("tables", "message"),
    [
        ({"controller": {"grip": "loose"}}, "grip = 'loose'; expected one of relaxed, firm, off"),
        ({"controller": {"grip": "relaxed", "design": "d.toml"}}, "with a design file"),
        (
            {"controller": {"grip": "relaxed"}, "estimator": {"name": "torque_sensor"}},
            "with the torque sensor",
        ),
    ],
)
def test_a_grip_the_stack_cannot_model_is_refused(tables: dict, message: str) -> None:
    with pytest.raises(MotosimError, match=message):
        _scenario(**tables)


def test_the_default_rider_holds_the_handlebar_with_the_relaxed_grip() -> None:
    """Without ``hands`` the rider grips relaxed, and the stack is designed for that grip."""
    assert DEFAULT_GRIP == "relaxed"
    for sc in (Scenario(), _scenario()):
        assert sc.rider.hands is None and sc.models_hands
        assert sc.rider_hands == GRIPS["relaxed"]
        assert sc.stack_hands == design_hands(GRIPS["relaxed"])
    assert _scenario({"hands": "off"}).rider_hands == GRIPS["off"]
    assert _scenario({"hands": "firm"}).rider_hands == GRIPS["firm"]
    # the stack designed for the handlebar alone leaves the rider's default grip alone
    alone = _scenario(controller={"grip": "off"})
    assert alone.rider_hands == GRIPS["relaxed"] and alone.stack_hands is None


def test_the_multibody_motorcycles_rider_grips_relaxed_too() -> None:
    """The multibody front frame carries the arms (motosim.model.tyred.held) as Sharp's does:
    the same default grip, and a grip for the stack is accepted."""
    multibody = {"model": "multibody", "params": "sel2004_motorcycle"}
    sc = _scenario(motorcycle=multibody)
    assert sc.models_hands and sc.rider_hands == GRIPS["relaxed"]
    assert sc.stack_hands == design_hands(GRIPS["relaxed"])
    firm = _scenario(motorcycle=multibody, controller={"grip": "firm"})
    assert firm.stack_hands == design_hands(GRIPS["firm"])


@pytest.mark.parametrize(
    "tables",
    [
        {"controller": {"design": "d.toml"}},
        {"estimator": {"name": "torque_sensor"}},
    ],
    ids=["design file", "torque sensor"],
)
def test_where_the_stack_models_no_hands_the_default_rider_has_none(tables: dict) -> None:
    """A design file or the torque sensor: the default is no hands, and the scenario is
    accepted as it is."""
    sc = _scenario(**tables)
    assert not sc.models_hands
    assert sc.rider_hands is None and sc.stack_hands is None
