"""The sampled haptic loop of Fig. 7, linearised with the observer and the motorcycle inside.

The controller's own analysis (:func:`motosim.control.torque_feedback.analyse_loop`) sees the
handlebar and the controller only. What the rider holds is the whole stack: the estimator
feeds the motorcycle, the motorcycle sets the reference, the feedforward cancels the estimate,
and every part is sampled. :func:`stack_loop` writes that loop, for one designed
:class:`~motosim.sim.stack.StackModel`, a true handlebar and a speed, as one discrete-time
linear system at the measurement step, exactly as :func:`motosim.sim.stack.step` computes
it, with three idealisations:

- the super-twisting differentiator in its sliding mode, where the implicit step returns the
  backward difference (theta_k - theta_{k-1}) / h exactly;
- the Walcott-Zak injection inside its boundary layer, E = (eta / epsilon) F (y - y_hat);
- no dry friction, and so neither the observer's friction compensation nor its stick
  projection (the friction's effect is judged separately, by a describing function), and no
  current limit.

:func:`analyse_stack` then gives the margins of the loop broken at the motor current, its
stability against the motorcycle's own modes, the rendered steering feel against the
motorcycle's, and the frequencies where the handlebar's dry friction can sustain a limit
cycle; :func:`robustness_grid` repeats it over perturbed handlebars.
"""

import math
from dataclasses import dataclass, replace
from enum import IntEnum

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.estimation.kernel import WALCOTT_ZAK, EstimatorKernel, ObserverInput, ObserverState
from motosim.estimation.walcott_zak import observer_row
from motosim.model.handlebar import matrices
from motosim.model.linear import StateSpace, zoh
from motosim.model.sharp import held_steering
from motosim.params.handlebar import HandlebarParameters
from motosim.params.sharp import SharpParameters
from motosim.sim.grips import Hands, held_handlebar
from motosim.sim.stack import (
    NO_DELAY,
    NO_PREDICTION,
    MotorcycleState,
    StackModel,
    default_prediction,
    design_stack,
)

__all__ = [
    "FEEL_BAND",
    "MARGINS",
    "CancellationBound",
    "GridSummary",
    "LimitCycle",
    "LoopInput",
    "StackLoop",
    "StackLoopAnalysis",
    "analyse_design",
    "analyse_stack",
    "cancellation_bound",
    "cancellation_loop_gain",
    "estimate_filter",
    "held_motorcycle",
    "negative_real_crossings",
    "prediction_lead",
    "robustness_grid",
    "stack_loop",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

MARGINS = (6.0, 45.0)
"""Gain [dB] and phase [deg] margins a loop should keep (the classical requirements, e.g.
Skogestad & Postlethwaite, Multivariable Feedback Control, section 2.4)."""
FEEL_BAND = (0.1, 3.0)
"""Band where the rendered steering feel is compared with the motorcycle's [Hz]."""
_GRID_POINTS = 600  # frequencies of the margin and limit-cycle search
_LATERAL = 8  # Sharp 1971's lateral states, the first of MotorcycleState


class _Bar(IntEnum):
    """The handlebar's state of eq. (10), (theta_h', theta_h): its matrices' rows."""

    rate = 0
    angle = 1


class _Drive(IntEnum):
    """The handlebar's inputs in :func:`_held_plant`, (i_m, tau_r): its B's columns."""

    current = 0
    torque = 1


class _Prediction(IntEnum):
    """The predicted cancellation's states in the loop: the filtered rate of the estimate,
    the notch's two states and the low-pass's (the stack's ``Held.tau_r_hat_rate``,
    ``notch_0``, ``notch_1``, ``low_pass``)."""

    rate = 0
    notch_0 = 1
    notch_1 = 2
    low_pass = 3


class LoopInput(IntEnum):
    """The inputs of :class:`StackLoop` (the columns of its B), by name."""

    rider_torque = 0
    """tau_r [N*m], the rider's active torque on the handlebar."""
    current = 1
    """u [A] added to the command at the motor: the loop broken at the motor current."""
    estimate = 2
    """w [N*m] added to the estimate the rider-torque cancellation reads."""
    angle = 3
    """n [rad] added to the measured angle: an encoder's rounding error."""


def _held_plant(handlebar: HandlebarParameters, hands: Hands | None) -> tuple[Array, Array]:
    """Eq. (10) with the arms' passive impedance on the handlebar: (A, [B, D]).

    For the state (theta_h', theta_h) and the inputs (i_m, tau_r),
    (J_eq + J_a) theta_h'' = -(beta_eq + c_a) theta_h' - k_a theta_h + N k_t i_m + tau_r:
    the held handlebar (:func:`~motosim.sim.grips.held_handlebar`) and the arms' stiffness
    about the held angle (a constant, left out of the linear loop).
    """
    held = held_handlebar(handlebar, hands)
    hb = matrices(held)
    A = hb.A.copy()
    if hands is not None:
        A[_Bar.rate, _Bar.angle] = -hands.stiffness / held.J_eq
    return A, np.column_stack([hb.B, hb.D])


def held_motorcycle(A_v: Array, B_v: Array, hands: Hands | None) -> tuple[Array, Array]:
    """Sharp 1971's lateral model with the rider's hands on its front frame: (A, B) from the
    rider's active torque (:func:`motosim.model.sharp.held_steering`).

    This is the motorcycle the rendered feel is compared with: what a rider holding a real
    front frame feels.
    """
    if hands is None or hands.is_off:
        return A_v, B_v
    A, B, _ = held_steering(A_v, B_v, hands.inertia, hands.damping, hands.stiffness)
    return A, B


@dataclass(frozen=True, slots=True)
class StackLoop:
    """The linearised sampled loop: x+ = A x + B [tau_r, u, w], at the measurement step.

    Attributes
    ----------
    A : ndarray, shape (n, n)
        Closed loop (the motor carries the commanded current, u = 0, w = 0, n = 0).
    B : ndarray, shape (n, 4)
        Inputs: rider torque tau_r [N*m] on the handlebar; a current u [A] added to the
        command at the motor (the loop's break point); a torque w [N*m] added to the
        estimate that the rider-torque cancellation reads (the cancellation loop's break
        point; a zero column without cancellation); an angle n [rad] added to the measured
        angle that the controller, the differentiator and the observer read (an encoder's
        rounding error; the break point at the measurement).
    current : ndarray, shape (n,)
        Row giving the commanded current i [A] from the state.
    rate : ndarray, shape (n,)
        Row giving the handlebar rate theta_h' [rad/s] (the true one) from the state.
    angle : ndarray, shape (n,)
        Row giving the handlebar angle theta_h [rad].
    estimate : ndarray, shape (n,)
        Row giving the torque [N*m] that the next command cancels: the estimate tau_r_hat
        held from the previous sample, plus T_d times its filtered rate with the prediction
        (:attr:`motosim.sim.stack.StackModel.prediction`).
    dt : float
        The step h [s].
    motorcycle : ndarray, shape (8, 8)
        The motorcycle's own lateral matrix A_v at the speed [1/s].
    motorcycle_input : ndarray, shape (8,)
        Its steer-torque input B_v.
    measured : ndarray, shape (n,)
        Row giving the angle the stack measures [rad]: ``angle``, or with a measurement
        delay d the angle d before the sample.
    """

    A: Array
    B: Array
    current: Array
    rate: Array
    angle: Array
    estimate: Array
    dt: float
    motorcycle: Array
    motorcycle_input: Array
    measured: Array

    def response(self, frequencies: Array, row: Array, column: int) -> CArray:
        """Closed-loop response from input ``column`` to the output ``row`` at ``frequencies``
        [Hz]."""
        n = self.A.shape[0]
        z = np.exp(2j * math.pi * np.asarray(frequencies, dtype=float) * self.dt)
        return np.array(
            [row @ np.linalg.solve(zk * np.eye(n) - self.A, self.B[:, column]) for zk in z]
        )

    def loop_gain(self, frequencies: Array, column: int) -> CArray:
        """Open-loop gain L (negative-feedback convention) of the loop broken at an input.

        ``column`` 1 breaks it at the motor current (L from the current applied to the
        commanded one), 2 at the estimate the rider-torque cancellation reads, 3 at the
        measured angle (L from the measured angle to the true one: where it is real and
        negative beyond -1 / 1.27, a rounding quantiser's describing function, whose gain
        lies between 0 and 4 / pi, can meet -1 / L and an encoder can sustain a limit
        cycle of about one count). The loop is
        opened by taking that signal's own feedback out of A: with the break's input b and
        output row c, A_open = A - b c and L = -c (zI - A_open)^-1 b. (The closed-loop
        response from the same input, c (zI - A)^-1 b = -L / (1 + L), is not the loop gain.)
        """
        row = {
            LoopInput.current: self.current,
            LoopInput.estimate: self.estimate,
            LoopInput.angle: self.measured,
        }[LoopInput(column)]
        n = self.A.shape[0]
        b = self.B[:, column]
        A_open = self.A - np.outer(b, row)
        z = np.exp(2j * math.pi * np.asarray(frequencies, dtype=float) * self.dt)
        return np.array([-(row @ np.linalg.solve(zk * np.eye(n) - A_open, b)) for zk in z])


def _inputs(B: Array, row: int, torque: float, current: float, cancel: float) -> None:
    """Row ``row`` of the loop's B: the gain of the rider's torque, of a current u added at
    the motor, and of the torque w added to the estimate (through the current the
    cancellation commands, ``cancel`` A per N*m)."""
    B[row, LoopInput.rider_torque] = torque
    B[row, LoopInput.current] = current
    B[row, LoopInput.estimate] = current * cancel


def stack_loop(
    model: StackModel,
    handlebar: HandlebarParameters,
    speed: float,
    *,
    delay: float | None = None,
    hands: Hands | None = None,
) -> StackLoop:
    """Write the stack of ``model`` around the true ``handlebar`` as one linear sampled loop.

    Parameters
    ----------
    model : StackModel
        The designed stack; its estimator must be the Walcott-Zak observer.
    handlebar : HandlebarParameters
        The true handlebar (possibly perturbed from the nominal one the stack was built for).
    speed : float
        Forward speed at which the motorcycle is linearised [m/s].
    delay : float, optional
        The measurement's true age d [s], 0 to the measurement step; by default the one the
        stack accounts for (``model.delay.age``).
    hands : Hands, optional
        The rider's hands on the true handlebar (their inertia, damping and stiffness); by
        default none, a pure torque source. The loop's :attr:`StackLoop.motorcycle` is then
        the motorcycle held the same way (:func:`held_motorcycle`), what the rendered feel
        should match.

    Returns
    -------
    StackLoop
        States: handlebar [theta_h', theta_h], the previous angle and differentiated rate,
        the observer [theta_h'_hat, theta_h_hat], its estimate (the filtered injection), the
        controller and the motorcycle's eight lateral states; with a measurement delay d
        (:attr:`~motosim.sim.stack.StackModel.delay`), the handlebar's state d before the
        sample (what the stack measures) and the current carried since the last sample.

    Notes
    -----
    With a measurement delay d (0 < d <= h) the stack reads at sample k the angle of
    t_k - d, x(t_k - d) = Phi(h - d) x_{k-1} + Gamma(h - d) [i_{k-1}, tau_r], over which
    the current i_{k-1} was carried (the command changes at the samples); as
    :func:`motosim.sim.stack.step_scaled` does, the controller reads that angle predicted
    over d and the observer is told the current carried over its step, the previous
    command for d and the new one for h - d.

    Raises
    ------
    MotosimError
        If the stack's estimator is not the Walcott-Zak observer, or ``delay`` is out of
        range.
    """
    h = model.dt * model.measure_every
    dl = model.delay
    bus = float(dl.age) if delay is None else float(delay)
    if not (math.isfinite(bus) and 0.0 <= bus <= h * (1.0 + 1e-12)):
        raise MotosimError(f"delay = {delay!r} s; expected 0 to one measurement step ({h:g} s)")
    if model.estimator.kind != WALCOTT_ZAK:
        raise MotosimError(
            f"estimator kind {model.estimator.kind}; the loop analysis needs the Walcott-Zak "
            "observer"
        )
    est = model.estimator
    rows = int(ObserverState.estimate)  # the observer's (theta_h', theta_h): the first rows
    Phi, Gamma, g = est.Phi[:rows, :rows], est.Gamma[:rows, : len(ObserverInput)], est.gain[:rows]
    wz = est.walcott_zak
    injection = wz.sign * wz.eta / wz.epsilon
    alpha, w = wz.filter_alpha, wz.rate_weight
    ff = model.feedforward
    A_h, B_h = _held_plant(handlebar, hands)
    Ap, Bp = zoh(A_h, B_h, h)
    Av = model.A0 + speed * model.A1
    Am, Bm = zoh(Av, model.Bv[:, None], h)
    nc = model.Ad.shape[0]
    c = model.prediction
    predicted = ff.cancellation > 0.0 and c.lead > 0.0
    delayed = dl.age > 0.0  # the stack accounts for a delay
    sizes = {
        "plant": len(_Bar),
        "theta_prev": 1,
        "rate_prev": 1,
        "observer": len(_Bar),  # the observer's (theta_h', theta_h)
        "estimate": 1,
        "prediction": len(_Prediction) if predicted else 0,
        "controller": nc,
        "motorcycle": _LATERAL,
        "before": len(_Bar) if bus > 0.0 else 0,
        "carried": 1 if delayed else 0,
    }
    start, n = {}, 0
    for name, size in sizes.items():
        start[name] = n
        n += size
    eye = np.eye(n + 1)  # the last coordinate: the angle n added to the measurement

    def state(name: str, k: int = 0) -> Array:
        return np.asarray(eye[start[name] + k], dtype=float)

    theta, rate = state("plant", _Bar.angle), state("plant", _Bar.rate)
    delta = state("motorcycle", MotorcycleState.delta)
    delta_rate = state("motorcycle", MotorcycleState.delta_dot)
    measured = (state("before", _Bar.angle) if bus > 0.0 else theta) + eye[n]
    held = state("estimate")  # the command uses the previous sample's estimate
    z1 = (measured - state("theta_prev")) / h
    rate_used = z1 + w * (z1 - state("rate_prev"))
    error = measured - delta
    if delayed:  # the angle predicted over d, by the carried current and the estimate
        carried = state("carried")
        error = error + dl.per_rate * (z1 + 0.5 * (z1 - state("rate_prev")))
        error = error + dl.per_torque * (dl.torque_per_amp * carried + held)
    command = model.Dd[0, 0] * error
    for j in range(nc):
        command = command + model.Cd[0, j] * state("controller", j)
    cancelled = held + c.lead * state("prediction", _Prediction.rate) if predicted else held
    torque = -ff.cancellation * cancelled
    if ff.reference > 0.0:  # the friction term's tanh is left out with the friction itself
        m0 = start["motorcycle"]
        steer_acc = (
            model.Bv[MotorcycleState.delta_dot] * held
            + Av[MotorcycleState.delta_dot] @ eye[m0 : m0 + _LATERAL]
        )
        torque = torque + ff.J_eq * steer_acc + ff.beta_eq * delta_rate
    if ff.cancellation > 0.0 or ff.reference > 0.0:
        command = command + torque / ff.torque_per_amp
    x0, x1 = state("observer", _Bar.rate), state("observer", _Bar.angle)
    E = injection * (g[_Bar.rate] * (rate_used - x0) + g[_Bar.angle] * (measured - x1))
    estimate = held + alpha * (E - held)

    # the cancellation's break point: a torque w added to the estimate it reads
    cancel = -ff.cancellation / ff.torque_per_amp if ff.cancellation > 0.0 else 0.0

    A = np.zeros((n, n + 1))  # rows over the states and the measurement's n
    B = np.zeros((n, len(LoopInput)))

    def bar_rows(rows: int, Ab: Array, Bb: Array) -> None:
        """The loop's rows of a handlebar's state (theta_h', theta_h) after a step of Ab,
        Bb."""
        for i in _Bar.rate, _Bar.angle:
            on_state = Ab[i, _Bar.rate] * rate + Ab[i, _Bar.angle] * theta
            A[rows + i] = on_state + Bb[i, _Drive.current] * command
            _inputs(B, rows + i, Bb[i, _Drive.torque], Bb[i, _Drive.current], cancel)

    bar_rows(start["plant"], Ap, Bp)
    told, share = command, 1.0  # the current the observer is told, and the new command's share
    if bus > 0.0:
        if h - bus > 1e-12 * h:
            Ab, Bb = zoh(A_h, B_h, h - bus)
        else:
            Ab, Bb = np.eye(2), np.zeros((2, 2))
        bar_rows(start["before"], Ab, Bb)
    if delayed:
        A[start["carried"]] = command
        _inputs(B, start["carried"], 0.0, 1.0, cancel)
        share = 1.0 - dl.carried
        told = share * command + dl.carried * carried
    A[start["theta_prev"]] = measured
    A[start["rate_prev"]] = z1
    for i in _Bar.rate, _Bar.angle:
        row = observer_row(Phi, Gamma, i, x0, x1, told, rate_used, measured, E)
        A[start["observer"] + i] = row
        # the estimator is told the measured current
        _inputs(B, start["observer"] + i, 0.0, Gamma[i, ObserverInput.current] * share, cancel)
    A[start["estimate"]] = estimate
    if predicted:  # the estimate's rate through the notch, the low-pass (as step does)
        x = (estimate - held) / h
        y = c.b0 * x + state("prediction", _Prediction.notch_0)
        rate_filtered = c.g * y + state("prediction", _Prediction.low_pass)
        p0 = start["prediction"]
        A[p0 + _Prediction.rate] = rate_filtered
        A[p0 + _Prediction.notch_0] = c.b1 * x - c.a1 * y + state("prediction", _Prediction.notch_1)
        A[p0 + _Prediction.notch_1] = c.b2 * x - c.a2 * y
        A[p0 + _Prediction.low_pass] = c.g * y + c.pole * rate_filtered
    for r in range(nc):
        row = model.Bd[r, 0] * error
        for j in range(nc):
            row = row + model.Ad[r, j] * state("controller", j)
        A[start["controller"] + r] = row
    m0 = start["motorcycle"]
    A[m0 : m0 + _LATERAL] = Am @ eye[m0 : m0 + _LATERAL] + np.outer(Bm[:, 0], estimate)
    B[:, LoopInput.angle] = A[:, n]
    own, own_input = held_motorcycle(Av, model.Bv.copy(), hands)
    return StackLoop(
        A[:, :n].copy(),
        B,
        command[:n],
        rate[:n],
        theta[:n],
        cancelled[:n],
        h,
        own,
        own_input,
        measured[:n],
    )


def estimate_filter(
    model: StackModel, handlebar: HandlebarParameters, speed: float, frequencies: Array
) -> CArray:
    """F(z): from the rider's torque to the estimate the cancellation reads, sample hold included.

    On the handlebar the observer was designed for, the estimate does not depend on the
    motor current (the observer's model is the handlebar's own), so tau_r_hat = F(z) tau_r
    whatever the loop does; F is the estimator's filter (injection, the estimate's low-pass,
    the differentiator) and the one-sample hold before the command reads it.

    Parameters
    ----------
    model : StackModel
        The designed stack (Walcott-Zak estimator).
    handlebar : HandlebarParameters
        The handlebar the observer was designed for.
    speed : float
        Forward speed [m/s] (F does not depend on it).
    frequencies : ndarray
        [Hz], below the Nyquist frequency of the measurement step.

    Returns
    -------
    ndarray of complex
        F at ``frequencies`` [-].
    """
    loop = stack_loop(model, handlebar, speed)
    return loop.response(frequencies, loop.estimate, LoopInput.rider_torque)


PREDICTION_FREQUENCY = 1.0
"""Where :func:`prediction_lead` reads the estimate filter's delay [Hz]: in the rider's band,
where F is an almost pure delay (gain 0.99-1.00 up to 3 Hz)."""


def prediction_lead(model: StackModel, handlebar: HandlebarParameters) -> float:
    """T_d of the predicted cancellation: the estimate filter's delay [s].

    The lag of F (:func:`estimate_filter`, the stack without prediction) at
    :data:`PREDICTION_FREQUENCY`, -arg F / (2 pi f), at the stack's speed (the simulate
    guide gives it for the default designs).

    Parameters
    ----------
    model : StackModel
        The designed stack (Walcott-Zak estimator).
    handlebar : HandlebarParameters
        The handlebar the observer was designed for.

    Returns
    -------
    float
        [s].
    """
    plain = model._replace(prediction=NO_PREDICTION)
    f = np.array([PREDICTION_FREQUENCY])
    F = estimate_filter(plain, handlebar, model.speed, f)[0]
    return float(-np.angle(F) / (2.0 * math.pi * f[0]))


def cancellation_loop_gain(loop: StackLoop, frequencies: Array) -> CArray:
    """The rider-torque cancellation's own loop gain, broken at the estimate it reads.

    The loop broken at the motor current (:func:`analyse_stack`'s margins) leaves this inner
    loop closed: on a perturbed handlebar the estimate reads part of the motor's own torque
    as rider torque, and the cancellation feeds it back. Negative-feedback convention: the
    loop is stable with margins when 1 + L keeps away from 0.

    Parameters
    ----------
    loop : StackLoop
        The stack around a (perturbed) handlebar.
    frequencies : ndarray
        [Hz].

    Returns
    -------
    ndarray of complex
        L at ``frequencies`` (zero without cancellation) [-].
    """
    return loop.loop_gain(frequencies, LoopInput.estimate)


@dataclass(frozen=True, slots=True)
class CancellationBound:
    """The cancellation loop's gain margin predicted from the estimate filter F alone.

    Attributes
    ----------
    gain_margin_db : float
        Smallest -20 log10 |F Delta| where F Delta crosses the negative real axis, the
        Nyquist frequency included (inf when it does not; negative: the loop is unstable)
        [dB].
    frequency : float
        Where [Hz] (nan when there is no crossing).
    low_frequency_db : float
        -20 log10 |Delta(0)| when Delta(0) = (k / k_hat)(beta_hat / beta) - 1 is negative,
        else inf [dB]: the margin left where F is 1 (the feel band) and the feedback's input
        sensitivity 1 / (1 - k K G) has zero phase and unit gain.
    """

    gain_margin_db: float
    frequency: float
    low_frequency_db: float


def cancellation_bound(
    F: CArray,
    frequencies: Array,
    nominal: HandlebarParameters,
    true: HandlebarParameters,
    dt: float,
) -> CancellationBound:
    """Predict the cancellation loop's gain margin from F and the handlebar's error.

    Parameters
    ----------
    F : ndarray of complex
        :func:`estimate_filter` at ``frequencies``.
    frequencies : ndarray
        [Hz], up to the Nyquist frequency 1 / (2 ``dt``) at most.
    nominal : HandlebarParameters
        The handlebar the observer and the cancellation were designed for (J_hat, beta_hat,
        k_hat = N k_t).
    true : HandlebarParameters
        The real one (J, beta, k).
    dt : float
        The measurement step h [s].

    Returns
    -------
    CancellationBound

    Notes
    -----
    The true handlebar obeys J theta'' + beta theta' = tau_r + k i (k = N k_t); the observer
    believes J_hat, beta_hat and k_hat, and so estimates tau_r_hat = F [tau_r + (J_hat - J)
    theta'' + (beta_hat - beta) theta' + (k - k_hat) i]. Sampled with the current held, the
    angle is theta = G(z) (tau_r + k i) with G the zero-order-hold transfer of
    1 / (J s^2 + beta s), and on the nominal handlebar the estimate does not depend on i, so
    the motor's current comes back into the estimate as F k_hat Delta i with

        Delta(z) = (k / k_hat) G(z) / G_hat(z) - 1,

    which tends to (k / k_hat)(J_hat / J) - 1 between the handlebar's pole beta / J and the
    Nyquist frequency, and to (k / k_hat)(beta_hat / beta) - 1 below it. The cancellation,
    i = -tau_r_hat / k_hat + ..., closes the loop 1 + F Delta. The feedback K around the
    handlebar multiplies it by its input sensitivity 1 / (1 - k K G), which is close to 1
    only above the feedback's bandwidth: the bound is the cancellation loop's margin where
    F Delta crosses the negative real axis well above it.
    """
    f = np.asarray(frequencies, dtype=float)
    z = np.exp(2j * math.pi * f * dt)

    def angle_per_torque(hb: HandlebarParameters) -> CArray:
        m = matrices(hb)
        Phi, Gamma = zoh(m.A, m.D[:, None], dt)
        return np.array([m.C @ np.linalg.solve(zk * np.eye(2) - Phi, Gamma[:, 0]) for zk in z])

    ratio = true.torque_per_amp / nominal.torque_per_amp
    delta = ratio * angle_per_torque(true) / angle_per_torque(nominal) - 1.0
    loop = np.asarray(F) * delta
    crossing = [(fk, -20.0 * math.log10(-x)) for _, fk, x in negative_real_crossings(loop, f)]
    if abs(f[-1] * dt - 0.5) < 1e-9 and loop[-1].real < 0.0:  # real at the Nyquist frequency
        crossing.append((float(f[-1]), -20.0 * math.log10(-loop[-1].real)))
    low = ratio * nominal.beta_eq / true.beta_eq - 1.0
    low_db = -20.0 * math.log10(-low) if low < 0.0 else math.inf
    if not crossing:
        return CancellationBound(math.inf, math.nan, low_db)
    where, gain = min(crossing, key=lambda c: c[1])
    return CancellationBound(gain, where, low_db)


def negative_real_crossings(response: CArray, frequencies: Array) -> list[tuple[int, float, float]]:
    """Where a frequency response crosses the negative real axis between two of its samples.

    Parameters
    ----------
    response : ndarray of complex, shape (n,)
        The response at ``frequencies``.
    frequencies : ndarray, shape (n,)
        Increasing frequencies [Hz].

    Returns
    -------
    list of (int, float, float)
        For each crossing: the sample before it, the frequency [Hz] and the real part (< 0)
        there, both interpolated linearly between the two samples.
    """
    out = []
    for k in range(response.size - 1):
        a, b = response[k], response[k + 1]
        if a.imag * b.imag < 0.0:
            s = a.imag / (a.imag - b.imag)
            x = a.real + s * (b.real - a.real)
            if x < 0.0:
                f = frequencies[k] + s * (frequencies[k + 1] - frequencies[k])
                out.append((k, float(f), float(x)))
    return out


@dataclass(frozen=True, slots=True)
class LimitCycle:
    """A limit cycle of the handlebar's dry friction that a describing function predicts.

    Attributes
    ----------
    frequency : float
        [Hz].
    amplitude : float
        Amplitude of the handlebar angle's oscillation [rad].
    """

    frequency: float
    amplitude: float


@dataclass(frozen=True, slots=True)
class StackLoopAnalysis:
    """What :func:`analyse_stack` finds.

    Attributes
    ----------
    speed : float
        [m/s].
    stable : bool
        The loop adds no unstable mode to the motorcycle's own (an unstable capsize mode of
        the motorcycle, which the rider stabilises, is not counted against the loop).
    spectral_radius : float
        Largest |eigenvalue| of the closed loop.
    gain_margin_db, phase_margin_deg : float
        Of the loop broken at the motor current, the estimator told the measured current
        (inf when there is no crossing) [dB, deg]. The gain margin is the smallest change of
        the loop gain, up or down, that reaches the critical point.
    modulus_margin : float
        min |1 + L| over frequency, the distance of the loop to the critical point.
    cancellation_gain_margin_db, cancellation_phase_margin_deg : float
        Of the rider-torque cancellation's own loop, broken at the estimate it reads
        (:func:`cancellation_loop_gain`), which the break at the motor current leaves closed
        (inf without cancellation or crossing) [dB, deg].
    feel_magnitude_db, feel_phase_deg : float
        Largest error of the rendered feel (rider torque to handlebar angle) against the
        motorcycle's own rider torque to steer angle over :data:`FEEL_BAND` [dB, deg].
    prediction_lead : float
        T_d of the stack's predicted cancellation [s] (0: it cancels the estimate as it is).
    measurement_delay : float
        The measurement's age d analysed [s] (the stack may or may not account for it:
        :attr:`~motosim.sim.stack.StackModel.delay`).
    limit_cycles : tuple of LimitCycle
        Where the rendered handlebar admittance is not passive but the motorcycle's is, and
        crosses the negative real axis: Coulomb friction of ``handlebar.beta_s`` sustains an
        oscillation there (first-harmonic balance, 1 + N(a) Y = 0 with N(a) = 4 beta_s /
        (pi a) for a rate amplitude a).
    """

    speed: float
    stable: bool
    spectral_radius: float
    gain_margin_db: float
    phase_margin_deg: float
    modulus_margin: float
    cancellation_gain_margin_db: float
    cancellation_phase_margin_deg: float
    feel_magnitude_db: float
    feel_phase_deg: float
    prediction_lead: float
    measurement_delay: float
    limit_cycles: tuple[LimitCycle, ...]


def _motorcycle_response(loop: StackLoop, frequencies: Array, state: int) -> CArray:
    """The motorcycle's own response from steer torque to one of its states (continuous)."""
    eye = np.eye(_LATERAL)
    return np.array(
        [
            np.linalg.solve(2j * math.pi * fk * eye - loop.motorcycle, loop.motorcycle_input)[state]
            for fk in frequencies
        ]
    )


def _unstable_count(eigenvalues: NDArray[np.generic], tol: float = 1e-9) -> int:
    return int(np.sum(np.abs(eigenvalues) > 1.0 + tol))


def _margins(loop_gain: CArray, frequencies: Array) -> tuple[float, float, float]:
    """Gain and phase margins and modulus margin of a negative-feedback loop gain G at
    ``frequencies`` [Hz]."""
    # phase crossovers: the gain may rise (|x| < 1) or fall (|x| > 1) this much
    gain_margin = min(
        (abs(20.0 * math.log10(-x)) for _, _, x in negative_real_crossings(loop_gain, frequencies)),
        default=math.inf,
    )
    phase_margin = math.inf
    phase = np.angle(loop_gain)
    magnitude = np.abs(loop_gain)
    for k in range(loop_gain.size - 1):
        if (magnitude[k] - 1.0) * (magnitude[k + 1] - 1.0) < 0.0:
            s = (1.0 - magnitude[k]) / (magnitude[k + 1] - magnitude[k])
            ph = phase[k] + s * (np.angle(loop_gain[k + 1] / loop_gain[k]))
            phase_margin = min(phase_margin, math.degrees(math.pi - abs(ph)))
    last = loop_gain[-1]
    if abs(last.imag) <= 1e-9 * abs(last) and last.real < 0.0:  # real at the Nyquist frequency
        gain_margin = min(gain_margin, abs(20.0 * math.log10(-last.real)))
    return gain_margin, phase_margin, float(np.min(np.abs(1.0 + loop_gain)))


def analyse_stack(
    model: StackModel,
    handlebar: HandlebarParameters,
    speed: float,
    *,
    delay: float | None = None,
    hands: Hands | None = None,
) -> StackLoopAnalysis:
    """Margins, stability, rendered feel and friction limit cycles of the sampled stack.

    Parameters
    ----------
    model : StackModel
        The designed stack (Walcott-Zak estimator).
    handlebar : HandlebarParameters
        The true handlebar.
    speed : float
        Forward speed [m/s].
    delay : float, optional
        The measurement's true age [s] (:func:`stack_loop`); by default the one the stack
        accounts for.
    hands : Hands, optional
        The rider's hands on the handlebar (:func:`stack_loop`): the margins are those of
        the loop with them, the stability and the feel are judged against the motorcycle
        held the same way.

    Returns
    -------
    StackLoopAnalysis
    """
    loop = stack_loop(model, handlebar, speed, delay=delay, hands=hands)
    nyquist = 0.5 / loop.dt
    f = np.append(np.geomspace(0.05, 0.999 * nyquist, _GRID_POINTS - 1), nyquist)
    eig = np.linalg.eigvals(loop.A)
    own = np.linalg.eigvals(zoh(loop.motorcycle, np.zeros((_LATERAL, 1)), loop.dt)[0])
    stable = _unstable_count(eig) <= _unstable_count(own)
    # broken at the motor current: the motor carries u, the estimator is told u
    gain_margin, phase_margin, modulus = _margins(loop.loop_gain(f, LoopInput.current), f)
    inner_gain, inner_phase, _ = _margins(cancellation_loop_gain(loop, f), f)

    band = np.geomspace(FEEL_BAND[0], FEEL_BAND[1], 60)
    rendered = loop.response(band, loop.angle, LoopInput.rider_torque)
    ratio = rendered / _motorcycle_response(loop, band, MotorcycleState.delta)
    feel_db = float(np.max(np.abs(20.0 * np.log10(np.abs(ratio)))))
    feel_deg = float(np.max(np.abs(np.degrees(np.angle(ratio)))))

    admittance = loop.response(f, loop.rate, LoopInput.rider_torque)
    own_admittance = _motorcycle_response(loop, f, MotorcycleState.delta_dot)
    cycles = []
    for k, fk, x in negative_real_crossings(admittance, f):
        if own_admittance[k].real > 0.0:
            rate_amplitude = 4.0 * handlebar.beta_s * (-x) / math.pi
            cycles.append(LimitCycle(fk, rate_amplitude / (2.0 * math.pi * fk)))
    return StackLoopAnalysis(
        speed=float(speed),
        stable=bool(stable),
        spectral_radius=float(np.max(np.abs(eig))),
        gain_margin_db=float(gain_margin),
        phase_margin_deg=float(phase_margin),
        modulus_margin=modulus,
        cancellation_gain_margin_db=float(inner_gain),
        cancellation_phase_margin_deg=float(inner_phase),
        feel_magnitude_db=feel_db,
        feel_phase_deg=feel_deg,
        prediction_lead=(
            float(model.prediction.lead) if model.feedforward.cancellation > 0.0 else 0.0
        ),
        measurement_delay=float(model.delay.age) if delay is None else float(delay),
        limit_cycles=tuple(cycles) if handlebar.beta_s > 0.0 else (),
    )


def robustness_grid(
    model: StackModel,
    handlebar: HandlebarParameters,
    speed: float,
    *,
    inertia: tuple[float, ...] = (0.5, 1.0, 1.5),
    damping: tuple[float, ...] = (0.5, 1.0, 1.5),
    torque_constant: tuple[float, ...] = (0.7, 1.0, 1.3),
    delay: float | None = None,
    hands: Hands | None = None,
) -> list[tuple[tuple[float, float, float], StackLoopAnalysis]]:
    """:func:`analyse_stack` with the true handlebar's J_eq, beta_eq and N k_t scaled.

    The stack keeps its nominal design; each true handlebar has J_eq, beta_eq and k_t
    multiplied by one factor of each tuple; ``delay`` is the measurement's true age [s]
    (by default the one the stack accounts for), ``hands`` the rider's hands on every
    handlebar (by default none).

    Returns
    -------
    list of ((J factor, beta factor, N k_t factor), StackLoopAnalysis)
    """
    out = []
    for fj in inertia:
        for fb in damping:
            for fk in torque_constant:
                true = replace(
                    handlebar,
                    J_eq=handlebar.J_eq * fj,
                    beta_eq=handlebar.beta_eq * fb,
                    k_t=handlebar.k_t * fk,
                    J_m=0.0,
                    beta_vm=0.0,
                )
                analysis = analyse_stack(model, true, speed, delay=delay, hands=hands)
                out.append(((fj, fb, fk), analysis))
    return out


@dataclass(frozen=True, slots=True)
class GridSummary:
    """The worst of :func:`robustness_grid`.

    Attributes
    ----------
    points, unstable : int
        Perturbed handlebars analysed, and how many of them the loop does not stabilise.
    with_margins : int
        How many the loop stabilises with :data:`MARGINS` (gain and phase margins).
    gain_margin_db, phase_margin_deg, modulus_margin : float
        Smallest over the grid [dB, deg, -].
    """

    points: int
    unstable: int
    with_margins: int
    gain_margin_db: float
    phase_margin_deg: float
    modulus_margin: float


def analyse_design(
    sharp: SharpParameters,
    estimator: EstimatorKernel,
    controller: StateSpace,
    handlebar: HandlebarParameters,
    *,
    rate: float,
    speeds: list[float],
    prediction: bool | None = None,
    delay: float = 0.0,
    account: bool = True,
    hands: Hands | None = None,
    true_hands: Hands | None = None,
) -> list[tuple[StackLoopAnalysis, GridSummary]]:
    """A designed observer and controller as the rider would hold them, at each speed.

    The stack of a scenario's defaults (both feedforward terms on, control and measurement at
    ``rate`` [Hz]; the predicted cancellation where ``prediction`` says, by default where
    :func:`~motosim.sim.stack.default_prediction` does, with :func:`prediction_lead`) around
    the nominal ``handlebar``, analysed by :func:`analyse_stack`, and the worst of its
    :func:`robustness_grid`. ``delay`` is the measurement's age when the stack reads it [s]
    (a status frame's latency; 0 to ``1 / rate``); with ``account`` the stack accounts for
    it (:func:`~motosim.sim.stack.account_for_delay`), else it is the stack designed for a
    fresh sample, read ``delay`` old. The predicted cancellation's lead is that of the stack
    designed for a fresh sample, as :func:`motosim.sim.build_stack` gives it to ``motosim
    run`` before the stack accounts for the age (read on the stack that accounts for it, the
    lead would grow with the age).

    ``hands`` are the rider's hands the stack is designed for (by default none): give then
    ``estimator`` and ``controller`` designed for :func:`~motosim.sim.grips.held_handlebar`
    of ``handlebar`` and these hands, and the stack models them
    (:func:`~motosim.sim.stack.design_stack`). ``true_hands`` are those on the handlebar
    in every loop analysed (:func:`analyse_stack`), by default ``hands`` (``GRIPS["off"]``:
    the rider has let go).
    """
    holding = hands if true_hands is None else true_hands
    designed_for = held_handlebar(handlebar, hands)

    def build(speed: float, lead: float = 0.0) -> StackModel:
        return design_stack(
            sharp,
            estimator,
            controller,
            control_rate=rate,
            measurement_rate=rate,
            lipschitz=300.0,
            max_current=30.0,
            speed=speed,
            handlebar=designed_for,
            rider_feedforward=True,
            reference_feedforward=True,
            prediction_lead=lead,
            measurement_delay=delay if account else 0.0,
            hands=hands,
        )

    out = []
    predict = default_prediction(rate) if prediction is None else prediction
    for speed in speeds:
        model = build(speed)
        if predict:  # the lead of the stack designed for a fresh sample, as build_stack's
            fresh = model._replace(delay=NO_DELAY)
            model = build(speed, prediction_lead(fresh, designed_for))
        grid = [a for _, a in robustness_grid(model, handlebar, speed, delay=delay, hands=holding)]
        summary = GridSummary(
            points=len(grid),
            unstable=sum(not a.stable for a in grid),
            with_margins=sum(
                a.stable and a.gain_margin_db >= MARGINS[0] and a.phase_margin_deg >= MARGINS[1]
                for a in grid
            ),
            gain_margin_db=min(a.gain_margin_db for a in grid),
            phase_margin_deg=min(a.phase_margin_deg for a in grid),
            modulus_margin=min(a.modulus_margin for a in grid),
        )
        nominal = analyse_stack(model, handlebar, speed, delay=delay, hands=holding)
        out.append((nominal, summary))
    return out
