"""Simulated handlebar runs shared by the estimator tests (a helper, not a test module)."""

import dataclasses
import functools

import numpy as np

from motosim.model.handlebar import simulate_handlebar
from motosim.params import load_parameters

QUANTUM = 2.0 * np.pi / 2**14  # 14-bit encoder [rad]
LOW, HIGH = 10.0, 70.0  # square rider torque [N*m]; Remark 3.3: peak about 70 N*m
STEP = HIGH - LOW
DURATION = 4.0  # [s]
SETTLE = 0.1  # excluded after each step [s]


@functools.cache
def scenario(rate: float, friction: bool) -> dict[str, np.ndarray]:
    """Square rider torque 10/70 N*m (period 1 s) resisted by the motor.

    The current opposes the rider torque through a 30 ms lag, as a position controller
    would, plus a 6 N*m, 1.3 Hz sine that keeps the handlebar moving (and reversing, through
    the dry friction). Exact stick-slip simulation at the sampling rate.
    """
    hb = load_parameters("simacom_handlebar", "handlebar")
    if not friction:
        hb = dataclasses.replace(hb, beta_s=0.0)
    h = 1.0 / rate
    t = np.arange(0.0, DURATION, h)
    tau = np.where((t % 1.0) < 0.5, LOW, HIGH)
    a = np.exp(-h / 0.03)
    lagged = np.empty_like(tau)
    v = tau[0]
    for k in range(t.size):
        lagged[k] = v
        v = a * v + (1 - a) * tau[k]
    current = -lagged / hb.torque_per_amp + 2.0 * np.sin(2 * np.pi * 1.3 * t)
    run = simulate_handlebar(hb, t, rider_torque=tau, current=current)
    return {
        "t": t,
        "tau_r": tau,
        "theta_h": run["theta_h"],
        "theta_h_dot": run["theta_h_dot"],
        "i_m": current,
    }


def rms_error(t: np.ndarray, tau: np.ndarray, tau_hat: np.ndarray) -> float:
    """RMS of tau_hat - tau outside SETTLE after each step (and the start)."""
    keep = np.ones(t.size, dtype=bool)
    for edge in np.arange(0.0, DURATION, 0.5):
        keep &= ~((t >= edge - 1e-9) & (t < edge + SETTLE))
    return float(np.sqrt(np.mean((tau_hat - tau)[keep] ** 2)))
