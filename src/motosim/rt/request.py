"""A real-time run as ``motosim run`` asks for it: checked, then configured, then reported.

The command line parses its options into a :class:`RunRequest` and hands it over:

1. :func:`check_run` reads the scenario and its ``[realtime]`` table and refuses what a
   real-time run cannot take, one line each, before anything is designed or the compiled
   stack is loaded (the command's own option checks come before numba is imported);
2. :func:`session_config` resolves the run and designs its stack (or takes it from the
   design cache): the :class:`~motosim.rt.session.SessionConfig` that
   :class:`~motosim.rt.session.RealtimeSession` runs;
3. :func:`summary_lines` is what the command prints of the
   :class:`~motosim.rt.session.Outcome`.
"""

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from motosim.errors import MotosimError
from motosim.rt.session import RunOptions

if TYPE_CHECKING:
    from motosim.io.cache import DesignCache
    from motosim.rt.recorder import LiveSink
    from motosim.rt.safety import SafetyLimits
    from motosim.rt.session import Outcome, SessionConfig
    from motosim.sim import RunInputs, Scenario

__all__ = ["CheckedRun", "RunRequest", "check_run", "session_config", "summary_lines"]

LiveView = Callable[["RunInputs", float, "SafetyLimits"], "LiveSink"]
"""Builds the rider's view and dashboard of a run: from its inputs, duration [s] and safety
limits."""


@dataclass(frozen=True, slots=True)
class RunRequest:
    """A real-time run as the command line asks for it, each option checked on its own
    (:mod:`motosim.cli.run`).

    Attributes
    ----------
    scenario : str
        The scenario file, with a ``[realtime.safety]`` table.
    bus : str
        python-can's ``INTERFACE[:CHANNEL]``.
    folder : Path
        The result folder, checked free (or to be overwritten).
    duration : float or None
        How long the run lasts [s]; None: the scenario's.
    options : RunOptions
        How the run runs and what it sends beside the drive's frames.
    """

    scenario: str
    bus: str
    folder: Path
    duration: float | None = None
    options: RunOptions = field(default_factory=RunOptions)


class CheckedRun(NamedTuple):
    """The scenario of a :class:`RunRequest` read and checked (:func:`check_run`): its
    ``[realtime]`` table, safety limits, status latency [s] and the status frame's age at
    the stack's step [s] (:func:`~motosim.rt.config.frame_age`)."""

    scenario: "Scenario"
    realtime: dict[str, Any]
    limits: "SafetyLimits"
    latency: float
    age: float


def check_run(request: RunRequest) -> CheckedRun:
    """Read the scenario and refuse what a real-time run cannot take (one line each).

    Raises
    ------
    MotosimError
        On a scenario a real-time run refuses: offline-only settings, a bad
        ``[realtime]`` table, a latency older than the stack accounts for, or
        ``pace = "bus"`` with unequal control and measurement rates.
    """
    from motosim.rt.config import (
        frame_age,
        parse_latency,
        parse_safety,
        read_realtime,
        refuse_offline_only,
        run_paces,
    )

    origin = request.scenario
    pace = request.options.pace
    sc, realtime = read_realtime(origin, safety=True, pace=pace)
    refuse_offline_only(sc, origin=origin)
    limits = parse_safety(realtime.get("safety"), origin=origin)
    rate, measurement = sc.rates.control, sc.rates.measurement
    latency = parse_latency(realtime, origin=origin)
    age = frame_age(
        latency,
        pace=pace,
        control_rate=rate,
        measurement_rate=measurement,
        origin=origin,
    )
    if pace not in run_paces(rate, measurement):
        raise MotosimError(
            f"--pace bus with control = {rate:g} Hz and measurement = {measurement:g} Hz; "
            "expected equal rates (one period per status frame)"
        )
    return CheckedRun(sc, realtime, limits, latency, age)


def session_config(
    request: RunRequest,
    checked: CheckedRun,
    cache: "DesignCache",
    *,
    live: LiveView | None = None,
) -> "SessionConfig":
    """The run resolved and its stack designed (or taken from ``cache``), the status
    frames' age accounted for: the session's configuration (seconds on a first design)."""
    from motosim.io.cache import cached_stack
    from motosim.rt.config import resolve_realtime, within_safety
    from motosim.rt.session import SessionConfig
    from motosim.sim import run_metadata
    from motosim.sim.stack import account_for_delay

    inputs = resolve_realtime(request.scenario, checked.scenario, cache)
    inputs = within_safety(inputs, checked.limits)  # the stack saturates where the clamp cuts
    sc = inputs.scenario
    duration = sc.duration if request.duration is None else request.duration
    with cache.designing(sc.name):
        model = cached_stack(cache, inputs)
    model = account_for_delay(model, checked.age, inputs.design_handlebar)
    options = request.options
    metadata = run_metadata(inputs) | {
        "realtime": {  # and the link in use, once the session has opened it
            "bus": request.bus,
            "pace": options.pace,
            "status_latency": checked.latency,
            "measurement_delay": checked.age,
            "safety": checked.limits,
            "duration": duration,
        }
    }
    return SessionConfig(
        inputs,
        model,
        checked.limits,
        request.bus,
        request.folder,
        metadata,
        duration,
        options,
        None if live is None else live(inputs, duration, checked.limits),
    )


def summary_lines(config: "SessionConfig", outcome: "Outcome") -> list[str]:
    """What a run's summary says: the periods, the timing, the privileges, the safety
    stage's state, lost frames and the advice that fits what the run saw."""
    from motosim.rt.check import advice

    stats, counters = outcome.stats, outcome.counters
    pace = config.options.pace
    wake = "wake-up" if pace == "clock" else "frame interval jitter"
    gaps = f", {stats.gaps} frame periods without a frame" if pace == "bus" else ""
    lines = [
        f"{config.inputs.scenario.name}: {stats.served} periods at {stats.rate:g} Hz, "
        f"result in {outcome.folder}",
        f"  {wake} p99 {stats.wake_p99 * 1e6:.0f} us, compute p99 "
        f"{stats.compute_p99 * 1e6:.0f} us, missed {stats.missed} of {stats.periods}{gaps}",
        *(f"  {p}" for p in outcome.privileges),
        f"  state {counters.state}; {counters.fault_reason}",
    ]
    if counters.frames_lost > max(10, counters.status_frames // 10):
        lines.append(
            f"  {counters.frames_lost} status frames lost for {counters.status_frames} "
            "received: is a second rig or drive on this bus? (udp_multicast: give each "
            "rig and run pair a group of its own, --bus udp_multicast:239.74.163.50)"
        )
    asked = config.options.privileges.all_given
    found = advice(
        stats, counters.fault, asked_all=asked, privileges=outcome.privileges, bus=config.bus
    )
    return lines + [f"  {line}" for line in found]
