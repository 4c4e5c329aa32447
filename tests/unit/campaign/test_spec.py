"""Campaign files and their sample: validation, grids, Latin hypercubes, distributions, ids."""

import math
from pathlib import Path

import numpy as np
import pytest

from motosim.campaign import Campaign, Factor, parse_campaign, plan_campaign
from motosim.campaign.plan import is_design_factor, sample_values
from motosim.errors import MotosimError

BASE = """
[scenario]
name = "base"
duration = 0.2
[rider]
kind = "torque"
profile = { kind = "square", low = -10.0, high = 10.0, period = 0.1 }
[controller]
kind = "paper"
"""


def _doc(factors: dict[str, object], **head: object) -> dict[str, object]:
    return {"campaign": {"scenario": "base.toml", **head}, "factors": factors}


def _campaign(tmp_path: Path, factors: dict[str, object], **head: object) -> Campaign:
    (tmp_path / "base.toml").write_text(BASE)
    return parse_campaign(_doc(factors, **head), origin="c.toml", folder=tmp_path)


UNIFORM = {"distribution": "uniform", "low": 0.5, "high": 1.5}


@pytest.mark.parametrize(
    ("doc", "message"),
    [
        (_doc({"handlebar.inertia_factor": UNIFORM}), "runs: missing"),
        (_doc({}, runs=3), "at least one factor"),
        (_doc({"x": {"distribution": "triangular"}}, runs=3), "expected 'uniform'"),
        (_doc({"x": {"distribution": "uniform", "low": 2.0, "high": 1.0}}, runs=3), "low < high"),
        (_doc({"x": {"values": [1, 1]}}, runs=3), "distinct values"),
        (_doc({"x": {"valeus": [1]}}, runs=3), "did you mean 'values'"),
        (_doc({"x": [1.0, 2.0]}, runs=3, metrics=["rms_tau_error"]), "unknown metric"),
        (_doc({"x": UNIFORM}, sampling="grid"), "a grid needs values"),
        (_doc({"x": [1.0, 2.0]}, sampling="grid", runs=3), "multiple of the 2 grid points"),
        (_doc({"true_handlebar.J": [1.0]}, runs=3), "did you mean 'true_handlebar.J_"),
        ({"campaign": {"runs": 3}, "factors": {"x": [1.0]}}, "missing scenario"),
        (
            _doc({"x": [1.0]}, runs=3, metrics=["max_abs_phi"], limits={"max_abs_e_y": 1.0}),
            "not a kept metric",
        ),
        (_doc({"x": [1.0]}, runs=3, limits=[1.0]), "table of metric = limit"),
        (_doc({"x": [1.0]}, runs=3, series=["theta_hh"]), "did you mean 'theta_h'"),
        (_doc({"x": [1.0]}, runs=3, series="delta"), "list of signal names"),
        (_doc({"x": [1.0]}, runs=3, series=["t"]), "unknown signal 't'"),
        (_doc({"x": [1.0]}, runs=3, series=["delta", "delta"]), "each signal once"),
        (_doc({"x": [1.0]}, runs=3, series=["delta"], every=0), "every = 0"),
        (_doc({"x": [1.0]}, runs=3, every=10), "expected series"),
        # a grid of levels without runs: 1e9 points were planned one by one (a hang)
        (_doc({"x": {**UNIFORM, "levels": 10**9}}, sampling="grid"), "1e\\+09 points"),
        (
            _doc({k: {**UNIFORM, "levels": 10**4} for k in "xyz"}, sampling="grid"),
            "10000 x 10000 x 10000 = 1e\\+12 points; expected at most 10000000",
        ),
    ],
)
def test_invalid_campaigns_are_one_line_errors(doc: dict[str, object], message: str) -> None:
    with pytest.raises(MotosimError, match=message) as err:
        parse_campaign(doc, origin="c.toml", folder=".")
    assert "\n" not in str(err.value)


@pytest.mark.parametrize(
    ("factors", "message"),
    [
        ({"handlebar.inertia": [1.0]}, "did you mean 'handlebar.inertia_factor'"),
        ({"measurement.encoder_bits": UNIFORM}, "is an integer; expected values"),
        ({"measurement.encoder_bits": [12, 40]}, "encoder_bits = 40"),
        ({"rates.measurement": [300.0]}, "control / measurement"),
        ({"true_handlebar.J_eq": [0.01]}, "N\\^2 J_m"),
        ({"rider.profile.file": ["a.csv"]}, "not a key|cannot be a factor"),
    ],
)
def test_factors_are_checked_against_the_base_scenario(
    tmp_path: Path, factors: dict[str, object], message: str
) -> None:
    with pytest.raises(MotosimError, match=message):
        plan_campaign(_campaign(tmp_path, factors, runs=2))


def test_latin_hypercube_puts_one_run_in_each_stratum_of_each_factor(tmp_path: Path) -> None:
    # the defining property of a Latin hypercube (McKay, Beckman & Conover 1979): with n runs,
    # each factor's range cut into n equal strata holds exactly one run per stratum
    n = 50
    factors = {"handlebar.inertia_factor": UNIFORM, "handlebar.damping_factor": UNIFORM}
    rows = np.array(sample_values(_campaign(tmp_path, factors, runs=n, sampling="lhs")))
    for column in rows.T:
        strata = np.floor((column - 0.5) / (1.0 / n)).astype(int)
        assert sorted(strata) == list(range(n))


def test_distributions_stay_in_their_range_and_have_their_moments(tmp_path: Path) -> None:
    factors = {
        "handlebar.inertia_factor": {"distribution": "loguniform", "low": 0.1, "high": 10.0},
        "handlebar.damping_factor": {"distribution": "normal", "mean": 1.0, "std": 0.2, "low": 0.9},
    }
    rows = np.array(sample_values(_campaign(tmp_path, factors, runs=4000, sampling="random")))
    log = np.log10(rows[:, 0])
    assert log.min() >= -1.0 and log.max() <= 1.0
    assert abs(np.mean(log)) < 0.05  # log-uniform: uniform in log10 over [-1, 1]
    assert rows[:, 1].min() >= 0.9
    # a normal truncated below one half std under its mean: mean + std phi(a) / (1 - Phi(a)),
    # a = -0.5, phi(a) = 0.35207, 1 - Phi(a) = 0.69146 (standard normal tables)
    assert np.mean(rows[:, 1]) == pytest.approx(1.0 + 0.2 * 0.35207 / 0.69146, abs=0.01)


def test_a_grid_is_the_full_factorial_repeated(tmp_path: Path) -> None:
    factors = {
        "measurement.encoder_bits": [12, 14],
        "handlebar.inertia_factor": {
            "distribution": "uniform",
            "low": 0.5,
            "high": 1.5,
            "levels": 3,
        },
    }
    campaign = _campaign(tmp_path, factors, sampling="grid", runs=12)
    rows = sample_values(campaign)
    assert len(rows) == 12 and len(set(rows)) == 6
    assert {r[1] for r in rows} == {0.5, 1.0, 1.5}


def test_runs_have_stable_distinct_ids_seeds_and_shared_designs(tmp_path: Path) -> None:
    factors = {"handlebar.inertia_factor": UNIFORM, "rates.measurement": [100.0, 1000.0]}
    campaign = _campaign(tmp_path, factors, runs=20, seed=7)
    plan, again = plan_campaign(campaign), plan_campaign(campaign)
    assert plan.runs == again.runs
    assert len({r.run_id for r in plan.runs}) == 20
    assert len({r.seed for r in plan.runs}) == 20 and all(0 <= r.seed < 2**63 for r in plan.runs)
    # the measurement rate changes the design, the true inertia does not: two designs
    assert len(plan.designs) == 2
    other = plan_campaign(_campaign(tmp_path, factors, runs=20, seed=8))
    assert not {r.run_id for r in plan.runs} & {r.run_id for r in other.runs}


@pytest.mark.parametrize(
    ("path", "design"),
    [
        ("handlebar.inertia_factor", False),
        ("true_handlebar.k_t", False),
        ("measurement.encoder_bits", False),
        ("rider.profile.high", False),
        ("duration", False),
        ("rates.measurement", True),
        ("controller.bandwidth", True),
        ("handlebar.nominal", True),
        ("motorcycle.speed", True),
    ],
)
def test_design_factors(path: str, design: bool) -> None:
    assert is_design_factor(path) is design


def test_factor_needs_values_or_a_distribution() -> None:
    with pytest.raises(MotosimError, match="either values"):
        Factor("x")
    assert Factor("x", distribution="normal", mean=1.0, std=1.0).bounds() == (1.0,)
    assert math.isinf(Factor("x", values=(1.0,)).low)
