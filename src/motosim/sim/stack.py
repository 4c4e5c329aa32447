"""The riding simulator's software stack (Fig. 7): a designed model, its data, and one step.

The stack is what runs on the simulator's computer. Each sample it takes the measured
handlebar angle, commands the motor current that makes the handlebar follow the virtual
motorcycle's steer angle, differentiates the angle, estimates the rider's torque and drives
the virtual motorcycle with that estimate. As in MuJoCo, it is split in two:

- :class:`StackModel`, everything designed, built once by the pure function
  :func:`design_stack`: the estimator's discrete kernel record, the differentiator's gains,
  the discrete controller, the motorcycle's speed-scheduled matrices, the limits and rates;
- :class:`StackData`, every state that changes in a run, made by :func:`new_data`.

:func:`reset` starts the data at a first measurement and :func:`step` advances the whole
stack by one control period and returns the motor current command. The offline simulator
(:mod:`motosim.sim.closed_loop`), the real-time loop and a campaign call exactly these two
functions; they are plain numeric code compiled with numba (``NUMBA_DISABLE_JIT=1`` runs them
as Python). Both records are named tuples so that compiled code takes them as they are.
"""

import math
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from motosim.control.statespace import StateSpace
from motosim.control.torque_feedback import discretize
from motosim.errors import MotosimError
from motosim.estimation.differentiator import LAMBDA_0, LAMBDA_1, std_step
from motosim.estimation.kernel import WALCOTT_ZAK, EstimatorKernel
from motosim.estimation.registry import start_kernel, step_kernel
from motosim.model import sharp as sharp_model
from motosim.model.handlebar import matrices as handlebar_matrices
from motosim.model.linear import zoh
from motosim.model.sharp import bike_rk4
from motosim.params.handlebar import HandlebarParameters
from motosim.params.sharp import SharpParameters, derived_geometry

__all__ = [
    "DELAY_FRICTION_WIDTH",
    "PREDICTION_CORNER",
    "PREDICTION_NOTCH",
    "PREDICTION_PAPER_RATE",
    "PREDICTION_RATE",
    "StackData",
    "StackModel",
    "account_for_delay",
    "default_prediction",
    "design_stack",
    "new_data",
    "reset",
    "step",
    "step_scaled",
]

Array = NDArray[np.float64]

MOTORCYCLE_STEP = 1e-3
"""Largest RK4 step of the virtual motorcycle inside a stack period [s]."""
FEEDFORWARD_FRICTION_WIDTH = 0.002
"""Rate scale of the tanh in the reference feedforward's dry-friction term [rad/s].

The term follows the motorcycle's steer rate, a noise-free model state, so it can be much
narrower than the observer's compensation, which reads a quantised, differentiated angle:
the handlebar then follows the slow steering of a lane change (a few mrad/s) instead of
sticking. (At 0.02 rad/s the crosswind run's tracking error was 9 % of its peak steer angle
against 3 % at this width.)"""
DELAY_FRICTION_WIDTH = 0.05
"""Rate scale of the tanh of the dry friction in the prediction over a measurement's age
[rad/s] with an estimator that has none; with the Walcott-Zak observer its own
``friction_width`` (:class:`~motosim.estimation.walcott_zak.ObserverSettings`, 0.05 by
default)."""
PREDICTION_RATE = 1000.0
"""Lowest measurement rate where the rider-torque cancellation is predicted by default [Hz]
(and at :data:`PREDICTION_PAPER_RATE`)."""
PREDICTION_PAPER_RATE = 100.0
"""The paper's measurement rate (its 100 Hz CAN link), where the rider-torque cancellation
is predicted by default too [Hz]."""
PREDICTION_CORNER = 3.0
"""Corner of the predicted cancellation's first-order low-pass on the estimate's rate [Hz]."""
PREDICTION_NOTCH = (10.0, 0.5)
"""Frequency [Hz] and quality factor of the predicted cancellation's notch on the estimate's
rate: the lead vanishes there, where the robustness grid's phase margins are set (the
feedback's crossover, 10 Hz by default), and stays small about the motorcycle's wobble."""


class StackModel(NamedTuple):
    """Everything the stack needs that a run does not change (build with :func:`design_stack`).

    Attributes
    ----------
    dt : float
        Stack (control) period h [s]; :func:`step` is called once per period.
    measure_every : int
        Periods per measurement: the controller, differentiator and estimator run on every
        ``measure_every``-th call (the first included) and hold their outputs in between.
    estimator : EstimatorKernel
        The rider-torque estimator, discretised at the measurement step.
    differentiator : ndarray, shape (3,)
        [h_meas [s], lambda_1 L^(1/2), lambda_0 L] of the super-twisting differentiator.
    Ad, Bd, Cd, Dd : ndarray
        Discrete controller at the measurement step (x+ = Ad x + Bd e, i = Cd x + Dd e,
        e = theta_h - delta [rad], i [A]); order 0 with Dd = 0 when there is no feedback.
    feedback : bool
        Whether the controller commands the motor (False: Fig. 9, 0 A).
    prediction : ndarray, shape (8,)
        The predicted cancellation: [lead T_d [s] (0: the cancellation reads tau_r_hat as it
        is), the low-pass's g and p (g (1 + 1/z) / (1 - p / z)), the notch's b0, b1, b2, a1,
        a2] (see :func:`step`).
    feedforward : ndarray, shape (7,)
        [rider-torque cancellation gain (0 to 1), reference inverse-dynamics gain (0 or 1),
        J_eq [kg*m^2], beta_eq [N*m*s/rad], beta_s [N*m], N k_t [N*m/A], tanh width of the
        friction term [rad/s]] of the nominal handlebar (see :func:`step`).
    max_current : float
        Current command limit [A].
    A0, A1, Bv : ndarray
        The motorcycle's lateral matrices, A_v = A0 + v_x A1 (8x8), B_v (8,).
    Bw : ndarray, shape (8,)
        The side force's input (:func:`motosim.model.sharp.side_force_input`).
    motorcycle : ndarray, shape (3,)
        [m [kg], m + J_R / r_D^2 [kg], lowest speed [m/s]] of eq. (2).
    motorcycle_substeps : int
        RK4 steps of the motorcycle per period.
    speed : float
        Forward speed at :func:`reset` [m/s].
    true_torque : bool
        Drive the motorcycle with the rider's true torque instead of the estimate
        (a simulation-only reference run).
    delay : ndarray, shape (7,)
        The measurement's age d when the stack reads it (a status frame's latency on the
        bus): [d [s] (0: fresh, nothing else is read), d / h the share of the observer's
        step over which the previous command was carried [-], the nominal handlebar's angle
        per initial rate [s] and per torque [rad/(N*m)] over d, its beta_s [N*m] and N k_t
        [N*m/A], the rate scale of the friction's tanh [rad/s]] (see :func:`step_scaled`
        and :func:`account_for_delay`).
    """

    dt: float
    measure_every: int
    estimator: EstimatorKernel
    differentiator: Array
    Ad: Array
    Bd: Array
    Cd: Array
    Dd: Array
    feedback: bool
    prediction: Array
    feedforward: Array
    max_current: float
    A0: Array
    A1: Array
    Bv: Array
    Bw: Array
    motorcycle: Array
    motorcycle_substeps: int
    speed: float
    true_torque: bool
    delay: Array


class StackData(NamedTuple):
    """Every state of the stack that changes during a run (make with :func:`new_data`).

    Attributes
    ----------
    estimator : ndarray, shape (4,)
        The estimator's state.
    differentiator : ndarray, shape (2,)
        [z0 [rad], z1 [rad/s]].
    controller : ndarray, shape (n,)
        The discrete controller's state.
    motorcycle : ndarray, shape (12,)
        [v_y, psi', phi', delta', phi, delta, F_yr, F_yf, v_x, psi, x, y] (SI units).
    held : ndarray, shape (8,)
        Outputs held between measurements: [theta_h measured [rad], i_m command [A],
        theta_h'_hat [rad/s], tau_r_hat [N*m], the predicted cancellation's filtered rate of
        tau_r_hat [N*m/s]], then the states of its notch (two) and low-pass [N*m/s].
    periods : ndarray of int64, shape (1,)
        Periods since :func:`reset`.
    work : ndarray, shape (13, 12)
        Scratch space of the motorcycle's RK4.
    controller_work : ndarray
        Scratch space of the controller (at least one entry).
    """

    estimator: Array
    differentiator: Array
    controller: Array
    motorcycle: Array
    held: Array
    periods: NDArray[np.int64]
    work: Array
    controller_work: Array


def default_prediction(measurement_rate: float) -> bool:
    """Whether a stack that cancels the estimated rider torque predicts it, by default.

    On from :data:`PREDICTION_RATE` and at the paper's :data:`PREDICTION_PAPER_RATE`, the
    rates where it was measured on runs. At 1 kHz it keeps the robustness grid's margins on
    as many handlebars as the plain cancellation or more and cuts the tracking error the
    estimate's lag leaves on fast manoeuvres. At 100 Hz it cuts that error too (7 of the
    unseen runs' tracking misses to 5), keeps the grid (5/3/3 against 4/3/3 at 10/20/30 m/s)
    and the real-time safety stage's frozen-angle measure on Fig. 15's run stays below a
    third of its 0.05 rad fault (0.0072 against 0.0047 rad). Between, off: not measured on
    runs, and at 500 Hz it costs a grid point (the design guide, "The predicted
    cancellation").

    Examples
    --------
    >>> [default_prediction(r) for r in (50.0, 100.0, 200.0, 500.0, 1000.0)]
    [False, True, False, False, True]
    """
    return measurement_rate >= PREDICTION_RATE or measurement_rate == PREDICTION_PAPER_RATE


def design_stack(
    sharp: SharpParameters,
    estimator: EstimatorKernel,
    controller: StateSpace | None,
    *,
    control_rate: float,
    measurement_rate: float,
    lipschitz: float,
    discretization: str = "zoh",
    max_current: float,
    speed: float,
    true_torque: bool = False,
    handlebar: HandlebarParameters | None = None,
    rider_feedforward: bool = False,
    reference_feedforward: bool = False,
    prediction_lead: float = 0.0,
    side_force_height: float = 1.0,
    measurement_delay: float = 0.0,
) -> StackModel:
    """Build the stack's model from its designed parts (a pure function).

    Parameters
    ----------
    sharp : SharpParameters
        The virtual motorcycle.
    estimator : EstimatorKernel
        The estimator's record (``stepper.kernel``), discretised at ``1 / measurement_rate``.
    controller : StateSpace or None
        Controller K [A/rad], positive feedback i_m = K (theta_h - delta) (eq. (24)):
        continuous (discretised here) or already discrete at the measurement step; None for
        no torque feedback (Fig. 9).
    control_rate, measurement_rate : float
        Stack period and measurement rates [Hz]; a whole number of periods per measurement.
    lipschitz : float
        L, the bound on |theta_h''| that sets the differentiator's gains [rad/s^2].
    discretization : {"zoh", "tustin"}
        How a continuous controller is discretised at the measurement step.
    max_current : float
        Current command limit [A].
    speed : float
        Forward speed at the start [m/s].
    true_torque : bool
        Drive the motorcycle with the true rider torque (simulation only).
    handlebar : HandlebarParameters, optional
        The nominal handlebar, needed by the feedforward terms.
    rider_feedforward : bool
        Cancel the estimated rider torque with the motor: i += -tau_r_hat / (N k_t).
    reference_feedforward : bool
        Drive the handlebar along the steer angle by its inverse dynamics:
        i += (J_eq delta'' + beta_eq delta' + beta_s sign(delta')) / (N k_t).
    prediction_lead : float
        T_d [s]: with the rider-torque cancellation, cancel tau_r_hat + T_d r instead of
        tau_r_hat, r the estimate's rate through a notch (:data:`PREDICTION_NOTCH`) and a
        first-order low-pass (:data:`PREDICTION_CORNER`); 0 for none. The estimate filter's
        delay (:func:`motosim.sim.loop_analysis.prediction_lead`).
    side_force_height : float
        Height above the ground where a side force (wind) acts on the motorcycle [m].
    measurement_delay : float
        d, the age of the measured angle and current when the stack reads them [s], from 0
        (fresh: the stack as it was designed) to one measurement step; a status frame's
        latency on the bus. The stack then accounts for it (:func:`account_for_delay`).

    Returns
    -------
    StackModel

    Raises
    ------
    MotosimError
        On rates that are not whole multiples or an estimator designed for another step.
    """
    for name, value in (("control_rate", control_rate), ("measurement_rate", measurement_rate)):
        if not (math.isfinite(value) and value > 0):
            raise MotosimError(f"{name} = {value!r}; expected a finite rate > 0 [Hz]")
    ratio = control_rate / measurement_rate
    if ratio < 1.0 - 1e-9 or abs(ratio - round(ratio)) > 1e-9:
        raise MotosimError(f"control / measurement rate = {ratio:g}; expected a whole number >= 1")
    h_meas = 1.0 / measurement_rate
    if abs(estimator.dt - h_meas) > 1e-12 * h_meas:
        raise MotosimError(
            f"the estimator was discretised at {estimator.dt:g} s; expected the measurement "
            f"step {h_meas:g} s"
        )
    if not (math.isfinite(lipschitz) and lipschitz > 0):
        raise MotosimError(f"lipschitz = {lipschitz!r}; expected a finite bound > 0 [rad/s^2]")
    if controller is None:
        Ad, Bd, Cd, Dd = np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.zeros((1, 1))
    else:
        if controller.is_discrete and abs(controller.dt - h_meas) > 1e-12 * h_meas:
            raise MotosimError(
                f"the controller is discrete at {controller.dt:g} s; expected the measurement "
                f"step {h_meas:g} s (design it for {measurement_rate:g} Hz)"
            )
        K = controller if controller.is_discrete else discretize(controller, h_meas, discretization)
        Ad, Bd, Cd, Dd = K.A, K.B, K.C, K.D
    if (rider_feedforward or reference_feedforward) and handlebar is None:
        raise MotosimError("feedforward needs the nominal handlebar; give handlebar=")
    on = controller is not None
    prediction = np.zeros(8)
    if on and rider_feedforward and prediction_lead != 0.0:
        prediction = _prediction(prediction_lead, h_meas)
    ff = np.zeros(7)
    if handlebar is not None:
        ff[:] = (
            float(on and rider_feedforward), float(on and reference_feedforward),
            handlebar.J_eq, handlebar.beta_eq, handlebar.beta_s, handlebar.torque_per_amp,
            FEEDFORWARD_FRICTION_WIDTH,
        )  # fmt: skip
    h = 1.0 / control_rate
    d = derived_geometry(sharp)
    A0, A1, Bv = sharp_model.lpv_matrices(sharp)
    return StackModel(
        dt=h,
        measure_every=round(ratio),
        estimator=estimator,
        differentiator=np.array([h_meas, LAMBDA_1 * math.sqrt(lipschitz), LAMBDA_0 * lipschitz]),
        Ad=np.ascontiguousarray(Ad),
        Bd=np.ascontiguousarray(Bd),
        Cd=np.ascontiguousarray(Cd),
        Dd=np.ascontiguousarray(Dd),
        feedback=controller is not None and bool(Ad.shape[0] + abs(Dd[0, 0]) > 0),
        prediction=prediction,
        feedforward=ff,
        max_current=float(max_current),
        A0=A0,
        A1=A1,
        Bv=Bv,
        Bw=sharp_model.side_force_input(sharp, height=side_force_height),
        motorcycle=np.array([d["m"], d["m_eq"], sharp_model.MIN_SPEED]),
        motorcycle_substeps=max(1, math.ceil(h / MOTORCYCLE_STEP - 1e-9)),
        speed=float(speed),
        true_torque=bool(true_torque),
        delay=_delay(measurement_delay, h_meas, handlebar, estimator),
    )


def account_for_delay(
    model: StackModel, delay: float, handlebar: HandlebarParameters
) -> StackModel:
    """``model`` reading measurements ``delay`` old, as :func:`design_stack` would build it.

    Parameters
    ----------
    model : StackModel
        A designed stack.
    delay : float
        d, the age of the measured angle and current when the stack reads them [s], from
        0 (fresh: ``model`` as it was designed) to one measurement step.
    handlebar : HandlebarParameters
        The nominal handlebar the prediction over d uses.

    Returns
    -------
    StackModel

    Raises
    ------
    MotosimError
        If d is not within 0 to one measurement step.

    Notes
    -----
    At a measurement the stack reads theta_h(t - d). The current changes only at the
    measurements (d <= h), so over [t - d, t] the motor carried the previous command i_p,
    and the nominal handlebar (eq. (5)) predicts the angle now from the angle and rate
    then, x(t) = exp(A d) x(t - d) + int_0^d exp(A s) ds D tau, with the net torque tau =
    N k_t i_p + tau_r_hat + tau_p_hat held: the rate is the differentiator's backward
    difference brought to the sample (as the observer does) and the dry friction is the
    observer's: -beta_s tanh(rate / w) sliding, what holds the rest within +-beta_s while
    it sticks. The controller reads the predicted angle (a Smith predictor whose model is
    driven by the estimated disturbance, so that a held handlebar predicts no motion); the
    differentiator and the observer read the measured one, and the observer is told the
    current carried over its step [t - d, t + h - d]: i_p for d, the new command for h - d,
    as the share d / h of i_p (else the change of command at t reads as rider torque for
    d, and a cancelling loop feeds it back). Designed for a fresh sample, the 100 Hz stack
    of the lane change with the plain cancellation keeps 7.8 dB and 55 deg of margins; read
    5.5 ms old, 0.7 dB and 7 deg (unstable); accounting for the age, 7.6 dB and 49 deg
    (:func:`motosim.sim.loop_analysis.stack_loop` with ``delay``; with the predicted
    cancellation, the 100 Hz default: 7.8 dB and 53 deg, unstable, 6.9 dB and 48 deg).
    """
    h = model.dt * model.measure_every
    return model._replace(delay=_delay(delay, h, handlebar, model.estimator))


def _delay(
    delay: float, h: float, handlebar: HandlebarParameters | None, estimator: EstimatorKernel
) -> Array:
    """:attr:`StackModel.delay` for a measurement ``delay`` d [s] at the measurement step
    ``h`` [s] on the nominal ``handlebar``, the friction's tanh as wide as the Walcott-Zak
    ``estimator``'s (else :data:`DELAY_FRICTION_WIDTH`); MotosimError if d is not in [0, h],
    or is positive without a handlebar."""
    out = np.zeros(7)
    if not (math.isfinite(delay) and 0.0 <= delay <= h * (1.0 + 1e-12)):
        raise MotosimError(
            f"measurement delay = {delay!r} s; expected 0 to one measurement step ({h:g} s)"
        )
    if delay == 0.0:
        return out
    if handlebar is None:
        raise MotosimError("a measurement delay needs the nominal handlebar; give handlebar=")
    hb = handlebar_matrices(handlebar)
    phi, gamma = zoh(hb.A, hb.D[:, None], delay)
    out[:] = (
        delay, min(delay / h, 1.0), phi[1, 0], gamma[1, 0], handlebar.beta_s,
        handlebar.torque_per_amp, _friction_width(estimator),
    )  # fmt: skip
    return out


def _friction_width(estimator: EstimatorKernel) -> float:
    """The rate scale of the Walcott-Zak observer's friction tanh [rad/s] (its setting
    ``friction_width``, ``p[5]`` of its kernel), else :data:`DELAY_FRICTION_WIDTH`."""
    if estimator.kind == WALCOTT_ZAK and estimator.p[5] > 0.0:
        return float(estimator.p[5])
    return DELAY_FRICTION_WIDTH


def _prediction(lead: float, h: float) -> Array:
    """:attr:`StackModel.prediction` for a lead ``lead`` [s] at the measurement step ``h`` [s].

    The notch s^2 + w0^2 over s^2 + (w0 / Q) s + w0^2 and the low-pass w_c / (s + w_c), by
    the bilinear transform prewarped at w0 and w_c: the notch's zero stays at
    :data:`PREDICTION_NOTCH`'s frequency, and the low-pass has a zero at the Nyquist
    frequency, where the lead would otherwise add T_d w_c of gain to the cancellation.
    """
    f0, q = PREDICTION_NOTCH
    if not (math.isfinite(lead) and 0.0 < lead < 1.0):
        raise MotosimError(f"prediction_lead = {lead!r}; expected a delay in (0, 1) s")
    if 2.0 * f0 * h >= 0.5:
        raise MotosimError(
            f"the predicted cancellation's {f0:g} Hz notch needs a measurement rate above "
            f"{4 * f0:g} Hz; got {1 / h:g} Hz"
        )
    w0 = 2.0 * math.pi * f0
    k = w0 / math.tan(0.5 * w0 * h)
    den = k * k + w0 * k / q + w0 * w0
    t = math.tan(math.pi * PREDICTION_CORNER * h)
    pole = (1.0 - t) / (1.0 + t)
    return np.array([
        lead, 0.5 * (1.0 - pole), pole,
        (k * k + w0 * w0) / den, 2.0 * (w0 * w0 - k * k) / den, (k * k + w0 * w0) / den,
        2.0 * (w0 * w0 - k * k) / den, (k * k - w0 * k / q + w0 * w0) / den,
    ])  # fmt: skip


def new_data(model: StackModel) -> StackData:
    """Fresh, zeroed data for ``model``; call :func:`reset` before the first step."""
    n = model.Ad.shape[0]
    return StackData(
        estimator=np.zeros(4),
        differentiator=np.zeros(2),
        controller=np.zeros(n),
        motorcycle=np.zeros(12),
        held=np.zeros(8),
        periods=np.zeros(1, dtype=np.int64),
        work=np.zeros((13, 12)),
        controller_work=np.zeros(max(1, n)),
    )


@njit(cache=True)
def reset(model: StackModel, data: StackData, theta: float, current: float) -> None:
    """Start every state at a first measurement.

    The differentiator and the estimator start at the angle ``theta`` [rad] (rate 0) and the
    current ``current`` [A]; the controller at rest; the motorcycle upright and straight at
    ``model.speed``.
    """
    data.differentiator[0] = theta
    data.differentiator[1] = 0.0
    start_kernel(model.estimator, data.estimator, theta, 0.0, current)
    data.controller[:] = 0.0
    data.motorcycle[:] = 0.0
    data.motorcycle[8] = model.speed
    data.held[0] = theta
    data.held[1] = 0.0
    data.held[2] = 0.0
    data.held[3:] = 0.0
    data.periods[0] = 0


@njit(cache=True, inline="always")
def _command(model: StackModel, data: StackData, theta_meas: float) -> float:
    """The motor current for this sample, saturated; advances the controller's state.

    Feedback i = K (theta_h - delta), positive feedback (eq. (24)), plus the feedforward
    terms switched on in ``model.feedforward``: the estimated rider torque cancelled, and the
    nominal handlebar's inverse dynamics along the steer angle delta of the motorcycle.
    """
    if not model.feedback:
        return 0.0
    z = data.motorcycle
    e = theta_meas - z[5]
    x, tmp = data.controller, data.controller_work
    n = x.size
    u = model.Dd[0, 0] * e
    for j in range(n):
        u += model.Cd[0, j] * x[j]
    for r in range(n):
        acc = model.Bd[r, 0] * e
        for j in range(n):
            acc += model.Ad[r, j] * x[j]
        tmp[r] = acc
    for r in range(n):
        x[r] = tmp[r]
    ff = model.feedforward
    torque = 0.0
    if ff[0] > 0.0:  # cancel what the rider is estimated to apply
        cancelled = data.held[3]
        if model.prediction[0] > 0.0:  # predicted: tau_r_hat + T_d LP(notch(d tau_r_hat / dt))
            cancelled += model.prediction[0] * data.held[4]
        torque -= ff[0] * cancelled
    if ff[1] > 0.0:  # J delta'' + beta delta' + beta_s sign(delta'), delta'' from the model
        v = z[8]
        dd = model.Bv[3] * data.held[3]
        for c in range(8):
            dd += (model.A0[3, c] + v * model.A1[3, c]) * z[c]
        torque += ff[2] * dd + ff[3] * z[3] + ff[4] * math.tanh(z[3] / ff[6])
    if ff[0] > 0.0 or ff[1] > 0.0:
        u += torque / ff[5]
    return float(min(max(u, -model.max_current), model.max_current))


@njit(cache=True, inline="always")
def step(
    model: StackModel,
    data: StackData,
    theta_meas: float,
    current_error: float,
    rider_torque: float,
    force: float,
    side_force: float,
) -> float:
    """Advance the stack by one period; return the motor current command [A].

    :func:`step_scaled` with the command carried whole (``current_scale`` 1): the offline
    loop's step; its parameters and value are those below.
    """
    return step_scaled(model, data, theta_meas, current_error, rider_torque, force, side_force, 1.0)


@njit(cache=True, inline="always")
def step_scaled(
    model: StackModel,
    data: StackData,
    theta_meas: float,
    current_error: float,
    rider_torque: float,
    force: float,
    side_force: float,
    current_scale: float,
) -> float:
    """Advance the stack by one period; return the motor current command [A].

    On a measurement period: the controller commands the current from the measured angle
    and the motorcycle's steer angle, the differentiator and the estimator take the sample,
    told that ``current_scale`` times the command plus ``current_error`` is what the motor
    carries over the coming period. Between measurements the outputs are held. Then the
    virtual motorcycle advances one period under the estimated rider torque. With a
    measurement delay (``model.delay``, :func:`account_for_delay`) the controller reads the
    angle predicted over the measurement's age, and the estimator is told the previous
    command for the share of its step that it was carried.

    Parameters
    ----------
    model : StackModel
        The designed stack.
    data : StackData
        Its states, updated in place.
    theta_meas : float
        Measured handlebar angle [rad] (read on measurement periods only).
    current_error : float
        Measured minus commanded motor current [A]: sensor noise in simulation, 0 when the
        drive's current loop is taken to follow its command.
    rider_torque : float
        Rider torque [N*m]: the true one, read by a ``model.true_torque`` reference run, or
        the one a torque sensor measures, read by the estimator of kind
        :data:`~motosim.estimation.kernel.TORQUE_SENSOR` (and then by a reference run too).
    force : float
        Longitudinal force of eq. (2), (tau_d - tau_b) / r_D + F_wx [N].
    side_force : float
        Side force on the motorcycle (a side wind), to the right [N].
    current_scale : float
        The share of the command the drive will carry [-]: 1 offline; in the real-time
        loop the safety stage's fade and hands-off gain, which the estimator must be told
        of (the measured current tells it only at the next status frame).

    Returns
    -------
    float
        Motor current command, held until the next measurement [A].
    """
    held = data.held
    if data.periods[0] % model.measure_every == 0:
        held[0] = theta_meas
        p = model.differentiator
        z1_before = data.differentiator[1]
        z0, z1 = std_step(data.differentiator[0], z1_before, theta_meas, p[0], p[1], p[2], True)
        if model.delay[0] > 0.0:  # a measurement d old: the angle now, predicted over d
            dl = model.delay
            previous = held[1]  # the command carried since the last measurement
            rate = z1 + 0.5 * (z1 - z1_before)  # the backward difference, at the sample
            torque = dl[5] * current_scale * previous + held[3]
            slide = math.tanh(rate / dl[6])
            stick = min(max(torque, -dl[4]), dl[4])
            torque -= dl[4] * slide + (1.0 - abs(slide)) * stick
            predicted = theta_meas + dl[2] * rate + dl[3] * torque
            held[1] = _command(model, data, predicted)
            told = (1.0 - dl[1]) * held[1] + dl[1] * previous
        else:
            held[1] = _command(model, data, theta_meas)
            told = held[1]
        data.differentiator[0] = z0
        data.differentiator[1] = z1
        held[2] = z1
        estimate = step_kernel(
            model.estimator, data.estimator, theta_meas, z1, current_scale * told + current_error,
            rider_torque,
        )  # fmt: skip
        c = model.prediction
        if c[0] > 0.0:
            # the estimate's rate through the notch and the low-pass (transposed form II)
            x = (estimate - held[3]) / p[0]
            y = c[3] * x + held[5]
            held[5] = c[4] * x - c[6] * y + held[6]
            held[6] = c[5] * x - c[7] * y
            held[4] = c[1] * y + held[7]
            held[7] = c[1] * y + c[2] * held[4]
        held[3] = estimate
    data.periods[0] += 1
    steer = rider_torque if model.true_torque else held[3]
    mc = model.motorcycle
    h = model.dt / model.motorcycle_substeps
    for _ in range(model.motorcycle_substeps):
        bike_rk4(data.motorcycle, data.work, model.A0, model.A1, model.Bv, steer, model.Bw,
                 side_force, force, mc[0], mc[1], mc[2], h)  # fmt: skip
    return float(held[1])
