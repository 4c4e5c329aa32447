"""The motorcycle tyres against their published coefficients and the properties they promise.

The sets are Evangelou's (2004, PhD thesis, Imperial College London, Tables 9.1-9.3 and 9.5),
tabulated in Sharp, Evangelou & Limebeer (2004), Multibody Syst. Dyn. 12:251-283, appendix;
the formulas are the MF-MC of Pacejka, Tyre and Vehicle Dynamics (2006), sec. 11.5, as in
motosim.model.tyres. The papers quote the coefficients, not the stiffnesses, so each
stiffness is checked twice: the curve's slope at zero slip against the coefficient product
(B C D), and that product against the number computed by hand from the tables.
"""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from motosim.errors import MotosimError
from motosim.model.tyres import (
    TyreCoefficients,
    camber_stiffness,
    cornering_stiffness,
    linear_tyre_coefficients,
    mf_forces,
    relax,
    relaxation_lengths,
    slip_rate,
    slip_stiffness,
    steady_forces,
    tyre_coefficients,
    tyre_curves,
)
from motosim.params import TyreParameters, load_parameters

FRONT = "sel2004_front_120_70_zr17"
REAR = "sel2004_rear_180_55_zr17"

# Normalised stiffnesses at F_z0, by hand from the tables (Evangelou 2004):
# K_x / F_z = p_Kx1 (Table 9.1) = 25.939 for both;
# K_y / F_z = p_Ky1 sin(p_Ky2 atan(1 / p_Ky3)) (Table 9.2):
#   front 22.841 sin(2.1578 atan(1 / 2.5058)) = 16.690, rear 15.791 sin(1.6935 atan(1 / 1.4604))
#   = 13.429 [1/rad];
# K_gamma / F_z = p_Ky6 (Table 9.2): front 0.69677, rear 0.45512 [1/rad];
# peaks: mu_x = p_Dx1 (Table 9.1) 1.3806 and 1.3548, mu_y = p_Dy1 (Table 9.2) 1.3 for both.
HAND = {
    FRONT: {"K_x": 25.939, "K_y": 16.690, "K_g": 0.69677, "mu_x": 1.3806, "mu_y": 1.3},
    REAR: {"K_x": 25.939, "K_y": 13.429, "K_g": 0.45512, "mu_x": 1.3548, "mu_y": 1.3},
}
# Normalised cornering stiffness of motorcycle tyres, 11-17 /rad: Cossalter, Motorcycle
# Dynamics (2006), ch. 2, as quoted by the project's reference notes (the book's table was not
# at hand to check the range against).
CORNERING_RANGE = (11.0, 17.0)


@pytest.fixture(scope="module", params=[FRONT, REAR])
def tyre(request: pytest.FixtureRequest) -> tuple[str, TyreParameters, TyreCoefficients]:
    params = load_parameters(request.param, "tyre")
    return request.param, params, tyre_coefficients(params)


def _slope(f: object, h: float = 1e-6) -> float:
    assert callable(f)
    return float((f(h) - f(-h)) / (2 * h))


def test_slopes_at_zero_slip_are_the_published_stiffnesses(
    tyre: tuple[str, TyreParameters, TyreCoefficients],
) -> None:
    name, p, c = tyre
    F_z = p.F_z0
    K_x = _slope(lambda k: mf_forces(c, F_z, k, 0.0, 0.0, 1.0)[0])
    K_y = _slope(lambda a: mf_forces(c, F_z, 0.0, a, 0.0, 1.0)[1])
    K_g = _slope(lambda g: mf_forces(c, F_z, 0.0, 0.0, g, 1.0)[1])
    # the curve's slope is the B C D product of the formula ...
    assert K_x == pytest.approx(slip_stiffness(c, F_z), rel=1e-6)
    assert K_y == pytest.approx(cornering_stiffness(c, F_z, 0.0), rel=1e-6)
    assert K_g == pytest.approx(camber_stiffness(c, F_z), rel=1e-6)
    # ... and that product is the number from the tables
    hand = HAND[name]
    assert K_x / F_z == pytest.approx(hand["K_x"], rel=1e-4)
    assert K_y / F_z == pytest.approx(hand["K_y"], rel=1e-4)
    assert K_g / F_z == pytest.approx(hand["K_g"], rel=1e-4)


def test_normalised_cornering_stiffness_lies_in_the_motorcycle_range(
    tyre: tuple[str, TyreParameters, TyreCoefficients],
) -> None:
    _, p, c = tyre
    assert CORNERING_RANGE[0] <= cornering_stiffness(c, p.F_z0, 0.0) / p.F_z0 <= CORNERING_RANGE[1]


def test_peak_friction_is_the_published_peak_factor(
    tyre: tuple[str, TyreParameters, TyreCoefficients],
) -> None:
    name, p, c = tyre
    kappa = np.linspace(-1.0, 1.0, 20001)
    F_x = tyre_curves(c, load=p.F_z0, kappa=kappa).F_x
    # C_x > 1 and E_x < 1 (Table 9.1): the peak D_x = p_Dx1 F_z is reached, driving and braking
    assert F_x.max() / p.F_z0 == pytest.approx(HAND[name]["mu_x"], abs=1e-6)
    assert -F_x.min() / p.F_z0 == pytest.approx(HAND[name]["mu_x"], abs=1e-6)
    # C_y < 1: side slip alone stays below D_y sin(C_y pi / 2); with camber the sine reaches 1
    alpha, gamma = np.meshgrid(np.linspace(0.0, 0.6, 601), np.linspace(0.0, 1.0, 201))
    F_y = tyre_curves(c, load=p.F_z0, alpha=alpha, gamma=gamma).F_y
    assert F_y.max() / p.F_z0 == pytest.approx(HAND[name]["mu_y"], abs=1e-4)
    pure = F_y[0] / p.F_z0
    assert pure.max() < HAND[name]["mu_y"] * math.sin(p.p_Cy1 * math.pi / 2)


@given(
    alpha=st.floats(-0.5, 0.5),
    gamma=st.floats(-1.0, 1.0),
    load=st.floats(0.3, 2.0),
)
def test_side_force_and_moments_are_odd_in_slip_and_camber(
    alpha: float, gamma: float, load: float
) -> None:
    for name in (FRONT, REAR):
        p = load_parameters(name, "tyre")
        c = tyre_coefficients(p)
        F_z = load * p.F_z0
        here = mf_forces(c, F_z, 0.0, alpha, gamma, 1.0)
        mirrored = mf_forces(c, F_z, 0.0, -alpha, -gamma, 1.0)
        assert mirrored[1] == pytest.approx(-here[1], rel=1e-12, abs=1e-9)
        assert mirrored[2] == pytest.approx(-here[2], rel=1e-12, abs=1e-9)
        assert mirrored[0] == pytest.approx(here[0], rel=1e-12, abs=1e-9)
        # each alone: the side force is odd in alpha at zero camber and in gamma at zero slip
        assert mf_forces(c, F_z, 0.0, -alpha, 0.0, 1.0)[1] == pytest.approx(
            -mf_forces(c, F_z, 0.0, alpha, 0.0, 1.0)[1], abs=1e-9
        )
        assert mf_forces(c, F_z, 0.0, 0.0, -gamma, 1.0)[1] == pytest.approx(
            -mf_forces(c, F_z, 0.0, 0.0, gamma, 1.0)[1], abs=1e-9
        )


@given(alpha=st.floats(0.01, 0.3), kappa=st.floats(0.01, 0.5))
def test_combined_slip_reduces_each_force(alpha: float, kappa: float) -> None:
    for name in (FRONT, REAR):
        p = load_parameters(name, "tyre")
        c = tyre_coefficients(p)
        F_x_pure, F_y_pure = (
            mf_forces(c, p.F_z0, kappa, 0.0, 0.0, 1.0)[0],
            mf_forces(c, p.F_z0, 0.0, alpha, 0.0, 1.0)[1],
        )
        F_x, F_y = mf_forces(c, p.F_z0, kappa, alpha, 0.0, 1.0)[:2]
        assert 0.0 <= F_x < F_x_pure
        assert 0.0 <= F_y < F_y_pure
        # braking too
        F_x_b, F_y_b = mf_forces(c, p.F_z0, -kappa, alpha, 0.0, 1.0)[:2]
        assert F_x_b > mf_forces(c, p.F_z0, -kappa, 0.0, 0.0, 1.0)[0]
        assert F_y_b < F_y_pure


def test_the_friction_ellipse_closes_at_full_slip(
    tyre: tuple[str, TyreParameters, TyreCoefficients],
) -> None:
    _, p, c = tyre
    # a locked wheel sliding sideways at 20 deg keeps less side force than at kappa = 0
    locked = mf_forces(c, p.F_z0, -1.0, math.radians(20.0), 0.0, 1.0)
    free = mf_forces(c, p.F_z0, 0.0, math.radians(20.0), 0.0, 1.0)
    assert abs(locked[1]) < 0.5 * abs(free[1])


def test_normalised_cornering_stiffness_falls_as_load_rises(
    tyre: tuple[str, TyreParameters, TyreCoefficients],
) -> None:
    _, p, c = tyre
    loads = np.linspace(0.3, 2.5, 23) * p.F_z0
    normalised = [cornering_stiffness(c, F_z, 0.0) / F_z for F_z in loads]
    assert np.all(np.diff(normalised) < 0.0)
    # the absolute stiffness still rises with load up to 1.5 F_z0 (p_Ky2 > 1: it peaks near
    # twice the nominal load)
    rising = loads[loads <= 1.5 * p.F_z0]
    assert np.all(np.diff([cornering_stiffness(c, F_z, 0.0) for F_z in rising]) > 0.0)


@given(mu=st.floats(0.1, 1.0))
def test_road_friction_scales_the_peak_not_the_stiffness(mu: float) -> None:
    for name in (FRONT, REAR):
        p = load_parameters(name, "tyre")
        c = tyre_coefficients(p)
        kappa = np.linspace(0.0, 0.5, 20001)
        F_x = tyre_curves(c, load=p.F_z0, kappa=kappa, mu=mu).F_x
        assert F_x.max() == pytest.approx(mu / p.mu_0 * p.p_Dx1 * p.F_z0, rel=1e-6)
        slope = _slope(lambda a, c=c, F_z=p.F_z0, m=mu: mf_forces(c, F_z, 0.0, a, 0.0, m)[1])
        assert slope == pytest.approx(cornering_stiffness(c, p.F_z0, 0.0), rel=1e-6)


def test_no_load_no_force(tyre: tuple[str, TyreParameters, TyreCoefficients]) -> None:
    _, _, c = tyre
    assert mf_forces(c, 0.0, 0.1, 0.1, 0.3, 1.0) == (0.0, 0.0, 0.0, 0.0)
    assert mf_forces(c, -10.0, 0.1, 0.1, 0.3, 1.0) == (0.0, 0.0, 0.0, 0.0)


def test_relaxation_length_follows_the_thesis_polynomial(
    tyre: tuple[str, TyreParameters, TyreCoefficients],
) -> None:
    # Evangelou 2004, sec. 9.3.10: sigma_y = K_y0 (c0 + c1 V + c2 V^2)
    _, p, c = tyre
    K_y0 = cornering_stiffness(c, p.F_z0, 0.0)
    for v in (0.0, 20.0, 50.0):
        expected = K_y0 * (p.sigma_c0 + p.sigma_c1 * v + p.sigma_c2 * v * v)
        assert relaxation_lengths(c, p.F_z0, v) == pytest.approx((p.sigma_x, expected))
        assert 0.1 <= expected <= 0.3  # the 0.1-0.3 m of motorcycle tyres


@pytest.mark.parametrize("speed", [5.0, 20.0, 50.0])
def test_relaxation_reaches_63_percent_after_one_relaxation_length(speed: float) -> None:
    sigma = 0.2
    time_constant = sigma / speed  # one relaxation length travelled
    # the exact update
    assert relax(0.0, 1.0, sigma, speed, time_constant) == pytest.approx(1.0 - math.exp(-1.0))
    # the rate integrated by RK4 in 1000 steps
    slip, h = 0.0, time_constant / 1000
    for _ in range(1000):
        k1 = slip_rate(slip, 1.0, sigma, speed)
        k2 = slip_rate(slip + h / 2 * k1, 1.0, sigma, speed)
        k3 = slip_rate(slip + h / 2 * k2, 1.0, sigma, speed)
        k4 = slip_rate(slip + h * k3, 1.0, sigma, speed)
        slip += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    assert slip == pytest.approx(1.0 - math.exp(-1.0), rel=1e-9)


def test_the_linear_tyre_is_sharps_at_its_load() -> None:
    sharp = load_parameters("sharp1971", "sharp")
    load = -sharp.Z_f
    c = linear_tyre_coefficients(
        nominal_load=load,
        cornering_stiffness=sharp.C_f1,
        camber_stiffness=sharp.C_f2,
        slip_stiffness=20.0 * load,
        relaxation_length=sharp.sigma,
        radius=sharp.R_f,
    )
    F_x, F_y, M_z, M_x = steady_forces(c, load, 0.01, 0.02, 0.1, 0.3)
    # Sharp 1971, Appendix 3: F_y = C_f1 alpha + C_f2 gamma at the static load, no limit
    assert F_y == pytest.approx(sharp.C_f1 * 0.02 + sharp.C_f2 * 0.1)
    assert F_x == pytest.approx(20.0 * load * 0.01)
    assert (M_z, M_x) == (0.0, 0.0)
    assert relaxation_lengths(c, load, 30.0) == (sharp.sigma, sharp.sigma)
    assert cornering_stiffness(c, 2 * load, 0.0) == pytest.approx(2 * sharp.C_f1)
    with pytest.raises(MotosimError, match="cornering_stiffness = -1"):
        linear_tyre_coefficients(
            nominal_load=load,
            cornering_stiffness=-1.0,
            camber_stiffness=0.0,
            slip_stiffness=1.0,
            relaxation_length=0.2,
            radius=0.3,
        )


def test_curves_refuse_bad_arrays(tyre: tuple[str, TyreParameters, TyreCoefficients]) -> None:
    _, _, c = tyre
    with pytest.raises(MotosimError, match="alpha has a value that is not finite"):
        tyre_curves(c, load=1000.0, alpha=[0.0, math.nan])
    with pytest.raises(MotosimError, match="do not broadcast"):
        tyre_curves(c, load=[1.0, 2.0], alpha=[0.0, 0.1, 0.2])


def test_bad_parameters_are_refused_in_one_line() -> None:
    p = load_parameters(FRONT, "tyre")
    from dataclasses import replace

    with pytest.raises(MotosimError, match=r"p_Cy1 \+ p_Cy2 = 2.03"):
        replace(p, p_Cy2=1.2)
    with pytest.raises(MotosimError, match="crown radius"):
        replace(p, R_c=0.29, R_0=0.28)
    with pytest.raises(MotosimError, match="lateral relaxation length"):
        replace(p, sigma_c0=0.0, sigma_c1=-1e-6)


def test_pneumatic_trail_at_small_slip_is_the_tables(
    tyre: tuple[str, TyreParameters, TyreCoefficients],
) -> None:
    # t0 = D_t = q_Dz1 R_c F_z / F_z0 (Table 9.3, R_c standing for R_o): at F_z0 front
    # 0.19796 x 0.06 = 11.9 mm, rear 0.26331 x 0.09 = 23.7 mm; the moment aligns (M_z < 0)
    _, p, c = tyre
    _, F_y, M_z, _ = mf_forces(c, p.F_z0, 0.0, 1e-6, 0.0, 1.0)
    assert -M_z / F_y == pytest.approx(p.q_Dz1 * p.R_c, rel=1e-6)


@given(
    kappa=st.floats(-1.0, 1.0),
    alpha=st.floats(-1.2, 1.2),
    gamma=st.floats(-1.0, 1.0),
    load=st.floats(0.05, 3.0),
    mu=st.floats(0.05, 1.5),
)
def test_forces_never_exceed_the_friction_limit(
    kappa: float, alpha: float, gamma: float, load: float, mu: float
) -> None:
    for name in (FRONT, REAR):
        p = load_parameters(name, "tyre")
        c = tyre_coefficients(p)
        F_z = load * p.F_z0
        dfz = load - 1.0
        F_x, F_y, M_z, M_x = mf_forces(c, F_z, kappa, alpha, gamma, mu)
        assert all(math.isfinite(v) for v in (F_x, F_y, M_z, M_x))
        assert abs(F_x) <= (p.p_Dx1 + p.p_Dx2 * dfz) * mu / p.mu_0 * F_z * (1 + 1e-12)
        assert abs(F_y) <= p.p_Dy1 * mu / p.mu_0 * F_z * (1 + 1e-12)
