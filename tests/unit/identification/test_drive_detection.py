"""Telling a voltage-driven log from a current-driven one (eq. (7))."""

import numpy as np

from motosim.identification import MeasurementModel, excitation_run, is_voltage_driven
from motosim.params import load_parameters
from motosim.timeseries import TimeSeries


def test_voltage_driven_log_is_recognised() -> None:
    hb = load_parameters("simacom_handlebar", "handlebar")
    log = excitation_run(hb, "chirp", 20.0, MeasurementModel(), np.random.default_rng(0))
    assert is_voltage_driven(log, torque_per_amp=hb.torque_per_amp)
    without_u = TimeSeries(log.t, np.column_stack([log["theta_h"], log["i_m"]]), ("theta_h", "i_m"))
    assert not is_voltage_driven(without_u, torque_per_amp=hb.torque_per_amp)
    rng = np.random.default_rng(1)
    unrelated = TimeSeries(
        log.t,
        np.column_stack([log["theta_h"], log["i_m"], rng.normal(size=log.t.size)]),
        ("theta_h", "i_m", "u"),
    )
    assert not is_voltage_driven(unrelated, torque_per_amp=hb.torque_per_amp)
