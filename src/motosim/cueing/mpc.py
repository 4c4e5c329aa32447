"""Model-predictive cueing on the vestibular states, solved with OSQP.

Each platform axis is planned on its own as a linear MPC. The prediction model is the
commanded axis as a double integrator (input: angular acceleration ``u``), the actuator's
first-order position loop at its bandwidth ``w_b`` (achieved angle ``y' = w_b (x - y)``, the
platform twin of :func:`motosim.cueing.limits.actuator_response`, so the plan is judged on
the motion the rider gets, as :func:`motosim.cueing.pipeline.cue` scores it), the
semicircular-canal model driven by the achieved rate and, for roll and pitch, the otolith
model with the specific force the tilt and the head's offset give (linearised: ``f_y = -g y
- z_h y''`` for roll, ``f_x = g y + z_h y''`` for pitch, ``z_h`` the head's z in the platform
frame, negative above the centre of rotation). The vestibular models are those of
:mod:`motosim.cueing.vestibular`.

Over ``N`` steps of ``h`` (the input held over each) the plan minimises::

    sum_k w_c ((canal_k - r_c) / thr_c)^2 + w_o ((otolith_k - r_o) / thr_o)^2
          + w_a ((angle_k - a_ref) / X)^2 + w_v (rate_k / V)^2 + w_u (u_k / A)^2

          + w_f sum_k ((s_k / thr_c)^2 + s_k / thr_c) + w_F sum_k S_k / thr_o

(for roll, the canal term is the Huber function of the error in thresholds, Huber, *Ann.
Math. Statist.* 35(1), 1964: ``e^2`` up to the tuning's corner ``c`` = ``roll_canal_corner``,
``2 c |e| - c^2`` beyond, so that a roll rate the platform cannot render, a swerve's 67 deg/s
against its 30, costs linearly and does not buy false lateral cues; in the QP, ``w_c (a_k^2
+ 2 c b_k)`` with ``|e_k| <= a_k + b_k``, ``b_k >= 0``, two variables per step, the standard
epigraph form, exact at the optimum) subject to ``|angle_k| <= X``, ``|rate_k| <= V`` (for
pitch, the smaller of ``V`` and the tuning's ``pitch_rate``, the tilt's rate below the pitch
threshold), ``|u_k| <= A``, and the
false-cue constraints ``L_k - s_k <= y_k <= U_k + s_k``, ``s_k >= 0``, on two perceived
signals ``y``: the rotation (canal, slack ``s``) over the first ``false_cue_steps`` steps,
and, for roll and pitch, the specific force (otolith, slack ``S``: lateral for roll,
longitudinal for pitch) over the whole horizon (the otolith lags by ``tau_S`` = 0.66 s,
longer than the rotation's band). The platform's perceived value stays within 0.9 of the
threshold unless the motorcycle's predicted perception is above threshold, and then it may
not be perceived the other way (``U_k`` or ``L_k`` is lifted on the motorcycle's side).
This is the score's definition of a false cue (:mod:`motosim.cueing.vestibular`) as a soft
constraint, so the plan trades a false cue against the tracking errors explicitly rather
than through their squares only. A force's slack costs ``w_F S / thr_o`` only
(``force_false_cue_weight``): linear, the convex envelope of a count of false cues, because
a tilt's force is a sustained offset that a squared cost would let dominate every other
term. The force band is what keeps a roll after a gust, or a pitch for the yaw of a leaned
turn, from being felt as a lateral or a longitudinal force.

The pitch onset of the suspension (the dive of a braking motorcycle, a pitch rate of up to
14 deg/s over 0.3 s) is not planned: the caller feeds it through (``onset`` of
:meth:`MpcCueing.step`, the washout's high-passed suspension pitch in
:func:`motosim.cueing.pipeline.cue`), and the plan renders the rest of the head's pitch rate
with a tilt below the threshold. The fed-through onset's perceived rotation, predicted from
its canal state, shifts the rotation band, so the plan trims an onset that would be
perceived beyond what the rest of the motion calls for.

The weights of the otolith and angle terms are per axis (the
tuning's ``otolith_weight`` and ``angle_weight`` for roll and yaw, ``surge_weight`` and
``pitch_angle_weight`` for pitch, whose tilt follows the perceived longitudinal force rather
than the washout's tilt). ``r_c`` and ``r_o`` are the vehicle's perceived
rate and specific force predicted by the same vestibular models from their present state,
each input predicted as a held part plus a part fading as ``exp(-t / prediction_time)``.
The angular velocities and the longitudinal force fade entirely: the future of the ride is
unknown, and holding a lean rate over the horizon would have the plan spread the platform's
travel evenly over it (the least-squares optimum of a held rate against an angle limit),
rolling at ``X / (N h)`` instead of reproducing the onset. The lateral force at the head
is split by its cause (:mod:`motosim.cueing.head`: ``f_y = a_y cos(phi) - g sin(phi) + h
phi_ddot + ...`` with ``h`` the head's height above the roll axis, the ground): the
tangential acceleration ``h phi_ddot`` of a roll onset fades with the roll rate, and the
rest, the turn's imbalance (a gust's side force, a lean that does not match the turn), is
held. ``phi_ddot`` is the backward difference of the roll rate over the loop period; its
noise only moves force between the two parts, whose sum is the present force exactly. A
force held over the whole horizon would have the plan answer every roll onset's transient
with a sustained tilt, and a faded one would have it ignore a gust's sustained force (the
measurements behind these choices are in docs/guide/cueing.md). The vehicle's angular
velocity is turned into the rate each axis must give with the head-frame kinematics of
:mod:`motosim.cueing.head` and the other axes' present state: ``q = theta_dot cos(phi) +
psi_dot sin(phi) cos(theta)`` means a rolled platform that yaws already gives pitch rate,
which the pitch plan does not add again (and likewise for roll and yaw).

With a road preview (:mod:`motosim.cueing.preview`: the roll rate and lateral force at
the head predicted from the road ahead, as a rider sees it), the roll plan's vehicle inputs
are the previewed ones plus their difference from the present ones, fading over
``prediction_time``; of the lateral force, the part that the roll and yaw accelerations
explain (``SWAY_HEIGHT phi_ddot + SWAY_X psi_ddot``) is in that difference and the rest
(a gust's side force) is held. Each step's mean previewed input drives the vestibular
models from rest (``T_canal``, ``T_otolith``), added to the free response, and the force
band's slack costs ``preview_force_false_cue_weight``: the lane change's false lateral cues
come from not knowing when the rider ends a roll (docs/guide/cueing.md), which the road
ahead tells. The force band then also covers what the horizon cannot see: the otolith's
response to a held tilt peaks 1.9 s after it, so the tilt the plan ends with is felt mostly
after the horizon. Three more rows band the lateral force of the terminal tilt held,
:data:`COAST_TIMES` (0.5, 1 and 2 s) after the horizon, against the motorcycle's predicted
perception at the horizon's end (on a straight road ahead, none): without them the plan
ended a lane change's return roll with a counter-tilt past neutral, which quenched the
lingering force of the lean's tilt and was itself felt 0.5 to 0.8 s later
(docs/guide/cueing.md). Without a preview these rows' slack is free (the causal plan is
unchanged: its prediction of the motion after the horizon is too poor to band it).

How heavy that band is depends on the road beyond the horizon. In a transient (a swerve, a
lane change, a slalom) the motorcycle's lean changes side within seconds and a tilt's lateral
force, felt for about 2 s after it, is a false cue to avoid; in one long curve the lean is
held, and the tilt that renders the roll into it is the sustained roll of the washout (Reid &
Nahon 1985), whose force the band would wash out at the cost of the roll rate into and out of
the curve (docs/guide/cueing.md). So on a preview the force rows' slack weight is blended from
``preview_force_false_cue_weight`` to ``sustained_force_false_cue_weight`` by the persistence
of the curve (:func:`motosim.cueing.preview.curve_persistence`: the road's steady-turn lean
one-signed over the horizon and the last coast time, ahead and behind), an input of
:meth:`MpcCueing.step` computed from the road like the preview.

The condensed QP (``N`` variables) has a constant Hessian and constraint matrix; each step
updates its linear term and bounds and warm-starts OSQP (Stellato et al., *OSQP: an operator
splitting solver for quadratic programs*, Math. Prog. Comp. 12, 2020). The first
acceleration is applied over the loop period; the planned angle and its rate
(:attr:`MpcCueing.rates`) go to the limit manager, which follows a planned trajectory
without braking towards each sample. Near a limit the coarse prediction may have no
admissible plan; that step is planned with the acceleration bounds only (the limit manager
keeps the angle and rate limits) and counted in :attr:`MpcCueing.fallbacks`.

``osqp`` is an optional dependency (the ``cueing`` extra), imported when a controller is
built.
"""

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motosim.cueing.head import GRAVITY
from motosim.cueing.platform import CueingConfig
from motosim.cueing.preview import SWAY_HEIGHT, SWAY_X
from motosim.cueing.vestibular import VestibularModel, canal_tf, otolith_tf
from motosim.errors import MotosimError
from motosim.timeseries import TimeSeries

__all__ = [
    "COAST_TIMES",
    "MOTION_INPUTS",
    "AxisPlan",
    "MpcCueing",
    "MpcDesign",
    "apply_mpc",
    "design_mpc",
]

Array = NDArray[np.float64]

MAX_ITER = 50
"""OSQP's iteration budget per step: a warm-started iterate that stops there is still used
(measured on the scenarios of the comparison table: the same wins as with 100, at a p99 step
time 0.6 ms lower)."""
BAND_MARGIN = 0.9
"""The band of the false-cue constraints, as a fraction of the perception threshold."""
MOTION_INPUTS = ("omega_x", "omega_y", "omega_z", "f_x", "f_y")
"""What :meth:`MpcCueing.step` reads, in order."""
COAST_TIMES = (0.5, 1.0, 2.0)
"""Times [s] after the horizon at which the roll plan on a road preview bands the lateral
force of its terminal tilt held (the platform at rest at its last planned angle): the
otolith's response to a held tilt peaks 1.9 s after it (Young & Meiry's model of
:mod:`motosim.cueing.vestibular`: 63 % of the peak at 0.5 s, 89 % at 1 s), so a tilt planned
within the horizon is felt mostly after it."""


@dataclass(frozen=True, slots=True)
class AxisPlan:
    """The condensed QP of one axis and its state propagation at the loop period.

    Attributes
    ----------
    A_loop, B_loop : ndarray
        Augmented model (commanded angle and rate, achieved angle, canal and otolith states)
        at the loop period.
    P : ndarray, shape (N, N)
        QP Hessian.
    F : ndarray, shape (N, nx)
        Linear term per unit initial state.
    G_canal, G_otolith : ndarray, shape (N, n + 2)
        The vehicle's predicted perception at steps 1..N per unit vestibular state and
        present input's held and fading parts.
    W_canal, W_otolith : ndarray, shape (N, N)
        Linear term per unit predicted perception, with the minus sign.
    G_angle : ndarray, shape (N,)
        Linear term per unit angle reference, with the minus sign.
    vehicle_canal, vehicle_otolith : tuple of ndarray
        ``(A, B)`` of the vehicle's canal and otolith models at the loop period.
    A_con : ndarray, shape (3N, N)
        Constraint matrix: inputs, angles, rates.
    H : ndarray, shape (2N, nx)
        Angle and rate predictions per unit initial state.
    band_M, band_E : ndarray
        The perceived rotation, then the perceived specific force, at the banded steps per
        unit input and per unit initial state (the false-cue constraints).
    band_thr, band_quad, band_lin : ndarray
        Their thresholds and the quadratic and linear weights of their slacks.
    band_steps : tuple of ndarray
        The banded prediction steps of the rotation and of the force (roll and pitch); for
        roll, the force's last three rows are the terminal tilt held :data:`COAST_TIMES`
        after the horizon, banded against the prediction at its last step.
    limits : tuple of float
        ``(X, V, A)``.
    head_height : float
        Height [m] of the rider's head above the motorcycle's roll axis (the ground) for the
        roll plan, whose lateral force has a part ``head_height * roll acceleration`` that
        fades; 0 for pitch and yaw.
    T_canal, T_otolith : ndarray, shape (N, N)
        The vehicle's perceived rotation and specific force at steps 1..N per unit input
        held over each step, from rest (the response to a previewed input, roll only).
    band_lin_preview : ndarray
        ``band_lin`` with the force's slack weighted by ``preview_force_false_cue_weight``
        (used on the steps planned with a preview).
    band_lin_sustained : ndarray
        ``band_lin`` with the force's slack weighted by ``sustained_force_false_cue_weight``
        (blended in on a preview by the persistence of the curve ahead).
    huber_M, huber_E : ndarray, shape (n_h, N) and (n_h, nx)
        The perceived rotation at steps 1..N per unit input and per unit initial state, in
        thresholds, where its error's cost is a Huber function (roll with a corner: ``n_h =
        N``; else ``n_h = 0`` and the squared cost is in ``P`` and ``F``).
    huber_weight, huber_corner, huber_thr : float
        Its weight (``canal_weight``), corner [thresholds] (0: none) and threshold [rad/s].
    """

    A_loop: Array
    B_loop: Array
    P: Array
    F: Array
    G_canal: Array
    G_otolith: Array
    W_canal: Array
    W_otolith: Array
    G_angle: Array
    vehicle_canal: tuple[Array, Array]
    vehicle_otolith: tuple[Array, Array]
    A_con: Array
    H: Array
    band_M: Array
    band_E: Array
    band_thr: Array
    band_quad: Array
    band_lin: Array
    band_steps: tuple[NDArray[np.intp], ...]
    limits: tuple[float, float, float]
    head_height: float
    T_canal: Array
    T_otolith: Array
    band_lin_preview: Array
    band_lin_sustained: Array
    huber_M: Array
    huber_E: Array
    huber_weight: float
    huber_corner: float
    huber_thr: float


@dataclass(frozen=True, slots=True)
class MpcDesign:
    """Per-axis plans (roll, pitch, yaw) at one loop period ``dt`` [s]."""

    dt: float
    axes: tuple[AxisPlan, AxisPlan, AxisPlan]


def _ss(num: Array, den: Array) -> tuple[Array, Array, Array]:
    from scipy.signal import tf2ss

    A, B, C, D = tf2ss(num, den)
    if np.any(D):
        raise MotosimError("vestibular model with a direct feedthrough; expected strictly proper")
    return A, B[:, 0], C[0]


def _discrete(A: Array, B: Array, dt: float) -> tuple[Array, Array]:
    from scipy.linalg import expm

    n = A.shape[0]
    M = np.zeros((n + 1, n + 1))
    M[:n, :n] = A
    M[:n, n] = B
    E = expm(M * dt)
    return E[:n, :n], E[:n, n]


def _vehicle_prediction(A: Array, B: Array, C: Array, h: float, N: int, tau: float) -> Array:
    """Outputs at steps 1..N of a model from state x driven by ``w(t) = w_h + w_f exp(-t /
    tau)`` (a held part and a fading part): (N, n + 2) map of ``[x, w_h, w_f]``."""
    from scipy.linalg import expm

    n = A.shape[0]
    M = np.zeros((n + 2, n + 2))
    M[:n, :n] = A
    M[:n, n] = B
    M[:n, n + 1] = B
    M[n + 1, n + 1] = -1.0 / tau
    E = expm(M * h)
    out = np.zeros((N, n + 2))
    power = np.eye(n + 2)
    for k in range(N):
        power = E @ power
        out[k] = C @ power[:n]
    return out


def _forced_response(A: Array, B: Array, C: Array, h: float, N: int) -> Array:
    """Outputs at steps 1..N of a model from rest, the input held over each step: (N, N)."""
    Ad, Bd = _discrete(A, B, h)
    out = np.zeros((N, N))
    x = Bd.copy()
    for lag in range(N):  # step k responds to the input of step k - 1 - lag
        out[np.arange(lag, N), np.arange(N - lag)] = C @ x
        x = Ad @ x
    return out


def _axis(config: CueingConfig, model: VestibularModel, axis: int, dt: float) -> AxisPlan:
    tuning = config.mpc
    limits = config.platform.axes[axis]
    rate = min(limits.rate, tuning.pitch_rate) if axis == 1 else limits.rate
    z_h = config.platform.head[2]
    Ac, Bc, Cc = _ss(*canal_tf(model))
    with_otolith = axis < 2
    Ao, Bo, Co = _ss(*otolith_tf(model))
    nc, no = Ac.shape[0], Ao.shape[0] if with_otolith else 0
    nx = 3 + nc + no
    wb = limits.bandwidth
    A = np.zeros((nx, nx))
    B = np.zeros(nx)
    A[0, 1] = 1.0  # commanded angle and rate: a double integrator
    B[1] = 1.0
    A[2, 0], A[2, 2] = wb, -wb  # achieved angle: the actuator's first-order position loop
    achieved_rate = A[2].copy()
    achieved_accel = wb * np.eye(nx)[1] - wb * achieved_rate
    c0, o0 = 3, 3 + nc
    A[c0:o0, c0:o0] = Ac
    A[c0:o0] += np.outer(Bc, achieved_rate)  # canal driven by the achieved rate
    if with_otolith:
        sign = -1.0 if axis == 0 else 1.0  # f_y = -g phi + ..., f_x = +g theta + ...
        A[o0:, o0:] = Ao
        A[o0:] += np.outer(Bo, sign * (GRAVITY * np.eye(nx)[2] + z_h * achieved_accel))
    C_canal = np.zeros(nx)
    C_canal[c0:o0] = Cc
    C_oto = np.zeros(nx)
    if with_otolith:
        C_oto[o0:] = Co
    N, h = tuning.horizon, tuning.step
    Ad, Bd = _discrete(A, B, h)
    A_loop, B_loop = _discrete(A, B, dt)
    # condensed prediction X_k = Phi_k x0 + sum_j Gamma_kj u_j, k = 1..N
    Phi = np.zeros((N, nx, nx))
    Gam = np.zeros((N, nx, N))
    power = np.eye(nx)
    for k in range(N):
        power = Ad @ power
        Phi[k] = power
        Gam[k, :, k] = Bd
        if k > 0:
            Gam[k, :, :k] = Ad @ Gam[k - 1, :, :k]
    thr_c, thr_o = model.thresholds[axis], model.thresholds[3 if axis == 1 else 4]
    rows = [
        (C_canal, tuning.canal_weight / thr_c**2, 0),
        (C_oto, (tuning.surge_weight if axis == 1 else tuning.otolith_weight) / thr_o**2, 1),
    ]
    e_angle, e_rate = np.eye(nx)[0], np.eye(nx)[1]
    P = np.eye(N) * tuning.accel_weight / limits.accel**2
    F = np.zeros((N, nx))
    G: list[Array] = []
    W: list[Array] = []
    band_M, band_E, band_thr = [], [], []
    Nb = min(N, tuning.false_cue_steps)
    band_quad, band_lin, band_steps = [], [], []
    band_lin_preview, band_lin_sustained = [], []
    # the roll canal error's cost: squared within the corner, linear beyond (Huber)
    huber = axis == 0 and tuning.roll_canal_corner > 0.0
    huber_M, huber_E, huber_w = np.zeros((0, N)), np.zeros((0, nx)), 0.0
    for C, w, ref in rows:
        M = np.einsum("i,kij->kj", C, Gam)  # (N outputs, N inputs)
        E = np.einsum("i,kij->kj", C, Phi)
        if ref == 0 or with_otolith:
            thr = thr_c if ref == 0 else thr_o
            # the otolith's 0.66 s lag: a tilt's force is felt after the rotation's band, so
            # it is banded over the whole horizon
            idx = np.arange(Nb) if ref == 0 else np.arange(N if Nb else 0)
            nk = idx.size
            band_steps.append(idx)
            band_M.append(M[idx])
            band_E.append(E[idx])
            band_thr.append(np.full(nk, thr))
            # rotation: (s / thr)^2 + s / thr; specific force: s / thr only, the convex
            # envelope of a count of false cues (a tilt's sustained force is not squared)
            quad = tuning.false_cue_weight / thr**2 if ref == 0 else 0.0
            lin = (tuning.false_cue_weight if ref == 0 else tuning.force_false_cue_weight) / thr
            band_quad.append(np.full(nk, quad))
            band_lin.append(np.full(nk, lin))
            lin_p = (
                tuning.false_cue_weight if ref == 0 else tuning.preview_force_false_cue_weight
            ) / thr
            band_lin_preview.append(np.full(nk, lin_p))
            lin_s = (
                tuning.false_cue_weight if ref == 0 else tuning.sustained_force_false_cue_weight
            ) / thr
            band_lin_sustained.append(np.full(nk, lin_s))
        Av, Bv, Cv = (Ac, Bc, Cc) if ref == 0 else (Ao, Bo, Co)
        G.append(_vehicle_prediction(Av, Bv, Cv, h, N, tuning.prediction_time))
        if ref == 0 and huber:
            huber_M, huber_E, huber_w = M / thr_c, E / thr_c, tuning.canal_weight
            W.append(np.zeros_like(M.T))
            continue
        P += w * M.T @ M
        F += w * M.T @ E
        W.append(w * M.T)
    if axis == 0:
        # the lateral force of the terminal tilt held, felt after the horizon: banded at
        # COAST_TIMES on a road preview (the slack is free without one), against the
        # motorcycle's predicted perception at the horizon's end
        from scipy.linalg import expm

        rest = np.eye(nx)
        rest[1, 1] = 0.0  # the commanded rate stopped: the platform held at its last angle
        for t_c in COAST_TIMES:
            coast = C_oto @ expm(A * t_c) @ rest
            band_M.append((coast @ Gam[N - 1])[None])
            band_E.append((coast @ Phi[N - 1])[None])
            band_thr.append(np.array([thr_o]))
            band_quad.append(np.zeros(1))
            band_lin.append(np.zeros(1))
            band_lin_preview.append(np.array([tuning.preview_force_false_cue_weight / thr_o]))
            band_lin_sustained.append(np.array([tuning.sustained_force_false_cue_weight / thr_o]))
            band_steps[1] = np.append(band_steps[1], N - 1)
    w_angle = (tuning.pitch_angle_weight if axis == 1 else tuning.angle_weight) / limits.angle**2
    for e, w in ((e_angle, w_angle), (e_rate, tuning.rate_weight / rate**2)):
        M = np.einsum("i,kij->kj", e, Gam)
        E = np.einsum("i,kij->kj", e, Phi)
        P += w * M.T @ M
        F += w * M.T @ E
    M_a = np.einsum("i,kij->kj", e_angle, Gam)
    M_v = np.einsum("i,kij->kj", e_rate, Gam)
    H = np.vstack([np.einsum("i,kij->kj", e_angle, Phi), np.einsum("i,kij->kj", e_rate, Phi)])
    return AxisPlan(
        A_loop=A_loop,
        B_loop=B_loop,
        P=0.5 * (P + P.T),
        F=F,
        G_canal=G[0],
        G_otolith=G[1],
        W_canal=W[0],
        W_otolith=W[1],
        G_angle=w_angle * M_a.T @ np.ones(N),
        vehicle_canal=_discrete(Ac, Bc, dt),
        vehicle_otolith=_discrete(Ao, Bo, dt),
        A_con=np.vstack([np.eye(N), M_a, M_v]),
        H=H,
        band_M=np.vstack(band_M),
        band_E=np.vstack(band_E),
        band_thr=np.concatenate(band_thr),
        band_quad=np.concatenate(band_quad),
        band_lin=np.concatenate(band_lin),
        band_steps=tuple(band_steps),
        limits=(limits.angle, rate, limits.accel),
        head_height=config.rider.height if axis == 0 else 0.0,
        T_canal=_forced_response(Ac, Bc, Cc, h, N),
        T_otolith=_forced_response(Ao, Bo, Co, h, N),
        band_lin_preview=np.concatenate(band_lin_preview),
        band_lin_sustained=np.concatenate(band_lin_sustained),
        huber_M=huber_M,
        huber_E=huber_E,
        huber_weight=huber_w,
        huber_corner=tuning.roll_canal_corner if huber else 0.0,
        huber_thr=thr_c,
    )


def design_mpc(config: CueingConfig, model: VestibularModel, dt: float) -> MpcDesign:
    """Build the three condensed QPs of the module docstring.

    Parameters
    ----------
    config : CueingConfig
        Platform limits, head position and :class:`~motosim.cueing.platform.MpcTuning`.
    model : VestibularModel
        Canal and otolith models and the thresholds that scale the errors.
    dt : float
        Loop period [s]; at most the prediction step.

    Returns
    -------
    MpcDesign
        The plans.

    Raises
    ------
    MotosimError
        If ``dt`` is not positive or exceeds the prediction step.
    """
    if not (math.isfinite(dt) and 0.0 < dt <= config.mpc.step):
        raise MotosimError(
            f"loop period dt = {dt!r} s; expected > 0 and <= the MPC step {config.mpc.step:g} s"
        )
    return MpcDesign(
        dt, (_axis(config, model, 0, dt), _axis(config, model, 1, dt), _axis(config, model, 2, dt))
    )


class MpcCueing:
    """Runtime MPC cueing: one OSQP problem per axis, warm-started step after step.

    Parameters
    ----------
    design : MpcDesign
        From :func:`design_mpc`.

    Raises
    ------
    MotosimError
        If osqp is not installed (``pip install motosim[cueing]``).
    """

    def __init__(self, design: MpcDesign) -> None:
        try:
            import osqp
        except ImportError:
            raise MotosimError(
                "the MPC cueing needs osqp; expected it installed (pip install 'motosim[cueing]')"
            ) from None
        from scipy import sparse

        self.design = design
        self._solvers: list[Any] = []
        self._state = [np.zeros(plan.A_loop.shape[0]) for plan in design.axes]
        self._canal = [np.zeros(plan.vehicle_canal[0].shape[0]) for plan in design.axes]
        self._otolith = [np.zeros(plan.vehicle_otolith[0].shape[0]) for plan in design.axes]
        self._feed = np.zeros(3)
        self._roll_rate = math.nan  # the last step's roll rate, for the roll acceleration
        self._yaw_rate = math.nan  # the last step's yaw rate, for the previewed plan
        self._feed_canal = [np.zeros(plan.vehicle_canal[0].shape[0]) for plan in design.axes]
        self._maps = [self._stack(plan) for plan in design.axes]
        self.fallbacks = 0
        """Steps planned without the angle and rate bounds (no admissible plan)."""
        self.rates = np.zeros(3)
        """Planned roll, pitch and yaw rates [rad/s] of the last step's targets."""
        for plan in design.axes:
            solver = osqp.OSQP()
            n = plan.P.shape[0]
            nb = plan.band_M.shape[0]
            nh = plan.huber_M.shape[0]
            nv = n + nb + 2 * nh
            P = np.zeros((nv, nv))
            P[:n, :n] = plan.P
            P[n : n + nb, n : n + nb] = np.diag(plan.band_quad)
            P[n + nb : n + nb + nh, n + nb : n + nb + nh] = plan.huber_weight * np.eye(nh)
            A_con = np.zeros((3 * n + 3 * nb + 3 * nh, nv))
            A_con[: 3 * n, :n] = plan.A_con
            A_con[3 * n : 3 * n + nb, :n] = plan.band_M  # p - s <= U
            A_con[3 * n : 3 * n + nb, n : n + nb] = -np.eye(nb)
            A_con[3 * n + nb : 3 * n + 2 * nb, :n] = plan.band_M  # p + s >= L
            A_con[3 * n + nb : 3 * n + 2 * nb, n : n + nb] = np.eye(nb)
            A_con[3 * n + 2 * nb : 3 * n + 3 * nb, n : n + nb] = np.eye(nb)  # s >= 0
            if nh:
                # Huber: e - a - b <= 0, e + a + b >= 0, b >= 0 (e the canal error)
                r0, a0, b0 = 3 * n + 3 * nb, n + nb, n + nb + nh
                A_con[r0 : r0 + nh, :n] = plan.huber_M
                A_con[r0 : r0 + nh, a0:b0] = -np.eye(nh)
                A_con[r0 : r0 + nh, b0:] = -np.eye(nh)
                A_con[r0 + nh : r0 + 2 * nh, :n] = plan.huber_M
                A_con[r0 + nh : r0 + 2 * nh, a0:b0] = np.eye(nh)
                A_con[r0 + nh : r0 + 2 * nh, b0:] = np.eye(nh)
                A_con[r0 + 2 * nh :, b0:] = np.eye(nh)
            lo, hi = self._bounds(plan, np.zeros(2 * n), np.zeros(nb), np.zeros(nb))
            lo, hi = self._huber_bounds(plan, lo, hi, np.zeros(nh))
            solver.setup(
                sparse.csc_matrix(np.triu(P)),
                np.zeros(nv),
                sparse.csc_matrix(A_con),
                lo,
                hi,
                verbose=False,
                eps_abs=1e-4,
                eps_rel=1e-4,
                max_iter=MAX_ITER,
                polishing=False,
                warm_starting=True,
            )
            self._solvers.append(solver)
        status = osqp.SolverStatus
        # an iterate of the warm-started ADMM that stopped at its budget is still a usable
        # plan (the limit manager keeps the limits); only an infeasible problem is replanned
        self._usable = {
            status.OSQP_SOLVED,
            status.OSQP_SOLVED_INACCURATE,
            status.OSQP_MAX_ITER_REACHED,
        }
        self._infeasible = {
            status.OSQP_PRIMAL_INFEASIBLE,
            status.OSQP_PRIMAL_INFEASIBLE_INACCURATE,
        }
        # OSQP takes Ctrl-C during a solve for itself and returns this status
        self._interrupted = status.OSQP_SIGINT

    @staticmethod
    def _stack(plan: AxisPlan) -> tuple[Array, Array, int, int]:
        """One matrix from ``v = [x0, xc, w_c, xo, w_o, xf, w_f, ref]`` (plan state, vehicle
        canal and otolith states and inputs, fed-through onset's canal state and rate,
        angle reference; each input as its held and fading parts) to ``[q_u, r_b, pred,
        free]``, and one to the next ``[xc, xo, xf]``."""
        N = plan.P.shape[0]
        nx = plan.A_loop.shape[0]
        nc = plan.vehicle_canal[0].shape[0]
        no = plan.vehicle_otolith[0].shape[0]
        c, o, f, r = nx, nx + nc + 2, nx + nc + no + 4, nx + 2 * nc + no + 6
        rows_c, rows_o = (*plan.band_steps, np.arange(0))[:2]
        nb, nr = plan.band_M.shape[0], rows_c.size
        nh = plan.huber_M.shape[0]
        K = np.zeros((N + nb + 2 * N + nb + nh, r + 1))
        K[:N, :nx] = plan.F
        K[:N, c:o] = -plan.W_canal @ plan.G_canal
        K[:N, o:f] = -plan.W_otolith @ plan.G_otolith
        K[:N, r] = -plan.G_angle
        K[N : N + nr, c:o] = plan.G_canal[rows_c]
        K[N + nr : N + nb, o:f] = plan.G_otolith[rows_o]
        K[N + nb : 3 * N + nb, :nx] = plan.H
        K[3 * N + nb : 3 * N + 2 * nb, :nx] = plan.band_E
        K[3 * N + nb : 3 * N + nb + nr, f:r] = plan.G_canal[rows_c]
        if nh:  # the canal error's free part, in thresholds
            K[3 * N + 2 * nb :, :nx] = plan.huber_E
            K[3 * N + 2 * nb :, c:o] = -plan.G_canal / plan.huber_thr
        (Ac, Bc), (Ao, Bo) = plan.vehicle_canal, plan.vehicle_otolith
        U = np.zeros((2 * nc + no, r + 1))
        U[:nc, c : c + nc], U[:nc, c + nc], U[:nc, c + nc + 1] = Ac, Bc, Bc
        U[nc : nc + no, o : o + no], U[nc : nc + no, o + no], U[nc : nc + no, o + no + 1] = (
            Ao,
            Bo,
            Bo,
        )
        U[nc + no :, f : f + nc], U[nc + no :, f + nc], U[nc + no :, f + nc + 1] = Ac, Bc, Bc
        return K, U, nc, no

    @staticmethod
    def _bounds(plan: AxisPlan, pred: Array, free: Array, felt: Array) -> tuple[Array, Array]:
        X, V, A = plan.limits
        N = plan.P.shape[0]
        thr = BAND_MARGIN * plan.band_thr
        big = np.full(free.size, 1e9)
        band_hi = np.where(felt > 0, big, thr - free)  # not perceived the other way
        band_lo = np.where(felt < 0, -big, -thr - free)
        upper = np.concatenate([np.full(N, A), X - pred[:N], V - pred[N:], band_hi, big, big])
        lower = np.concatenate(
            [np.full(N, -A), -X - pred[:N], -V - pred[N:], -big, band_lo, np.zeros(free.size)]
        )
        return lower, upper

    @staticmethod
    def _huber_bounds(plan: AxisPlan, lo: Array, hi: Array, free: Array) -> tuple[Array, Array]:
        """``lo``, ``hi`` with the Huber rows' bounds appended (``free``: the canal error's
        part that does not depend on the plan, in thresholds; empty: no rows)."""
        nh = free.size
        if not nh:
            return lo, hi
        big = np.full(nh, 1e9)
        lo = np.concatenate([lo, -big, -free, np.zeros(nh)])
        hi = np.concatenate([hi, -free, big, big])
        return lo, hi

    def reset(self) -> None:
        """Back to neutral rest, vestibular states at zero."""
        for x in (*self._state, *self._canal, *self._otolith, self._feed, *self._feed_canal):
            x[:] = 0.0
        self._roll_rate = math.nan
        self._yaw_rate = math.nan

    def step(
        self,
        motion: Array,
        reference: Array,
        onset: Array | None = None,
        preview: Array | None = None,
        trust: float = 1.0,
        persistence: float = 0.0,
    ) -> Array:
        """One loop step.

        Parameters
        ----------
        motion : ndarray, shape (5,)
            The motorcycle's motion at the rider's head now: ``omega_x``, ``omega_y``,
            ``omega_z`` [rad/s], ``f_x``, ``f_y`` [m/s^2] (predicted to fade over the
            horizon with the tuning's ``prediction_time``).
        reference : ndarray, shape (3,)
            Roll, pitch and yaw angles [rad] the plan is drawn to by the angle weight (the
            washout's commands, or zeros for neutral).
        onset : ndarray, shape (2, 3), optional
            Row 0: roll, pitch and yaw angles [rad] fed through to the targets beside the
            plan (the suspension's pitch onset); row 1: the motorcycle's head-frame angular
            velocity [rad/s] they render, which the plan then leaves out of its tracking.
        preview : ndarray, shape (N + 1, 2), optional
            The roll rate [rad/s] and lateral specific force [m/s^2] at the head predicted
            from the road at 0, h, ..., N h ahead (:func:`motosim.cueing.preview.road_preview`);
            the roll plan then follows it (module docstring). None: from the present motion.
        trust : float, optional
            Weight in [0, 1] of the preview (:func:`motosim.cueing.preview.preview_trust`:
            by the lean the road asks for): the previewed motion is scaled by it; at 0
            the plan is the one from the present motion, as without a preview.
        persistence : float, optional
            How sustained the curve ahead is, in [0, 1]
            (:func:`motosim.cueing.preview.curve_persistence`): on a preview the roll plan's
            force band weight is blended from ``preview_force_false_cue_weight`` (0) to
            ``sustained_force_false_cue_weight`` (1) by it.

        Returns
        -------
        ndarray, shape (3,)
            Platform roll, pitch and yaw targets [rad] for the limit manager.
        """
        out = np.empty(3)
        (roll, _), (pitch, pitch_dot), (_, yaw_dot) = (x[:2] for x in self._state)
        # the rate each axis must give so that the head's angular velocity (module
        # docstring of motosim.cueing.head) matches, the other axes' present rates held
        sr, cr, sp, cp = math.sin(roll), math.cos(roll), math.sin(pitch), math.cos(pitch)
        inputs = (
            (motion[0] + yaw_dot * sp, motion[4]),
            ((motion[1] - yaw_dot * sr * cp) / cr, motion[3]),
            ((motion[2] + pitch_dot * sr) / (cr * cp), 0.0),
        )
        for j, plan in enumerate(self.design.axes):
            x0 = self._state[j]
            w_c, w_o = inputs[j]
            feed = 0.0 if onset is None else float(onset[0, j])
            feed_rate = (feed - self._feed[j]) / self.design.dt
            self._feed[j] = feed
            # the vehicle's rotation the fed-through onset renders is not planned for; the
            # band below keeps the onset's perceived rotation with the plan's within it
            if onset is not None:
                w_c -= float(onset[1, j])
            K, U, nc, no = self._maps[j]
            held, fading = 0.0, w_o  # the otolith input's parts (module docstring)
            if j == 0:
                alpha = (w_c - self._roll_rate) / self.design.dt
                self._roll_rate = w_c
                fading = plan.head_height * alpha if math.isfinite(alpha) else 0.0
                held = w_o - fading
            v = np.concatenate(
                [
                    x0,
                    self._canal[j],
                    (0.0, w_c),
                    self._otolith[j],
                    (held, fading),
                    self._feed_canal[j],
                    (0.0, feed_rate),
                    (reference[j] - feed,),
                ]
            )
            N = plan.P.shape[0]
            nb = plan.band_M.shape[0]
            band_lin = plan.band_lin
            if j == 0 and preview is not None and trust > 0.0:
                preview = trust * preview if trust < 1.0 else preview
                # the previewed input plus the difference from the present one, fading; of
                # the lateral force, the part the previewed motion explains fades too, the
                # rest (a gust's side force) is held
                yaw_accel = (motion[2] - self._yaw_rate) / self.design.dt
                dynamic = SWAY_HEIGHT * (alpha if math.isfinite(alpha) else 0.0) + SWAY_X * (
                    yaw_accel if math.isfinite(yaw_accel) else 0.0
                )
                vp = v.copy()
                c_fade, o_held = x0.size + nc + 1, x0.size + nc + no + 2
                vp[c_fade - 1 : c_fade + 1] = 0.0, w_c - preview[0, 0]
                vp[o_held : o_held + 2] = w_o - dynamic, dynamic - preview[0, 1]
                y = K @ vp
                mid = 0.5 * (preview[:-1] + preview[1:])  # each step's mean input
                tc, to = plan.T_canal @ mid[:, 0], plan.T_otolith @ mid[:, 1]
                y[:N] -= plan.W_canal @ tc + plan.W_otolith @ to
                nr = plan.band_steps[0].size
                y[N : N + nr] += tc[plan.band_steps[0]]
                y[N + nr : N + nb] += to[plan.band_steps[1]]
                if plan.huber_M.shape[0]:
                    y[3 * N + 2 * nb :] -= tc / plan.huber_thr
                band_lin = plan.band_lin_preview
                if persistence > 0.0:
                    band_lin = band_lin + persistence * (plan.band_lin_sustained - band_lin)
            else:
                y = K @ v
            r_b = y[N : N + nb]
            felt = np.where(np.abs(r_b) > plan.band_thr, np.sign(r_b), 0.0)
            # the Huber split of the roll canal error (if any): a_k quadratic, b_k linear
            nh = plan.huber_M.shape[0]
            b_cost = np.full(nh, plan.huber_weight * plan.huber_corner)
            q = np.concatenate([y[:N], band_lin, np.zeros(nh), b_cost])
            free = y[3 * N + nb : 3 * N + 2 * nb]
            lo, hi = self._bounds(plan, y[N + nb : 3 * N + nb], free, felt)
            lo, hi = self._huber_bounds(plan, lo, hi, y[3 * N + 2 * nb :])
            nxt = U @ v
            self._canal[j], self._otolith[j] = nxt[:nc], nxt[nc : nc + no]
            self._feed_canal[j] = nxt[nc + no :]
            solver = self._solvers[j]
            solver.update(q=q, l=lo, u=hi)
            result = solver.solve(raise_error=False)
            if result.info.status_val == self._interrupted:  # Ctrl-C, swallowed by OSQP
                raise KeyboardInterrupt
            if result.info.status_val in self._infeasible:
                # the angle and rate bounds of the coarse prediction cannot be met from this
                # state (near a limit): plan with the input bounds only, the limit manager
                # keeps the angle and rate limits
                self.fallbacks += 1
                n = plan.P.shape[0]
                lo[n : 3 * n], hi[n : 3 * n] = -1e9, 1e9
                solver.update(l=lo, u=hi)
                result = solver.solve(raise_error=False)
                if result.info.status_val == self._interrupted:
                    raise KeyboardInterrupt
            if result.info.status_val in self._usable and math.isfinite(result.x[0]):
                u = float(result.x[0])
            else:  # not solved in the iteration budget: brake
                u = -math.copysign(plan.limits[2], x0[1]) if x0[1] else 0.0
            u = min(plan.limits[2], max(-plan.limits[2], u))
            self._state[j] = plan.A_loop @ x0 + plan.B_loop * u
            out[j] = self._state[j][0] + feed
            self.rates[j] = self._state[j][1] + feed_rate
        self._yaw_rate = float(motion[2])
        return out


def apply_mpc(
    design: MpcDesign,
    vehicle: TimeSeries,
    reference: Array,
    onset: Array | None = None,
    preview: Array | None = None,
    trust: Array | None = None,
    persistence: Array | None = None,
) -> tuple[Array, Array]:
    """Run the MPC cueing over a whole series from rest.

    Parameters
    ----------
    design : MpcDesign
        At the series' sample period.
    vehicle : TimeSeries
        The motorcycle's motion at the head with ``omega_x``, ``omega_y``, ``omega_z``,
        ``f_x``, ``f_y`` (:func:`motosim.cueing.head.vehicle_motion`).
    reference : ndarray, shape (n, 3)
        Angle references [rad] (see :meth:`MpcCueing.step`).
    onset : ndarray, shape (n, 2, 3), optional
        The onsets fed through, per sample (see :meth:`MpcCueing.step`).
    preview : ndarray, shape (n, N + 1, 2), optional
        The road preview per sample (see :meth:`MpcCueing.step`).
    trust : ndarray, shape (n,), optional
        The preview's weight per sample (see :meth:`MpcCueing.step`); default 1.
    persistence : ndarray, shape (n,), optional
        The persistence of the curve ahead per sample (see :meth:`MpcCueing.step`);
        default 0.

    Returns
    -------
    targets, rates : ndarray, shape (n, 3)
        Platform roll, pitch, yaw targets [rad] and their planned rates [rad/s].

    Raises
    ------
    MotosimError
        If ``preview`` is not one horizon per sample; if osqp is missing.
    """
    N = design.axes[0].P.shape[0]
    if preview is not None and preview.shape != (vehicle.t.size, N + 1, 2):
        raise MotosimError(
            f"road preview of shape {preview.shape}; expected {(vehicle.t.size, N + 1, 2)}"
        )
    mpc = MpcCueing(design)
    motion = np.column_stack([vehicle[name] for name in MOTION_INPUTS])
    ref = np.asarray(reference, dtype=np.float64)
    targets, rates = np.empty((motion.shape[0], 3)), np.empty((motion.shape[0], 3))
    for k in range(motion.shape[0]):
        targets[k] = mpc.step(
            motion[k],
            ref[k],
            None if onset is None else onset[k],
            None if preview is None else preview[k],
            1.0 if trust is None else float(trust[k]),
            0.0 if persistence is None else float(persistence[k]),
        )
        rates[k] = mpc.rates
    return targets, rates
