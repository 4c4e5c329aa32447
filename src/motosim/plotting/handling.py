"""The handling figure: the rider's steer torque and the roll against lateral acceleration."""

import math
from collections.abc import Mapping, Sequence

from matplotlib.figure import Figure

from motosim.model.trim import Trim

__all__ = ["plot_handling"]


def plot_handling(curves: Mapping[float, Sequence[Trim]], *, title: str = "") -> Figure:
    """Steer torque and roll of steady turns against lateral acceleration, one line a speed.

    Parameters
    ----------
    curves : mapping of float to sequence of Trim
        Per speed [m/s], its steady turns in increasing lateral acceleration
        (:func:`motosim.model.trim.handling_curve`).
    title : str
        Figure title.

    Returns
    -------
    Figure
        Two panels sharing the lateral acceleration axis [g]: the steer torque tau_r [N*m]
        and the roll [deg], the kinematic roll atan(a_y / g) dashed.
    """
    fig = Figure(figsize=(8.0, 6.5), layout="constrained")
    ax_tau, ax_phi = fig.subplots(2, 1, sharex=True)
    top = 0.0
    for speed, turns in sorted(curves.items()):
        if not turns:
            continue
        a = [t.lateral_g for t in turns]
        top = max(top, a[-1])
        ax_tau.plot(a, [t.tau_r for t in turns], marker="o", ms=3, label=f"{speed:g} m/s")
        ax_phi.plot(
            a, [math.degrees(t.phi) for t in turns], marker="o", ms=3, label=f"{speed:g} m/s"
        )
    if top > 0.0:
        grid = [top * k / 50 for k in range(51)]
        ax_phi.plot(
            grid,
            [math.degrees(math.atan(x)) for x in grid],
            "k--",
            lw=1,
            label="kinematic roll atan(a_y / g)",
        )
    ax_tau.axhline(0.0, color="0.6", lw=0.8)
    ax_tau.set_ylabel("rider's steer torque tau_r [N m]")
    ax_phi.set_ylabel("roll phi [deg]")
    ax_phi.set_xlabel("lateral acceleration a_y [g]")
    ax_tau.legend(title="speed")
    ax_phi.legend()
    for ax in (ax_tau, ax_phi):
        ax.grid(True, alpha=0.3)
    if title:
        fig.suptitle(title)
    return fig
