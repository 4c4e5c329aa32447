"""The rider's hands: the arms' passive impedance about the steering axis.

A rider holds the handlebar: besides the torque the rider means to apply (the *active*
torque of a profile or of the virtual rider), the hands and arms add an inertia, a damping
and a stiffness about a neutral angle that the hands hold,

    tau_passive = -J_a theta_h'' - c_a theta_h' - k_a (theta_h - theta_hold),

which act on the handlebar exactly as the active torque does (Cossalter, Doria, Lot &
Massaro, "The effect of rider's passive steering impedance on motorcycle stability:
identification and analysis", Meccanica 46 (2011) 279-292, who identified it on a riding
simulator; Massaro & Cole, "Neuromuscular-steering dynamics: motorcycle riders vs car
drivers", ASME DSCC 2012, a review). In the simulated rig the arms' inertia adds to the
handlebar's J_eq in the plant's integration and the damping and stiffness are torques, so
the stack's estimate sees the passive torque as a real front frame would.

:data:`GRIPS` holds the named grips (``relaxed``, ``firm`` and ``off``, no impedance), each
value with its source; a scenario names one (``[rider] hands = "relaxed"``) or gives its
own table. Both are defined in :mod:`motosim.sim.grips`, which a scenario's check imports
without numba.
"""

from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from motosim.model.handlebar import HandlebarPlant, step_exact
from motosim.sim.grips import GRIPS, Hands, resolve_hands

__all__ = [
    "GRIPS",
    "NO_ARMS",
    "Arms",
    "Hands",
    "arms_of",
    "hands_torque",
    "is_held",
    "plant_step",
    "resolve_hands",
    "step_spring",
]

Array = NDArray[np.float64]


class Arms(NamedTuple):
    """The arms at the handlebar as compiled loops take them: J_a [kg*m^2], c_a
    [N*m*s/rad], k_a [N*m/rad] and the held angle theta_hold [rad]; zeros: a pure torque
    source."""

    J_a: float
    c_a: float
    k_a: float
    theta_hold: float


NO_ARMS = Arms(0.0, 0.0, 0.0, 0.0)
"""No arms: the rider is a pure torque source."""


def arms_of(hands: Hands | None) -> Arms:
    """The :class:`Arms` of ``hands`` (:data:`NO_ARMS` without)."""
    if hands is None:
        return NO_ARMS
    return Arms(
        float(hands.inertia), float(hands.damping), float(hands.stiffness), float(hands.hold)
    )


@njit(cache=True)
def hands_torque(
    theta: float, omega: float, accel: float, J_a: float, c_a: float, k_a: float, hold: float
) -> float:
    """The arms' passive torque on the handlebar [N*m].

    -J_a theta'' - c_a theta' - k_a (theta - theta_hold), with ``theta`` [rad], ``omega``
    [rad/s] and ``accel`` [rad/s^2] the handlebar's angle, rate and acceleration.

    Examples
    --------
    >>> hands_torque(0.1, 0.0, 0.0, 0.1, 1.0, 10.0, 0.0)
    -1.0
    """
    return -J_a * accel - c_a * omega - k_a * (theta - hold)


@njit(cache=True)
def step_spring(theta: float, omega: float, k_a: float, hold: float, h: float) -> float:
    """The arms' spring torque -k_a (theta - theta_hold) [N*m] held over a plant step of
    ``h`` [s] from angle ``theta`` [rad] at rate ``omega`` [rad/s]: taken at the step's
    midpoint, theta + omega h / 2, so that the step is second order in ``h``.

    Examples
    --------
    >>> step_spring(0.1, 2.0, 10.0, 0.0, 0.01)
    -1.1
    """
    return -k_a * (theta + 0.5 * h * omega - hold)


@njit(cache=True)
def is_held(t: float, off: Array) -> bool:
    """Whether the hands hold the handlebar at ``t`` [s]: outside every hands-off phase
    ``off[i] = [t0, t1]`` (from t0 included to t1 excluded)."""
    for i in range(off.shape[0]):
        if off[i, 0] <= t < off[i, 1]:
            return False
    return True


@njit(cache=True)
def plant_step(
    theta: float,
    omega: float,
    torque: float,
    plant: HandlebarPlant,
    arms: Arms,
    held: bool,
    h: float,
) -> tuple[float, float]:
    """The true handlebar over a plant step of ``h`` [s], exact stick-slip
    (:func:`~motosim.model.handlebar.step_exact`).

    ``torque`` [N*m], held over the step, is the rider's active torque and the motor's. While
    the rider ``held`` the handlebar, the arms' inertia and damping add to J_eq and beta_eq
    and their spring is a torque taken at the step's midpoint (:func:`step_spring`). This is
    the one plant of the simulated rig (:mod:`motosim.sim.closed_loop`) and of the virtual
    rig (:mod:`motosim.rt.rig`).

    Returns
    -------
    theta, omega : float
        The angle [rad] and rate [rad/s] at the end of the step.
    """
    if not held:
        return step_exact(theta, omega, torque, plant.J_eq, plant.beta_eq, plant.beta_s, h)
    spring = step_spring(theta, omega, arms.k_a, arms.theta_hold, h)
    J = plant.J_eq + arms.J_a
    return step_exact(theta, omega, torque + spring, J, plant.beta_eq + arms.c_a, plant.beta_s, h)
