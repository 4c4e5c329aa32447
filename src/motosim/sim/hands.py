"""The rider's hands: the arms' passive impedance about the steering axis.

A rider holds the handlebar: besides the torque the rider means to apply (the *active*
torque of a profile or of the virtual rider), the hands and arms add an inertia, a damping
and a stiffness about a neutral angle that the hands hold,

    tau_passive = -J_a theta_h'' - c_a theta_h' - k_a (theta_h - theta_hold),

which act on the handlebar exactly as the active torque does (Cossalter, Doria, Lot &
Massaro, "The effect of rider's passive steering impedance on motorcycle stability:
identification and analysis", Meccanica 46 (2011) 279-292, who identified it on a riding
simulator; Massaro & Cole, "Neuromuscular-steering dynamics: motorcycle riders vs car
drivers", ASME DSCC 2012, a review). In the simulated rig the arms' inertia adds to the
handlebar's J_eq in the plant's integration and the damping and stiffness are torques, so
the stack's estimate sees the passive torque as a real front frame would.

:data:`GRIPS` holds the named grips (``relaxed``, ``firm`` and ``off``, hands off), each
value with its source; a scenario names one (``[rider] hands = "relaxed"``) or gives its
own table.
"""

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.params.checks import check_number

__all__ = ["GRIPS", "Hands", "hands_array", "hands_torque", "is_held", "resolve_hands"]

Array = NDArray[np.float64]

_LIMITS = (("inertia", 1.0, "kg*m^2"), ("damping", 100.0, "N*m*s/rad"),
           ("stiffness", 1000.0, "N*m/rad"))  # fmt: skip
"""Largest value of each parameter a scenario accepts, an order of magnitude above the firm
grip's: beyond, a value is a unit slip."""


@dataclass(frozen=True, slots=True)
class Hands:
    """The arms' passive impedance at the handlebar, reduced to the steering axis.

    Attributes
    ----------
    inertia : float
        J_a, the arms' and hands' inertia about the steering axis [kg*m^2], >= 0.
    damping : float
        c_a [N*m*s/rad], >= 0.
    stiffness : float
        k_a [N*m/rad], >= 0, about ``hold``.
    hold : float
        theta_hold, the handlebar angle the hands hold [rad].
    source : str
        Where the values come from.

    Raises
    ------
    MotosimError
        On a negative, non-finite or implausibly large value (one line naming it).

    Examples
    --------
    >>> Hands(inertia=0.1, damping=2.0, stiffness=20.0).stiffness
    20.0
    """

    inertia: float = 0.0
    damping: float = 0.0
    stiffness: float = 0.0
    hold: float = 0.0
    source: str = "the scenario"

    def __post_init__(self) -> None:
        for name, high, unit in _LIMITS:
            check_number(getattr(self, name), where=name, lower=0.0, upper=high, unit=unit)
        check_number(self.hold, where="hold", lower=-math.pi, upper=math.pi, unit="rad")

    @property
    def is_off(self) -> bool:
        """Whether nothing holds the handlebar (every parameter zero)."""
        return self.inertia == 0.0 and self.damping == 0.0 and self.stiffness == 0.0


_PROVISIONAL = (
    "provisional, to be checked against Cossalter, Doria, Lot & Massaro, Meccanica 46 (2011) "
    "279-292 and Massaro & Cole (2012): an arms' inertia about the steering axis of the order "
    "of 0.1 kg*m^2 (the equivalent J_eq of the handlebar is 0.0415), a damping of a few "
    "N*m*s/rad and a stiffness rising from about 10 N*m/rad relaxed to tens of N*m/rad with "
    "the muscles co-contracted"
)

GRIPS: dict[str, Hands] = {
    "relaxed": Hands(inertia=0.1, damping=1.0, stiffness=10.0, source=_PROVISIONAL),
    "firm": Hands(inertia=0.1, damping=4.0, stiffness=50.0, source=_PROVISIONAL),
    "off": Hands(source="hands off: nothing holds the handlebar"),
}
"""The named grips. ``off``: nobody holds the handlebar (no active torque either)."""


def hands_array(hands: Hands | None) -> Array:
    """[J_a, c_a, k_a, theta_hold] of ``hands`` (zeros without), for compiled loops."""
    if hands is None:
        return np.zeros(4)
    return np.array([hands.inertia, hands.damping, hands.stiffness, hands.hold])


def resolve_hands(hands: "str | Hands | None") -> Hands | None:
    """The :class:`Hands` of a grip name or table (None: no hands, a pure torque source).

    Raises
    ------
    MotosimError
        On an unknown grip name.
    """
    if hands is None or isinstance(hands, Hands):
        return hands
    if hands not in GRIPS:
        raise MotosimError(f"hands = {hands!r}; expected one of {', '.join(GRIPS)} or a table")
    return GRIPS[hands]


@njit(cache=True)
def hands_torque(
    theta: float, omega: float, accel: float, J_a: float, c_a: float, k_a: float, hold: float
) -> float:
    """The arms' passive torque on the handlebar [N*m].

    -J_a theta'' - c_a theta' - k_a (theta - theta_hold), with ``theta`` [rad], ``omega``
    [rad/s] and ``accel`` [rad/s^2] the handlebar's angle, rate and acceleration.

    Examples
    --------
    >>> hands_torque(0.1, 0.0, 0.0, 0.1, 1.0, 10.0, 0.0)
    -1.0
    """
    return -J_a * accel - c_a * omega - k_a * (theta - hold)


@njit(cache=True)
def is_held(t: float, off: Array) -> bool:
    """Whether the hands hold the handlebar at ``t`` [s]: outside every hands-off phase
    ``off[i] = [t0, t1]`` (from t0 included to t1 excluded)."""
    for i in range(off.shape[0]):
        if off[i, 0] <= t < off[i, 1]:
            return False
    return True
