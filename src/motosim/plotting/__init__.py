"""Figures from results. matplotlib is imported here and nowhere else.

Every function returns a :class:`matplotlib.figure.Figure` and never shows it; callers save it.
"""

from motosim.plotting.estimation import plot_torque_estimates
from motosim.plotting.handling import plot_handling
from motosim.plotting.identification import plot_identification
from motosim.plotting.loads import plot_tyre_loads
from motosim.plotting.modes import plot_mode_comparison, plot_modes
from motosim.plotting.tyres import plot_tyre

__all__ = [
    "plot_handling",
    "plot_identification",
    "plot_mode_comparison",
    "plot_modes",
    "plot_torque_estimates",
    "plot_tyre",
    "plot_tyre_loads",
]
