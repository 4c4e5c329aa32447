"""The compiled step of the riding simulator's software stack (Fig. 7), shared by both loops.

The stack is what runs on the simulator's computer: it takes the measured handlebar angle and
motor current, estimates the rider's torque (differentiator + observer), drives the virtual
motorcycle with it, and commands the motor current that makes the handlebar follow the
motorcycle's steer angle. The offline simulator (:mod:`motosim.sim.closed_loop`) and the
real-time loop call the same two functions each sample:

1. :func:`stack_command` -- the controller: i_m = K (theta_h - delta), positive feedback
   (eq. (24)), saturated, from the measured angle and the current steer angle;
2. :func:`stack_update` -- with the current that will be held over the coming interval:
   differentiator and estimator (dispatching on its kind, see
   :func:`motosim.estimation.registry.kernel_arguments`); the loop then advances the
   motorcycle with :func:`motosim.model.sharp.bike_rk4`.

Everything is plain numeric code over float64 arrays, compiled with numba and runnable
uncompiled under ``NUMBA_DISABLE_JIT=1``.
"""

import numpy as np
from numba import njit
from numpy.typing import NDArray

from motosim.estimation.baselines import inverse_dynamics_step, kalman_step
from motosim.estimation.differentiator import std_step
from motosim.estimation.walcott_zak import wz_step

__all__ = ["stack_command", "stack_update"]

Array = NDArray[np.float64]


@njit(cache=True)
def stack_command(
    ctrl_x: Array,
    Ad: Array,
    Bd: Array,
    Cd: Array,
    Dd: Array,
    theta_meas: float,
    delta: float,
    max_current: float,
    enabled: bool,
    work: Array,
) -> float:
    """Motor current command [A] for this sample; advances the controller state in place.

    The controller is discrete (x+ = Ad x + Bd e, i = Cd x + Dd e) with the tracking error
    e = theta_meas - delta [rad]; ``enabled`` False (Fig. 9, open loop) commands 0 A.
    ``work`` is scratch space of at least the controller's order.
    """
    if not enabled:
        return 0.0
    e = theta_meas - delta
    n = ctrl_x.size
    u = Dd[0, 0] * e
    for j in range(n):
        u += Cd[0, j] * ctrl_x[j]
    tmp = work
    for r in range(n):
        acc = Bd[r, 0] * e
        for j in range(n):
            acc += Ad[r, j] * ctrl_x[j]
        tmp[r] = acc
    for r in range(n):
        ctrl_x[r] = tmp[r]
    return float(min(max(u, -max_current), max_current))


@njit(cache=True)
def stack_update(
    est: Array,
    diff: Array,
    flags: Array,
    est_kind: int,
    Phi: Array,
    Gamma: Array,
    gain: Array,
    p: Array,
    diff_p: Array,
    theta_meas: float,
    current: float,
    new_sample: bool,
) -> tuple[float, float]:
    """Differentiator and estimator on a new sample; returns (theta_h_dot_hat, tau_r_hat).

    ``diff`` = [z0, z1] of the super-twisting differentiator with ``diff_p`` = [h, l1, l2];
    ``est`` (4,) is the estimator state; ``flags`` = [first sample?, last rate, last torque].
    Between samples (``new_sample`` False) the last outputs are held.
    """
    if not new_sample:
        return flags[1], flags[2]
    if flags[0] > 0.5:  # first sample: start every state at the measurement
        diff[0], diff[1] = theta_meas, 0.0
        if est_kind == 0:
            est[0], est[1], est[2], est[3] = 0.0, theta_meas, 0.0, 0.0
        elif est_kind == 1:
            est[0], est[1], est[2], est[3] = theta_meas, 0.0, current, 0.0
        else:
            est[0], est[1], est[2], est[3] = 0.0, theta_meas, 0.0, 0.0
        flags[0] = 0.0
    else:
        diff[0], diff[1] = std_step(
            diff[0], diff[1], theta_meas, diff_p[0], diff_p[1], diff_p[2], True
        )
    rate = diff[1]
    if est_kind == 0:
        new, _ = wz_step(est, theta_meas, rate, current, Phi[:2, :2], Gamma[:2, :], gain[:2], p)
        for i in range(4):
            est[i] = new[i]
        tau = new[2]
    elif est_kind == 1:
        new, tau = inverse_dynamics_step(est, theta_meas, current, Phi, Gamma[:, :2], p[:7])
        for i in range(4):
            est[i] = new[i]
    else:
        post, nxt = kalman_step(
            est[:3], theta_meas, current, Phi[:3, :3], Gamma[:3, :2], gain[:3], p[:3]
        )
        for i in range(3):
            est[i] = nxt[i]
        tau = post[2]
    flags[1], flags[2] = rate, tau
    return rate, tau
