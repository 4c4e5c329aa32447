"""The linear regression of eq. (8), Phi p = N k_t i_m, built from a sampled log.

Only theta_h and i_m are measured (section II.D); theta_h' and theta_h'' come from a filtered
differentiation, here a zero-phase Savitzky-Golay filter: a least-squares polynomial of degree
3 fitted over a centred window, whose first and second derivatives are the estimates. It is
chosen because

* it is zero-phase (the window is centred), so the rows of Phi stay aligned in time with the
  current and with each other: a causal filter would delay theta'' more than theta' and bias
  J_eq, which is small and already hard to see at 100 Hz;
* it smooths the staircase of the encoder (quantisation) and the noise with one parameter,
  the window length, and is exact on cubic polynomials so a slow excitation passes unchanged;
* the current is smoothed by the same filter (degree 0 derivative), so both sides of eq. (8)
  see the same linear filter and the regression stays consistent (except for the sign term,
  a nonlinearity; rows at rest are dropped, where sign() is ill defined anyway).

Offline identification can afford non-causal filtering; the real-time differentiator of
:mod:`motosim.estimation` is a separate matter.

Data flow: ``model -> identification`` (pure functions of arrays).
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.signal import savgol_filter

from motosim.errors import MotosimError
from motosim.timeseries import TimeSeries

__all__ = [
    "MIN_SAMPLES",
    "Regression",
    "check_log",
    "differentiate",
    "regression",
    "sample_period",
]

Array = NDArray[np.float64]

MIN_SAMPLES = 50
"""Fewest samples in a log for identification."""

_POLYORDER = 3


def check_log(log: TimeSeries, columns: tuple[str, ...] = ("theta_h", "i_m")) -> None:
    """Check that a log can be identified from: columns, time grid, finite values, length.

    Parameters
    ----------
    log : TimeSeries
        The log.
    columns : tuple of str
        Columns that must be present.

    Raises
    ------
    MotosimError
        One line naming the problem: a missing column, a time that is not strictly
        increasing (a duplicated or backward sample), a NaN or infinite value, or fewer
        than :data:`MIN_SAMPLES` samples.
    """
    for name in columns:
        if name not in log.names:
            raise MotosimError(
                f"log has no column {name!r}; expected {', '.join(columns)} (have "
                f"{', '.join(log.names) or 'none'})"
            )
    if log.t.size < MIN_SAMPLES:
        raise MotosimError(
            f"log has {log.t.size} samples; expected at least {MIN_SAMPLES} to identify from"
        )
    if not np.all(np.isfinite(log.t)):
        raise MotosimError("log time t has a NaN or infinite sample; expected finite times [s]")
    dt = np.diff(log.t)
    if np.any(dt <= 0.0):
        k = int(np.argmax(dt <= 0.0))
        kind = "duplicated" if dt[k] == 0.0 else "decreasing"
        raise MotosimError(
            f"log time is {kind} at sample {k + 1} (t = {log.t[k + 1]:g} s); expected strictly "
            "increasing time"
        )
    for name in columns:
        bad = ~np.isfinite(log[name])
        if np.any(bad):
            k = int(np.argmax(bad))
            raise MotosimError(
                f"log column {name!r} is not finite at sample {k} (t = {log.t[k]:g} s); "
                "expected finite values"
            )


def sample_period(t: Array) -> float:
    """The sampling period of a uniform time grid [s].

    Raises
    ------
    MotosimError
        If the periods vary by more than 1 % (the filters assume uniform sampling).
    """
    dt = np.diff(t)
    h = float(np.median(dt))
    if np.max(np.abs(dt - h)) > 0.01 * h:
        raise MotosimError(
            f"log sampling periods span {dt.min():g}-{dt.max():g} s; expected uniform sampling "
            "(motosim.io.read_rig_log and motosim.io.resample put a log on a uniform grid)"
        )
    return h


def _window(window: float, h: float, n: int) -> int:
    if not (math.isfinite(window) and window > 0.0):
        raise MotosimError(f"window = {window!r}; expected a finite duration > 0 [s]")
    w = max(round(window / h) | 1, _POLYORDER + 2)  # odd, at least 5
    return min(w, n if n % 2 else n - 1)


def differentiate(x: Array, h: float, *, window: float = 0.1) -> tuple[Array, Array, Array]:
    """Zero-phase Savitzky-Golay smoothing and first and second derivatives.

    Parameters
    ----------
    x : ndarray, shape (n,)
        Uniformly sampled signal.
    h : float
        Sampling period [s].
    window : float
        Length of the centred fitting window [s]; rounded to an odd number of samples, at
        least 5. 0.1 s passes an excitation of a few hertz (the -3 dB point of a cubic fit
        over a window of length W is near 1.3 / W).

    Returns
    -------
    x, x_dot, x_ddot : ndarray, shape (n,)
        Smoothed signal and its first and second derivatives (per s and per s^2).

    Examples
    --------
    >>> t = np.arange(200) * 0.01
    >>> _, v, a = differentiate(t**2, 0.01)
    >>> bool(np.allclose(v, 2 * t) and np.allclose(a, 2.0))
    True
    """
    w = _window(window, h, x.size)
    smooth = savgol_filter(x, w, _POLYORDER, mode="interp")
    rate = savgol_filter(x, w, _POLYORDER, deriv=1, delta=h, mode="interp")
    accel = savgol_filter(x, w, _POLYORDER, deriv=2, delta=h, mode="interp")
    return smooth, rate, accel


@dataclass(frozen=True, slots=True)
class Regression:
    """Rows of eq. (8), Phi p = y with y = N k_t i_m, and which rows are used.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Sample times [s].
    Phi : ndarray, shape (n, 3)
        [theta_h'', theta_h', sign(theta_h')] per sample [rad/s^2, rad/s, 1].
    y : ndarray, shape (n,)
        N k_t i_m, the smoothed motor torque at the handlebar [N*m], centred on t_k: the
        average of the samples k-1 and k, since the drive holds each sample for one period.
    used : ndarray of bool, shape (n,)
        Rows away from the log ends and with the handlebar moving (|theta_h'| above the rest
        threshold): at rest the friction is anywhere in [-beta_s, beta_s] and eq. (8) does
        not hold.
    theta_h_dot : ndarray, shape (n,)
        The differentiated rate [rad/s], also the initial rate for simulations.
    torque_held : ndarray, shape (n,)
        N k_t i_m smoothed but not re-centred [N*m]: the torque held from t_k to t_k+1, for
        simulations.
    h : float
        Sampling period [s].
    """

    t: Array
    Phi: Array
    y: Array
    used: NDArray[np.bool_]
    theta_h_dot: Array
    torque_held: Array
    h: float


def regression(
    log: TimeSeries,
    *,
    torque_per_amp: float,
    window: float = 0.1,
    rest_fraction: float = 0.05,
) -> Regression:
    """Build the regression of eq. (8) from a log of theta_h and i_m.

    Parameters
    ----------
    log : TimeSeries
        Uniformly sampled columns ``theta_h`` [rad] and ``i_m`` [A].
    torque_per_amp : float
        N k_t [N*m/A], known (the paper: "J_m, beta_v,m, k_t and N are known").
    window : float
        Savitzky-Golay window [s], see :func:`differentiate`.
    rest_fraction : float
        Rows with |theta_h'| below this fraction of the RMS rate count as at rest and are not
        used.

    Returns
    -------
    Regression
        The rows.

    Raises
    ------
    MotosimError
        On a bad log (see :func:`check_log`), a non-uniform grid or a non-positive
        ``torque_per_amp``.
    """
    check_log(log)
    if not (math.isfinite(torque_per_amp) and torque_per_amp > 0.0):
        raise MotosimError(f"torque_per_amp = {torque_per_amp!r}; expected > 0 [N*m/A]")
    if not (math.isfinite(rest_fraction) and 0.0 <= rest_fraction < 1.0):
        raise MotosimError(f"rest_fraction = {rest_fraction!r}; expected in [0, 1)")
    h = sample_period(log.t)
    _, rate, accel = differentiate(log["theta_h"], h, window=window)
    w = _window(window, h, log.t.size)
    # the drive holds i_k over [t_k, t_k+1): centre it on t_k with a half-sample average
    held = savgol_filter(log["i_m"], w, _POLYORDER, mode="interp")
    current = held.copy()
    current[1:] = 0.5 * (held[1:] + held[:-1])
    # the same filter on sign(theta_h') keeps the three columns and y consistent
    direction = savgol_filter(np.sign(rate), w, _POLYORDER, mode="interp")
    Phi = np.column_stack([accel, rate, direction])
    rms = float(np.sqrt(np.mean(rate**2)))
    used = np.abs(rate) > rest_fraction * rms
    used[: w // 2] = False
    used[log.t.size - w // 2 :] = False
    return Regression(
        log.t.copy(), Phi, torque_per_amp * current, used, rate, torque_per_amp * held, h
    )
