"""The road a scenario's virtual rider follows, for the motion cueing's road preview.

:func:`scenario_road` rebuilds the path of a scenario (a saved result keeps its scenario)
as the :class:`motosim.cueing.preview.Road` that :func:`motosim.cueing.cue` previews; a
rider-torque scenario has none.
"""

from collections.abc import Mapping
from typing import Any

from motosim.cueing.preview import Road
from motosim.sim.closed_loop import route_length
from motosim.sim.scenario import Scenario, scenario_from_dict

__all__ = ["result_road", "scenario_road"]


def scenario_road(scenario: Scenario) -> Road | None:
    """The virtual rider's path as a road, or None for a rider-torque scenario.

    Parameters
    ----------
    scenario : Scenario
        The scenario.

    Returns
    -------
    Road or None
        The path as long as the simulator builds it (:func:`motosim.sim.simulate`).
    """
    path = scenario.rider.path
    if scenario.rider.kind != "virtual" or path is None:
        return None
    route = path.build(route_length(scenario))
    return Road(route.ds, route.x, route.y, route.kappa)


def result_road(metadata: Mapping[str, Any], *, origin: str) -> Road | None:
    """The road of a saved result's scenario (its ``scenario`` metadata), or None.

    Parameters
    ----------
    metadata : Mapping
        The result's metadata (:func:`motosim.io.results.load_result`).
    origin : str
        Where it came from, the prefix of error messages.

    Returns
    -------
    Road or None
        None when the result has no scenario (a real-time run's file) or it has no path.

    Raises
    ------
    MotosimError
        If the scenario recorded is not valid.
    """
    data = metadata.get("scenario")
    if not isinstance(data, Mapping) or "rider" not in data:
        return None
    return scenario_road(scenario_from_dict(data, origin=origin))
