"""The ``[realtime]`` table of a scenario file: the safety limits and the virtual rig.

A scenario file that ``motosim run`` and ``motosim rig`` take is a scenario of
:mod:`motosim.sim.scenario` plus one table, ignored by ``motosim simulate``::

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
handlebar on the bench and must be written down for it.
"""

from collections.abc import Mapping
from dataclasses import fields, replace
from typing import TYPE_CHECKING, Any

from motosim.errors import MotosimError
from motosim.rt.safety import SafetyLimits

if TYPE_CHECKING:
    from motosim.sim import RunInputs

__all__ = ["parse_safety", "split_realtime", "within_safety"]


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
    unknown = set(table) - {"safety", "rig"}
    if unknown:
        raise MotosimError(
            f"{origin}: unknown key {sorted(unknown)[0]!r} in [realtime]; expected safety, rig"
        )
    return rest, dict(table)


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
    values: dict[str, Any] = {}
    for key, value in table.items():
        if key == "watchdog_periods":
            if not isinstance(value, int) or isinstance(value, bool):
                raise MotosimError(f"{where} watchdog_periods = {value!r}: expected an integer")
            values[key] = value
        elif isinstance(value, bool) or not isinstance(value, int | float):
            raise MotosimError(f"{where} {key} = {value!r}: expected a number")
        else:
            values[key] = float(value)
    return SafetyLimits(**values)


def within_safety(inputs: "RunInputs", limits: SafetyLimits) -> "RunInputs":
    """The run with its controller's current limit lowered to the safety stage's clamp.

    The stack saturates its command where the safety stage would clamp it, so its
    estimator is told the current the drive carries, not a command the clamp cuts: told
    more than the drive carries, it reads the difference as rider torque until the next
    status frame, and with 100 Hz frames under a 1 kHz loop that sustains an 8 Hz limit
    cycle at the clamp (measured on the lane change at 20 m/s with a 10 A clamp).
    """
    controller = inputs.scenario.controller
    if limits.max_current >= controller.max_current:
        return inputs
    clamped = replace(controller, max_current=limits.max_current)
    return replace(inputs, scenario=replace(inputs.scenario, controller=clamped))
