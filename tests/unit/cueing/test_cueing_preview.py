"""The road preview: the steady-turn lean of the road ahead, and the MPC planning with it."""

import dataclasses

import numpy as np
import pytest

from motosim.cueing import TELBAN_CARDULLO_2005, cue, load_platform
from motosim.cueing.preview import (
    LEAD_DISTANCE,
    SWAY_HEIGHT,
    SWAY_X,
    Road,
    arc_length,
    road_preview,
)
from motosim.errors import MotosimError
from motosim.timeseries import TimeSeries

G = 9.81


def _road(kappa: np.ndarray, ds: float = 0.05) -> Road:
    s = ds * np.arange(kappa.size)
    return Road(ds, s.copy(), np.zeros_like(s), kappa)


def test_steady_turn_and_curvature_ramp_against_the_steady_turn_lean() -> None:
    # the lean of a steady turn phi = atan(v^2 kappa / g) (Cossalter, Motorcycle Dynamics,
    # 2006, steady turning) on a curvature ramp kappa = c s: its rate in the time ahead is
    # d phi / d tau = (v^3 c / g) / (1 + (v^2 kappa / g)^2), and no force in a steady turn
    s = 0.05 * np.arange(40_000)
    c, v = 1e-5, 20.0
    ramp = _road(c * s)
    arc, speed = np.array([100.0, 500.0]), np.full(2, v)
    ahead = road_preview(ramp, arc, speed, horizon=20, step=0.05)
    tau = 0.05 * np.arange(21)
    lean_arg = v**2 * c * (arc[:, None] + LEAD_DISTANCE + v * tau) / G
    expected = (v**3 * c / G) / (1.0 + lean_arg**2)
    np.testing.assert_allclose(ahead[..., 0], expected, rtol=1e-3)
    # the force: SWAY_HEIGHT phi'' + SWAY_X v^2 c (yaw acceleration of the ramp)
    phi_ddot = -2 * lean_arg * (v**3 * c / G) * (v**3 * c / G) / (1 + lean_arg**2) ** 2
    np.testing.assert_allclose(
        ahead[..., 1], SWAY_HEIGHT * phi_ddot + SWAY_X * v**2 * c, rtol=1e-3, atol=1e-6
    )
    turn = road_preview(_road(np.full(s.size, 0.01)), arc, speed, horizon=20, step=0.05)
    np.testing.assert_allclose(turn, 0.0, atol=1e-9)


def test_arc_length_follows_the_road_and_bad_roads_are_refused() -> None:
    road = _road(np.zeros(4001))
    x = np.linspace(0.0, 150.0, 301)
    np.testing.assert_allclose(arc_length(road, x, np.full(x.size, 0.3)), x, atol=0.025)
    with pytest.raises(MotosimError, match="road ds = 0"):
        Road(0.0, np.zeros(3), np.zeros(3), np.zeros(3))
    with pytest.raises(MotosimError, match="expected the same number"):
        Road(0.05, np.zeros(3), np.zeros(2), np.zeros(3))
    with pytest.raises(MotosimError, match="smoothing = 0"):
        road_preview(road, x, x, horizon=2, step=0.05, smoothing=0.0)


def test_the_plan_follows_the_previewed_roll_and_no_preview_is_the_causal_plan() -> None:
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    from motosim.cueing.mpc import MpcCueing, design_mpc

    cfg = load_platform("simacom_platform")
    # the same force band's weight with and without the preview: only the prediction differs
    tuning = dataclasses.replace(cfg.mpc, preview_force_false_cue_weight=0.5)
    design = design_mpc(dataclasses.replace(cfg, mpc=tuning), TELBAN_CARDULLO_2005, 0.01)
    rate = np.radians(10.0)
    motion = np.array([rate, 0.0, 0.0, 0.0, 0.0])  # the motorcycle rolls at 10 deg/s
    held = np.tile([rate, 0.0], (tuning.horizon + 1, 1))  # the road: the roll goes on
    ends = held.copy()
    ends[4:] = 0.0  # the road: the roll ends 0.2 s ahead
    plans = [MpcCueing(design) for _ in range(4)]
    for _ in range(10):
        out = [
            plans[0].step(motion, np.zeros(3), None, held),
            plans[1].step(motion, np.zeros(3), None, ends),
            plans[2].step(motion, np.zeros(3)),
            plans[3].step(motion, np.zeros(3), None, None),
        ]
    # a roll that goes on is spread over the platform's travel; one that ends is given now
    assert out[1][0] > 1.1 * out[0][0] > 0.0
    assert out[1][0] > 1.1 * out[2][0]  # the causal plan's roll rate fades instead
    np.testing.assert_array_equal(out[3], out[2])
    from motosim.cueing.head import vehicle_motion
    from motosim.cueing.mpc import apply_mpc

    t = np.arange(0.0, 0.1, 0.01)
    still = TimeSeries(
        t,
        np.column_stack([20 + 0 * t, 0 * t, 0 * t, 0 * t, 0 * t]),
        ("v_x", "v_y", "psi_dot", "phi_dot", "phi"),
    )
    with pytest.raises(MotosimError, match=r"road preview of shape \(10, 20, 2\)"):
        apply_mpc(
            design,
            vehicle_motion(still, cfg.rider),
            np.zeros((10, 3)),
            preview=np.zeros((10, 20, 2)),
        )


def test_cue_needs_the_positions_for_a_road() -> None:
    t = np.arange(0.0, 1.0, 0.01)
    ride = TimeSeries(
        t,
        np.column_stack([20 + 0 * t, 0 * t, 0 * t, 0 * t, 0 * t]),
        ("v_x", "v_y", "psi_dot", "phi_dot", "phi"),
    )
    cfg = load_platform("simacom_platform")
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    with pytest.raises(MotosimError, match="road preview of a run without x and y"):
        cue(cfg, ride, TELBAN_CARDULLO_2005, algorithm="mpc", road=_road(np.zeros(10)))


def test_the_terminal_rows_band_the_held_tilt_as_the_otolith_feels_it() -> None:
    # the roll plan's last three force rows are the lateral force of the terminal tilt held,
    # COAST_TIMES after the horizon: for a platform at rest at a tilt a from t = 0 (otolith
    # at rest), -g a times the step response of Young & Meiry's otolith (the transfer
    # function of motosim.cueing.vestibular, evaluated by scipy.signal) at N h + t_c
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    from scipy.signal import step

    from motosim.cueing.head import GRAVITY
    from motosim.cueing.mpc import COAST_TIMES, design_mpc
    from motosim.cueing.vestibular import otolith_tf

    cfg = load_platform("simacom_platform")
    roll = design_mpc(cfg, TELBAN_CARDULLO_2005, 0.01).axes[0]
    a = np.radians(2.0)
    x0 = np.zeros(roll.A_loop.shape[0])
    x0[0] = x0[2] = a  # commanded and achieved angle, rate and vestibular states at rest
    end = cfg.mpc.horizon * cfg.mpc.step
    grid = np.linspace(0.0, 4.0, 4001)
    _, response = step(otolith_tf(TELBAN_CARDULLO_2005), T=grid)
    rows = roll.band_E[-len(COAST_TIMES) :] @ x0
    expected = -GRAVITY * a * np.interp([end + t for t in COAST_TIMES], grid, response)
    np.testing.assert_allclose(rows, expected, rtol=1e-4)
    # their slack costs the force band's weight on a road preview only
    thr = TELBAN_CARDULLO_2005.thresholds[4]
    np.testing.assert_array_equal(roll.band_lin[-len(COAST_TIMES) :], 0.0)
    np.testing.assert_allclose(
        roll.band_lin_preview[-len(COAST_TIMES) :], cfg.mpc.preview_force_false_cue_weight / thr
    )


def test_a_tilt_drawn_after_the_road_straightens_is_felt_less_with_the_terminal_rows(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # the mechanism of the 30 m/s lane change (docs/guide/cueing.md): on a straight road
    # ahead, the angle reference holds a tilt of 1.5 deg (the washout's onset after a return
    # roll); the perceived lateral force of the platform's tilt peaks about 1.9 s after it,
    # beyond the 1 s horizon, so without the terminal rows the plan holds more of it
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    import dataclasses

    import motosim.cueing.mpc as mpc
    from motosim.cueing import perceive, platform_motion

    # with the squared roll canal cost: the Huber corner is not reached here (0.19 of the
    # roll threshold), but its two variables per step change the 50-iteration iterate
    # (1.16 against 1.21 thresholds); converged, the rows lower the peak less (1.22 against
    # 1.24, OSQP with 4000 iterations; docs/guide/cueing.md)
    cfg0 = load_platform("simacom_platform")
    cfg = dataclasses.replace(cfg0, mpc=dataclasses.replace(cfg0.mpc, roll_canal_corner=0.0))
    straight = np.zeros((cfg.mpc.horizon + 1, 2))
    reference = np.array([np.radians(1.5), 0.0, 0.0])
    n = 400
    t = 0.01 * np.arange(n)
    peaks = []
    for coast in (mpc.COAST_TIMES, ()):
        monkeypatch.setattr(mpc, "COAST_TIMES", coast)
        plan = mpc.MpcCueing(mpc.design_mpc(cfg, TELBAN_CARDULLO_2005, 0.01))
        roll = np.array([plan.step(np.zeros(5), reference, None, straight)[0] for _ in t])
        motion = platform_motion(t, roll, 0 * t, 0 * t, cfg.platform)
        sway = perceive(TELBAN_CARDULLO_2005, motion)["sway"]
        peaks.append(float(np.max(np.abs(sway))) / TELBAN_CARDULLO_2005.thresholds[4])
    # 1.09 against 1.19 thresholds
    assert peaks[0] < 0.95 * peaks[1], peaks


def test_the_preview_fades_with_the_lean_asked_and_where_untrusted_is_the_causal_plan() -> None:
    from motosim.cueing.preview import LEAN_LIMIT, LEAN_TRUSTED, preview_trust

    # a road whose curvature asks, at 20 m/s, for steady-turn leans atan(v^2 kappa / g) of
    # 0, LEAN_TRUSTED, halfway to LEAN_LIMIT, and LEAN_LIMIT, 100 m each (Cossalter, 2006)
    v = 20.0
    leans = [0.0, LEAN_TRUSTED, 0.5 * (LEAN_TRUSTED + LEAN_LIMIT), LEAN_LIMIT]
    road = _road(np.repeat([np.tan(a) * G / v**2 for a in leans], 2000))
    arc = np.array([10.0, 110.0, 210.0, 310.0, 60.0])  # the last sees 61-81 m: straight
    trust = preview_trust(road, arc, np.full(5, v), ahead=1.0, lead=1.0)
    np.testing.assert_allclose(trust, [1.0, 1.0, 0.5, 0.0, 1.0], atol=1e-9)
    trust = preview_trust(road, np.array([290.0]), np.array([v]), ahead=1.0, lead=1.0)
    np.testing.assert_allclose(trust, 0.0, atol=1e-9)  # LEAN_LIMIT in sight, 291-311 m
    with pytest.raises(MotosimError, match="expected 0 <= trusted < limit"):
        preview_trust(road, arc, arc, ahead=1.0, trusted=1.0, limit=0.5)
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    from motosim.cueing.mpc import MpcCueing, design_mpc

    cfg = load_platform("simacom_platform")
    design = design_mpc(cfg, TELBAN_CARDULLO_2005, 0.01)
    rate = np.radians(10.0)
    motion = np.array([rate, 0.0, 0.0, 0.0, 0.5])
    ends = np.tile([rate, 0.0], (cfg.mpc.horizon + 1, 1))
    ends[4:] = 0.0  # the road says the roll ends 0.2 s ahead
    plans = [MpcCueing(design) for _ in range(3)]
    for _ in range(10):
        out = [
            plans[0].step(motion, np.zeros(3)),  # causal
            plans[1].step(motion, np.zeros(3), None, ends, 0.0),  # a road not trusted
            plans[2].step(motion, np.zeros(3), None, ends),  # trusted
        ]
    np.testing.assert_array_equal(out[1], out[0])  # exactly the causal plan
    assert out[2][0] > 1.01 * out[0][0], out  # the roll that ends is given now
    # a whole run on a road asking for a 60 deg lean: cue with it is the causal MPC's run
    t = np.arange(0.0, 2.0, 0.01)
    phi = 0.2 * np.sin(2 * np.pi * 0.5 * t)
    ride = TimeSeries(
        t,
        np.column_stack(
            [v + 0 * t, 0 * t, G * np.tan(phi) / v, np.gradient(phi, t), phi, v * t, 0 * t]
        ),
        ("v_x", "v_y", "psi_dot", "phi_dot", "phi", "x", "y"),
    )
    wavy = np.sin(0.05 * np.arange(4001) / 15.0)
    runs = [
        cue(cfg, ride, TELBAN_CARDULLO_2005, algorithm="mpc", road=road)
        for road in (
            None,
            _road(np.tan(np.radians(60)) * G / v**2 * wavy),
            _road(np.tan(np.radians(20)) * G / v**2 * wavy),
        )
    ]
    np.testing.assert_array_equal(runs[1].commands.data, runs[0].commands.data)
    assert not np.array_equal(runs[2].commands.data, runs[0].commands.data)
