"""Baseline rider-torque estimators to compare the Walcott-Zak observer against.

Both use the same stepper interface as
:class:`~motosim.estimation.walcott_zak.WalcottZakObserver`
(``reset()``, ``step(theta_h, theta_h_dot, i_m) -> (x_hat, tau_r_hat)``) and the same dry
friction compensation (dead zone and tanh edge, Remarks 3.3 and 5.2).

Inverse dynamics
    Eq. (5) solved for the rider torque, tau_r = J_eq theta_h'' + beta_eq theta_h'
    + beta_s sign(theta_h') - N k_t i_m, with theta_h', theta_h'' from a critically damped
    second-order state-variable filter of the angle, and the current through the same filter
    so that both sides of eq. (5) see the same lag. It ignores the differentiated rate.
Kalman filter
    Eq. (10) augmented with a random-walk torque state, x = [theta_h', theta_h, tau_r],
    discretised exactly (matrix exponential, Van Loan for the process noise), measuring the
    angle only, with the steady-state gain. It ignores the differentiated rate.
"""

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray
from scipy.linalg import expm, solve_discrete_are

from motosim.estimation._friction import smooth_sign
from motosim.estimation.kernel import (
    INVERSE_DYNAMICS,
    KALMAN,
    EstimatorKernel,
    InverseDynamicsSettings,
    InverseDynamicsState,
    KalmanSettings,
    KalmanState,
    pack,
)
from motosim.model.handlebar import matrices
from motosim.model.linear import zoh
from motosim.params.checks import check_number
from motosim.params.handlebar import HandlebarParameters

__all__ = [
    "InverseDynamicsEstimator",
    "InverseDynamicsGains",
    "KalmanGains",
    "KalmanTorqueEstimator",
    "design_inverse_dynamics",
    "design_kalman",
    "inverse_dynamics_start",
    "inverse_dynamics_step",
    "kalman_start",
    "kalman_step",
]

Array = NDArray[np.float64]


def _check(name: str, value: float, unit: str, *, allow_zero: bool = False) -> None:
    check_number(value, where=name, lower=0.0, lower_closed=allow_zero, unit=unit)


@dataclass(frozen=True, slots=True)
class InverseDynamicsGains:
    """Design of the filtered inverse-dynamics estimator.

    Attributes
    ----------
    handlebar : HandlebarParameters
        Nominal model (J_eq, beta_eq, N k_t).
    cutoff : float
        Natural frequency of the critically damped derivative filter [rad/s].
    beta_s, dead_zone, friction_width : float
        Dry friction compensated [N*m] (0: off), dead zone and tanh width [rad/s].
    """

    handlebar: HandlebarParameters
    cutoff: float
    beta_s: float
    dead_zone: float
    friction_width: float


def design_inverse_dynamics(
    hb: HandlebarParameters,
    *,
    cutoff: float = 2.0 * math.pi * 10.0,
    friction_compensation: bool = True,
    dead_zone: float = 0.05,
    friction_width: float = 0.05,
) -> InverseDynamicsGains:
    """Design the inverse-dynamics baseline of eq. (5).

    Parameters
    ----------
    hb : HandlebarParameters
        Nominal handlebar.
    cutoff : float
        Filter natural frequency omega_f [rad/s]; the filter is
        omega_f^2 / (s + omega_f)^2 on both the angle and the current.
    friction_compensation : bool
        Add beta_s sign(theta_h') with the dead-zoned, smoothed sign.
    dead_zone, friction_width : float
        On the filtered rate [rad/s].

    Returns
    -------
    InverseDynamicsGains

    Raises
    ------
    MotosimError
        If an option is out of range.
    """
    _check("cutoff", cutoff, "rad/s")
    _check("dead_zone", dead_zone, "rad/s", allow_zero=True)
    _check("friction_width", friction_width, "rad/s", allow_zero=True)
    return InverseDynamicsGains(
        hb, float(cutoff), hb.beta_s if friction_compensation else 0.0, dead_zone, friction_width
    )


_ANGLE_INPUT, _CURRENT_INPUT = 0, 1
"""The inverse dynamics filters' inputs: the columns of their Gamma."""
_KALMAN_CURRENT, _KALMAN_FRICTION = 0, 1
"""The Kalman filter's inputs, i_m and tau_p_hat: the columns of its Gamma."""


@njit(cache=True)
def inverse_dynamics_step(
    state: Array, theta: float, current: float, Phi: Array, Gamma: Array, c: InverseDynamicsSettings
) -> float:
    """One sample of the filtered inverse dynamics.

    Parameters
    ----------
    state : ndarray, shape (4,)
        Filter states [theta_f, theta_f', i_f, i_f'], advanced to the next sample in place.
    theta, current : float
        Angle [rad] and current [A] at this sample, held over the step.
    Phi : ndarray, shape (4, 4)
        Exact discretisation of the two filters.
    Gamma : ndarray, shape (4, 2)
        Their input matrix for [theta, current].
    c : InverseDynamicsSettings
        J_eq, beta_eq, N k_t, the filters' corner omega_f and the friction compensation.

    Returns
    -------
    float
        J theta_f'' + beta theta_f' + beta_s sign(theta_f') - N k_t i_f at this sample [N*m].
    """
    S = InverseDynamicsState
    w = c.cutoff
    x0, x1, x2, x3 = state[S.angle], state[S.rate], state[S.current], state[S.current_rate]
    acc = w * w * (theta - x0) - 2.0 * w * x1
    friction = c.beta_s * smooth_sign(x1, c.dead_zone, c.friction_width)
    tau = c.inertia * acc + c.damping * x1 + friction - c.torque_per_amp * x2
    for r in (S.angle, S.rate, S.current, S.current_rate):
        state[r] = (
            Gamma[r, _ANGLE_INPUT] * theta
            + Gamma[r, _CURRENT_INPUT] * current
            + Phi[r, S.angle] * x0
            + Phi[r, S.rate] * x1
            + Phi[r, S.current] * x2
            + Phi[r, S.current_rate] * x3
        )
    return float(tau)


@njit(cache=True)
def inverse_dynamics_start(state: Array, theta: float, theta_dot: float, current: float) -> None:
    """Start the filters at rest at the first sample's angle [rad] and current [A], in place."""
    state[InverseDynamicsState.angle] = theta
    state[InverseDynamicsState.rate] = 0.0
    state[InverseDynamicsState.current] = current
    state[InverseDynamicsState.current_rate] = 0.0


class InverseDynamicsEstimator:
    """Stepper: eq. (5) solved for tau_r with filtered derivatives.

    Parameters
    ----------
    gains : InverseDynamicsGains
        From :func:`design_inverse_dynamics`.
    dt : float
        Sampling step [s]; the filters are discretised exactly with the inputs held.

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> hb = load_parameters("simacom_handlebar", "handlebar")
    >>> est = InverseDynamicsEstimator(design_inverse_dynamics(hb), 1e-3)
    >>> est.step(0.0, 0.0, 0.0)[1]
    0.0
    """

    def __init__(self, gains: InverseDynamicsGains, dt: float) -> None:
        _check("dt", dt, "s")
        self.gains = gains
        self.dt = float(dt)
        w = gains.cutoff
        block = np.array([[0.0, 1.0], [-w * w, -2.0 * w]])
        A = np.zeros((4, 4))
        A[:2, :2] = block
        A[2:, 2:] = block
        inputs = np.zeros((4, 2))
        inputs[1, 0] = inputs[3, 1] = w * w
        self._Phi, self._Gamma = zoh(A, inputs, self.dt)
        hb = gains.handlebar
        self._settings = InverseDynamicsSettings(
            inertia=hb.J_eq,
            damping=hb.beta_eq,
            torque_per_amp=hb.torque_per_amp,
            cutoff=w,
            beta_s=gains.beta_s,
            dead_zone=gains.dead_zone,
            friction_width=gains.friction_width,
        )
        self.reset()

    @property
    def kernel(self) -> EstimatorKernel:
        """The compiled kernel's record (:func:`inverse_dynamics_step`), for compiled loops."""
        return pack(INVERSE_DYNAMICS, self._Phi, self._Gamma, np.zeros(4), self._settings, self.dt)

    def reset(self) -> None:
        """Forget the past: the next sample initialises the filters at rest."""
        self._state: Array | None = None

    def step(self, theta_h: float, theta_h_dot: float, i_m: float) -> tuple[Array, float]:
        """Take one sample; ``theta_h_dot`` is not used (the filter differentiates).

        Returns
        -------
        x_hat : ndarray, shape (2,)
            [theta_f', theta_f] [rad/s, rad].
        tau_r_hat : float
            Rider-torque estimate [N*m].
        """
        state = self._state
        if state is None:
            state = self._state = np.zeros(4)
            inverse_dynamics_start(state, float(theta_h), float(theta_h_dot), float(i_m))
        x_hat = np.array([state[InverseDynamicsState.rate], state[InverseDynamicsState.angle]])
        tau = inverse_dynamics_step(
            state, float(theta_h), float(i_m), self._Phi, self._Gamma, self._settings
        )
        return x_hat, float(tau)


@dataclass(frozen=True, slots=True)
class KalmanGains:
    """Design of the Kalman filter with a random-walk torque state.

    Attributes
    ----------
    handlebar : HandlebarParameters
        Nominal model.
    torque_rate_noise : float
        Square root of the intensity of the white noise driving tau_r' [N*m/s^(1/2)].
    angle_noise : float
        Standard deviation of the angle measurement [rad].
    beta_s, dead_zone, friction_width : float
        Dry friction compensated [N*m] (0: off), dead zone and tanh width [rad/s].
    """

    handlebar: HandlebarParameters
    torque_rate_noise: float
    angle_noise: float
    beta_s: float
    dead_zone: float
    friction_width: float


def design_kalman(
    hb: HandlebarParameters,
    *,
    torque_rate_noise: float = 10.0,
    angle_noise: float = 2.0 * math.pi / 2**14 / math.sqrt(12.0),
    friction_compensation: bool = True,
    dead_zone: float = 0.05,
    friction_width: float = 0.05,
) -> KalmanGains:
    """Design the Kalman-filter baseline.

    Parameters
    ----------
    hb : HandlebarParameters
        Nominal handlebar.
    torque_rate_noise : float
        sqrt(q), the random walk of tau_r [N*m/s^(1/2)]; larger tracks faster, noisier.
    angle_noise : float
        Angle noise standard deviation [rad]; default: a 14-bit encoder's quantisation,
        2 pi / 2^14 / sqrt(12).
    friction_compensation : bool
        Add tau_p_hat = -beta_s sign(theta_h'_hat) as a known input.
    dead_zone, friction_width : float
        On the estimated rate [rad/s].

    Returns
    -------
    KalmanGains

    Raises
    ------
    MotosimError
        If an option is out of range.
    """
    _check("torque_rate_noise", torque_rate_noise, "N*m/s^(1/2)")
    _check("angle_noise", angle_noise, "rad")
    _check("dead_zone", dead_zone, "rad/s", allow_zero=True)
    _check("friction_width", friction_width, "rad/s", allow_zero=True)
    return KalmanGains(
        hb,
        float(torque_rate_noise),
        float(angle_noise),
        hb.beta_s if friction_compensation else 0.0,
        float(dead_zone),
        float(friction_width),
    )


@njit(cache=True)
def kalman_step(
    z: Array,
    theta: float,
    current: float,
    Phi: Array,
    Gamma: Array,
    K: Array,
    c: KalmanSettings,
) -> tuple[float, float, float]:
    """Measurement update with ``theta`` and prediction over one step.

    Parameters
    ----------
    z : ndarray, shape (3,)
        Predicted [theta_h', theta_h, tau_r] at this sample; the prediction at the next
        sample in place.
    theta, current : float
        Measured angle [rad]; current held over the step [A].
    Phi : ndarray, shape (3, 3)
        exp(A_z h).
    Gamma : ndarray, shape (3, 2)
        int_0^h exp(A_z s) ds for the inputs [i_m, tau_p_hat].
    K : ndarray, shape (3,)
        Steady-state Kalman gain.
    c : KalmanSettings
        The friction compensation.

    Returns
    -------
    tuple of float
        Filtered [theta_h', theta_h, tau_r] at this sample [rad/s, rad, N*m].
    """
    S = KalmanState
    innovation = theta - z[S.angle]
    p0 = z[S.rate] + K[S.rate] * innovation
    p1 = z[S.angle] + K[S.angle] * innovation
    p2 = z[S.torque] + K[S.torque] * innovation
    tau_p_hat = -c.beta_s * smooth_sign(p0, c.dead_zone, c.friction_width)
    for r in (S.rate, S.angle, S.torque):
        z[r] = (
            Gamma[r, _KALMAN_CURRENT] * current
            + Gamma[r, _KALMAN_FRICTION] * tau_p_hat
            + Phi[r, S.rate] * p0
            + Phi[r, S.angle] * p1
            + Phi[r, S.torque] * p2
        )
    return p0, p1, p2


@njit(cache=True)
def kalman_start(state: Array, theta: float, theta_dot: float, current: float) -> None:
    """Start the prediction at the first sample's angle [rad], rate and torque 0, in place."""
    state[:] = 0.0
    state[KalmanState.angle] = theta


class KalmanTorqueEstimator:
    """Stepper: steady-state Kalman filter on eq. (10) with a random-walk rider torque.

    Parameters
    ----------
    gains : KalmanGains
        From :func:`design_kalman`.
    dt : float
        Sampling step [s]; the model and the process noise are discretised exactly.

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> hb = load_parameters("simacom_handlebar", "handlebar")
    >>> est = KalmanTorqueEstimator(design_kalman(hb), 1e-3)
    >>> est.step(0.0, 0.0, 0.0)[1]
    0.0
    """

    def __init__(self, gains: KalmanGains, dt: float) -> None:
        _check("dt", dt, "s")
        self.gains = gains
        self.dt = h = float(dt)
        hb = gains.handlebar
        m = matrices(hb)  # eq. (10), augmented with the random-walk torque
        A = np.zeros((3, 3))
        A[:2, :2], A[:2, 2] = m.A, m.D
        inputs = np.zeros((3, 2))
        inputs[:2, 0], inputs[:2, 1] = m.B, m.D
        self._Phi, self._Gamma = zoh(A, inputs, h)
        # Van Loan: Q_d = int_0^h exp(A s) G q G^T exp(A^T s) ds
        Qc = np.zeros((3, 3))
        Qc[2, 2] = gains.torque_rate_noise**2
        V = np.zeros((6, 6))
        V[:3, :3] = -A * h
        V[:3, 3:] = Qc * h
        V[3:, 3:] = A.T * h
        EV = expm(V)
        Qd = EV[3:, 3:].T @ EV[:3, 3:]
        Qd = 0.5 * (Qd + Qd.T)
        H = np.array([[0.0, 1.0, 0.0]])
        R = np.array([[gains.angle_noise**2]])
        P = solve_discrete_are(self._Phi.T, H.T, Qd, R)
        self._K = (P @ H.T / (H @ P @ H.T + R)[0, 0])[:, 0]
        self._settings = KalmanSettings(gains.beta_s, gains.dead_zone, gains.friction_width)
        self.reset()

    @property
    def kernel(self) -> EstimatorKernel:
        """The compiled kernel's record (:func:`kalman_step`, Kalman gain), for compiled loops."""
        return pack(KALMAN, self._Phi, self._Gamma, self._K, self._settings, self.dt)

    def reset(self) -> None:
        """Forget the past: the next sample initialises the angle; rate and torque 0."""
        self._z: Array | None = None

    def step(self, theta_h: float, theta_h_dot: float, i_m: float) -> tuple[Array, float]:
        """Take one sample; ``theta_h_dot`` is not used (the filter measures the angle only).

        Returns
        -------
        x_hat : ndarray, shape (2,)
            Filtered [theta_h', theta_h] [rad/s, rad].
        tau_r_hat : float
            Filtered rider-torque estimate [N*m].
        """
        z = self._z
        if z is None:
            start = np.zeros(4)
            kalman_start(start, float(theta_h), float(theta_h_dot), float(i_m))
            z = self._z = start[:3]
        rate, angle, tau = kalman_step(
            z, float(theta_h), float(i_m), self._Phi, self._Gamma, self._K, self._settings
        )
        return np.array([rate, angle]), float(tau)
