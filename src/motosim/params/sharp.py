"""Parameters of Sharp's (1971) motorcycle: the virtual motorcycle of the simulator.

Symbols follow the paper's appendix and Sharp (1971); the trail, written eta in the paper,
is ``t`` here (the normal trail, perpendicular to the steering axis). Axes are SAE: x forward,
y right, z down, so the front normal force ``Z_f`` is negative.
"""

import math
from dataclasses import dataclass
from typing import ClassVar

from motosim.errors import MotosimError
from motosim.params._spec import Spec, validate_fields

__all__ = ["SharpParameters", "derived_geometry"]

_MIN_PRINCIPAL_INERTIA = 0.1
"""Smallest principal moment of the rear frame in the x-z plane [kg*m^2], I_rx's lower bound.

With it, every body's kinetic energy is positive, so the mass matrix of the model is positive
definite (never singular) for any parameters in range.
"""


@dataclass(frozen=True, slots=True)
class SharpParameters:
    """Sharp's two-body motorcycle with relaxing tyres, in SI units.

    Every field is a physical constant; see :attr:`SPECS` for its unit, meaning and range.
    Derived quantities (``j``, ``k``, ``l``, ...) come from :func:`derived_geometry`.

    Raises
    ------
    MotosimError
        If a value is not finite or outside its physical range, if the rear frame's inertia
        is not positive definite (I_rx I_rz > C_rxz^2, with margin), if the front load is not
        below the total weight, or if the front contact is not ahead of G_r.
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
        "m_f": Spec.between(
            "kg",
            "front frame mass (wheel, forks, handlebar)",
            2.0,
            150.0,
            reason="from a bicycle's fork and wheel (7 kg in Meijaard et al. 2007, Table 1) "
            "to a heavy motorcycle's front assembly",
        ),
        "m_r": Spec.between(
            "kg",
            "rear frame mass including the rider",
            10.0,
            1000.0,
            reason="from a child's bicycle with its rider to a touring motorcycle with two "
            "riders and luggage",
        ),
        "I_rx": Spec.between(
            "kg*m^2",
            "rear frame roll inertia about G_r",
            0.1,
            500.0,
            reason="a bicycle with rider is 9.2 (Meijaard et al. 2007), Sharp's machine 31",
        ),
        "I_rz": Spec.between(
            "kg*m^2",
            "rear frame yaw inertia about G_r",
            0.1,
            500.0,
            reason="same order as the roll inertia for any rider and machine",
        ),
        "C_rxz": Spec.between(
            "kg*m^2",
            "rear frame product of inertia (enters as -C_rxz)",
            -100.0,
            100.0,
            reason="smaller in magnitude than the roll and yaw inertias it couples",
        ),
        "I_fx": Spec.between(
            "kg*m^2",
            "front frame inertia perpendicular to the steering axis",
            1e-3,
            50.0,
            reason="a wheel and a fork: 0.1 to a few kg*m^2",
        ),
        "I_fz": Spec.between(
            "kg*m^2",
            "front frame inertia about an axis parallel to the steering axis",
            1e-3,
            50.0,
            reason="a wheel and a fork: 0.1 to a few kg*m^2",
        ),
        "i_fy": Spec.between(
            "kg*m^2",
            "front wheel spin inertia",
            0.01,
            20.0,
            reason="from a bicycle wheel (0.28 in Meijaard et al. 2007) to a motorcycle's (0.7)",
        ),
        "i_Ry": Spec.between(
            "kg*m^2",
            "rear wheel spin inertia with the reflected engine flywheel",
            0.01,
            20.0,
            reason="a wheel plus an engine seen through the gearbox: Sharp's machine 1.05",
        ),
        "a": Spec.between(
            "m",
            "distance from A to the steering axis, perpendicular to it",
            0.1,
            3.0,
            reason="a fraction of a wheelbase of 0.8 to 2 m",
        ),
        "b": Spec.between(
            "m",
            "rear contact behind G_r",
            0.1,
            2.0,
            reason="a fraction of a wheelbase of 0.8 to 2 m",
        ),
        "e": Spec.between(
            "m",
            "G_f ahead of the steering axis",
            -0.5,
            0.5,
            reason="the front assembly's centre of mass lies near its steering axis",
        ),
        "f": Spec.between(
            "m",
            "G_f above the foot of the perpendicular from A, along the steering axis",
            -1.0,
            1.0,
            reason="within a front assembly about a metre tall",
        ),
        "h": Spec.between(
            "m",
            "height of G_r",
            0.2,
            2.0,
            reason="from a low scooter to a bicycle with rider (0.9 m, Meijaard et al. 2007)",
        ),
        "R_f": Spec.between(
            "m",
            "front wheel radius",
            0.1,
            0.6,
            reason="from a small scooter wheel to a large off-road wheel; no two-wheeler "
            "rolls on a smaller one",
        ),
        "R_r": Spec.between(
            "m",
            "rear wheel radius",
            0.1,
            0.6,
            reason="from a small scooter wheel to a large off-road wheel",
        ),
        "t": Spec.between(
            "m",
            "normal trail (eta in the paper)",
            -0.2,
            0.5,
            reason="road machines have 0.05 to 0.15 m (Sharp's 0.116); negative trail "
            "admitted for studies",
        ),
        "epsilon": Spec.between(
            "rad",
            "caster angle from vertical",
            -0.35,
            1.05,
            reason="-20 to 60 deg: road machines have 18 to 35 deg (Sharp's 27 deg)",
        ),
        "Z_f": Spec(
            "N",
            "front normal force along +z (down), so negative",
            lower=-2e4,
            lower_closed=True,
            upper=-1.0,
            upper_closed=True,
            reason="the ground pushes the front wheel up (Z_f < 0) with at most the weight "
            "of a heavy machine",
        ),
        "C_f1": Spec.between(
            "N/rad",
            "front cornering stiffness",
            100.0,
            5e5,
            reason="10 to 25 per radian times the tyre load of a bicycle or motorcycle",
        ),
        "C_f2": Spec.between(
            "N/rad",
            "front camber stiffness",
            0.0,
            1e5,
            reason="about one tyre load per radian; below the cornering stiffness",
        ),
        "C_r1": Spec.between(
            "N/rad",
            "rear cornering stiffness",
            100.0,
            5e5,
            reason="10 to 25 per radian times the tyre load of a bicycle or motorcycle",
        ),
        "C_r2": Spec.between(
            "N/rad",
            "rear camber stiffness",
            0.0,
            1e5,
            reason="about one tyre load per radian; below the cornering stiffness",
        ),
        "K": Spec.between(
            "N*m*s/rad",
            "steering damper",
            0.0,
            1000.0,
            reason="none to a stiff hydraulic damper (Sharp's 6.8)",
        ),
        "sigma": Spec.between(
            "m",
            "tyre relaxation length",
            0.01,
            2.0,
            reason="a fraction of the tyre circumference (Sharp's 0.24 m)",
        ),
        "g": Spec.between(
            "m/s^2",
            "gravitational acceleration",
            9.7,
            9.9,
            reason="the Earth's surface gravity is 9.78 m/s^2 at the equator to 9.83 at the poles",
        ),
    }

    TYPICAL: ClassVar[dict[str, tuple[float, float, str]]] = {
        "m_f": (10.0, 60.0, "a motorcycle's front wheel, fork and handlebar; Sharp: 30.6"),
        "m_r": (80.0, 500.0, "a motorcycle's rear frame with its rider; Sharp: 217"),
        "I_rx": (5.0, 150.0, "a motorcycle with its rider; Sharp: 31"),
        "I_rz": (5.0, 150.0, "a motorcycle with its rider; Sharp: 21"),
        "i_fy": (0.2, 2.0, "a motorcycle's front wheel; Sharp: 0.72"),
        "i_Ry": (0.2, 5.0, "a motorcycle's rear wheel and engine; Sharp: 1.05"),
        "h": (0.3, 1.2, "a motorcycle's centre of mass with its rider; Sharp: 0.62 m"),
        "R_f": (0.2, 0.4, "motorcycle front wheels, 12 to 21 inch rims; Sharp: 0.30 m"),
        "R_r": (0.2, 0.4, "motorcycle rear wheels; Sharp: 0.30 m"),
        "t": (0.0, 0.2, "road and off-road motorcycles; Sharp: 0.116 m"),
        "epsilon": (0.3, 0.65, "17 to 37 deg of caster on motorcycles; Sharp: 27 deg"),
        "sigma": (0.05, 0.6, "motorcycle tyres; Sharp: 0.24 m"),
    }
    """Typical range of the main parameters (low, high, why): a value outside is legal (see
    :attr:`SPECS`: bicycles and studies are admitted) but far from a motorcycle, and is
    accepted with a warning."""

    def __post_init__(self) -> None:
        validate_fields(self, context="Sharp parameters")
        weight = (self.m_f + self.m_r) * self.g
        if -self.Z_f >= weight:
            raise MotosimError(
                f"Sharp parameters: front load -Z_f = {-self.Z_f:g} N is not below the total "
                f"weight (m_f + m_r) g = {weight:g} N; expected the rear wheel to carry some load"
            )
        smallest = 0.5 * (self.I_rx + self.I_rz - math.hypot(self.I_rx - self.I_rz, 2 * self.C_rxz))
        if smallest < _MIN_PRINCIPAL_INERTIA:
            raise MotosimError(
                f"Sharp parameters: rear frame inertia I_rx = {self.I_rx:g}, I_rz = {self.I_rz:g}, "
                f"C_rxz = {self.C_rxz:g} kg*m^2 has a principal moment of {smallest:g}; expected "
                f"a positive definite inertia, each principal moment >= {_MIN_PRINCIPAL_INERTIA:g}"
            )
        l = (self.a - self.t) / math.cos(self.epsilon)  # noqa: E741 - Sharp's symbol
        if l <= 0.0:
            raise MotosimError(
                f"Sharp parameters: front contact l = (a - t) / cos(epsilon) = {l:g} m; expected "
                "the front contact ahead of G_r (l > 0), so a > t"
            )


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
