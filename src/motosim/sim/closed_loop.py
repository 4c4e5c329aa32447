"""The closed loop of Fig. 7 (and the open loop of Fig. 9), simulated.

Each stack period the simulator: measures the handlebar (latest sample of the measurement
rate, the angle quantised like the encoder, the current with noise), lets the stack command
the motor (:func:`~motosim.sim.stack.stack_command`), updates the stack's estimator and
virtual motorcycle (:func:`~motosim.sim.stack.stack_update`, :func:`~motosim.model.sharp.bike_rk4`),
asks the rider for a torque (a profile, or the virtual rider looking at the motorcycle), and
advances the true handlebar over the period in plant sub-steps with exact stick-slip friction,
the motor current held. One row of :data:`SIGNALS` is recorded per stack period.
"""

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray

from motosim import __version__
from motosim.control.statespace import StateSpace
from motosim.control.torque_feedback import discretize
from motosim.errors import MotosimError
from motosim.estimation.registry import kernel_arguments
from motosim.model import sharp as sharp_model
from motosim.model.handlebar import perturbed, step_exact
from motosim.model.sharp import bike_rk4
from motosim.params.handlebar import HandlebarParameters
from motosim.params.sharp import SharpParameters, derived_geometry
from motosim.sim import paths
from motosim.sim.rider import design_rider, rider_torque
from motosim.sim.scenario import PathSpec, Profile, Scenario
from motosim.sim.stack import stack_command, stack_update
from motosim.timeseries import TimeSeries

__all__ = ["SIGNALS", "RunInputs", "prepare", "run_metadata", "sample_profile", "simulate"]

Array = NDArray[np.float64]

SIGNALS = (
    "t", "tau_r", "tau_r_hat", "tau_p", "theta_h", "theta_h_dot", "theta_h_meas",
    "theta_h_dot_hat", "i_m", "tau_m", "delta", "v_x", "v_y", "psi_dot", "phi_dot",
    "delta_dot", "phi", "F_yr", "F_yf", "psi", "x", "y", "e_y",
)  # fmt: skip
"""Recorded signals, in column order (see :mod:`motosim.signals`)."""

_BIKE_STEP = 1e-3  # largest RK4 step of the virtual motorcycle [s]


def sample_profile(profile: Profile, t: Array, tables: Mapping[str, TimeSeries]) -> Array:
    """Values of a profile at the times ``t`` [s].

    ``tables`` maps a CSV file name to its loaded log, for ``kind = "csv"`` (held samples).
    """
    s = profile.settings
    if profile.kind == "constant":
        return np.full(t.size, float(s["value"]))
    if profile.kind == "steps":
        idx = np.searchsorted(np.asarray(s["times"]), t, side="right") - 1
        values = np.concatenate([[0.0], np.asarray(s["values"])])
        return np.asarray(values[idx + 1], dtype=float)
    if profile.kind == "square":
        phase = np.floor((t - s["start"]) / (0.5 * s["period"]))
        levels = np.where(phase % 2 == 0, s["high"], s["low"])
        return np.asarray(np.where(t < s["start"], s["low"], levels), dtype=np.float64)
    if profile.kind == "chirp":
        tt = np.clip(t - s["start"], 0.0, None)
        span = max(float(t[-1] - s["start"]), 1e-9)
        phase = 2 * np.pi * (s["f0"] * tt + (s["f1"] - s["f0"]) * tt**2 / (2 * span))
        return np.asarray(
            s["offset"] + np.where(t < s["start"], 0.0, s["amplitude"] * np.sin(phase))
        )
    log = tables[s["file"]]
    if s["column"] not in log.names:
        raise MotosimError(f"{s['file']}: no column {s['column']!r}; have {', '.join(log.names)}")
    idx = np.clip(np.searchsorted(log.t, t, side="right") - 1, 0, log.t.size - 1)
    return np.asarray(log[s["column"]][idx], dtype=float)


def _path(spec: PathSpec, length: float) -> paths.Path:
    s = spec.settings
    if spec.kind == "straight":
        return paths.straight(length)
    if spec.kind == "lane_change":
        return paths.lane_change(s["offset"], length=s["length"], start=s["start"], total=length)
    if spec.kind == "slalom":
        return paths.slalom(
            s["amplitude"], wavelength=s["wavelength"], cycles=s["cycles"], start=s["start"],
            total=length,
        )  # fmt: skip
    if spec.kind == "turn":
        return paths.constant_radius_turn(
            s["radius"], angle=s["angle"], start=s["start"], transition=s["transition"],
            total=length,
        )  # fmt: skip
    return paths.obstacle_avoidance(
        s["offset"], length=s["length"], hold=s["hold"], start=s["start"], total=length
    )


@dataclass(frozen=True, slots=True)
class RunInputs:
    """Everything a scenario refers to, resolved: parameter sets, controller, tables."""

    scenario: Scenario
    sharp: SharpParameters
    true_handlebar: HandlebarParameters
    nominal_handlebar: HandlebarParameters
    controller: StateSpace | None
    tables: Mapping[str, TimeSeries]


def prepare(
    scenario: Scenario,
    *,
    sharp: SharpParameters,
    true_handlebar: HandlebarParameters,
    nominal_handlebar: HandlebarParameters,
    controller: StateSpace | None,
    tables: Mapping[str, TimeSeries] | None = None,
) -> RunInputs:
    """Apply the scenario's perturbations to the true handlebar and bundle the inputs.

    The true handlebar's J_eq and beta_eq are scaled by the scenario's factors and its dry
    friction removed when ``friction = false``; the nominal one is used as given (also without
    dry friction then, as the paper neglects it in that case).
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
    if (
        scenario.controller.kind != "none"
        and scenario.architecture == "closed_loop"
        and controller is None
    ):
        raise MotosimError('the scenario needs a controller: give one (or kind = "none")')
    return RunInputs(scenario, sharp, true, nominal, controller, tables or {})


@njit(cache=True)
def _run_chunk(
    k0: int,
    out: Array,
    hb: Array,
    hbp: Array,
    n_sub: int,
    tau_profile: Array,
    rider_kind: int,
    path: Array,
    path_ds: float,
    rg_speeds: Array,
    rg_K: Array,
    rg_xss: Array,
    rg_tauss: Array,
    rg: Array,
    rider_state: Array,
    meas_every: int,
    quantum: float,
    noise: Array,
    est: Array,
    diff: Array,
    flags: Array,
    est_kind: int,
    Phi: Array,
    Gamma: Array,
    gain: Array,
    p: Array,
    diff_p: Array,
    z: Array,
    work: Array,
    A0: Array,
    A1: Array,
    Bv: Array,
    bikep: Array,
    force: Array,
    n_bike: int,
    true_input: bool,
    ctrl_x: Array,
    ctrl_work: Array,
    Ad: Array,
    Bd: Array,
    Cd: Array,
    Dd: Array,
    max_current: float,
    ctrl_on: bool,
    held: Array,
    h: float,
) -> None:
    """Advance ``out.shape[0]`` stack periods from period ``k0``, recording each."""
    J, beta, beta_s, nkt = hbp[0], hbp[1], hbp[2], hbp[3]
    m, m_eq, v_min = bikep[0], bikep[1], bikep[2]
    h_sub = h / n_sub
    for row in range(out.shape[0]):
        k = k0 + row
        t = k * h
        new_sample = k % meas_every == 0
        if new_sample:  # the sensors: quantised angle; the current loop's command is measured
            theta_meas = math.floor(hb[0] / quantum + 0.5) * quantum if quantum > 0.0 else hb[0]
            held[0] = theta_meas
            held[1] = stack_command(
                ctrl_x, Ad, Bd, Cd, Dd, theta_meas, z[5], max_current, ctrl_on, ctrl_work
            )
        theta_meas, i_cmd = held[0], held[1]
        rate_hat, tau_hat = stack_update(
            est, diff, flags, est_kind, Phi, Gamma, gain, p, diff_p,
            theta_meas, i_cmd + noise[k], new_sample,
        )  # fmt: skip
        # the rider: a profile, or the virtual rider looking at the motorcycle
        e_y = 0.0
        if rider_kind == 1:
            tau_rider, idx, e_y = rider_torque(
                z[:8], z[8], z[9], z[10], z[11], int(rider_state[0]), path, path_ds,
                rg_speeds, rg_K, rg_xss, rg_tauss, rg[0], rg[1],
            )  # fmt: skip
            rider_state[0] = idx
        else:
            tau_rider = tau_profile[k * n_sub]
        friction = -beta_s if hb[1] > 0.0 else (beta_s if hb[1] < 0.0 else 0.0)
        o = out[row]
        o[0], o[1], o[2], o[3] = t, tau_rider, tau_hat, friction
        o[4], o[5], o[6], o[7] = hb[0], hb[1], theta_meas, rate_hat
        o[8], o[9], o[10], o[11] = i_cmd, nkt * i_cmd, z[5], z[8]
        o[12], o[13], o[14], o[15], o[16] = z[0], z[1], z[2], z[3], z[4]
        o[17], o[18], o[19], o[20], o[21], o[22] = z[6], z[7], z[9], z[10], z[11], e_y
        # the virtual motorcycle, driven by the estimate (or the true torque)
        steer = tau_rider if true_input else tau_hat
        for _ in range(n_bike):
            bike_rk4(z, work, A0, A1, Bv, steer, force[k], m, m_eq, v_min, h / n_bike)
        # the true handlebar over the period, the current held: one exact step while the
        # rider torque is constant over it, else one per plant sub-step
        steady = rider_kind == 1
        if not steady:
            steady = True
            for j in range(1, n_sub):
                if tau_profile[k * n_sub + j] != tau_rider:
                    steady = False
                    break
        if steady:
            hb[0], hb[1] = step_exact(hb[0], hb[1], tau_rider + nkt * i_cmd, J, beta, beta_s, h)
        else:
            for j in range(n_sub):
                tr = tau_profile[k * n_sub + j]
                hb[0], hb[1] = step_exact(hb[0], hb[1], tr + nkt * i_cmd, J, beta, beta_s, h_sub)


def _controller_arrays(inputs: RunInputs, h_meas: float) -> tuple[Array, ...]:
    sc = inputs.scenario
    if sc.architecture == "open_loop" or sc.controller.kind == "none" or inputs.controller is None:
        return np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.zeros((1, 1))
    K = discretize(inputs.controller, h_meas, sc.controller.discretization)
    return K.A, K.B, K.C, K.D


def simulate(
    inputs: RunInputs,
    *,
    rng: np.random.Generator,
    on_block: Callable[[Array], None] | None = None,
    chunk: float = 1.0,
    keep: bool = True,
) -> TimeSeries:
    """Simulate a scenario, block by block.

    Parameters
    ----------
    inputs : RunInputs
        From :func:`prepare`.
    rng : numpy.random.Generator
        Source of the current-sensor noise.
    on_block : callable, optional
        Called with each recorded block (rows of :data:`SIGNALS`) as soon as it is computed,
        for example to write it to a file and advance a progress bar.
    chunk : float
        Simulated time per block [s].
    keep : bool
        Keep and return every row (else the result holds only the last block).

    Returns
    -------
    TimeSeries
        The recorded signals (without ``t``, which is the time axis).

    Raises
    ------
    MotosimError
        If a design is impossible at the scenario's rates.
    """
    sc = inputs.scenario
    h = 1.0 / sc.rates.control
    h_meas = 1.0 / sc.rates.measurement
    n_sub = round(sc.rates.plant / sc.rates.control)
    meas_every = round(sc.rates.control / sc.rates.measurement)
    n = round(sc.duration / h)
    t: Array = np.arange(n, dtype=np.float64) * h
    hb = inputs.true_handlebar
    nominal = inputs.nominal_handlebar
    t_fine = (np.arange(n * n_sub) / (n * n_sub)) * (n * h)
    rider = sc.rider
    if rider.kind == "torque":
        assert rider.profile is not None
        tau_profile = sample_profile(rider.profile, t_fine, inputs.tables)
        path_arr, path_ds = np.zeros((4, 2)), 1.0
        gains = design_rider(inputs.sharp, speeds=np.array([1.0, 2.0]))
    else:
        assert rider.path is not None
        tau_profile = np.zeros(1)
        route = _path(rider.path, max(sc.motorcycle.speed, 20.0) * sc.duration * 1.5 + 200.0)
        path_arr, path_ds = np.vstack([route.x, route.y, route.psi, route.kappa]), route.ds
        gains = design_rider(
            inputs.sharp,
            lateral_tolerance=rider.lateral_tolerance,
            course_tolerance=rider.course_tolerance,
            torque_scale=rider.torque_scale,
            preview=rider.preview,
            max_torque=rider.max_torque,
        )
    est = kernel_arguments(
        sc.estimator.name, nominal, h_meas, friction_compensation=sc.estimator.friction_compensation
    )
    lip = sc.estimator.lipschitz
    diff_p = np.array([h_meas, 1.5 * math.sqrt(lip), 1.1 * lip])
    mc = sc.motorcycle
    d = derived_geometry(inputs.sharp)
    A0, A1, Bv = sharp_model.lpv_matrices(inputs.sharp)
    drive = sample_profile(mc.drive_torque, t, inputs.tables)
    brake = np.maximum(sample_profile(mc.brake_torque, t, inputs.tables), 0.0)
    force = (drive - brake) / d["r_D"] + sample_profile(mc.wind_force, t, inputs.tables)
    Ad, Bd, Cd, Dd = _controller_arrays(inputs, h_meas)
    quantum = 2 * math.pi / 2**sc.measurement.encoder_bits if sc.measurement.encoder_bits else 0.0
    noise = (
        rng.normal(0.0, sc.measurement.current_noise, n)
        if sc.measurement.current_noise
        else np.zeros(n)
    )
    z = np.zeros(12)
    z[8] = mc.speed
    state = {
        "hb": np.zeros(2), "rider": np.zeros(1), "est": np.zeros(4), "diff": np.zeros(2),
        "flags": np.array([1.0, 0.0, 0.0]), "ctrl": np.zeros(Ad.shape[0]), "held": np.zeros(2),
    }  # fmt: skip
    rows = max(1, round(chunk / h))
    hb_p = np.array([hb.J_eq, hb.beta_eq, hb.beta_s, nominal.torque_per_amp])
    blocks = []
    for k0 in range(0, n, rows):
        out = np.empty((min(rows, n - k0), len(SIGNALS)))
        _run_chunk(
            k0, out, state["hb"], hb_p,
            n_sub, tau_profile, 1 if rider.kind == "virtual" else 0, path_arr, path_ds,
            gains.speeds, gains.K, gains.x_ss, gains.tau_ss,
            np.array([gains.preview, gains.max_torque]), state["rider"], meas_every, quantum,
            noise, state["est"], state["diff"], state["flags"], est.kind, est.Phi, est.Gamma,
            est.gain, est.p, diff_p, z, np.zeros((13, 12)), A0, A1, Bv,
            np.array([d["m"], d["m_eq"], sharp_model.MIN_SPEED]), force,
            max(1, math.ceil(h / _BIKE_STEP - 1e-9)), mc.input == "true", state["ctrl"],
            np.zeros(max(1, Ad.shape[0])), Ad, Bd, Cd, Dd, sc.controller.max_current,
            sc.architecture == "closed_loop" and Ad.shape[0] + abs(Dd[0, 0]) > 0, state["held"], h,
        )  # fmt: skip
        if not np.all(np.isfinite(out)):
            raise MotosimError(
                f"the simulation diverged near t = {out[0, 0]:.3f} s (a non-finite signal); "
                "check the rates, the controller and the rider"
            )
        if on_block is not None:
            on_block(out)
        if keep or k0 + rows >= n:
            blocks.append(out)
    data = np.vstack(blocks)
    return TimeSeries(data[:, 0].copy(), data[:, 1:].copy(), SIGNALS[1:])


def run_metadata(inputs: RunInputs) -> dict[str, object]:
    """What produced a run: scenario, parameters and version, as plain JSON-able values."""
    return {
        "version": __version__,
        "scenario": dataclasses.asdict(inputs.scenario),
        "sharp": dataclasses.asdict(inputs.sharp),
        "true_handlebar": dataclasses.asdict(inputs.true_handlebar),
        "nominal_handlebar": dataclasses.asdict(inputs.nominal_handlebar),
        "controller": None
        if inputs.controller is None
        else {k: getattr(inputs.controller, k).tolist() for k in "ABCD"},
    }
