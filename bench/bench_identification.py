"""Identification of 60 s of 100 Hz data: each method, against plain batch least squares."""

import numpy as np

from motosim.identification import (
    METHODS,
    MeasurementModel,
    back_emf_damping,
    excitation_run,
    identify,
)
from motosim.params import load_parameters
from timing import best


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
    phi = np.column_stack([np.ones(log.t.size), log["theta_h"], log["i_m"]])
    baseline = best(lambda: np.linalg.lstsq(phi, log["i_m"], rcond=None))
    out["numpy lstsq on the raw 6000 x 3 regressor [s]"] = baseline
    out["output_error / lstsq"] = out["output_error [s]"] / baseline
    return out
