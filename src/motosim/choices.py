"""Names and limits that a scenario's values are checked against, importable without SciPy.

A scenario file is checked before the numerical stack is imported, so what its check reads
lives here, in a module that imports nothing: the estimator names (the keys of
:data:`motosim.estimation.registry.ESTIMATORS`, which the registry checks equal to
:data:`ESTIMATOR_NAMES`), the tuned controller's largest order and default integral corner
(:mod:`motosim.control.torque_feedback`), its lowest bandwidth and the speeds the virtual
rider is scheduled over (:mod:`motosim.sim.rider`). Those modules, and the command line's
parsers, import their values from here.
"""

from typing import Final

__all__ = [
    "ESTIMATOR_NAMES",
    "GRIP_NAMES",
    "INTEGRAL_CORNER",
    "LOWEST_BANDWIDTH",
    "MAX_ORDER",
    "MOTORCYCLE_PROFILES",
    "RIDER_SPEEDS",
    "SENSOR_ESTIMATOR",
]

MOTORCYCLE_PROFILES: Final = (
    "drive_torque",
    "brake_torque",
    "front_brake_torque",
    "rear_brake_torque",
    "wind_force",
    "side_wind",
)
"""The profiles of a scenario's ``[motorcycle]`` table
(:class:`motosim.sim.scenario.Motorcycle`)."""
ESTIMATOR_NAMES: Final = ("walcott_zak", "inverse_dynamics", "kalman")
"""The names of :data:`motosim.estimation.registry.ESTIMATORS`, in its order (the default,
the paper's observer, first)."""
SENSOR_ESTIMATOR: Final = "torque_sensor"
"""The scenario name of the estimator that reads a torque sensor
(:func:`motosim.estimation.registry.torque_sensor_kernel`)."""
GRIP_NAMES: Final = ("relaxed", "firm", "off")
"""The names of the rider's grips, :data:`motosim.sim.grips.GRIPS`, in its order."""
INTEGRAL_CORNER: Final = 0.1
"""W1's integral corner by default, as a fraction of the bandwidth: a decade below it."""
MAX_ORDER: Final = 3
"""Highest controller order: the shaped plant W1 G_h has 3 states (handlebar 2, weight 1), and a
controller of that order already reaches the full-order optimum (Glover & McFarlane 1989)."""
LOWEST_BANDWIDTH: Final = 0.1
"""Lowest tuned-controller bandwidth admitted [Hz] (``[controller] bandwidth``, ``design
--bandwidth``): a rider steers at 0.1-5 Hz, a loop slower than the slowest of it renders no
feel, and far below it the loop-shaping weight's integrator corner and the Riccati equations
of the synthesis lose their precision."""
RIDER_SPEEDS: Final = (3.0, 60.0)
"""Speeds the virtual rider's gains are scheduled over by default [m/s]."""
