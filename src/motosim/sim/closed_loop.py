"""The closed loop of Fig. 7 (and the open loop of Fig. 9), simulated.

The stack (:mod:`motosim.sim.stack`) runs as it would on the simulator; this module adds the
world around it, the *rig*: the true handlebar, its sensors and the rider. Each stack period
the simulator measures the handlebar (the angle quantised like the encoder, the current with
noise), asks the rider for a torque (a profile, or the virtual rider looking at the
motorcycle), records a row of :data:`SIGNALS`, calls :func:`motosim.sim.stack.step`, and
advances the true handlebar over the period with exact stick-slip friction, the motor current
held. The design happens once, before the run: :func:`build_stack` and :func:`build_rig`.
"""

import dataclasses
import functools
import math
import zlib
from collections import namedtuple
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from enum import IntEnum
from typing import Any, NamedTuple

import numpy as np
from numba import njit
from numba.extending import overload
from numpy.typing import NDArray

from motosim import __version__
from motosim.control.statespace import StateSpace
from motosim.errors import MotosimError, RunFailedError
from motosim.estimation.registry import ESTIMATORS, SENSOR_ESTIMATOR, torque_sensor_kernel
from motosim.estimation.walcott_zak import (
    ObserverSettings,
    WalcottZakObserver,
    design_with,
)
from motosim.model.handlebar import HandlebarPlant, perturbed, plant_of
from motosim.model.tyred import ContactLoads, Domain, TyredModel
from motosim.params.handlebar import HandlebarParameters
from motosim.params.sharp import SharpParameters, derived_geometry
from motosim.signals import RECORDED
from motosim.sim.brakes import BrakeSettings, brake_torques, design_brakes, new_brake_state
from motosim.sim.grips import held_handlebar
from motosim.sim.hands import Arms, arms_of, hands_torque, is_held, plant_step
from motosim.sim.loop_analysis import prediction_lead
from motosim.sim.metrics import validity_limits
from motosim.sim.multibody_rider import (
    MultibodyRider,
    design_multibody_rider,
    multibody_rider_torque,
)
from motosim.sim.rider import RiderGains, design_rider, rider_torque
from motosim.sim.scenario import CsvProfile, Profile, Scenario, scenario_dict
from motosim.sim.stack import (
    Held,
    MotorcycleInput,
    MotorcycleState,
    StackData,
    StackModel,
    contact_loads,
    default_prediction,
    design_stack,
    is_multibody,
    new_data,
    outside,
    pitch,
    reset,
    step,
)
from motosim.timeseries import TimeSeries

__all__ = [
    "SIGNALS",
    "RigData",
    "RigModel",
    "RunInputs",
    "StopLimits",
    "TrueBar",
    "build_rig",
    "build_stack",
    "design_virtual_rider",
    "new_world",
    "perturb_rig",
    "prepare",
    "rider_design",
    "rider_route",
    "rig_key",
    "route_length",
    "run_limits",
    "run_metadata",
    "simulate",
]

Array = NDArray[np.float64]

SIGNALS = RECORDED
"""Recorded signals, in column order: :data:`motosim.signals.RECORDED`."""

_Columns = namedtuple("_Columns", RECORDED)  # type: ignore[misc]
_COL: Any = _Columns(*range(len(RECORDED)))
"""Column of each recorded signal by name (``_COL.tau_r``): compile-time constants of the
compiled loop, taken from :data:`motosim.signals.RECORDED` when it is compiled."""
_LAYOUT_KEY = zlib.crc32(" ".join(RECORDED).encode())
"""Fingerprint of the column layout, frozen into the compiled code beside the columns."""
_COLUMNS_OF_MOTORCYCLE = tuple(
    (RECORDED.index(m.name), int(m)) for m in MotorcycleState if m.name in RECORDED
)
"""The recorded columns of the motorcycle's states, each with its position in the state."""
_INSIDE = int(Domain.INSIDE)
"""The code of a motorcycle inside its model's domain (:func:`~motosim.sim.stack.outside`)."""


@njit(cache=True)
def _compiled_layout_key() -> int:
    return _LAYOUT_KEY


def _ensure_current_layout() -> None:
    """Recompile the loop if its cached machine code predates a change of the signal table.

    numba's cache follows this file, not :mod:`motosim.signals`, where the columns come from.
    """
    if _compiled_layout_key() != _LAYOUT_KEY:
        _compiled_layout_key.recompile()
        _run_chunk.recompile()
        _run_chunk_unreferenced.recompile()


@dataclass(frozen=True, slots=True)
class RunInputs:
    """Everything a scenario refers to, resolved: parameter sets, designs, tables.

    Attributes
    ----------
    scenario : Scenario
        The run.
    sharp : SharpParameters
        The virtual motorcycle.
    true_handlebar : HandlebarParameters
        The simulated handlebar, the scenario's perturbations applied.
    nominal_handlebar : HandlebarParameters
        The handlebar the observer and the controller were designed for, held by the
        scenario's :attr:`~motosim.sim.scenario.Scenario.stack_hands`
        (:attr:`design_handlebar`).
    controller : StateSpace or None
        Controller K [A/rad] (continuous, or discrete at the measurement step); None without
        torque feedback.
    observer : ObserverSettings or None
        Walcott-Zak settings from a design file; None for the defaults at the measurement step.
    tables : Mapping of str to TimeSeries
        CSV profiles by file name.
    rider : RiderGains or MultibodyRider or None
        The virtual rider's gain schedule, :func:`~motosim.sim.rider.design_rider` of
        ``sharp`` (or :func:`~motosim.sim.multibody_rider.design_multibody_rider` of
        ``multibody``) with :func:`rider_design` of the scenario, designed beforehand (a
        design cache's, or one shared by a campaign's runs); None to design it in
        :func:`build_rig`.
    """

    scenario: Scenario
    sharp: SharpParameters
    true_handlebar: HandlebarParameters
    nominal_handlebar: HandlebarParameters
    controller: StateSpace | None
    tables: Mapping[str, TimeSeries]
    observer: ObserverSettings | None = None
    rider: RiderGains | MultibodyRider | None = None
    multibody: TyredModel | None = None

    @property
    def design_handlebar(self) -> HandlebarParameters:
        """The nominal handlebar with the hands the stack is designed for
        (:func:`~motosim.sim.grips.held_handlebar`): what the observer, the controller and
        the feedforward model."""
        return held_handlebar(self.nominal_handlebar, self.scenario.stack_hands)


def prepare(
    scenario: Scenario,
    *,
    sharp: SharpParameters,
    true_handlebar: HandlebarParameters,
    nominal_handlebar: HandlebarParameters,
    controller: StateSpace | None,
    observer: ObserverSettings | None = None,
    tables: Mapping[str, TimeSeries] | None = None,
    rider: RiderGains | MultibodyRider | None = None,
    multibody: TyredModel | None = None,
) -> RunInputs:
    """Apply the scenario's perturbations to the true handlebar and bundle the inputs.

    The true handlebar's J_eq and beta_eq are scaled by the scenario's factors and its dry
    friction removed when ``friction = false``; the nominal one is used as given (also without
    dry friction then, as the paper neglects it in that case). ``rider`` is the virtual
    rider's schedule designed for ``sharp`` and :func:`rider_design` of ``scenario`` (None:
    :func:`build_rig` designs it).
    """
    hb = scenario.handlebar
    true = perturbed(
        true_handlebar,
        inertia_factor=hb.inertia_factor,
        damping_factor=hb.damping_factor,
        friction=hb.friction,
    )
    nominal = (
        nominal_handlebar if hb.friction else dataclasses.replace(nominal_handlebar, beta_s=0.0)
    )
    if _feedback(scenario) and controller is None:
        raise MotosimError('the scenario needs a controller: give one (or kind = "none")')
    if (scenario.motorcycle.model == "multibody") != (multibody is not None):
        raise MotosimError(
            f"[motorcycle] model = {scenario.motorcycle.model!r}; expected the multibody model "
            "given exactly when the scenario asks for it"
        )
    return RunInputs(
        scenario, sharp, true, nominal, controller, tables or {}, observer, rider, multibody
    )


def rider_design(scenario: Scenario) -> dict[str, Any]:
    """The keyword arguments of :func:`~motosim.sim.rider.design_rider` for ``scenario``.

    Everything the virtual rider's schedule depends on besides the motorcycle: a rider of
    torque profiles gets a two-speed placeholder schedule, which :func:`build_rig` carries
    but the loop does not read.
    """
    rider = scenario.rider
    if rider.kind == "torque":
        return {"speeds": np.array([1.0, 2.0])}
    return {
        "lateral_tolerance": rider.lateral_tolerance,
        "course_tolerance": rider.course_tolerance,
        "torque_scale": rider.torque_scale,
        "preview": rider.preview,
        "max_torque": rider.max_torque,
    }


STACK_OBSERVER_INERTIA = (200.0, 2.0)
"""(rate [Hz], largest factor): below that rate the stack's observer is designed for
min(largest, rate / measurement rate) times the handlebar's J_eq (:func:`observer_settings`)."""


def observer_settings(measurement_rate: float, *, cancellation: bool = True) -> ObserverSettings:
    """The rider-torque observer's default settings inside the stack at ``measurement_rate``.

    Those of :meth:`ObserverSettings.for_step`; with the rider-torque cancellation on, the
    observer designed for ``inertia_factor`` = min(2, max(1, 200 Hz / measurement_rate))
    times the handlebar's J_eq: 2 at 100 Hz, 1.33 at 150 Hz, 1 from 200 Hz. Believing the
    handlebar heavier than it is, the observer reads the excess J_eq theta_h'' as rider
    torque, which the cancellation takes off the motor, and its estimate filter (rider torque
    to estimate) keeps a gain near 1 where it would reach 2 near 16 Hz: the sampled loop's
    margins at 100 Hz rise (:func:`motosim.sim.loop_analysis.analyse_stack`; the design
    guide gives them) and the rendered feel over 0.1-3 Hz is unchanged. From 500 Hz the
    bias costs margins, hence 1 there; without the cancellation it would only add J_eq
    theta_h'' to the estimate.

    Parameters
    ----------
    measurement_rate : float
        [Hz].
    cancellation : bool
        Whether the stack cancels the estimated rider torque (feedforward ``"rider"``).

    Returns
    -------
    ObserverSettings

    Examples
    --------
    >>> [observer_settings(r).inertia_factor for r in (100.0, 200.0, 1000.0)]
    [2.0, 1.0, 1.0]
    """
    settings = ObserverSettings.for_step(1.0 / measurement_rate)
    if not cancellation:
        return settings
    rate, largest = STACK_OBSERVER_INERTIA
    factor = min(largest, max(1.0, rate / measurement_rate))
    return dataclasses.replace(settings, inertia_factor=factor)


def _feedback(scenario: Scenario) -> bool:
    return scenario.controller.kind != "none" and scenario.architecture == "closed_loop"


def build_stack(inputs: RunInputs) -> StackModel:
    """Design the stack of a run: estimator, differentiator, controller, motorcycle.

    The estimator is the scenario's, designed for the nominal handlebar (held by the hands
    the stack is designed for: :attr:`RunInputs.design_handlebar`) at the measurement step;
    a Walcott-Zak observer takes the design file's settings when the run has them. With
    the predicted cancellation (``[controller] prediction``, by default
    :func:`~motosim.sim.stack.default_prediction` with the Walcott-Zak observer), the stack is
    designed twice: its lead T_d is the first one's estimate filter's delay
    (:func:`~motosim.sim.loop_analysis.prediction_lead`) on that handlebar.
    """
    sc = inputs.scenario
    h_meas = 1.0 / sc.rates.measurement
    est = sc.estimator
    if est.name == "walcott_zak":
        settings = dataclasses.replace(
            inputs.observer
            or observer_settings(
                sc.rates.measurement,
                cancellation=_feedback(sc) and "rider" in (sc.controller.feedforward or ()),
            ),
            friction_compensation=est.friction_compensation,
        )
        gains = design_with(inputs.design_handlebar, settings)
        kernel = WalcottZakObserver(gains, h_meas, stick_projection=est.stick_projection).kernel
    elif est.name == SENSOR_ESTIMATOR:
        sensor = sc.sensor.torque
        kernel = torque_sensor_kernel(h_meas, low_pass=sensor.low_pass if sensor else 0.0)
    else:
        stepper = ESTIMATORS[est.name](
            inputs.design_handlebar, h_meas, friction_compensation=est.friction_compensation
        )
        kernel = stepper.kernel

    def build(lead: float = 0.0) -> StackModel:
        return design_stack(
            inputs.sharp,
            kernel,
            inputs.controller if _feedback(sc) else None,
            control_rate=sc.rates.control,
            measurement_rate=sc.rates.measurement,
            lipschitz=est.lipschitz,
            discretization=sc.controller.discretization,
            max_current=sc.controller.max_current,
            speed=sc.motorcycle.speed,
            true_torque=sc.motorcycle.input == "true",
            handlebar=inputs.design_handlebar,
            rider_feedforward="rider" in (sc.controller.feedforward or ()),
            reference_feedforward="reference" in (sc.controller.feedforward or ()),
            prediction_lead=lead,
            side_force_height=sc.motorcycle.side_wind_height,
            multibody=inputs.multibody,
            hands=sc.stack_hands,
        )

    model = build()
    predict = sc.controller.prediction
    if predict is None:
        predict = est.name == "walcott_zak" and default_prediction(sc.rates.measurement)
    if predict and model.feedforward.cancellation > 0.0:
        model = build(prediction_lead(model, inputs.design_handlebar))
    return model


class RigModel(NamedTuple):
    """The simulated world around the stack: true handlebar, sensors, rider, longitudinal inputs.

    Attributes
    ----------
    handlebar : HandlebarPlant
        The true handlebar.
    plant_substeps : int
        Plant sub-steps per stack period (while the rider's torque changes within one).
    quantum : float
        Encoder resolution [rad]; 0 for an exact angle.
    virtual_rider : bool
        The rider is the path-following virtual rider (else ``rider_profile``).
    rider_profile : ndarray
        Rider torque at every plant sub-step [N*m]; read-only, one array shared by the
        runs with the same profile and rates.
    rider_probe : ndarray, shape (n,)
        Torque added to the virtual rider's each period (a chirp to measure the feel) [N*m].
    path : ndarray, shape (4, m)
        The virtual rider's path: x, y [m], heading [rad], curvature [1/m].
    path_ds : float
        Path spacing [m].
    rider_speeds, rider_K, rider_x_ss, rider_tau_ss : ndarray
        The virtual rider's gain schedule (:class:`~motosim.sim.rider.RiderGains`).
    rider_preview : float
        The virtual rider's preview [s].
    rider_max_torque : float
        The virtual rider's largest torque [N*m].
    force : ndarray, shape (n,)
        Longitudinal force of eq. (2) each period [N].
    side_force : ndarray, shape (n,)
        Side force on the motorcycle (side wind, to the right) each period [N].
    current_noise : ndarray, shape (n,)
        Current-sensor error each period [A].
    arms : Arms
        The rider's arms at the handlebar (:mod:`motosim.sim.hands`); zeros: a pure torque
        source.
    hands_off : ndarray, shape (m, 2)
        Phases [t0, t1] [s] in which nobody holds the handlebar (no torque at all).
    sensed : bool
        The stack reads the rider's torque from a torque sensor (the estimator
        ``torque_sensor``): it is told the rider's torque plus ``torque_error``.
    torque_error : ndarray, shape (n,)
        The torque sensor's error each period (offset and noise) [N*m].
    motorcycle_inputs : ndarray, shape (n, 4) or (0, 4)
        The multibody motorcycle's inputs each period, columns in the order of
        :class:`~motosim.sim.stack.MotorcycleInput`, the brake torques as the rider demands
        them; no rows for Sharp 1971 (``force``).
    multibody_rider : MultibodyRider
        The virtual rider of the multibody motorcycle (steering, throttle), read when
        ``virtual_rider`` and ``motorcycle_inputs`` has rows (else a placeholder).
    brakes : BrakeSettings
        How the virtual rider modulates the brake demand of the multibody motorcycle
        (:mod:`motosim.sim.brakes`; ``enabled`` false: as demanded).
    """

    handlebar: HandlebarPlant
    plant_substeps: int
    quantum: float
    virtual_rider: bool
    rider_profile: Array
    rider_probe: Array
    path: Array
    path_ds: float
    rider_speeds: Array
    rider_K: Array
    rider_x_ss: Array
    rider_tau_ss: Array
    rider_preview: float
    rider_max_torque: float
    force: Array
    side_force: Array
    current_noise: Array
    arms: Arms
    hands_off: Array
    sensed: bool
    torque_error: Array
    motorcycle_inputs: Array
    multibody_rider: MultibodyRider
    brakes: BrakeSettings


class TrueBar(IntEnum):
    """The true handlebar's state in :attr:`RigData.handlebar`: angle theta_h [rad], rate
    theta_h' [rad/s] and the rate a period before [rad/s]."""

    theta = 0
    omega = 1
    last_omega = 2


class StopLimits(NamedTuple):
    """Where a run stops (:func:`simulate`'s ``stop_outside``): the largest roll [rad] and
    the lowest and highest speeds [m/s]."""

    roll: float
    low_speed: float
    high_speed: float


NO_STOP = StopLimits(math.inf, -math.inf, math.inf)
"""Limits a run never leaves."""


class RigData(NamedTuple):
    """The world's states: the true handlebar (:class:`TrueBar`), the rider's path index,
    the speed its throttle holds [m/s] (the start speed, then the speed at which it last
    braked) and its brake controller's state (:class:`~motosim.sim.brakes.BrakeState`)."""

    handlebar: Array
    path_index: NDArray[np.int64]
    target_speed: Array
    brakes: Array


def new_world(scenario: Scenario) -> RigData:
    """The world's states at the start of a run of ``scenario``."""
    return RigData(
        np.zeros(len(TrueBar)),
        np.zeros(1, dtype=np.int64),
        np.array([scenario.motorcycle.speed]),
        new_brake_state(),
    )


_NO_MULTIBODY_RIDER = MultibodyRider(
    speeds=np.array([1.0, 2.0]),
    leans=np.zeros(2),
    curvature=np.zeros((2, 2)),
    x_ss=np.zeros((2, 2, 15)),
    tau_ss=np.zeros((2, 2)),
    drive_ss=np.zeros((2, 2)),
    K=np.zeros((2, 2, 17)),
    speed_gain=0.0,
    preview=0.0,
    max_torque=0.0,
    max_drive_torque=0.0,
)
"""The rig's multibody rider when the motorcycle is Sharp's (never read)."""
_NO_BRAKES = BrakeSettings(
    enabled=False,
    slip_target=0.1,
    time_constant=1.0,
    radius_front=1.0,
    radius_rear=1.0,
    inertia_front=1.0,
    inertia_rear=1.0,
    min_rear_load=0.0,
    rear_load_band=1.0,
    load_lead=0.0,
    min_speed=0.0,
    override_torque=math.inf,
    rise_rate=math.inf,
)
"""The brakes of a run that does not modulate them."""


@functools.lru_cache(maxsize=8)
def route_length(scenario: Scenario) -> float:
    """Length of the virtual rider's path built for ``scenario`` [m]: the distance it could
    ride at its speed (at least 20 m/s) over its duration, with half again and 200 m to
    spare."""
    return max(scenario.motorcycle.speed, 20.0) * scenario.duration * 1.5 + 200.0


def rider_route(scenario: Scenario) -> tuple[Array, float]:
    """The virtual rider's path of ``scenario`` as the rig holds it: rows x, y [m], heading
    [rad], curvature [1/m], and its spacing [m]."""
    assert scenario.rider.path is not None
    route = scenario.rider.path.build(route_length(scenario))
    return np.vstack([route.x, route.y, route.psi, route.kappa]), float(route.ds)


def perturb_rig(rig: RigModel, inputs: RunInputs, *, rng: np.random.Generator) -> RigModel:
    """``rig``, built for a run that differs from ``inputs`` only in its true handlebar and its
    seed, made ``inputs``': the handlebar's parameters, and in place the current sensor's
    noise and the torque sensor's error (drawn from ``rng`` as :func:`build_rig` draws them, in
    the same order).

    A campaign's worker builds the rig once and perturbs it run after run; the caller
    checks that the runs differ only there (:func:`rig_key`).
    """
    rig = rig._replace(handlebar=plant_of(inputs.true_handlebar))
    noise = inputs.scenario.measurement.current_noise
    if noise:
        rng.standard_normal(out=rig.current_noise)  # rng.normal(0, noise, n), in place
        np.multiply(rig.current_noise, noise, out=rig.current_noise)
    sensor = inputs.scenario.sensor.torque
    if sensor is not None and sensor.noise:  # after the current's noise, as build_rig
        rig.torque_error[:] = sensor.offset
        np.add(
            rig.torque_error,
            rng.normal(0.0, sensor.noise, rig.torque_error.size),
            out=rig.torque_error,
        )
    return rig


def rig_key(scenario: Scenario) -> Scenario:
    """What a run's rig depends on besides its true handlebar and its seed: two runs with
    equal keys (and equal motorcycles and tables) share a rig up to :func:`perturb_rig`."""
    return dataclasses.replace(
        scenario,
        seed=0,
        handlebar=dataclasses.replace(scenario.handlebar, inertia_factor=1.0, damping_factor=1.0),
    )


def _plant_rate_profile(profile: Profile, n: int, n_sub: int, h: float) -> Array:
    """``profile`` at the ``n * n_sub`` plant sub-steps of a run, read-only.

    Cached: the runs of a campaign that share a rider profile and rates share this array
    instead of sampling it again.
    """
    t_fine = (np.arange(n * n_sub) / (n * n_sub)) * (n * h)
    values = profile.sample(t_fine, {})
    values.flags.writeable = False
    return values


def build_rig(
    inputs: RunInputs, *, rng: np.random.Generator, route: "tuple[Array, float] | None" = None
) -> RigModel:
    """The world of a run: true handlebar, sensors (noise drawn from ``rng``), rider, inputs.

    ``route`` is the virtual rider's path as :func:`rider_route` builds it for the scenario
    (a campaign's worker reuses it across the runs that share it); by default built here.
    """
    sc = inputs.scenario
    h = 1.0 / sc.rates.control
    n_sub = round(sc.rates.plant / sc.rates.control)
    n = round(sc.duration / h)
    t: Array = np.arange(n, dtype=np.float64) * h
    rider = sc.rider
    if rider.kind == "torque":
        assert rider.profile is not None
        if isinstance(rider.profile, CsvProfile):
            t_fine = (np.arange(n * n_sub) / (n * n_sub)) * (n * h)
            profile = rider.profile.sample(t_fine, inputs.tables)
        else:  # a profile of its own values only: the same array for every such run
            profile = _plant_rate_profile(rider.profile, n, n_sub, h)
        path_arr, path_ds = np.zeros((4, 2)), 1.0
    else:
        profile = np.zeros(1)
        path_arr, path_ds = rider_route(sc) if route is None else route
    gains = inputs.rider
    if gains is None:
        gains = design_virtual_rider(inputs)
    mb_rider = gains if isinstance(gains, MultibodyRider) else _NO_MULTIBODY_RIDER
    if isinstance(gains, MultibodyRider):  # the linear-model schedule is not read
        gains = _placeholder_gains(gains)
    mc = sc.motorcycle
    r_D = derived_geometry(inputs.sharp)["r_D"]
    drive = mc.drive_torque.sample(t, inputs.tables)
    brake = np.maximum(mc.brake_torque.sample(t, inputs.tables), 0.0)
    force = (drive - brake) / r_D + mc.wind_force.sample(t, inputs.tables)
    motorcycle_inputs = np.zeros((0, len(MotorcycleInput)))
    if inputs.multibody is not None:
        motorcycle_inputs = np.zeros((n, len(MotorcycleInput)))
        motorcycle_inputs[:, MotorcycleInput.drive_torque] = drive
        for name in ("front_brake_torque", "rear_brake_torque"):
            torque = getattr(mc, name).sample(t, inputs.tables)
            motorcycle_inputs[:, MotorcycleInput[name]] = np.maximum(torque, 0.0)
        motorcycle_inputs[:, MotorcycleInput.friction] = sc.road.friction.sample(t, inputs.tables)
    bits = sc.measurement.encoder_bits
    noise = sc.measurement.current_noise
    current_noise = rng.normal(0.0, noise, n) if noise else np.zeros(n)
    sensor = sc.sensor.torque
    torque_error = np.zeros(n)
    if sensor is not None:  # drawn after the current's noise, which stays as without it
        torque_error += sensor.offset
        if sensor.noise:
            torque_error += rng.normal(0.0, sensor.noise, n)
    off = np.array(rider.hands_off, dtype=np.float64).reshape(-1, 2)
    return RigModel(
        handlebar=plant_of(inputs.true_handlebar),
        plant_substeps=n_sub,
        quantum=2 * math.pi / 2**bits if bits else 0.0,
        virtual_rider=rider.kind == "virtual",
        rider_profile=profile,
        rider_probe=rider.probe.sample(t, inputs.tables) if rider.probe else np.zeros(n),
        path=path_arr,
        path_ds=float(path_ds),
        rider_speeds=gains.speeds,
        rider_K=gains.K,
        rider_x_ss=gains.x_ss,
        rider_tau_ss=gains.tau_ss,
        rider_preview=float(gains.preview),
        rider_max_torque=float(gains.max_torque),
        force=force,
        side_force=mc.side_wind.sample(t, inputs.tables),
        current_noise=current_noise,
        arms=arms_of(sc.rider_hands),
        hands_off=off,
        sensed=sc.estimator.name == SENSOR_ESTIMATOR,
        torque_error=torque_error,
        motorcycle_inputs=motorcycle_inputs,
        multibody_rider=mb_rider,
        brakes=(
            design_brakes(inputs.multibody, slip_target=rider.brake_slip)
            if inputs.multibody is not None and rider.kind == "virtual" and rider.brake_control
            else _NO_BRAKES
        ),
    )


MULTIBODY_LOWEST_SPEED = 1.0
"""The lowest speed of a run on the multibody motorcycle [m/s]: its tyres' slips are defined
down to a walking pace."""


def run_limits(inputs: RunInputs) -> tuple[float, float, float]:
    """(largest roll [rad], lowest and highest speed [m/s]) of a run of ``inputs``, for
    :func:`simulate`'s ``stop_outside``: :func:`motosim.sim.metrics.validity_limits`, and on
    the multibody motorcycle its own roll limit and speeds from
    :data:`MULTIBODY_LOWEST_SPEED`."""
    limits = validity_limits(inputs.scenario.motorcycle.speed)
    if inputs.multibody is None:
        return limits
    return inputs.multibody.roll_limit, min(MULTIBODY_LOWEST_SPEED, limits[1]), limits[2]


def design_virtual_rider(inputs: RunInputs) -> RiderGains | MultibodyRider:
    """The virtual rider's schedule of a run: on Sharp 1971's linear model
    (:func:`~motosim.sim.rider.design_rider`), or scheduled on speed and lean on the
    multibody motorcycle (:func:`~motosim.sim.multibody_rider.design_multibody_rider`)."""
    settings = rider_design(inputs.scenario)
    if inputs.multibody is None or inputs.scenario.rider.kind != "virtual":
        return design_rider(inputs.sharp, **settings)
    return design_multibody_rider(inputs.multibody, **settings)


def _placeholder_gains(rider: MultibodyRider) -> RiderGains:
    """A two-speed schedule for the linear-model rider slots of a rig whose rider is the
    multibody one (never read)."""
    return RiderGains(
        np.array([1.0, 2.0]),
        np.zeros((2, 10)),
        np.zeros((2, 8)),
        np.zeros(2),
        rider.preview,
        rider.max_torque,
    )


def _multibody_period_sharp(
    mc: Any, stack: StackModel, data: StackData, rig: RigModel, world: RigData, k: int
) -> tuple[bool, float, float, ContactLoads]:
    return False, 0.0, 0.0, contact_loads(stack, data, rig.force[k])


def _multibody_period_multibody(
    mc: Any, stack: StackModel, data: StackData, rig: RigModel, world: RigData, k: int
) -> tuple[bool, float, float, ContactLoads]:
    u = data.inputs
    for j in range(u.size):
        u[j] = rig.motorcycle_inputs[k, j]
    loads = contact_loads(stack, data, 0.0)  # on this period's road (its friction)
    if not rig.virtual_rider:
        return False, 0.0, 0.0, loads
    demand_f = u[MotorcycleInput.front_brake_torque]
    demand_r = u[MotorcycleInput.rear_brake_torque]
    braking = demand_f + demand_r > 0.0
    if braking:  # the throttle then holds the speed the brakes leave
        world.target_speed[0] = data.motorcycle[MotorcycleState.v_x]
    tau, drive, idx, e_y = multibody_rider_torque(
        rig.multibody_rider,
        data.multibody,
        loads,
        int(world.path_index[0]),
        rig.path,
        rig.path_ds,
        world.target_speed[0],
        braking,
    )
    world.path_index[0] = idx
    u[MotorcycleInput.drive_torque] += drive
    front, rear = brake_torques(
        rig.brakes, world.brakes, data.multibody, demand_f, demand_r, loads, stack.dt
    )
    u[MotorcycleInput.front_brake_torque] = front
    u[MotorcycleInput.rear_brake_torque] = rear
    return True, tau, e_y, loads


def _multibody_period(
    mc: Any, stack: StackModel, data: StackData, rig: RigModel, world: RigData, k: int
) -> tuple[bool, float, float, ContactLoads]:
    """The multibody motorcycle's part of period ``k``: its inputs from the rig's table, and
    with the virtual rider its steering, throttle and modulated brakes; (whether the rider
    steered, its torque [N*m], its lateral error [m], the contact loads of the period, which
    the row records). On Sharp 1971's motorcycle only its loads, and its stack never compiles
    the rest (numba picks by the motorcycle's type)."""
    if is_multibody(mc):
        return _multibody_period_multibody(mc, stack, data, rig, world, k)
    return _multibody_period_sharp(mc, stack, data, rig, world, k)


@overload(_multibody_period)
def _multibody_period_typed(
    mc: Any, stack: StackModel, data: StackData, rig: RigModel, world: RigData, k: int
) -> Any:
    return _multibody_period_multibody if is_multibody(mc) else _multibody_period_sharp


@njit(cache=True)
def _steady(profile: Array, k: int, n_sub: int) -> bool:
    """Whether the rider's torque ``profile`` (one value a plant sub-step) is constant over
    period ``k`` of ``n_sub`` sub-steps."""
    first = profile[k * n_sub]
    for j in range(1, n_sub):
        if profile[k * n_sub + j] != first:
            return False
    return True


@njit(cache=True)
def _run_chunk(
    k0: int,
    out: Array,
    stack: StackModel,
    data: StackData,
    rig: RigModel,
    world: RigData,
    limits: StopLimits,
) -> int:
    """Advance ``out.shape[0]`` stack periods from period ``k0``, recording a row each.

    Stops after the first row outside ``limits`` or whose motorcycle is outside its model's
    domain (:func:`~motosim.sim.stack.outside`); returns the number of rows recorded.
    """
    plant, a = rig.handlebar, rig.arms
    beta_s, nkt = plant.beta_s, plant.torque_per_amp
    arms = a.J_a > 0.0 or a.c_a > 0.0 or a.k_a > 0.0
    n_sub = rig.plant_substeps
    h = stack.dt
    hb = world.handlebar
    z = data.motorcycle
    for row in range(out.shape[0]):
        k = k0 + row
        q = rig.quantum
        theta = hb[TrueBar.theta]
        theta_meas = math.floor(theta / q + 0.5) * q if q > 0.0 else theta
        held = rig.hands_off.shape[0] == 0 or is_held(k * h, rig.hands_off)
        # the multibody motorcycle's road and the rider's demands (nothing on Sharp 1971's)
        steered, tau_rider, e_y, loads = _multibody_period(
            stack.motorcycle, stack, data, rig, world, k
        )
        if steered:
            tau_rider += rig.rider_probe[k]
        elif rig.virtual_rider:
            tau_rider, idx, e_y = rider_torque(
                z[: MotorcycleState.v_x],
                z[MotorcycleState.v_x],
                z[MotorcycleState.psi],
                z[MotorcycleState.x],
                z[MotorcycleState.y],
                int(world.path_index[0]),
                rig.path,
                rig.path_ds,
                rig.rider_speeds,
                rig.rider_K,
                rig.rider_x_ss,
                rig.rider_tau_ss,
                rig.rider_preview,
                rig.rider_max_torque,
            )
            world.path_index[0] = idx
            tau_rider += rig.rider_probe[k]
        else:
            tau_rider = rig.rider_profile[k * n_sub]
        active = tau_rider if held else 0.0
        holding = arms and held
        if not held:
            tau_rider = 0.0
        omega = hb[TrueBar.omega]
        if holding:  # the arms' passive torque, theta_h'' the last period's mean
            accel = (omega - hb[TrueBar.last_omega]) / h if k > 0 else 0.0
            tau_rider += hands_torque(theta, omega, accel, a.J_a, a.c_a, a.k_a, a.theta_hold)
        if arms:
            hb[TrueBar.last_omega] = omega
        o = out[row]
        o[_COL.t] = k * h
        o[_COL.tau_r] = tau_rider
        o[_COL.tau_r_active] = active
        o[_COL.tau_p] = -beta_s if omega > 0.0 else (beta_s if omega < 0.0 else 0.0)
        o[_COL.theta_h] = theta
        o[_COL.theta_h_dot] = omega
        for column, at in _COLUMNS_OF_MOTORCYCLE:
            o[column] = z[at]
        o[_COL.e_y] = e_y
        left = outside(stack, data) != _INSIDE
        o[_COL.F_xr], o[_COL.F_xf] = loads.F_xr, loads.F_xf
        o[_COL.F_zr], o[_COL.F_zf] = loads.F_zr, loads.F_zf
        o[_COL.kappa_r], o[_COL.kappa_f] = loads.kappa_r, loads.kappa_f
        o[_COL.alpha_r], o[_COL.alpha_f] = loads.alpha_r, loads.alpha_f
        o[_COL.theta] = pitch(stack, data)
        inside = limits.low_speed <= o[_COL.v_x] <= limits.high_speed
        stop = left or abs(o[_COL.phi]) > limits.roll or not inside
        # the stack: command, estimate, virtual motorcycle
        told = tau_rider + rig.torque_error[k] if rig.sensed else tau_rider
        i_cmd = step(
            stack,
            data,
            theta_meas,
            rig.current_noise[k],
            told,
            rig.force[k],
            rig.side_force[k],
        )
        o[_COL.theta_h_meas] = data.held[Held.theta_h_meas]
        o[_COL.theta_h_dot_hat] = data.held[Held.theta_h_dot_hat]
        o[_COL.tau_r_hat] = data.held[Held.tau_r_hat]
        o[_COL.i_m] = i_cmd
        o[_COL.tau_m] = nkt * i_cmd
        # the true handlebar over the period, the current held: one step while the rider's
        # torque is constant over it, else one per plant sub-step
        motor = nkt * i_cmd
        if rig.virtual_rider or not held or _steady(rig.rider_profile, k, n_sub):
            theta, omega = plant_step(theta, omega, active + motor, plant, a, holding, h)
        else:
            h_sub = h / n_sub
            for j in range(n_sub):
                torque = rig.rider_profile[k * n_sub + j] + motor
                theta, omega = plant_step(theta, omega, torque, plant, a, holding, h_sub)
        hb[TrueBar.theta], hb[TrueBar.omega] = theta, omega
        if stop:
            return row + 1
    return len(out)


_UNREFERENCED: dict[str, Any] = {"_nrt": False}
"""numba's target option that compiles a function, and its own copies of the functions it
calls, without reference counting (they must allocate nothing: an allocation fails to
compile)."""


@njit(cache=True, **_UNREFERENCED)  # type: ignore[untyped-decorator]
def _run_chunk_unreferenced(
    k0: int,
    out: Array,
    stack: StackModel,
    data: StackData,
    rig: RigModel,
    world: RigData,
    limits: StopLimits,
) -> int:
    """:func:`_run_chunk` compiled without numba's reference counting, for a loop that
    allocates nothing (Sharp 1971's): the arrays the step takes from its named tuples are
    then not counted in and out at every period (see "Compiled without reference counting"
    in the organisation guide)."""
    done: int = _run_chunk(k0, out, stack, data, rig, world, limits)
    return done


def chunk_loop(stack: StackModel) -> Callable[..., int]:
    """The compiled loop that runs ``stack``: :func:`_run_chunk_unreferenced` for Sharp
    1971's motorcycle, :func:`_run_chunk` (whose multibody model allocates its rates) for the
    multibody one; both take and return what :func:`_run_chunk` does."""
    if is_multibody(stack.motorcycle):
        return _run_chunk
    return _run_chunk_unreferenced  # type: ignore[no-any-return]


def _check_block(out: Array) -> None:
    """Refuse a block with a non-finite value: a signal never written, or a divergence."""
    finite = np.isfinite(out)
    if finite.all():
        return
    unwritten = [SIGNALS[j] for j in range(out.shape[1]) if np.isnan(out[:, j]).all()]
    if unwritten and out.shape[0] > 1:
        raise AssertionError(f"recorded signals never computed: {', '.join(unwritten)}")
    row = int(np.argmin(finite.all(axis=1)))
    bad = [SIGNALS[j] for j in range(out.shape[1]) if not finite[row, j]]
    raise RunFailedError(
        f"the simulation diverged at t = {out[row, _COL.t]:.3f} s ({', '.join(bad)} not finite); "
        "check the rates, the controller and the rider",
        time=float(out[row, _COL.t]),
    )


def simulate(
    inputs: RunInputs,
    *,
    rng: np.random.Generator,
    stack: StackModel | None = None,
    on_block: Callable[[Array], None] | None = None,
    chunk: float = 1.0,
    keep: bool = True,
    stop_outside: tuple[float, float, float] | None = None,
    rig: RigModel | None = None,
) -> TimeSeries:
    """Simulate a scenario, block by block.

    Parameters
    ----------
    inputs : RunInputs
        From :func:`prepare`.
    rng : numpy.random.Generator
        Source of the current-sensor noise.
    stack : StackModel, optional
        The designed stack; by default :func:`build_stack` of ``inputs``. A campaign builds
        it once and runs it on many perturbed handlebars.
    on_block : callable, optional
        Called with each recorded block (rows of :data:`SIGNALS`) as soon as it is computed,
        for example to write it to a file and advance a progress bar.
    chunk : float
        Simulated time per block [s].
    keep : bool
        Keep and return every row (else the result holds only the last block).
    stop_outside : tuple of float, optional
        (largest roll [rad], lowest speed [m/s], highest speed [m/s]): stop at the first
        instant beyond them, that instant the last row (the model's range of validity,
        :func:`motosim.sim.metrics.validity_limits`). By default the run goes to its end.
    rig : RigModel, optional
        The run's world, built beforehand (:func:`build_rig`, :func:`perturb_rig`; ``rng``
        is then not read); by default :func:`build_rig` of ``inputs`` with ``rng``.

    Returns
    -------
    TimeSeries
        The recorded signals (without ``t``, which is the time axis); shorter than the
        scenario when the run stopped outside ``stop_outside``.

    Raises
    ------
    MotosimError
        If a design is impossible at the scenario's rates.
    RunFailedError
        If the simulation diverges (a non-finite signal); the blocks before it were passed
        to ``on_block``.
    """
    sc = inputs.scenario
    model = build_stack(inputs) if stack is None else stack
    rig = build_rig(inputs, rng=rng) if rig is None else rig
    _ensure_current_layout()
    data = new_data(model)
    world = new_world(sc)
    reset(model, data, 0.0, 0.0)
    n = rig.current_noise.size
    rows = max(1, round(chunk * sc.rates.control))
    limits = NO_STOP if stop_outside is None else StopLimits(*map(float, stop_outside))
    blocks = []
    loop = chunk_loop(model)
    for k0 in range(0, n, rows):
        out = np.full((min(rows, n - k0), len(SIGNALS)), np.nan)
        done = loop(k0, out, model, data, rig, world, limits)
        stopped = done < out.shape[0]
        out = out[:done]
        _check_block(out)
        if on_block is not None:
            on_block(out)
        if keep or k0 + rows >= n or stopped:
            blocks.append(out)
        if stopped:
            break
    out = blocks[0] if len(blocks) == 1 else np.vstack(blocks)
    # t is the first column (signals.RECORDED): the others are views after it, no copy
    return TimeSeries(out[:, _COL.t], out[:, _COL.t + 1 :], SIGNALS[1:])


def run_metadata(inputs: RunInputs) -> dict[str, object]:
    """What produced a run: scenario, parameters and version, as plain JSON-able values."""
    return {
        "version": __version__,
        "scenario": scenario_dict(inputs.scenario),
        "sharp": dataclasses.asdict(inputs.sharp),
        "true_handlebar": dataclasses.asdict(inputs.true_handlebar),
        "nominal_handlebar": dataclasses.asdict(inputs.nominal_handlebar),
        "rider_hands": (
            None if (held := inputs.scenario.rider_hands) is None else dataclasses.asdict(held)
        ),
        "stack_hands": (
            None if (hands := inputs.scenario.stack_hands) is None else dataclasses.asdict(hands)
        ),
        "controller": None
        if inputs.controller is None
        else {
            **{k: getattr(inputs.controller, k).tolist() for k in "ABCD"},
            "dt": inputs.controller.dt,
        },
        "observer": None if inputs.observer is None else dataclasses.asdict(inputs.observer),
        "multibody": None if inputs.multibody is None else _plain(inputs.multibody),
    }


def _plain(value: Any) -> Any:
    """A record of numbers and arrays (named tuples nested) as JSON-able values."""
    if isinstance(value, tuple) and hasattr(value, "_fields"):
        return {name: _plain(getattr(value, name)) for name in value._fields}
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value.item() if isinstance(value, np.generic) else value
