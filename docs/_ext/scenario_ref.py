"""The scenario file reference, generated from the dataclasses that parse it.

Keys, types and defaults come from :mod:`motosim.sim.scenario` (and, for ``[realtime]``,
:class:`motosim.rt.safety.SafetyLimits`, :class:`motosim.rt.rig.RigSettings` and
:class:`motosim.rt.rig.RigFaults`); only the meaning of each key is written here, in
:data:`DESCRIPTIONS`. ``tests/unit/test_docs.py`` checks that every key has one (a new key
without a description fails the tests) and that no description is left for a removed key.
"""

import dataclasses
import math
import types
import typing
from typing import Any, Literal, get_args, get_origin

from motosim.rt.config import RealtimeOptions
from motosim.rt.rig import RigFaults, RigSettings
from motosim.rt.safety import SafetyLimits
from motosim.sim import scenario as sc
from motosim.sim.hands import GRIPS, Hands

# table -> the dataclass whose fields are its keys
TABLES: dict[str, type] = {
    "scenario": sc.Scenario,
    "rates": sc.Rates,
    "measurement": sc.Measurement,
    "motorcycle": sc.Motorcycle,
    "rider": sc.Rider,
    "handlebar": sc.Handlebar,
    "estimator": sc.Estimator,
    "controller": sc.Controller,
    "sensor": sc.Sensor,
    "sensor.torque": sc.TorqueSensor,
    "road": sc.Road,
    "rider.hands": Hands,
    "realtime": RealtimeOptions,
    "realtime.safety": SafetyLimits,
    "realtime.rig": RigSettings,
    "realtime.rig.faults": RigFaults,
}
# profiles and paths: inline tables tagged by ``kind``
TAGGED: dict[str, dict[str, type]] = {"profile": dict(sc.PROFILES), "path": dict(sc.PATHS)}

DESCRIPTIONS: dict[str, str] = {
    # [scenario]
    "scenario.name": "Name of the run, shown in reports.",
    "scenario.description": "One line on what the run shows.",
    "scenario.duration": "Length of the run [s].",
    "scenario.seed": "Seed of the sensor noise (a campaign sets it per run).",
    "scenario.architecture": (
        '`"closed_loop"`: the paper\'s Fig. 7, with torque feedback; `"open_loop"`: Fig. 9, '
        "without it."
    ),
    # [rates]
    "rates.plant": "Sub-step rate of the simulated handlebar and motorcycle [Hz].",
    "rates.control": "Rate of the stack's step (estimator, motorcycle, command) [Hz].",
    "rates.measurement": (
        "Rate of the angle and current samples [Hz] (100 for the paper's CAN link); "
        "`control` must be a whole multiple of it and `plant` of `control`."
    ),
    # [measurement]
    "measurement.encoder_bits": "Encoder resolution per handlebar revolution [bits]; 0: exact.",
    "measurement.current_noise": "Standard deviation of the current sensor's noise [A].",
    # [motorcycle]
    "motorcycle.model": (
        '`"sharp1971"`: Sharp\'s linear model with eq. (2); `"multibody"`: the multibody '
        "motorcycle on tyres (load transfer, pitch, slips, tyres that saturate at the road's "
        "friction; the models guide)."
    ),
    "motorcycle.params": (
        "Parameter set of the virtual motorcycle (a packaged name or a file): a `sharp` set, "
        "or with the multibody model a `multibody` set with its tyres (`sel2004_motorcycle`)."
    ),
    "motorcycle.speed": "Initial forward speed [m/s].",
    "motorcycle.input": (
        '`"estimate"`: the motorcycle is driven by the estimated rider torque (the '
        'simulator); `"true"`: by the true torque (for comparison).'
    ),
    "motorcycle.drive_torque": "Drive torque at the rear wheel [N*m], eq. (2); -5000 to 5000.",
    "motorcycle.brake_torque": "Brake torque [N*m], eq. (2); 0 to 5000 (Sharp 1971 only).",
    "motorcycle.front_brake_torque": (
        "Front brake torque [N*m], 0 to 5000, opposing the wheel's spin (the multibody model)."
    ),
    "motorcycle.rear_brake_torque": "Rear brake torque [N*m], 0 to 5000 (the multibody model).",
    "motorcycle.wind_force": "Longitudinal wind force [N], eq. (2); -5000 to 5000.",
    "motorcycle.side_wind": (
        "Lateral wind force, to the right [N], with its yaw and roll moments; -3000 to 3000."
    ),
    "motorcycle.side_wind_height": "Height at which the side wind acts [m].",
    # [rider]
    "rider.kind": '`"torque"`: a torque profile; `"virtual"`: a rider steering along a path.',
    "rider.profile": "The rider's torque [N*m] (kind `torque`); -1000 to 1000.",
    "rider.path": "The path the virtual rider follows (kind `virtual`; default straight).",
    "rider.probe": "A torque profile added to the virtual rider's (e.g. a chirp) [N*m].",
    "rider.lateral_tolerance": (
        "Bryson weight of the LQR: a lateral error [m] that costs as much as `torque_scale`."
    ),
    "rider.course_tolerance": "Likewise, a course-angle error [rad].",
    "rider.torque_scale": "The rider torque [N*m] the two errors are weighed against.",
    "rider.preview": "How far ahead the rider reads the path's curvature [s].",
    "rider.max_torque": "The virtual rider's torque limit [N*m] (70: the paper's Remark 3.3).",
    "rider.brake_control": (
        "On the multibody motorcycle, the virtual rider modulates the brake demands to a slip "
        "target and keeps the rear wheel down (an ABS); false: the brakes act as demanded."
    ),
    "rider.brake_slip": "The braking slip it holds, -kappa, 0 to 0.5 (0.1: near the tyres' peak).",
    "rider.hands": (
        "The arms' passive impedance at the handlebar, added to the active torque of either "
        "kind: a grip, " + ", ".join(f'`"{g}"`' for g in GRIPS) + " (`motosim.sim.hands.GRIPS`, "
        "`off`: no arms' impedance, a pure torque source), or a table (below). Default: "
        '`"relaxed"` (`motosim.sim.grips.DEFAULT_GRIP`) where the stack models hands, on '
        'Sharp 1971 without a design file or a torque sensor; elsewhere `"off"`.'
    ),
    "rider.hands_off": (
        "Phases `[[t0, t1], ...]` [s] in which nobody holds the handlebar: no active and no "
        "passive torque."
    ),
    # [rider.hands]
    "rider.hands.inertia": "J_a, the arms' inertia about the steering axis [kg*m^2], 0 to 1.",
    "rider.hands.damping": "c_a [N*m*s/rad], 0 to 100.",
    "rider.hands.stiffness": "k_a about `hold` [N*m/rad], 0 to 1000.",
    "rider.hands.hold": "The handlebar angle the hands hold [rad].",
    "rider.hands.source": "Where the values come from.",
    # [handlebar]
    "handlebar.true": "Parameter set of the simulated (true) handlebar.",
    "handlebar.nominal": "Parameter set the observer and the controller are designed for.",
    "handlebar.inertia_factor": "Factor on the true handlebar's J_eq.",
    "handlebar.damping_factor": "Factor on the true handlebar's beta_eq.",
    "handlebar.friction": "Whether the true handlebar has its dry friction beta_s.",
    # [estimator]
    "estimator.name": (
        'Rider-torque estimator: `"walcott_zak"`, `"inverse_dynamics"`, `"kalman"`, or '
        '`"torque_sensor"` (the torque measured by the sensor of `[sensor] torque`, ideal '
        "without it)."
    ),
    "estimator.friction_compensation": "Subtract the nominal dry friction from the estimate.",
    "estimator.stick_projection": (
        "Walcott-Zak observer: while the handlebar sticks, let the dry friction hold what keeps "
        "the estimate at its last value (false: the paper's dead-zoned compensation)."
    ),
    "estimator.lipschitz": (
        "Bound L on the angle's second derivative for the differentiator [rad/s^2]."
    ),
    # [controller]
    "controller.kind": (
        '`"ours"`: designed by loop shaping (or read from `design`); `"paper"`: eq. (26); '
        '`"none"`: no feedback.'
    ),
    "controller.design": "A design file of `motosim design --out` (relative to the scenario).",
    "controller.bandwidth": (
        "Tracking bandwidth of the designed controller [Hz]; by default 10 Hz, a fifth of the "
        "measurement rate below 50 Hz."
    ),
    "controller.order": "Order of the tuned K_s (0 to 3).",
    "controller.integral_corner": (
        "Corner of the loop-shaping weight W1 = k (s + a omega_c) / s as a fraction a of the "
        "bandwidth, from 1e-6 to 0.5 (0.1): more tracks tighter below the bandwidth, with less "
        "phase margin and fewer handlebars of the robustness grid kept."
    ),
    "controller.discretization": (
        'Discretisation of a continuous controller: `"zoh"` or `"tustin"`.'
    ),
    "controller.max_current": "Limit of the current command [A].",
    "controller.feedforward": (
        'Feedforward terms, a list of `"rider"` (cancel the estimated rider torque) and '
        '`"reference"` (the nominal handlebar\'s inverse dynamics along the steer angle); '
        "default both for ours, none for the paper's."
    ),
    "controller.prediction": (
        "Cancel the rider torque predicted over the estimate's lag, tau_r_hat + T_d r (T_d the "
        "estimate filter's delay, r the estimate's rate through a 10 Hz notch and a 3 Hz "
        'low-pass); needs `"rider"` and the Walcott-Zak observer. Default: on with them '
        "from a 1 kHz measurement rate and at the paper's 100 Hz."
    ),
    "controller.grip": (
        'The rider\'s grip the stack is designed for, `"relaxed"`, `"firm"` or `"off"` (the '
        "handlebar alone): the observer, the controller and the feedforward model the handlebar "
        "held by 0.4 of the grip's inertia and damping, and the virtual motorcycle carries the "
        "same on its front frame. Default: the rider's `hands`; none with a design file, a "
        "torque sensor or the multibody motorcycle."
    ),
    # [road]
    "road.friction": (
        "Tyre-road friction coefficient over time (a profile; steps from t = 0), 0.01 to 3: "
        "about 1 dry, 0.5-0.7 wet, 0.1 on ice (the multibody model)."
    ),
    # [sensor]
    "sensor.torque": (
        "A rider-torque sensor at the grips (the table below), read by `[estimator] name = "
        '"torque_sensor"`; the paper\'s stack has none.'
    ),
    "sensor.torque.noise": "Standard deviation of its white noise [N*m].",
    "sensor.torque.offset": "Its offset [N*m].",
    "sensor.torque.low_pass": "Corner of its first-order low-pass [Hz]; 0: none.",
    # [realtime]
    "realtime.status_latency": (
        "The status frames' latency on the bus, from the drive's sample to the frame's "
        "arrival at the host [s]; the stack accounts for the frame's age (the real-time "
        "guide). 0: a fresh sample."
    ),
    # [realtime.safety]
    "realtime.safety.max_current": "Current clamp [A], > 0.",
    "realtime.safety.max_slew": "Largest change of the command [A/s], > 0.",
    "realtime.safety.max_speed": "Handlebar rate where the speed limiter starts [rad/s].",
    "realtime.safety.speed_band": (
        "Excess rate over `max_speed` where the pushing command is gone [rad/s]."
    ),
    "realtime.safety.soft_stop": "Angle where the soft end stop's restoring spring starts [rad].",
    "realtime.safety.hard_stop": "Angle of the end-stop fault [rad], above `soft_stop`.",
    "realtime.safety.end_stop_gain": "Restoring current per radian beyond the soft stop [A/rad].",
    "realtime.safety.hands_off_torque": (
        "Estimated rider torque below which nobody holds the bar [N*m]; 0 disables."
    ),
    "realtime.safety.hands_off_time": "How long it must last [s].",
    "realtime.safety.hands_off_gain": "Scale of the command meanwhile, 0 to 1.",
    "realtime.safety.fade_in": "Ramp of the command on enable and on stop [s].",
    "realtime.safety.watchdog_periods": (
        "Status-frame periods without a valid frame that trip the watchdog."
    ),
    "realtime.safety.frozen_angle": (
        "Turn of a free handlebar [rad], predicted from the change of motor torque while the "
        "angle stands still, that trips the frozen-sensor fault."
    ),
    # [realtime.rig]
    "realtime.rig.plant_rate": "The rig's plant sub-step rate [Hz] (default: the scenario's).",
    "realtime.rig.status_rate": "Rate of the status frames [Hz] (default: the measurement rate).",
    "realtime.rig.encoder_bits": "Encoder resolution [bits] (default: the scenario's).",
    "realtime.rig.current_noise": "Current noise [A] (default: the scenario's).",
    "realtime.rig.max_current": "The drive's current limit [A] (default: the controller's).",
    "realtime.rig.current_time_constant": (
        "Time constant of the drive's current loop [s]; 0: ideal."
    ),
    "realtime.rig.command_timeout": (
        "How long the drive keeps the last command without a new one [s]."
    ),
    "realtime.rig.latency": "Mean one-way delay of a status frame [s].",
    "realtime.rig.jitter": "Standard deviation of that delay [s].",
    "realtime.rig.loss": "Probability that a frame is lost, independently.",
    "realtime.rig.burst_enter": (
        "Per-frame probability of entering a burst of lost frames (Gilbert-Elliott)."
    ),
    "realtime.rig.burst_leave": "Per-frame probability of leaving it.",
    "realtime.rig.stale": "Probability of sending the previous frame again (counter unchanged).",
    "realtime.rig.duplicate": "Probability of sending a new frame twice.",
    "realtime.rig.bus_off_at": "Start of a window in which the rig sends nothing [s].",
    "realtime.rig.bus_off_duration": "Its length [s].",
    "realtime.rig.faults": "Injected faults (the table below).",
    # [realtime.rig.faults]
    "realtime.rig.faults.frozen_encoder": "From this time [s] the angle stops changing.",
    "realtime.rig.faults.sign_flip": "From this time [s] the angle's sign is flipped.",
    "realtime.rig.faults.current_offset_at": "From this time [s] the current sensor is offset...",
    "realtime.rig.faults.current_offset": "...by this much [A].",
    "realtime.rig.faults.bad_checksum": "From this time [s] the frames carry a wrong checksum.",
    "realtime.rig.faults.estop": "At this time [s] an E-stop frame is sent.",
    "realtime.rig.faults.drive_fault": "From this time [s] the drive's fault flag is set.",
    # profiles
    "profile.constant.value": "The value.",
    "profile.steps.times": "Times of the steps [s], increasing.",
    "profile.steps.values": "The value from each time on (0 before the first).",
    "profile.square.low": "Low level (also before `start`).",
    "profile.square.high": "High level.",
    "profile.square.period": "Period [s].",
    "profile.square.start": "Start time [s].",
    "profile.chirp.amplitude": "Amplitude.",
    "profile.chirp.f0": "Start frequency [Hz], 0 to 10 000.",
    "profile.chirp.f1": "End frequency at the end of the run [Hz], 0 to 10 000.",
    "profile.chirp.start": "Start time [s].",
    "profile.chirp.offset": "Constant added.",
    "profile.multisine.amplitude": "Peak of the sum (each line has the same amplitude).",
    "profile.multisine.f0": "Lowest line [Hz], at least 1 / period.",
    "profile.multisine.f1": "Highest line [Hz].",
    "profile.multisine.period": "Period [s]: the lines are its harmonics.",
    "profile.multisine.per_decade": "Lines per decade, log-spaced (fewer where sparse).",
    "profile.multisine.start": "Start time [s]; zero before.",
    "profile.csv.file": "A CSV log (relative to the scenario), sampled and held.",
    "profile.csv.column": "Its column.",
    # paths
    "path.lane_change.offset": "Lateral offset [m], right positive.",
    "path.lane_change.length": "Length of the change [m].",
    "path.lane_change.start": "Where it starts [m].",
    "path.slalom.amplitude": "Lateral amplitude [m].",
    "path.slalom.wavelength": "Wavelength [m].",
    "path.slalom.cycles": "Number of cycles.",
    "path.slalom.start": "Where it starts [m].",
    "path.turn.radius": "Radius [m]; negative turns left.",
    "path.turn.angle": "Heading change [rad].",
    "path.turn.start": "Where it starts [m].",
    "path.turn.transition": "Length of the clothoid into and out of the turn [m].",
    "path.avoidance.offset": "Lateral offset [m].",
    "path.avoidance.length": "Length of the way out (and back) [m].",
    "path.avoidance.hold": "Length held at the offset [m].",
    "path.avoidance.start": "Where it starts [m].",
    "path.opendrive.file": (
        "An OpenDRIVE (`.xodr`) file, relative to the scenario: the reference line of its "
        "road's `<planView>` (lines, arcs, spirals, `paramPoly3` and `poly3`), "
        "moved to start at the origin heading along x, straight on past its end."
    ),
    "path.opendrive.road": 'The `id` of the road; `""`: the file\'s only road.',
    "path.opendrive.geometry": (
        "The road's geometries (`kind`, `s`, `x`, `y`, `hdg`, `length`, `curv_start`, "
        "`curv_end`, a cubic's `poly` and `p_end`, in the file's frame), read from `file` "
        "when the scenario is loaded; a saved result keeps them, so leave it out."
    ),
}


def _type(annotation: Any) -> str:
    origin, args = get_origin(annotation), get_args(annotation)
    if annotation is float:
        return "number"
    if annotation is int:
        return "integer"
    if annotation is str:
        return "string"
    if annotation is bool:
        return "boolean"
    if origin is Literal:
        return " \\| ".join(f'`"{a}"`' for a in args)
    if origin is tuple:
        return f"list of {_type(args[0])}s"
    if origin in (typing.Union, types.UnionType):
        kinds = [a for a in args if a is not type(None)]
        if all(dataclasses.is_dataclass(a) for a in kinds):
            if kinds[0] in sc.PROFILES.values():
                return "profile"
            return "path" if kinds[0] in sc.PATHS.values() else "table"
        return " or ".join(_type(a) for a in kinds)
    if dataclasses.is_dataclass(annotation):
        return "table"
    return str(annotation)


def _default(field: dataclasses.Field[Any]) -> str:
    if field.default is not dataclasses.MISSING:
        value = field.default
    elif field.default_factory is not dataclasses.MISSING:
        return "(table)"
    else:
        return "required"
    if value is None:
        return "(none)"
    if isinstance(value, float) and math.isinf(value):
        return "never"
    if dataclasses.is_dataclass(value):
        kind = getattr(value, "kind", None)
        if kind == "constant":
            return str(value.value)  # type: ignore[attr-defined]
        return "(table)"
    if isinstance(value, str):
        return f'`"{value}"`' if value else '`""`'
    return f"`{value}`"


def keys(table: str) -> list[tuple[str, str, str]]:
    """(key, type, default) of each key of a table (``[scenario]``: its own keys only)."""
    cls = TABLES[table]
    hints = typing.get_type_hints(cls)
    out = []
    for field in dataclasses.fields(cls):
        if table == "scenario" and dataclasses.is_dataclass(hints[field.name]):
            continue  # the other tables
        out.append((field.name, _type(hints[field.name]), _default(field)))
    return out


def tagged_keys(group: str, kind: str) -> list[tuple[str, str, str]]:
    """(key, type, default) of each key of a profile or path of ``kind``."""
    cls = TAGGED[group][kind]
    hints = typing.get_type_hints(cls)
    return [(f.name, _type(hints[f.name]), _default(f)) for f in dataclasses.fields(cls)]


def all_keys() -> list[str]:
    """Every documented key, as ``table.key`` (``profile.KIND.key``, ``path.KIND.key``)."""
    names = [f"{table}.{key}" for table in TABLES for key, _, _ in keys(table)]
    for group, kinds in TAGGED.items():
        for kind in kinds:
            names += [f"{group}.{kind}.{key}" for key, _, _ in tagged_keys(group, kind)]
    return names


def _rows(prefix: str, rows: list[tuple[str, str, str]]) -> list[str]:
    lines = ["| key | type | default | meaning |", "|---|---|---|---|"]
    for key, kind, default in rows:
        text = DESCRIPTIONS.get(f"{prefix}.{key}", "")
        lines.append(f"| `{key}` | {kind} | {default} | {text} |")
    return [*lines, ""]


def markdown() -> str:
    """The reference page, in MyST Markdown."""
    out = [
        "# Scenario file reference",
        "",
        "Generated from the dataclasses of `motosim.sim.scenario` (and `motosim.rt` for",
        "`[realtime]`): every table and key a scenario file may hold, its type and default.",
        "Every table but `[scenario]` is optional; an unknown key is refused with the closest",
        "known one; numbers are SI. A *profile* is an inline table with a `kind` (below);",
        "a number where a profile goes is a constant.",
        "",
    ]
    for table in TABLES:
        out += [f"## `[{table}]`", ""]
        if table.startswith("realtime"):
            out += [
                "Read by `motosim run` and `motosim rig` only (`simulate` ignores `[realtime]`).",
                "",
            ]
        out += _rows(table, keys(table))
    titles = {"profile": "Profiles (`kind = ...`)", "path": "Paths of the virtual rider"}
    for group, kinds in TAGGED.items():
        out += [f"## {titles[group]}", ""]
        for kind in kinds:
            rows = tagged_keys(group, kind)
            out += [f'### `kind = "{kind}"`', ""]
            out += _rows(f"{group}.{kind}", rows) if rows else ["No other key.", ""]
    return "\n".join(out)
