"""The ``[realtime]`` table of a scenario file: the safety limits and the virtual rig.

A scenario file that ``motosim run`` and ``motosim rig`` take is a scenario of
:mod:`motosim.sim.scenario` plus one table, ignored by ``motosim simulate``::

    [realtime]          status_latency = 0 [s]: the drive's status frames' latency on the
                        bus, from the drive's sample to the frame's arrival at the host
    [realtime.safety]   max_current [A], max_slew [A/s], max_speed [rad/s],
                        speed_band [rad/s], soft_stop [rad], hard_stop [rad],
                        end_stop_gain [A/rad], hands_off_torque [N*m], hands_off_time [s],
                        hands_off_gain, fade_in = 0.5 [s], watchdog_periods = 3,
                        frozen_angle = 0.05 [rad]
    [realtime.rig]      the fields of :class:`~motosim.rt.rig.RigSettings` (each optional:
                        the plant, status rate, encoder and current noise default to the
                        scenario's rates and measurement, the current limit to its
                        controller's), with a sub-table ``faults``
                        (:class:`~motosim.rt.rig.RigFaults`)

The safety limits have no defaults but the fade-in, the watchdog and the frozen-sensor
monitor's angle: they belong to the
handlebar on the bench and must be written down for it. The status latency defaults to 0 (a
fresh sample, what the stack was designed for); given, the stack accounts for the frame's
age (:func:`frame_age`, :func:`motosim.sim.stack.account_for_delay`).
"""

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from motosim.errors import MotosimError, warn
from motosim.params.toml import read_toml
from motosim.rt.safety import SafetyLimits

if TYPE_CHECKING:
    from motosim.io.cache import DesignCache
    from motosim.rt.rig import RigSettings
    from motosim.sim import RunInputs, Scenario

__all__ = [
    "MAX_LATENCY",
    "RealtimeOptions",
    "frame_age",
    "load_realtime",
    "parse_latency",
    "parse_safety",
    "read_realtime",
    "refuse_offline_only",
    "resolve_realtime",
    "rig_settings",
    "run_paces",
    "split_realtime",
    "table_number",
    "within_safety",
]

MAX_LATENCY = 1.0
"""Largest ``status_latency`` read [s]; the stack accounts for up to one frame period."""


def split_realtime(
    data: Mapping[str, Any], *, origin: str
) -> tuple[dict[str, Any], dict[str, Any]]:
    """Separate the ``[realtime]`` table from the rest of a scenario file's data.

    Examples
    --------
    >>> split_realtime({"scenario": {}, "realtime": {"rig": {}}}, origin="x.toml")
    ({'scenario': {}}, {'rig': {}})
    """
    rest = {key: value for key, value in data.items() if key != "realtime"}
    table = data.get("realtime", {})
    if not isinstance(table, Mapping):
        raise MotosimError(f"{origin}: [realtime] must be a table")
    unknown = set(table) - {"safety", "rig", "status_latency"}
    if unknown:
        raise MotosimError(
            f"{origin}: unknown key {sorted(unknown)[0]!r} in [realtime]; expected "
            "status_latency, safety, rig"
        )
    return rest, dict(table)


@dataclass(frozen=True, slots=True)
class RealtimeOptions:
    """The keys of the ``[realtime]`` table itself (beside its ``safety`` and ``rig`` tables).

    Attributes
    ----------
    status_latency : float
        The drive's status frames' latency on the bus, from the drive's sample of the angle
        and current to the frame's arrival at the host [s], 0 to :data:`MAX_LATENCY`; 0: a
        fresh sample, what the stack was designed for.
    """

    status_latency: float = 0.0


def parse_latency(table: Mapping[str, Any], *, origin: str) -> float:
    """``status_latency`` of the ``[realtime]`` table [s] (0 when absent).

    Examples
    --------
    >>> parse_latency({"status_latency": 0.002}, origin="x.toml"), parse_latency({}, origin="x")
    (0.002, 0.0)
    """
    value = table.get("status_latency", 0.0)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise MotosimError(
            f"{origin}: [realtime] status_latency = {value!r}: expected a number of seconds"
        )
    if not (math.isfinite(value) and 0.0 <= value <= MAX_LATENCY):
        raise MotosimError(
            f"{origin}: [realtime] status_latency = {value!r} s; expected 0 to {MAX_LATENCY:g} s"
        )
    return float(value)


def frame_age(
    latency: float, *, pace: str, control_rate: float, measurement_rate: float, origin: str
) -> float:
    """The status frame's age when the stack reads it [s], from its latency on the bus.

    Paced by the frames (``pace`` "bus") the loop runs when a frame arrives: the age is the
    latency. Paced by its clock (``pace`` "clock") the frame waits for the next period, half
    a control period on average. A latency of 0 is the stack's design (a fresh sample): 0.

    Raises
    ------
    MotosimError
        If the age exceeds one frame period (the stack accounts for up to one).

    Examples
    --------
    >>> kw = {"control_rate": 1000.0, "measurement_rate": 100.0, "origin": "x.toml"}
    >>> frame_age(0.005, pace="clock", **kw), frame_age(0.005, pace="bus", **kw)
    (0.0055, 0.005)
    """
    if latency == 0.0:
        return 0.0
    age = latency + (0.5 / control_rate if pace == "clock" else 0.0)
    period = 1.0 / measurement_rate
    if age > period * (1.0 + 1e-9):
        wait = ", and half a control period waiting for the clock," if pace == "clock" else ""
        raise MotosimError(
            f"{origin}: [realtime] status_latency = {latency:g} s{wait} makes the status "
            f"frame {1e3 * age:.3g} ms old; the stack accounts for up to one frame period "
            f"({1e3 * period:.3g} ms at {measurement_rate:g} Hz): lower the latency or the "
            "frame rate"
        )
    return age


def run_paces(control_rate: float, measurement_rate: float) -> tuple[str, ...]:
    """The paces ``motosim run --pace`` takes at the loop's and the status frames' rates
    [Hz]: ``"clock"``, and ``"bus"`` when the loop has one period per status frame.

    The last is the one under which the status frame is youngest when the stack reads it
    (:func:`frame_age`): a command that serves whichever run comes (``motosim rig``)
    refuses, under it, what every run refuses.

    Examples
    --------
    >>> run_paces(1000.0, 100.0), run_paces(100.0, 100.0)
    (('clock',), ('clock', 'bus'))
    """
    return ("clock", "bus") if round(control_rate / measurement_rate) == 1 else ("clock",)


def parse_safety(table: Any, *, origin: str) -> SafetyLimits:
    """:class:`SafetyLimits` from the ``[realtime.safety]`` table (every limit required)."""
    where = f"{origin}: [realtime.safety]"
    if table is None:
        raise MotosimError(
            f"{where} is missing; the run needs the handlebar's safety limits (the SIMACOM "
            "handlebar's are in scenarios/realtime_square.toml; see the real-time guide)"
        )
    if not isinstance(table, Mapping):
        raise MotosimError(f"{where} must be a table")
    names = [f.name for f in fields(SafetyLimits)]
    optional = {"fade_in", "watchdog_periods", "frozen_angle"}
    for key in table:
        if key not in names:
            raise MotosimError(f"{where}: unknown key {key!r}; expected one of {', '.join(names)}")
    missing = [n for n in names if n not in table and n not in optional]
    if missing:
        raise MotosimError(f"{where}: missing {', '.join(missing)}")
    integer = "watchdog_periods"
    return SafetyLimits(**{k: table_number(k, v, where, k == integer) for k, v in table.items()})


def table_number(key: str, value: Any, where: str, integer: bool = False) -> Any:
    """The number ``value`` of ``key`` in the table ``where`` (a float, or with ``integer`` the
    integer as it is), or a one-line error."""
    if isinstance(value, bool) or not isinstance(value, int if integer else int | float):
        raise MotosimError(
            f"{where} {key} = {value!r}: expected {'an integer' if integer else 'a number'}"
        )
    return value if integer else float(value)


def within_safety(inputs: "RunInputs", limits: SafetyLimits) -> "RunInputs":
    """The run with its controller's current limit lowered to the safety stage's clamp.

    The stack saturates its command where the safety stage would clamp it, so its
    estimator is told the current the drive carries, not a command the clamp cuts: told
    more than the drive carries, it reads the difference as rider torque until the next
    status frame, and with 100 Hz frames under a 1 kHz loop that sustains a limit cycle at
    the clamp.
    """
    controller = inputs.scenario.controller
    if limits.max_current >= controller.max_current:
        return inputs
    clamped = replace(controller, max_current=limits.max_current)
    return replace(inputs, scenario=replace(inputs.scenario, controller=clamped))


def refuse_offline_only(scenario: "Scenario", *, origin: str) -> None:
    """Refuse what ``scenario`` asks of the offline simulator only: a real-time run (``motosim
    run``, :class:`~motosim.rt.lockstep.Lockstep`) steps the virtual motorcycle by the
    estimate (of the observer, or of a torque sensor's ``HB_TORQUE`` frames).

    Raises
    ------
    MotosimError
        One line, starting with ``origin`` (the scenario file, or its name).
    """
    if scenario.motorcycle.input == "true":
        raise MotosimError(
            f'{origin}: motorcycle input = "true" is a simulation-only reference; expected '
            '"estimate" for a real-time run'
        )


def load_realtime(
    path: str, *, safety: bool = False, pace: str | None = None, cache: "DesignCache | None" = None
) -> tuple["RunInputs", dict[str, Any]]:
    """Read a scenario file: its resolved run and its ``[realtime]`` table
    (:func:`read_realtime`, then :func:`resolve_realtime`)."""
    scenario, realtime = read_realtime(path, safety=safety, pace=pace)
    return resolve_realtime(path, scenario, cache), realtime


def read_realtime(
    path: str, *, safety: bool = False, pace: str | None = None
) -> tuple["Scenario", dict[str, Any]]:
    """Read and check a scenario file: its scenario and its ``[realtime]`` table.

    With ``safety``, a missing ``[realtime.safety]`` table is refused here, before the run is
    resolved (which designs its controller: seconds). A ``status_latency`` that makes the
    status frame older than the stack accounts for is refused here too, in the line
    ``motosim run`` gives (:func:`frame_age`): for ``motosim run`` at its
    ``pace``; without a ``pace`` (``motosim rig``, which serves whichever run comes) at the
    pace of ``run`` that reads the frame youngest at the scenario's rates
    (:func:`run_paces`), so that a lab learns it before starting the rig.
    The rig thus keeps a latency that ``run --pace clock`` refuses and ``run --pace bus``
    takes (equal control and measurement rates: up to a frame period against half a control
    period less). The rig's own ``[realtime.rig]`` latency, the bus it emulates, is not
    bounded by the frame period: a slow bus is what it is there to show ``run``.
    """
    from motosim.sim import parse_scenario
    from motosim.sim.scenario import implausible

    data = read_toml(Path(path), what="scenario file")
    rest, realtime = split_realtime(data, origin=str(path))
    scenario = parse_scenario(rest, origin=str(path))
    for line in implausible(scenario):
        warn(f"{path}: {line}")
    # both tables are checked whichever command reads the file: a typo in the table the
    # other command uses is refused now, not when that command runs
    if "safety" in realtime or safety:
        parse_safety(realtime.get("safety"), origin=str(path))
    rates = scenario.rates
    frame_age(
        parse_latency(realtime, origin=str(path)),
        pace=pace or run_paces(rates.control, rates.measurement)[-1],
        control_rate=rates.control,
        measurement_rate=rates.measurement,
        origin=str(path),
    )
    rig_settings(scenario, realtime, origin=str(path))
    _check_realtime_motorcycle(scenario, origin=str(path))
    return scenario, realtime


def resolve_realtime(
    path: str, scenario: "Scenario", cache: "DesignCache | None" = None
) -> "RunInputs":
    """The run of a scenario read by :func:`read_realtime` (its files resolved beside
    ``path``, its controller designed, from ``cache`` when one is given)."""
    from motosim.io.runs import resolve

    source = Path(path)
    if cache is None:
        return resolve(scenario, source.parent)
    with cache.designing(scenario.name):
        return resolve(scenario, source.parent, cache=cache)


def _check_realtime_motorcycle(scenario: "Scenario", *, origin: str) -> None:
    """Refuse what the real-time loop does not read of a multibody motorcycle: its drive and
    brake torques and the road's friction change only offline (motosim simulate)."""
    from motosim.sim.scenario import ConstantProfile, Road

    mc = scenario.motorcycle
    if mc.model != "multibody":
        return
    for key in ("drive_torque", "front_brake_torque", "rear_brake_torque"):
        if getattr(mc, key) != ConstantProfile(0.0):
            raise MotosimError(
                f"{origin}: [motorcycle] {key} on the multibody motorcycle is read offline "
                "only (motosim simulate); expected none in real time"
            )
    if scenario.road != Road():
        raise MotosimError(
            f"{origin}: [road] friction is read offline only (motosim simulate); expected "
            "none in real time (the road's friction 1)"
        )


def rig_settings(scenario: "Scenario", realtime: dict[str, Any], *, origin: str) -> "RigSettings":
    """The virtual rig's settings: the ``[realtime.rig]`` table over the scenario's values."""
    from motosim.rt.rig import parse_rig

    return parse_rig(
        realtime.get("rig", {}),
        base={
            "plant_rate": scenario.rates.plant,
            "status_rate": scenario.rates.measurement,
            "encoder_bits": scenario.measurement.encoder_bits,
            "current_noise": scenario.measurement.current_noise,
            "max_current": scenario.controller.max_current,
        },
        where=f"{origin}: [realtime.rig]",
    )
