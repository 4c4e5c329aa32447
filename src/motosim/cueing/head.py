"""What the rider's head undergoes: specific force and angular velocity, vehicle and platform.

Both the virtual motorcycle and the platform are rigid bodies carrying the head at a fixed
point ``r`` of the body frame (SAE: x forward, y right, z down). With the body's
orientation given by roll ``phi`` and pitch ``theta`` relative to a heading frame turning
at the yaw rate ``psi_dot`` (Z-Y-X Euler angles), and ``a_O`` the acceleration of the
body's reference point in the heading frame, the head's angular velocity and specific force
in the body frame are (rigid-body kinematics, e.g. Greenwood, *Principles of Dynamics*, 2nd
ed., 1988, ch. 2 and 7)::

    p = phi_dot - psi_dot sin(theta)
    q = theta_dot cos(phi) + psi_dot sin(phi) cos(theta)
    r = -theta_dot sin(phi) + psi_dot cos(phi) cos(theta)
    f = R^T a_O + alpha x r + omega x (omega x r) - g (-sin theta, sin phi cos theta,
                                                       cos phi cos theta)

with ``R = R_y(theta) R_x(phi)`` and ``alpha`` the time derivative of ``omega``. The
specific force of a rider at rest is ``(0, 0, -g)``: the seat pushes up.

For the motorcycle the reference point is the rear-wheel contact point, whose acceleration
in the heading frame is ``(v_x' - v_y psi_dot, v_y' + v_x psi_dot, 0)``; ``v_x'`` is eq. (2)
of Nehaoua, Arioui & Mammar (2012) when the drive and brake torques are recorded, else the
derivative of the recorded speed (the same quantity). The motorcycle's pitch is the
suspension pitch of :func:`suspension_pitch`; rotating about the contact point rather than
the suspension's pitch centre is a small-angle approximation.
"""

import numpy as np
from numpy.typing import NDArray

from motosim.cueing.filters import lowpass2, run_section
from motosim.cueing.platform import Platform, RiderHead
from motosim.errors import MotosimError
from motosim.params.sharp import SharpParameters
from motosim.timeseries import TimeSeries

__all__ = [
    "HEAD_SIGNALS",
    "check_rate",
    "head_kinematics",
    "platform_motion",
    "suspension_pitch",
    "vehicle_motion",
]

Array = NDArray[np.float64]

HEAD_SIGNALS = (
    "a_x",
    "a_y",
    "theta",
    "theta_dot",
    "omega_x",
    "omega_y",
    "omega_z",
    "f_x",
    "f_y",
    "f_z",
)
"""Columns of :func:`vehicle_motion` and :func:`platform_motion` (see :mod:`motosim.signals`)."""

GRAVITY = 9.81  # [m/s^2], the g of the Sharp parameter sets


def check_rate(t: Array) -> float:
    """The constant sample period of ``t`` [s].

    Raises
    ------
    MotosimError
        If there are fewer than 3 samples or the spacing varies by more than 1e-6 relative.
    """
    if t.size < 3:
        raise MotosimError(f"time series of {t.size} samples; expected at least 3")
    steps = np.diff(t)
    dt = float(np.median(steps))
    if not dt > 0.0 or np.max(np.abs(steps - dt)) > 1e-6 * dt:
        raise MotosimError(
            f"sample period from {steps.min():g} to {steps.max():g} s; expected a constant rate"
        )
    return dt


def head_kinematics(
    a_O: Array,
    phi: Array,
    theta: Array,
    phi_dot: Array,
    theta_dot: Array,
    psi_dot: Array,
    head: tuple[float, float, float],
    dt: float,
    *,
    g: float = GRAVITY,
) -> tuple[Array, Array]:
    """Angular velocity and specific force at the head, in the body frame.

    Parameters
    ----------
    a_O : ndarray, shape (n, 2)
        Longitudinal and lateral acceleration of the reference point in the heading frame
        [m/s^2].
    phi, theta : ndarray, shape (n,)
        Roll (right side down positive) and pitch (nose up positive) [rad].
    phi_dot, theta_dot, psi_dot : ndarray, shape (n,)
        Euler angle rates [rad/s].
    head : tuple of float
        Head position in the body frame [m].
    dt : float
        Sample period [s] (the angular acceleration is the centred difference of omega).
    g : float, optional
        Gravitational acceleration [m/s^2].

    Returns
    -------
    omega : ndarray, shape (n, 3)
        Body angular velocity (p, q, r) [rad/s].
    f : ndarray, shape (n, 3)
        Specific force at the head in the body frame [m/s^2].

    Examples
    --------
    >>> z = np.zeros(3)
    >>> _, f = head_kinematics(np.zeros((3, 2)), z, z, z, z, z, (0.0, 0.0, -1.0), 0.01)
    >>> f[0]
    array([ 0.  ,  0.  , -9.81])
    """
    sf, cf = np.sin(phi), np.cos(phi)
    st, ct = np.sin(theta), np.cos(theta)
    omega = np.column_stack(
        [
            phi_dot - psi_dot * st,
            theta_dot * cf + psi_dot * sf * ct,
            -theta_dot * sf + psi_dot * cf * ct,
        ]
    )
    alpha = np.gradient(omega, dt, axis=0)
    r = np.asarray(head, dtype=np.float64)
    ax, ay = a_O[:, 0], a_O[:, 1]
    body = np.column_stack([ct * ax, cf * ay + sf * st * ax, -sf * ay + cf * st * ax])
    gravity = g * np.column_stack([-st, sf * ct, cf * ct])
    f = body + np.cross(alpha, r) + np.cross(omega, np.cross(omega, r)) - gravity
    return omega, f


def suspension_pitch(rider: RiderHead, a_x: Array, dt: float) -> Array:
    """Suspension pitch of the motorcycle under longitudinal acceleration [rad].

    A second-order pitch mode driven by the quasi-static load-transfer pitch:
    ``theta = K w^2 / (s^2 + 2 zeta w s + w^2) a_x`` with ``K`` = ``rider.pitch_gain``
    (nose up when accelerating, down when braking), discretised with Tustin.

    Parameters
    ----------
    rider : RiderHead
        Pitch gain [rad/(m/s^2)], frequency [rad/s] and damping.
    a_x : ndarray, shape (n,)
        Longitudinal acceleration [m/s^2].
    dt : float
        Sample period [s].

    Returns
    -------
    ndarray, shape (n,)
        Pitch angle, nose up positive [rad].
    """
    coef = lowpass2(rider.pitch_gain, rider.pitch_frequency, rider.pitch_damping, dt)
    return run_section(coef, a_x)


def vehicle_motion(
    series: TimeSeries, rider: RiderHead, *, params: SharpParameters | None = None
) -> TimeSeries:
    """The motorcycle's motion at the rider's head.

    Parameters
    ----------
    series : TimeSeries
        A recorded run at a constant rate with ``v_x``, ``v_y``, ``psi_dot``, ``phi_dot`` and
        ``phi`` (the signals of :mod:`motosim.signals`); with ``tau_d`` and ``tau_b`` (and
        optionally ``F_wx``) and ``params``, ``v_x'`` is computed by eq. (2). A recorded
        ``theta``, the multibody motorcycle's pitch on its tyres as the load transfers (0
        on Sharp's model, which has none), adds to the suspension's pitch.
    rider : RiderHead
        The head's position on the motorcycle and the suspension pitch model.
    params : SharpParameters, optional
        The motorcycle, for eq. (2).

    Returns
    -------
    TimeSeries
        Columns :data:`HEAD_SIGNALS`: ``a_x`` = v_x' - v_y psi_dot and ``a_y`` = v_y' +
        v_x psi_dot [m/s^2] of the contact point, pitch ``theta`` [rad] (the suspension's and
        the recorded one) and its rate [rad/s], head angular velocity ``omega_*`` [rad/s]
        and specific force ``f_*`` [m/s^2] in the head frame.

    Raises
    ------
    MotosimError
        If a signal is missing or the rate is not constant.
    """
    t = np.asarray(series.t, dtype=np.float64)
    dt = check_rate(t)
    try:
        v_x, v_y = series["v_x"], series["v_y"]
        psi_dot, phi_dot, phi = series["psi_dot"], series["phi_dot"], series["phi"]
    except KeyError as err:
        raise MotosimError(
            f"motion at the head: {err.args[0]}; expected v_x, v_y, psi_dot, phi_dot, phi"
        ) from None
    if params is not None and "tau_d" in series.names and "tau_b" in series.names:
        from motosim.params.sharp import derived_geometry

        d = derived_geometry(params)
        wind = series["F_wx"] if "F_wx" in series.names else np.zeros_like(t)
        force = (series["tau_d"] - series["tau_b"]) / d["r_D"] + d["m"] * psi_dot * v_y + wind
        v_x_dot = force / d["m_eq"]  # eq. (2) in its consistent form
        g = params.g
    else:
        v_x_dot = np.gradient(v_x, dt)
        g = GRAVITY
    a_x = v_x_dot - v_y * psi_dot
    a_y = np.gradient(v_y, dt) + v_x * psi_dot
    theta = suspension_pitch(rider, a_x, dt)
    if "theta" in series.names:  # the multibody motorcycle's pitch on its tyres (0 on Sharp's)
        theta = theta + series["theta"]
    theta_dot = np.gradient(theta, dt)
    omega, f = head_kinematics(
        np.column_stack([a_x, a_y]),
        phi,
        theta,
        phi_dot,
        theta_dot,
        psi_dot,
        (rider.x, 0.0, -rider.height),
        dt,
        g=g,
    )
    data = np.column_stack([a_x, a_y, theta, theta_dot, omega, f])
    return TimeSeries(t, data, HEAD_SIGNALS)


def platform_motion(
    t: Array, roll: Array, pitch: Array, yaw: Array, platform: Platform
) -> TimeSeries:
    """The platform's motion at the rider's head, from its achieved angles.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Time at a constant rate [s].
    roll, pitch, yaw : ndarray, shape (n,)
        Platform angles [rad].
    platform : Platform
        Where the head is relative to the centre of rotation.

    Returns
    -------
    TimeSeries
        Columns :data:`HEAD_SIGNALS`; ``a_x`` and ``a_y`` are zero (the centre of rotation
        is fixed), ``theta`` is the platform pitch.
    """
    dt = check_rate(t)
    roll_dot, pitch_dot, yaw_dot = (np.gradient(x, dt) for x in (roll, pitch, yaw))
    zeros = np.zeros((t.size, 2))
    omega, f = head_kinematics(zeros, roll, pitch, roll_dot, pitch_dot, yaw_dot, platform.head, dt)
    data = np.column_stack([zeros, pitch, pitch_dot, omega, f])
    return TimeSeries(np.asarray(t, dtype=np.float64), data, HEAD_SIGNALS)
