"""Sharp's (1971) motorcycle: lateral dynamics, modes and the longitudinal equation (2).

The lateral model is written in constant-mass-matrix form::

    M x' + E(u) x = F tau_r,     E(u) = E0 + u E1,     x = [v_y, psi_dot, phi_dot,
                                                           delta_dot, phi, delta, F_yr, F_yf]

so that A_v(u) = -M^-1 E(u) and B_v = M^-1 F (the paper's eq. (1)). Rows 1-4 are the
lateral force, yaw, roll and steer equations whose coefficients are the paper's a_ij and b_ij;
rows 5-6 are kinematics; rows 7-8 are the tyre relaxation equations multiplied by u, which
keeps M independent of speed. Mistakes of the printed appendix are not copied: A_v carries the
minus sign, B_v has eight entries with the 1 in the steer row, and the entries the appendix
omits (E27, E28, E44, E48 and the tyre rows) are included.
"""

import math
from collections.abc import Callable
from dataclasses import dataclass
from enum import IntEnum
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from motosim.errors import MotosimError
from motosim.model._inputs import input_series, sample_times
from motosim.model.linear import StateSpace
from motosim.params.sharp import SharpParameters, derived_geometry
from motosim.timeseries import TimeSeries

__all__ = [
    "MAX_SPEED",
    "MIN_SPEED",
    "MODE_NAMES",
    "STATE_NAMES",
    "ModeTable",
    "MotorcycleResponse",
    "MotorcycleState",
    "RK4Work",
    "bike_rk4",
    "check_speed",
    "eigenvalues",
    "held_steering",
    "input_matrix",
    "linearize",
    "longitudinal_acceleration",
    "lpv_matrices",
    "mass_matrix",
    "modes",
    "rk4_work",
    "side_force_input",
    "simulate",
    "stiffness_matrices",
    "track_modes",
]

Array = NDArray[np.float64]

STATE_NAMES = ("v_y", "psi_dot", "phi_dot", "delta_dot", "phi", "delta", "F_yr", "F_yf")
MODE_NAMES = ("capsize", "weave", "wobble")

MIN_SPEED = 1.0
"""Lowest forward speed [m/s] accepted by the lateral model.

Sharp's model linearises about steady running with non-slipping, relaxing tyres; at walking
pace the tyre lags and slip angles lose their meaning (Sharp's tables start at 3 m/s), and at
standstill the model is singular in its divided form.
"""

MAX_SPEED = 150.0
"""Highest forward speed [m/s] accepted by the lateral model: 540 km/h, above any motorcycle.

Sharp's tables stop at 60 m/s; beyond this bound a speed is a unit slip (km/h for m/s), and
following the modes up to it would take an unbounded number of eigenvalue problems.
"""


def check_speed(speed: float) -> float:
    """Return ``speed`` as float if the lateral model accepts it.

    Raises
    ------
    MotosimError
        If the speed is not finite or outside [:data:`MIN_SPEED`, :data:`MAX_SPEED`].
    """
    value = float(speed)
    if not (math.isfinite(value) and MIN_SPEED <= value <= MAX_SPEED):
        raise MotosimError(
            f"speed = {value:g} m/s; expected a finite forward speed >= {MIN_SPEED:g} m/s "
            f"and <= {MAX_SPEED:g} m/s (Sharp's lateral model linearises about forward running)"
        )
    return value


def mass_matrix(p: SharpParameters) -> Array:
    """The constant mass matrix M (8 x 8).

    The upper-left block holds the paper's a_ij (symmetric); M55 = M66 = 1 and
    M77 = M88 = sigma.
    """
    d = derived_geometry(p)
    j, k = d["j"], d["k"]
    se, ce = math.sin(p.epsilon), math.cos(p.epsilon)
    a11 = p.m_f + p.m_r
    a12 = p.m_f * k
    a13 = p.m_f * j + p.m_r * p.h
    a14 = p.m_f * p.e
    a22 = p.m_f * k**2 + p.I_rz + p.I_fx * se**2 + p.I_fz * ce**2
    a23 = p.m_f * j * k - p.C_rxz + (p.I_fz - p.I_fx) * se * ce
    a24 = p.m_f * p.e * k + p.I_fz * ce
    a33 = p.m_f * j**2 + p.m_r * p.h**2 + p.I_rx + p.I_fx * ce**2 + p.I_fz * se**2
    a34 = p.m_f * p.e * j + p.I_fz * se
    a44 = p.m_f * p.e**2 + p.I_fz
    M = np.zeros((8, 8))
    M[:4, :4] = [
        [a11, a12, a13, a14],
        [a12, a22, a23, a24],
        [a13, a23, a33, a34],
        [a14, a24, a34, a44],
    ]
    M[4, 4] = M[5, 5] = 1.0
    M[6, 6] = M[7, 7] = p.sigma
    return M


def stiffness_matrices(p: SharpParameters) -> tuple[Array, Array]:
    """The speed-independent part E0 and the speed coefficient E1 of E(u) = E0 + u E1.

    Returns
    -------
    E0, E1 : ndarray, shape (8, 8)
        Rows 1-4 reproduce the paper's b_ij (E0 in N, N*m and E1 in kg, kg*m).
    """
    d = derived_geometry(p)
    j, k, l = d["j"], d["k"], d["l"]  # noqa: E741 - Sharp's symbol
    se, ce = math.sin(p.epsilon), math.cos(p.epsilon)
    Gf, Gr = p.i_fy / p.R_f, p.i_Ry / p.R_r
    S = p.Z_f * p.t - p.m_f * p.e * p.g
    mgh = (p.m_f * j + p.m_r * p.h) * p.g
    E0 = np.zeros((8, 8))
    E1 = np.zeros((8, 8))
    # 1 lateral force
    E1[0, 1] = p.m_f + p.m_r
    E0[0, 6] = E0[0, 7] = -1.0
    # 2 yaw moment
    E1[1, 1] = p.m_f * k
    E1[1, 2] = -(Gf + Gr)
    E1[1, 3] = -Gf * se
    E0[1, 6] = p.b
    E0[1, 7] = -l
    # 3 roll moment
    E1[2, 1] = p.m_f * j + p.m_r * p.h + Gf + Gr
    E1[2, 3] = Gf * ce
    E0[2, 4] = -mgh
    E0[2, 5] = S
    # 4 steer moment about the steering axis
    E1[3, 1] = p.m_f * p.e + Gf * se
    E1[3, 2] = -Gf * ce
    E0[3, 3] = p.K
    E0[3, 4] = S
    E0[3, 5] = S * se
    E0[3, 7] = p.t
    # 5-6 kinematics
    E0[4, 2] = -1.0
    E0[5, 3] = -1.0
    # 7 rear tyre, (sigma/u) F_yr' + F_yr = C_r1 (b r - v)/u + C_r2 phi, times u
    E0[6, 0] = p.C_r1
    E0[6, 1] = -p.C_r1 * p.b
    E1[6, 4] = -p.C_r2
    E1[6, 6] = 1.0
    # 8 front tyre, slip cos(eps) delta - (v + l r - t delta')/u, camber phi + sin(eps) delta
    E0[7, 0] = p.C_f1
    E0[7, 1] = p.C_f1 * l
    E0[7, 3] = -p.C_f1 * p.t
    E1[7, 4] = -p.C_f2
    E1[7, 5] = -(p.C_f1 * ce + p.C_f2 * se)
    E1[7, 7] = 1.0
    return E0, E1


def input_matrix(p: SharpParameters) -> Array:
    """F of M x' + E x = F tau_r: the rider torque acts on the steer row only, shape (8,)."""
    del p  # the rider torque enters the steer equation with unit gain for any machine
    F = np.zeros(8)
    F[3] = 1.0
    return F


def side_force_input(p: SharpParameters, *, height: float, ahead: float = 0.0) -> Array:
    """B_w of x' = A_v x + B_v tau_r + B_w F_wy: a side force on the rear frame, shape (8,).

    A lateral force F_wy [N] (to the right, +y), as a side wind, applied at ``height`` [m]
    above the ground and ``ahead`` [m] of the reference point A (below G_r), enters the
    lateral-force equation with F_wy, the yaw moment about A with ``ahead`` F_wy and the roll
    moment about the ground line with ``height`` F_wy (a force to the right above the ground
    tips the machine right side down, as phi is counted); the steer and tyre equations are not
    touched. Sharp's model has no aerodynamics; this adds the generalised force of one
    concentrated side force to its equations (section 5 of Sharp 1971's derivation).

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> B_w = side_force_input(load_parameters("sharp1971", "sharp"), height=0.9)
    >>> B_w.shape
    (8,)
    """
    for name, value in (("height", height), ("ahead", ahead)):
        if not (math.isfinite(value) and abs(value) <= 10.0):
            raise MotosimError(f"{name} = {value!r}; expected a finite lever within 10 m")
    F = np.zeros(8)
    F[0], F[1], F[2] = 1.0, ahead, height
    return np.asarray(np.linalg.solve(mass_matrix(p), F), dtype=np.float64)


def lpv_matrices(p: SharpParameters) -> tuple[Array, Array, Array]:
    """A0, A1 and B_v of the lateral model, A_v(u) = A0 + u A1 = -M^-1 (E0 + u E1).

    The speed-scheduled (LPV) form used by the compiled steps, where the speed changes in
    time; :func:`linearize` gives the model at one speed.
    """
    M = mass_matrix(p)
    E0, E1 = stiffness_matrices(p)
    Minv = np.linalg.inv(M)
    return -Minv @ E0, -Minv @ E1, Minv @ input_matrix(p)


def held_steering(
    A: Array, B: Array, inertia: float, damping: float, stiffness: float, G: Array | None = None
) -> tuple[Array, Array, Array | None]:
    """The lateral model with a rider's arms on the handlebar: (A_h, B_h, G_h).

    The arms add -J_a delta'' - c_a delta' - k_a delta to the rider's steer torque tau.
    The steer acceleration delta'' = A[delta'] x + B[delta'] tau + G[delta'] w depends on
    that torque itself, so the torque is eliminated: with s = 1 / (1 + J_a B[delta']),
    A_h = A + s B (-J_a A[delta'] - c_a e_delta' - k_a e_delta), B_h = s B and, for other
    inputs w (e.g. a side force) of matrix G, G_h = G - s J_a B G[delta']. This is adding
    J_a, c_a and k_a to the steer equation's inertia, damping and stiffness (by the
    Sherman-Morrison formula on M^-1), as a rider's hands on a real front frame do
    (Cossalter, Doria, Lot & Massaro, Meccanica 46, 2011, 279-292).

    Parameters
    ----------
    A : ndarray, shape (8, 8)
        A_v [1/s].
    B : ndarray, shape (8,)
        B_v, the steer-torque input.
    inertia, damping, stiffness : float
        J_a [kg*m^2], c_a [N*m*s/rad], k_a [N*m/rad] about the steering axis.
    G : ndarray, shape (8,) or (8, m), optional
        Other inputs' matrix.
    """
    rate, angle = STATE_NAMES.index("delta_dot"), STATE_NAMES.index("delta")
    s = 1.0 / (1.0 + inertia * B[rate])
    row = -inertia * A[rate]
    row[rate] -= damping
    row[angle] -= stiffness
    held_G = None if G is None else G - s * inertia * np.multiply.outer(B, G[rate])
    return A + s * np.outer(B, row), s * B, held_G


def linearize(p: SharpParameters, speed: float) -> StateSpace:
    """The lateral model at a constant forward speed.

    Parameters
    ----------
    p : SharpParameters
        The motorcycle.
    speed : float
        Forward speed v_x [m/s], at least :data:`MIN_SPEED`.

    Returns
    -------
    StateSpace
        A_v = -M^-1 E(v_x), B_v = M^-1 F (input ``tau_r`` [N*m]), every state as output.

    Raises
    ------
    MotosimError
        If the speed is out of range.

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> lin = linearize(load_parameters("sharp1971", "sharp"), 20.0)
    >>> lin.state_names[:3], lin.A.shape
    (('v_y', 'psi_dot', 'phi_dot'), (8, 8))
    """
    u = check_speed(speed)
    A0, A1, Bv = lpv_matrices(p)
    return StateSpace(
        A=A0 + u * A1,
        B=Bv[:, None],
        C=np.eye(8),
        D=np.zeros((8, 1)),
        state_names=STATE_NAMES,
        input_names=("tau_r",),
        output_names=STATE_NAMES,
    )


def _speeds_array(speeds: ArrayLike) -> Array:
    arr = np.atleast_1d(np.asarray(speeds, dtype=float))
    if arr.ndim != 1 or arr.size == 0:
        raise MotosimError(f"speeds have shape {arr.shape}; expected a non-empty 1-D list")
    for s in arr:
        check_speed(s)
    return arr


def eigenvalues(p: SharpParameters, speeds: ArrayLike) -> NDArray[np.complex128]:
    """Eigenvalues of A_v at each speed, shape (n_speeds, 8), each row sorted by real part.

    Parameters
    ----------
    p : SharpParameters
        The motorcycle.
    speeds : array_like
        Forward speeds [m/s].

    Returns
    -------
    ndarray of complex
        Eigenvalues [1/s]; real part is the growth rate, imaginary part the frequency [rad/s].
    """
    v = _speeds_array(speeds)
    M = mass_matrix(p)
    E0, E1 = stiffness_matrices(p)
    out = np.empty((v.size, 8), dtype=complex)
    for i, u in enumerate(v):
        ev = np.linalg.eigvals(-np.linalg.solve(M, E0 + u * E1))
        out[i] = ev[np.lexsort((ev.imag, ev.real))]
    return out


@dataclass(frozen=True, slots=True)
class ModeTable:
    """Capsize, weave and wobble followed over speed.

    Attributes
    ----------
    speeds : ndarray, shape (n,)
        Forward speeds [m/s].
    eigenvalues : ndarray of complex, shape (n, m)
        All eigenvalues at each speed [1/s] (m = 8 for Sharp's model and the multibody
        model's lateral dynamics), sorted by real part.
    capsize, weave, wobble : ndarray of complex, shape (n,)
        The eigenvalue of each mode; for oscillatory modes the one with positive imaginary part.
    """

    speeds: Array
    eigenvalues: NDArray[np.complex128]
    capsize: NDArray[np.complex128]
    weave: NDArray[np.complex128]
    wobble: NDArray[np.complex128]

    def mode(self, name: str) -> NDArray[np.complex128]:
        """The eigenvalues of the named mode (``capsize``, ``weave`` or ``wobble``)."""
        if name not in MODE_NAMES:
            raise MotosimError(f"mode {name!r}; expected one of {', '.join(MODE_NAMES)}")
        values: NDArray[np.complex128] = getattr(self, name)
        return values

    @staticmethod
    def frequency_hz(values: NDArray[np.complex128]) -> Array:
        """Damped frequency |Im| / 2 pi [Hz]."""
        return np.abs(values.imag) / (2 * np.pi)

    @staticmethod
    def damping_ratio(values: NDArray[np.complex128]) -> Array:
        """Damping ratio -Re / |lambda| (negative when unstable; +/-1 for a real eigenvalue)."""
        mag = np.abs(values)
        return np.divide(-values.real, mag, out=np.zeros_like(mag), where=mag > 0)


_TRACK_STEP = 0.25  # m/s, internal speed step for following the modes
_REFERENCE_SPEED = 20.0  # m/s, where the three modes are unambiguous for road motorcycles


def _classify(ev: NDArray[np.complex128], speed: float) -> dict[str, list[int]]:
    """Indices of capsize, weave and wobble among the eigenvalues at the reference speed.

    Wobble is the oscillatory pair of highest frequency, weave the other oscillatory pair, and
    capsize the real eigenvalue closest to zero.
    """
    osc = [i for i in range(ev.size) if ev[i].imag > 1e-9]
    real = [i for i in range(ev.size) if abs(ev[i].imag) <= 1e-9]
    if len(osc) < 2 or not real:
        raise MotosimError(
            "cannot identify capsize, weave and wobble: expected two oscillatory modes and a "
            f"real one at {speed:g} m/s, found eigenvalues {np.round(ev, 3).tolist()}"
        )
    osc.sort(key=lambda i: ev[i].imag)
    conj = {i: int(np.argmin(np.abs(ev - np.conj(ev[i])))) for i in osc}
    weave, wobble = osc[-2], osc[-1]
    capsize = min(real, key=lambda i: abs(ev[i].real))
    return {"capsize": [capsize], "weave": [weave, conj[weave]], "wobble": [wobble, conj[wobble]]}


def _follow(path: NDArray[np.complex128]) -> NDArray[np.complex128]:
    """Reorder each row of eigenvalues so that column c is one continuous branch."""
    from scipy.optimize import linear_sum_assignment  # only here: a run does not need it

    out = path.copy()
    for i in range(1, len(out)):
        cost = np.abs(out[i - 1][:, None] - out[i][None, :])
        _, cols = linear_sum_assignment(cost)
        out[i] = out[i][cols]
    return out


def track_modes(
    speeds: ArrayLike,
    spectrum: Callable[[Array], NDArray[np.complex128]],
    *,
    reference_speed: float = _REFERENCE_SPEED,
) -> ModeTable:
    """Classify capsize, weave and wobble of any lateral spectrum, following them over speed.

    The modes are named at ``reference_speed``, where they are distinct (wobble the
    oscillatory pair of highest frequency, weave the next one, capsize the real eigenvalue
    nearest zero), and followed eigenvalue by eigenvalue along a fine internal grid
    (0.25 m/s) down and up to the requested speeds, so a mode keeps its name where two modes
    come close in frequency or a pair splits into two real eigenvalues. Nothing here depends
    on the model: Sharp's (:func:`modes`) and the multibody model's
    (:func:`motosim.model.tyred.lateral_modes`) spectra are classified alike.

    Parameters
    ----------
    speeds : array_like
        Forward speeds [m/s], within [:data:`MIN_SPEED`, :data:`MAX_SPEED`], in any order.
    spectrum : callable
        ``spectrum(speeds)`` returns the eigenvalues [1/s] at the given speeds [m/s], shape
        (n_speeds, n) with the same n >= 3 at every speed (e.g. the eigenvalues of a lateral
        state matrix).
    reference_speed : float, optional
        Where the modes are named [m/s] (default 20 m/s, where the three are distinct for
        road motorcycles).

    Returns
    -------
    ModeTable
        ``eigenvalues`` holds each row sorted by real part, then imaginary part.

    Raises
    ------
    MotosimError
        If a speed is out of range, the spectrum has the wrong shape or is not finite, or the
        modes cannot be identified at the reference speed.

    Examples
    --------
    >>> def spectrum(v):  # a capsize, a weave and a wobble whose frequency rises with speed
    ...     v = np.asarray(v)[:, None]
    ...     wobble = -3 + 40j + 0 * v
    ...     return np.hstack([0.01 * v + 0j, -1 + 1.5j * v, -1 - 1.5j * v, wobble, wobble.conj()])
    >>> table = track_modes([5.0, 30.0], spectrum)  # the weave passes the wobble at 26.7 m/s
    >>> table.weave.tolist(), table.wobble.tolist()
    ([(-1+7.5j), (-1+45j)], [(-3+40j), (-3+40j)])
    """
    v = _speeds_array(speeds)
    check_speed(reference_speed)

    def eigenvalues_at(at: ArrayLike) -> NDArray[np.complex128]:
        grid = _speeds_array(at)
        ev = np.asarray(spectrum(grid), dtype=complex)
        if ev.ndim != 2 or ev.shape[0] != grid.size or ev.shape[1] < 3:
            raise MotosimError(
                f"mode spectrum has shape {ev.shape} at {grid.size} speeds; expected "
                f"({grid.size}, n) with n >= 3 eigenvalues at each speed"
            )
        if not np.all(np.isfinite(ev)):
            raise MotosimError("mode spectrum is not finite; expected finite eigenvalues")
        order = np.lexsort((ev.imag, ev.real), axis=1)
        return np.take_along_axis(ev, order, axis=1)

    lo, hi = min(v.min(), reference_speed), max(v.max(), reference_speed)
    down = np.append(np.arange(reference_speed, lo, -_TRACK_STEP), lo)
    up = np.append(np.arange(reference_speed, hi, _TRACK_STEP), hi)
    ref = eigenvalues_at([reference_speed])[0]
    idx = _classify(ref, reference_speed)
    branches_down = _follow(eigenvalues_at(down))
    branches_up = _follow(eigenvalues_at(up))
    grid = np.concatenate([down[::-1], up[1:]])
    branches = np.concatenate([branches_down[::-1], branches_up[1:]])
    order = np.argsort(grid, kind="stable")
    grid, branches = grid[order], branches[order]

    def pick(name: str, row: NDArray[np.complex128]) -> complex:
        vals = row[idx[name]]
        return complex(vals[np.argmax(vals.imag + 1e-12 * vals.real)])

    exact = eigenvalues_at(v)
    chosen = {name: np.empty(v.size, dtype=complex) for name in MODE_NAMES}
    for n, s in enumerate(v):
        row = branches[int(np.argmin(np.abs(grid - s)))]
        for name in MODE_NAMES:
            # the grid value identifies the branch; report the exact eigenvalue at s
            approx = pick(name, row)
            chosen[name][n] = exact[n][int(np.argmin(np.abs(exact[n] - approx)))]
    return ModeTable(
        speeds=v,
        eigenvalues=exact,
        capsize=chosen["capsize"],
        weave=chosen["weave"],
        wobble=chosen["wobble"],
    )


def modes(
    p: SharpParameters,
    speeds: ArrayLike,
    *,
    spectrum: Callable[[Array], NDArray[np.complex128]] | None = None,
) -> ModeTable:
    """Capsize, weave and wobble of Sharp's model at each speed, followed continuously.

    :func:`track_modes` of the :func:`eigenvalues` of Sharp's lateral model.

    Parameters
    ----------
    p : SharpParameters
        The motorcycle.
    speeds : array_like
        Forward speeds [m/s], at least :data:`MIN_SPEED`, in any order.
    spectrum : callable, optional
        Another spectrum of the same machine to classify instead (e.g. the multibody model's):
        the eigenvalues at given speeds, shape (n_speeds, n).

    Returns
    -------
    ModeTable

    Raises
    ------
    MotosimError
        If a speed is out of range or the modes cannot be identified.

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> table = modes(load_parameters("sharp1971", "sharp"), [3.048])
    >>> bool(table.weave[0].real > 0)    # weave unstable at 10 ft/s (Sharp 1971, Table 1)
    True
    """
    if spectrum is None:
        return track_modes(speeds, lambda at: eigenvalues(p, at))
    return track_modes(speeds, spectrum)


def longitudinal_acceleration(
    p: SharpParameters,
    *,
    v_y: float,
    psi_dot: float,
    drive_torque: float,
    brake_torque: float,
    wind_force: float,
) -> float:
    """Forward acceleration of eq. (2) in its dimensionally consistent form [m/s^2].

    (m + J_R / r_D^2) v_x' = (tau_d - tau_b) / r_D + m psi_dot v_y + F_wx

    Parameters
    ----------
    p : SharpParameters
        The motorcycle; m = m_f + m_r, J_R = i_fy + i_Ry, r_D = R_r.
    v_y, psi_dot : float
        Lateral velocity [m/s] and yaw rate [rad/s] of the lateral model.
    drive_torque, brake_torque : float
        tau_d, tau_b [N*m] at the wheels; the brake torque opposes forward motion.
    wind_force : float
        F_wx [N], positive forward.

    Notes
    -----
    The printed eq. (2) multiplies by the inverse of m_e and only the torque term; the form
    above is the one whose terms are all forces (force balance along the body x axis, with
    the wheels' spin inertia J_R reflected to the contact, a_x = v_x' - psi_dot v_y).
    """
    d = derived_geometry(p)
    force = (drive_torque - brake_torque) / d["r_D"] + d["m"] * psi_dot * v_y + wind_force
    return force / d["m_eq"]


class MotorcycleState(IntEnum):
    """Positions in the state of the coupled Sharp + eq. (2) model (:func:`bike_rk4`):
    Sharp 1971's eight lateral states, then eq. (2)'s speed and the ground track (the names
    of :mod:`motosim.signals`)."""

    v_y = 0
    psi_dot = 1
    phi_dot = 2
    delta_dot = 3
    phi = 4
    delta = 5
    F_yr = 6
    F_yf = 7
    v_x = 8
    psi = 9
    x = 10
    y = 11


_LATERAL = int(MotorcycleState.v_x)
"""The lateral states come first, up to the speed."""
_STATES = len(MotorcycleState)


class RK4Work(NamedTuple):
    """Scratch space of :func:`bike_rk4` (:func:`rk4_work`): the four stage rates, the stage
    state, each of shape (12,), and the lateral matrix A_v of the step, (8, 8)."""

    k1: NDArray[np.float64]
    k2: NDArray[np.float64]
    k3: NDArray[np.float64]
    k4: NDArray[np.float64]
    tmp: NDArray[np.float64]
    A: NDArray[np.float64]


@njit(cache=True)
def rk4_work() -> RK4Work:
    """A new :class:`RK4Work`, zeroed."""
    n = _STATES
    lateral = np.zeros((_LATERAL, _LATERAL))
    return RK4Work(np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), lateral)


@njit(cache=True)
def _bike_rates(
    z: Array,
    out: Array,
    A: Array,
    Bv: Array,
    tau: float,
    Bw: Array,
    side: float,
    force: float,
    m: float,
    m_eq: float,
    v_min: float,
    cos_psi: float,
    sin_psi: float,
) -> None:
    v_x, v_y, psi_dot = z[MotorcycleState.v_x], z[MotorcycleState.v_y], z[MotorcycleState.psi_dot]
    for r in range(_LATERAL):
        acc = Bv[r] * tau + Bw[r] * side
        for c in range(_LATERAL):
            acc += A[r, c] * z[c]
        out[r] = acc
    dv = (force + m * psi_dot * v_y) / m_eq
    out[MotorcycleState.v_x] = 0.0 if (v_x <= v_min and dv < 0.0) else dv
    out[MotorcycleState.psi] = psi_dot
    out[MotorcycleState.x] = v_x * cos_psi - v_y * sin_psi
    out[MotorcycleState.y] = v_x * sin_psi + v_y * cos_psi


_SERIES_TURN = 0.01
"""Largest turn [rad] :func:`_turned` takes by its series; the first term it omits, d^8 / 8!,
is then below 3e-21, far under the rounding of a double."""


@njit(cache=True)
def _turned(psi: float, cos_psi: float, sin_psi: float, d: float) -> tuple[float, float]:
    """cos(psi + d) and sin(psi + d) for the yaw ``psi`` [rad] turned by ``d`` [rad] in one RK4
    stage: from cos(psi) and sin(psi) by the angle-addition formulas, with cos(d) and sin(d)
    from their Taylor series (to d^6 and d^7) when |d| <= :data:`_SERIES_TURN`; by
    ``math.cos`` and ``math.sin`` beyond."""
    if abs(d) > _SERIES_TURN:
        return math.cos(psi + d), math.sin(psi + d)
    d2 = d * d
    cos_d = 1.0 - d2 * (1.0 / 2.0 - d2 * (1.0 / 24.0 - d2 / 720.0))
    sin_d = d * (1.0 - d2 * (1.0 / 6.0 - d2 * (1.0 / 120.0 - d2 / 5040.0)))
    return cos_psi * cos_d - sin_psi * sin_d, sin_psi * cos_d + cos_psi * sin_d


@njit(cache=True)
def bike_rk4(
    z: Array,
    work: RK4Work,
    A0: Array,
    A1: Array,
    Bv: Array,
    tau: float,
    Bw: Array,
    side: float,
    force: float,
    m: float,
    m_eq: float,
    v_min: float,
    h: float,
) -> None:
    """One RK4 step of the coupled Sharp + eq. (2) model, in place, without allocation.

    ``z`` is the state (:class:`MotorcycleState`); ``work`` the scratch space (:func:`rk4_work`),
    whose ``A`` is the lateral matrix A_v = A0 + v_x A1 frozen at the start of the step (the
    speed changes by a few mm/s over a millisecond); ``tau`` is the steer torque [N*m],
    ``side`` a side force F_wy [N] entering through ``Bw`` (:func:`side_force_input`) and
    ``force`` = (tau_d - tau_b) / r_D + F_wx [N], all held over ``h`` [s].
    """
    k1, k2, k3, k4, tmp, A = work
    v = z[MotorcycleState.v_x]
    for r in range(_LATERAL):
        for c in range(_LATERAL):
            A[r, c] = A0[r, c] + v * A1[r, c]
    psi = z[MotorcycleState.psi]
    cos_psi, sin_psi = math.cos(psi), math.sin(psi)
    n = z.size
    _bike_rates(z, k1, A, Bv, tau, Bw, side, force, m, m_eq, v_min, cos_psi, sin_psi)
    for i in range(n):
        tmp[i] = z[i] + 0.5 * h * k1[i]
    cos_k, sin_k = _turned(psi, cos_psi, sin_psi, tmp[MotorcycleState.psi] - psi)
    _bike_rates(tmp, k2, A, Bv, tau, Bw, side, force, m, m_eq, v_min, cos_k, sin_k)
    for i in range(n):
        tmp[i] = z[i] + 0.5 * h * k2[i]
    cos_k, sin_k = _turned(psi, cos_psi, sin_psi, tmp[MotorcycleState.psi] - psi)
    _bike_rates(tmp, k3, A, Bv, tau, Bw, side, force, m, m_eq, v_min, cos_k, sin_k)
    for i in range(n):
        tmp[i] = z[i] + h * k3[i]
    cos_k, sin_k = _turned(psi, cos_psi, sin_psi, tmp[MotorcycleState.psi] - psi)
    _bike_rates(tmp, k4, A, Bv, tau, Bw, side, force, m, m_eq, v_min, cos_k, sin_k)
    for i in range(n):
        z[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    if z[MotorcycleState.v_x] < v_min:
        z[MotorcycleState.v_x] = v_min


@njit(cache=True)
def _run_coupled(
    dts: NDArray[np.float64],
    z0: NDArray[np.float64],
    A0: NDArray[np.float64],
    A1: NDArray[np.float64],
    Bv: NDArray[np.float64],
    tau_r: NDArray[np.float64],
    Bw: NDArray[np.float64],
    side: NDArray[np.float64],
    force: NDArray[np.float64],
    m: float,
    m_eq: float,
    v_min: float,
    max_step: float,
) -> NDArray[np.float64]:
    n = tau_r.size
    out = np.empty((n, _STATES))
    z = z0.copy()
    work = rk4_work()
    out[0] = z
    for k in range(n - 1):
        n_sub = max(1, int(math.ceil(dts[k] / max_step - 1e-9)))  # noqa: RUF046 - numba typing
        h = dts[k] / n_sub
        for _ in range(n_sub):
            bike_rk4(z, work, A0, A1, Bv, tau_r[k], Bw, side[k], force[k], m, m_eq, v_min, h)
        out[k + 1] = z
    return out


MotorcycleResponse = TimeSeries
"""Result of :func:`simulate`: the 8 lateral states, ``v_x``, ``psi``, ``x`` and ``y``."""


def simulate(
    p: SharpParameters,
    t: ArrayLike,
    *,
    initial_speed: float,
    rider_torque: ArrayLike = 0.0,
    drive_torque: ArrayLike = 0.0,
    brake_torque: ArrayLike = 0.0,
    wind_force: ArrayLike = 0.0,
    side_force: ArrayLike = 0.0,
    side_force_height: float = 1.0,
    initial_state: ArrayLike | None = None,
    max_step: float = 1e-3,
) -> TimeSeries:
    """Simulate the lateral model with the speed of eq. (2) changing in time.

    The lateral matrices follow the speed (A_v = A0 + v_x A1, taken at the start of each RK4
    step: the speed changes by millimetres per second over a step), the longitudinal equation
    is integrated alongside, and the yaw angle and ground position of
    the rear-frame ground point are integrated for the path.

    Parameters
    ----------
    p : SharpParameters
        The motorcycle.
    t : array_like, shape (n,)
        Strictly increasing sample times [s]; inputs are held between samples.
    initial_speed : float
        v_x at t[0] [m/s], at least :data:`MIN_SPEED`.
    rider_torque, drive_torque, brake_torque, wind_force : array_like, shape (n,) or scalar
        tau_r [N*m], tau_d [N*m], tau_b >= 0 [N*m] and F_wx [N].
    side_force : array_like, shape (n,) or scalar
        F_wy, a side force to the right (a side wind) [N], applied at ``side_force_height``
        [m] above the ground below the rear frame's mass centre (:func:`side_force_input`).
    initial_state : array_like, shape (8,), optional
        Lateral state at t[0] in the order of :data:`STATE_NAMES`; zero (upright) by default.
    max_step : float
        Largest RK4 step [s]; the default 1 ms is stable up to well above 100 m/s (the fastest
        tyre lag is about -4 v_x 1/s).

    Returns
    -------
    TimeSeries
        Columns ``v_y ... F_yf`` (the lateral states), ``v_x``, ``psi``, ``x``, ``y``.

    Raises
    ------
    MotosimError
        On a speed below :data:`MIN_SPEED`, a negative brake torque, non-finite inputs or
        inconsistent shapes.

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> p = load_parameters("sharp1971", "sharp")
    >>> r = simulate(p, np.linspace(0, 1, 11), initial_speed=20.0, drive_torque=200.0)
    >>> bool(r["v_x"][-1] > 20.0)
    True
    """
    tt = sample_times(t)
    u0 = check_speed(initial_speed)
    if not (math.isfinite(max_step) and max_step > 0):
        raise MotosimError(f"max_step = {max_step!r}; expected > 0 [s]")
    n = tt.size
    series = {
        name: input_series(name, values, n)
        for name, values in (
            ("rider_torque", rider_torque),
            ("drive_torque", drive_torque),
            ("brake_torque", brake_torque),
            ("wind_force", wind_force),
            ("side_force", side_force),
        )
    }
    if np.any(series["brake_torque"] < 0):
        raise MotosimError("brake_torque has a negative sample; expected >= 0 N*m")
    x0 = np.zeros(8) if initial_state is None else np.asarray(initial_state, dtype=float)
    if x0.shape != (8,) or not np.all(np.isfinite(x0)):
        raise MotosimError(f"initial_state has shape {x0.shape}; expected 8 finite values")
    d = derived_geometry(p)
    A0, A1, Bv = lpv_matrices(p)
    force = (series["drive_torque"] - series["brake_torque"]) / d["r_D"] + series["wind_force"]
    z0 = np.concatenate([x0, [u0, 0.0, 0.0, 0.0]])
    out = _run_coupled(
        np.diff(tt),
        z0,
        A0,
        A1,
        Bv,
        series["rider_torque"],
        side_force_input(p, height=side_force_height),
        series["side_force"],
        force,
        d["m"],
        d["m_eq"],
        MIN_SPEED,
        max_step,
    )
    return TimeSeries(tt, out, (*STATE_NAMES, "v_x", "psi", "x", "y"))
