"""The handlebar's torque-feedback loop (section IV, eqs. (18)-(26)): design and analysis.

The handlebar follows the virtual steer angle delta while the rider pushes on it: with the
tracking error e = theta_h - delta and the paper's positive feedback, i_m = K e, so

    theta_h = -G_h K / (1 - G_h K) delta + G_w / (1 - G_h K) w,    w = tau_r + tau_p,

with G_h = N k_t / (J_eq s^2 + beta_eq s) (current to angle) and G_w = G_h / (N k_t).

Loop shaping (Glover & McFarlane): the pre-compensator W1 = k (s + omega_i) / s gives the
shaped plant G_s = G_h W1 a crossover at the chosen tracking bandwidth omega_c
(|G_s(j omega_c)| = 1) and integral action below omega_i = omega_c / 10, so the handlebar
returns exactly to delta whatever constant torque the rider applies; W2 = 1 (a single,
clean angle measurement). A controller K_s of fixed order is tuned on G_s for the four-block
objective of eq. (25) (HIFOO-like), beside the full-order optimum gamma_min; the implemented
controller is K = W1 K_s W2. The default bandwidth (:func:`default_bandwidth`) is 10 Hz, which
follows the weave (up to 3.5 Hz) closely and is a decade under the 1 kHz control rate, or a
fifth of a slower rate; from :data:`STIFF_RATE`, a handlebar whose loop would be softer at
1 Hz than the packaged handlebar's gets a higher one (:func:`handlebar_bandwidth`).
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import expm
from scipy.signal import cont2discrete, ss2tf

from motosim.choices import INTEGRAL_CORNER, MAX_ORDER
from motosim.control.fixed_order import FixedOrderResult, fixed_order_synthesis
from motosim.control.loops import closed_loop_poles, four_block_norm
from motosim.control.ncf import ncfsyn
from motosim.control.statespace import StateSpace, frequency_response
from motosim.errors import MotosimError
from motosim.model.handlebar import matrices, perturbed
from motosim.params.handlebar import HandlebarParameters

__all__ = [
    "DEFAULT_BANDWIDTH",
    "INTEGRAL_CORNER",
    "MAX_COMPLIANCE",
    "MAX_ORDER",
    "PAPER_CONTROLLER",
    "PAPER_DEN",
    "PAPER_NUM",
    "STIFF_RATE",
    "LoopAnalysis",
    "TorqueFeedbackDesign",
    "analyse_loop",
    "check_options",
    "default_bandwidth",
    "design_torque_feedback",
    "discretize",
    "handlebar_bandwidth",
    "handlebar_plants",
    "series",
    "synthesize_controller",
]

Array = NDArray[np.float64]

DEFAULT_BANDWIDTH = 10.0
"""Tracking bandwidth at control rates of 50 Hz and above [Hz]."""
MAX_COMPLIANCE = 0.88e-3
"""The most compliance at 1 Hz, |theta_h / w| for a 1 Hz rider torque, that a default design
keeps from :data:`STIFF_RATE` [rad/(N*m)]: the default design's for the packaged handlebar
(Table I; 10 Hz, order 1, integral corner 0.1: 0.879 mrad/(N*m)), on which the training
scenarios meet the tracking target (:func:`handlebar_bandwidth`)."""
STIFF_RATE = 1000.0
"""Lowest control rate at which :func:`handlebar_bandwidth` raises the bandwidth for a soft
loop [Hz]: at 100 Hz the lighter handlebar's stack designed at 13.6 Hz keeps 5.7 dB and
47 deg (7.6 dB and 57 deg at 10 Hz)."""
PAPER_NUM = (-2.355, -613.7)
"""Numerator of eq. (26), highest power first [A/rad]."""
PAPER_DEN = (1.0, 1445.0)
"""Denominator of eq. (26), highest power first."""
PAPER_CONTROLLER = StateSpace(
    np.array([[-PAPER_DEN[1]]]),
    np.array([[1.0]]),
    np.array([[PAPER_NUM[1] - PAPER_NUM[0] * PAPER_DEN[1]]]),
    np.array([[PAPER_NUM[0]]]),
)
"""Eq. (26): K(s) = (-2.355 s - 613.7) / (s + 1445) [A/rad], positive feedback."""


def handlebar_plants(hb: HandlebarParameters) -> tuple[StateSpace, StateSpace]:
    """G_h (i_m [A] to theta_h [rad]) and G_w (torque [N*m] to theta_h), eqs. (18)-(19).

    States [theta_h', theta_h] as in eq. (10).
    """
    m = matrices(hb)
    C, D = m.C[None, :], np.zeros((1, 1))
    return StateSpace(m.A, m.B[:, None], C, D), StateSpace(m.A, m.D[:, None], C, D)


def series(first: StateSpace, second: StateSpace) -> StateSpace:
    """The cascade ``second(first(u))``, states [x_first; x_second]."""
    n1 = first.n_states
    A = np.block(
        [
            [first.A, np.zeros((n1, second.n_states))],
            [second.B @ first.C, second.A],
        ]
    )
    B = np.vstack([first.B, second.B @ first.D])
    C = np.hstack([second.D @ first.C, second.C])
    return StateSpace(A, B, C, second.D @ first.D)


def _weight(gain: float, corner: float) -> StateSpace:
    """W1 = gain (s + corner) / s."""
    return StateSpace(
        np.zeros((1, 1)), np.array([[1.0]]), np.array([[gain * corner]]), np.array([[gain]])
    )


def discretize(system: StateSpace, dt: float, method: str) -> StateSpace:
    """Discrete-time matrices of ``system`` at the step ``dt`` [s], ``"zoh"`` or ``"tustin"``."""
    if method not in ("zoh", "tustin"):
        raise MotosimError(f"method = {method!r}; expected 'zoh' or 'tustin'")
    if system.is_discrete:
        raise MotosimError(f"the system is already discrete (dt = {system.dt:g} s)")
    Ad, Bd, Cd, Dd, _ = cont2discrete(
        (system.A, system.B, system.C, system.D),
        dt,
        method="bilinear" if method == "tustin" else "zoh",
    )
    return StateSpace(Ad, Bd, Cd, Dd, dt=float(dt))


def _discrete_loop_radius(
    plant: StateSpace, controller: StateSpace, dt: float, method: str
) -> float:
    """Spectral radius of the sampled loop: plant held (ZOH), controller discretised."""
    n = plant.n_states
    phi = expm(np.block([[plant.A, plant.B], [np.zeros((1, n + 1))]]) * dt)
    Ap, Bp, Cp = phi[:n, :n], phi[:n, n:], plant.C
    k = discretize(controller, dt, method)
    # u_k = C_k x_k + D_k y_k, y_k = C_p x_p (the plant has no feedthrough)
    A = np.block(
        [
            [Ap + Bp @ k.D @ Cp, Bp @ k.C],
            [k.B @ Cp, k.A],
        ]
    )
    return float(np.max(np.abs(np.linalg.eigvals(A))))


@dataclass(frozen=True, slots=True)
class LoopAnalysis:
    """How a controller does on the handlebar loop.

    Attributes
    ----------
    four_block_gamma : float
        Four-block norm of eq. (25) with the unshaped plant G_h (W = 1).
    closed_loop_poles : ndarray of complex
        Poles of the loop [1/s].
    gain_margin_db, phase_margin_deg, crossover : float
        Margins of the loop gain -G_h K at its crossover [rad/s].
    tracking_bandwidth : float
        -3 dB frequency of theta_h / delta [Hz].
    stiffness : float
        Static rider-torque stiffness |K(0)| N k_t [N*m/rad] (inf with integral action).
    peak_compliance : float
        Largest |theta_h / w| over frequency [rad/(N*m)].
    tracking_error_1hz : float
        |theta_h - delta| / |delta| for a 1 Hz steer angle, |S(j 2 pi)|.
    compliance_1hz : float
        |theta_h / w| for a 1 Hz rider torque [rad/(N*m)].
    discrete_radius : dict of str to float
        Spectral radius of the sampled loop for ``zoh`` and ``tustin`` controllers (< 1 is
        stable).
    robust_over_50_percent : bool
        Closed loop stable for every J_eq and beta_eq between half and 1.5 times nominal.
    worst_perturbed_gamma : float
        Largest four-block norm over that grid.
    """

    four_block_gamma: float
    closed_loop_poles: NDArray[np.complex128]
    gain_margin_db: float
    phase_margin_deg: float
    crossover: float
    tracking_bandwidth: float
    stiffness: float
    peak_compliance: float
    tracking_error_1hz: float
    compliance_1hz: float
    discrete_radius: dict[str, float]
    robust_over_50_percent: bool
    worst_perturbed_gamma: float


def _sensitivity_1hz(G_h: StateSpace, controller: StateSpace) -> complex:
    """1 / (1 - G_h K) at 1 Hz: theta_h - delta over delta, and over G_w w."""
    one_hz = 2 * math.pi
    loop = frequency_response(G_h, one_hz)[0, 0] * frequency_response(controller, one_hz)[0, 0]
    return complex(1.0 / (1.0 - loop))


def _compliance_1hz(hb: HandlebarParameters, controller: StateSpace) -> float:
    """|theta_h / w| for a 1 Hz rider torque w on ``hb`` held by ``controller`` [rad/(N*m)]."""
    G_h, G_w = handlebar_plants(hb)
    g_w = frequency_response(G_w, 2 * math.pi)[0, 0]
    return float(abs(g_w * _sensitivity_1hz(G_h, controller)))


def analyse_loop(hb: HandlebarParameters, controller: StateSpace, *, rate: float) -> LoopAnalysis:
    """Margins, tracking, rider-torque rejection, sampling and robustness of a controller.

    Parameters
    ----------
    hb : HandlebarParameters
        Nominal handlebar.
    controller : StateSpace
        K, positive feedback i_m = K (theta_h - delta) [A/rad].
    rate : float
        Control rate [Hz] for the sampled-loop check.

    Returns
    -------
    LoopAnalysis
    """
    G_h, G_w = handlebar_plants(hb)
    omega = np.logspace(-2, 5, 3000)
    loop = np.array(
        [-frequency_response(G_h, w)[0, 0] * frequency_response(controller, w)[0, 0] for w in omega]
    )
    gw = np.array([frequency_response(G_w, w)[0, 0] for w in omega])
    sens = 1.0 / (1.0 - (-loop))  # 1 / (1 - G K) with L = -G K
    track = np.abs(loop * sens)
    compliance = np.abs(gw * sens)
    mag = np.abs(loop)
    above = np.flatnonzero(mag >= 1.0)
    crossover = math.nan
    phase_margin = math.inf
    if above.size and above[-1] + 1 < omega.size:
        k = above[-1]
        crossover = float(omega[k])
        phase_margin = float(180.0 + np.degrees(np.angle(loop[k])))
    phase = np.unwrap(np.angle(loop))
    crossings = np.flatnonzero(np.diff(np.sign(phase + np.pi)) != 0)
    gain_margin = math.inf
    if crossings.size:
        gain_margin = float(-20 * np.log10(mag[crossings].max()))
    low = track >= track[0] / math.sqrt(2.0)
    bandwidth = float(omega[np.argmin(low)] / (2 * math.pi)) if not np.all(low) else math.inf
    s_1hz = _sensitivity_1hz(G_h, controller)
    if (
        abs(np.linalg.det(controller.A))
        < 1e-12 * max(1.0, np.abs(controller.A).max()) ** controller.n_states
    ):
        stiffness = math.inf  # a pole at the origin: integral action
    else:
        k0 = controller.D - controller.C @ np.linalg.solve(controller.A, controller.B)
        stiffness = float(abs(k0[0, 0]) * hb.torque_per_amp)
    poles = closed_loop_poles(G_h, controller)
    gammas = []
    stable = True
    for fj in (0.5, 1.0, 1.5):
        for fb in (0.5, 1.0, 1.5):
            G, _ = handlebar_plants(perturbed(hb, inertia_factor=fj, damping_factor=fb))
            gamma = four_block_norm(G, controller)
            stable &= math.isfinite(gamma)
            gammas.append(gamma)
    dt = 1.0 / rate
    return LoopAnalysis(
        four_block_gamma=four_block_norm(G_h, controller),
        closed_loop_poles=poles,
        gain_margin_db=gain_margin,
        phase_margin_deg=phase_margin,
        crossover=crossover,
        tracking_bandwidth=bandwidth,
        stiffness=stiffness,
        peak_compliance=float(compliance.max()),
        tracking_error_1hz=float(abs(s_1hz)),
        compliance_1hz=float(abs(frequency_response(G_w, 2 * math.pi)[0, 0] * s_1hz)),
        discrete_radius={
            m: _discrete_loop_radius(G_h, controller, dt, m) for m in ("zoh", "tustin")
        },
        robust_over_50_percent=bool(stable),
        worst_perturbed_gamma=float(max(gammas)),
    )


def default_bandwidth(rate: float) -> float:
    """The default tracking bandwidth at a control rate [Hz].

    :data:`DEFAULT_BANDWIDTH` (10 Hz), or a fifth of ``rate`` if less (the most
    :func:`check_options` admits). The rule comes from the whole sampled stack's margins at
    the motor current (:func:`motosim.sim.loop_analysis.analyse_stack`: observer,
    differentiator, feedforward and motorcycle inside; 20 m/s): 10 Hz keeps the most at every
    rate tried, 25.0 dB and 76 deg at 1 kHz, 12.8 dB and 65 deg at 200 Hz, 10.7 dB and
    56 deg at 150 Hz, 8.0 dB and 47 deg at 120 Hz, 5.5 dB and 37 deg at 100 Hz (20 Hz:
    12.5/52, 7.7/44, 4.1/37, 1.3 dB and 33 deg), 2.7 dB and 23 deg at 80 Hz (16 Hz is
    unstable there). Below about 120 Hz the rider-torque estimate's gain above 1 (2 near 16 Hz
    at 100 Hz), fed back by the cancellation, leaves less than 6 dB and 45 deg.

    Parameters
    ----------
    rate : float
        Control (measurement) rate [Hz].

    Returns
    -------
    float
        [Hz].
    """
    if not (math.isfinite(rate) and rate > 0):
        raise MotosimError(f"rate = {rate!r}; expected a control rate > 0 [Hz]")
    return min(DEFAULT_BANDWIDTH, rate / 5.0)


def handlebar_bandwidth(
    hb: HandlebarParameters,
    *,
    rate: float,
    n_starts: int = 8,
    seed: int = 0,
) -> tuple[float, StateSpace]:
    """The default tracking bandwidth for a handlebar at a control rate, and K designed there.

    :func:`default_bandwidth` of ``rate``; from :data:`STIFF_RATE`, if the default controller
    (order 1, :data:`INTEGRAL_CORNER`) designed there leaves the loop more than 1 % softer at
    1 Hz than :data:`MAX_COMPLIANCE`, the bandwidth at which it is that stiff (within 1 %), at
    most twice the default. The bandwidth is the handlebar's: a scenario's or a design's other
    order or integral corner is then designed at it.

    The tracking error is the rider-torque estimate's error through the loop's compliance,
    and that error [N*m] does not shrink with the handlebar (its lag times the rider's torque
    rate, and the dry friction the observer cannot tell from the rider's torque in slow
    motion: 3.1 % of the peak rider torque on the lane change with a handlebar of two thirds
    of Table I's J_eq, beta_eq and beta_s, 3.7 % on Table I's), while a 10 Hz crossover makes
    the loop as stiff as the handlebar's impedance there: 1.37 mrad/(N*m) at 1 Hz on that
    handlebar against 0.88 on Table I's, and 5.3 % of the peak steer angle of tracking error
    against 4.0 %; at 13.3 Hz, as stiff as Table I's, 3.5 % (the simulate guide, "Unseen
    checks"). Twice the default bounds the raise where the packaged handlebar's stack was
    measured (at 1 kHz, 20 Hz keeps 12.5 dB and 52 deg).

    Parameters
    ----------
    hb : HandlebarParameters
        Nominal handlebar.
    rate : float
        Control rate [Hz].
    n_starts : int
        Starts of each design's search.
    seed : int
        Seed of the starts of each design (``numpy.random.default_rng(seed)``).

    Returns
    -------
    bandwidth : float
        [Hz].
    controller : StateSpace
        :func:`synthesize_controller` at that bandwidth, order 1, :data:`INTEGRAL_CORNER`
        [A/rad].

    Raises
    ------
    MotosimError
        On a rate out of range, or if no stabilising controller is found.
    """

    def synthesis(bw: float) -> tuple[StateSpace, float]:
        K = synthesize_controller(
            hb, rng=np.random.default_rng(seed), bandwidth=bw, rate=rate, n_starts=n_starts
        )
        return K, math.log(_compliance_1hz(hb, K) / MAX_COMPLIANCE)

    bandwidth = default_bandwidth(rate)
    controller, excess = synthesis(bandwidth)
    if rate < STIFF_RATE or excess <= math.log(1.01):
        return bandwidth, controller
    highest = min(2.0 * bandwidth, rate / 5.0)
    # d log compliance / d log bandwidth, about (Table I's: 0.88 mrad/(N*m) at 10 Hz, 0.67 at 12)
    slope = -1.5
    for _ in range(8):
        trial = min(highest, bandwidth * math.exp(-excess / slope))
        if trial == bandwidth:
            break
        K, new = synthesis(trial)
        if new != excess:
            slope = min(-0.1, (new - excess) / math.log(trial / bandwidth))
        bandwidth, controller, excess = trial, K, new
        if abs(excess) <= math.log(1.01):
            break
    return bandwidth, controller


def check_options(
    *, bandwidth: float, rate: float, integral_corner: float = INTEGRAL_CORNER
) -> None:
    """Raise :class:`MotosimError` unless 0 < bandwidth <= rate / 5 [Hz], rate > 0 [Hz] and
    1e-6 <= integral_corner <= 0.5."""
    if not (math.isfinite(rate) and rate > 0):
        raise MotosimError(f"rate = {rate!r}; expected a control rate > 0 [Hz]")
    if not (math.isfinite(bandwidth) and 0 < bandwidth <= rate / 5):
        raise MotosimError(
            f"bandwidth = {bandwidth!r} Hz; expected > 0 and at most a fifth of the "
            f"{rate:g} Hz control rate"
        )
    # 1e-6, as a scenario's positive values: 1e-300 reached the search as a singular weight
    if not (math.isfinite(integral_corner) and 1e-6 <= integral_corner <= 0.5):
        raise MotosimError(
            f"integral_corner = {integral_corner!r}; expected a fraction of the bandwidth "
            "from 1e-06 to 0.5"
        )


@dataclass(frozen=True, slots=True)
class TorqueFeedbackDesign:
    """A torque-feedback controller for the handlebar and how it was obtained.

    Attributes
    ----------
    bandwidth : float
        Requested tracking bandwidth (loop crossover of the shaped plant) [Hz].
    weight_gain, weight_corner : float
        W1 = weight_gain (s + weight_corner) / s [A/rad, rad/s].
    order : int
        Order of the tuned K_s.
    gamma : float
        Four-block norm of eq. (25) achieved by K_s on G_s.
    gamma_min : float
        Full-order optimum on the same G_s (Glover-McFarlane).
    shaped_controller : StateSpace
        K_s.
    controller : StateSpace
        The implemented K = W1 K_s [A/rad], positive feedback i_m = K (theta_h - delta).
    num, den : ndarray
        K as a ratio of polynomials in s, highest power first.
    rate : float
        Control rate [Hz].
    controller_zoh, controller_tustin : StateSpace
        K discretised at the control rate.
    analysis : LoopAnalysis
        Margins, tracking, rejection, sampling and robustness.
    """

    bandwidth: float
    weight_gain: float
    weight_corner: float
    order: int
    gamma: float
    gamma_min: float
    shaped_controller: StateSpace
    controller: StateSpace
    num: Array
    den: Array
    rate: float
    controller_zoh: StateSpace
    controller_tustin: StateSpace
    analysis: LoopAnalysis


def _shaped_synthesis(
    hb: HandlebarParameters,
    *,
    rng: np.random.Generator,
    bandwidth: float,
    order: int,
    n_starts: int,
    integral_corner: float,
) -> tuple[float, float, StateSpace, FixedOrderResult]:
    """W1's gain and corner [rad/s], the shaped plant G_s = G_h W1 and K_s tuned on it."""
    G_h, _ = handlebar_plants(hb)
    omega_c = 2 * math.pi * bandwidth
    corner = omega_c * integral_corner
    unit = abs(frequency_response(series(_weight(1.0, corner), G_h), omega_c)[0, 0])
    gain = 1.0 / unit
    G_s = series(_weight(gain, corner), G_h)
    tuned = fixed_order_synthesis(G_s.A, G_s.B, G_s.C, G_s.D, order, rng=rng, n_starts=n_starts)
    if not tuned.is_stable:
        raise MotosimError(f"no stabilising controller of order {order} was found; try order + 1")
    return gain, corner, G_s, tuned


def synthesize_controller(
    hb: HandlebarParameters,
    *,
    rng: np.random.Generator,
    bandwidth: float | None = None,
    order: int = 1,
    rate: float = 1000.0,
    n_starts: int = 8,
    integral_corner: float = INTEGRAL_CORNER,
) -> StateSpace:
    """The controller K = W1 K_s of :func:`design_torque_feedback`, without its analysis.

    What a simulation needs: the same synthesis (same ``rng``, same K) without the full-order
    optimum, the margins and the robustness grid. Parameters as for
    :func:`design_torque_feedback`.

    Returns
    -------
    StateSpace
        Continuous controller K [A/rad], positive feedback.
    """
    if bandwidth is None:
        bandwidth = default_bandwidth(rate)
    check_options(bandwidth=bandwidth, rate=rate, integral_corner=integral_corner)
    gain, corner, _, tuned = _shaped_synthesis(
        hb,
        rng=rng,
        bandwidth=bandwidth,
        order=order,
        n_starts=n_starts,
        integral_corner=integral_corner,
    )
    return series(tuned.controller, _weight(gain, corner))


def design_torque_feedback(
    hb: HandlebarParameters,
    *,
    rng: np.random.Generator,
    bandwidth: float | None = None,
    order: int = 1,
    rate: float = 1000.0,
    n_starts: int = 8,
    integral_corner: float = INTEGRAL_CORNER,
) -> TorqueFeedbackDesign:
    """Design the handlebar's torque-feedback controller by loop shaping and fixed order.

    Parameters
    ----------
    hb : HandlebarParameters
        Nominal handlebar (packaged or identified).
    rng : numpy.random.Generator
        Random starts of the fixed-order search.
    bandwidth : float, optional
        Tracking bandwidth, the crossover of the shaped loop [Hz]; below a fifth of the
        control rate. By default :func:`default_bandwidth` of ``rate``.
    order : int
        Order of K_s (the implemented K has one more state, W1's integrator).
    rate : float
        Control rate [Hz].
    n_starts : int
        Starts of the fixed-order search.
    integral_corner : float
        W1's corner as a fraction of the bandwidth, from 1e-6 to 0.5: W1 = gain (s + corner) / s
        with corner = 2 pi ``bandwidth`` ``integral_corner`` [rad/s]. Above the default 0.1
        the loop gains stiffness below the bandwidth (the tracking error from the rider
        torque's estimate) and loses phase at the crossover.

    Returns
    -------
    TorqueFeedbackDesign

    Raises
    ------
    MotosimError
        On a bandwidth or rate out of range, or if no stabilising controller is found.
    """
    if bandwidth is None:
        bandwidth = default_bandwidth(rate)
    check_options(bandwidth=bandwidth, rate=rate, integral_corner=integral_corner)
    gain, corner, G_s, tuned = _shaped_synthesis(
        hb,
        rng=rng,
        bandwidth=bandwidth,
        order=order,
        n_starts=n_starts,
        integral_corner=integral_corner,
    )
    full = ncfsyn(G_s.A, G_s.B, G_s.C, G_s.D)
    K = series(tuned.controller, _weight(gain, corner))
    num, den = ss2tf(K.A, K.B, K.C, K.D)
    return TorqueFeedbackDesign(
        bandwidth=float(bandwidth),
        weight_gain=float(gain),
        weight_corner=float(corner),
        order=order,
        gamma=float(tuned.gamma),
        gamma_min=float(full.gamma_min),
        shaped_controller=tuned.controller,
        controller=K,
        num=np.atleast_1d(np.squeeze(num)),
        den=np.asarray(den, dtype=float),
        rate=float(rate),
        controller_zoh=discretize(K, 1.0 / rate, "zoh"),
        controller_tustin=discretize(K, 1.0 / rate, "tustin"),
        analysis=analyse_loop(hb, K, rate=rate),
    )
