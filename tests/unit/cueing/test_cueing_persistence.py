"""The force band's weight scheduled by the persistence of the curve ahead."""

import dataclasses

import numpy as np
import pytest

from motosim.cueing import TELBAN_CARDULLO_2005, cue, load_platform
from motosim.cueing.preview import PERSISTENCE_FLOOR, Road, curve_persistence
from motosim.errors import MotosimError
from motosim.timeseries import TimeSeries

G = 9.81
V = 20.0


def _kappa(lean_deg: float) -> float:
    # the curvature of the steady turn of that lean at V: tan(phi) = v^2 kappa / g
    # (Cossalter, Motorcycle Dynamics, 2006, steady turning)
    return float(np.tan(np.radians(lean_deg)) * G / V**2)


def _road(kappa: np.ndarray, ds: float = 0.05) -> Road:
    s = ds * np.arange(kappa.size)
    return Road(ds, s.copy(), np.zeros_like(s), kappa)


def _pieces(*parts: tuple[float, float]) -> np.ndarray:
    """Curvature every 0.05 m from (length [m], lean [deg]) pieces."""
    return np.concatenate([np.full(round(length / 0.05), _kappa(lean)) for length, lean in parts])


def test_a_long_curve_is_sustained_a_swerve_and_a_straight_are_not() -> None:
    # window +/-3 s at 20 m/s: +/-60 m around s + 1 m
    curve = _road(_pieces((200.0, 0.0), (600.0, 15.0)))
    at = np.array([150.0, 190.0, 400.0, 700.0])  # before, entering, in, held
    p = curve_persistence(curve, at, np.full(at.size, V), ahead=3.0, behind=3.0)
    np.testing.assert_allclose(p, 1.0, atol=1e-12)  # one-signed wherever the curve is seen
    # a swerve: 15 deg one way for 20 m, the other way for 20 m; seen whole, the lean's mean
    # is zero
    swerve = _road(_pieces((200.0, 0.0), (20.0, 15.0), (20.0, -15.0), (200.0, 0.0)))
    p = curve_persistence(swerve, np.array([219.0]), np.array([V]), ahead=3.0, behind=3.0)
    np.testing.assert_allclose(p, 0.0, atol=0.01)
    # a straight is at 0; a curve whose lean stays under the floor counts by its mean lean
    straight = _road(np.zeros(8000))
    p = curve_persistence(straight, np.array([200.0]), np.array([V]), ahead=3.0, behind=3.0)
    np.testing.assert_array_equal(p, 0.0)
    gentle = _road(_pieces((400.0, 0.5)))
    p = curve_persistence(gentle, np.array([200.0]), np.array([V]), ahead=3.0, behind=3.0)
    np.testing.assert_allclose(p, np.radians(0.5) / PERSISTENCE_FLOOR, rtol=1e-6)
    # the floor is the lean whose tilt is felt at the otolith's threshold, 0.17 m/s^2
    assert G * np.sin(PERSISTENCE_FLOOR) == pytest.approx(0.17)
    with pytest.raises(MotosimError, match="curve persistence ahead = 0"):
        curve_persistence(curve, at, at, ahead=0.0)
    with pytest.raises(MotosimError, match="curve persistence behind = -1"):
        curve_persistence(curve, at, at, ahead=1.0, behind=-1.0)


def test_the_band_weight_is_blended_by_the_persistence() -> None:
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    from motosim.cueing.mpc import MpcCueing, design_mpc

    cfg = load_platform("simacom_platform")
    design = design_mpc(cfg, TELBAN_CARDULLO_2005, 0.01)
    roll = design.axes[0]
    thr = TELBAN_CARDULLO_2005.thresholds[4]
    force = slice(roll.band_steps[0].size, None)
    np.testing.assert_allclose(
        roll.band_lin_sustained[force], cfg.mpc.sustained_force_false_cue_weight / thr
    )
    np.testing.assert_array_equal(  # the rotation's band is not scheduled
        roll.band_lin_sustained[: force.start], roll.band_lin_preview[: force.start]
    )
    # a long steady curve: the motorcycle leaned and balanced (no roll rate, no lateral
    # force at the head), the road ahead the same; the angle reference (the washout's) holds
    # a 5 deg tilt, whose lateral force the motorcycle does not give
    steady = np.zeros((cfg.mpc.horizon + 1, 2))
    reference = np.array([np.radians(-5.0), 0.0, 0.0])
    plans = [MpcCueing(design) for _ in range(3)]
    for _ in range(300):
        out = [
            plans[0].step(np.zeros(5), reference, None, steady),
            plans[1].step(np.zeros(5), reference, None, steady, 1.0, 0.0),
            plans[2].step(np.zeros(5), reference, None, steady, 1.0, 1.0),
        ]
    np.testing.assert_array_equal(out[1], out[0])  # persistence 0: the transient design
    # the sustained curve's lighter band lets the plan hold more of the tilt
    assert out[2][0] < 1.5 * out[1][0] < 0.0, out


def test_on_a_long_curve_the_platform_holds_more_tilt_than_with_the_transient_band() -> None:
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    # a ride along a long curve: 40 m straight, a 60 m clothoid to a 15 deg lean, 140 m held;
    # the motorcycle at the steady-turn lean of the road under it (the road's x, y straight:
    # only the curvature is read)
    kappa = np.concatenate(
        [np.zeros(800), np.linspace(0.0, _kappa(15.0), 1200), np.full(4000, _kappa(15.0))]
    )
    road = _road(kappa)
    t = np.arange(0.0, 11.0, 0.01)
    s = V * t
    phi = np.arctan(V**2 * np.interp(s, 0.05 * np.arange(kappa.size), kappa) / G)
    ride = TimeSeries(
        t,
        np.column_stack(
            [V + 0 * t, 0 * t, G * np.tan(phi) / V, np.gradient(phi, t), phi, s, 0 * t]
        ),
        ("v_x", "v_y", "psi_dot", "phi_dot", "phi", "x", "y"),
    )
    cfg = load_platform("simacom_platform")
    transient = dataclasses.replace(
        cfg,
        mpc=dataclasses.replace(
            cfg.mpc, sustained_force_false_cue_weight=cfg.mpc.preview_force_false_cue_weight
        ),
    )
    runs = [
        cue(c, ride, TELBAN_CARDULLO_2005, algorithm="mpc", road=road) for c in (cfg, transient)
    ]
    held = [float(np.mean(r.commands["phi_s"][t > 8.0])) for r in runs]
    assert held[0] > 1.2 * held[1] > 0.0, np.degrees(held)
    assert [r.score.violations for r in runs] == [0, 0]
