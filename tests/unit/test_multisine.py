"""The periodic multisine probe: lines on the period's harmonics, periodic, its peak as asked."""

import tomllib

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.sim import parse_scenario
from motosim.sim.scenario import MultisineProfile, scenario_dict, scenario_from_dict


def test_lines_are_distinct_harmonics_of_the_period_spanning_the_band() -> None:
    probe = MultisineProfile(3.0, 0.1, 5.0, 20.0)
    f = probe.frequencies()
    k = f * probe.period
    assert np.allclose(k, np.round(k)) and np.all(np.diff(k) >= 1)
    assert f[0] == pytest.approx(0.1) and f[-1] == pytest.approx(5.0)
    # about 12 lines a decade over 1.7 decades, fewer where harmonics are 0.05 Hz apart
    assert 15 <= f.size <= 22


def test_periodic_with_the_asked_peak_and_zero_before_start() -> None:
    probe = MultisineProfile(3.0, 0.1, 5.0, 20.0, start=1.0)
    t = np.arange(0.0, 61.0, 1e-3)
    x = probe.sample(t, {})
    assert np.all(x[t < 1.0] == 0.0)
    one = round(20.0 / 1e-3)
    after = t >= 1.0
    assert np.max(np.abs(x[after][:one] - x[after][one : 2 * one])) < 1e-9
    assert np.max(np.abs(x)) == pytest.approx(3.0, rel=0.01)
    # each line carries the same power: the spectrum of one period is flat on the lines
    spectrum = np.abs(np.fft.rfft(x[after][:one]))
    lines = np.round(probe.frequencies() * 20.0).astype(int)
    assert np.ptp(spectrum[lines]) < 1e-6 * spectrum[lines].max()
    off = np.setdiff1d(np.arange(spectrum.size), lines)
    assert spectrum[off].max() < 1e-6 * spectrum[lines].max()


def test_parsed_from_a_scenario_and_round_trips() -> None:
    sc = parse_scenario(
        tomllib.loads(
            """
[scenario]
name = "feel"
[rider]
kind = "virtual"
probe = { kind = "multisine", amplitude = 3.0, f0 = 0.1, f1 = 5.0, period = 20.0 }
"""
        ),
        origin="s.toml",
    )
    assert isinstance(sc.rider.probe, MultisineProfile) and sc.rider.probe.per_decade == 12
    assert scenario_from_dict(scenario_dict(sc), origin="meta") == sc


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"f0": 0.01}, "f0 = 0.01"),
        ({"f1": 0.05}, "f1 = 0.05"),
        ({"period": -1.0}, "period = -1"),
        ({"amplitude": float("nan")}, "amplitude = nan"),
    ],
)
def test_bad_multisines(kwargs: dict[str, float], message: str) -> None:
    args = {"amplitude": 3.0, "f0": 0.1, "f1": 5.0, "period": 20.0} | kwargs
    with pytest.raises(MotosimError) as info:
        MultisineProfile(**args)  # type: ignore[arg-type]
    assert message in str(info.value) and "\n" not in str(info.value)
