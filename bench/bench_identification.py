"""Identification of 60 s of 100 Hz data: each method, against plain batch least squares.

Two logs: the paper's voltage-driven chirp (``motosim excite``: t, theta_h, i_m, u), and
issue 11's rig log, a continuous measured current (t, theta_h, i_m: a 0.1-4 Hz chirp of 4 A,
5 mA noise, 14-bit encoder) on a 1.5 ms handlebar, identified with the default options as
``motosim identify LOG --ratio 1 --torque-constant 1`` does (output error with the cubic
inter-sample current and the 8-refit encoder bootstrap for the intervals). Issue 11's
target: under 1 s.
"""

import dataclasses
import math

import numpy as np

from motosim.identification import (
    METHODS,
    MeasurementModel,
    back_emf_damping,
    excitation_run,
    identify,
    measure,
)
from motosim.model.handlebar import simulate_handlebar
from motosim.params import load_parameters
from motosim.timeseries import TimeSeries
from timing import best


def _rig_log() -> TimeSeries:
    hb = dataclasses.replace(
        load_parameters("simacom_handlebar", "handlebar"),
        J_eq=0.028,
        beta_eq=18.5,
        beta_s=1.0,
        N=1.0,
        k_t=1.0,
    )
    t = np.arange(600_001) * 1e-4
    current = 4.0 * np.sin(2 * math.pi * (0.1 * t + 0.5 * (4.0 - 0.1) / 60.0 * t**2))
    truth = simulate_handlebar(hb, t, current=current)
    model = MeasurementModel(
        sample_rate=100.0, counts_per_revolution=2**14, pulley_ratio=1.0, current_noise=0.005
    )
    log = measure(truth, model, np.random.default_rng(0))
    return TimeSeries(log.t, np.column_stack([log["theta_h"], log["i_m"]]), ("theta_h", "i_m"))


def run() -> dict[str, float]:
    """Seconds per identification of a 60 s, 100 Hz excitation log, after compilation."""
    hb = load_parameters("simacom_handlebar", "handlebar")
    log = excitation_run(hb, "chirp", 60.0, MeasurementModel(), np.random.default_rng(0))
    damping = back_emf_damping(hb)
    out: dict[str, float] = {}
    for method in METHODS:
        identify(log, torque_per_amp=hb.torque_per_amp, method=method, back_emf_damping=damping)
        out[f"{method} [s]"] = best(
            lambda m=method: identify(  # type: ignore[misc]
                log, torque_per_amp=hb.torque_per_amp, method=m, back_emf_damping=damping
            )
        )
    rig = _rig_log()
    identify(rig, torque_per_amp=1.0)
    out["output_error, rig log, continuous current [s]"] = best(
        lambda: identify(rig, torque_per_amp=1.0)
    )
    phi = np.column_stack([np.ones(log.t.size), log["theta_h"], log["i_m"]])
    baseline = best(lambda: np.linalg.lstsq(phi, log["i_m"], rcond=None))
    out["numpy lstsq on the raw 6000 x 3 regressor [s]"] = baseline
    out["output_error / lstsq"] = out["output_error [s]"] / baseline
    return out
