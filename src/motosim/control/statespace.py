"""Continuous-time state-space quadruples and the checks every control routine shares.

A :class:`StateSpace` is the plain ``(A, B, C, D)`` of

.. math::  \\dot x = A x + B u, \\qquad y = C x + D u,

with ``x`` of size n, ``u`` of size m and ``y`` of size p. It is a frozen record, not a
system algebra: interconnections live in :mod:`motosim.control.loops`. Every public routine
of :mod:`motosim.control` accepts either a :class:`StateSpace` or a 4-tuple of array-likes.
"""

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motosim.errors import MotosimError
from motosim.model.linear import StateSpace, _matrix

__all__ = ["StateSpace", "StateSpaceLike", "as_state_space", "frequency_response"]

Array = NDArray[np.float64]


StateSpaceLike = StateSpace | tuple[ArrayLike, ArrayLike, ArrayLike, ArrayLike]


def _from_array_likes(A: ArrayLike, B: ArrayLike, C: ArrayLike, D: ArrayLike) -> StateSpace:
    """Validated :class:`StateSpace` from array-likes (the error names the bad matrix)."""
    return StateSpace(_matrix(A, "A"), _matrix(B, "B"), _matrix(C, "C"), _matrix(D, "D"))


def as_state_space(system: StateSpaceLike, name: str = "system") -> StateSpace:
    """Return ``system`` as a validated :class:`StateSpace`.

    Parameters
    ----------
    system : StateSpace or tuple of 4 array-likes
        ``(A, B, C, D)``.
    name : str
        Name used in error messages.

    Returns
    -------
    StateSpace
        The same system, validated.

    Raises
    ------
    MotosimError
        If ``system`` is not a 4-tuple or its matrices are inconsistent.
    """
    if isinstance(system, StateSpace):
        return system
    if not isinstance(system, tuple | list) or len(system) != 4:
        raise MotosimError(f"{name} must be a StateSpace or a tuple (A, B, C, D)")
    try:
        return _from_array_likes(*system)
    except MotosimError as exc:
        raise MotosimError(f"{name}: {exc}") from None


def frequency_response(system: StateSpaceLike, omega: float) -> NDArray[np.complex128]:
    """Evaluate ``G(j omega) = C (j omega I - A)^-1 B + D``.

    Parameters
    ----------
    system : StateSpace or tuple of 4 array-likes
        The system.
    omega : float
        Angular frequency [rad/s]; ``math.inf`` returns ``D``.

    Returns
    -------
    NDArray[np.complex128], shape (p, m)
        The frequency response.
    """
    sys = as_state_space(system)
    if np.isinf(omega) or sys.n_states == 0:
        return sys.D.astype(np.complex128)
    n = sys.n_states
    X = np.linalg.solve(1j * omega * np.eye(n) - sys.A, sys.B)
    return np.asarray(sys.C @ X + sys.D, dtype=np.complex128)
