"""The motorised handlebar: DC motor, belt and handlebar with viscous and dry friction.

Mechanics, eq. (5) of the paper::

    J_eq theta_h'' + beta_eq theta_h' + beta_s sign(theta_h') = tau_r + N k_t i_m

Electrics, eq. (6) with the motor shaft speed N theta_h' (the printed eq. (7) drops the
derivative; the back-EMF is proportional to speed)::

    L i_m' + R i_m = u - k_e N theta_h'

Dry friction is treated exactly by default (``friction_width = 0``): over each step the input
torque is held, the motion between velocity reversals is integrated in closed form, and the
handlebar sticks at zero velocity while |applied torque| <= beta_s (Karnopp's stick-slip).
This is what the hardware does and what identification and estimation must cope with, and it
costs no more than one exponential per step. A smooth ``beta_s tanh(theta_h' / width)`` with
a positive width is available for analysis and for the electrical dynamics (L > 0), which are
integrated by RK4 sub-steps.
"""

import math
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from motosim.errors import MotosimError
from motosim.model._inputs import input_series, sample_times
from motosim.model.linear import StateSpace
from motosim.params.handlebar import HandlebarParameters
from motosim.timeseries import TimeSeries

__all__ = [
    "HandlebarMatrices",
    "HandlebarPlant",
    "friction_torque",
    "linear_model",
    "matrices",
    "perturbed",
    "plant_of",
    "simulate_handlebar",
    "step_exact",
    "step_smooth",
]

Array = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class HandlebarMatrices:
    """Eq. (10): x' = A x + B i_m + D (tau_r + tau_p), y = C x, with x = [theta_h', theta_h].

    B is per ampere (the paper's u = N k_t i_m folded in), D per N*m.
    """

    A: Array
    B: Array
    D: Array
    C: Array


class HandlebarPlant(NamedTuple):
    """The handlebar of eq. (5) as compiled loops step it (:func:`step_exact`): J_eq
    [kg*m^2], beta_eq [N*m*s/rad], beta_s [N*m] and the torque per ampere N k_t [N*m/A]."""

    J_eq: float
    beta_eq: float
    beta_s: float
    torque_per_amp: float


def plant_of(hb: HandlebarParameters) -> HandlebarPlant:
    """The :class:`HandlebarPlant` of ``hb``."""
    return HandlebarPlant(
        float(hb.J_eq), float(hb.beta_eq), float(hb.beta_s), float(hb.torque_per_amp)
    )


def perturbed(
    hb: HandlebarParameters,
    *,
    inertia_factor: float = 1.0,
    damping_factor: float = 1.0,
    friction: bool = True,
) -> HandlebarParameters:
    """The handlebar with J_eq and beta_eq scaled and, without ``friction``, no dry friction.

    The motor's own share (J_m, beta_vm) is set to zero so that any factor, including a
    large cut, gives valid parameters: eq. (5) sees only the equivalent values.
    """
    return replace(
        hb,
        J_eq=hb.J_eq * inertia_factor,
        beta_eq=hb.beta_eq * damping_factor,
        beta_s=hb.beta_s if friction else 0.0,
        J_m=0.0,
        beta_vm=0.0,
    )


def matrices(hb: HandlebarParameters) -> HandlebarMatrices:
    """State-space matrices of eq. (10) for the handlebar ``hb``.

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> m = matrices(load_parameters("simacom_handlebar", "handlebar"))
    >>> round(float(-m.A[0, 0]), 1)    # beta_eq / J_eq [1/s]
    336.3
    """
    return HandlebarMatrices(
        A=np.array([[-hb.beta_eq / hb.J_eq, 0.0], [1.0, 0.0]]),
        B=np.array([hb.torque_per_amp / hb.J_eq, 0.0]),
        D=np.array([1.0 / hb.J_eq, 0.0]),
        C=np.array([0.0, 1.0]),
    )


def linear_model(hb: HandlebarParameters) -> StateSpace:
    """Eq. (10) as a :class:`StateSpace` with inputs (i_m, tau_r) and output theta_h.

    Dry friction is left out: it acts like rider torque, through D (tau_p = -beta_s sign).
    """
    m = matrices(hb)
    return StateSpace(
        A=m.A,
        B=np.column_stack([m.B, m.D]),
        C=m.C[None, :],
        D=np.zeros((1, 2)),
        state_names=("theta_h_dot", "theta_h"),
        input_names=("i_m", "tau_r"),
        output_names=("theta_h",),
    )


@njit(cache=True)
def friction_torque(omega: float, beta_s: float, width: float) -> float:
    """Dry-friction torque tau_p opposing the rate ``omega`` [rad/s].

    ``width`` 0 gives -beta_s sign(omega) (zero at rest); a positive width [rad/s] gives
    -beta_s tanh(omega / width).
    """
    if width > 0.0:
        return -beta_s * math.tanh(omega / width)
    if omega > 0.0:
        return -beta_s
    if omega < 0.0:
        return beta_s
    return 0.0


@njit(cache=True)
def step_exact(
    theta: float, omega: float, torque: float, J: float, beta: float, beta_s: float, dt: float
) -> tuple[float, float]:
    """Advance eq. (5) by ``dt`` with exact stick-slip, the applied torque held.

    Parameters
    ----------
    theta, omega : float
        Angle [rad] and rate [rad/s] at the start; ``omega == 0`` means at rest.
    torque : float
        tau_r + N k_t i_m [N*m], constant over the step.
    J, beta, beta_s : float
        J_eq [kg*m^2], beta_eq > 0 [N*m*s/rad], beta_s >= 0 [N*m].
    dt : float
        Step [s].

    Returns
    -------
    theta, omega : float
        At the end of the step.
    """
    a = beta / J
    remaining = dt
    for _ in range(3):
        if omega == 0.0:
            if abs(torque) <= beta_s:
                return theta, 0.0
            s = 1.0 if torque > 0.0 else -1.0
        else:
            s = 1.0 if omega > 0.0 else -1.0
        w_inf = (torque - beta_s * s) / beta
        t_hit = remaining
        if s * w_inf < 0.0:  # decelerating through zero: when does the rate vanish?
            t_hit = -math.log(-w_inf / (omega - w_inf)) / a
        if t_hit >= remaining:
            decay = math.exp(-a * remaining)
            theta += w_inf * remaining + (omega - w_inf) * (1.0 - decay) / a
            return theta, w_inf + (omega - w_inf) * decay
        decay = math.exp(-a * t_hit)
        theta += w_inf * t_hit + (omega - w_inf) * (1.0 - decay) / a
        omega = 0.0
        remaining -= t_hit
    return theta, omega


@njit(cache=True)
def _rhs(
    omega: float, current: float, torque_ext: float, volts: float, p: NDArray[np.float64]
) -> tuple[float, float, float]:
    """Rates of (theta, omega, i_m); p = [J, beta, beta_s, width, Nk_t, R, L, k_e N]."""
    J, beta, beta_s, width, nkt, R, L, ken = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    domega = (torque_ext + nkt * current - beta * omega + friction_torque(omega, beta_s, width)) / J
    dcurrent = (volts - R * current - ken * omega) / L if L > 0.0 else 0.0
    return omega, domega, dcurrent


@njit(cache=True)
def step_smooth(
    state: NDArray[np.float64],
    tau_r: float,
    drive: float,
    p: NDArray[np.float64],
    dt: float,
    n_sub: int,
) -> None:
    """Advance (theta, omega, i_m) in place by ``dt`` with ``n_sub`` RK4 sub-steps.

    ``drive`` is the voltage [V] when p[6] = L > 0 (current is a state); otherwise it is the
    current [A], held. The friction width p[3] must be positive.
    """
    h = dt / n_sub
    L = p[6]
    if L <= 0.0:
        state[2] = drive
    for _ in range(n_sub):
        th, om, cu = state[0], state[1], state[2]
        k1 = _rhs(om, cu, tau_r, drive, p)
        k2 = _rhs(om + 0.5 * h * k1[1], cu + 0.5 * h * k1[2], tau_r, drive, p)
        k3 = _rhs(om + 0.5 * h * k2[1], cu + 0.5 * h * k2[2], tau_r, drive, p)
        k4 = _rhs(om + h * k3[1], cu + h * k3[2], tau_r, drive, p)
        state[0] = th + h / 6.0 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        state[1] = om + h / 6.0 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        if L > 0.0:
            state[2] = cu + h / 6.0 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2])


@njit(cache=True)
def _run(
    dts: NDArray[np.float64],
    tau_r: NDArray[np.float64],
    drive: NDArray[np.float64],
    by_voltage: bool,
    p: NDArray[np.float64],
    theta0: float,
    max_step: float,
) -> NDArray[np.float64]:
    """Columns theta_h, theta_h_dot, i_m, u at each sample; inputs held between samples."""
    n = tau_r.size
    out = np.empty((n, 4))
    J, beta, beta_s, width, nkt, R, L, ken = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    state = np.array([theta0, 0.0, 0.0])
    if by_voltage and L <= 0.0:
        state[2] = drive[0] / R
    elif not by_voltage:
        state[2] = drive[0]
    for k in range(n):
        if by_voltage:
            volts = drive[k]
            if L <= 0.0:
                state[2] = (volts - ken * state[1]) / R
        else:
            state[2] = drive[k]
            volts = R * state[2] + ken * state[1]
        out[k, 0], out[k, 1], out[k, 2], out[k, 3] = state[0], state[1], state[2], volts
        if k == n - 1:
            break
        dt = dts[k]
        n_sub = max(1, int(math.ceil(dt / max_step - 1e-9)))  # noqa: RUF046 - numba typing
        if width == 0.0 and L <= 0.0:
            # exact: quasi-static current adds the electrical damping N^2 k_t k_e / R
            if by_voltage:
                beta_eff = beta + nkt * ken / R
                torque = tau_r[k] + nkt * volts / R
            else:
                beta_eff = beta
                torque = tau_r[k] + nkt * state[2]
            state[0], state[1] = step_exact(state[0], state[1], torque, J, beta_eff, beta_s, dt)
        else:
            step_smooth(state, tau_r[k], volts if L > 0.0 else state[2], p, dt, n_sub)
    return out


def simulate_handlebar(
    hb: HandlebarParameters,
    t: ArrayLike,
    *,
    rider_torque: ArrayLike = 0.0,
    current: ArrayLike | None = None,
    voltage: ArrayLike | None = None,
    electrical: bool = False,
    friction_width: float = 0.0,
    max_step: float = 1e-4,
    initial_angle: float = 0.0,
) -> TimeSeries:
    """Simulate the handlebar driven by current or by voltage, from rest.

    Parameters
    ----------
    hb : HandlebarParameters
        The handlebar.
    t : array_like, shape (n,)
        Strictly increasing sample times [s]; inputs are held between samples.
    rider_torque : array_like, shape (n,) or scalar
        tau_r [N*m].
    current, voltage : array_like, shape (n,), exactly one of them
        Motor current i_m [A] (current drive, eq. (5)) or voltage u [V] (eqs. (5)-(7)).
    electrical : bool
        With voltage drive, integrate the armature inductance L (eq. (6)); otherwise the
        current follows the voltage at once (eq. (7)).
    friction_width : float
        0 for exact stick-slip, else the rate [rad/s] of the tanh approximation of sign().
        Electrical dynamics need a positive width.
    max_step : float
        Largest internal step [s] for the RK4 integration.
    initial_angle : float
        theta_h at t[0] [rad].

    Returns
    -------
    TimeSeries
        Signals ``theta_h``, ``theta_h_dot``, ``i_m``, ``u`` and ``tau_r`` at the instants t.

    Raises
    ------
    MotosimError
        On inconsistent shapes, non-finite samples or options.
    """
    tt = sample_times(t)
    if (current is None) == (voltage is None):
        raise MotosimError("give exactly one of current= or voltage=")
    if not (math.isfinite(friction_width) and friction_width >= 0):
        raise MotosimError(f"friction_width = {friction_width!r}; expected >= 0 [rad/s]")
    if electrical and (voltage is None or friction_width == 0.0 or hb.L == 0.0):
        raise MotosimError(
            "electrical dynamics need voltage drive, L > 0 and a friction_width > 0 [rad/s]"
        )
    if not (math.isfinite(max_step) and max_step > 0):
        raise MotosimError(f"max_step = {max_step!r}; expected > 0 [s]")
    n = tt.size
    tau = input_series("rider_torque", rider_torque, n)
    by_voltage = voltage is not None
    if voltage is not None:
        drive = input_series("voltage", voltage, n)
    else:
        assert current is not None
        drive = input_series("current", current, n)
    p = np.array(
        [
            hb.J_eq,
            hb.beta_eq,
            hb.beta_s,
            friction_width,
            hb.torque_per_amp,
            hb.R,
            hb.L if electrical else 0.0,
            hb.k_e * hb.N,
        ]
    )
    out = _run(np.diff(tt), tau, drive, by_voltage, p, float(initial_angle), max_step)
    data = np.column_stack([out, tau])
    return TimeSeries(tt, data, ("theta_h", "theta_h_dot", "i_m", "u", "tau_r"))
