"""Figures from results. matplotlib is imported here and nowhere else.

Every function returns a :class:`matplotlib.figure.Figure` and never shows it; callers save it.
The functions below are imported from their modules on first use (PEP 562), so that a module
of figures (:mod:`motosim.plotting.closed_loop`) loads without the models the others draw.
"""

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from motosim.plotting.estimation import plot_torque_estimates
    from motosim.plotting.handling import plot_handling
    from motosim.plotting.identification import plot_identification
    from motosim.plotting.loads import plot_tyre_loads
    from motosim.plotting.modes import plot_mode_comparison, plot_modes
    from motosim.plotting.tyres import plot_tyre

_MODULES = {
    "plot_handling": "handling",
    "plot_identification": "identification",
    "plot_mode_comparison": "modes",
    "plot_modes": "modes",
    "plot_torque_estimates": "estimation",
    "plot_tyre": "tyres",
    "plot_tyre_loads": "loads",
}

__all__ = [
    "plot_handling",
    "plot_identification",
    "plot_mode_comparison",
    "plot_modes",
    "plot_torque_estimates",
    "plot_tyre",
    "plot_tyre_loads",
]


def __getattr__(name: str) -> Any:
    """The figure function ``name``, imported from its module."""
    if name in _MODULES:
        value = getattr(import_module(f"motosim.plotting.{_MODULES[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
