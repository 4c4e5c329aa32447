"""Parameters of the motorised handlebar: DC motor, belt reduction and handlebar (eqs. 3-7).

The identified quantities are the equivalent ones of eq. (5), seen at the handlebar axis:
``J_eq = J_h + N^2 J_m`` and ``beta_eq = beta_vh + N^2 beta_vm``. The regression of eq. (8)
identifies exactly these, so the packaged Table I set stores them as such.
"""

from dataclasses import dataclass
from typing import ClassVar

from motosim.errors import MotosimError
from motosim.params._spec import Spec, validate_fields

__all__ = ["HandlebarParameters"]


@dataclass(frozen=True, slots=True)
class HandlebarParameters:
    """DC motor driving the handlebar through a belt of ratio ``N`` (theta_m = N theta_h).

    Raises
    ------
    MotosimError
        If a value is not finite or outside its range, or if the motor alone would have more
        inertia or damping at the handlebar axis than the equivalent values.
    """

    J_eq: float
    beta_eq: float
    beta_s: float
    N: float
    k_t: float
    J_m: float
    beta_vm: float
    R: float
    L: float
    k_e: float

    SPECS: ClassVar[dict[str, Spec]] = {
        "J_eq": Spec.between(
            "kg*m^2",
            "equivalent inertia at the handlebar axis, J_h + N^2 J_m",
            1e-4,
            10.0,
            reason="a handlebar with its motor: Table I of the paper gives 0.0415",
        ),
        "beta_eq": Spec.between(
            "N*m*s/rad",
            "equivalent viscous friction, beta_vh + N^2 beta_vm",
            1e-4,
            1000.0,
            reason="bearings, belt and motor seen at the handlebar: Table I gives 13.956",
        ),
        "beta_s": Spec.between(
            "N*m",
            "dry (Coulomb) friction torque",
            0.0,
            200.0,
            reason="below the torque a rider can apply (Table I gives 1.734)",
        ),
        "N": Spec.between(
            "1",
            "belt reduction ratio, motor angle over handlebar angle",
            0.1,
            200.0,
            reason="direct drive (1) to a two-stage reduction",
        ),
        "k_t": Spec.between(
            "N*m/A",
            "motor torque constant",
            1e-3,
            20.0,
            reason="small servo motors to large torque motors",
        ),
        "J_m": Spec.between(
            "kg*m^2",
            "rotor inertia",
            0.0,
            0.1,
            reason="the rotor of a motor of a few kilowatts at most",
        ),
        "beta_vm": Spec.between(
            "N*m*s/rad",
            "rotor viscous friction",
            0.0,
            10.0,
            reason="bearing and brush drag of such a rotor",
        ),
        "R": Spec.between(
            "ohm",
            "armature resistance",
            1e-3,
            100.0,
            reason="from a large low-voltage motor to a small high-voltage one",
        ),
        "L": Spec.between(
            "H",
            "armature inductance",
            0.0,
            1.0,
            reason="millihenries for such motors (Remark 2.2: very low)",
        ),
        "k_e": Spec.between(
            "V*s/rad",
            "back-EMF constant, per rad/s of the motor shaft",
            0.0,
            20.0,
            reason="equal to k_t in SI units for a DC motor",
        ),
    }

    TYPICAL: ClassVar[dict[str, tuple[float, float, str]]] = {
        "J_eq": (0.01, 1.0, "a handlebar with its motor; Table I: 0.0415"),
        "beta_eq": (0.1, 100.0, "bearings, belt and a motor's drag; Table I: 13.956"),
        "beta_s": (
            0.01,
            10.0,
            "dry friction a rider overcomes unnoticed, at least the hundredths of N*m of a "
            "handlebar's bearings and belt; Table I: 1.734",
        ),
        "N": (1.0, 30.0, "a direct drive to a one-stage belt; the paper's belt: 12"),
        "k_t": (0.01, 2.0, "servo motors of 50 W to 2 kW; the paper's motor: 0.25"),
        "R": (0.05, 20.0, "armatures of such motors"),
        "L": (0.0, 0.05, "millihenries (Remark 2.2 of the paper: very low)"),
        "k_e": (0.01, 2.0, "equal to k_t in SI units for a DC motor"),
    }
    """Typical range of the main parameters (low, high, why): a value outside is legal (see
    :attr:`SPECS`) but far from any motorised handlebar, and is accepted with a warning."""

    def __post_init__(self) -> None:
        validate_fields(self, context="handlebar parameters")
        if self.N**2 * self.J_m >= self.J_eq:
            raise MotosimError(
                f"handlebar parameters: N^2 J_m = {self.N**2 * self.J_m:g} kg*m^2 is not below "
                f"J_eq = {self.J_eq:g}; expected a positive handlebar inertia J_h = J_eq - N^2 J_m"
            )
        if self.N**2 * self.beta_vm > self.beta_eq:
            raise MotosimError(
                f"handlebar parameters: N^2 beta_vm = {self.N**2 * self.beta_vm:g} N*m*s/rad "
                f"exceeds beta_eq = {self.beta_eq:g}; expected beta_vh = beta_eq - N^2 beta_vm >= 0"
            )

    @property
    def torque_per_amp(self) -> float:
        """Motor torque at the handlebar per ampere, N k_t [N*m/A]."""
        return self.N * self.k_t

    @property
    def J_h(self) -> float:
        """Handlebar inertia alone, J_eq - N^2 J_m [kg*m^2]."""
        return self.J_eq - self.N**2 * self.J_m

    @property
    def beta_vh(self) -> float:
        """Handlebar viscous friction alone, beta_eq - N^2 beta_vm [N*m*s/rad]."""
        return self.beta_eq - self.N**2 * self.beta_vm
