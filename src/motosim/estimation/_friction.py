"""Dry-friction compensation shared by the estimators (Remarks 3.3 and 5.2)."""

import math

from numba import njit

__all__ = ["smooth_sign"]


@njit(cache=True)
def smooth_sign(omega: float, dead_zone: float, width: float) -> float:
    """sign(omega) with a dead zone and a tanh edge, for friction compensation.

    Parameters
    ----------
    omega : float
        Handlebar rate theta_h' [rad/s].
    dead_zone : float
        Half-width of the dead zone [rad/s], >= 0 (Remark 5.2): 0 inside it.
    width : float
        Rate scale of the tanh edge [rad/s] (Remark 3.3); 0 gives a hard step.

    Returns
    -------
    float
        0 for |omega| <= dead_zone, else sign(omega) tanh((|omega| - dead_zone) / width),
        continuous in omega.
    """
    excess = abs(omega) - dead_zone
    if excess <= 0.0:
        return 0.0
    mag = math.tanh(excess / width) if width > 0.0 else 1.0
    return mag if omega > 0.0 else -mag
