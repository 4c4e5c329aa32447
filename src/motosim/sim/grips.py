"""The rider's hands as a scenario names them: :class:`Hands` and the named :data:`GRIPS`.

The arms' passive impedance about the steering axis (:mod:`motosim.sim.hands`, which
re-exports these and holds the compiled torque), in a module that imports neither NumPy nor
numba, so that a scenario is checked without them.
"""

import math
from dataclasses import dataclass, replace

from motosim.errors import MotosimError
from motosim.params.checks import check_number
from motosim.params.handlebar import HandlebarParameters

__all__ = [
    "DEFAULT_GRIP",
    "DESIGN_SHARE",
    "GRIPS",
    "Hands",
    "design_hands",
    "held_handlebar",
    "resolve_hands",
]

_LIMITS = (
    ("inertia", 1.0, "kg*m^2"),
    ("damping", 100.0, "N*m*s/rad"),
    ("stiffness", 1000.0, "N*m/rad"),
)
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
        """Whether the arms add nothing to the handlebar (every parameter zero)."""
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
    "off": Hands(source="no arms' impedance: the rider's torque alone, as without hands"),
}
"""The named grips. ``off``: no passive impedance, the rider a pure torque source as without
``hands``; a phase where nobody holds the handlebar, active torque included, is the rider's
``hands_off``."""

DEFAULT_GRIP = "relaxed"
"""The grip of a rider whose scenario names no ``hands``, where the stack models hands
(:attr:`motosim.sim.scenario.Scenario.models_hands`: no design file, no torque sensor), on
either motorcycle: a rider holds the handlebar, and the relaxed grip is the lighter of the
two. Where the stack cannot model them, the default rider has no hands (``off``), so that no
scenario is refused for the default: a design file's controller was designed for the
handlebar alone, and a torque sensor measures the arms' whole torque."""


def held_handlebar(handlebar: HandlebarParameters, hands: Hands | None) -> HandlebarParameters:
    """The handlebar as the stack designed for ``hands`` models it: the arms' inertia added to
    J_eq [kg*m^2] and their damping to beta_eq [N*m*s/rad].

    The observer, the controller and the feedforward designed for this handlebar, and the
    virtual motorcycle given the same inertia and damping on its front frame, leave to the
    estimate only the rider's active torque and the arms' stiffness, slow torques, while the
    arms' fast inertial and viscous torques are rendered by the model, without the estimate's
    lag (the design is written out in the design guide). Without hands, ``handlebar``.

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> hb = load_parameters("simacom_handlebar", "handlebar")
    >>> round(held_handlebar(hb, Hands(inertia=0.1, damping=1.0)).J_eq - hb.J_eq, 6)
    0.1
    """
    if hands is None or hands.is_off:
        return handlebar
    return replace(
        handlebar,
        J_eq=handlebar.J_eq + hands.inertia,
        beta_eq=handlebar.beta_eq + hands.damping,
    )


DESIGN_SHARE = 0.4
"""Share of a rider's grip (inertia and damping) the stack is designed for: between holding
and letting go, so that both keep their margins (the design guide compares the shares)."""


def design_hands(hands: Hands | None) -> Hands | None:
    """The hands a stack designed for a rider gripping with ``hands`` models:
    :data:`DESIGN_SHARE` of their inertia and damping (their stiffness reaches the virtual
    motorcycle through the estimate); None without hands.

    Examples
    --------
    >>> design_hands(GRIPS["relaxed"]).inertia == DESIGN_SHARE * GRIPS["relaxed"].inertia
    True
    """
    if hands is None or hands.is_off:
        return None
    return Hands(
        inertia=DESIGN_SHARE * hands.inertia,
        damping=DESIGN_SHARE * hands.damping,
        source=f"{DESIGN_SHARE:g} of the inertia and damping of {hands.source}",
    )


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
