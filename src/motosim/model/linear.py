"""A continuous-time linear model with named states, inputs and outputs."""

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import expm

from motosim.errors import MotosimError

__all__ = ["LinearModel", "zoh"]

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


@dataclass(frozen=True, slots=True)
class LinearModel:
    """x' = A x + B u, y = C x + D u, with named signals.

    Attributes
    ----------
    A, B, C, D : ndarray
        State-space matrices, shapes (n, n), (n, m), (p, n), (p, m).
    state_names, input_names, output_names : tuple of str
        Signal names from :mod:`motosim.signals`, in matrix order.
    """

    A: Array
    B: Array
    C: Array
    D: Array
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    output_names: tuple[str, ...]

    def __post_init__(self) -> None:
        n, m, p = len(self.state_names), len(self.input_names), len(self.output_names)
        for name, mat, shape in (
            ("A", self.A, (n, n)),
            ("B", self.B, (n, m)),
            ("C", self.C, (p, n)),
            ("D", self.D, (p, m)),
        ):
            if mat.shape != shape:
                raise MotosimError(f"LinearModel: {name} has shape {mat.shape}; expected {shape}")
            if not np.all(np.isfinite(mat)):
                raise MotosimError(f"LinearModel: {name} has a non-finite entry")

    def poles(self) -> NDArray[np.complex128]:
        """Eigenvalues of A [1/s], sorted by real part."""
        ev = np.linalg.eigvals(self.A).astype(complex)
        return ev[np.lexsort((ev.imag, ev.real))]

    def discretize(self, dt: float) -> tuple[Array, Array]:
        """Exact zero-order-hold discretisation at the step ``dt`` [s].

        Returns
        -------
        Ad, Bd : ndarray
            x[k+1] = Ad x[k] + Bd u[k], with u held over the step.
        """
        return zoh(self.A, self.B, dt)
