"""Cost of one estimation step: differentiator + Walcott-Zak observer, compiled and not."""

import numpy as np
from numba import njit

from motosim.estimation.differentiator import std_step
from motosim.estimation.registry import walcott_zak_for_step
from motosim.estimation.walcott_zak import wz_step
from motosim.params import load_parameters
from timing import best


def _loop(theta, current, h, l1, l2, Phi, Gamma, g, settings):  # type: ignore[no-untyped-def]
    n = theta.size
    tau = np.empty(n)
    z0, z1 = theta[0], 0.0
    state = np.array([0.0, theta[0], 0.0, 0.0])
    for k in range(n):
        z0, z1 = std_step(z0, z1, theta[k], h, l1, l2, True)
        tau[k] = wz_step(state, theta[k], z1, current[k], Phi, Gamma, g, settings)
    return tau


_compiled = njit(cache=True)(_loop)


def run() -> dict[str, float]:
    """Nanoseconds per sample of the estimation step over 100 000 samples at 1 kHz."""
    hb = load_parameters("simacom_handlebar", "handlebar")
    h = 1e-3
    obs = walcott_zak_for_step(hb, h)
    t = np.arange(100_000) * h
    theta = 0.2 * np.sin(2 * np.pi * 0.5 * t)
    current = np.sin(2 * np.pi * 1.3 * t)
    lip = 300.0
    args = (h, 1.5 * np.sqrt(lip), 1.1 * lip, obs._Phi, obs._Gamma, obs._g, obs._settings)
    _compiled(theta[:10], current[:10], *args)
    compiled = best(lambda: _compiled(theta, current, *args)) / t.size
    few = 5_000
    plain = (
        best(lambda: _loop(theta[:few], current[:few], *args), repeat=1) / few
    )  # the same code, interpreted, calling the compiled kernels
    stepper = (
        best(lambda: [obs.step(theta[k], 0.0, current[k]) for k in range(few)], repeat=1) / few
    )
    return {
        "compiled step [ns]": 1e9 * compiled,
        "python loop over compiled kernels [ns]": 1e9 * plain,
        "python stepper call [ns]": 1e9 * stepper,
        "compiled speed-up over python stepper": stepper / compiled,
    }
