"""Rider torque against its estimate (Figs. 11 and 14 of the paper)."""

from collections.abc import Mapping
from typing import Protocol

import numpy as np
from matplotlib.figure import Figure
from numpy.typing import NDArray

__all__ = ["plot_torque_estimates"]


class _Run(Protocol):
    t: NDArray[np.float64]
    tau_r: NDArray[np.float64]
    tau_r_hat: NDArray[np.float64]


def plot_torque_estimates(
    runs: Mapping[str, _Run], *, title: str = "Rider torque and its estimate"
) -> Figure:
    """One panel per run: the true rider torque and the estimate [N*m] against time [s].

    Parameters
    ----------
    runs : Mapping of str to run
        Label to an object with arrays ``t``, ``tau_r`` and ``tau_r_hat`` (for example
        :class:`motosim.estimation.study.Outcome`).
    title : str
        Figure title.

    Returns
    -------
    Figure
    """
    fig = Figure(figsize=(9.0, 2.2 * len(runs) + 0.8), layout="constrained")
    axes = np.atleast_1d(fig.subplots(len(runs), 1, sharex=True))
    for ax, (label, run) in zip(axes, runs.items(), strict=True):
        ax.plot(run.t, run.tau_r, color="k", lw=1.0, label="tau_r")
        ax.plot(run.t, run.tau_r_hat, color="tab:red", lw=1.0, ls="--", label="estimate")
        ax.set_ylabel("rider torque [N m]")
        ax.set_title(label, fontsize=9)
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8, frameon=False)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(title)
    return fig
