"""Logs for the identification reference tests, made with the model's exact stick-slip kernel."""

import dataclasses
from collections.abc import Callable

import numpy as np
import pytest

from motosim.identification import MeasurementModel, chirp_voltage, measure
from motosim.model.handlebar import simulate_handlebar
from motosim.params import HandlebarParameters, load_parameters
from motosim.timeseries import TimeSeries

SIMULATION_RATE = 10_000.0  # [Hz] fine simulation (beta/J = 336 1/s), then sampled


@pytest.fixture(scope="session")
def table1() -> HandlebarParameters:
    # J_eq 0.0415 kg*m^2, beta_eq 13.956 N*m*s/rad, beta_s 1.734 N*m: paper Table I
    return load_parameters("simacom_handlebar", "handlebar")


UNLIKE_TABLE1 = {
    # time constants J/beta of 13 ms and 2 ms ("a few ms"), frictions unlike Table I
    "heavy": {"J_eq": 0.08, "beta_eq": 6.0, "beta_s": 3.0},
    "light": {"J_eq": 0.03, "beta_eq": 15.0, "beta_s": 0.8},
}


def unlike_table1(hb: HandlebarParameters, case: str) -> HandlebarParameters:
    """Handlebars unlike Table I, motor constants kept."""
    return dataclasses.replace(hb, **UNLIKE_TABLE1[case])


def current_driven_log(
    hb: HandlebarParameters,
    *,
    sample_rate: float,
    duration: float = 60.0,
    amplitude: float = 2.0,
    held: bool = True,
) -> TimeSeries:
    """A 0.1-2 Hz chirp current [A], held between samples (i_cmd) or continuous (i_m).

    Simulated by simulate_handlebar at 10 kHz, then sampled and quantised like the encoder
    of the default measurement model (no current noise).
    """
    n = round(duration * SIMULATION_RATE) + 1
    t = np.arange(n) / SIMULATION_RATE
    if held:
        command = chirp_voltage(
            amplitude=amplitude, f0=0.1, f1=2.0, duration=duration, rate=sample_rate
        )
        m = round(SIMULATION_RATE / sample_rate)
        current = np.repeat(command["u"], m)[:n]
    else:
        current = amplitude * np.cos(2 * np.pi * (0.1 * t + (2.0 - 0.1) * t**2 / (2 * duration)))
    truth = simulate_handlebar(hb, t, current=current)
    model = MeasurementModel(sample_rate=sample_rate, current_noise=0.0)
    log = measure(truth, model, np.random.default_rng(0))
    # the log schema: a held set-point is i_cmd, a measured continuous current i_m
    return TimeSeries(
        log.t,
        np.column_stack([log["theta_h"], log["i_m"]]),
        ("theta_h", "i_cmd" if held else "i_m"),
    )


@pytest.fixture(scope="session")
def make_unlike_table1() -> Callable[[HandlebarParameters, str], HandlebarParameters]:
    """The factory :func:`unlike_table1`."""
    return unlike_table1


@pytest.fixture(scope="session")
def make_current_log() -> Callable[..., TimeSeries]:
    """The factory :func:`current_driven_log`."""
    return current_driven_log
