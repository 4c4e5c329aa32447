"""A handlebar rig simulated independently of motosim, for the identification reference tests.

Nothing here calls motosim's model or kernel: eq. (5) of Nehaoua, Arioui & Mammar (2012),
J theta'' + beta theta' + beta_s sign(theta') = N k_t i(t), is integrated with Heun's method
(explicit trapezoidal rule) at a fine fixed step, with Karnopp's stick rule (the handlebar stops
when its rate changes sign within a step and stays stuck while |N k_t i| <= beta_s). (Optionally the
dry friction is smooth, beta_s tanh(theta_h' / w), as some simulators model it.) The motor
current i(t) is continuous (a current drive whose current is measured, not held), here a linear
chirp; the log samples it with white noise, and samples the angle through an encoder of
``bits`` bits per handlebar turn (floored to whole counts).

This is the rig of issue 11's targets: 60 s at 100 Hz or 20 s at 1 kHz, 14-bit encoder,
5 mA current noise, Coulomb friction.
"""

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

Array = NDArray[np.float64]

FINE_STEP = 5e-6  # [s]: 300 steps per 1.5 ms time constant, Heun's error ~ (h/tau)^2 ~ 1e-5


@njit(cache=True)
def _integrate(
    duration: float,
    step: float,
    J: float,
    beta: float,
    beta_s: float,
    amplitude: float,
    f0: float,
    f1: float,
    theta0: float,
    omega0: float,
    every: int,
    width: float,
) -> tuple[Array, Array]:
    n = int(duration / step + 0.5)
    m = n // every + 1
    theta_out = np.empty(m)
    omega_out = np.empty(m)
    theta = theta0
    omega = omega0
    k_rate = (f1 - f0) / duration
    for k in range(n + 1):
        if k % every == 0:
            theta_out[k // every] = theta
            omega_out[k // every] = omega
        if k == n:
            break
        t = k * step
        u0 = amplitude * math.sin(2.0 * math.pi * (f0 * t + 0.5 * k_rate * t * t))
        t1 = t + step
        u1 = amplitude * math.sin(2.0 * math.pi * (f0 * t1 + 0.5 * k_rate * t1 * t1))
        if width > 0.0:
            # smooth friction beta_s tanh(omega / width), no sticking
            a0 = (u0 - beta * omega - beta_s * math.tanh(omega / width)) / J
            omega_p = omega + step * a0
            a1 = (u1 - beta * omega_p - beta_s * math.tanh(omega_p / width)) / J
            omega_new = omega + 0.5 * step * (a0 + a1)
            theta += 0.5 * step * (omega + omega_new)
            omega = omega_new
            continue
        if omega == 0.0:
            if abs(u0) <= beta_s:
                continue  # stuck (Karnopp)
            s = 1.0 if u0 > 0.0 else -1.0
        else:
            s = 1.0 if omega > 0.0 else -1.0
        a0 = (u0 - beta * omega - beta_s * s) / J
        omega_p = omega + step * a0
        a1 = (u1 - beta * omega_p - beta_s * s) / J
        omega_new = omega + 0.5 * step * (a0 + a1)
        theta += 0.5 * step * (omega + omega_new)
        if omega_new * s < 0.0:
            omega_new = 0.0  # the rate reverses within the step: the handlebar sticks
        omega = omega_new
    return theta_out, omega_out


def rig_log(
    *,
    J: float,
    beta: float,
    beta_s: float,
    sample_rate: float,
    duration: float,
    amplitude: float,
    f0: float = 0.1,
    f1: float = 4.0,
    bits: int = 14,
    current_noise: float = 0.005,
    seed: int = 0,
    theta0: float = 0.0,
    omega0: float = 0.0,
    friction_width: float = 0.0,
) -> tuple[Array, Array, Array]:
    """Sample a simulated rig: t [s], theta_h [rad] (encoder-floored), i_m [A] (noisy).

    The torque per ampere N k_t is 1 N*m/A (``--ratio 1 --torque-constant 1``). With a
    positive ``friction_width`` w [rad/s] the dry friction is beta_s tanh(theta_h' / w)
    instead of Coulomb with Karnopp sticking (Heun stays stable for
    FINE_STEP beta_s / (J w) < 2).
    """
    every = round(1.0 / (sample_rate * FINE_STEP))
    theta, _ = _integrate(
        duration,
        FINE_STEP,
        J,
        beta,
        beta_s,
        amplitude,
        f0,
        f1,
        theta0,
        omega0,
        every,
        friction_width,
    )
    t = np.arange(theta.size) / sample_rate
    rng = np.random.default_rng(seed)
    resolution = 2.0 * math.pi / 2**bits
    encoder = np.floor(theta / resolution) * resolution
    current = amplitude * np.sin(2.0 * math.pi * (f0 * t + 0.5 * (f1 - f0) / duration * t * t))
    current = current + current_noise * rng.standard_normal(t.size)
    return t, encoder, current


def write_csv(path: str, t: Array, theta: Array, current: Array) -> None:
    """Write the log as the issue's schema: t [s], theta_h [rad], i_m [A] (measured)."""
    with open(path, "w", encoding="utf-8") as handle:
        handle.write("t,theta_h,i_m\n")
        for row in zip(t, theta, current, strict=True):
            handle.write(",".join(repr(float(v)) for v in row) + "\n")
