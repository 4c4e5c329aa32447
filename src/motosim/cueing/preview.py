"""Road preview: the motorcycle's motion at the head predicted from the road ahead.

A training scenario's road is known in advance, as a rider sees it ahead. From the arc length
``s`` the motorcycle has reached and its present speed ``v``, the lean of a steady turn of the
road's curvature ``kappa`` at the arc length reached ``tau`` seconds ahead is::

    phi_p(tau) = atan(v^2 kappa(s + lead + v tau) / g)

(the roll equilibrium of a steady turn of a thin-tyred motorcycle, e.g. Cossalter,
*Motorcycle Dynamics*, 2nd ed., 2006, on steady turning), with ``lead`` the distance by
which the rider's lean leads the road's curvature under the rear contact point, whose
position the run records (a fitted constant, :data:`LEAD_DISTANCE`). A distance, not a time:
the rear contact's path follows the front wheel's, which the steering turns, a wheelbase
behind (small angles: ``kappa_front = kappa_rear + w d kappa_rear / ds``, a lag in distance),
and the lean, which balances the turn of the mass centre ahead of the rear contact, leads
it likewise. Its derivatives in ``tau`` (central differences of :data:`SMOOTHING`) give
the predicted roll rate at the head ``p = phi_p'`` and lateral specific force ``f_y =
SWAY_HEIGHT phi_p'' + SWAY_X psi_p''`` with ``psi_p' = v kappa``: the head's tangential
accelerations from the roll and the yaw (rigid-body kinematics, :mod:`motosim.cueing.head`),
with lengths fitted on recorded runs (:data:`SWAY_HEIGHT`, :data:`SWAY_X`); in the steady
turn's lean the centripetal acceleration and gravity balance, so no imbalance is predicted.
The MPC (:meth:`motosim.cueing.mpc.MpcCueing.step`) plans the roll axis with this
prediction, the difference between the present measured motion and the preview fading over
its first steps. MPC cueing for a vehicle on a predefined path predicts its references the
same way (the MPMCA of Drop & Olivari, predictivecueing.com); an oracle prediction of the
future reference lowers the cueing's delay and raises its correlation against a constant
one (*SIMULATION*, SAGE, doi:10.1177/0037549718815972).

This module knows a road only as arrays (positions and curvature every ``ds`` metres of arc
length): the scenario's path is built where it is known (:mod:`motosim.sim` and the
``motosim cueing`` command), and passed in. A rider who leaves the road's line (a free ride,
a rider-torque scenario) breaks the preview: there is none.

The preview assumes the rider can ride the road's line. Where the road asks for a lean the
motorcycle does not reach (an obstacle avoidance taken too fast: a 63 deg lean asked at
35 m/s, 18 deg ridden), the rider leaves the line and the preview misleads the plan:
:func:`preview_trust` weighs the preview by the largest steady-turn lean it asks for over the
horizon, fully trusted up to :data:`LEAN_TRUSTED` (above the training runs' leans), not at
all from :data:`LEAN_LIMIT` (a lateral acceleration of 1 g, the grip of a road tyre), linearly
between; the MPC scales the previewed motion by it, and plans from the present motion alone
where it is zero (:meth:`motosim.cueing.mpc.MpcCueing.step`). Fading it by the distance to
the line instead (the rider is off it after the fact) was measured to add false cues
(docs/guide/cueing.md).
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from motosim.cueing.head import GRAVITY
from motosim.errors import MotosimError

__all__ = [
    "LEAD_DISTANCE",
    "LEAN_LIMIT",
    "LEAN_TRUSTED",
    "PERSISTENCE_FLOOR",
    "PREVIEW_SIGNALS",
    "SMOOTHING",
    "SWAY_HEIGHT",
    "SWAY_X",
    "Road",
    "arc_length",
    "curve_persistence",
    "preview_trust",
    "road_preview",
]

Array = NDArray[np.float64]

LEAD_DISTANCE = 1.0
"""Distance [m] by which the rider's lean leads the curvature of the road under the rear
contact point: of 0.6, 0.8, ..., 1.4 m, the least RMS roll-rate error 1 s ahead summed over
the training lane change (20 m/s), slalom (10 m/s), obstacle avoidance (15 m/s) and turn
(30 m/s) of docs/guide/cueing.md, 12.97 deg/s against 13.64 for the constant time lead of
0.1 s it replaces (a time lead's best value fell with the speed: 0.1 s at 10 and 15 m/s,
0.05 s at 20 and 30 m/s). Between the mass centre's 0.59 m ahead of the rear contact and
the wheelbase, 1.41 m (Sharp 1971's standard machine)."""
SMOOTHING = 0.2
"""Half-width [s] of the finite differences that give the lean's rate and acceleration:
they smooth the road's curvature as a rider's lean does (0.02, 0.05, 0.1, 0.2 s measured;
0.2 s gives the least lateral-force error on the lane change and the obstacle avoidance)."""
SWAY_HEIGHT = 0.70
"""Lateral specific force at the head per unit roll acceleration [m]: least squares of the
recorded head force on the roll and yaw accelerations on the lane change at 20 m/s (0.70;
0.71-0.76 on the lane change at 30 m/s, the slalom and the obstacle avoidance). Below the
head's height (1.45 m): the tyres' side force that rolls the motorcycle also pushes the
contact point sideways, so the head moves as if the roll axis were 0.75 m up."""
SWAY_X = 0.90
"""Lateral specific force at the head per unit yaw acceleration [m]: the same fit (0.89-0.91
on the four runs; the head's offset ahead of the rear contact is 1.0 m)."""
LEAN_TRUSTED = math.radians(30.0)
"""Largest steady-turn lean [rad] over the horizon up to which the preview is fully trusted:
above the largest the road asks for on the training runs of docs/guide/cueing.md, 24.7 deg on
the turn at 30 m/s (12.9-22.7 deg on the lane change, slalom and obstacle avoidance; 27.4 deg
ridden on the turn), and on the unseen runs of that page (up to 22.8 deg)."""
LEAN_LIMIT = math.radians(45.0)
"""Steady-turn lean [rad] from which the preview is not trusted: ``tan(phi) = a_y / g = 1``, a
lateral acceleration at a road tyre's grip on dry asphalt (friction coefficient about 1,
Pacejka, *Tire and Vehicle Dynamics*, 3rd ed., 2012): a road the rider cannot follow."""
PERSISTENCE_FLOOR = math.asin(0.17 / GRAVITY)
"""Mean steady-turn lean [rad] below which the road ahead is not a sustained curve for
:func:`curve_persistence`: a platform tilt of that angle gives a lateral specific force of
0.17 m/s^2, the otolith's threshold of the score (:mod:`motosim.cueing.vestibular`), so a
lean below it held as a tilt is not felt and there is no trade-off to schedule (about
1 deg)."""
PREVIEW_SIGNALS = ("omega_x", "f_y")
"""What :func:`road_preview` predicts, in order: roll rate [rad/s] and lateral specific
force [m/s^2] at the head."""


@dataclass(frozen=True, slots=True)
class Road:
    """A road's line sampled every ``ds`` metres of arc length (SAE axes seen from above).

    Attributes
    ----------
    ds : float
        Spacing [m].
    x, y : ndarray, shape (n,)
        Position [m] of the line at ``s = k ds``.
    kappa : ndarray, shape (n,)
        Curvature [1/m] (positive turning right).
    """

    ds: float
    x: Array
    y: Array
    kappa: Array

    def __post_init__(self) -> None:
        if not (math.isfinite(self.ds) and self.ds > 0):
            raise MotosimError(f"road ds = {self.ds!r}; expected a finite spacing > 0 [m]")
        n = self.kappa.size
        if n < 2 or self.x.shape != (n,) or self.y.shape != (n,):
            raise MotosimError(
                f"road of {self.x.size}, {self.y.size}, {n} samples of x, y, kappa; "
                "expected the same number, at least 2"
            )
        if not (
            np.all(np.isfinite(self.x))
            and np.all(np.isfinite(self.y))
            and np.all(np.isfinite(self.kappa))
        ):
            raise MotosimError("road with a non-finite position or curvature; expected finite")


def arc_length(road: Road, x: Array, y: Array) -> Array:
    """Arc length [m] of the road's sample nearest to each position, searched forward.

    Parameters
    ----------
    road : Road
        The road.
    x, y : ndarray, shape (m,)
        The motorcycle's positions [m] in the road's frame, in time order.

    Returns
    -------
    ndarray, shape (m,)
        The arc length reached at each position.
    """
    out = np.empty(x.size)
    k = 0
    n = road.x.size
    window = 400  # samples searched ahead of the last match (20 m at 0.05 m)
    for i in range(x.size):
        lo, hi = max(k - 20, 0), min(k + window, n)
        d = (road.x[lo:hi] - x[i]) ** 2 + (road.y[lo:hi] - y[i]) ** 2
        k = lo + int(np.argmin(d))
        out[i] = k * road.ds
    return out


def _steady_lean(road: Road, at: Array, speed: Array) -> tuple[Array, Array]:
    """The lean ``atan(v^2 kappa / g)`` [rad] of the steady turn of the road's curvature
    ``kappa`` [1/m] at arc lengths ``at`` [m], at ``speed`` [m/s] (broadcast), and ``kappa``."""
    kappa = np.interp(at, road.ds * np.arange(road.kappa.size), road.kappa)
    return np.arctan(speed**2 * kappa / GRAVITY), kappa


def _window_leans(
    road: Road, arc: Array, speed: Array, lead: float, behind: float, ahead: float
) -> Array:
    """The steady-turn leans [rad] of the road from ``s + lead - v behind`` to ``s + lead + v
    ahead`` (``behind``, ``ahead`` [s]), every 0.25 m or the road's spacing if coarser: one
    row per sample of ``arc`` [m] and ``speed`` [m/s]."""
    v = speed[:, None]
    reach = float(np.max(speed, initial=0.0)) * (behind + ahead)
    steps = np.linspace(-behind, ahead, max(2, math.ceil(reach / max(road.ds, 0.25)) + 1))
    phi, _ = _steady_lean(road, arc[:, None] + lead + v * steps[None, :], v)
    return phi


def _check_samples(what: str, arc: Array, speed: Array) -> None:
    """As many speeds as arc lengths, or a one-line error naming ``what`` needs them."""
    if arc.shape != speed.shape:
        raise MotosimError(
            f"{what} of {arc.size} arc lengths and {speed.size} speeds; expected as many"
        )


def preview_trust(
    road: Road,
    arc: Array,
    speed: Array,
    *,
    ahead: float,
    lead: float = LEAD_DISTANCE,
    trusted: float = LEAN_TRUSTED,
    limit: float = LEAN_LIMIT,
) -> Array:
    """How far the road preview is trusted at each sample, by the lean the road asks for.

    Parameters
    ----------
    road : Road
        The road.
    arc : ndarray, shape (m,)
        Arc length [m] reached at each sample (:func:`arc_length`).
    speed : ndarray, shape (m,)
        Forward speed [m/s] at each sample, held over the horizon.
    ahead : float
        The preview's horizon [s].
    lead : float, optional
        Distance [m] by which the lean leads the road's curvature (:data:`LEAD_DISTANCE`).
    trusted, limit : float, optional
        Leans [rad] up to which the trust is full and from which it is zero
        (:data:`LEAN_TRUSTED`, :data:`LEAN_LIMIT`).

    Returns
    -------
    ndarray, shape (m,)
        ``clip((limit - phi_max) / (limit - trusted), 0, 1)`` with ``phi_max`` the largest
        ``|atan(v^2 kappa / g)|`` of the road from ``s + lead`` to ``s + lead + v ahead``.

    Raises
    ------
    MotosimError
        If the leans are not ``0 <= trusted < limit``, ``ahead`` is negative, or ``arc``
        and ``speed`` differ in length.
    """
    if not (0.0 <= trusted < limit and math.isfinite(limit)):
        raise MotosimError(
            f"preview trust leans {trusted!r}, {limit!r} rad; expected 0 <= trusted < limit"
        )
    if not (math.isfinite(ahead) and ahead >= 0):
        raise MotosimError(f"preview trust ahead = {ahead!r} s; expected a finite number >= 0")
    _check_samples("preview trust", arc, speed)
    lean: Array = np.max(np.abs(_window_leans(road, arc, speed, lead, 0.0, ahead)), axis=1)
    trust: Array = np.clip((limit - lean) / (limit - trusted), 0.0, 1.0)
    return trust


def curve_persistence(
    road: Road,
    arc: Array,
    speed: Array,
    *,
    ahead: float,
    behind: float = 0.0,
    lead: float = LEAD_DISTANCE,
    floor: float = PERSISTENCE_FLOOR,
) -> Array:
    """How sustained the curve ahead is: 1 for one long curve, 0 for an S or a straight.

    Parameters
    ----------
    road : Road
        The road.
    arc : ndarray, shape (m,)
        Arc length [m] reached at each sample (:func:`arc_length`).
    speed : ndarray, shape (m,)
        Forward speed [m/s] at each sample, held over the window.
    ahead : float
        The window [s]: the MPC's horizon and the time after it over which the tilt it ends
        with is felt (:data:`motosim.cueing.mpc.COAST_TIMES`).
    behind : float, optional
        The part of the window [s] behind the present position: a lean is sustained by how
        long it has lasted as well as by how long it will last.
    lead : float, optional
        Distance [m] by which the lean leads the road's curvature (:data:`LEAD_DISTANCE`).
    floor : float, optional
        Mean lean [rad] below which the road is not a curve (:data:`PERSISTENCE_FLOOR`).

    Returns
    -------
    ndarray, shape (m,)
        ``|mean(phi)| / max(mean(|phi|), floor)`` over the steady-turn leans ``phi =
        atan(v^2 kappa / g)`` of the road from ``s + lead - v behind`` to ``s + lead + v
        ahead``, in
        [0, 1]: the lean is one-signed over the window (a turn, a curve, entering or leaving
        it) at 1, changes side (a swerve, a lane change, a slalom) towards 0, and a straight
        road (the mean lean under ``floor``) is at most ``mean / floor``.

    Raises
    ------
    MotosimError
        If ``ahead`` is not positive, ``floor`` not positive, or ``arc`` and ``speed``
        differ in length.

    Notes
    -----
    A tilt's lateral force is felt for seconds after it (the otolith's response to a held
    tilt peaks 1.9 s after it), so whether holding a tilt now is a false cue or the
    rendering of a lean depends on the road over the horizon and beyond it: in a long curve
    the rider holds the lean (the washout's sustained roll, Reid & Nahon 1985), in a swerve
    the lean changes side before the tilt's force fades.
    """
    if not (math.isfinite(ahead) and ahead > 0):
        raise MotosimError(f"curve persistence ahead = {ahead!r} s; expected a finite number > 0")
    if not (math.isfinite(behind) and behind >= 0):
        raise MotosimError(
            f"curve persistence behind = {behind!r} s; expected a finite number >= 0"
        )
    if not (math.isfinite(floor) and floor > 0):
        raise MotosimError(f"curve persistence floor = {floor!r} rad; expected a number > 0")
    _check_samples("curve persistence", arc, speed)
    phi = _window_leans(road, arc, speed, lead, behind, ahead)
    held = np.abs(np.mean(phi, axis=1))
    persistence: Array = held / np.maximum(np.mean(np.abs(phi), axis=1), floor)
    return persistence


def road_preview(
    road: Road,
    arc: Array,
    speed: Array,
    *,
    horizon: int,
    step: float,
    lead: float = LEAD_DISTANCE,
    smoothing: float = SMOOTHING,
) -> Array:
    """The motion at the head predicted from the road ahead, at each sample.

    Parameters
    ----------
    road : Road
        The road the rider follows.
    arc : ndarray, shape (m,)
        Arc length [m] reached at each sample (:func:`arc_length`).
    speed : ndarray, shape (m,)
        Forward speed [m/s] at each sample, held over the horizon.
    horizon, step : int, float
        The prediction: ``horizon`` steps of ``step`` [s] (the MPC's).
    lead : float, optional
        Distance [m] by which the lean leads the road's curvature under the rear contact
        (:data:`LEAD_DISTANCE`).
    smoothing : float, optional
        Half-width [s] of the finite differences of the lean (:data:`SMOOTHING`).

    Returns
    -------
    ndarray, shape (m, horizon + 1, 2)
        :data:`PREVIEW_SIGNALS` at ``tau = 0, step, ..., horizon * step`` ahead: the lean's
        rate and ``SWAY_HEIGHT * phi'' + SWAY_X * psi''`` with ``psi' = v kappa``.

    Raises
    ------
    MotosimError
        If ``smoothing`` is not positive or ``arc`` and ``speed`` differ in length.
    """
    if not (math.isfinite(smoothing) and smoothing > 0):
        raise MotosimError(f"preview smoothing = {smoothing!r} s; expected a finite number > 0")
    if arc.shape != speed.shape:
        raise MotosimError(
            f"preview of {arc.size} arc lengths and {speed.size} speeds; expected as many"
        )
    tau = np.arange(horizon + 1) * step
    v = speed[:, None]
    d = smoothing
    (phi_m, k_m), (phi_0, _), (phi_p, k_p) = (
        _steady_lean(road, arc[:, None] + lead + v * (tau[None, :] + e), v) for e in (-d, 0.0, d)
    )
    rate = (phi_p - phi_m) / (2 * d)
    accel = (phi_p - 2 * phi_0 + phi_m) / d**2
    yaw_accel = v * (k_p - k_m) / (2 * d)
    return np.stack([rate, SWAY_HEIGHT * accel + SWAY_X * yaw_accel], axis=-1)
