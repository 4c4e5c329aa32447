"""Motorcycle tyres: the Magic Formula motorcycle tyre (MF-MC) and a linear relaxing tyre.

The multibody model calls these pure, compiled functions of plain floats in its step: the
steady-state forces and moments of a tyre at a normal load, longitudinal slip, sideslip,
camber and road friction (:func:`steady_forces`), its relaxation lengths
(:func:`relaxation_lengths`) and the first-order lag of its slips (:func:`slip_rate`,
:func:`relax`). A tyre's coefficients travel as one :class:`TyreCoefficients` named tuple,
built from :class:`~motosim.params.TyreParameters` by :func:`tyre_coefficients` or, for the
linear tyre of Sharp (1971), by :func:`linear_tyre_coefficients`; both kinds go through the
same functions, so the model runs either. :func:`tyre_curves` evaluates them over arrays for
plots and checks.

Axes and signs are Meijaard et al.'s (2007) and the SAE's: x forward along the wheel's
heading in the road plane, y to the right, z down. The sideslip ``alpha`` is positive when
the contact point moves to the left of the heading (``tan(alpha) = -v_y / |v_x|``), the
camber ``gamma`` when the wheel leans to the right, the longitudinal slip ``kappa`` when the
wheel spins faster than it rolls (``kappa = (omega r_e - v_x) / |v_x|``). A positive alpha and
a positive gamma each give a positive (rightward) side force ``F_y``; ``F_x`` is positive
forward; ``M_z`` is about +z (positive turns the heading to the right) and ``M_x`` about +x.

Notes
-----
The MF-MC of Pacejka (2006, section 11.5) as completed and fitted by Evangelou (2004, chapter
9 and appendix C) and used by Sharp, Evangelou & Limebeer (2004). With
``dfz = (F_z - F_z0) / F_z0``, ``lam = mu / mu_0`` and ``shape(B, E, x) = B x - E (B x -
atan(B x))``, every curvature ``E`` capped at 1:

- longitudinal: ``F_x0 = D_x sin(C_x atan(shape(B_x, E_x, kappa)))``, ``C_x = p_Cx1``,
  ``D_x = (p_Dx1 + p_Dx2 dfz) lam F_z``, ``E_x = (p_Ex1 + p_Ex2 dfz + p_Ex3 dfz^2)(1 - p_Ex4
  sgn kappa)``, ``K_x = F_z (p_Kx1 + p_Kx2 dfz) exp(p_Kx3 dfz) = B_x C_x D_x``;
- lateral, side slip and camber inside one sine: ``F_y0 = D_y sin(C_y atan(shape(B_y, E_y,
  tan alpha)) + C_g atan(shape(B_g, E_g, gamma)))``, ``C_y = p_Cy1``, ``C_g = p_Cy2``,
  ``D_y = p_Dy1 exp(p_Dy2 dfz) / (1 + p_Dy3 gamma^2) lam F_z``, ``E_y = p_Ey1 + p_Ey2 gamma^2
  + (p_Ey3 + p_Ey4 gamma) sgn alpha``, ``E_g = p_Ey5``, ``K_y = p_Ky1 F_z0 sin(p_Ky2
  atan(F_z / ((p_Ky3 + p_Ky4 gamma^2) F_z0))) / (1 + p_Ky5 gamma^2) = B_y C_y D_y``, ``K_g =
  (p_Ky6 + p_Ky7 dfz) F_z = B_g C_g D_y``; so the cornering stiffness is ``K_y`` and the camber
  stiffness ``K_g``;
- combined slip, cosine weightings: ``F_x = G_xa F_x0`` with ``G_xa = cos(r_Cx1 atan(B_xa tan
  alpha))``, ``B_xa = r_Bx1 cos(atan(r_Bx2 kappa))``; ``F_y = G_yk F_y0`` with ``G_yk = cos(r_Cy1
  atan(B_yk kappa))``, ``B_yk = r_By1 cos(atan(r_By2 (tan alpha - r_By3)))``, both >= 0;
- aligning moment: ``M_z = -t G_yk F_y0(gamma = 0) + M_zr``, the pneumatic trail ``t = D_t
  cos(C_t atan(shape(B_t, E_t, a_t))) cos alpha`` acting on the camber-free side force, the
  residual (twisting) torque ``M_zr = D_r cos(atan(B_r a_r))``; ``B_t = (q_Bz1 + q_Bz2 dfz)(1 +
  q_Bz5 |gamma| + q_Bz6 gamma^2)``, ``C_t = q_Cz1``, ``D_t = F_z (R_c / F_z0)(q_Dz1 + q_Dz2
  dfz)(1 + q_Dz3 |gamma| + q_Dz4 gamma^2)``, ``E_t = (q_Ez1 + q_Ez2 dfz + q_Ez3 dfz^2)(1 +
  q_Ez5 gamma (2/pi) atan(B_t C_t tan alpha))``, ``B_r = q_Bz9 + q_Bz10 B_y C_y``, ``D_r = F_z
  R_c ((q_Dz8 + q_Dz9 dfz) gamma + (q_Dz10 + q_Dz11 dfz) gamma |gamma|) cos alpha``; the slips
  combined as ``a_t = sgn(tan alpha) sqrt(tan^2 alpha + (K_x / K_y0)^2 kappa^2)`` and likewise
  ``a_r`` from ``tan alpha + (q_Hz3 + q_Hz4 dfz) gamma``;
- overturning moment: ``M_x = R_0 F_z (q_Sx1 + q_Sx2 gamma + q_Sx3 F_y / F_z0)``; Evangelou's
  sets have none (the moment comes from the contact point moving round the crown, which the
  multibody model's toroidal geometry carries);
- relaxation: ``sigma / |v| dslip/dt + slip = slip_ss``, with ``sigma_y = K_y0 (sigma_c0 +
  sigma_c1 |v| + sigma_c2 v^2)`` (Evangelou 2004, section 9.3.10) and a constant ``sigma_x``.

The linear tyre (Sharp 1971) is ``F_y = F_z (C_alpha alpha + C_gamma gamma)``, ``F_x = F_z
C_kappa kappa``, no moments and no friction limit, its stiffnesses normalised by the nominal
load so that at that load they are Sharp's.

References
----------
Pacejka, H. B. (2006). *Tyre and Vehicle Dynamics*, 2nd ed., Butterworth-Heinemann, ch. 4
and 11. Evangelou, S. (2004). *Control and stability analysis of two-wheeled road vehicles*,
PhD thesis, Imperial College London. Sharp, R. S., Evangelou, S. & Limebeer, D. J. N. (2004).
Advances in the modelling of motorcycle dynamics. *Multibody Syst. Dyn.* 12:251-283. Sharp,
R. S. (1971). The stability and control of motorcycles. *J. Mech. Eng. Sci.* 13(5):316-329.
"""

import math
from enum import IntEnum
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from motosim.errors import MotosimError
from motosim.params.tyre import TyreParameters

__all__ = [
    "TyreCoefficients",
    "TyreForces",
    "TyreKind",
    "camber_stiffness",
    "cornering_stiffness",
    "linear_forces",
    "linear_tyre_coefficients",
    "mf_forces",
    "relax",
    "relaxation_lengths",
    "slip_rate",
    "slip_stiffness",
    "steady_forces",
    "tyre_coefficients",
    "tyre_curves",
]

_EPS = 1e-9
"""Guards the divisions B = K / (C D) at a vanishing load or friction [N]."""


class TyreKind(IntEnum):
    """Which tyre model a :class:`TyreCoefficients` describes."""

    MAGIC_FORMULA = 0
    LINEAR = 1


class TyreCoefficients(NamedTuple):
    """A tyre for compiled code: its kind, its MF-MC coefficients and its linear stiffnesses.

    The fields after ``kind`` are those of :class:`~motosim.params.TyreParameters` (SI units;
    zero where the kind does not use them), then the linear tyre's normalised stiffnesses
    ``C_kappa`` [1], ``C_alpha`` [1/rad], ``C_gamma`` [1/rad] and its constant lateral
    relaxation length ``sigma_y`` [m].
    """

    kind: int
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
    C_kappa: float
    C_alpha: float
    C_gamma: float
    sigma_y: float


class TyreForces(NamedTuple):
    """Steady-state forces [N] and moments [N*m] of a tyre, over arrays (see module axes)."""

    F_x: NDArray[np.float64]
    F_y: NDArray[np.float64]
    M_z: NDArray[np.float64]
    M_x: NDArray[np.float64]


_LINEAR_FIELDS = ("C_kappa", "C_alpha", "C_gamma", "sigma_y")


def tyre_coefficients(params: TyreParameters) -> TyreCoefficients:
    """The MF-MC coefficients of a tyre, for the compiled functions.

    Parameters
    ----------
    params : TyreParameters
        A validated tyre, e.g. ``load_parameters("sel2004_front_120_70_zr17", "tyre")``.

    Returns
    -------
    TyreCoefficients
        Of kind :attr:`TyreKind.MAGIC_FORMULA`, the linear fields zero.
    """
    values = {name: float(getattr(params, name)) for name in TyreParameters.SPECS}
    return TyreCoefficients(
        kind=int(TyreKind.MAGIC_FORMULA), **values, **dict.fromkeys(_LINEAR_FIELDS, 0.0)
    )


def linear_tyre_coefficients(
    *,
    nominal_load: float,
    cornering_stiffness: float,
    camber_stiffness: float,
    slip_stiffness: float,
    relaxation_length: float,
    radius: float,
) -> TyreCoefficients:
    """A linear relaxing tyre (Sharp 1971) behind the same functions as the Magic Formula.

    Parameters
    ----------
    nominal_load : float
        Normal load at which the stiffnesses hold [N] (Sharp 1971: the static load).
    cornering_stiffness, camber_stiffness : float
        dF_y/dalpha and dF_y/dgamma at that load [N/rad] (Sharp's C_f1, C_f2 or C_r1, C_r2).
    slip_stiffness : float
        dF_x/dkappa at that load [N] (Sharp 1971 has none: the caller chooses).
    relaxation_length : float
        The lateral relaxation length, also used longitudinally [m].
    radius : float
        The wheel's radius [m], for the overturning-moment lever (zero moment here).

    Returns
    -------
    TyreCoefficients
        Of kind :attr:`TyreKind.LINEAR`; the stiffnesses normalised by ``nominal_load``.

    Raises
    ------
    MotosimError
        If the load, a stiffness, the relaxation length or the radius is not a finite positive
        number (the camber stiffness may be zero).
    """
    checks = {
        "nominal_load": (nominal_load, "N"),
        "cornering_stiffness": (cornering_stiffness, "N/rad"),
        "slip_stiffness": (slip_stiffness, "N"),
        "relaxation_length": (relaxation_length, "m"),
        "radius": (radius, "m"),
    }
    for name, (value, unit) in checks.items():
        if not (math.isfinite(value) and value > 0.0):
            raise MotosimError(
                f"linear tyre: {name} = {value!r}; expected a finite number > 0 [{unit}]"
            )
    if not (math.isfinite(camber_stiffness) and camber_stiffness >= 0.0):
        raise MotosimError(
            f"linear tyre: camber_stiffness = {camber_stiffness!r}; "
            "expected a finite number >= 0 [N/rad]"
        )
    values = dict.fromkeys(TyreParameters.SPECS, 0.0)
    values.update(F_z0=nominal_load, R_0=radius, sigma_x=relaxation_length, mu_0=1.0)
    return TyreCoefficients(
        kind=int(TyreKind.LINEAR),
        **values,
        C_kappa=slip_stiffness / nominal_load,
        C_alpha=cornering_stiffness / nominal_load,
        C_gamma=camber_stiffness / nominal_load,
        sigma_y=relaxation_length,
    )


@njit(cache=True)
def _shape(B: float, E: float, x: float) -> float:
    Bx = B * x
    return Bx - E * (Bx - math.atan(Bx))


@njit(cache=True)
def _sign(x: float) -> float:
    return 1.0 if x >= 0.0 else -1.0


@njit(cache=True)
def slip_stiffness(c: TyreCoefficients, F_z: float) -> float:
    """Longitudinal slip stiffness K_x = dF_x/dkappa at zero slip [N], at load F_z [N]."""
    if c.kind == TyreKind.LINEAR:
        return c.C_kappa * F_z
    dfz = (F_z - c.F_z0) / c.F_z0
    return F_z * (c.p_Kx1 + c.p_Kx2 * dfz) * math.exp(c.p_Kx3 * dfz)


@njit(cache=True)
def cornering_stiffness(c: TyreCoefficients, F_z: float, gamma: float) -> float:
    """Cornering stiffness K_y = dF_y/dalpha at zero sideslip [N/rad], at F_z [N], camber [rad]."""
    if c.kind == TyreKind.LINEAR:
        return c.C_alpha * F_z
    g2 = gamma * gamma
    K = c.p_Ky1 * c.F_z0 * math.sin(c.p_Ky2 * math.atan(F_z / ((c.p_Ky3 + c.p_Ky4 * g2) * c.F_z0)))
    return K / (1.0 + c.p_Ky5 * g2)


@njit(cache=True)
def camber_stiffness(c: TyreCoefficients, F_z: float) -> float:
    """Camber stiffness K_gamma = dF_y/dgamma at zero slip and camber [N/rad], at F_z [N]."""
    if c.kind == TyreKind.LINEAR:
        return c.C_gamma * F_z
    return (c.p_Ky6 + c.p_Ky7 * (F_z - c.F_z0) / c.F_z0) * F_z


@njit(cache=True)
def _lateral(
    c: TyreCoefficients, F_z: float, dfz: float, tan_a: float, gamma: float, lam: float
) -> tuple[float, float, float]:
    """F_y0 [N] of the MF-MC at camber gamma, and its B_y, C_y."""
    g2 = gamma * gamma
    D_y = c.p_Dy1 * math.exp(c.p_Dy2 * dfz) / (1.0 + c.p_Dy3 * g2) * lam * F_z
    C_y = c.p_Cy1
    B_y = cornering_stiffness(c, F_z, gamma) / (C_y * D_y + _EPS)
    E_y = min(c.p_Ey1 + c.p_Ey2 * g2 + (c.p_Ey3 + c.p_Ey4 * gamma) * _sign(tan_a), 1.0)
    C_g = c.p_Cy2
    B_g = camber_stiffness(c, F_z) / (C_g * D_y + _EPS)
    E_g = min(c.p_Ey5, 1.0)
    angle = C_y * math.atan(_shape(B_y, E_y, tan_a)) + C_g * math.atan(_shape(B_g, E_g, gamma))
    return D_y * math.sin(angle), B_y, C_y


@njit(cache=True)
def mf_forces(
    c: TyreCoefficients, F_z: float, kappa: float, alpha: float, gamma: float, mu: float
) -> tuple[float, float, float, float]:
    """Steady-state forces and moments of the MF-MC (module notes) at one operating point.

    Parameters
    ----------
    c : TyreCoefficients
        A Magic Formula tyre (:func:`tyre_coefficients`).
    F_z : float
        Normal load, positive in compression [N]; zero or less gives no force.
    kappa, alpha, gamma : float
        Longitudinal slip [1], sideslip [rad], camber [rad] (module axes).
    mu : float
        Road friction coefficient [1]; ``mu / mu_0`` scales the peak factors.

    Returns
    -------
    tuple of float
        ``(F_x, F_y, M_z, M_x)`` [N, N, N*m, N*m].
    """
    if F_z <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    lam = mu / c.mu_0
    dfz = (F_z - c.F_z0) / c.F_z0
    tan_a = math.tan(alpha)
    cos_a = math.cos(alpha)
    # pure longitudinal slip
    C_x = c.p_Cx1
    D_x = (c.p_Dx1 + c.p_Dx2 * dfz) * lam * F_z
    K_x = slip_stiffness(c, F_z)
    B_x = K_x / (C_x * D_x + _EPS)
    E_x = min((c.p_Ex1 + c.p_Ex2 * dfz + c.p_Ex3 * dfz * dfz) * (1.0 - c.p_Ex4 * _sign(kappa)), 1.0)
    F_x0 = D_x * math.sin(C_x * math.atan(_shape(B_x, E_x, kappa)))
    # pure side slip with camber, and without (for the trail)
    F_y0, B_y, C_y = _lateral(c, F_z, dfz, tan_a, gamma, lam)
    F_y00 = F_y0 if gamma == 0.0 else _lateral(c, F_z, dfz, tan_a, 0.0, lam)[0]
    K_y0 = cornering_stiffness(c, F_z, 0.0)
    # combined slip
    B_xa = c.r_Bx1 * math.cos(math.atan(c.r_Bx2 * kappa))
    G_xa = max(math.cos(c.r_Cx1 * math.atan(B_xa * tan_a)), 0.0)
    B_yk = c.r_By1 * math.cos(math.atan(c.r_By2 * (tan_a - c.r_By3)))
    G_yk = max(math.cos(c.r_Cy1 * math.atan(B_yk * kappa)), 0.0)
    F_x = G_xa * F_x0
    F_y = G_yk * F_y0
    # aligning moment: trail on the camber-free side force, residual torque from camber
    g_abs = abs(gamma)
    B_t = (c.q_Bz1 + c.q_Bz2 * dfz) * (1.0 + c.q_Bz5 * g_abs + c.q_Bz6 * gamma * gamma)
    C_t = c.q_Cz1
    D_t = (
        F_z
        * (c.R_c / c.F_z0)
        * (c.q_Dz1 + c.q_Dz2 * dfz)
        * (1.0 + c.q_Dz3 * g_abs + c.q_Dz4 * gamma * gamma)
    )
    E_t = min(
        (c.q_Ez1 + c.q_Ez2 * dfz + c.q_Ez3 * dfz * dfz)
        * (1.0 + c.q_Ez5 * gamma * (2.0 / math.pi) * math.atan(B_t * C_t * tan_a)),
        1.0,
    )
    k2 = (K_x / (K_y0 + _EPS)) ** 2 * kappa * kappa
    a_t = math.sqrt(tan_a * tan_a + k2) * _sign(tan_a)
    a_r0 = tan_a + (c.q_Hz3 + c.q_Hz4 * dfz) * gamma
    a_r = math.sqrt(a_r0 * a_r0 + k2) * _sign(a_r0)
    t = D_t * math.cos(C_t * math.atan(_shape(B_t, E_t, a_t))) * cos_a
    B_r = c.q_Bz9 + c.q_Bz10 * B_y * C_y
    D_r = (
        F_z
        * c.R_c
        * ((c.q_Dz8 + c.q_Dz9 * dfz) * gamma + (c.q_Dz10 + c.q_Dz11 * dfz) * gamma * g_abs)
        * cos_a
    )
    M_zr = D_r * math.cos(math.atan(B_r * a_r))
    M_z = -t * G_yk * F_y00 + M_zr
    M_x = c.R_0 * F_z * (c.q_Sx1 + c.q_Sx2 * gamma + c.q_Sx3 * F_y / c.F_z0)
    return F_x, F_y, M_z, M_x


@njit(cache=True)
def linear_forces(
    c: TyreCoefficients, F_z: float, kappa: float, alpha: float, gamma: float, mu: float
) -> tuple[float, float, float, float]:
    """Forces of the linear tyre: ``F_x = F_z C_kappa kappa``, ``F_y = F_z (C_alpha alpha +
    C_gamma gamma)``, no moments; ``mu`` is not used (the linear tyre has no limit).

    Parameters and returns as :func:`mf_forces`.
    """
    if F_z <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    return F_z * c.C_kappa * kappa, F_z * (c.C_alpha * alpha + c.C_gamma * gamma), 0.0, 0.0


@njit(cache=True)
def steady_forces(
    c: TyreCoefficients, F_z: float, kappa: float, alpha: float, gamma: float, mu: float
) -> tuple[float, float, float, float]:
    """Steady-state ``(F_x, F_y, M_z, M_x)`` of either kind of tyre (see :func:`mf_forces`)."""
    if c.kind == TyreKind.LINEAR:
        return linear_forces(c, F_z, kappa, alpha, gamma, mu)
    return mf_forces(c, F_z, kappa, alpha, gamma, mu)


@njit(cache=True)
def relaxation_lengths(c: TyreCoefficients, F_z: float, speed: float) -> tuple[float, float]:
    """Longitudinal and lateral relaxation lengths ``(sigma_x, sigma_y)`` [m].

    Parameters
    ----------
    c : TyreCoefficients
        Either kind of tyre.
    F_z : float
        Normal load [N]; the MF-MC's sigma_y scales with the cornering stiffness at it (a
        small floor keeps it positive as the load vanishes).
    speed : float
        Rolling speed [m/s].

    Returns
    -------
    tuple of float
        ``(sigma_x, sigma_y)`` [m].
    """
    if c.kind == TyreKind.LINEAR:
        return c.sigma_x, c.sigma_y
    v = abs(speed)
    K_y0 = cornering_stiffness(c, max(F_z, 0.01 * c.F_z0), 0.0)
    sigma_y = K_y0 * (c.sigma_c0 + c.sigma_c1 * v + c.sigma_c2 * v * v)
    return c.sigma_x, max(sigma_y, 1e-4)


@njit(cache=True)
def slip_rate(slip: float, steady: float, sigma: float, speed: float) -> float:
    """Rate of a relaxing slip, from ``sigma / |v| dslip/dt + slip = steady`` [1/s or rad/s].

    Parameters
    ----------
    slip : float
        The lagged slip (the state) [1 or rad].
    steady : float
        The slip the tyre would have at once without lag [1 or rad].
    sigma : float
        Relaxation length [m] (> 0).
    speed : float
        Rolling speed [m/s].
    """
    return abs(speed) / sigma * (steady - slip)


@njit(cache=True)
def relax(slip: float, steady: float, sigma: float, speed: float, dt: float) -> float:
    """The lagged slip after ``dt`` [s] with ``steady``, ``sigma``, ``speed`` held: exact.

    ``steady + (slip - steady) exp(-|v| dt / sigma)``: after a distance ``sigma`` travelled,
    63.2 % of a step.
    """
    return steady + (slip - steady) * math.exp(-abs(speed) * dt / sigma)


@njit(cache=True)
def _curves(
    c: TyreCoefficients,
    F_z: NDArray[np.float64],
    kappa: NDArray[np.float64],
    alpha: NDArray[np.float64],
    gamma: NDArray[np.float64],
    mu: NDArray[np.float64],
    out: NDArray[np.float64],
) -> None:
    for i in range(F_z.size):
        F_x, F_y, M_z, M_x = steady_forces(c, F_z[i], kappa[i], alpha[i], gamma[i], mu[i])
        out[0, i] = F_x
        out[1, i] = F_y
        out[2, i] = M_z
        out[3, i] = M_x


def tyre_curves(
    c: TyreCoefficients,
    *,
    load: ArrayLike,
    kappa: ArrayLike = 0.0,
    alpha: ArrayLike = 0.0,
    gamma: ArrayLike = 0.0,
    mu: ArrayLike = 1.0,
) -> TyreForces:
    """Steady-state forces and moments over arrays (broadcast together), for plots and checks.

    Parameters
    ----------
    c : TyreCoefficients
        Either kind of tyre.
    load : array_like
        Normal load F_z [N].
    kappa, alpha, gamma : array_like, optional
        Longitudinal slip [1], sideslip [rad], camber [rad]; zero by default.
    mu : array_like, optional
        Road friction [1]; 1 by default (the measurement surface of the packaged sets).

    Returns
    -------
    TyreForces
        ``F_x, F_y, M_z, M_x`` with the broadcast shape [N, N, N*m, N*m].

    Raises
    ------
    MotosimError
        If an input is not finite or the arrays do not broadcast.

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> front = tyre_coefficients(load_parameters("sel2004_front_120_70_zr17", "tyre"))
    >>> forces = tyre_curves(front, load=1100.0, alpha=[0.0, 0.02])
    >>> [round(float(f)) for f in forces.F_y]
    [0, 365]
    """
    try:
        arrays = np.broadcast_arrays(
            *(np.asarray(a, dtype=float) for a in (load, kappa, alpha, gamma, mu))
        )
    except ValueError as err:
        raise MotosimError(f"tyre curves: the inputs do not broadcast ({err})") from None
    for name, a in zip(("load", "kappa", "alpha", "gamma", "mu"), arrays, strict=True):
        if not np.all(np.isfinite(a)):
            raise MotosimError(f"tyre curves: {name} has a value that is not finite")
    shape = arrays[0].shape
    flat = [np.ascontiguousarray(a.ravel()) for a in arrays]
    out = np.empty((4, flat[0].size))
    _curves(c, flat[0], flat[1], flat[2], flat[3], flat[4], out)
    return TyreForces(*(row.reshape(shape) for row in out))
