"""Scenarios, the virtual rider, the compiled stack step and the closed-loop simulator."""

from motosim.sim.closed_loop import (
    SIGNALS,
    RunInputs,
    build_rig,
    build_stack,
    prepare,
    run_metadata,
    simulate,
)
from motosim.sim.scenario import Scenario, parse_scenario

__all__ = [
    "SIGNALS",
    "RunInputs",
    "Scenario",
    "build_rig",
    "build_stack",
    "parse_scenario",
    "prepare",
    "run_metadata",
    "simulate",
]
