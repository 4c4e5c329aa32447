"""
Identify a handlebar from an excitation log
===========================================

A synthetic version of the paper's section II.D: the handlebar of Table I, driven in open
loop through a voltage drive by a 6 V chirp of 0.1-6 Hz sampled at 100 Hz (the paper used
3 V and 0.1-2 Hz, which leaves the inertia weakly identified: ``identify`` says so and names
a better chirp), its angle measured by a 14-bit encoder and its current with 0.05 A of noise
(:func:`motosim.identification.excitation_run`, what ``motosim excite`` writes).
:func:`motosim.identification.identify` then fits J_eq, beta_eq and beta_s by output error,
with 95 % intervals, as ``motosim identify`` does on a rig's log.
"""

import numpy as np

from motosim.identification import (
    MeasurementModel,
    back_emf_damping,
    excitation_run,
    identify,
    validate,
)
from motosim.params import load_parameters
from motosim.plotting import plot_identification

hb = load_parameters("simacom_handlebar", "handlebar")  # the truth of this example
sensors = MeasurementModel(sample_rate=100.0, counts_per_revolution=2**14, current_noise=0.05)
log = excitation_run(hb, "chirp", 30.0, sensors, np.random.default_rng(1), amplitude=6.0, f1=6.0)
print(log.names, log.t.size, "samples")

# %%
# The log has ``theta_h``, ``i_m`` and ``u``: a voltage drive, whose current moves with the
# back-EMF between samples (``drive="voltage_held"``, which ``motosim identify`` infers from
# the columns).
est = identify(
    log,
    torque_per_amp=hb.torque_per_amp,
    drive="voltage_held",
    back_emf_damping=back_emf_damping(hb),
    rng=np.random.default_rng(0),
)
for name, value, (lo, hi) in zip(
    ("J_eq", "beta_eq", "beta_s"), est.parameters, est.confidence, strict=True
):
    print(f"{name} = {value:.4g} (95 % interval {lo:.4g} to {hi:.4g})")
print("true:", hb.J_eq, hb.beta_eq, hb.beta_s)
print(*est.warnings, sep="\n")

# %%
# The identified model replayed on the log: measured and simulated angle, residual, current.
fit = validate(est, log, torque_per_amp=hb.torque_per_amp)
fig = plot_identification(fit=fit, estimate=est.parameters, confidence=est.confidence)
