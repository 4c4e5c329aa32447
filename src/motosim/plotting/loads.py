"""The tyres' loads and slips of a run on the multibody motorcycle."""

import math

import numpy as np
from matplotlib.figure import Figure

from motosim.timeseries import TimeSeries

__all__ = ["plot_tyre_loads"]


def plot_tyre_loads(run: TimeSeries, *, title: str = "") -> Figure:
    """Normal loads, longitudinal forces, slips and pitch against time, both tyres.

    Parameters
    ----------
    run : TimeSeries
        A run's recorded signals (:data:`motosim.signals.RECORDED`): ``F_zr``, ``F_zf``,
        ``F_xr``, ``F_xf`` [N], ``kappa_r``, ``kappa_f`` [1], ``theta`` [rad], ``v_x`` [m/s].
    title : str
        Figure title.

    Returns
    -------
    Figure
        Four panels sharing the time axis [s]: the normal loads [N], the longitudinal forces
        [N] (< 0 braking), the longitudinal slips [-] and the pitch [deg] beside the speed
        [m/s].
    """
    fig = Figure(figsize=(8.0, 8.0), layout="constrained")
    ax_z, ax_x, ax_k, ax_p = fig.subplots(4, 1, sharex=True)
    t = run.t
    for wheel, suffix, style in (("rear", "r", "-"), ("front", "f", "--")):
        ax_z.plot(t, run[f"F_z{suffix}"], style, lw=1.0, label=wheel)
        ax_x.plot(t, run[f"F_x{suffix}"], style, lw=1.0, label=wheel)
        ax_k.plot(t, run[f"kappa_{suffix}"], style, lw=1.0, label=wheel)
    ax_z.set_ylabel("normal load F_z [N]")
    ax_x.set_ylabel("longitudinal F_x [N]")
    ax_k.set_ylabel("slip kappa [-]")
    ax_p.plot(t, np.degrees(run["theta"]), color="k", lw=1.0)
    ax_p.set_ylabel("pitch theta [deg]")
    speed = ax_p.twinx()
    speed.plot(t, run["v_x"], color="0.5", lw=1.0)
    speed.set_ylabel("speed v_x [m/s]", color="0.4")
    ax_p.set_xlabel("time t [s]")
    for ax in (ax_z, ax_x, ax_k):
        ax.legend(loc="best", fontsize="small")
        ax.grid(True, alpha=0.3)
    ax_p.grid(True, alpha=0.3)
    if title:
        fig.suptitle(title)
    top = float(np.max(np.abs(run["kappa_f"])))
    if math.isfinite(top) and top > 0.5:
        ax_k.set_ylim(-1.05, 0.2)
    return fig
