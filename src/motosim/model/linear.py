"""A continuous-time linear model with named states, inputs and outputs."""

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import expm

from motosim.errors import MotosimError

__all__ = ["LinearModel"]

Array = NDArray[np.float64]


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
        if not (np.isfinite(dt) and dt > 0):
            raise MotosimError(f"dt = {dt!r}; expected a finite step > 0 [s]")
        n, m = self.B.shape
        block = np.zeros((n + m, n + m))
        block[:n, :n] = self.A * dt
        block[:n, n:] = self.B * dt
        phi = expm(block)
        return phi[:n, :n], phi[:n, n:]
