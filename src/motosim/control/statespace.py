"""Continuous-time state-space quadruples and the checks every control routine shares.

A :class:`StateSpace` is the plain ``(A, B, C, D)`` of

.. math::  \\dot x = A x + B u, \\qquad y = C x + D u,

with ``x`` of size n, ``u`` of size m and ``y`` of size p. It is a frozen record, not a
system algebra: interconnections live in :mod:`motosim.control.loops`. Every public routine
of :mod:`motosim.control` accepts either a :class:`StateSpace` or a 4-tuple of array-likes.
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motosim.errors import MotosimError

__all__ = ["StateSpace", "StateSpaceLike", "as_state_space", "frequency_response"]

Array = NDArray[np.float64]


def _matrix(value: ArrayLike, name: str) -> Array:
    """``value`` as a finite 2-D float64 array, or a MotosimError naming it."""
    try:
        M = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise MotosimError(f"{name} is not a real numeric matrix: {exc}") from None
    if M.ndim == 0:
        M = M.reshape(1, 1)
    if M.ndim != 2:
        raise MotosimError(f"{name} has shape {M.shape}; expected a 2-D matrix")
    if not np.all(np.isfinite(M)):
        raise MotosimError(f"{name} contains NaN or infinite entries")
    return M


@dataclass(frozen=True, slots=True)
class StateSpace:
    """A continuous-time linear system ``x' = A x + B u``, ``y = C x + D u``.

    Parameters
    ----------
    A : NDArray[np.float64], shape (n, n)
        State matrix [1/s].
    B : NDArray[np.float64], shape (n, m)
        Input matrix.
    C : NDArray[np.float64], shape (p, n)
        Output matrix.
    D : NDArray[np.float64], shape (p, m)
        Direct feedthrough.
    dt : float
        Sampling time [s]: 0 for a continuous-time system, > 0 for a discrete-time one
        (x_{k+1} = A x_k + B u_k, as :func:`motosim.control.torque_feedback.discretize` returns).

    Raises
    ------
    MotosimError
        If a matrix is not 2-D, contains NaN/inf, or the shapes do not match.
    """

    A: Array
    B: Array
    C: Array
    D: Array
    dt: float = 0.0

    def __post_init__(self) -> None:
        if not (isinstance(self.dt, int | float) and math.isfinite(self.dt) and self.dt >= 0):
            raise MotosimError(f"dt = {self.dt!r}; expected a finite sampling time >= 0 [s]")
        A = _matrix(self.A, "A")
        n = A.shape[0]
        if A.shape != (n, n):
            raise MotosimError(f"A has shape {A.shape}; expected a square (n, n) matrix")
        B = _matrix(self.B, "B")
        C = _matrix(self.C, "C")
        D = _matrix(self.D, "D")
        if n == 0:
            # Static gain: accept empty B (0, m) and C (p, 0) given in any degenerate form.
            B = B.reshape(0, D.shape[1]) if B.size == 0 else B
            C = C.reshape(D.shape[0], 0) if C.size == 0 else C
        if B.shape[0] != n:
            raise MotosimError(f"B has shape {B.shape}; expected ({n}, m) to match A")
        if C.shape[1] != n:
            raise MotosimError(f"C has shape {C.shape}; expected (p, {n}) to match A")
        if D.shape != (C.shape[0], B.shape[1]):
            raise MotosimError(
                f"D has shape {D.shape}; expected {(C.shape[0], B.shape[1])} to match C and B"
            )
        object.__setattr__(self, "A", A)
        object.__setattr__(self, "B", B)
        object.__setattr__(self, "C", C)
        object.__setattr__(self, "D", D)

    @property
    def is_discrete(self) -> bool:
        """Whether this is a discrete-time system (``dt`` > 0)."""
        return self.dt > 0

    @property
    def n_states(self) -> int:
        """Number of states n."""
        return int(self.A.shape[0])

    @property
    def n_inputs(self) -> int:
        """Number of inputs m."""
        return int(self.B.shape[1])

    @property
    def n_outputs(self) -> int:
        """Number of outputs p."""
        return int(self.C.shape[0])

    def poles(self) -> NDArray[np.complex128]:
        """Eigenvalues of A [rad/s], in the order LAPACK returns them."""
        return np.linalg.eigvals(self.A).astype(np.complex128)


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
