"""Rider-torque estimation: differentiator, Walcott-Zak observer and baselines.

Layer: after :mod:`motosim.model`, beside identification and control. Each estimator is
designed offline (pure functions returning frozen gains) and run by a small stepper with
``reset()`` and ``step(theta_h, theta_h_dot, i_m) -> (x_hat, tau_r_hat)`` over a compiled
one-sample kernel; :func:`estimate` runs one on logged samples.
"""

from motosim.estimation.differentiator import SuperTwistingDifferentiator, differentiate
from motosim.estimation.registry import ESTIMATORS, TorqueEstimator, estimate
from motosim.estimation.walcott_zak import WalcottZakGains, WalcottZakObserver, design

__all__ = [
    "ESTIMATORS",
    "SuperTwistingDifferentiator",
    "TorqueEstimator",
    "WalcottZakGains",
    "WalcottZakObserver",
    "design",
    "differentiate",
    "estimate",
]
