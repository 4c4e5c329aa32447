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
from enum import IntEnum
from typing import Any, NamedTuple

import numpy as np
from numba import njit
from numba.extending import overload
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.estimation.differentiator import LAMBDA_0, LAMBDA_1, cell_step, std_step
from motosim.estimation.kernel import TORQUE_SENSOR, WALCOTT_ZAK, EstimatorKernel
from motosim.estimation.registry import start_kernel, step_kernel
from motosim.model import sharp as sharp_model
from motosim.model import tyred
from motosim.model.handlebar import matrices as handlebar_matrices
from motosim.model.linear import StateSpace, zoh
from motosim.model.sharp import MotorcycleState, RK4Work, bike_rk4, rk4_work
from motosim.params.handlebar import HandlebarParameters
from motosim.params.sharp import SharpParameters, derived_geometry
from motosim.sim.grips import Hands

__all__ = [
    "DELAY_FRICTION_WIDTH",
    "NO_DELAY",
    "NO_FEEDFORWARD",
    "NO_PREDICTION",
    "NO_QUIET",
    "PREDICTION_CORNER",
    "PREDICTION_NOTCH",
    "PREDICTION_PAPER_RATE",
    "PREDICTION_RATE",
    "Delay",
    "DifferentiatorGains",
    "DifferentiatorState",
    "Feedforward",
    "Held",
    "MotorcycleInput",
    "MotorcycleState",
    "MultibodyMotorcycle",
    "Prediction",
    "Quiet",
    "SharpMotorcycle",
    "StackData",
    "StackModel",
    "account_for_delay",
    "contact_loads",
    "dahl_friction",
    "default_prediction",
    "design_stack",
    "is_multibody",
    "new_data",
    "outside",
    "pitch",
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
sticking (a wider tanh triples the crosswind run's tracking error: ``docs/performance.md``,
"Figures behind the code's constants")."""
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


class Held(IntEnum):
    """Positions in the outputs held between measurements (:attr:`StackData.held`)."""

    theta_h_meas = 0
    """The measured handlebar angle [rad]."""
    i_m = 1
    """The current command [A]."""
    theta_h_dot_hat = 2
    """The differentiated handlebar rate [rad/s]."""
    tau_r_hat = 3
    """The estimated rider torque [N*m]."""
    tau_r_hat_rate = 4
    """The predicted cancellation's filtered rate of tau_r_hat [N*m/s]."""
    notch_0 = 5
    """The first state of the prediction's notch [N*m/s]."""
    notch_1 = 6
    """Its second state [N*m/s]."""
    low_pass = 7
    """The state of its low-pass [N*m/s]."""
    friction_feedforward = 8
    """The reference feedforward's dry-friction torque, with presliding memory [N*m]."""
    still = 9
    """Measurements in a row with the same encoder count [-]."""


class DifferentiatorState(IntEnum):
    """Positions in the super-twisting differentiator's state
    (:attr:`StackData.differentiator`)."""

    z0 = 0
    """The angle it tracks [rad]."""
    z1 = 1
    """The rate it estimates [rad/s]."""


class MotorcycleInput(IntEnum):
    """Positions in the multibody motorcycle's inputs this period
    (:attr:`StackData.inputs`), which the world around the stack sets before a step; Sharp
    1971 reads eq. (2)'s longitudinal force instead."""

    drive_torque = 0
    """On the rear wheel [N*m], positive driving forward."""
    front_brake_torque = 1
    """[N*m], >= 0."""
    rear_brake_torque = 2
    """[N*m], >= 0."""
    friction = 3
    """The road's friction coefficient mu [-]."""


class DifferentiatorGains(NamedTuple):
    """The super-twisting differentiator's step and gains."""

    h: float
    """Its step, the measurement step [s]."""
    k1: float
    """lambda_1 L^(1/2) [rad^(1/2)/s]."""
    k0: float
    """lambda_0 L [rad/s^2]."""


class Prediction(NamedTuple):
    """The predicted cancellation, tau_r_hat + T_d r with r the estimate's rate through a
    notch and a low-pass (see :func:`step`); all zero for none."""

    lead: float
    """T_d [s] (0: the cancellation reads tau_r_hat as it is)."""
    g: float
    """The low-pass's gain, g (1 + 1/z) / (1 - p / z) [-]."""
    pole: float
    """Its pole p [-]."""
    b0: float
    """The notch's numerator, b0 + b1 / z + b2 / z^2 [-]."""
    b1: float
    b2: float
    a1: float
    """Its denominator, 1 + a1 / z + a2 / z^2 [-]."""
    a2: float


class Feedforward(NamedTuple):
    """The feedforward terms on the nominal handlebar (see :func:`step`)."""

    cancellation: float
    """The rider-torque cancellation's gain (0 to 1)."""
    reference: float
    """The reference inverse dynamics' gain (0 or 1)."""
    J_eq: float
    """[kg*m^2]."""
    beta_eq: float
    """[N*m*s/rad]."""
    beta_s: float
    """[N*m]."""
    torque_per_amp: float
    """N k_t [N*m/A]."""
    friction_width: float
    """The tanh width of the friction term [rad/s]."""


class Quiet(NamedTuple):
    """How the stack keeps the encoder's counts and the handlebar's sticking out of its
    command (see :func:`step_scaled` and :func:`_command`); all zero for none.

    Three loops make a current buzz on a handlebar held steady: a count edge read as a rate
    spike, the reference feedforward's friction sign flipped by the virtual motorcycle's
    wobble, and the parts that integrate while the handlebar sticks, where the rider's
    torque is unobservable. Each setting breaks one.
    """

    quantum: float
    """q, the encoder's count [rad] that the differentiator knows (0: it reads the count as
    the angle). It predicts the angle and corrects only by how far the prediction left the
    measured count's cell [theta_meas - q/2, theta_meas + q/2], with the gains below; the
    controller and the estimator read its in-cell angle."""
    position_gain: float
    """a, the share of the distance outside the cell taken into the angle [-]."""
    rate_gain: float
    """b, the share of that distance over one step taken into the rate [-]."""
    presliding: float
    """x_0, the steer displacement over which the reference feedforward's friction term
    reverses (a Dahl friction, dF/dx = (beta_s sign(dx) - F) / x_0) [rad]; 0: the tanh of
    the steer rate."""
    release: float
    """With ``presliding``, the time constant over which the friction term relaxes to 0
    while the steer rests [s] (0: it keeps its value, the Dahl model's): a handlebar held
    still needs no friction torque, and one pushed at the friction's edge creeps."""
    stick_samples: int
    """Measurements in a row on the same count after which the handlebar is taken to stick:
    the controller's state and the estimator (not a torque sensor, which measures) are then
    held until the count changes (0: never)."""


class Delay(NamedTuple):
    """How the stack accounts for a measurement's age d (see :func:`step_scaled` and
    :func:`account_for_delay`); all zero for a fresh measurement."""

    age: float
    """d [s] (0: fresh, nothing else is read)."""
    carried: float
    """d / h, the share of the observer's step over which the previous command was
    carried [-]."""
    per_rate: float
    """The nominal handlebar's angle per initial rate over d [s]."""
    per_torque: float
    """Its angle per torque over d [rad/(N*m)]."""
    beta_s: float
    """Its dry friction [N*m]."""
    torque_per_amp: float
    """Its N k_t [N*m/A]."""
    friction_width: float
    """The rate scale of the friction's tanh [rad/s]."""


class SharpMotorcycle(NamedTuple):
    """The virtual motorcycle as Sharp's (1971) linear lateral model with eq. (2)."""

    m: float
    """Its mass [kg]."""
    m_eq: float
    """m + J_R / r_D^2 [kg]."""
    min_speed: float
    """The lowest speed of the model [m/s]."""
    substeps: int
    """RK4 steps per stack period."""
    rear_load: float
    """The rear tyre's normal load, m g + Z_f [N]."""
    front_load: float
    """The front tyre's, -Z_f [N]."""


class MultibodyMotorcycle(NamedTuple):
    """The virtual motorcycle as the multibody model on tyres (:mod:`motosim.model.tyred`)."""

    model: tyred.TyredModel
    """Its compiled constants."""
    start: Array
    """The compiled state at :func:`reset`: upright straight running at the start speed on
    the tyres' static compression."""
    substeps: int
    """RK4 steps per stack period."""


NO_PREDICTION = Prediction(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
"""No predicted cancellation (the cancellation reads tau_r_hat as it is)."""
NO_FEEDFORWARD = Feedforward(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
"""No feedforward term."""
NO_DELAY = Delay(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
"""A fresh measurement."""
NO_QUIET = Quiet(0.0, 0.0, 0.0, 0.0, 0.0, 0)
"""None of :class:`Quiet`'s settings: the count read as the angle, the tanh friction term,
nothing held while the handlebar sticks."""

_LATERAL = int(MotorcycleState.v_x)
"""The motorcycle's lateral states, Sharp 1971's eight, come before v_x."""


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
    differentiator : DifferentiatorGains
        The super-twisting differentiator's step and gains.
    Ad, Bd, Cd, Dd : ndarray
        Discrete controller at the measurement step (x+ = Ad x + Bd e, i = Cd x + Dd e,
        e = theta_h - delta [rad], i [A]); order 0 with Dd = 0 when there is no feedback.
    feedback : bool
        Whether the controller commands the motor (False: Fig. 9, 0 A).
    prediction : Prediction
        The predicted cancellation (see :func:`step`).
    feedforward : Feedforward
        The feedforward terms of the nominal handlebar (see :func:`step`).
    max_current : float
        Current command limit [A].
    A0, A1, Bv : ndarray
        The motorcycle's lateral matrices in the order of :class:`MotorcycleState`,
        A_v = A0 + v_x A1 (8x8), B_v (8,): Sharp 1971's, or the multibody model's
        linearised about upright running at the start speed (A1 = 0), which the loop's
        analysis reads.
    Bw : ndarray, shape (8,)
        The side force's input (:func:`motosim.model.sharp.side_force_input`).
    motorcycle : SharpMotorcycle or MultibodyMotorcycle
        The virtual motorcycle the step advances.
    speed : float
        Forward speed at :func:`reset` [m/s].
    true_torque : bool
        Drive the motorcycle with the rider's true torque instead of the estimate
        (a simulation-only reference run).
    delay : Delay
        How the stack accounts for the measurement's age d when it reads it (a status
        frame's latency on the bus).
    quiet : Quiet
        How it keeps the encoder's counts and the handlebar's sticking out of its command.
    """

    dt: float
    measure_every: int
    estimator: EstimatorKernel
    differentiator: DifferentiatorGains
    Ad: Array
    Bd: Array
    Cd: Array
    Dd: Array
    feedback: bool
    prediction: Prediction
    feedforward: Feedforward
    max_current: float
    A0: Array
    A1: Array
    Bv: Array
    Bw: Array
    motorcycle: SharpMotorcycle | MultibodyMotorcycle
    speed: float
    true_torque: bool
    delay: Delay
    quiet: Quiet = NO_QUIET


class StackData(NamedTuple):
    """Every state of the stack that changes during a run (make with :func:`new_data`).

    Attributes
    ----------
    estimator : ndarray, shape (4,)
        The estimator's state.
    differentiator : ndarray, shape (len(DifferentiatorState),)
        The differentiator's state, in the order of :class:`DifferentiatorState`.
    controller : ndarray, shape (n,)
        The discrete controller's state.
    motorcycle : ndarray, shape (12,)
        The virtual motorcycle's state, in the order of :class:`MotorcycleState` (SI units;
        an array: its RK4 steps it whole). With the multibody motorcycle, what its state
        reads as in these names (the rear wheel centre's lateral velocity, the rear
        contact's position).
    multibody : ndarray, shape (20,) or (0,)
        The multibody motorcycle's state, in the order of :class:`motosim.model.tyred.Index`.
    inputs : ndarray, shape (4,)
        The multibody motorcycle's inputs this period, in the order of
        :class:`MotorcycleInput`.
    held : ndarray, shape (len(Held),)
        Outputs held between measurements, in the order of :class:`Held`.
    periods : ndarray of int64, shape (1,)
        Periods since :func:`reset`.
    work : RK4Work
        Scratch space of the motorcycle's RK4.
    controller_work : ndarray
        Scratch space of the controller (at least one entry).
    """

    estimator: Array
    differentiator: Array
    controller: Array
    motorcycle: Array
    multibody: Array
    inputs: Array
    held: Array
    periods: NDArray[np.int64]
    work: RK4Work
    controller_work: Array


def default_prediction(measurement_rate: float) -> bool:
    """Whether a stack that cancels the estimated rider torque predicts it, by default.

    On from :data:`PREDICTION_RATE` and at the paper's :data:`PREDICTION_PAPER_RATE`, the
    rates where it was measured on runs: there it keeps the robustness grid's margins, cuts
    the tracking error the estimate's lag leaves on fast manoeuvres and keeps the real-time
    safety stage's frozen-angle measure well below its fault; between, off (the design
    guide, "The predicted cancellation"; the figures in ``docs/performance.md``, "Figures
    behind the code's constants").

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
    multibody: tyred.TyredModel | None = None,
    hands: Hands | None = None,
    quiet: Quiet = NO_QUIET,
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
    multibody : TyredModel, optional
        The virtual motorcycle as the multibody model on tyres (:mod:`motosim.model.tyred`)
        instead of Sharp's ``sharp``, which then only sets the side force's input.
    hands : Hands, optional
        The rider's hands the stack is designed for: give with them ``handlebar`` and an
        estimator and controller designed for :func:`~motosim.sim.grips.held_handlebar`;
        the virtual motorcycle carries the arms' inertia and damping on its front frame
        (:func:`~motosim.model.sharp.held_steering`, :func:`~motosim.model.tyred.held`),
        their stiffness reaching it through the estimate.
    quiet : Quiet
        How the stack keeps the encoder's counts and the handlebar's sticking out of its
        command; none by default (measured in the simulate guide, "The buzz, loop by
        loop").

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
        if controller.is_discrete:
            K = controller
        else:  # SciPy's signal module only when a continuous controller is discretised here
            from motosim.control.torque_feedback import discretize

            K = discretize(controller, h_meas, discretization)
        Ad, Bd, Cd, Dd = K.A, K.B, K.C, K.D
    if (rider_feedforward or reference_feedforward) and handlebar is None:
        raise MotosimError("feedforward needs the nominal handlebar; give handlebar=")
    on = controller is not None
    prediction = NO_PREDICTION
    if on and rider_feedforward and prediction_lead != 0.0:
        prediction = _prediction(prediction_lead, h_meas)
    ff = NO_FEEDFORWARD
    if handlebar is not None:
        ff = Feedforward(
            cancellation=float(on and rider_feedforward),
            reference=float(on and reference_feedforward),
            J_eq=float(handlebar.J_eq),
            beta_eq=float(handlebar.beta_eq),
            beta_s=float(handlebar.beta_s),
            torque_per_amp=float(handlebar.torque_per_amp),
            friction_width=FEEDFORWARD_FRICTION_WIDTH,
        )
    h = 1.0 / control_rate
    substeps = max(1, math.ceil(h / MOTORCYCLE_STEP - 1e-9))
    motorcycle: SharpMotorcycle | MultibodyMotorcycle
    Bw = sharp_model.side_force_input(sharp, height=side_force_height)
    # the arms' inertia and damping on the front frame, their stiffness in the estimate
    arms = None if hands is None or hands.is_off else hands
    if multibody is None:
        d = derived_geometry(sharp)
        A0, A1, Bv = sharp_model.lpv_matrices(sharp)
        if arms is not None:
            A1 = sharp_model.held_steering(A1, Bv, arms.inertia, 0.0, 0.0)[0]
            A0, Bv, held_Bw = sharp_model.held_steering(A0, Bv, arms.inertia, arms.damping, 0.0, Bw)
            assert held_Bw is not None
            Bw = held_Bw
        motorcycle = SharpMotorcycle(
            float(d["m"]),
            float(d["m_eq"]),
            float(sharp_model.MIN_SPEED),
            substeps,
            float(d["m"] * sharp.g + sharp.Z_f),
            float(-sharp.Z_f),
        )
    else:
        if arms is not None:
            multibody = tyred.held(multibody, arms.inertia, arms.damping)
        A0, Bv = _multibody_lateral(multibody, speed)
        A1 = np.zeros_like(A0)
        start = np.array(tyred.upright_state(multibody, speed), dtype=np.float64)
        motorcycle = MultibodyMotorcycle(multibody, start, substeps)
    return StackModel(
        dt=h,
        measure_every=round(ratio),
        estimator=estimator,
        differentiator=DifferentiatorGains(
            h_meas, LAMBDA_1 * math.sqrt(lipschitz), LAMBDA_0 * lipschitz
        ),
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
        Bw=Bw,
        motorcycle=motorcycle,
        speed=float(speed),
        true_torque=bool(true_torque),
        delay=_delay(measurement_delay, h_meas, handlebar, estimator),
        quiet=_checked_quiet(quiet),
    )


def _checked_quiet(quiet: Quiet) -> Quiet:
    """``quiet`` with its fields as floats and int; MotosimError naming one out of range."""
    bounds = (
        ("quantum", quiet.quantum, 0.1),
        ("presliding", quiet.presliding, 0.1),
        ("release", quiet.release, 100.0),
    )
    for name, value, high in bounds:
        if not (math.isfinite(value) and 0.0 <= value <= high):
            raise MotosimError(f"quiet {name} = {value!r}; expected 0 to {high:g}")
    for name, value in (("position_gain", quiet.position_gain), ("rate_gain", quiet.rate_gain)):
        if quiet.quantum > 0.0 and not (math.isfinite(value) and 0.0 < value <= 1.0):
            raise MotosimError(f"quiet {name} = {value!r}; expected a share in (0, 1]")
    if not (0 <= quiet.stick_samples <= 100_000):
        raise MotosimError(f"quiet stick_samples = {quiet.stick_samples!r}; expected 0 to 100000")
    return Quiet(
        float(quiet.quantum),
        float(quiet.position_gain),
        float(quiet.rate_gain),
        float(quiet.presliding),
        float(quiet.release),
        int(quiet.stick_samples),
    )


_AS_SHARP = {
    MotorcycleState.v_y: tyred.Index.lateral,
    MotorcycleState.psi_dot: tyred.Index.yaw_rate,
    MotorcycleState.phi_dot: tyred.Index.roll_rate,
    MotorcycleState.delta_dot: tyred.Index.steer_rate,
    MotorcycleState.phi: tyred.Index.roll,
    MotorcycleState.delta: tyred.Index.steer,
    MotorcycleState.F_yr: tyred.Index.Fy_r,
    MotorcycleState.F_yf: tyred.Index.Fy_f,
}
"""The multibody state that reads as each of Sharp 1971's lateral states (the
:func:`_multibody_view` of the side forces: those the tyres apply)."""
_FROM_TYRED_LATERAL = tuple(tyred.LATERAL.index(_AS_SHARP[s]) for s in sorted(_AS_SHARP))
"""Sharp 1971's lateral states (:class:`MotorcycleState` up to ``v_x``) among those of
:func:`motosim.model.tyred.lateral_system`."""


def _multibody_lateral(model: tyred.TyredModel, speed: float) -> tuple[Array, Array]:
    """The multibody motorcycle's lateral A (8x8) and steer-torque input (8,) about upright
    running at ``speed`` [m/s], in the order of :class:`MotorcycleState`."""
    A, B = tyred.lateral_system(model, speed)
    order = list(_FROM_TYRED_LATERAL)
    return np.ascontiguousarray(A[np.ix_(order, order)]), np.ascontiguousarray(B[order])


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
    d, and a cancelling loop feeds it back). Designed for a fresh sample, a stack read a
    bus latency late can lose its margins altogether; accounting for the age keeps them
    (:func:`motosim.sim.loop_analysis.stack_loop` with ``delay``; the figures of the 100 Hz
    lane change in ``docs/performance.md``, "Figures behind the code's constants").
    """
    h = model.dt * model.measure_every
    return model._replace(delay=_delay(delay, h, handlebar, model.estimator))


def _delay(
    delay: float, h: float, handlebar: HandlebarParameters | None, estimator: EstimatorKernel
) -> Delay:
    """:attr:`StackModel.delay` for a measurement ``delay`` d [s] at the measurement step
    ``h`` [s] on the nominal ``handlebar``, the friction's tanh as wide as the Walcott-Zak
    ``estimator``'s (else :data:`DELAY_FRICTION_WIDTH`); MotosimError if d is not in [0, h],
    or is positive without a handlebar."""
    if not (math.isfinite(delay) and 0.0 <= delay <= h * (1.0 + 1e-12)):
        raise MotosimError(
            f"measurement delay = {delay!r} s; expected 0 to one measurement step ({h:g} s)"
        )
    if delay == 0.0:
        return NO_DELAY
    if handlebar is None:
        raise MotosimError("a measurement delay needs the nominal handlebar; give handlebar=")
    hb = handlebar_matrices(handlebar)
    phi, gamma = zoh(hb.A, hb.D[:, None], delay)
    return Delay(
        age=float(delay),
        carried=min(delay / h, 1.0),
        per_rate=float(phi[1, 0]),
        per_torque=float(gamma[1, 0]),
        beta_s=float(handlebar.beta_s),
        torque_per_amp=float(handlebar.torque_per_amp),
        friction_width=_friction_width(estimator),
    )


def _friction_width(estimator: EstimatorKernel) -> float:
    """The rate scale of the Walcott-Zak observer's friction tanh [rad/s] (its setting
    ``friction_width``, in its kernel's parameters), else :data:`DELAY_FRICTION_WIDTH`."""
    if estimator.kind == WALCOTT_ZAK and estimator.walcott_zak.friction_width > 0.0:
        return estimator.walcott_zak.friction_width
    return DELAY_FRICTION_WIDTH


def _prediction(lead: float, h: float) -> Prediction:
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
    return Prediction(
        lead=float(lead),
        g=0.5 * (1.0 - pole),
        pole=pole,
        b0=(k * k + w0 * w0) / den,
        b1=2.0 * (w0 * w0 - k * k) / den,
        b2=(k * k + w0 * w0) / den,
        a1=2.0 * (w0 * w0 - k * k) / den,
        a2=(k * k - w0 * k / q + w0 * w0) / den,
    )


def new_data(model: StackModel) -> StackData:
    """Fresh, zeroed data for ``model``; call :func:`reset` before the first step."""
    n = model.Ad.shape[0]
    return StackData(
        estimator=np.zeros(4),
        differentiator=np.zeros(len(DifferentiatorState)),
        controller=np.zeros(n),
        motorcycle=np.zeros(len(MotorcycleState)),
        multibody=np.zeros(
            tyred.N_STATE if isinstance(model.motorcycle, MultibodyMotorcycle) else 0
        ),
        inputs=np.zeros(len(MotorcycleInput)),
        held=np.zeros(len(Held)),
        periods=np.zeros(1, dtype=np.int64),
        work=rk4_work(),
        controller_work=np.zeros(max(1, n)),
    )


@njit(cache=True)
def reset(model: StackModel, data: StackData, theta: float, current: float) -> None:
    """Start every state at a first measurement.

    The differentiator and the estimator start at the angle ``theta`` [rad] (rate 0) and the
    current ``current`` [A]; the controller at rest; the motorcycle upright and straight at
    ``model.speed``.
    """
    data.differentiator[DifferentiatorState.z0] = theta
    data.differentiator[DifferentiatorState.z1] = 0.0
    start_kernel(model.estimator, data.estimator, theta, 0.0, current)
    data.controller[:] = 0.0
    _start(model.motorcycle, data, model.speed)
    data.held[:] = 0.0
    data.held[Held.theta_h_meas] = theta
    data.periods[0] = 0


@njit(cache=True)
def dahl_friction(
    friction: float, dx: float, beta_s: float, presliding: float, h: float, release: float
) -> float:
    """A Dahl friction torque after a displacement ``dx`` [rad] over a step ``h`` [s].

    dF/dx = (beta_s sign(dx) - F) / x_0, integrated exactly over ``dx``: the torque
    approaches +-beta_s [N*m] over a few x_0 = ``presliding`` [rad] of displacement in
    one direction, so a wobble of amplitude A << x_0 moves it by about 2 beta_s A / x_0
    (the tanh of the rate would flip it by 2 beta_s at each reversal). With ``release``
    T > 0 [s] it then relaxes by exp(-h / T) towards 0, the value a handlebar held still
    needs.

    Examples
    --------
    >>> round(dahl_friction(0.0, 1e-3, 2.0, 1e-3, 1e-3, 0.0), 6)  # one x_0: 1 - 1/e
    1.264241
    """
    target = beta_s if dx > 0.0 else -beta_s
    friction = target - (target - friction) * math.exp(-abs(dx) / presliding)
    if release > 0.0:
        friction *= math.exp(-h / release)
    return friction


@njit(cache=True, inline="always")
def _command(model: StackModel, data: StackData, theta_meas: float, stuck: bool) -> float:
    """The motor current for this sample, saturated; advances the controller's state
    unless the handlebar is ``stuck`` (its state is then held).

    Feedback i = K (theta_h - delta), positive feedback (eq. (24)), plus the feedforward
    terms switched on in ``model.feedforward``: the estimated rider torque cancelled, and the
    nominal handlebar's inverse dynamics along the steer angle delta of the motorcycle, its
    dry friction the tanh of the steer rate or, with ``model.quiet.presliding``, a Dahl
    friction of the steer displacement.
    """
    if not model.feedback:
        return 0.0
    z = data.motorcycle
    e = theta_meas - z[MotorcycleState.delta]
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
    if not stuck:
        for r in range(n):
            x[r] = tmp[r]
    ff = model.feedforward
    torque = 0.0
    if ff.cancellation > 0.0:  # cancel what the rider is estimated to apply
        cancelled = data.held[Held.tau_r_hat]
        if model.prediction.lead > 0.0:  # predicted: tau_r_hat + T_d LP(notch(d tau_r_hat / dt))
            cancelled += model.prediction.lead * data.held[Held.tau_r_hat_rate]
        torque -= ff.cancellation * cancelled
    if ff.reference > 0.0:  # J delta'' + beta delta' + beta_s sign(delta'), delta'' from the model
        dd = _steer_acceleration(model.motorcycle, model, data, data.held[Held.tau_r_hat])
        rate = z[MotorcycleState.delta_dot]
        qt = model.quiet
        if qt.presliding > 0.0:  # a Dahl friction of the steer displacement
            h = model.differentiator.h
            friction = dahl_friction(
                data.held[Held.friction_feedforward],
                rate * h,
                ff.beta_s,
                qt.presliding,
                h,
                qt.release,
            )
            data.held[Held.friction_feedforward] = friction
        else:
            friction = ff.beta_s * math.tanh(rate / ff.friction_width)
        torque += ff.J_eq * dd + ff.beta_eq * rate + friction
    if ff.cancellation > 0.0 or ff.reference > 0.0:
        u += torque / ff.torque_per_amp
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
    command for the share of its step that it was carried. With ``model.quiet`` the
    differentiator knows the encoder's count and the controller and the estimator read its
    in-cell angle, and while the handlebar sticks the controller's state and the estimate
    are held (:class:`Quiet`).

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
        Longitudinal force of eq. (2), (tau_d - tau_b) / r_D + F_wx [N] (Sharp 1971; the
        multibody motorcycle reads its torques in ``data.inputs`` instead).
    side_force : float
        Side force on Sharp 1971's motorcycle (a side wind), to the right [N].
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
        qt = model.quiet
        held[Held.still] = held[Held.still] + 1.0 if theta_meas == held[Held.theta_h_meas] else 0.0
        stuck = qt.stick_samples > 0 and held[Held.still] >= qt.stick_samples
        held[Held.theta_h_meas] = theta_meas
        g = model.differentiator
        z0_before = data.differentiator[DifferentiatorState.z0]
        z1_before = data.differentiator[DifferentiatorState.z1]
        if qt.quantum > 0.0:  # the count's cell, not its centre: the angle read is z0
            z0, z1 = cell_step(
                z0_before,
                z1_before,
                theta_meas,
                g.h,
                qt.quantum,
                qt.position_gain,
                qt.rate_gain,
            )
            angle = z0
        else:
            z0, z1 = std_step(z0_before, z1_before, theta_meas, g.h, g.k1, g.k0, True)
            angle = theta_meas
        dl = model.delay
        if dl.age > 0.0:  # a measurement d old: the angle now, predicted over d
            previous = held[Held.i_m]  # the command carried since the last measurement
            rate = z1 + 0.5 * (z1 - z1_before)  # the backward difference, at the sample
            torque = dl.torque_per_amp * current_scale * previous + held[Held.tau_r_hat]
            slide = math.tanh(rate / dl.friction_width)
            stick = min(max(torque, -dl.beta_s), dl.beta_s)
            torque -= dl.beta_s * slide + (1.0 - abs(slide)) * stick
            predicted = angle + dl.per_rate * rate + dl.per_torque * torque
            held[Held.i_m] = _command(model, data, predicted, stuck)
            told = (1.0 - dl.carried) * held[Held.i_m] + dl.carried * previous
        else:
            held[Held.i_m] = _command(model, data, angle, stuck)
            told = held[Held.i_m]
        data.differentiator[DifferentiatorState.z0] = z0
        data.differentiator[DifferentiatorState.z1] = z1
        held[Held.theta_h_dot_hat] = z1
        if stuck and model.estimator.kind != TORQUE_SENSOR:  # unobservable: hold the estimate
            estimate = held[Held.tau_r_hat]
        else:
            estimate = step_kernel(
                model.estimator,
                data.estimator,
                angle,
                z1,
                current_scale * told + current_error,
                rider_torque,
            )
        c = model.prediction
        if c.lead > 0.0:
            # the estimate's rate through the notch and the low-pass (transposed form II)
            x = (estimate - held[Held.tau_r_hat]) / g.h
            y = c.b0 * x + held[Held.notch_0]
            held[Held.notch_0] = c.b1 * x - c.a1 * y + held[Held.notch_1]
            held[Held.notch_1] = c.b2 * x - c.a2 * y
            held[Held.tau_r_hat_rate] = c.g * y + held[Held.low_pass]
            held[Held.low_pass] = c.g * y + c.pole * held[Held.tau_r_hat_rate]
        held[Held.tau_r_hat] = estimate
    data.periods[0] += 1
    steer = rider_torque if model.true_torque else held[Held.tau_r_hat]
    _advance(model.motorcycle, model, data, steer, force, side_force)
    return float(held[Held.i_m])


# The virtual motorcycle's parts of the step, one implementation per kind of motorcycle:
# numba picks the one of the motorcycle's type when it compiles the step (through the
# overloads below: a stack on Sharp 1971 never compiles the multibody model), and plain
# Python (NUMBA_DISABLE_JIT=1) dispatches on the type.


def _start_sharp(mc: Any, data: StackData, speed: float) -> None:
    data.motorcycle[:] = 0.0
    data.motorcycle[MotorcycleState.v_x] = speed


def _start_multibody(mc: Any, data: StackData, speed: float) -> None:
    for i in range(data.multibody.size):
        data.multibody[i] = mc.start[i]
    data.inputs[:] = 0.0
    data.inputs[MotorcycleInput.friction] = 1.0
    _multibody_view(mc, data)


def _advance_sharp(
    mc: Any,
    model: StackModel,
    data: StackData,
    steer: float,
    force: float,
    side_force: float,
) -> None:
    h = model.dt / mc.substeps
    for _ in range(mc.substeps):
        bike_rk4(
            data.motorcycle,
            data.work,
            model.A0,
            model.A1,
            model.Bv,
            steer,
            model.Bw,
            side_force,
            force,
            mc.m,
            mc.m_eq,
            mc.min_speed,
            h,
        )


@njit(cache=True, inline="always")
def _multibody_inputs(data: StackData, steer: float) -> tyred.Inputs:
    u = data.inputs
    return tyred.Inputs(
        steer,
        u[MotorcycleInput.drive_torque],
        u[MotorcycleInput.front_brake_torque],
        u[MotorcycleInput.rear_brake_torque],
        u[MotorcycleInput.friction],
    )


def _advance_multibody(
    mc: Any,
    model: StackModel,
    data: StackData,
    steer: float,
    force: float,
    side_force: float,
) -> None:
    h = model.dt / mc.substeps
    inputs = _multibody_inputs(data, steer)
    x = data.multibody
    for _ in range(mc.substeps):
        after = tyred.advance(mc.model, x, inputs, h)
        for i in range(x.size):
            x[i] = after[i]
    _multibody_view(mc, data)


@njit(cache=True)
def _multibody_view(mc: MultibodyMotorcycle, data: StackData) -> None:
    """The multibody state in the names of :class:`MotorcycleState`: the rear wheel
    centre's lateral velocity, the rear contact's ground position, the side forces the tyres
    apply."""
    x, z = data.multibody, data.motorcycle
    Ix = tyred.Index
    loads = tyred.observe(mc.model, x, data.inputs[MotorcycleInput.friction])
    z[MotorcycleState.v_y] = x[Ix.lateral]
    z[MotorcycleState.phi_dot] = x[Ix.roll_rate]
    z[MotorcycleState.psi_dot] = x[Ix.yaw_rate]
    z[MotorcycleState.delta_dot] = x[Ix.steer_rate]
    z[MotorcycleState.phi] = x[Ix.roll]
    z[MotorcycleState.delta] = x[Ix.steer]
    z[MotorcycleState.F_yr] = loads.F_yr
    z[MotorcycleState.F_yf] = loads.F_yf
    z[MotorcycleState.v_x] = x[Ix.forward]
    z[MotorcycleState.psi] = x[Ix.yaw]
    z[MotorcycleState.x] = loads.x_r
    z[MotorcycleState.y] = loads.y_r


def _steer_acceleration_sharp(mc: Any, model: StackModel, data: StackData, torque: float) -> float:
    z = data.motorcycle
    v = z[MotorcycleState.v_x]
    j = MotorcycleState.delta_dot
    dd = model.Bv[j] * torque
    for c in range(_LATERAL):
        dd += (model.A0[j, c] + v * model.A1[j, c]) * z[c]
    return float(dd)


def _steer_acceleration_multibody(
    mc: Any, model: StackModel, data: StackData, torque: float
) -> float:
    rates = tyred.rates(mc.model, data.multibody, _multibody_inputs(data, torque))
    return float(rates[tyred.Index.steer_rate])


def _contact_loads_sharp(
    mc: Any, model: StackModel, data: StackData, force: float
) -> tyred.ContactLoads:
    z = data.motorcycle
    return tyred.ContactLoads(
        force,
        z[MotorcycleState.F_yr],
        mc.rear_load,
        0.0,
        0.0,
        0.0,
        z[MotorcycleState.F_yf],
        mc.front_load,
        0.0,
        0.0,
        z[MotorcycleState.x],
        z[MotorcycleState.y],
    )


def _contact_loads_multibody(
    mc: Any, model: StackModel, data: StackData, force: float
) -> tyred.ContactLoads:
    return tyred.observe(mc.model, data.multibody, data.inputs[MotorcycleInput.friction])


def is_multibody(mc: Any) -> bool:
    """Whether ``mc``, a motorcycle or its numba type, is a :class:`MultibodyMotorcycle` (for
    the parts of compiled code that differ by motorcycle, through ``numba.extending.overload``)."""
    return isinstance(mc, MultibodyMotorcycle) or (
        getattr(mc, "instance_class", None) is MultibodyMotorcycle
    )


def _start(mc: Any, data: StackData, speed: float) -> None:
    """Start the motorcycle upright and straight at ``speed`` [m/s]."""
    if is_multibody(mc):
        return _start_multibody(mc, data, speed)
    return _start_sharp(mc, data, speed)


def _advance(
    mc: Any, model: StackModel, data: StackData, steer: float, force: float, side_force: float
) -> None:
    """Advance the motorcycle one stack period under the steer torque ``steer`` [N*m]."""
    if is_multibody(mc):
        return _advance_multibody(mc, model, data, steer, force, side_force)
    return _advance_sharp(mc, model, data, steer, force, side_force)


def _steer_acceleration(mc: Any, model: StackModel, data: StackData, torque: float) -> float:
    """The motorcycle's steer acceleration now under the steer torque ``torque`` [rad/s^2]."""
    if is_multibody(mc):
        return _steer_acceleration_multibody(mc, model, data, torque)
    return _steer_acceleration_sharp(mc, model, data, torque)


def _contact_loads(mc: Any, model: StackModel, data: StackData, force: float) -> tyred.ContactLoads:
    """:func:`contact_loads` of the motorcycle ``mc``."""
    if is_multibody(mc):
        return _contact_loads_multibody(mc, model, data, force)
    return _contact_loads_sharp(mc, model, data, force)


def _outside_sharp(mc: Any, data: StackData) -> int:
    return tyred.Domain.INSIDE


def _outside_multibody(mc: Any, data: StackData) -> int:
    return tyred.outside(mc.model, data.multibody)


def _outside(mc: Any, data: StackData) -> int:
    """Why the motorcycle is outside its model's domain, as a
    :class:`~motosim.model.tyred.Domain` code (always inside for Sharp 1971, whose range
    the loop's roll and speed limits bound)."""
    if is_multibody(mc):
        return _outside_multibody(mc, data)
    return _outside_sharp(mc, data)


@overload(_outside, inline="always")
def _outside_typed(mc: Any, data: StackData) -> Any:
    return _outside_multibody if is_multibody(mc) else _outside_sharp


def _pitch_sharp(mc: Any, data: StackData) -> float:
    return 0.0


def _pitch_multibody(mc: Any, data: StackData) -> float:
    return float(data.multibody[tyred.Index.pitch] - mc.start[tyred.Index.pitch])


def _pitch(mc: Any, data: StackData) -> float:
    """The motorcycle's pitch from its start, nose up positive [rad] (0 for Sharp 1971)."""
    if is_multibody(mc):
        return _pitch_multibody(mc, data)
    return _pitch_sharp(mc, data)


@overload(_pitch, inline="always")
def _pitch_typed(mc: Any, data: StackData) -> Any:
    return _pitch_multibody if is_multibody(mc) else _pitch_sharp


@overload(_start, inline="always")
def _start_typed(mc: Any, data: StackData, speed: float) -> Any:
    return _start_multibody if is_multibody(mc) else _start_sharp


@overload(_advance, inline="always")
def _advance_typed(
    mc: Any, model: StackModel, data: StackData, steer: float, force: float, side_force: float
) -> Any:
    return _advance_multibody if is_multibody(mc) else _advance_sharp


# compiled as a call rather than inlined at numba's IR level, where its loop's accumulator
# trips numba's scope check (NumbaIRAssumptionWarning)
@overload(_steer_acceleration)
def _steer_acceleration_typed(mc: Any, model: StackModel, data: StackData, torque: float) -> Any:
    return _steer_acceleration_multibody if is_multibody(mc) else _steer_acceleration_sharp


@overload(_contact_loads, inline="always")
def _contact_loads_typed(mc: Any, model: StackModel, data: StackData, force: float) -> Any:
    return _contact_loads_multibody if is_multibody(mc) else _contact_loads_sharp


# The motorcycle's observations for compiled and Python callers alike: each is compiled into
# its caller (an overload whose implementation is the function itself), not as a function of
# its own.


def outside(model: StackModel, data: StackData) -> int:
    """Why the virtual motorcycle is outside its model's domain now, as a
    :class:`~motosim.model.tyred.Domain` code (``INSIDE`` when it is not, and always with
    Sharp 1971)."""
    code: int = _outside(model.motorcycle, data)
    return code


def pitch(model: StackModel, data: StackData) -> float:
    """The virtual motorcycle's pitch from upright running on level ground, nose up positive
    [rad]: the multibody model's (load transfer on the tyres' radial stiffness); 0 for Sharp
    1971, which has none."""
    angle: float = _pitch(model.motorcycle, data)
    return angle


def contact_loads(model: StackModel, data: StackData, force: float) -> tyred.ContactLoads:
    """The virtual motorcycle's tyre forces and slips now, as
    :class:`~motosim.model.tyred.ContactLoads`: the multibody model's; Sharp 1971's side
    forces with its constant normal loads on level ground, eq. (2)'s longitudinal ``force``
    [N] at the rear contact and no slips (its tyres have none)."""
    loads: tyred.ContactLoads = _contact_loads(model.motorcycle, model, data, force)
    return loads


@overload(outside, inline="always")
def _outside_in(model: StackModel, data: StackData) -> Any:
    return outside


@overload(pitch, inline="always")
def _pitch_in(model: StackModel, data: StackData) -> Any:
    return pitch


@overload(contact_loads, inline="always")
def _contact_loads_in(model: StackModel, data: StackData, force: float) -> Any:
    return contact_loads
