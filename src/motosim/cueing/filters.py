"""Second-order sections discretised with the bilinear (Tustin) transform, and their step.

A continuous filter ``(b2 s^2 + b1 s + b0) / (a2 s^2 + a1 s + a0)`` becomes the discrete
section ``(c0 + c1 z^-1 + c2 z^-2) / (1 + d1 z^-1 + d2 z^-2)``, packed as the five numbers
``[c0, c1, c2, d1, d2]`` and run in direct form II transposed with two states. The packing
lets a compiled step read several sections from one coefficient array.
"""

import numpy as np
from numba import njit
from numpy.typing import NDArray

from motosim.errors import MotosimError

__all__ = ["biquad_step", "highpass2", "lowpass2", "run_section", "tustin"]

Array = NDArray[np.float64]


def tustin(num: tuple[float, ...], den: tuple[float, ...], dt: float) -> Array:
    """Discretise a continuous filter of order <= 2 with the bilinear transform.

    Parameters
    ----------
    num, den : tuple of float
        Polynomial coefficients in s, highest power first (as :func:`scipy.signal.bilinear`).
    dt : float
        Sample period [s].

    Returns
    -------
    ndarray, shape (5,)
        ``[c0, c1, c2, d1, d2]``, the section of the module docstring.

    Raises
    ------
    MotosimError
        If the order exceeds 2, the filter is improper or ``dt`` is not positive.

    Examples
    --------
    >>> tustin((1.0,), (1.0, 1.0), 0.1).round(6)    # 1 / (s + 1)
    array([ 0.047619,  0.047619,  0.      , -0.904762,  0.      ])
    """
    if not dt > 0.0:
        raise MotosimError(f"sample period dt = {dt!r}; expected a finite number > 0 [s]")
    if len(den) > 3 or len(num) > len(den) or den[0] == 0.0:
        raise MotosimError(f"filter {num}/{den}; expected a proper filter of order <= 2")
    from scipy.signal import bilinear

    zero = not any(num)  # scipy's bilinear fails on a zero numerator
    bz, az = bilinear(np.asarray((1.0,) if zero else num, float), np.asarray(den, float), fs=1 / dt)
    if zero:
        bz = np.zeros_like(bz)
    b = np.zeros(3)
    a = np.zeros(3)
    b[: bz.size] = bz  # both in powers of z^-1 from z^0, as long as the filter's order
    a[: az.size] = az
    b, a = b / a[0], a / a[0]
    return np.array([b[0], b[1], b[2], a[1], a[2]])


def highpass2(gain: float, frequency: float, damping: float, dt: float) -> Array:
    """Tustin section of ``gain s^2 / (s^2 + 2 zeta w s + w^2)`` (w = ``frequency`` [rad/s])."""
    w, z = frequency, damping
    return tustin((gain, 0.0, 0.0), (1.0, 2 * z * w, w * w), dt)


def lowpass2(gain: float, frequency: float, damping: float, dt: float) -> Array:
    """Tustin section of ``gain w^2 / (s^2 + 2 zeta w s + w^2)`` (w = ``frequency`` [rad/s])."""
    w, z = frequency, damping
    return tustin((gain * w * w,), (1.0, 2 * z * w, w * w), dt)


@njit(cache=True)
def biquad_step(coef: Array, c: int, state: Array, s: int, x: float) -> float:
    """One sample of the section ``coef[c:c+5]`` with states ``state[s:s+2]``.

    Parameters
    ----------
    coef : ndarray
        Packed sections; this one starts at index ``c``.
    c : int
        Offset of the section in ``coef``.
    state : ndarray
        Filter states, updated in place; this section's two start at index ``s``.
    s : int
        Offset of the states.
    x : float
        Input sample.

    Returns
    -------
    float
        Output sample.
    """
    y = coef[c] * x + state[s]
    state[s] = coef[c + 1] * x - coef[c + 3] * y + state[s + 1]
    state[s + 1] = coef[c + 2] * x - coef[c + 4] * y
    return float(y)


@njit(cache=True)
def _run(coef: Array, x: Array, out: Array) -> None:
    state = np.zeros(2)
    for k in range(x.size):
        out[k] = biquad_step(coef, 0, state, 0, x[k])


def run_section(coef: Array, x: Array) -> Array:
    """Filter a whole signal with one section from zero state.

    Parameters
    ----------
    coef : ndarray, shape (5,)
        A section from :func:`tustin`.
    x : ndarray, shape (n,)
        Input samples.

    Returns
    -------
    ndarray, shape (n,)
        Output samples.
    """
    xx = np.ascontiguousarray(x, dtype=np.float64)
    out = np.empty_like(xx)
    _run(np.ascontiguousarray(coef, dtype=np.float64), xx, out)
    return out
