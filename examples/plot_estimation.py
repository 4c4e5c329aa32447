"""
Estimate the rider's torque from angle and current
==================================================

The handlebar has no torque sensor. From the sampled angle and the motor current alone, the
super-twisting differentiator and the Walcott-Zak observer reconstruct the rider's torque
(:func:`motosim.estimation.estimate`, what ``motosim estimate`` runs on a log). Here the
rider pushes a 20 N*m step on the simulated Table I handlebar (exact stick-slip friction)
while the motor plays a sine; the three estimators of :data:`motosim.estimation.ESTIMATORS`
are compared.
"""

from types import SimpleNamespace

import numpy as np

from motosim.estimation import ESTIMATORS, estimate
from motosim.model.handlebar import simulate_handlebar
from motosim.params import load_parameters
from motosim.plotting import plot_torque_estimates

hb = load_parameters("simacom_handlebar", "handlebar")
t = np.arange(0.0, 3.0, 1e-3)  # 1 kHz [s]
tau_r = np.where(t > 1.0, 20.0, 0.0)  # the rider pushes 20 N*m after 1 s
run = simulate_handlebar(hb, t, rider_torque=tau_r, current=np.sin(6 * t))

runs = {}
for name in ESTIMATORS:
    _, tau_hat = estimate(name, t, run["theta_h"], run["i_m"], hb)
    runs[name] = SimpleNamespace(t=t, tau_r=tau_r, tau_r_hat=tau_hat)
    error = np.sqrt(np.mean((tau_hat[t > 1.1] - tau_r[t > 1.1]) ** 2))
    print(f"{name:>16}: final {tau_hat[-1]:6.2f} N*m, RMS error after 1.1 s {error:.3f} N*m")

fig = plot_torque_estimates(runs, title="A 20 N*m step of the rider, three estimators")
