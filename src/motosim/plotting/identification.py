"""Identification figures: parameter convergence and the validation overlay (Figs. 4-5)."""

import numpy as np
from matplotlib.figure import Figure
from numpy.typing import NDArray

__all__ = ["plot_identification"]

_NAMES = ("J_eq [kg m^2]", "beta_eq [N m s/rad]", "beta_s [N m]")


def plot_identification(
    *,
    t: NDArray[np.float64],
    measured: NDArray[np.float64],
    simulated: NDArray[np.float64],
    estimate: NDArray[np.float64],
    history_t: NDArray[np.float64] | None = None,
    history: NDArray[np.float64] | None = None,
    title: str = "",
) -> Figure:
    """Measured against simulated angle, and the estimates over adaptation time.

    Parameters
    ----------
    t, measured, simulated : ndarray, shape (n,)
        Time [s], measured and replayed handlebar angle [rad].
    estimate : ndarray, shape (3,)
        Final J_eq, beta_eq, beta_s.
    history_t, history : ndarray, shapes (m,) and (m, 3), optional
        Estimates after each update, for the adaptive methods.
    title : str
        Figure title.

    Returns
    -------
    Figure
    """
    adaptive = history is not None and history_t is not None
    fig = Figure(figsize=(9.0, 7.5 if adaptive else 5.5), layout="constrained")
    grid = fig.add_gridspec(
        3 if adaptive else 2, 3, height_ratios=[2.0, 1.0, 1.2][: 3 if adaptive else 2]
    )
    ax = fig.add_subplot(grid[0, :])
    ax.plot(t, measured, color="k", lw=1.0, label="measured")
    ax.plot(t, simulated, color="tab:red", lw=1.0, ls="--", label="identified model")
    ax.set_ylabel("theta_h [rad]")
    ax.legend(loc="upper right")
    ax.grid(True, alpha=0.3)
    err = fig.add_subplot(grid[1, :], sharex=ax)
    err.plot(t, simulated - measured, color="tab:red", lw=0.8)
    err.set_ylabel("error [rad]")
    err.grid(True, alpha=0.3)
    err.set_xlabel("time [s]")
    if history is not None and history_t is not None:
        for k, name in enumerate(_NAMES):
            axk = fig.add_subplot(grid[2, k])
            axk.plot(history_t, history[:, k], color="tab:blue", lw=1.0)
            axk.axhline(estimate[k], color="tab:red", ls="--", lw=1.0)
            axk.set_xlabel("adaptation time [s]")
            axk.set_title(f"{name} = {estimate[k]:.4g}", fontsize=9)
            axk.grid(True, alpha=0.3)
    summary = ", ".join(f"{n.split()[0]} = {v:.4g}" for n, v in zip(_NAMES, estimate, strict=True))
    fig.suptitle(f"{title or 'Handlebar identification'}\n{summary}", fontsize=10)
    return fig
