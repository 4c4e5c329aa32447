"""What ``motosim run`` and ``motosim rig`` share: their options' checks and the scenario's
``[realtime]`` table read with the run it belongs to."""

import argparse
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from motosim.cli.rtcheck import check_privilege_options
from motosim.errors import MotosimError, warn
from motosim.params.checks import short_repr
from motosim.params.toml import read_toml

if TYPE_CHECKING:
    from motosim.cueing import CueingConfig
    from motosim.io.cache import DesignCache
    from motosim.rt.rig import RigSettings
    from motosim.sim import RunInputs, Scenario

__all__ = [
    "RtOptions",
    "check_rt_options",
    "check_wait",
    "load_realtime",
    "read_realtime",
    "resolve_realtime",
    "rig_settings",
]


def _platform_address(text: str) -> tuple[str, int]:
    from motosim.rt.telemetry import parse_address

    try:
        return parse_address(text)
    except MotosimError:
        raise MotosimError(
            f"--platform-udp {text!r}; expected HOST:PORT such as 127.0.0.1:47480, or off"
        ) from None


@dataclass(frozen=True)
class RtOptions:
    """The options of run and rig that :func:`check_rt_options` parsed, for the command to use.

    Attributes
    ----------
    telemetry : (str, int) or None
        ``--telemetry`` as (host, port); None when ``off``.
    platform_udp : (str, int) or None
        ``--platform-udp`` as (host, port); None when ``off``.
    platform : CueingConfig or None
        The ``--platform`` file, loaded when ``--platform-udp`` or ``--platform-can`` asks
        for it; else None.
    """

    telemetry: tuple[str, int] | None
    platform_udp: tuple[str, int] | None
    platform: "CueingConfig | None"


def check_rt_options(args: argparse.Namespace) -> RtOptions:
    """Refuse the options of run and rig before any work: --bus, --duration, --telemetry,
    --platform-udp, --platform, --fifo, --cpu, --spin (one line each); return those parsed."""
    from motosim.io.bus_spec import check_bus
    from motosim.rt.telemetry import parse_address

    check_bus(args.bus)
    if args.duration is not None and not (
        math.isfinite(args.duration) and 1e-3 <= args.duration <= 86_400.0
    ):
        raise MotosimError(
            f"--duration {short_repr(args.duration)}; expected seconds from 0.001 to 86400"
        )
    telemetry = None if args.telemetry == "off" else parse_address(args.telemetry)
    platform_udp = None if args.platform_udp == "off" else _platform_address(args.platform_udp)
    platform = None
    if platform_udp is not None or args.platform_can:
        from motosim.cueing import load_platform

        platform = load_platform(args.platform)  # refused here, not after the scenario's designs
    check_privilege_options(args)
    return RtOptions(telemetry, platform_udp, platform)


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
    ``motosim run`` gives (:func:`motosim.rt.config.frame_age`): for ``motosim run`` at its
    ``pace``; without a ``pace`` (``motosim rig``, which serves whichever run comes) at the
    pace of ``run`` that reads the frame youngest at the scenario's rates
    (:func:`motosim.rt.config.run_paces`), so that a lab learns it before starting the rig.
    The rig thus keeps a latency that ``run --pace clock`` refuses and ``run --pace bus``
    takes (equal control and measurement rates: up to a frame period against half a control
    period less). The rig's own ``[realtime.rig]`` latency, the bus it emulates, is not
    bounded by the frame period: a slow bus is what it is there to show ``run``.
    """
    from motosim.rt.config import frame_age, parse_latency, parse_safety, run_paces, split_realtime
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


def check_wait(args: argparse.Namespace) -> None:
    """Refuse ``--wait compiled`` given with ``--pace bus`` or ``--link python-can``.

    The compiled wait ends a clock-paced loop's wait and reads the fast link's socket; those
    runs wait in Python, which the option left out (None) lets pass silently. Reads only the
    options: the line comes before the numerical stack is loaded.

    Raises
    ------
    MotosimError
        Naming both options.
    """
    if args.wait != "compiled":
        return
    if args.pace == "bus":
        raise MotosimError(
            "--wait compiled with --pace bus; the compiled wait applies only to a clock-paced "
            "loop (--pace clock): leave --wait out with --pace bus"
        )
    if args.link == "python-can":
        raise MotosimError(
            "--wait compiled with --link python-can; the compiled wait applies only to the "
            "fast link (--link fast): leave --wait out with --link python-can"
        )
