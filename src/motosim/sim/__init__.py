"""Scenarios, the virtual rider, the compiled stack step and the closed-loop simulator.

The names of :mod:`motosim.sim.closed_loop` are imported on first use (PEP 562), so that
:func:`parse_scenario` and the light modules of this package (:mod:`motosim.sim.scenario`,
:mod:`motosim.sim.paths`, :mod:`motosim.sim.grips`) are imported without SciPy or numba.
"""

from typing import TYPE_CHECKING, Any

from motosim.sim.scenario import Scenario, parse_scenario

if TYPE_CHECKING:
    from motosim.sim.closed_loop import (
        SIGNALS,
        RunInputs,
        build_rig,
        build_stack,
        prepare,
        run_metadata,
        simulate,
    )

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

_CLOSED_LOOP = frozenset(
    ("SIGNALS", "RunInputs", "build_rig", "build_stack", "prepare", "run_metadata", "simulate")
)


def __getattr__(name: str) -> Any:
    """The closed loop's names, imported from :mod:`motosim.sim.closed_loop` on first use."""
    if name in _CLOSED_LOOP:
        from motosim.sim import closed_loop

        value = getattr(closed_loop, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
