"""Parameters of Sharp's (1971) motorcycle: the virtual motorcycle of the simulator.

Symbols follow the paper's appendix and Sharp (1971); the trail, written eta in the paper,
is ``t`` here (the normal trail, perpendicular to the steering axis). Axes are SAE: x forward,
y right, z down, so the front normal force ``Z_f`` is negative.
"""

import math
from dataclasses import dataclass
from typing import ClassVar

from motosim.params._spec import Spec, validate_fields

__all__ = ["SharpParameters", "derived_geometry"]


@dataclass(frozen=True, slots=True)
class SharpParameters:
    """Sharp's two-body motorcycle with relaxing tyres, in SI units.

    Every field is a physical constant; see :attr:`SPECS` for its unit, meaning and range.
    Derived quantities (``j``, ``k``, ``l``, ...) come from :func:`derived_geometry`.

    Raises
    ------
    MotosimError
        If a value is not finite or outside its physical range.
    """

    m_f: float
    m_r: float
    I_rx: float
    I_rz: float
    C_rxz: float
    I_fx: float
    I_fz: float
    i_fy: float
    i_Ry: float
    a: float
    b: float
    e: float
    f: float
    h: float
    R_f: float
    R_r: float
    t: float
    epsilon: float
    Z_f: float
    C_f1: float
    C_f2: float
    C_r1: float
    C_r2: float
    K: float
    sigma: float
    g: float

    SPECS: ClassVar[dict[str, Spec]] = {
        "m_f": Spec.positive("kg", "front frame mass (wheel, forks, handlebar)"),
        "m_r": Spec.positive("kg", "rear frame mass including the rider"),
        "I_rx": Spec.positive("kg*m^2", "rear frame roll inertia about G_r"),
        "I_rz": Spec.positive("kg*m^2", "rear frame yaw inertia about G_r"),
        "C_rxz": Spec("kg*m^2", "rear frame product of inertia (enters as -C_rxz)"),
        "I_fx": Spec.positive("kg*m^2", "front frame inertia perpendicular to the steering axis"),
        "I_fz": Spec.positive(
            "kg*m^2", "front frame inertia about an axis parallel to the steering axis"
        ),
        "i_fy": Spec.positive("kg*m^2", "front wheel spin inertia"),
        "i_Ry": Spec.positive(
            "kg*m^2", "rear wheel spin inertia with the reflected engine flywheel"
        ),
        "a": Spec.positive("m", "distance from A to the steering axis, perpendicular to it"),
        "b": Spec.positive("m", "rear contact behind G_r"),
        "e": Spec("m", "G_f ahead of the steering axis"),
        "f": Spec("m", "G_f above the foot of the perpendicular from A, along the steering axis"),
        "h": Spec.positive("m", "height of G_r"),
        "R_f": Spec.positive("m", "front wheel radius"),
        "R_r": Spec.positive("m", "rear wheel radius"),
        "t": Spec("m", "normal trail (eta in the paper)"),
        "epsilon": Spec("rad", "caster angle from vertical", lower=-math.pi / 2, upper=math.pi / 2),
        "Z_f": Spec("N", "front normal force along +z (down), so negative", upper=0.0),
        "C_f1": Spec.positive("N/rad", "front cornering stiffness"),
        "C_f2": Spec.non_negative("N/rad", "front camber stiffness"),
        "C_r1": Spec.positive("N/rad", "rear cornering stiffness"),
        "C_r2": Spec.non_negative("N/rad", "rear camber stiffness"),
        "K": Spec.non_negative("N*m*s/rad", "steering damper"),
        "sigma": Spec.positive("m", "tyre relaxation length"),
        "g": Spec.positive("m/s^2", "gravitational acceleration"),
    }

    def __post_init__(self) -> None:
        validate_fields(self, context="Sharp parameters")


def derived_geometry(p: SharpParameters) -> dict[str, float]:
    """Quantities Sharp does not tabulate, derived from the tabulated ones.

    Parameters
    ----------
    p : SharpParameters
        The motorcycle.

    Returns
    -------
    dict of str to float
        ``j`` height of G_f [m], ``k`` G_f ahead of G_r [m], ``l`` front contact ahead of G_r
        [m], ``wheelbase`` [m], ``m`` total mass [kg], ``J_R`` wheel spin inertia [kg*m^2],
        ``r_D`` rolling radius [m] and ``m_eq`` = m + J_R / r_D^2 [kg] of eq. (2).

    Notes
    -----
    j = (a + e) sin(eps) + f cos(eps), k = (a + e) cos(eps) - f sin(eps),
    l = (a - t) / cos(eps). This reading of Sharp's geometry (f up the steering axis) is the
    one that reproduces his published eigenvalues and front load; the opposite sign of f, used
    by some public codes, does not.

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> round(derived_geometry(load_parameters("sharp1971"))["l"], 5)
    0.9347
    """
    se, ce = math.sin(p.epsilon), math.cos(p.epsilon)
    m = p.m_f + p.m_r
    J_R = p.i_fy + p.i_Ry
    l = (p.a - p.t) / ce  # noqa: E741 - Sharp's symbol
    return {
        "j": (p.a + p.e) * se + p.f * ce,
        "k": (p.a + p.e) * ce - p.f * se,
        "l": l,
        "wheelbase": p.b + l,
        "m": m,
        "J_R": J_R,
        "r_D": p.R_r,
        "m_eq": m + J_R / p.R_r**2,
    }
