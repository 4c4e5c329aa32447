"""Named rider-torque estimators and a batch runner over logged samples.

:data:`ESTIMATORS` maps a name to a factory ``(hb, dt) -> stepper`` built with each
estimator's default design; :func:`estimate` differentiates the angle with the implicit
super-twisting differentiator and runs the stepper over the samples. The command line uses
these names.
"""

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motosim.errors import MotosimError
from motosim.estimation.baselines import (
    InverseDynamicsEstimator,
    KalmanTorqueEstimator,
    design_inverse_dynamics,
    design_kalman,
)
from motosim.estimation.differentiator import differentiate
from motosim.estimation.walcott_zak import WalcottZakObserver, design
from motosim.params.handlebar import HandlebarParameters

__all__ = [
    "ESTIMATORS",
    "EstimatorFactory",
    "KernelArguments",
    "TorqueEstimator",
    "estimate",
    "kernel_arguments",
    "walcott_zak_for_step",
]

Array = NDArray[np.float64]


class TorqueEstimator(Protocol):
    """Stepper interface shared by the rider-torque estimators."""

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
    if not (math.isfinite(dt) and dt > 0):
        raise MotosimError(f"dt = {dt!r}; expected a finite step > 0 [s]")
    gains = design(
        hb,
        injection_bandwidth=min(800.0, 0.8 / dt),
        friction_compensation=friction_compensation,
    )
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


def estimate(
    name: str,
    t: ArrayLike,
    theta_h: ArrayLike,
    i_m: ArrayLike,
    hb: HandlebarParameters,
    *,
    lipschitz: float = 300.0,
    friction_compensation: bool = True,
) -> tuple[Array, Array]:
    """Estimate the rider torque from logged, uniformly sampled angle and current.

    Parameters
    ----------
    name : str
        A key of :data:`ESTIMATORS`.
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
    if name not in ESTIMATORS:
        raise MotosimError(f"estimator {name!r} is unknown; expected one of {sorted(ESTIMATORS)}")
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
    for label, values in (("theta_h", theta_h), ("i_m", i_m)):
        arr = np.asarray(values, dtype=float)
        if arr.shape != tt.shape:
            raise MotosimError(f"{label} has shape {arr.shape}; expected {tt.shape} like t")
        if not np.all(np.isfinite(arr)):
            raise MotosimError(f"{label} has a NaN or infinite sample; expected finite values")
        arrays.append(arr)
    theta, current = arrays
    rate = differentiate(theta, dt, lipschitz)
    stepper = ESTIMATORS[name](hb, dt, friction_compensation=friction_compensation)
    tau = np.empty(tt.size)
    for k in range(tt.size):
        _, tau[k] = stepper.step(theta[k], rate[k], current[k])
    return rate, tau


@dataclass(frozen=True, slots=True)
class KernelArguments:
    """The arrays of an estimator's compiled one-sample kernel, padded to common shapes.

    ``kind`` 0 is :func:`~motosim.estimation.walcott_zak.wz_step` (Phi 2x2, Gamma 2x4, gain
    F C_a in ``gain[:2]``, p[:8]); 1 is
    :func:`~motosim.estimation.baselines.inverse_dynamics_step` (Phi 4x4, Gamma 4x2, p[:7]);
    2 is :func:`~motosim.estimation.baselines.kalman_step` (Phi 3x3, Gamma 3x2, Kalman gain in
    ``gain[:3]``, p[:3]). Compiled loops (:mod:`motosim.sim`) dispatch on ``kind``.
    """

    kind: int
    Phi: Array
    Gamma: Array
    gain: Array
    p: Array


def _padded(values: Array, shape: tuple[int, ...]) -> Array:
    out = np.zeros(shape)
    out[tuple(slice(0, n) for n in values.shape)] = values
    return out


def kernel_arguments(
    name: str, hb: HandlebarParameters, dt: float, *, friction_compensation: bool = True
) -> KernelArguments:
    """The compiled-kernel arrays of the estimator ``name`` designed for ``hb`` at ``dt``.

    Raises
    ------
    MotosimError
        On an unknown estimator or an impossible design at this step.
    """
    if name not in ESTIMATORS:
        raise MotosimError(f"estimator {name!r} is unknown; expected one of {sorted(ESTIMATORS)}")
    stepper = ESTIMATORS[name](hb, dt, friction_compensation=friction_compensation)
    if isinstance(stepper, WalcottZakObserver):
        kind, gain = 0, stepper._g
    elif isinstance(stepper, InverseDynamicsEstimator):
        kind, gain = 1, np.zeros(4)
    else:
        assert isinstance(stepper, KalmanTorqueEstimator)
        kind, gain = 2, stepper._K
    return KernelArguments(
        kind=kind,
        Phi=_padded(stepper._Phi, (4, 4)),
        Gamma=_padded(stepper._Gamma, (4, 4)),
        gain=_padded(np.asarray(gain, dtype=float), (4,)),
        p=_padded(stepper._p, (8,)),
    )
