"""Linear state-space systems: the one :class:`StateSpace` type and exact ZOH discretisation.

A :class:`StateSpace` is the plain ``(A, B, C, D)`` of x' = A x + B u, y = C x + D u (or, with
a sampling time ``dt`` > 0, x_{k+1} = A x_k + B u_k), optionally with named signals. It is a
frozen record, not a system algebra: models (:mod:`motosim.model.sharp`,
:mod:`motosim.model.handlebar`) return it, and :mod:`motosim.control` designs with it.
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import expm

from motosim.errors import MotosimError

__all__ = ["StateSpace", "zoh"]

Array = NDArray[np.float64]


def zoh(A: Array, B: Array, dt: float) -> tuple[Array, Array]:
    """Exact zero-order-hold discretisation by one matrix exponential.

    Parameters
    ----------
    A : ndarray, shape (n, n)
        State matrix [1/s].
    B : ndarray, shape (n, m)
        Input matrix.
    dt : float
        Step [s], > 0.

    Returns
    -------
    Ad, Bd : ndarray
        exp(A dt) and int_0^dt exp(A s) ds B, so that x[k+1] = Ad x[k] + Bd u[k].
    """
    if not (np.isfinite(dt) and dt > 0):
        raise MotosimError(f"dt = {dt!r}; expected a finite step > 0 [s]")
    n, m = B.shape
    block = np.zeros((n + m, n + m))
    block[:n, :n] = A * dt
    block[:n, n:] = B * dt
    phi = expm(block)
    return phi[:n, :n], phi[:n, n:]


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
    state_names, input_names, output_names : tuple of str
        Signal names from :mod:`motosim.signals`, in matrix order; empty when unnamed.

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
    state_names: tuple[str, ...] = ()
    input_names: tuple[str, ...] = ()
    output_names: tuple[str, ...] = ()

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
        for what, names, size in (
            ("state_names", self.state_names, n),
            ("input_names", self.input_names, B.shape[1]),
            ("output_names", self.output_names, C.shape[0]),
        ):
            if names and len(names) != size:
                raise MotosimError(f"{what} has {len(names)} names; expected {size} or none")

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
        """Eigenvalues of A [1/s] (continuous) or [1] (discrete), sorted by real part."""
        ev = np.linalg.eigvals(self.A).astype(np.complex128)
        return ev[np.lexsort((ev.imag, ev.real))]

    def discretize(self, dt: float) -> tuple[Array, Array]:
        """Exact zero-order-hold discretisation of a continuous system at the step ``dt`` [s].

        Returns
        -------
        Ad, Bd : ndarray
            x[k+1] = Ad x[k] + Bd u[k], with u held over the step.
        """
        if self.is_discrete:
            raise MotosimError(f"the system is already discrete (dt = {self.dt:g} s)")
        return zoh(self.A, self.B, dt)
