"""A scenario is parsed, and refused, without the numerical stack (issue 37's last gap).

:mod:`motosim.sim.scenario` and what it imports read neither SciPy, numba nor h5py: the names
and limits its check needs are in light modules (:mod:`motosim.choices`,
:mod:`motosim.sim.grips`) and :mod:`motosim.sim` imports its closed loop on first use. The
check is on ``sys.modules`` in a fresh interpreter, as in ``test_cli_light``.
"""

import dataclasses
import subprocess
import sys
from pathlib import Path

import pytest

HEAVY = ("scipy", "numba", "h5py", "motosim.sim.stack")
"""What a scenario's check must not import (seconds on a loaded machine)."""

_PARSE = """
import sys
from motosim.errors import MotosimError
from motosim.sim import Scenario, parse_scenario
good = parse_scenario({{
    "scenario": {{"name": "good"}},
    "rider": {{
        "kind": "virtual",
        "path": {{"kind": "lane_change", "offset": 3.0, "length": 30.0, "start": 20.0}},
        "hands": "firm",
    }},
    "estimator": {{"name": "kalman"}},
    "controller": {{"order": 3}},
}}, origin="good.toml")
assert isinstance(good, Scenario)
try:
    parse_scenario({bad!r}, origin="bad.toml")
except MotosimError as error:
    print(error)
print(sorted(m for m in {heavy!r} if m in sys.modules))
"""


@pytest.mark.parametrize(
    ("bad", "refusal"),
    [
        ({"scenario": {"name": "b"}, "motorcycle": {"drive_torque": 1e6}}, "drive_torque"),
        ({"scenario": {"name": "b"}, "controller": {"order": 9}}, "order = 9"),
        ({"scenario": {"name": "b"}, "estimator": {"name": "nope"}}, "kalman, torque_sensor"),
        ({"scenario": {"name": "b"}, "rider": {"kind": "virtual", "hands": "tight"}}, "firm"),
        ({"scenario": {"name": "b"}, "motorcycle": {"speed": 200.0}}, "speed"),
    ],
)
def test_a_scenario_parsed_and_refused_imports_nothing_heavy(
    bad: dict[str, object], refusal: str
) -> None:
    done = subprocess.run(
        [sys.executable, "-c", _PARSE.format(bad=bad, heavy=HEAVY)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-500:]
    error, heavy = done.stdout.strip().splitlines()
    assert error.startswith("bad.toml") and refusal in error
    assert heavy == "[]"


_COMMAND = """
import sys
from motosim.cli.main import main
code = main({argv!r})
print(code, sorted(m for m in {heavy!r} if m in sys.modules))
"""


@pytest.mark.parametrize(
    "argv",
    [
        ["simulate", "bad.toml", "--out", "r"],
        ["campaign", "campaign.toml", "--out", "c"],
        ["run", "bad.toml", "--bus", "virtual", "--out", "r"],
        ["rig", "bad.toml", "--bus", "virtual"],
    ],
    ids=lambda argv: argv[0],
)
def test_a_scenario_value_out_of_range_is_one_line_before_the_stack(
    tmp_path: Path, argv: list[str]
) -> None:
    (tmp_path / "bad.toml").write_text(
        '[scenario]\nname = "bad"\n[motorcycle]\ndrive_torque = 1e6\n', encoding="utf-8"
    )
    (tmp_path / "campaign.toml").write_text(
        '[campaign]\nscenario = "bad.toml"\nruns = 2\n', encoding="utf-8"
    )
    done = subprocess.run(
        [sys.executable, "-c", _COMMAND.format(argv=argv, heavy=HEAVY)],
        capture_output=True,
        text=True,
        check=False,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr[-500:]
    assert done.stdout.strip() == "2 []"
    assert done.stderr.startswith("motosim: error: bad.toml [motorcycle]: drive_torque reaches")
    assert done.stderr.count("\n") == 1


def test_the_light_names_equal_their_sources() -> None:
    from motosim import choices
    from motosim.control import torque_feedback
    from motosim.estimation import registry
    from motosim.sim import grips, hands, rider, scenario

    assert choices.ESTIMATOR_NAMES == tuple(registry.ESTIMATORS)
    assert choices.SENSOR_ESTIMATOR == registry.SENSOR_ESTIMATOR
    assert choices.GRIP_NAMES == tuple(grips.GRIPS)
    assert choices.MAX_ORDER == torque_feedback.MAX_ORDER
    assert choices.INTEGRAL_CORNER == torque_feedback.INTEGRAL_CORNER
    assert choices.RIDER_SPEEDS == rider.SPEED_RANGE
    profiles = [
        f.name for f in dataclasses.fields(scenario.Motorcycle) if f.type == scenario.Profile
    ]  # every profile of [motorcycle], in the table's order
    assert choices.MOTORCYCLE_PROFILES == tuple(profiles)
    assert hands.GRIPS is grips.GRIPS and hands.Hands is grips.Hands
