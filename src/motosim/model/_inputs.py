"""Validation of the time grid and input signals shared by the model simulations."""

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motosim.errors import MotosimError

__all__ = ["input_series", "sample_times"]


def sample_times(t: ArrayLike) -> NDArray[np.float64]:
    """``t`` as a float array, checked 1-D, finite, strictly increasing, >= 2 samples [s]."""
    tt = np.asarray(t, dtype=float)
    if tt.ndim != 1 or tt.size < 2 or not np.all(np.isfinite(tt)) or np.any(np.diff(tt) <= 0):
        raise MotosimError("t must be a 1-D, finite, strictly increasing array of >= 2 samples")
    return tt


def input_series(name: str, values: ArrayLike, n: int) -> NDArray[np.float64]:
    """An input sampled like ``t``: a scalar is held, an array must have shape (n,), finite."""
    arr = np.asarray(values, dtype=float)
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        raise MotosimError(f"{name} has shape {arr.shape}; expected ({n},) like t")
    if not np.all(np.isfinite(arr)):
        raise MotosimError(f"{name} has a NaN or infinite sample; expected finite values")
    return arr
