"""The handlebar's torque-feedback design and its analysis (section IV, eqs. (18)-(26))."""

import math

import numpy as np
import pytest

from motosim.control import closed_loop_poles, four_block_norm
from motosim.control.torque_feedback import (
    PAPER_CONTROLLER,
    analyse_loop,
    default_bandwidth,
    design_torque_feedback,
    handlebar_plants,
)
from motosim.errors import MotosimError
from motosim.params import HandlebarParameters


@pytest.fixture(scope="module")
def design(handlebar: HandlebarParameters):  # type: ignore[no-untyped-def]
    return design_torque_feedback(handlebar, rng=np.random.default_rng(0), n_starts=4)


def test_plants_are_eq_19(handlebar: HandlebarParameters) -> None:
    G_h, G_w = handlebar_plants(handlebar)
    s = 3.0j
    want = handlebar.torque_per_amp / (handlebar.J_eq * s**2 + handlebar.beta_eq * s)
    got = (G_h.C @ np.linalg.solve(s * np.eye(2) - G_h.A, G_h.B))[0, 0]
    assert got == pytest.approx(want, rel=1e-12)
    got_w = (G_w.C @ np.linalg.solve(s * np.eye(2) - G_w.A, G_w.B))[0, 0]
    assert got_w == pytest.approx(want / handlebar.torque_per_amp, rel=1e-12)


def test_first_order_within_2_percent_of_full_order(design) -> None:  # type: ignore[no-untyped-def]
    assert design.gamma_min <= design.gamma <= 1.02 * design.gamma_min
    assert design.order == 1
    assert design.controller.n_states == 2  # K_s and the integrator of W1


def test_loop_meets_its_specification(design, handlebar: HandlebarParameters) -> None:  # type: ignore[no-untyped-def]
    a = design.analysis
    G_h, _ = handlebar_plants(handlebar)
    assert np.all(closed_loop_poles(G_h, design.controller).real < 0)
    assert 8.0 < a.tracking_bandwidth < 16.0  # the 10 Hz asked for
    assert a.phase_margin_deg > 45.0
    assert math.isinf(a.stiffness)  # integral action: no steady deflection under rider torque
    assert a.robust_over_50_percent
    assert all(radius < 1.0 for radius in a.discrete_radius.values())
    # the implemented K = W1 K_s: its shaped loop reaches the tuned gamma
    assert four_block_norm(G_h, design.controller) > 1.0


def test_paper_controller_on_our_plant(handlebar: HandlebarParameters) -> None:
    # sqrt(1 + 2.355^2) = 2.5585: G_h vanishes at infinite frequency, where the four-block
    # transfer tends to [[1, 0], [K(inf), 0]]; N k_t only scales G_h, not that limit
    paper = analyse_loop(handlebar, PAPER_CONTROLLER, rate=1000.0)
    assert paper.four_block_gamma == pytest.approx(math.sqrt(1 + 2.355**2), rel=1e-9)
    assert paper.robust_over_50_percent
    # K(0) = -613.7 / 1445 A/rad: a finite stiffness N k_t |K(0)|
    assert paper.stiffness == pytest.approx(handlebar.torque_per_amp * 613.7 / 1445, rel=1e-9)


def test_ours_tracks_and_rejects_better_than_the_paper(
    design, handlebar: HandlebarParameters
) -> None:  # type: ignore[no-untyped-def]
    paper = analyse_loop(handlebar, PAPER_CONTROLLER, rate=1000.0)
    assert design.analysis.tracking_error_1hz < 0.2 * paper.tracking_error_1hz
    assert design.analysis.compliance_1hz < 0.2 * paper.compliance_1hz


def test_bad_options(handlebar: HandlebarParameters) -> None:
    with pytest.raises(MotosimError, match="at most a fifth"):
        design_torque_feedback(handlebar, rng=np.random.default_rng(0), bandwidth=300.0)
    with pytest.raises(MotosimError, match="rate"):
        design_torque_feedback(handlebar, rng=np.random.default_rng(0), rate=-1.0)
    # 1e-300 reached the search (SciPy's warnings, then "no stabilising controller")
    for corner in (0.0, 1e-300, 9e-7, 0.6, math.nan):
        with pytest.raises(MotosimError, match="integral_corner"):
            design_torque_feedback(handlebar, rng=np.random.default_rng(0), integral_corner=corner)


def test_integral_corner_trades_phase_for_stiffness(design, handlebar: HandlebarParameters) -> None:  # type: ignore[no-untyped-def]
    """W1 = g (s + a) / s: moving a from a tenth to a fifth of the crossover raises the loop
    gain below it by up to |1 + 2 j w_c / (10 w)| / |1 + j w_c / (10 w)| (1.58 at 1 Hz for a
    10 Hz crossover) and takes atan(0.2) - atan(0.1) = 5.6 deg of phase at the crossover."""
    stiff = design_torque_feedback(
        handlebar, rng=np.random.default_rng(0), n_starts=4, integral_corner=0.2
    )
    assert stiff.weight_corner == pytest.approx(2.0 * design.weight_corner, rel=1e-12)
    assert stiff.analysis.tracking_error_1hz < 0.75 * design.analysis.tracking_error_1hz
    assert stiff.analysis.compliance_1hz < 0.75 * design.analysis.compliance_1hz
    lost = design.analysis.phase_margin_deg - stiff.analysis.phase_margin_deg
    assert 2.0 < lost < 10.0
    assert stiff.analysis.phase_margin_deg > 45.0


def test_default_bandwidth_depends_on_the_rate() -> None:
    """10 Hz, or a fifth of the rate below 50 Hz, the most the design admits (the whole
    stack's margins at 100 Hz, where 10 Hz keeps more than 20 Hz, are in
    tests/unit/test_loop_analysis.py)."""
    assert default_bandwidth(1000.0) == 10.0
    assert default_bandwidth(200.0) == 10.0
    assert default_bandwidth(190.0) == 10.0
    assert default_bandwidth(100.0) == 10.0
    assert default_bandwidth(80.0) == 10.0  # 16 Hz is unstable there
    assert default_bandwidth(40.0) == pytest.approx(8.0)
    with pytest.raises(MotosimError, match="rate"):
        default_bandwidth(0.0)
