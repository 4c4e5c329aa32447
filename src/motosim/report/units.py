"""How a run's summary numbers are shown to a person: degrees, per cent, the unit written.

A run's summary (:func:`motosim.sim.metrics.run_metrics`) is SI, and stays SI in its files
and in every ``--json``; where a person reads it (the HTML reports, the paper's index, the
lines ``motosim simulate`` and ``motosim campaign --rerun`` print) each number is shown by
:func:`shown`: angles in degrees, shares in per cent, counts as integers, flags as yes or no,
each with its unit written.
"""

import math
from typing import NamedTuple

__all__ = ["METRICS", "Metric", "shown", "summary_lines"]

_DEG = 180.0 / math.pi


class Metric(NamedTuple):
    """How one summary number is shown."""

    label: str
    """What it is, in words."""
    unit: str
    """Its SI unit in the files ("" for a ratio or a count)."""
    scale: float
    """Shown value = scale * stored SI value."""
    display_unit: str
    """The unit shown ("" for a count or a flag)."""
    kind: str = "number"
    """``number``, ``count`` (an integer) or ``flag`` (1 or 0, shown as yes or no)."""


METRICS: dict[str, Metric] = {
    "duration": Metric("duration", "s", 1.0, "s"),
    "samples": Metric("recorded instants", "", 1.0, "", "count"),
    "complete": Metric("run complete", "", 1.0, "", "flag"),
    "rms_tau_r_error": Metric("RMS of tau_r_hat - tau_r", "N*m", 1.0, "N*m"),
    "rms_tracking_error": Metric("RMS of theta_h - delta", "rad", _DEG, "deg"),
    "rms_rate_error": Metric("RMS of theta_h_dot_hat - theta_h_dot", "rad/s", _DEG, "deg/s"),
    "max_abs_phi": Metric("max |phi| (roll)", "rad", _DEG, "deg"),
    "max_abs_e_y": Metric("max |e_y| (lateral path error)", "m", 1.0, "m"),
    "min_speed": Metric("lowest speed", "m/s", 1.0, "m/s"),
    "max_speed": Metric("highest speed", "m/s", 1.0, "m/s"),
    "peak_steer": Metric("peak |delta| (steer angle)", "rad", _DEG, "deg"),
    "tracking_rms_fraction": Metric("RMS of theta_h - delta / peak steer", "", 100.0, "%"),
    "tracking_peak_fraction": Metric("max |theta_h - delta| / peak steer", "", 100.0, "%"),
    "peak_rider_torque": Metric("peak |tau_r|", "N*m", 1.0, "N*m"),
    "estimate_rms_fraction": Metric("RMS of tau_r_hat - tau_r / peak |tau_r|", "", 100.0, "%"),
    "stick_share": Metric("time with the handlebar sticking", "", 100.0, "%"),
    "rms_tau_r_error_moving": Metric("RMS of tau_r_hat - tau_r outside stick", "N*m", 1.0, "N*m"),
    "buzz_current_p2p": Metric("current above 3 Hz, last 2 s, peak to peak", "A", 1.0, "A"),
    "buzz_frequency": Metric("its strongest frequency", "Hz", 1.0, "Hz"),
    "saturated_share": Metric("time at the current limit", "", 100.0, "%"),
    "max_abs_tau_r_error": Metric("max |tau_r_hat - tau_r|", "N*m", 1.0, "N*m"),
    "max_abs_tracking_error": Metric("max |theta_h - delta|", "rad", _DEG, "deg"),
    "max_abs_i_m": Metric("max |i_m| (motor current)", "A", 1.0, "A"),
    "failed_at": Metric("time of the failure", "s", 1.0, "s"),
    "elapsed": Metric("computing time", "s", 1.0, "s"),
    "flag_oscillation": Metric("sustained current buzz above 3 Hz", "", 1.0, "", "flag"),
    "flag_saturation": Metric("at the current limit over half the time", "", 1.0, "", "flag"),
    "flag_fall": Metric("the motorcycle fell (roll beyond 45 deg)", "", 1.0, "", "flag"),
    "flag_out_of_range": Metric("the speed left 3-60 m/s", "", 1.0, "", "flag"),
}
"""Summary key -> how it is shown; keys not listed are shown as stored, without a unit."""


def shown(key: str, value: object) -> tuple[str, str]:
    """``value`` of summary ``key`` as a person reads it: (text, unit).

    Parameters
    ----------
    key : str
        A key of a run's summary (:data:`METRICS`; another is shown as stored).
    value : object
        Its stored value, SI.

    Returns
    -------
    tuple of str
        The value's text (4 significant digits, a count as an integer, a flag as yes or no)
        and its unit ("" where it has none).

    Examples
    --------
    >>> shown("rms_tracking_error", 0.0006569)
    ('0.03764', 'deg')
    >>> shown("samples", 1e4), shown("flag_fall", 0.0), shown("speed_gain", 2.0)
    (('10000', ''), ('no', ''), ('2', ''))
    """
    info = METRICS.get(key)
    if isinstance(value, bool) or not isinstance(value, int | float):
        return str(value), ""
    if not math.isfinite(value):
        return str(value), info.display_unit if info is not None else ""
    if info is None:
        return (str(value) if isinstance(value, int) else f"{value:.4g}"), ""
    if info.kind == "flag":
        return ("yes" if value else "no"), ""
    if info.kind == "count":
        return str(round(value)), ""
    return f"{info.scale * value:.4g}", info.display_unit


def summary_lines(summary: dict[str, object], *, indent: str = "  ") -> list[str]:
    """One line per summary number, ``key value unit``, as ``motosim simulate`` prints them.

    Examples
    --------
    >>> summary_lines({"samples": 10000.0, "max_abs_phi": 0.2322})
    ['  samples                          10000', '  max_abs_phi                      13.3 deg']
    """
    lines = []
    for key, value in summary.items():
        text, unit = shown(key, value)
        lines.append(f"{indent}{key:<32} {text}" + (f" {unit}" if unit else ""))
    return lines
