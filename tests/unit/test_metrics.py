"""Run metrics and flags against hand-made signals."""

import math

import numpy as np

from motosim.sim.metrics import failure, run_metrics, warnings


def _metrics(**columns: np.ndarray) -> dict[str, float]:
    t = np.arange(0.0, 4.0, 1e-3)
    full = {name: np.broadcast_to(values, t.shape).copy() for name, values in columns.items()}
    return run_metrics(t, full.get, complete=True, max_current=30.0)


def test_buzz_is_flagged_only_while_the_rider_holds_still() -> None:
    t = np.arange(0.0, 4.0, 1e-3)
    buzz = 0.5 * np.sin(2 * np.pi * 10.0 * t)  # 1 A peak to peak at 10 Hz
    quiet = _metrics(i_m=buzz, tau_r=np.zeros(1))
    assert quiet["flag_oscillation"] == 1.0
    assert math.isclose(quiet["buzz_current_p2p"], 1.0, rel_tol=0.02)
    assert math.isclose(quiet["buzz_frequency"], 10.0, rel_tol=0.05)
    assert "buzzes" in warnings(quiet)[0]
    steering = _metrics(i_m=buzz, tau_r=20.0 * np.sin(2 * np.pi * 10.0 * t))
    assert steering["flag_oscillation"] == 0.0  # current the rider asks for is no buzz
    slow = _metrics(i_m=5.0 * np.sin(2 * np.pi * 0.5 * t), tau_r=np.zeros(1))
    assert slow["flag_oscillation"] == 0.0  # steering-rate current is below the 3 Hz cutoff


def test_fall_saturation_and_speed_flags() -> None:
    fell = _metrics(phi=np.linspace(0.0, math.radians(60.0), 4000))
    assert fell["flag_fall"] == 1.0 and "fell" in (failure(fell) or "")
    saturated = _metrics(i_m=np.full(1, 30.0))
    assert saturated["flag_saturation"] == 1.0 and "limit" in (failure(saturated) or "")
    stopped = _metrics(v_x=np.linspace(10.0, 1.0, 4000))
    assert stopped["flag_out_of_range"] == 1.0 and "speed left" in (failure(stopped) or "")
    slow_start = _metrics(v_x=np.full(1, 1.0))  # accepted outside 3-60 m/s, stays where it was
    assert slow_start["flag_out_of_range"] == 0.0
    fine = _metrics(phi=np.full(1, 0.2), i_m=np.full(1, 2.0), v_x=np.full(1, 20.0))
    assert failure(fine) is None and warnings(fine) == []


def test_fractions_of_the_peaks() -> None:
    t = np.arange(0.0, 4.0, 1e-3)
    delta = 0.02 * np.sin(t)
    m = _metrics(
        delta=delta, theta_h=delta + 0.001, tau_r=np.full(1, 10.0), tau_r_hat=np.full(1, 10.5)
    )
    assert math.isclose(m["tracking_rms_fraction"], 0.001 / np.max(np.abs(delta)), rel_tol=1e-9)
    assert math.isclose(m["estimate_rms_fraction"], 0.05, rel_tol=1e-9)
    assert math.isnan(_metrics(delta=np.zeros(1), theta_h=np.zeros(1))["tracking_rms_fraction"])


def test_slow_steering_in_the_last_seconds_is_no_buzz() -> None:
    # a slalom's current at 0.3 Hz: not a whole number of periods in the last 2 s, so a
    # plain FFT high-pass of that window spreads the slow swing above 3 Hz (leakage)
    t = np.arange(0.0, 14.0, 1e-3)
    slow = _metrics_at(t, i_m=5.0 * np.sin(2 * np.pi * 0.3 * t), tau_r=np.zeros(1))
    assert slow["buzz_current_p2p"] < 0.05
    assert slow["flag_oscillation"] == 0.0
    buzz = 0.5 * np.sin(2 * np.pi * 9.0 * t)  # the same swing carrying 1 A p-p at 9 Hz
    both = _metrics_at(t, i_m=5.0 * np.sin(2 * np.pi * 0.3 * t) + buzz, tau_r=np.zeros(1))
    assert math.isclose(both["buzz_current_p2p"], 1.0, rel_tol=0.05)
    assert math.isclose(both["buzz_frequency"], 9.0, rel_tol=0.06)


def test_buzz_while_the_rider_holds_a_steady_turn_is_flagged() -> None:
    # a steady turn: the rider holds 3 N*m and asks for no change; a 1 A buzz is felt
    t = np.arange(0.0, 4.0, 1e-3)
    buzz = 0.5 * np.sin(2 * np.pi * 9.0 * t)
    held = _metrics_at(t, i_m=1.0 + buzz, tau_r=3.0 + 0.2 * np.sin(2 * np.pi * 0.2 * t))
    assert held["flag_oscillation"] == 1.0
    turning = _metrics_at(t, i_m=1.0 + buzz, tau_r=3.0 * np.sin(2 * np.pi * 0.4 * t))
    assert turning["flag_oscillation"] == 0.0  # the rider is steering: not judged


def test_the_buzz_is_judged_on_the_riders_active_torque() -> None:
    # hands on the handlebar: the arms' passive torque follows the 9 Hz buzz it damps, so
    # tau_r swings though the rider asks for nothing; the active torque stays put
    t = np.arange(0.0, 4.0, 1e-3)
    buzz = 0.5 * np.sin(2 * np.pi * 9.0 * t)
    passive = -1.5 * np.cos(2 * np.pi * 9.0 * t)
    holding = _metrics_at(t, i_m=1.0 + buzz, tau_r=2.0 + passive, tau_r_active=np.full(1, 2.0))
    assert holding["flag_oscillation"] == 1.0
    unknown = _metrics_at(t, i_m=1.0 + buzz, tau_r=2.0 + passive)
    assert unknown["flag_oscillation"] == 0.0  # without it, the swing reads as steering
    steering = _metrics_at(t, i_m=1.0 + buzz, tau_r=2.0, tau_r_active=3.0 * np.sin(t))
    assert steering["flag_oscillation"] == 0.0


def _metrics_at(t: np.ndarray, **columns: np.ndarray) -> dict[str, float]:
    full = {name: np.broadcast_to(values, t.shape).copy() for name, values in columns.items()}
    return run_metrics(t, full.get, complete=True, max_current=30.0)


def test_a_real_time_run_is_judged_while_running_not_over_its_stop() -> None:
    # a real-time run: 6 s at 3 A while the rider holds steady, then an emergency stop (zero
    # torque from the next period on); no true rider torque recorded, only the estimate
    t = np.arange(0.0, 6.5, 1e-3)
    running = t < 6.0
    fade = running.astype(float)
    estimate = np.full(t.shape, 2.0)
    steady = {"i_m": 3.0 * fade, "tau_r_hat": estimate}
    whole = run_metrics(t, steady.get, complete=False)
    assert whole["buzz_current_p2p"] > 1.0  # the stop's step read as content above 3 Hz
    judged = run_metrics(t, steady.get, complete=False, running=running)
    assert judged["buzz_current_p2p"] < 0.01 and judged["flag_oscillation"] == 0.0
    # a 1 A buzz while running swings the estimate above 3 Hz too: still a held handlebar
    buzz = 0.5 * np.sin(2 * np.pi * 9.0 * t)
    buzzing = {"i_m": (3.0 + buzz) * fade, "tau_r_hat": estimate + 3.0 * buzz}
    flagged = run_metrics(t, buzzing.get, complete=False, running=running)
    assert math.isclose(flagged["buzz_current_p2p"], 1.0, rel_tol=0.05)
    assert flagged["flag_oscillation"] == 1.0
    # the rider steering (the estimate's slow swing) is not judged
    steering = {"i_m": (3.0 + buzz) * fade, "tau_r_hat": 10.0 * np.sin(2 * np.pi * 0.4 * t)}
    assert run_metrics(t, steering.get, complete=False, running=running)["flag_oscillation"] == 0.0
    # no running rows (a run stopped during its fade-in): nothing judged
    none = run_metrics(t, buzzing.get, complete=False, running=np.zeros(t.shape, dtype=bool))
    assert "buzz_current_p2p" not in none


def test_the_highpass_is_scipys_sosfiltfilt() -> None:
    """The buzz's high-pass, computed without scipy.signal, equals scipy.signal.sosfiltfilt
    of the 4th-order Butterworth it describes (the independent implementation)."""
    from scipy.signal import butter, sosfiltfilt

    from motosim.sim.metrics import highpass

    rng = np.random.default_rng(1)
    t = np.arange(3000) * 1e-3
    for x in (rng.normal(size=3000) + 2.0 + np.sin(t), rng.normal(size=3000).cumsum()):
        for cutoff in (3.0, 20.0):
            sos = butter(4, cutoff, "highpass", fs=1000.0, output="sos")
            pad = min(x.size - 1, math.ceil(3.0 / (cutoff * 1e-3)))
            expected = sosfiltfilt(sos, x - x.mean(), padlen=pad)
            np.testing.assert_allclose(highpass(t, x, cutoff), expected, rtol=0, atol=1e-10)
