"""The targets of section V.A (paper Figs. 9-14) on the study cases, for every estimator.

Targets (issue: rider-torque estimation): nominal noise-free 1 kHz square torque 10/70 N*m,
RMS error below 2 % of the step outside 0.1 s after each step and convergence within 0.1 s;
+/-50 % inertia and damping error: bounded, RMS below 8 %; 100 Hz with 14-bit quantisation:
below 15 % and better than every baseline.
"""

import numpy as np
import pytest

from motosim.estimation import ESTIMATORS
from motosim.estimation.study import PAPER_CASES, Case, run_case
from motosim.params import HandlebarParameters

CASES = {case.name: case for case in PAPER_CASES}


def test_nominal_converges_in_finite_time(handlebar: HandlebarParameters) -> None:
    out = run_case(CASES["nominal, no friction, 1 kHz"], handlebar, "walcott_zak")
    assert out.relative_rms < 0.02
    assert out.convergence_time < 0.1


@pytest.mark.parametrize("factor", [0.5, 1.5])
def test_half_wrong_inertia_and_damping_stays_bounded(
    handlebar: HandlebarParameters, factor: float
) -> None:
    case = Case("perturbed", 1000.0, inertia_factor=factor, damping_factor=factor)
    out = run_case(case, handlebar, "walcott_zak")
    assert out.relative_rms < 0.08
    assert np.max(np.abs(out.tau_r_hat)) < 2 * case.high  # bounded: no divergence


def test_friction_compensation_helps(handlebar: HandlebarParameters) -> None:
    on = run_case(CASES["dry friction, compensated, 1 kHz"], handlebar, "walcott_zak")
    off = run_case(CASES["dry friction, not compensated, 1 kHz"], handlebar, "walcott_zak")
    assert on.relative_rms < 0.02 < off.relative_rms


def test_100_hz_quantised_beats_every_baseline(handlebar: HandlebarParameters) -> None:
    case = CASES["dry friction, 14-bit encoder, 100 Hz"]
    ours = run_case(case, handlebar, "walcott_zak").relative_rms
    assert ours < 0.15
    for name in ESTIMATORS:
        if name != "walcott_zak":
            assert ours < run_case(case, handlebar, name).relative_rms
