"""Summary numbers of a closed-loop run, computed from its recorded signals.

Free of plotting and of files: the simulator, the report, the real-time loop and campaigns
all summarise runs with :func:`run_metrics`.
"""

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

__all__ = ["run_metrics"]

Array = NDArray[np.float64]


def _rms(values: Array) -> float:
    return float(np.sqrt(np.mean(np.square(values))))


def run_metrics(
    t: Array, signal: Callable[[str], Array | None], *, complete: bool
) -> dict[str, float]:
    """Summary numbers of a run, in SI units.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Time [s].
    signal : callable
        ``signal(name)`` returns the recorded column ``name`` (shape (n,)), or None when
        the run did not record it.
    complete : bool
        Whether the run reached its end.

    Returns
    -------
    dict of str to float
        Always ``duration`` [s] (last minus first time), ``samples`` and ``complete`` (1.0 or
        0.0); when the run has at least one instant and the signals they need:
        ``rms_tau_r_error`` [N*m] (RMS of ``tau_r_hat - tau_r``), ``rms_tracking_error`` [rad]
        (RMS of ``theta_h - delta``), ``rms_rate_error`` [rad/s] (RMS of
        ``theta_h_dot_hat - theta_h_dot``), ``max_abs_phi`` [rad], ``max_abs_e_y`` [m].

    Examples
    --------
    >>> cols = {"phi": np.array([0.2, 0.0])}
    >>> m = run_metrics(np.array([0.0, 1.0]), cols.get, complete=False)
    >>> m["duration"], m["complete"], round(m["max_abs_phi"], 3)
    (1.0, 0.0, 0.2)
    """
    out = {
        "duration": float(t[-1] - t[0]) if t.size else 0.0,
        "samples": float(t.size),
        "complete": 1.0 if complete else 0.0,
    }
    if t.size == 0:
        return out
    differences = {
        "rms_tau_r_error": ("tau_r_hat", "tau_r"),
        "rms_tracking_error": ("theta_h", "delta"),
        "rms_rate_error": ("theta_h_dot_hat", "theta_h_dot"),
    }
    for key, (estimate_name, truth_name) in differences.items():
        estimate, truth = signal(estimate_name), signal(truth_name)
        if estimate is not None and truth is not None:
            out[key] = _rms(estimate - truth)
    for key, name in (("max_abs_phi", "phi"), ("max_abs_e_y", "e_y")):
        values = signal(name)
        if values is not None:
            out[key] = float(np.max(np.abs(values)))
    return out
