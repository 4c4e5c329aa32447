"""Handlebar identification: excitation runs and the estimation of J_eq, beta_eq, beta_s.

Section II.D of the paper: the motor drives the free handlebar in open loop (tau_r = 0); the
angle and the current are logged; eq. (5) is written as the linear regression of eq. (8),
Phi p = N k_t i_m, and solved. Layer: ``params -> model -> identification``; nothing here
reads files or prints.

Modules
-------
excitation
    Chirp and rectangular voltages, the measurement model, simulated excitation runs.
regressors
    Eq. (8) from a log, with zero-phase Savitzky-Golay differentiation.
least_squares, gradient, output_error
    The estimators.
identify
    :func:`identify` and :func:`validate`.
"""

from motosim.identification.excitation import (
    ExcitationPlan,
    MeasurementModel,
    chirp_voltage,
    excitation_run,
    measure,
    plan_excitation,
    square_voltage,
)
from motosim.identification.identify import (
    DRIVE_COLUMNS,
    METHODS,
    Identification,
    Validation,
    back_emf_damping,
    current_noise,
    drive_from_columns,
    identified_parameters,
    identify,
    is_voltage_driven,
    validate,
)

__all__ = [
    "DRIVE_COLUMNS",
    "METHODS",
    "ExcitationPlan",
    "Identification",
    "MeasurementModel",
    "Validation",
    "back_emf_damping",
    "chirp_voltage",
    "current_noise",
    "drive_from_columns",
    "excitation_run",
    "identified_parameters",
    "identify",
    "is_voltage_driven",
    "measure",
    "plan_excitation",
    "square_voltage",
    "validate",
]
