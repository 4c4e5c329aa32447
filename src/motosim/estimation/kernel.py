"""The record every rider-torque estimator publishes for compiled loops.

A compiled loop (the stack step of :mod:`motosim.sim.stack`) cannot call a Python stepper
object, so each estimator also publishes its discretised design as an
:class:`EstimatorKernel`: which compiled kernel to run (``kind``) and its arrays, padded to
common shapes so that one compiled loop serves every estimator. The kinds are the
estimators' own constants; :mod:`motosim.estimation.registry` holds the one dispatch on them.
"""

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["INVERSE_DYNAMICS", "KALMAN", "TORQUE_SENSOR", "WALCOTT_ZAK", "EstimatorKernel", "pack"]

Array = NDArray[np.float64]

WALCOTT_ZAK = 0
"""Kind of :func:`motosim.estimation.walcott_zak.wz_step`."""
INVERSE_DYNAMICS = 1
"""Kind of :func:`motosim.estimation.baselines.inverse_dynamics_step`."""
KALMAN = 2
"""Kind of :func:`motosim.estimation.baselines.kalman_step`."""
TORQUE_SENSOR = 3
"""Kind of :func:`motosim.estimation.registry.torque_sensor_kernel`: a measured torque
passed through (its low-pass's coefficient in ``p[0]``)."""


class EstimatorKernel(NamedTuple):
    """An estimator's compiled one-sample kernel and its arrays.

    A named tuple (immutable, and passed to numba-compiled code as is). The arrays are padded
    with zeros; each kernel reads its own leading block.

    Attributes
    ----------
    kind : int
        :data:`WALCOTT_ZAK`, :data:`INVERSE_DYNAMICS`, :data:`KALMAN` or
        :data:`TORQUE_SENSOR`.
    Phi : ndarray, shape (4, 4)
        State transition over one sample.
    Gamma : ndarray, shape (4, 4)
        Input matrix over one sample (inputs held).
    gain : ndarray, shape (4,)
        Output-injection or Kalman gain.
    p : ndarray, shape (10,)
        The kernel's scalar settings.
    dt : float
        Sampling step the kernel was discretised for [s].
    """

    kind: int
    Phi: Array
    Gamma: Array
    gain: Array
    p: Array
    dt: float


def _padded(values: ArrayLike, shape: tuple[int, ...]) -> Array:
    arr = np.asarray(values, dtype=np.float64)
    out = np.zeros(shape)
    out[tuple(slice(0, n) for n in arr.shape)] = arr
    return out


def pack(
    kind: int, Phi: ArrayLike, Gamma: ArrayLike, gain: ArrayLike, p: ArrayLike, dt: float
) -> EstimatorKernel:
    """Pad an estimator's arrays into an :class:`EstimatorKernel`."""
    return EstimatorKernel(
        int(kind),
        _padded(Phi, (4, 4)),
        _padded(Gamma, (4, 4)),
        _padded(gain, (4,)),
        _padded(p, (10,)),
        float(dt),
    )
