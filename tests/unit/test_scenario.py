"""Scenario files: the documented schema and its one-line errors."""

import tomllib

import pytest

from motosim.errors import MotosimError
from motosim.sim import parse_scenario
from motosim.sim.scenario import TurnPath, scenario_dict, scenario_from_dict

MINIMAL = """
[scenario]
name = "minimal"
[rider]
kind = "torque"
profile = { kind = "constant", value = 1.0 }
"""


def _parse(text: str):  # type: ignore[no-untyped-def]
    return parse_scenario(tomllib.loads(text), origin="s.toml")


def test_defaults() -> None:
    sc = _parse(MINIMAL)
    assert sc.duration == 10.0 and sc.architecture == "closed_loop"
    assert (sc.rates.plant, sc.rates.control, sc.rates.measurement) == (10_000.0, 1000.0, 1000.0)
    assert sc.estimator.name == "walcott_zak" and sc.controller.kind == "ours"
    assert sc.motorcycle.speed == 20.0 and sc.handlebar.friction


def test_virtual_rider_and_profiles() -> None:
    sc = _parse(
        """
[scenario]
duration = 5.0
[motorcycle]
speed = 15.0
brake_torque = { kind = "steps", times = [1.0, 2.0], values = [100.0, 0.0] }
[rider]
kind = "virtual"
path = { kind = "turn", radius = -150.0, angle = 0.5, start = 10.0, transition = 20.0 }
"""
    )
    assert isinstance(sc.rider.path, TurnPath) and sc.rider.path.radius == -150.0
    assert sc.motorcycle.brake_torque.kind == "steps"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (MINIMAL + "[rates]\ncontrol = 1000.0\nmeasurement = 300.0\n", "control / measurement"),
        (MINIMAL + "[rates]\nplant = 500.0\n", "plant / control = 0.5"),
        (MINIMAL.replace('name = "minimal"', "duration = -1.0"), "duration = -1.0"),
        (MINIMAL.replace('name = "minimal"', "duration = nan"), "duration = nan"),
        (MINIMAL + "[motorcycle]\nspeed = 0.5\n", "speed = 0.5; expected a finite number >= 1"),
        (MINIMAL + "[motorcycle]\ncolour = 'red'\n", "unknown key 'colour'"),
        (MINIMAL + "[weather]\nrain = true\n", "unknown key 'weather'"),
        (
            MINIMAL.replace('kind = "constant", value = 1.0', 'kind = "sawtooth"'),
            "kind = 'sawtooth'",
        ),
        (MINIMAL.replace("value = 1.0", "value = 1.0, extra = 2"), "unknown key 'extra'"),
        (
            MINIMAL.replace('kind = "torque"\n', 'kind = "torque"\n').replace(
                "profile = ", "prof = "
            ),
            "unknown key 'prof' (did you mean 'profile'?)",
        ),
        (MINIMAL.replace("profile = ", "# no profile "), "missing profile"),
        (MINIMAL + "[estimator]\nname = 'oracle'\n", "name = 'oracle'; expected one of"),
        (MINIMAL + "[controller]\nkind = 'pid'\n", "kind = 'pid'"),
        (MINIMAL + "[controller]\nintegral_corner = 0.7\n", "integral_corner = 0.7"),
        (
            MINIMAL + "[controller]\nprediction = true\nfeedforward = ['reference']\n",
            'prediction = true predicts the rider-torque cancellation; expected "rider"',
        ),
        (
            MINIMAL + "[controller]\nprediction = true\n[estimator]\nname = 'kalman'\n",
            "prediction = true with [estimator] name = 'kalman'; expected \"walcott_zak\"",
        ),
        (MINIMAL + "[controller]\nprediction = 1\n", "prediction = 1; expected true or false"),
        (MINIMAL + "[handlebar]\ninertia_factor = 0.0\n", "inertia_factor = 0.0"),
        (MINIMAL + "[measurement]\nencoder_bits = 40\n", "encoder_bits = 40"),
        (
            MINIMAL.replace(
                'kind = "constant", value = 1.0',
                'kind = "steps", times = [2.0, 1.0], values = [1.0, 2.0]',
            ),
            "expected increasing times",
        ),
        (  # a chirp to 1e9 Hz was accepted and sampled into aliased noise
            MINIMAL.replace(
                'kind = "constant", value = 1.0',
                'kind = "chirp", amplitude = 5.0, f0 = 0.1, f1 = 1e9',
            ),
            "f1 = 1000000000.0; expected a finite number >= 0 and <= 10000 [Hz]",
        ),
        (  # 6 kHz on the default 10 kHz plant is sampled into 4 kHz
            MINIMAL.replace(
                'kind = "constant", value = 1.0',
                'kind = "chirp", amplitude = 5.0, f0 = 0.1, f1 = 6000.0',
            ),
            "[rider] profile: a chirp up to 6000 Hz; expected at most 5000 Hz, half [rates] plant",
        ),
        (  # the side wind is sampled at the control rate (1 kHz by default), not the plant's
            MINIMAL
            + "[motorcycle]\nside_wind = { kind = 'chirp', amplitude = 1.0, f0 = 800.0, "
            + "f1 = 900.0 }\n",
            "[motorcycle] side_wind: a chirp up to 900 Hz; expected at most 500 Hz, half [rates] "
            "control = 1000 Hz",
        ),
        (
            MINIMAL
            + "[motorcycle]\nside_wind = { kind = 'multisine', amplitude = 1.0, f0 = 1.0, "
            + "f1 = 90.0, period = 10.0 }\n[rates]\nplant = 1000.0\ncontrol = 100.0\n"
            + "measurement = 100.0\n",
            "[motorcycle] side_wind: a multisine up to 90 Hz; expected at most 50 Hz",
        ),
        (  # a list of [t0, t1] pairs, not of tables
            MINIMAL.replace('kind = "torque"\n', 'kind = "torque"\nhands_off = "0:1"\n'),
            "hands_off = '0:1'; expected a list of lists of numbers",
        ),
        (  # an empty table of the arms' impedance names nothing: "off" says no hands
            MINIMAL.replace('kind = "torque"\n', 'kind = "torque"\nhands = {}\n'),
            "hands = {}; expected one of relaxed, firm, off or a table",
        ),
        ("[rider]\nkind = 'virtual'\n", "missing table [scenario]"),
        (
            "[scenario]\n[motorcycle]\nspeed = 2.0\n[rider]\nkind = 'virtual'\n",
            "speed = 2.0; expected 3 to 60 m/s with the virtual rider",
        ),
    ],
)
def test_bad_scenarios(text: str, message: str) -> None:
    with pytest.raises(MotosimError) as info:
        _parse(text)
    assert message in str(info.value) and "\n" not in str(info.value)
    assert str(info.value).startswith("s.toml")


def test_round_trip_through_plain_data() -> None:
    sc = _parse(
        MINIMAL
        + "[motorcycle]\nbrake_torque = { kind = 'square', low = 0.0, high = 5.0, period = 2.0 }\n"
    )
    assert scenario_from_dict(scenario_dict(sc), origin="meta") == sc
