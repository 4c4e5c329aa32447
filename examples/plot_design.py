"""
Design the torque feedback: loop shapes
=======================================

:func:`motosim.control.torque_feedback.design_torque_feedback` shapes the handlebar loop
with W1 = k (s + omega_c/10) / s (crossover at the tracking bandwidth, integral action) and
tunes a first-order K_s by nonsmooth optimisation of the Glover-McFarlane four-block norm,
the controller of ``motosim design``. Below: the loop gain L = -G_h K, the sensitivity
S = 1/(1 + L) (the tracking error theta_h - delta relative to the steer angle) and the
complementary sensitivity T.
"""

import matplotlib.pyplot as plt
import numpy as np

from motosim.control import frequency_response
from motosim.control.torque_feedback import design_torque_feedback, handlebar_plants
from motosim.params import load_parameters

hb = load_parameters("simacom_handlebar", "handlebar")
design = design_torque_feedback(hb, rng=np.random.default_rng(0), bandwidth=10.0, n_starts=4)
a = design.analysis
print(f"gamma {design.gamma:.4f} (full-order optimum {design.gamma_min:.4f})")
print(
    f"phase margin {a.phase_margin_deg:.0f} deg, tracking bandwidth {a.tracking_bandwidth:.1f} Hz"
)

G_h, _ = handlebar_plants(hb)
omega = np.logspace(-1, 4, 400)  # [rad/s]
L = np.array(
    [-(frequency_response(G_h, w) @ frequency_response(design.controller, w))[0, 0] for w in omega]
)
S = 1.0 / (1.0 + L)

fig, ax = plt.subplots(figsize=(7.0, 4.0), layout="constrained")
for values, label in ((L, "L = -G_h K"), (S, "S"), (L * S, "T")):
    ax.loglog(omega / (2 * np.pi), np.abs(values), label=label)
ax.axvline(design.bandwidth, color="0.6", ls=":", label="requested bandwidth")
ax.set_xlabel("frequency [Hz]")
ax.set_ylabel("magnitude")
ax.legend()
ax.grid(True, which="both", alpha=0.3)
