"""Parameters of the multibody motorcycle (or bicycle): four rigid bodies, two wheels.

The names and axes are those of Meijaard, Papadopoulos, Ruina & Schwab (2007, Proc. R. Soc. A
463:1955-1982), Table 1: the rear wheel R, the rear frame B (with the rider), the front frame
H (fork and handlebar) and the front wheel F. Lengths are given in the upright reference
configuration with the origin at the rear contact point, x forward, y to the right and z down,
so the mass centres above the ground have a negative z. Inertias are about each body's mass
centre, in the same axes; the products of inertia are the tensor entries (``I_Bxz`` is the
x-z entry of the inertia matrix, as in Meijaard's Table 1). The wheels are axisymmetric
(``I_Rxx = I_Rzz``). ``t_R`` and ``t_F`` are the tyres' crown radii: the wheel is a torus whose
tube has this radius around a circle of radius ``r - t`` (0 is the knife-edge wheel of the
benchmark).
"""

import math
from dataclasses import dataclass
from typing import ClassVar

from motosim.errors import MotosimError
from motosim.params._spec import Spec, validate_fields

__all__ = ["MultibodyParameters"]


def _length(description: str, lower: float, upper: float, reason: str) -> Spec:
    return Spec.between("m", description, lower, upper, reason=reason)


_BODY_REASON = "from a bicycle's parts to a heavy motorcycle with its rider"
_INERTIA_MAX = 500.0


@dataclass(frozen=True, slots=True)
class MultibodyParameters:
    """The four bodies of the Whipple-Carvallo machine, in SI units (Meijaard 2007, Table 1).

    Every field is a physical constant; see :attr:`SPECS` for its unit, meaning and range.

    Raises
    ------
    MotosimError
        If a value is not finite or outside its physical range, if an inertia tensor is not
        that of a real body (positive definite in the x-z plane, the triangle inequality of
        the principal moments), if a tyre's crown radius is not below its wheel's radius, or
        if a mass centre is below the ground.
    """

    w: float
    c: float
    lam: float
    g: float
    r_R: float
    m_R: float
    I_Rxx: float
    I_Ryy: float
    x_B: float
    z_B: float
    m_B: float
    I_Bxx: float
    I_Byy: float
    I_Bzz: float
    I_Bxz: float
    x_H: float
    z_H: float
    m_H: float
    I_Hxx: float
    I_Hyy: float
    I_Hzz: float
    I_Hxz: float
    r_F: float
    m_F: float
    I_Fxx: float
    I_Fyy: float
    t_R: float
    t_F: float

    SPECS: ClassVar[dict[str, Spec]] = {
        "w": _length("wheelbase", 0.3, 3.0, "a child's bicycle to a long touring motorcycle"),
        "c": _length(
            "trail (front contact behind the steering axis's ground point)",
            -0.5,
            0.5,
            reason="negative trails are legal (unstable designs); 0.5 m is a chopper's",
        ),
        "lam": Spec.between(
            "rad",
            "steering axis tilt from the vertical (Meijaard's lambda, the caster angle)",
            -math.pi / 2 + 0.01,
            math.pi / 2 - 0.01,
            reason="the steering axis is not horizontal",
        ),
        "g": Spec.between(
            "m/s^2", "acceleration due to gravity", 0.0, 30.0, reason="zero g to 3 g"
        ),
        "r_R": _length("rear wheel radius", 0.05, 1.0, "a scooter's wheel to a large one"),
        "m_R": Spec.between("kg", "rear wheel mass", 0.0, 100.0, reason=_BODY_REASON),
        "I_Rxx": Spec.between(
            "kg*m^2", "rear wheel inertia about a diameter", 0.0, 20.0, reason=_BODY_REASON
        ),
        "I_Ryy": Spec.between("kg*m^2", "rear wheel spin inertia", 0.0, 20.0, reason=_BODY_REASON),
        "x_B": _length(
            "rear frame mass centre ahead of the rear contact", -1.0, 3.0, "inside the machine"
        ),
        "z_B": _length("rear frame mass centre height, negative up", -3.0, 0.0, "above the ground"),
        "m_B": Spec.between(
            "kg", "rear frame mass with the rider", 1.0, 1000.0, reason=_BODY_REASON
        ),
        "I_Bxx": Spec.between(
            "kg*m^2", "rear frame roll inertia", 0.0, _INERTIA_MAX, reason=_BODY_REASON
        ),
        "I_Byy": Spec.between(
            "kg*m^2", "rear frame pitch inertia", 0.0, _INERTIA_MAX, reason=_BODY_REASON
        ),
        "I_Bzz": Spec.between(
            "kg*m^2", "rear frame yaw inertia", 0.0, _INERTIA_MAX, reason=_BODY_REASON
        ),
        "I_Bxz": Spec.between(
            "kg*m^2",
            "rear frame x-z entry of the inertia tensor",
            -_INERTIA_MAX,
            _INERTIA_MAX,
            reason=_BODY_REASON,
        ),
        "x_H": _length(
            "front frame mass centre ahead of the rear contact", 0.0, 4.0, "inside the machine"
        ),
        "z_H": _length(
            "front frame mass centre height, negative up", -3.0, 0.0, "above the ground"
        ),
        "m_H": Spec.between("kg", "front frame mass", 0.0, 200.0, reason=_BODY_REASON),
        "I_Hxx": Spec.between("kg*m^2", "front frame roll inertia", 0.0, 50.0, reason=_BODY_REASON),
        "I_Hyy": Spec.between(
            "kg*m^2", "front frame pitch inertia", 0.0, 50.0, reason=_BODY_REASON
        ),
        "I_Hzz": Spec.between("kg*m^2", "front frame yaw inertia", 0.0, 50.0, reason=_BODY_REASON),
        "I_Hxz": Spec.between(
            "kg*m^2",
            "front frame x-z entry of the inertia tensor",
            -50.0,
            50.0,
            reason=_BODY_REASON,
        ),
        "r_F": _length("front wheel radius", 0.05, 1.0, "a scooter's wheel to a large one"),
        "m_F": Spec.between("kg", "front wheel mass", 0.0, 100.0, reason=_BODY_REASON),
        "I_Fxx": Spec.between(
            "kg*m^2", "front wheel inertia about a diameter", 0.0, 20.0, reason=_BODY_REASON
        ),
        "I_Fyy": Spec.between("kg*m^2", "front wheel spin inertia", 0.0, 20.0, reason=_BODY_REASON),
        "t_R": _length(
            "rear tyre crown radius (0: knife edge)", 0.0, 0.3, "up to a wide car-like tyre"
        ),
        "t_F": _length(
            "front tyre crown radius (0: knife edge)", 0.0, 0.3, "up to a wide car-like tyre"
        ),
    }

    TYPICAL: ClassVar[dict[str, tuple[float, float, str]]] = {
        "g": (9.7, 9.9, "the Earth's surface gravity"),
        "lam": (0.05, 0.6, "bicycles and motorcycles: 3 to 34 deg of caster"),
        "c": (0.0, 0.2, "bicycles (Meijaard: 0.08) and motorcycles (about 0.1)"),
    }
    """Typical range of some parameters (low, high, why): a value outside is legal (see
    :attr:`SPECS`) but unusual, and is accepted with a warning."""

    def __post_init__(self) -> None:
        validate_fields(self, context="multibody parameters")
        for body in ("B", "H"):
            ixx, iyy, izz, ixz = (
                getattr(self, f"I_{body}{axes}") for axes in ("xx", "yy", "zz", "xz")
            )
            if ixx * izz <= ixz**2 or ixx <= 0.0 or izz <= 0.0:
                raise MotosimError(
                    f"multibody parameters: I_{body}xx I_{body}zz = {ixx * izz:g} is not above "
                    f"I_{body}xz^2 = {ixz**2:g} (kg*m^2)^2; expected a positive definite "
                    "inertia tensor"
                )
            det_root = math.sqrt(((ixx - izz) / 2) ** 2 + ixz**2)
            principal = ((ixx + izz) / 2 - det_root, (ixx + izz) / 2 + det_root, iyy)
            if any(p > (sum(principal) - p) * (1 + 1e-12) for p in principal):
                raise MotosimError(
                    f"multibody parameters: the principal inertias of {body} "
                    f"({', '.join(f'{p:g}' for p in principal)} kg*m^2) break the triangle "
                    "inequality; expected each at most the sum of the other two"
                )
        for wheel in ("R", "F"):
            ixx, iyy = getattr(self, f"I_{wheel}xx"), getattr(self, f"I_{wheel}yy")
            if iyy > 2 * ixx * (1 + 1e-12):
                raise MotosimError(
                    f"multibody parameters: I_{wheel}yy = {iyy:g} kg*m^2 exceeds "
                    f"2 I_{wheel}xx = {2 * ixx:g}; expected a wheel's spin inertia at most "
                    "twice its diametral inertia"
                )
            radius, crown = getattr(self, f"r_{wheel}"), getattr(self, f"t_{wheel}")
            if crown >= radius:
                raise MotosimError(
                    f"multibody parameters: t_{wheel} = {crown:g} m is not below "
                    f"r_{wheel} = {radius:g} m; expected a crown radius smaller than the wheel"
                )

    @property
    def mass(self) -> float:
        """Total mass, m_R + m_B + m_H + m_F [kg]."""
        return self.m_R + self.m_B + self.m_H + self.m_F

    @property
    def mass_centre(self) -> tuple[float, float]:
        """The whole machine's mass centre (x, z) in the upright configuration [m].

        The wheel centres are at (0, -r_R) and (w, -r_F), Meijaard's axes.
        """
        m = self.mass
        x = (self.m_B * self.x_B + self.m_H * self.x_H + self.m_F * self.w) / m
        z = (
            -self.m_R * self.r_R + self.m_B * self.z_B + self.m_H * self.z_H - self.m_F * self.r_F
        ) / m
        return x, z
