"""Walcott-Zak sliding-mode unknown-input observer of the rider torque (section III).

The handlebar of eq. (10)::

    x' = A x + B i_m + D (tau_r + tau_p),   x = [theta_h', theta_h],
    A = [[-beta_eq/J_eq, 0], [1, 0]],  B = [N k_t / J_eq, 0],  D = [1/J_eq, 0]

has no torque sensor; the observer of eqs. (11)-(17) reconstructs tau_r from the angle, the
differentiated angle (the extra output y_a = C_a x of eq. (15)) and the motor current.
:func:`design` is the offline part (checks, pole placement, Lyapunov equation, the matching
matrix F), returning frozen :class:`WalcottZakGains`; :class:`WalcottZakObserver` is the run
part, a stepper over the compiled one-sample kernel :func:`wz_step`.

Conventions and the paper's mistakes
------------------------------------
With e = x - x_hat, the printed eq. (11)/(15) "- D E" with E built from (y_a - y_a_hat)
gives e' = (A - L C_a) e + D (tau_r + E): the injection pushes the error away from the
sliding surface and the observer diverges (``sign_convention="printed"`` reproduces it for
tests). The consistent observer is::

    x_hat' = A x_hat + B i_m + D tau_p_hat + L (y_a - C_a x_hat) + D E,
    E = eta F (y_a - C_a x_hat) / (|F (y_a - C_a x_hat)| + epsilon)          (12)

and on the sliding surface the equivalent injection E_eq equals tau_r (+ the friction not
compensated), so tau_r_hat is E low-pass filtered (eq. (17) with the sign of E consistent).

Dry friction tau_p = -beta_s sign(theta_h') is compensated with the measured rate through a
dead zone (Remark 5.2) and a tanh edge (Remark 3.3). While the handlebar sticks, the rider
torque below beta_s is not observable from the motion and the estimate reads tau_r + tau_p.
"""

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numba import njit
from numba.extending import register_jitable
from numpy.typing import NDArray
from scipy.linalg import solve_continuous_lyapunov

from motosim.errors import MotosimError
from motosim.estimation._friction import smooth_sign
from motosim.estimation.kernel import (
    WALCOTT_ZAK,
    EstimatorKernel,
    ObserverInput,
    ObserverState,
    WalcottZakSettings,
    pack,
)
from motosim.model.handlebar import matrices
from motosim.model.linear import zoh
from motosim.params.checks import check_number
from motosim.params.handlebar import HandlebarParameters

__all__ = [
    "OUTPUT_ROWS",
    "ObserverSettings",
    "WalcottZakGains",
    "WalcottZakObserver",
    "design",
    "design_with",
    "invariant_zeros",
    "observer_row",
    "wz_start",
    "wz_step",
]

Array = NDArray[np.float64]

OUTPUT_ROWS: dict[str, tuple[float, float]] = {
    "theta_h": (0.0, 1.0),
    "theta_h_dot": (1.0, 0.0),
}
"""Rows of C_a for each available output, over x = [theta_h', theta_h]."""

_REL_TOL = 1e-9


@dataclass(frozen=True, slots=True)
class WalcottZakGains:
    """Design result of :func:`design`: the observer of eqs. (12)-(17), continuous time.

    Attributes
    ----------
    handlebar : HandlebarParameters
        The nominal model the observer uses.
    outputs : tuple of str
        Names of the outputs y_a, in the order of the rows of ``C``.
    A, B, D : ndarray, shapes (2, 2), (2,), (2,)
        Eq. (10): B per ampere, D per N*m.
    C : ndarray, shape (p, 2)
        C_a of eq. (15).
    L : ndarray, shape (2, p)
        Output-error gain; A - L C_a has the eigenvalues ``poles``.
    Q, P : ndarray, shape (2, 2)
        Eq. (13): (A - L C_a)^T P + P (A - L C_a) + Q = 0, P = P^T > 0.
    F : ndarray, shape (p,)
        Eq. (14): P D = C_a^T F^T (one unknown input, so F is one row).
    poles : tuple of float
        Eigenvalues of A - L C_a [1/s].
    eta : float
        Injection amplitude eta >= rho >= |tau_r| [N*m].
    epsilon : float
        Boundary layer of eq. (12), in the units of F (y_a - y_a_hat).
    filter_time_constant : float
        Time constant of the first-order low-pass on the injection E [s].
    beta_s : float
        Dry friction compensated [N*m]; 0 switches the compensation off.
    dead_zone, friction_width : float
        Dead zone (Remark 5.2) and tanh width (Remark 3.3) on theta_h' [rad/s].
    injection_sign : float
        +1 for the consistent observer, -1 for the literal eq. (11) (diverges).
    """

    handlebar: HandlebarParameters
    outputs: tuple[str, ...]
    A: Array
    B: Array
    D: Array
    C: Array
    L: Array
    Q: Array
    P: Array
    F: Array
    poles: tuple[float, ...]
    eta: float
    epsilon: float
    filter_time_constant: float
    beta_s: float
    dead_zone: float
    friction_width: float
    injection_sign: float

    @property
    def injection_bandwidth(self) -> float:
        """Linear gain of the injection inside the boundary layer, eta D^T P D / epsilon [1/s]."""
        return float(self.eta * (self.D @ self.P @ self.D) / self.epsilon)


def invariant_zeros(A: Array, D: Array, C: Array) -> Array:
    """Invariant zeros of (A, D, C) with one input and p >= 1 outputs, when C D != 0.

    The pencil [[s I - A, -D], [C, 0]] is squared down with (C D)^T, the finite generalised
    eigenvalues of the square pencil are the candidates, and those at which the original
    (tall) pencil keeps full column rank are discarded.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    D : ndarray, shape (n,)
    C : ndarray, shape (p, n)

    Returns
    -------
    ndarray of complex, shape (k,)
        The invariant zeros [1/s].
    """
    from scipy.linalg import eigvals, svdvals

    n = A.shape[0]
    CD = C @ D
    W = CD[None, :]  # (1, p): squares the pencil down to n + 1 rows
    M = np.block([[A, D[:, None]], [W @ C, np.zeros((1, 1))]])
    N = np.block([[np.eye(n), np.zeros((n, 1))], [np.zeros((1, n + 1))]])
    cand = eigvals(M, N)
    cand = cand[np.isfinite(cand)]
    scale = max(1.0, float(np.linalg.norm(A)), float(np.linalg.norm(C)), float(np.linalg.norm(D)))
    zeros = []
    for s in cand:
        pencil = np.block(
            [[s * np.eye(n) - A, -D[:, None]], [C.astype(complex), np.zeros((C.shape[0], 1))]]
        )
        sv = svdvals(pencil)
        if sv[-1] <= 1e-8 * scale * max(1.0, abs(s)):
            zeros.append(s)
    return np.array(zeros, dtype=complex)


@dataclass(frozen=True, slots=True)
class ObserverSettings:
    """The settings of :func:`design` that a design file records; the defaults are ours.

    Attributes
    ----------
    poles : tuple of two floats
        Eigenvalues of A - L C_a [1/s].
    eta : float
        Injection amplitude [N*m].
    injection_bandwidth : float
        eta F D / epsilon, the injection's bandwidth inside its boundary layer [1/s].
    filter_time_constant : float
        Low-pass filter of the equivalent injection [s].
    dead_zone, friction_width : float
        Velocity dead zone (Remark 5.2) and tanh width of the friction compensation [rad/s].
    friction_compensation : bool
        Subtract the nominal dry friction.
    damping_factor, inertia_factor : float
        The beta_eq and J_eq the observer is designed with, as factors of the handlebar's
        (1: the identified handlebar). 0.85 and 1.25 were chosen to keep the closed-loop
        stack's margins over more of the +/-50 % J_eq, beta_eq, +/-30 % N k_t handlebars, on a
        margin reading since corrected: they keep fewer (12 of 27 against 17 at 1 kHz,
        20 m/s; ``scripts/stack_design_study.py``, the design guide).
    """

    poles: tuple[float, float] = (-0.1, -60.0)
    eta: float = 150.0
    injection_bandwidth: float = 800.0
    filter_time_constant: float = 0.01
    dead_zone: float = 0.05
    friction_width: float = 0.05
    friction_compensation: bool = True
    damping_factor: float = 1.0
    inertia_factor: float = 1.0

    def __post_init__(self) -> None:
        for name in ("damping_factor", "inertia_factor"):
            check_number(getattr(self, name), where=name, lower=0.0, lower_closed=False, upper=10.0)

    @classmethod
    def for_step(cls, dt: float, *, friction_compensation: bool = True) -> "ObserverSettings":
        """The defaults with the injection as fast as a sampled loop at ``dt`` [s] allows.

        The injection bandwidth is min(800, 0.8 / dt) [1/s] (see :class:`WalcottZakObserver`).
        """
        _check_positive("dt", dt, "s")
        return cls(
            injection_bandwidth=min(800.0, 0.8 / dt), friction_compensation=friction_compensation
        )


_DEFAULT = ObserverSettings()


def design_with(hb: HandlebarParameters, settings: ObserverSettings) -> "WalcottZakGains":
    """:func:`design` with the recorded ``settings`` (eq. (15) outputs, consistent sign).

    The observer's handlebar is ``hb`` with beta_eq and J_eq scaled by the settings' factors.
    """
    if settings.damping_factor != 1.0 or settings.inertia_factor != 1.0:
        hb = dataclasses.replace(
            hb,
            beta_eq=settings.damping_factor * hb.beta_eq,
            J_eq=settings.inertia_factor * hb.J_eq,
        )
    return design(
        hb,
        poles=settings.poles,
        eta=settings.eta,
        injection_bandwidth=settings.injection_bandwidth,
        filter_time_constant=settings.filter_time_constant,
        dead_zone=settings.dead_zone,
        friction_width=settings.friction_width,
        friction_compensation=settings.friction_compensation,
    )


def design(
    hb: HandlebarParameters,
    *,
    outputs: tuple[str, ...] = ("theta_h", "theta_h_dot"),
    poles: tuple[float, float] = _DEFAULT.poles,
    eta: float = _DEFAULT.eta,
    epsilon: float | None = None,
    injection_bandwidth: float = _DEFAULT.injection_bandwidth,
    state_weight: Array | None = None,
    filter_time_constant: float = _DEFAULT.filter_time_constant,
    friction_compensation: bool = _DEFAULT.friction_compensation,
    dead_zone: float = _DEFAULT.dead_zone,
    friction_width: float = _DEFAULT.friction_width,
    sign_convention: Literal["consistent", "printed"] = "consistent",
) -> WalcottZakGains:
    """Design the Walcott-Zak rider-torque observer for the handlebar ``hb``.

    Parameters
    ----------
    hb : HandlebarParameters
        Nominal handlebar model (eq. (10)).
    outputs : tuple of str
        The outputs y_a, names from :data:`OUTPUT_ROWS`. The default is eq. (15); the angle
        alone is eq. (10) and fails the matching condition.
    poles : tuple of two negative floats
        Eigenvalues of A - L C_a [1/s]. With C_a square, A - L C_a = diag(poles) in the
        coordinates [theta_h' error, theta_h error]. A slow rate pole leaves the rate error to
        the injection and keeps the boundary-layer bias of the torque estimate,
        -poles[0] / (injection bandwidth - poles[0]), small.
    eta : float
        Injection amplitude [N*m]; must exceed the largest rider torque, rho (Remark 3.3:
        70 N*m).
    epsilon : float, optional
        Boundary layer of eq. (12). If omitted it is eta D^T P D / ``injection_bandwidth``.
    injection_bandwidth : float
        Linear gain of the injection inside the boundary layer [1/s], used when ``epsilon``
        is omitted. A sampled observer needs it below about 1/dt (see
        :class:`WalcottZakObserver`).
    state_weight : ndarray, shape (2, 2), optional
        Q of eq. (13), symmetric positive definite; identity by default.
    filter_time_constant : float
        Time constant of the low-pass filter on E giving tau_r_hat [s].
    friction_compensation : bool
        Add tau_p_hat = -beta_s sign(theta_h') with the dead-zoned, smoothed sign.
    dead_zone, friction_width : float
        Dead zone and tanh width on the measured rate for the compensation [rad/s].
    sign_convention : {"consistent", "printed"}
        "printed" uses the injection sign of the printed eq. (11), which diverges; only for
        demonstrating that.

    Returns
    -------
    WalcottZakGains

    Raises
    ------
    MotosimError
        If an option is out of range; if the observer matching condition
        rank(D) = rank(C_a D) fails (e.g. the angle alone, C = [0 1]); if (A, D, C_a) has an
        invariant zero in the closed right half plane or (A, C_a) is not observable; or if no
        F solves P D = C_a^T F^T.

    Notes
    -----
    With C_a square and invertible, L = (A - diag(poles)) C_a^-1, P solves eq. (13) and
    F = D^T P C_a^-1 satisfies eq. (14) exactly.

    References
    ----------
    B. L. Walcott and S. H. Zak, "State observation of nonlinear uncertain dynamical systems",
    IEEE TAC 32(2), 1987. C. Edwards and S. K. Spurgeon, "On the development of discontinuous
    observers", IJC 59(5), 1994.

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> g = design(load_parameters("simacom_handlebar", "handlebar"), poles=(-60.0, -40.0))
    >>> np.round(g.F, 4)
    array([0.    , 0.2008])
    """
    _check_positive("eta", eta, "N*m")
    _check_positive("filter_time_constant", filter_time_constant, "s")
    _check_positive("injection_bandwidth", injection_bandwidth, "1/s")
    for name, value in (("dead_zone", dead_zone), ("friction_width", friction_width)):
        if not (math.isfinite(value) and value >= 0):
            raise MotosimError(f"{name} = {value!r}; expected a finite value >= 0 [rad/s]")
    if sign_convention not in ("consistent", "printed"):
        raise MotosimError(
            f"sign_convention = {sign_convention!r}; expected 'consistent' or 'printed'"
        )
    unknown = [name for name in outputs if name not in OUTPUT_ROWS]
    if unknown or not outputs or len(set(outputs)) != len(outputs):
        raise MotosimError(
            f"outputs = {outputs!r}; expected distinct names among {tuple(OUTPUT_ROWS)}"
        )
    m = matrices(hb)
    A, B, D = m.A, m.B, m.D
    C = np.array([OUTPUT_ROWS[name] for name in outputs])
    n = A.shape[0]

    rank_D = np.linalg.matrix_rank(D[:, None])
    rank_CD = np.linalg.matrix_rank((C @ D)[:, None])
    if rank_CD != rank_D:
        raise MotosimError(
            f"outputs {outputs}: matching condition fails, rank(C D) = {rank_CD} != rank(D) = "
            f"{rank_D}; the rider torque does not act directly on a measured output, "
            "so add the differentiated angle theta_h_dot as an output (eq. (15))"
        )
    zeros = invariant_zeros(A, D, C)
    bad = zeros[zeros.real >= -1e-9]
    if bad.size:
        raise MotosimError(
            f"outputs {outputs}: (A, D, C) has invariant zeros {np.round(bad, 6).tolist()} in the "
            "closed right half plane; expected all in the open left half plane"
        )
    obsv = np.vstack([C @ np.linalg.matrix_power(A, k) for k in range(n)])
    if np.linalg.matrix_rank(obsv) < n:
        raise MotosimError(f"outputs {outputs}: (A, C) is not observable; expected rank {n}")
    if C.shape[0] != n:
        raise MotosimError(
            f"outputs {outputs}: {C.shape[0]} outputs for {n} states; the Lyapunov design "
            "needs C_a square and invertible"
        )

    pole_arr = np.asarray(poles, dtype=float)
    if pole_arr.shape != (n,) or not np.all(np.isfinite(pole_arr)) or np.any(pole_arr >= 0):
        raise MotosimError(f"poles = {poles!r}; expected {n} finite negative reals [1/s]")
    A_L = np.diag(pole_arr)
    C_inv = np.linalg.inv(C)
    L = (A - A_L) @ C_inv

    Q = np.eye(n) if state_weight is None else np.asarray(state_weight, dtype=float)
    if (
        Q.shape != (n, n)
        or not np.all(np.isfinite(Q))
        or not np.allclose(Q, Q.T)
        or np.min(np.linalg.eigvalsh(0.5 * (Q + Q.T))) <= 0
    ):
        raise MotosimError(
            f"state_weight has shape {Q.shape} or is not symmetric positive definite; "
            f"expected ({n}, {n}) symmetric > 0"
        )
    P = solve_continuous_lyapunov(A_L.T, -Q)
    P = 0.5 * (P + P.T)
    F = D @ P @ C_inv  # eq. (14): P D = C_a^T F^T with C_a invertible
    residual = np.linalg.norm(P @ D - C.T @ F)
    if residual > _REL_TOL * max(1.0, float(np.linalg.norm(P @ D))):
        raise MotosimError(
            f"no F solves P D = C_a^T F^T: residual {residual:.3g}; expected < {_REL_TOL:g}"
        )
    if epsilon is None:
        epsilon = float(eta * (D @ P @ D) / injection_bandwidth)
    _check_positive("epsilon", epsilon, "units of F (y_a - y_a_hat)")
    return WalcottZakGains(
        handlebar=hb,
        outputs=tuple(outputs),
        A=A,
        B=B,
        D=D,
        C=C,
        L=L,
        Q=Q,
        P=P,
        F=F,
        poles=tuple(float(p) for p in pole_arr),
        eta=float(eta),
        epsilon=float(epsilon),
        filter_time_constant=float(filter_time_constant),
        beta_s=hb.beta_s if friction_compensation else 0.0,
        dead_zone=float(dead_zone),
        friction_width=float(friction_width),
        injection_sign=1.0 if sign_convention == "consistent" else -1.0,
    )


def _check_positive(name: str, value: float, unit: str) -> None:
    check_number(value, where=name, lower=0.0, lower_closed=False, unit=unit)


@register_jitable
def observer_row(
    Phi: Array,
    Gamma: Array,
    r: int,
    x0: Any,
    x1: Any,
    current: Any,
    rate: Any,
    theta: Any,
    torque: Any,
) -> Any:
    """Row ``r`` (an :class:`~motosim.estimation.kernel.ObserverState`) of the observer's
    update over a sample, Phi x_hat + Gamma [i_m, rate, theta, torque], with x_hat =
    (``x0``, ``x1``): of numbers in :func:`wz_step`, and of the rows of a linear map in the
    loop analysis (:func:`motosim.sim.loop_analysis.stack_loop`), which writes the same
    update in the loop's coordinates."""
    return (
        Phi[r, ObserverState.rate] * x0
        + Phi[r, ObserverState.angle] * x1
        + Gamma[r, ObserverInput.current] * current
        + Gamma[r, ObserverInput.rate] * rate
        + Gamma[r, ObserverInput.angle] * theta
        + Gamma[r, ObserverInput.torque] * torque
    )


@njit(cache=True)
def wz_step(
    state: Array,
    theta: float,
    theta_dot: float,
    current: float,
    Phi: Array,
    Gamma: Array,
    g: Array,
    c: WalcottZakSettings,
) -> float:
    """One sample of the Walcott-Zak observer, exactly discretised (ZOH) at its step.

    Parameters
    ----------
    state : ndarray, shape (4,)
        The observer's state (:class:`~motosim.estimation.kernel.ObserverState`), advanced
        to the next sample in place; its ``estimate`` is then the rider-torque estimate at
        this sample.
    theta, theta_dot : float
        Measured angle [rad] and differentiated rate [rad/s] at this sample.
    current : float
        Motor current i_m, held over the step [A].
    Phi : ndarray, shape (2, 2)
        exp((A - L C_a) h).
    Gamma : ndarray, shape (2, 4)
        int_0^h exp((A - L C_a) s) ds [B, L C_a, D]: columns for i_m, the measured rate and
        angle (held), and the torque input of D
        (:class:`~motosim.estimation.kernel.ObserverInput`).
    g : ndarray, shape (2,)
        F C_a, so that F (y_a - y_a_hat) = g . ([theta_dot, theta] - x_hat).
    c : WalcottZakSettings
        The injection, the friction compensation, the filter and the rate extrapolation:
        the rate used is theta_dot + w (theta_dot - previous theta_dot); w = 1/2 turns a
        backward difference, the mean rate over the last step, into an estimate at the
        sample.

    Returns
    -------
    float
        Rider-torque estimate at this sample [N*m] (the state's ``estimate`` after the step).

    Notes
    -----
    Over the step the observer integrates eq. (15) with the consistent sign,
    x_hat' = (A - L C_a) x_hat + B i_m + L y_a + D (tau_p_hat + E), with y_a, i_m, E and
    tau_p_hat held.

    While the handlebar sticks, N k_t i_m + tau_r + tau_p = 0 with any dry friction
    |tau_p| <= beta_s: the rider's torque is only known to lie in
    [-N k_t i_m - beta_s, -N k_t i_m + beta_s]. A dead-zoned compensation (tau_p_hat = 0)
    picks the middle, -N k_t i_m, so a held handlebar reads every change of the motor
    current as rider torque, and a loop that cancels the estimate with the motor integrates
    its own current (the stick-slip hunting of a torque-feedback handlebar). With the stick
    projection on, the friction estimate takes, within its bounds, the value that keeps the
    rider's torque at its last estimate: tau_p_hat = clip(-(N k_t i_m + tau_r_hat), +-beta_s),
    blended with the sliding friction -beta_s sign(theta_h') by the smoothed sign's
    magnitude m, tau_p_hat = -m beta_s sign(theta_h') + (1 - m) clip(...), continuous in the
    rate. The estimate then stays where it was while the stuck handlebar is consistent with
    it, and moves by what friction cannot explain.
    """
    beta_s = c.beta_s
    x0, x1 = state[ObserverState.rate], state[ObserverState.angle]
    rate = theta_dot + c.rate_weight * (theta_dot - state[ObserverState.previous_rate])
    s = g[0] * (rate - x0) + g[1] * (theta - x1)  # F (y_a - y_a_hat)
    E = c.sign * c.eta * s / (abs(s) + c.epsilon)  # eq. (12), injected as + sign D E
    slide = smooth_sign(theta_dot, c.dead_zone, c.friction_width)
    tau_p_hat = -beta_s * slide
    if c.stick_projection and beta_s > 0.0:  # stick: friction holds what the estimate does not
        held = -(c.torque_per_amp * current + state[ObserverState.estimate])
        tau_p_hat += (1.0 - abs(slide)) * min(max(held, -beta_s), beta_s)
    torque = tau_p_hat + E
    for r in (ObserverState.rate, ObserverState.angle):
        state[r] = observer_row(Phi, Gamma, r, x0, x1, current, rate, theta, torque)
    estimate = state[ObserverState.estimate] + c.filter_alpha * (E - state[ObserverState.estimate])
    state[ObserverState.estimate] = estimate
    state[ObserverState.previous_rate] = theta_dot
    return float(estimate)


@njit(cache=True)
def wz_start(state: Array, theta: float, theta_dot: float, current: float) -> None:
    """Start the observer state at the first sample: x_hat = [theta_dot, theta], no torque.

    ``state`` (4,) is written in place; ``current`` [A] is not needed by this observer.
    """
    state[ObserverState.rate] = theta_dot
    state[ObserverState.angle] = theta
    state[ObserverState.estimate] = 0.0
    state[ObserverState.previous_rate] = theta_dot


class WalcottZakObserver:
    """Stepper: the rider-torque observer of :func:`design` sampled at the step ``dt``.

    Parameters
    ----------
    gains : WalcottZakGains
        From :func:`design`.
    dt : float
        Sampling step h [s]. The linear part x_hat' = (A - L C_a) x_hat + ... is discretised
        exactly (ZOH, matrix exponential); the measurements, the injection and the friction
        compensation are held over the step.
    rate_measurement : {"backward_difference", "instantaneous"}
        What the rate input is. The implicit super-twisting differentiator returns, once
        converged, the backward difference (theta_k - theta_{k-1}) / h, the mean rate over
        the last step, which lags the rate at the sample by h/2; through eq. (15) that lag
        would read as a torque error of about beta_eq (h/2) theta_h''. With
        "backward_difference" the observer extrapolates it by half a step,
        theta_dot + (theta_dot - previous theta_dot) / 2; "instantaneous" uses it as is.
    stick_projection : bool
        While the handlebar sticks, let the dry friction hold what keeps the rider-torque
        estimate at its last value, within +-beta_s (see :func:`wz_step`); False gives the
        plain dead-zoned compensation of Remark 5.2.

    Raises
    ------
    MotosimError
        If ``dt`` is not positive, or if, with the consistent sign, the sampled injection
        loop is unstable: the error map linearised inside the boundary layer,
        exp((A - L C_a) h) - Gamma_D (eta / epsilon) F C_a, must have a spectral radius below
        1 (raise epsilon or lower ``injection_bandwidth``).

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> hb = load_parameters("simacom_handlebar", "handlebar")
    >>> obs = WalcottZakObserver(design(hb), 1e-3)
    >>> x_hat, tau_hat = obs.step(0.0, 0.0, 0.0)
    >>> tau_hat
    0.0
    """

    def __init__(
        self,
        gains: WalcottZakGains,
        dt: float,
        *,
        rate_measurement: Literal["backward_difference", "instantaneous"] = "backward_difference",
        stick_projection: bool = True,
    ) -> None:
        _check_positive("dt", dt, "s")
        if rate_measurement not in ("backward_difference", "instantaneous"):
            raise MotosimError(
                f"rate_measurement = {rate_measurement!r}; expected 'backward_difference' "
                "or 'instantaneous'"
            )
        self.gains = gains
        self.dt = h = float(dt)
        K = gains.L @ gains.C
        Phi, Gamma = zoh(gains.A - K, np.column_stack([gains.B, K, gains.D]), h)
        self._Phi = np.ascontiguousarray(Phi)
        self._Gamma = np.ascontiguousarray(Gamma)
        self._g = gains.F @ gains.C
        gain = gains.injection_sign * gains.eta / gains.epsilon
        error_map = Phi - gain * np.outer(Gamma[:, ObserverInput.torque], self._g)
        self.error_map_radius = float(np.max(np.abs(np.linalg.eigvals(error_map))))
        """Spectral radius of the sampled error map inside the boundary layer."""
        if gains.injection_sign > 0 and self.error_map_radius >= 1.0:
            raise MotosimError(
                f"dt = {dt:g} s: the sampled injection loop is unstable (spectral radius "
                f"{self.error_map_radius:.3g} >= 1); raise epsilon or lower the injection "
                f"bandwidth ({gains.injection_bandwidth:.4g} 1/s) below about 1/dt"
            )
        self._settings = WalcottZakSettings(
            eta=gains.eta,
            epsilon=gains.epsilon,
            sign=gains.injection_sign,
            beta_s=gains.beta_s,
            dead_zone=gains.dead_zone,
            friction_width=gains.friction_width,
            filter_alpha=-math.expm1(-h / gains.filter_time_constant),
            rate_weight=0.5 if rate_measurement == "backward_difference" else 0.0,
            torque_per_amp=gains.handlebar.torque_per_amp,
            stick_projection=bool(stick_projection),
        )
        self.reset()

    @property
    def kernel(self) -> EstimatorKernel:
        """The compiled kernel's record (:func:`wz_step`, gain F C_a), for compiled loops."""
        return pack(WALCOTT_ZAK, self._Phi, self._Gamma, self._g, self._settings, self.dt)

    def reset(self) -> None:
        """Return to the initial state: the next sample initialises x_hat; tau_r_hat = 0."""
        self._state: Array | None = None

    def step(self, theta_h: float, theta_h_dot: float, i_m: float) -> tuple[Array, float]:
        """Take one sample and return the estimates at this instant.

        Parameters
        ----------
        theta_h : float
            Measured handlebar angle [rad].
        theta_h_dot : float
            Differentiated handlebar rate, e.g. from a
            :class:`~motosim.estimation.differentiator.SuperTwistingDifferentiator` [rad/s].
        i_m : float
            Motor current, held until the next sample [A].

        Returns
        -------
        x_hat : ndarray, shape (2,)
            [theta_h'_hat, theta_h_hat] [rad/s, rad]; the first sample after :meth:`reset`
            starts the state at the measurements.
        tau_r_hat : float
            Rider-torque estimate [N*m].
        """
        state = self._state
        if state is None:
            state = self._state = np.zeros(4)
            wz_start(state, float(theta_h), float(theta_h_dot), float(i_m))
        x_hat = state[: ObserverState.estimate].copy()
        args = (float(theta_h), float(theta_h_dot), float(i_m))
        tau = wz_step(state, *args, self._Phi, self._Gamma, self._g, self._settings)
        return x_hat, float(tau)
