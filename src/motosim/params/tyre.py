"""Parameters of a Magic Formula motorcycle tyre (MF-MC), in SI units.

The coefficients are those of the motorcycle Magic Formula of Pacejka, *Tyre and Vehicle
Dynamics* (2nd ed. 2006, section 11.5), as fitted by Evangelou (PhD thesis, Imperial College
London, 2004, chapter 9 and appendix C) and tabulated by Sharp, Evangelou & Limebeer (2004),
Multibody Syst. Dyn. 12:251-283, appendix. Their names are Pacejka's (``p_Cx1``, ``q_Bz9``, ...):
``p`` for forces, ``q`` for moments, ``r`` for the combined-slip weighting functions. The
equations that use them are in :mod:`motosim.model.tyres`.

Besides the coefficients a tyre has its nominal load ``F_z0``, its unloaded radius ``R_0``, the
radius of its crown ``R_c`` (the toroidal tyre's minor radius, which also stands for ``R_0`` in
the aligning-moment equations of the MF-MC, after Evangelou), its radial stiffness ``k_z`` and
damping ``c_z``, its relaxation lengths (``sigma_x``; the lateral one from ``sigma_c0..2``) and
the friction coefficient ``mu_0`` of the surface it was measured on, against which a road's
friction scales the peak factors.
"""

import math
from dataclasses import dataclass
from typing import ClassVar

from motosim.errors import MotosimError
from motosim.params._spec import Spec, validate_fields

__all__ = ["TyreParameters"]

_SPEED_RANGE = 80.0
"""Highest rolling speed [m/s] at which the lateral relaxation length must stay positive."""


def _coef(description: str, lower: float, upper: float, reason: str) -> Spec:
    return Spec.between("1", description, lower, upper, reason=reason)


def _positive(description: str, upper: float, reason: str) -> Spec:
    return Spec("1", description, 0.0, upper=upper, upper_closed=True, reason=reason)


_CURVATURE = "curvature factors of published fits lie within +/-25; E <= 1 is enforced in use"
_SHAPE = "a shape factor between 0 and 2 keeps the sine's argument below pi"
_VARIATION = "a variation with load or camber, dimensionless, of order one in published fits"


@dataclass(frozen=True, slots=True)
class TyreParameters:
    """One motorcycle tyre: radii, radial and relaxation properties and MF-MC coefficients.

    Every field is a physical constant; see :attr:`SPECS` for its unit, meaning and range.
    The stiffnesses and peaks they imply are computed by :mod:`motosim.model.tyres`.

    Raises
    ------
    MotosimError
        If a value is not finite or outside its range, if the crown radius is not below the
        unloaded radius, if ``p_Cy1 + p_Cy2`` is not below 2 (the side force's sine would
        fold back), if the cornering stiffness at the nominal load is not positive, or if the
        lateral relaxation length is not positive at the nominal load at 0 to 80 m/s.
    """

    F_z0: float
    R_0: float
    R_c: float
    k_z: float
    c_z: float
    sigma_x: float
    sigma_c0: float
    sigma_c1: float
    sigma_c2: float
    mu_0: float
    p_Cx1: float
    p_Dx1: float
    p_Dx2: float
    p_Ex1: float
    p_Ex2: float
    p_Ex3: float
    p_Ex4: float
    p_Kx1: float
    p_Kx2: float
    p_Kx3: float
    p_Cy1: float
    p_Dy1: float
    p_Dy2: float
    p_Dy3: float
    p_Ey1: float
    p_Ey2: float
    p_Ey3: float
    p_Ey4: float
    p_Ky1: float
    p_Ky2: float
    p_Ky3: float
    p_Ky4: float
    p_Ky5: float
    p_Cy2: float
    p_Ky6: float
    p_Ky7: float
    p_Ey5: float
    q_Hz3: float
    q_Hz4: float
    q_Bz1: float
    q_Bz2: float
    q_Bz5: float
    q_Bz6: float
    q_Cz1: float
    q_Dz1: float
    q_Dz2: float
    q_Dz3: float
    q_Dz4: float
    q_Ez1: float
    q_Ez2: float
    q_Ez3: float
    q_Ez5: float
    q_Bz9: float
    q_Bz10: float
    q_Dz8: float
    q_Dz9: float
    q_Dz10: float
    q_Dz11: float
    q_Sx1: float
    q_Sx2: float
    q_Sx3: float
    r_Bx1: float
    r_Bx2: float
    r_Cx1: float
    r_By1: float
    r_By2: float
    r_By3: float
    r_Cy1: float

    SPECS: ClassVar[dict[str, Spec]] = {
        "F_z0": Spec.between(
            "N",
            "nominal load F_z0",
            100.0,
            2e4,
            reason="motorcycle tyres are fitted at 0.5-3 kN; a heavy tourer's rear below 20 kN",
        ),
        "R_0": Spec.between(
            "m",
            "unloaded radius",
            0.1,
            0.6,
            reason="from a scooter's 10 inch wheel to a large off-road wheel",
        ),
        "R_c": Spec.between(
            "m",
            "crown radius (the toroidal tyre's minor radius)",
            0.0,
            0.3,
            reason="0 for a knife edge; half a section width at most (a 300 mm tyre: 0.15)",
        ),
        "k_z": Spec.between(
            "N/m",
            "radial stiffness",
            1e4,
            2e6,
            reason="a soft bicycle tyre to a hard racing slick (motorcycles: about 1.3e5)",
        ),
        "c_z": Spec.between(
            "N*s/m",
            "radial damping",
            0.0,
            2e4,
            reason="rubber's damping, well below the critical damping of a wheel on its tyre",
        ),
        "sigma_x": Spec.between(
            "m",
            "longitudinal relaxation length",
            1e-3,
            2.0,
            reason="a fraction of the contact length to a few radii",
        ),
        "sigma_c0": Spec.between(
            "m/N",
            "lateral relaxation length over cornering stiffness, constant term",
            0.0,
            1e-3,
            reason="sigma_y = K_y0 (c0 + c1 V + c2 V^2) of Evangelou's thesis, sec. 9.3.10",
        ),
        "sigma_c1": Spec.between(
            "s/N",
            "lateral relaxation length over cornering stiffness, per speed",
            -1e-4,
            1e-4,
            reason="a small variation with speed (Evangelou: 3.7e-8 for the front tyre)",
        ),
        "sigma_c2": Spec.between(
            "s^2/(N*m)",
            "lateral relaxation length over cornering stiffness, per speed squared",
            -1e-5,
            1e-5,
            reason="a small variation with speed (Evangelou: 8.4e-10 for the front tyre)",
        ),
        "mu_0": Spec.between(
            "1",
            "friction coefficient of the surface the tyre was measured on",
            0.05,
            2.0,
            reason="the road's friction over mu_0 scales the peak factors",
        ),
        "p_Cx1": _positive("shape factor C_x of the longitudinal force", 2.0, _SHAPE),
        "p_Dx1": _positive("longitudinal friction mu_x at F_z0", 3.0, "dry rubber below 3"),
        "p_Dx2": _coef("variation of mu_x with load", -1.0, 1.0, _VARIATION),
        "p_Ex1": _coef("curvature E_x at F_z0", -100.0, 100.0, _CURVATURE),
        "p_Ex2": _coef("variation of E_x with load", -100.0, 100.0, _CURVATURE),
        "p_Ex3": _coef("variation of E_x with load squared", -100.0, 100.0, _CURVATURE),
        "p_Ex4": _coef("E_x's asymmetry, driving against braking", -100.0, 100.0, _CURVATURE),
        "p_Kx1": _positive("longitudinal slip stiffness K_x / F_z at F_z0", 200.0, "5-50 found"),
        "p_Kx2": _coef("variation of K_x / F_z with load", -100.0, 100.0, _VARIATION),
        "p_Kx3": _coef("exponential variation of K_x / F_z with load", -10.0, 10.0, _VARIATION),
        "p_Cy1": _positive("shape factor C_y of the side force", 2.0, _SHAPE),
        "p_Dy1": _positive("lateral friction mu_y at F_z0", 3.0, "dry rubber below 3"),
        "p_Dy2": _coef("exponential variation of mu_y with load", -10.0, 10.0, _VARIATION),
        "p_Dy3": _coef("variation of mu_y with camber squared", 0.0, 100.0, _VARIATION),
        "p_Ey1": _coef("curvature E_y at F_z0", -100.0, 100.0, _CURVATURE),
        "p_Ey2": _coef("variation of E_y with camber squared", -100.0, 100.0, _CURVATURE),
        "p_Ey3": _coef("E_y's asymmetry with the sign of the slip", -100.0, 100.0, _CURVATURE),
        "p_Ey4": _coef("E_y's asymmetry with camber", -100.0, 100.0, _CURVATURE),
        "p_Ky1": _positive("peak of K_y / F_z0", 200.0, "motorcycle tyres: 10-30"),
        "p_Ky2": _positive("shape of K_y against load", 10.0, "of order one"),
        "p_Ky3": _positive("load at the peak of K_y, over F_z0", 100.0, "of order one"),
        "p_Ky4": _coef("variation of p_Ky3 with camber squared", -100.0, 100.0, _VARIATION),
        "p_Ky5": _coef("variation of K_y with camber squared", -100.0, 100.0, _VARIATION),
        "p_Cy2": _positive("shape factor C_gamma of the camber force", 2.0, _SHAPE),
        "p_Ky6": _coef("camber stiffness K_gamma / F_z at F_z0", 0.0, 20.0, "about one"),
        "p_Ky7": _coef("variation of K_gamma / F_z with load", -20.0, 20.0, _VARIATION),
        "p_Ey5": _coef("curvature E_gamma of the camber force", -100.0, 100.0, _CURVATURE),
        "q_Hz3": _coef("shift of the residual torque's slip with camber", -1.0, 1.0, _VARIATION),
        "q_Hz4": _coef("variation of q_Hz3 with load", -1.0, 1.0, _VARIATION),
        "q_Bz1": _positive("trail slope factor B_t at F_z0", 100.0, "of order ten"),
        "q_Bz2": _coef("variation of B_t with load", -100.0, 100.0, _VARIATION),
        "q_Bz5": _coef("variation of B_t with |camber|", -100.0, 100.0, _VARIATION),
        "q_Bz6": _coef("variation of B_t with camber squared", -100.0, 100.0, _VARIATION),
        "q_Cz1": _positive("shape factor C_t of the pneumatic trail", 3.0, "about one"),
        "q_Dz1": _coef("peak trail D_t F_z0 / (F_z R_c)", 0.0, 10.0, "of order 0.1"),
        "q_Dz2": _coef("variation of the peak trail with load", -10.0, 10.0, _VARIATION),
        "q_Dz3": _coef("variation of the peak trail with |camber|", -10.0, 10.0, _VARIATION),
        "q_Dz4": _coef("variation of the peak trail with camber squared", -10.0, 10.0, _VARIATION),
        "q_Ez1": _coef("curvature E_t of the trail at F_z0", -100.0, 100.0, _CURVATURE),
        "q_Ez2": _coef("variation of E_t with load", -100.0, 100.0, _CURVATURE),
        "q_Ez3": _coef("variation of E_t with load squared", -100.0, 100.0, _CURVATURE),
        "q_Ez5": _coef("variation of E_t with camber and slip", -100.0, 100.0, _CURVATURE),
        "q_Bz9": _coef("slope factor B_r of the residual torque", 0.0, 200.0, "of order ten"),
        "q_Bz10": _coef("variation of B_r with B_y C_y", -100.0, 100.0, _VARIATION),
        "q_Dz8": _coef("residual torque per camber, over F_z R_c", -10.0, 10.0, _VARIATION),
        "q_Dz9": _coef("variation of q_Dz8 with load", -10.0, 10.0, _VARIATION),
        "q_Dz10": _coef("residual torque per camber |camber|", -10.0, 10.0, _VARIATION),
        "q_Dz11": _coef("variation of q_Dz10 with load", -10.0, 10.0, _VARIATION),
        "q_Sx1": _coef("overturning moment offset, over F_z R_0", -1.0, 1.0, _VARIATION),
        "q_Sx2": _coef("overturning moment per camber", -1.0, 1.0, _VARIATION),
        "q_Sx3": _coef("overturning moment per F_y / F_z0", -1.0, 1.0, _VARIATION),
        "r_Bx1": _positive("slope of the weighting G_x(alpha)", 100.0, "of order ten"),
        "r_Bx2": _coef("variation of that slope with kappa", -100.0, 100.0, _VARIATION),
        "r_Cx1": _positive("shape of the weighting G_x(alpha)", 3.0, "about one"),
        "r_By1": _positive("slope of the weighting G_y(kappa)", 100.0, "of order ten"),
        "r_By2": _coef("variation of that slope with alpha", -100.0, 100.0, _VARIATION),
        "r_By3": _coef("shift of alpha in that slope", -1.0, 1.0, _VARIATION),
        "r_Cy1": _positive("shape of the weighting G_y(kappa)", 3.0, "about one"),
    }

    TYPICAL: ClassVar[dict[str, tuple[float, float, str]]] = {
        "F_z0": (500.0, 4000.0, "motorcycle tyres; Evangelou's fits: 1100 N front, 1600 N rear"),
        "R_0": (0.2, 0.4, "motorcycle wheels of 13 to 21 inches with their tyres"),
        "k_z": (5e4, 5e5, "motorcycle tyres at road pressures (about 1.3e5)"),
        "p_Dx1": (0.5, 2.0, "road tyres on dry asphalt: about 1.3"),
        "p_Dy1": (0.5, 2.0, "road tyres on dry asphalt: about 1.3"),
        "sigma_x": (0.02, 0.5, "about the contact length to a half radius"),
    }
    """Typical range of the main parameters (low, high, why): a value outside is legal (see
    :attr:`SPECS`) but far from a road motorcycle tyre, and is accepted with a warning."""

    def __post_init__(self) -> None:
        validate_fields(self, context="tyre parameters")
        if self.R_c >= self.R_0:
            raise MotosimError(
                f"tyre parameters: crown radius R_c = {self.R_c:g} m is not below the unloaded "
                f"radius R_0 = {self.R_0:g} m"
            )
        if self.p_Cy1 + self.p_Cy2 >= 2.0:
            raise MotosimError(
                f"tyre parameters: p_Cy1 + p_Cy2 = {self.p_Cy1 + self.p_Cy2:g}; expected below 2 "
                "(the side force's sine would fold back at large slip and camber)"
            )
        if self.p_Ky2 * math.atan(1.0 / self.p_Ky3) >= math.pi:
            raise MotosimError(
                f"tyre parameters: p_Ky2 atan(1 / p_Ky3) = "
                f"{self.p_Ky2 * math.atan(1.0 / self.p_Ky3):g}; expected below pi (a positive "
                "cornering stiffness at the nominal load)"
            )
        K_y0 = self.p_Ky1 * self.F_z0 * math.sin(self.p_Ky2 * math.atan(1.0 / self.p_Ky3))
        speeds = [0.0, _SPEED_RANGE]
        if self.sigma_c2 > 0.0 and 0.0 < -self.sigma_c1 / (2.0 * self.sigma_c2) < _SPEED_RANGE:
            speeds.append(-self.sigma_c1 / (2.0 * self.sigma_c2))  # the quadratic's minimum
        for speed in speeds:
            sigma = K_y0 * (self.sigma_c0 + self.sigma_c1 * speed + self.sigma_c2 * speed**2)
            if not sigma > 0.0:
                raise MotosimError(
                    f"tyre parameters: the lateral relaxation length at F_z0 and {speed:g} m/s "
                    f"is {sigma:g} m; expected > 0 (sigma_c0, sigma_c1, sigma_c2)"
                )
