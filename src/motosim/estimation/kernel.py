"""The record every rider-torque estimator publishes for compiled loops.

A compiled loop (the stack step of :mod:`motosim.sim.stack`) cannot call a Python stepper
object, so each estimator also publishes its discretised design as an
:class:`EstimatorKernel`: which compiled kernel to run (``kind``, an
:class:`EstimatorKind`), its matrices, padded to common shapes, and its scalar settings by
name. Every record carries the settings of every kind (those of the other kinds zero), so
that one compiled loop serves every estimator. :mod:`motosim.estimation.registry` holds the
one dispatch on the kind.
"""

from enum import IntEnum
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "INVERSE_DYNAMICS",
    "KALMAN",
    "TORQUE_SENSOR",
    "WALCOTT_ZAK",
    "EstimatorKernel",
    "EstimatorKind",
    "InverseDynamicsSettings",
    "InverseDynamicsState",
    "KalmanSettings",
    "KalmanState",
    "ObserverInput",
    "ObserverState",
    "SensorState",
    "TorqueSensorSettings",
    "WalcottZakSettings",
    "pack",
]

Array = NDArray[np.float64]


class EstimatorKind(IntEnum):
    """Which compiled kernel an :class:`EstimatorKernel` runs."""

    WALCOTT_ZAK = 0
    """:func:`motosim.estimation.walcott_zak.wz_step`."""
    INVERSE_DYNAMICS = 1
    """:func:`motosim.estimation.baselines.inverse_dynamics_step`."""
    KALMAN = 2
    """:func:`motosim.estimation.baselines.kalman_step`."""
    TORQUE_SENSOR = 3
    """A measured torque passed through a low-pass
    (:func:`motosim.estimation.registry.torque_sensor_kernel`)."""


WALCOTT_ZAK = EstimatorKind.WALCOTT_ZAK
INVERSE_DYNAMICS = EstimatorKind.INVERSE_DYNAMICS
KALMAN = EstimatorKind.KALMAN
TORQUE_SENSOR = EstimatorKind.TORQUE_SENSOR


class ObserverState(IntEnum):
    """Positions in the Walcott-Zak observer's state
    (:func:`~motosim.estimation.walcott_zak.wz_step`): its estimate of the handlebar's
    state of eq. (10), (theta_h', theta_h) [rad/s, rad], then the filtered injection, the
    rider-torque estimate [N*m], and the rate input of the last sample [rad/s]."""

    rate = 0
    angle = 1
    estimate = 2
    previous_rate = 3


class ObserverInput(IntEnum):
    """The Walcott-Zak observer's inputs over a sample, in the order of its Gamma's columns:
    the motor current [A], the measured rate [rad/s] and angle [rad], and the torque input
    of D [N*m]."""

    current = 0
    rate = 1
    angle = 2
    torque = 3


class InverseDynamicsState(IntEnum):
    """Positions in the filtered inverse dynamics' state
    (:func:`~motosim.estimation.baselines.inverse_dynamics_step`): the filtered angle
    theta_f [rad] and its rate [rad/s], the filtered current i_f [A] and its rate [A/s];
    also the rows and columns of the filters' Phi."""

    angle = 0
    rate = 1
    current = 2
    current_rate = 3


class KalmanState(IntEnum):
    """Positions in the Kalman filter's predicted state
    (:func:`~motosim.estimation.baselines.kalman_step`): (theta_h', theta_h, tau_r)
    [rad/s, rad, N*m], the rows and columns of its Phi."""

    rate = 0
    angle = 1
    torque = 2


class SensorState(IntEnum):
    """Positions in the torque sensor kernel's state: the low-pass's output [N*m] and
    whether the first sample came (1) or not (0)."""

    torque = 0
    started = 1


class WalcottZakSettings(NamedTuple):
    """The scalar settings of :func:`~motosim.estimation.walcott_zak.wz_step`.

    Attributes
    ----------
    eta : float
        Injection gain eta of eq. (12) [N*m].
    epsilon : float
        Boundary layer epsilon of eq. (12) [units of F (y_a - y_a_hat)].
    sign : float
        Injection sign: +1 (consistent with eq. 15) or -1 (as printed).
    beta_s : float
        Dry friction compensated [N*m]; 0 for none.
    dead_zone : float
        Rate below which the friction compensation is off [rad/s].
    friction_width : float
        Rate scale of the friction's smoothed sign [rad/s].
    filter_alpha : float
        The injection's low-pass over one step, 1 - exp(-h / T) [-].
    rate_weight : float
        Rate extrapolation weight w: the rate used is theta_dot + w (theta_dot - previous) [-].
    torque_per_amp : float
        N k_t [N*m/A].
    stick_projection : bool
        While the handlebar sticks, the friction holds what the last estimate does not.
    """

    eta: float = 0.0
    epsilon: float = 1.0
    sign: float = 1.0
    beta_s: float = 0.0
    dead_zone: float = 0.0
    friction_width: float = 0.0
    filter_alpha: float = 1.0
    rate_weight: float = 0.0
    torque_per_amp: float = 0.0
    stick_projection: bool = False


class InverseDynamicsSettings(NamedTuple):
    """The settings of :func:`~motosim.estimation.baselines.inverse_dynamics_step`.

    Attributes
    ----------
    inertia, damping : float
        J_eq [kg*m^2] and beta_eq [N*m*s/rad].
    torque_per_amp : float
        N k_t [N*m/A].
    cutoff : float
        The derivative filters' corner omega_f [rad/s].
    beta_s, dead_zone, friction_width : float
        Dry friction [N*m], its dead zone and its smoothed sign's scale [rad/s].
    """

    inertia: float = 0.0
    damping: float = 0.0
    torque_per_amp: float = 0.0
    cutoff: float = 0.0
    beta_s: float = 0.0
    dead_zone: float = 0.0
    friction_width: float = 0.0


class KalmanSettings(NamedTuple):
    """The friction compensation of :func:`~motosim.estimation.baselines.kalman_step`.

    Attributes
    ----------
    beta_s, dead_zone, friction_width : float
        Dry friction [N*m], its dead zone and its smoothed sign's scale [rad/s].
    """

    beta_s: float = 0.0
    dead_zone: float = 0.0
    friction_width: float = 0.0


class TorqueSensorSettings(NamedTuple):
    """A torque sensor's low-pass.

    Attributes
    ----------
    low_pass : float
        Coefficient a of y+ = y + a (u - y) over one step; 1 for the torque as measured [-].
    """

    low_pass: float = 1.0


class EstimatorKernel(NamedTuple):
    """An estimator's compiled one-sample kernel, its arrays and settings.

    A named tuple (immutable, and passed to numba-compiled code as is). The arrays are padded
    with zeros; each kernel reads its own leading block and its own settings.

    Attributes
    ----------
    kind : EstimatorKind
        Which kernel runs.
    Phi : ndarray, shape (4, 4)
        State transition over one sample.
    Gamma : ndarray, shape (4, 4)
        Input matrix over one sample (inputs held).
    gain : ndarray, shape (4,)
        Output-injection or Kalman gain.
    dt : float
        Sampling step the kernel was discretised for [s].
    walcott_zak, inverse_dynamics, kalman, torque_sensor : NamedTuple
        Each kind's settings; those of the other kinds are their defaults.
    """

    kind: int
    Phi: Array
    Gamma: Array
    gain: Array
    dt: float
    walcott_zak: WalcottZakSettings = WalcottZakSettings()
    inverse_dynamics: InverseDynamicsSettings = InverseDynamicsSettings()
    kalman: KalmanSettings = KalmanSettings()
    torque_sensor: TorqueSensorSettings = TorqueSensorSettings()


def _padded(values: ArrayLike, shape: tuple[int, ...]) -> Array:
    arr = np.asarray(values, dtype=np.float64)
    out = np.zeros(shape)
    out[tuple(slice(0, n) for n in arr.shape)] = arr
    return out


def pack(
    kind: EstimatorKind,
    Phi: ArrayLike,
    Gamma: ArrayLike,
    gain: ArrayLike,
    settings: WalcottZakSettings | InverseDynamicsSettings | KalmanSettings | TorqueSensorSettings,
    dt: float,
) -> EstimatorKernel:
    """Pad an estimator's arrays and file its settings into an :class:`EstimatorKernel`.

    Each setting is converted to its default's type (float or bool), so that every record
    has one numba type and the compiled loop is compiled once.
    """
    defaults = type(settings)()
    values: list[Any] = [type(d)(v) for v, d in zip(settings, defaults, strict=True)]
    typed = type(settings)(*values)
    return EstimatorKernel(
        int(kind),
        _padded(Phi, (4, 4)),
        _padded(Gamma, (4, 4)),
        _padded(gain, (4,)),
        float(dt),
        typed if isinstance(typed, WalcottZakSettings) else WalcottZakSettings(),
        typed if isinstance(typed, InverseDynamicsSettings) else InverseDynamicsSettings(),
        typed if isinstance(typed, KalmanSettings) else KalmanSettings(),
        typed if isinstance(typed, TorqueSensorSettings) else TorqueSensorSettings(),
    )
