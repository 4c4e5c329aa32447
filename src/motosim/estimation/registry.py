"""Named rider-torque estimators and a batch runner over logged samples.

:data:`ESTIMATORS` maps a name to a factory ``(hb, dt) -> stepper`` built with each
estimator's default design; :func:`estimate` differentiates the angle with the implicit
super-twisting differentiator and runs the stepper over the samples. The command line uses
these names.

A handlebar with a torque sensor needs no estimate from the angle and the current: the
kind :data:`~motosim.estimation.kernel.TORQUE_SENSOR` (:func:`torque_sensor_kernel`,
named :data:`SENSOR_ESTIMATOR` in scenarios) passes the measured torque through, with the
sensor's low-pass if any. It is not in :data:`ESTIMATORS`, whose estimators read only the
angle and the current.

A scenario's ``[estimator] name`` is checked against these names without importing numba:
:data:`motosim.choices.ESTIMATOR_NAMES` holds them, and this module refuses to load unless
they equal the keys of :data:`ESTIMATORS` in order; :data:`SENSOR_ESTIMATOR` is defined there.
"""

import math
from typing import Protocol

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from motosim.choices import ESTIMATOR_NAMES, SENSOR_ESTIMATOR
from motosim.errors import MotosimError
from motosim.estimation.baselines import (
    InverseDynamicsEstimator,
    KalmanTorqueEstimator,
    design_inverse_dynamics,
    design_kalman,
    inverse_dynamics_start,
    inverse_dynamics_step,
    kalman_start,
    kalman_step,
)
from motosim.estimation.differentiator import differentiate
from motosim.estimation.kernel import (
    INVERSE_DYNAMICS,
    TORQUE_SENSOR,
    WALCOTT_ZAK,
    EstimatorKernel,
    SensorState,
    TorqueSensorSettings,
    pack,
)
from motosim.estimation.walcott_zak import (
    ObserverSettings,
    WalcottZakObserver,
    design_with,
    wz_start,
    wz_step,
)
from motosim.params.handlebar import HandlebarParameters

__all__ = [
    "ESTIMATORS",
    "SENSOR_ESTIMATOR",
    "EstimatorFactory",
    "TorqueEstimator",
    "estimate",
    "kernel",
    "start_kernel",
    "step_kernel",
    "torque_sensor_kernel",
    "walcott_zak_for_step",
]

Array = NDArray[np.float64]


class TorqueEstimator(Protocol):
    """Stepper interface shared by the rider-torque estimators."""

    @property
    def kernel(self) -> EstimatorKernel:
        """The record of the compiled kernel, for compiled loops."""
        ...

    def reset(self) -> None:
        """Return to the initial state."""

    def step(self, theta_h: float, theta_h_dot: float, i_m: float) -> tuple[Array, float]:
        """Take theta_h [rad], theta_h' [rad/s], i_m [A]; return (x_hat, tau_r_hat [N*m])."""
        ...


def walcott_zak_for_step(
    hb: HandlebarParameters, dt: float, *, friction_compensation: bool = True
) -> WalcottZakObserver:
    """Walcott-Zak observer with the default design and an injection bandwidth for ``dt``.

    The injection bandwidth is min(800, 0.8 / dt) [1/s]: as fast as the sampled injection
    loop allows (see :class:`~motosim.estimation.walcott_zak.WalcottZakObserver`).

    Parameters
    ----------
    hb : HandlebarParameters
        Nominal handlebar.
    dt : float
        Sampling step [s].
    friction_compensation : bool
        Subtract the nominal dry friction from the estimate.

    Returns
    -------
    WalcottZakObserver
    """
    settings = ObserverSettings.for_step(dt, friction_compensation=friction_compensation)
    gains = design_with(hb, settings)
    return WalcottZakObserver(gains, dt)


def _inverse_dynamics(
    hb: HandlebarParameters, dt: float, *, friction_compensation: bool = True
) -> InverseDynamicsEstimator:
    gains = design_inverse_dynamics(hb, friction_compensation=friction_compensation)
    return InverseDynamicsEstimator(gains, dt)


def _kalman(
    hb: HandlebarParameters, dt: float, *, friction_compensation: bool = True
) -> KalmanTorqueEstimator:
    return KalmanTorqueEstimator(design_kalman(hb, friction_compensation=friction_compensation), dt)


class EstimatorFactory(Protocol):
    """Builds a fresh estimator for a nominal handlebar and a sampling step [s]."""

    def __call__(
        self, hb: HandlebarParameters, dt: float, *, friction_compensation: bool = True
    ) -> TorqueEstimator:
        """Return a new stepper."""
        ...


ESTIMATORS: dict[str, EstimatorFactory] = {
    "walcott_zak": walcott_zak_for_step,
    "inverse_dynamics": _inverse_dynamics,
    "kalman": _kalman,
}
"""Estimator factories by name: ``ESTIMATORS[name](hb, dt)`` returns a fresh stepper.

The first entry is the default (the paper's observer)."""


if tuple(ESTIMATORS) != ESTIMATOR_NAMES:  # the light names a scenario is checked against
    raise AssertionError(
        f"motosim.choices.ESTIMATOR_NAMES {ESTIMATOR_NAMES} differs from the registry's "
        f"{tuple(ESTIMATORS)}: write the registry's names there, in its order"
    )


def torque_sensor_kernel(dt: float, *, low_pass: float = 0.0) -> EstimatorKernel:
    """The record of a torque sensor read every ``dt`` [s], through a low-pass.

    The estimate is the measured torque through the first-order low-pass of corner
    ``low_pass`` [Hz] discretised exactly for a held input, y+ = y + a (u - y) with
    a = 1 - exp(-2 pi f_c dt) (its :class:`~motosim.estimation.kernel.TorqueSensorSettings`;
    a = 1, the torque as measured, for ``low_pass`` 0).

    Parameters
    ----------
    dt : float
        Sampling step [s].
    low_pass : float
        Corner frequency [Hz]; 0 for none.

    Returns
    -------
    EstimatorKernel

    Raises
    ------
    MotosimError
        On a step or corner out of range.

    Examples
    --------
    >>> torque_sensor_kernel(1e-3).torque_sensor.low_pass
    1.0
    """
    if not (math.isfinite(dt) and dt > 0.0):
        raise MotosimError(f"dt = {dt!r}; expected a finite step > 0 [s]")
    if not (math.isfinite(low_pass) and low_pass >= 0.0):
        raise MotosimError(f"low_pass = {low_pass!r}; expected a finite corner >= 0 [Hz]")
    a = 1.0 if low_pass == 0.0 else -math.expm1(-2.0 * math.pi * low_pass * dt)
    zero = np.zeros((1, 1))
    return pack(TORQUE_SENSOR, zero, zero, np.zeros(1), TorqueSensorSettings(a), dt)


def estimate(
    name: str,
    t: ArrayLike,
    theta_h: ArrayLike,
    i_m: ArrayLike,
    hb: HandlebarParameters,
    *,
    lipschitz: float = 300.0,
    friction_compensation: bool = True,
    torque: ArrayLike | None = None,
) -> tuple[Array, Array]:
    """Estimate the rider torque from logged, uniformly sampled angle and current.

    Parameters
    ----------
    name : str
        A key of :data:`ESTIMATORS`, or :data:`SENSOR_ESTIMATOR` (the torque sensor's
        ``torque``, as measured).
    t : array_like, shape (n,)
        Uniformly spaced sample times [s], n >= 2.
    theta_h : array_like, shape (n,)
        Handlebar angle [rad].
    i_m : array_like, shape (n,)
        Motor current, held between samples [A].
    hb : HandlebarParameters
        Nominal handlebar used by the estimator.
    lipschitz : float
        L, a bound on |theta_h''| for the differentiator [rad/s^2].
    friction_compensation : bool
        Subtract the nominal dry friction from the estimate (section V.A).
    torque : array_like, shape (n,), optional
        The rider's torque measured by a torque sensor [N*m] (a log's ``tau_r_meas``), read
        by :data:`SENSOR_ESTIMATOR` only, which needs it.

    Returns
    -------
    theta_h_dot_hat : ndarray, shape (n,)
        Differentiated rate (implicit super-twisting differentiator) [rad/s].
    tau_r_hat : ndarray, shape (n,)
        Rider-torque estimate [N*m].

    Raises
    ------
    MotosimError
        On an unknown name, bad shapes, non-finite samples or non-uniform sampling.
    """
    if name not in ESTIMATORS and name != SENSOR_ESTIMATOR:
        known = [*sorted(ESTIMATORS), SENSOR_ESTIMATOR]
        raise MotosimError(f"estimator {name!r} is unknown; expected one of {known}")
    if (name == SENSOR_ESTIMATOR) != (torque is not None):
        raise MotosimError(
            f"estimator {name!r} with torque {'given' if torque is not None else 'missing'}; "
            f"the measured torque is for {SENSOR_ESTIMATOR!r} only, which needs it"
        )
    tt = np.asarray(t, dtype=float)
    if tt.ndim != 1 or tt.size < 2 or not np.all(np.isfinite(tt)):
        raise MotosimError(f"t has shape {tt.shape}; expected (n,) finite with n >= 2")
    steps = np.diff(tt)
    dt = float(np.mean(steps))
    if not (dt > 0 and np.all(np.abs(steps - dt) <= 0.01 * dt)):
        k = int(np.argmax(np.abs(steps - dt) > 0.01 * dt))
        raise MotosimError(
            f"t is not uniformly sampled: step {steps[k]:g} s at t = {tt[k]:g} s against a mean "
            f"of {dt:g} s; expected a constant rate (within 1 %)"
        )
    arrays = []
    named = [("theta_h", theta_h), ("i_m", i_m)]
    if torque is not None:
        named.append(("torque", torque))
    for label, values in named:
        arr = np.asarray(values, dtype=float)
        if arr.shape != tt.shape:
            raise MotosimError(f"{label} has shape {arr.shape}; expected {tt.shape} like t")
        if not np.all(np.isfinite(arr)):
            raise MotosimError(f"{label} has a NaN or infinite sample; expected finite values")
        arrays.append(arr)
    theta, current = arrays[0], arrays[1]
    rate = differentiate(theta, dt, lipschitz)
    if torque is not None:  # the sensor's kernel, without a low-pass: the torque as measured
        record, state = torque_sensor_kernel(dt), np.zeros(4)
        start_kernel(record, state, theta[0], 0.0, current[0])
        measured = np.array(
            [
                step_kernel(record, state, theta[k], rate[k], current[k], arrays[2][k])
                for k in range(tt.size)
            ]
        )
        return rate, measured
    stepper = ESTIMATORS[name](hb, dt, friction_compensation=friction_compensation)
    tau = np.empty(tt.size)
    for k in range(tt.size):
        _, tau[k] = stepper.step(theta[k], rate[k], current[k])
    return rate, tau


def kernel(
    name: str, hb: HandlebarParameters, dt: float, *, friction_compensation: bool = True
) -> EstimatorKernel:
    """The compiled-kernel record of the estimator ``name``, default design, for ``hb`` at ``dt``.

    Raises
    ------
    MotosimError
        On an unknown estimator or an impossible design at this step.
    """
    if name not in ESTIMATORS:
        raise MotosimError(f"estimator {name!r} is unknown; expected one of {sorted(ESTIMATORS)}")
    return ESTIMATORS[name](hb, dt, friction_compensation=friction_compensation).kernel


@njit(cache=True)
def start_kernel(
    k: EstimatorKernel, state: Array, theta: float, theta_dot: float, current: float
) -> None:
    """Start ``state`` (4,) at the first sample, as the estimator of ``k.kind`` does."""
    if k.kind == TORQUE_SENSOR:
        state[:] = 0.0
    elif k.kind == WALCOTT_ZAK:
        wz_start(state, theta, theta_dot, current)
    elif k.kind == INVERSE_DYNAMICS:
        inverse_dynamics_start(state, theta, theta_dot, current)
    else:
        kalman_start(state, theta, theta_dot, current)


@njit(cache=True, inline="always")
def step_kernel(
    k: EstimatorKernel,
    state: Array,
    theta: float,
    theta_dot: float,
    current: float,
    torque: float = 0.0,
) -> float:
    """One sample of the estimator of ``k.kind``: updates ``state`` (4,), returns tau_r_hat.

    Parameters
    ----------
    k : EstimatorKernel
        The estimator's record.
    state : ndarray, shape (4,)
        Its state, started by :func:`start_kernel`; advanced to the next sample in place.
    theta, theta_dot : float
        Measured angle [rad] and differentiated rate [rad/s].
    current : float
        Motor current held over the coming step [A].
    torque : float
        The rider's torque measured by a torque sensor [N*m], read by the kind
        :data:`~motosim.estimation.kernel.TORQUE_SENSOR` only.

    Returns
    -------
    float
        Rider-torque estimate at this sample [N*m].
    """
    if k.kind == TORQUE_SENSOR:  # the low-pass's output, started at the first sample
        a = k.torque_sensor.low_pass
        if state[SensorState.started] == 0.0 or a >= 1.0:  # the first sample, or no low-pass
            state[SensorState.torque], state[SensorState.started] = torque, 1.0
        else:
            state[SensorState.torque] += a * (torque - state[SensorState.torque])
        return float(state[SensorState.torque])
    if k.kind == WALCOTT_ZAK:
        return wz_step(
            state,
            theta,
            theta_dot,
            current,
            k.Phi[:2, :2],
            k.Gamma[:2, :],
            k.gain[:2],
            k.walcott_zak,
        )
    if k.kind == INVERSE_DYNAMICS:
        return inverse_dynamics_step(
            state, theta, current, k.Phi, k.Gamma[:, :2], k.inverse_dynamics
        )
    _, _, tau = kalman_step(
        state[:3], theta, current, k.Phi[:3, :3], k.Gamma[:3, :2], k.gain[:3], k.kalman
    )
    return tau
