"""Positive-feedback loops of a plant and a controller, and the four-block objective.

Convention (the paper's eqs. (24)-(25), and SLICOT SB10ID's): the controller output is
``u = K y`` and the loop closes with a **plus** sign, so the sensitivity is
``(I - G K)^-1``. For a negative-feedback design ``u = -K' y`` use ``K = -K'``.

The four-block transfer of eq. (25), from the output and input disturbances ``[w1; w2]`` to
``[y; u]`` in the loop ``y = G (u + w2) + w1``, ``u = K y``, is

.. math::  T = \\begin{bmatrix} I \\\\ K \\end{bmatrix} (I - G K)^{-1}
              \\begin{bmatrix} I & G \\end{bmatrix},

whose H-infinity norm is the Glover-McFarlane robustness measure ``gamma = 1 / epsilon``
(the paper omits the third column ``G_w``; for a unit disturbance input it adds nothing new).
"""

import math

import numpy as np
from numpy.typing import NDArray

from motosim.control.norms import _hinf_norm_stable
from motosim.control.statespace import StateSpace, StateSpaceLike, as_state_space
from motosim.errors import MotosimError

__all__ = ["closed_loop_poles", "four_block_norm", "four_block_system", "is_stable"]

Array = NDArray[np.float64]

# A closed loop whose spectral abscissa is >= -_STAB_RTOL * ||A_cl||_1 counts as unstable.
_STAB_RTOL = 1e-12


def four_block_system(plant: StateSpaceLike, controller: StateSpaceLike) -> StateSpace:
    """State-space model of the four-block transfer of eq. (25), positive feedback.

    Parameters
    ----------
    plant : StateSpace or tuple (A, B, C, D)
        The (shaped) plant ``G_s`` with m inputs (motor current [A] for the handlebar) and
        p outputs (``theta_h`` [rad]).
    controller : StateSpace or tuple (A, B, C, D)
        The controller ``K``: p inputs, m outputs, ``u = K y`` (positive feedback).

    Returns
    -------
    StateSpace
        ``T`` with inputs ``[w1 (p); w2 (m)]`` and outputs ``[y (p); u (m)]``; its states are
        ``[x_G; x_K]``.

    Raises
    ------
    MotosimError
        If the dimensions of plant and controller do not fit, or ``I - D_G D_K`` is singular
        (the loop is not well posed).
    """
    G = as_state_space(plant, "plant")
    K = as_state_space(controller, "controller")
    if K.n_inputs != G.n_outputs or K.n_outputs != G.n_inputs:
        raise MotosimError(
            f"controller is {K.n_outputs}x{K.n_inputs}; expected {G.n_inputs}x{G.n_outputs} "
            "(plant inputs x plant outputs)"
        )
    return _four_block(G.A, G.B, G.C, G.D, K.A, K.B, K.C, K.D)


def _four_block(
    Ag: Array, Bg: Array, Cg: Array, Dg: Array, Ak: Array, Bk: Array, Ck: Array, Dk: Array
) -> StateSpace:
    """Four-block closed loop from raw matrices (no validation of shapes)."""
    ng, m = Bg.shape
    p = Cg.shape[0]
    nk = Ak.shape[0]
    W = np.eye(p) - Dg @ Dk
    if np.linalg.cond(W) > 1e12:
        raise MotosimError("the loop is not well posed: I - D_G D_K is singular")
    E = np.linalg.inv(W)
    # y = Cy x + Dy w,  u = Cu x + Du w  with x = [x_G; x_K], w = [w1; w2].
    Cy = np.hstack((E @ Cg, E @ Dg @ Ck))
    Dy = np.hstack((E, E @ Dg))
    Cu = Dk @ Cy + np.hstack((np.zeros((m, ng)), Ck))
    Du = Dk @ Dy
    A = np.zeros((ng + nk, ng + nk))
    A[:ng, :ng] = Ag
    A[ng:, ng:] = Ak
    A[:ng, :] += Bg @ Cu
    A[ng:, :] += Bk @ Cy
    Bw = np.zeros((ng + nk, p + m))
    Bw[:ng, :] = Bg @ Du
    Bw[:ng, p:] += Bg
    Bw[ng:, :] = Bk @ Dy
    return StateSpace(A, Bw, np.vstack((Cy, Cu)), np.vstack((Dy, Du)))


def closed_loop_poles(plant: StateSpaceLike, controller: StateSpaceLike) -> NDArray[np.complex128]:
    """Poles of the positive-feedback loop ``u = K y`` [rad/s].

    Parameters
    ----------
    plant : StateSpace or tuple (A, B, C, D)
        The plant G (m inputs, p outputs).
    controller : StateSpace or tuple (A, B, C, D)
        The controller K (p inputs, m outputs).

    Returns
    -------
    NDArray[np.complex128], shape (n_G + n_K,)
        Eigenvalues of the closed-loop state matrix.

    Raises
    ------
    MotosimError
        As :func:`four_block_system`.
    """
    return np.linalg.eigvals(four_block_system(plant, controller).A).astype(np.complex128)


def is_stable(poles: NDArray[np.complex128], scale: float = 1.0) -> bool:
    """True if every pole has ``Re(p) < -1e-12 * scale`` (``scale``: a norm of A [1/s])."""
    return poles.size == 0 or float(np.max(poles.real)) < -_STAB_RTOL * scale


def four_block_norm(plant: StateSpaceLike, controller: StateSpaceLike) -> float:
    """Glover-McFarlane four-block norm ``|| [I; K] (I - G K)^-1 [I, G] ||_inf``, eq. (25).

    Parameters
    ----------
    plant : StateSpace or tuple (A, B, C, D)
        The (shaped) plant ``G_s``.
    controller : StateSpace or tuple (A, B, C, D)
        The controller ``K`` in the positive-feedback convention ``u = K y``.

    Returns
    -------
    float
        The norm ``gamma`` (>= 1 for any stabilising K); ``math.inf`` if the closed loop
        is not internally stable.

    Raises
    ------
    MotosimError
        As :func:`four_block_system`.

    Examples
    --------
    The paper's eq. (26) controller on the unit-weight handlebar: the peak is at infinite
    frequency, ``sqrt(1 + K(inf)^2)``.

    >>> J, beta = 0.0415, 13.956
    >>> G = ([[0.0, 1.0], [0.0, -beta / J]], [[0.0], [1.0 / J]], [[1.0, 0.0]], [[0.0]])
    >>> K = ([[-1445.0]], [[1.0]], [[-613.7 + 2.355 * 1445.0]], [[-2.355]])
    >>> round(four_block_norm(G, K), 4)
    2.5585
    """
    T = four_block_system(plant, controller)
    poles = np.linalg.eigvals(T.A).astype(np.complex128)
    if not is_stable(poles, float(np.linalg.norm(T.A, 1))):
        return math.inf
    return _hinf_norm_stable(T.A, T.B, T.C, T.D, poles, 1e-10)[0]
