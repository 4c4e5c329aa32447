"""The paper's estimation study (section V.A, Fig. 9): estimators against a known rider torque.

A square rider torque acts on the simulated handlebar (exact stick-slip, 10 kHz); the motor
current, a digital command held at the sampling rate, resists it through a 30 ms lag and
adds a 1.3 Hz wiggle that keeps the handlebar moving and reversing through its dry friction.
Angle and current are sampled at 1 kHz or 100 Hz, the angle optionally quantised like a
14-bit encoder, and each estimator reconstructs the torque with the nominal handlebar while
the true one may differ (the paper's +/-50 % on inertia and viscous damping).
"""

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.estimation.registry import ESTIMATORS, estimate
from motosim.model.handlebar import perturbed, simulate_handlebar
from motosim.params.handlebar import HandlebarParameters

__all__ = ["PAPER_CASES", "Case", "Outcome", "run_case", "score"]

Array = NDArray[np.float64]

_SIMULATION_RATE = 10_000.0  # [Hz]
ENCODER_14_BIT = 2.0 * math.pi / 2**14  # [rad]


@dataclass(frozen=True, slots=True)
class Case:
    """One simulated run of the study.

    Attributes
    ----------
    name : str
        Label for tables.
    rate : float
        Sampling rate of angle and current [Hz].
    inertia_factor, damping_factor : float
        True J_eq and beta_eq over the nominal ones.
    friction : bool
        Whether the true handlebar has its dry friction beta_s.
    compensation : bool
        Whether the estimators subtract the nominal dry friction.
    quantum : float
        Encoder resolution [rad]; 0 for an exact angle.
    low, high : float
        Levels of the square rider torque [N*m], switching every ``half_period`` [s].
    duration : float
        Length [s].
    """

    name: str
    rate: float
    inertia_factor: float = 1.0
    damping_factor: float = 1.0
    friction: bool = False
    compensation: bool = True
    quantum: float = 0.0
    low: float = 10.0
    high: float = 70.0
    half_period: float = 0.5
    duration: float = 4.0


PAPER_CASES: tuple[Case, ...] = (
    Case("nominal, no friction, 1 kHz", 1000.0),
    Case("J, beta x0.5, 1 kHz", 1000.0, inertia_factor=0.5, damping_factor=0.5),
    Case("J, beta x1.5, 1 kHz", 1000.0, inertia_factor=1.5, damping_factor=1.5),
    Case("dry friction, compensated, 1 kHz", 1000.0, friction=True),
    Case("dry friction, not compensated, 1 kHz", 1000.0, friction=True, compensation=False),
    Case("dry friction, 14-bit encoder, 100 Hz", 100.0, friction=True, quantum=ENCODER_14_BIT),
    Case(
        "J, beta x1.5, friction, 14-bit, 100 Hz",
        100.0,
        inertia_factor=1.5,
        damping_factor=1.5,
        friction=True,
        quantum=ENCODER_14_BIT,
    ),
)
"""The cases of section V.A: nominal, +/-50 %, dry friction with and without compensation,
and the paper's 100 Hz CAN rate with encoder quantisation."""


@dataclass(frozen=True, slots=True)
class Outcome:
    """What one estimator achieved on one case.

    Attributes
    ----------
    rms_error : float
        RMS of tau_r_hat - tau_r outside 0.1 s after each step [N*m].
    relative_rms : float
        ``rms_error`` over the step height.
    convergence_time : float
        Worst time over the steps after which |tau_r_hat - tau_r| stays below 5 % of the
        step height until the next step [s] (inf if it never does).
    t, tau_r, tau_r_hat : ndarray
        The run, for figures.
    """

    rms_error: float
    relative_rms: float
    convergence_time: float
    t: Array
    tau_r: Array
    tau_r_hat: Array


def _log(case: Case, nominal: HandlebarParameters) -> tuple[Array, Array, Array, Array]:
    """Sample times, true torque at the samples, measured angle and current."""
    true = perturbed(
        nominal,
        inertia_factor=case.inertia_factor,
        damping_factor=case.damping_factor,
        friction=case.friction,
    )
    m = round(_SIMULATION_RATE / case.rate)
    if not math.isclose(m * case.rate, _SIMULATION_RATE):
        raise MotosimError(f"rate = {case.rate!r} Hz; expected a divisor of 10 kHz")
    n = round(case.duration * case.rate)
    t_fine = np.arange(n * m) / _SIMULATION_RATE
    tau_fine = np.where((t_fine // case.half_period) % 2 == 0, case.low, case.high)
    t = t_fine[::m]
    tau = tau_fine[::m]
    # the motor command, held at the sampling rate: resist the torque through a 30 ms lag
    a = math.exp(-1.0 / (case.rate * 0.03))
    lagged = np.empty(n)
    v = tau[0]
    for k in range(n):
        lagged[k] = v
        v = a * v + (1.0 - a) * tau[k]
    current = -lagged / nominal.torque_per_amp + 2.0 * np.sin(2 * np.pi * 1.3 * t)
    run = simulate_handlebar(true, t_fine, rider_torque=tau_fine, current=np.repeat(current, m))
    theta = run["theta_h"][::m]
    if case.quantum > 0:
        theta = np.round(theta / case.quantum) * case.quantum
    return t, tau, theta, current


def score(case: Case, t: Array, tau: Array, tau_hat: Array) -> Outcome:
    """RMS error and convergence time of an estimate (see :class:`Outcome`)."""
    height = abs(case.high - case.low)
    edges = np.arange(0.0, case.duration, case.half_period)
    keep = np.ones(t.size, dtype=bool)
    worst = 0.0
    error = np.abs(tau_hat - tau)
    for edge in edges:
        keep &= ~((t >= edge - 1e-9) & (t < edge + 0.1))
        window = np.flatnonzero((t >= edge - 1e-9) & (t < edge + case.half_period - 1e-9))
        bad = np.flatnonzero(error[window] > 0.05 * height)
        if bad.size == window.size:
            worst = math.inf
        elif bad.size:
            worst = max(
                worst,
                float(t[window[bad[-1] + 1]] - edge) if bad[-1] + 1 < window.size else math.inf,
            )
    rms = float(np.sqrt(np.mean((tau_hat - tau)[keep] ** 2)))
    return Outcome(rms, rms / height, worst, t, tau, tau_hat)


def run_case(case: Case, nominal: HandlebarParameters, estimator: str) -> Outcome:
    """Simulate ``case`` and estimate the torque with ``estimator`` (a key of ESTIMATORS).

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> hb = load_parameters("simacom_handlebar", "handlebar")
    >>> out = run_case(PAPER_CASES[0], hb, "walcott_zak")
    >>> bool(out.relative_rms < 0.02)
    True
    """
    if estimator not in ESTIMATORS:
        raise MotosimError(f"estimator {estimator!r}; expected one of {', '.join(ESTIMATORS)}")
    if not case.friction:  # "the dry friction effect is neglected": in the model too
        nominal = dataclasses.replace(nominal, beta_s=0.0)
    t, tau, theta, current = _log(case, nominal)
    _, tau_hat = estimate(
        estimator, t, theta, current, nominal, friction_compensation=case.compensation
    )
    return score(case, t, tau, tau_hat)
