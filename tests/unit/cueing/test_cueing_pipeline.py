"""The cueing chain on a synthetic ride: limits kept, MPC within limits, one-line errors."""

import numpy as np
import pytest

from motosim.cueing import TELBAN_CARDULLO_2005, cue, decimate, load_platform
from motosim.errors import MotosimError
from motosim.timeseries import TimeSeries


def _ride(rate: float = 100.0, duration: float = 12.0) -> TimeSeries:
    """A slalom with braking: lean to +/-25 deg at 0.25 Hz, speed 20 -> 12 m/s."""
    t = np.arange(0.0, duration, 1.0 / rate)
    v_x = np.where(t < 4.0, 20.0, np.maximum(12.0, 20.0 - 4.0 * (t - 4.0)))
    phi = np.radians(25.0) * np.sin(0.5 * np.pi * t) * np.minimum(1.0, t / 2.0)
    phi_dot = np.gradient(phi, t)
    psi_dot = 9.81 * np.tan(phi) / v_x
    data = np.column_stack([v_x, 0 * t, psi_dot, phi_dot, phi])
    return TimeSeries(t, data, ("v_x", "v_y", "psi_dot", "phi_dot", "phi"))


@pytest.mark.parametrize("algorithm", ["washout", "mpc"])
def test_no_limit_violation_and_a_roll_cue_in_phase(algorithm: str) -> None:
    if algorithm == "mpc":
        pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    cfg = load_platform("simacom_platform")
    run = cue(cfg, _ride(), TELBAN_CARDULLO_2005, algorithm=algorithm)  # type: ignore[arg-type]
    assert run.score.violations == 0
    assert all(m > -1e-6 for margins in run.score.margins.values() for m in margins)
    assert run.score.channels["roll"].correlation > 0.8
    np.testing.assert_allclose(
        run.commands["phi_s"] + run.commands["phi_vis"],
        cfg.washout.horizon_gain * _ride()["phi"],
        atol=1e-12,
    )


def test_decimate_and_bad_inputs() -> None:
    ride = _ride(rate=1000.0, duration=1.0)
    assert decimate(ride, 100.0).t.size == 100
    with pytest.raises(MotosimError, match="integer divisor"):
        decimate(ride, 300.0)
    cfg = load_platform("simacom_platform")
    with pytest.raises(MotosimError, match="cueing algorithm 'lqr'"):
        cue(cfg, ride, TELBAN_CARDULLO_2005, algorithm="lqr")  # type: ignore[arg-type]


def test_mpc_rests_at_neutral_and_refuses_a_slow_loop() -> None:
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    from motosim.cueing.mpc import MpcCueing, design_mpc

    cfg = load_platform("simacom_platform")
    mpc = MpcCueing(design_mpc(cfg, TELBAN_CARDULLO_2005, 0.01))
    for _ in range(20):
        out = mpc.step(np.zeros(5), np.zeros(3))
    np.testing.assert_allclose(out, 0.0, atol=1e-9)
    with pytest.raises(MotosimError, match="<= the MPC step"):
        design_mpc(cfg, TELBAN_CARDULLO_2005, 0.1)


def test_mpc_vehicle_prediction_fades_with_its_time_constant() -> None:
    from motosim.cueing.mpc import _vehicle_prediction

    # an integrator 1/s driven by w_h + w_f exp(-t / tau) reaches w_h t + w_f tau (1 -
    # exp(-t / tau)): the held part integrates to a ramp, the fading part saturates
    tau, h, N = 0.3, 0.05, 20
    out = _vehicle_prediction(np.zeros((1, 1)), np.ones(1), np.ones(1), h, N, tau)
    t = h * np.arange(1, N + 1)
    np.testing.assert_allclose(out[:, 1], t, rtol=1e-9)
    np.testing.assert_allclose(out[:, 2], tau * (1 - np.exp(-t / tau)), rtol=1e-9)
    np.testing.assert_allclose(out[:, 0], 1.0)  # the state itself is held by 1/s


def test_mpc_rolls_faster_with_a_fading_prediction_than_with_a_held_one() -> None:
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    import dataclasses

    from motosim.cueing.mpc import MpcCueing, design_mpc

    # a 60 deg/s lean rate (beyond the platform's 30 deg/s): held over the 1 s horizon, the
    # plan spreads the platform's 20 deg of travel over it (about 20 deg/s); faded with the
    # 0.15 s of the platform file, it rolls at the onset as fast as it can (1e4 s, the longest
    # prediction time a platform file admits, is a held motion over a 1 s horizon); the
    # lateral-force false-cue band, which slows a roll onset for both, is off
    cfg = load_platform("simacom_platform")
    cfg = dataclasses.replace(cfg, mpc=dataclasses.replace(cfg.mpc, force_false_cue_weight=0.0))
    held = dataclasses.replace(cfg, mpc=dataclasses.replace(cfg.mpc, prediction_time=1e4))
    motion = np.array([np.radians(60.0), 0.0, 0.0, 0.0, 0.0])
    peaks = []
    for config in (cfg, held):
        mpc = MpcCueing(design_mpc(config, TELBAN_CARDULLO_2005, 0.01))
        rates = []
        for _ in range(40):
            mpc.step(motion, np.zeros(3))
            rates.append(mpc.rates[0])
        peaks.append(np.degrees(max(rates)))
    assert peaks[0] > 23.0 and peaks[0] > peaks[1] + 3.0


def test_mpc_holds_a_sustained_lateral_force_and_lets_a_roll_transient_fade() -> None:
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    from motosim.cueing.mpc import MpcCueing, design_mpc

    # a gust's side force of 1 m/s^2 at the head, no rotation: predicted held, it tilts the
    # platform to give it (f_y = -g sin(phi_s)), measured -0.67 deg after 3 s; the previous
    # design, which predicted it to fade in 0.15 s, tilted -0.18 deg
    cfg = load_platform("simacom_platform")
    design = design_mpc(cfg, TELBAN_CARDULLO_2005, 0.01)
    mpc = MpcCueing(design)
    for _ in range(300):
        roll = mpc.step(np.array([0.0, 0.0, 0.0, 0.0, 1.0]), np.zeros(3))[0]
    assert np.degrees(roll) < -0.5
    # a roll onset (20 deg/s for 0.3 s) whose lateral force is only the head's tangential
    # acceleration h phi_ddot: that part fades, so the roll is not held afterwards (measured
    # 4.3 deg at 0.7 s, 0.09 deg at 3 s, as with a fading prediction: 4.3 and 0.06 deg)
    mpc = MpcCueing(design)
    t = np.arange(0.0, 3.0, 0.01)
    rate = np.radians(20.0) * np.clip(np.minimum(t / 0.2, (0.7 - t) / 0.2), 0.0, 1.0)
    alpha = np.gradient(rate, 0.01)
    rolls = [
        mpc.step(np.array([w, 0.0, 0.0, 0.0, cfg.rider.height * a]), np.zeros(3))[0]
        for w, a in zip(rate, alpha, strict=True)
    ]
    assert np.degrees(max(rolls)) > 4.0 and abs(np.degrees(rolls[-1])) < 0.2


def test_mpc_false_cue_constraint_keeps_an_unprompted_roll_below_threshold() -> None:
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    import dataclasses

    from motosim.cueing.mpc import MpcCueing, design_mpc

    # the motorcycle still, the angle reference stepping to 10 deg of roll: without the
    # false-cue constraint the plan rolls there at a perceptible rate; with it, the roll
    # rate stays near the 3 deg/s roll threshold (soft: measured 3.4 against 6.0 deg/s)
    cfg = load_platform("simacom_platform")
    free = dataclasses.replace(cfg, mpc=dataclasses.replace(cfg.mpc, false_cue_steps=0))
    peaks = []
    for config in (cfg, free):
        mpc = MpcCueing(design_mpc(config, TELBAN_CARDULLO_2005, 0.01))
        rates = []
        for _ in range(300):
            mpc.step(np.zeros(5), np.array([np.radians(10.0), 0.0, 0.0]))
            rates.append(abs(mpc.rates[0]))
        peaks.append(np.degrees(max(rates)))
    assert peaks[0] < 3.6 and peaks[0] < 0.65 * peaks[1]


def test_mpc_force_false_cue_band_holds_back_a_sustained_roll() -> None:
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    import dataclasses

    from motosim.cueing.mpc import MpcCueing, design_mpc

    # the motorcycle still, the angle reference at 10 deg of roll: the tilt's lateral force
    # g sin(10 deg) = 1.7 m/s^2 is ten times the 0.17 m/s^2 threshold, a false cue the band
    # weighs; measured 5.9 deg after 3 s with the band (weight 0.5 of the platform file)
    # against 7.9 deg without
    cfg = load_platform("simacom_platform")
    free = dataclasses.replace(cfg, mpc=dataclasses.replace(cfg.mpc, force_false_cue_weight=0.0))
    final = []
    for config in (cfg, free):
        mpc = MpcCueing(design_mpc(config, TELBAN_CARDULLO_2005, 0.01))
        for _ in range(300):
            roll = mpc.step(np.zeros(5), np.array([np.radians(10.0), 0.0, 0.0]))[0]
        final.append(np.degrees(roll))
    assert final[0] < 0.8 * final[1]


def test_mpc_feeds_the_pitch_onset_through_in_the_same_step() -> None:
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    from motosim.cueing.mpc import MpcCueing, design_mpc

    # a nose-down onset of 10 deg/s: the first step's pitch target is the onset's angle and
    # the planned rate its rate, within 5 and 10 % (measured 3 and 6 %: the plan trims the
    # onset, whose perceived rotation is beyond the false-cue band)
    mpc = MpcCueing(design_mpc(load_platform("simacom_platform"), TELBAN_CARDULLO_2005, 0.01))
    rate = np.radians(-10.0)
    onset = np.array([[0.0, rate * 0.01, 0.0], [0.0, rate, 0.0]])
    target = mpc.step(np.array([0.0, rate, 0.0, 0.0, 0.0]), onset[0], onset)
    assert target[1] == pytest.approx(rate * 0.01, rel=0.05)
    assert mpc.rates[1] == pytest.approx(rate, rel=0.1)


def test_mpc_on_abrupt_and_noisy_motion_stays_finite_and_within_limits() -> None:
    pytest.importorskip("osqp", reason="the MPC needs the cueing extra (osqp)")
    from motosim.cueing.limits import apply_limits, design_limits
    from motosim.cueing.mpc import MpcCueing, design_mpc
    from motosim.cueing.vestibular import limit_margins

    # steps, white noise and square waves of 3 rad/s and 15 m/s^2 on every input: the roll
    # acceleration the plan differences from the roll rate is then huge and noisy; the
    # targets stay finite and, through the limit manager with the planned rates fed
    # forward, within every limit
    cfg = load_platform("simacom_platform")
    design = design_mpc(cfg, TELBAN_CARDULLO_2005, 0.01)
    rng = np.random.default_rng(13)
    t = np.arange(300) * 0.01
    for s in (
        np.where(t > 0.5, 3.0, 0.0),
        3.0 * rng.standard_normal(t.size),
        3.0 * np.sign(np.sin(4.0 * np.pi * t)),
    ):
        mpc = MpcCueing(design)
        motion = np.column_stack([s, 0.3 * s[::-1], -s, 5.0 * s, 5.0 * s[::-1]])
        targets, rates = np.empty((t.size, 3)), np.empty((t.size, 3))
        for k in range(t.size):
            targets[k] = mpc.step(motion[k], np.zeros(3))
            rates[k] = mpc.rates
        assert np.all(np.isfinite(targets)) and np.all(np.isfinite(rates))
        limited = apply_limits(design_limits(cfg.platform, 0.01), targets, rates)
        assert limit_margins(cfg.platform, limited, 0.01)[1] == 0
