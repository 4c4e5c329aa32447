"""Identification figure: the fit, the validation replay, the input, the residual (Figs. 4-5)."""

from typing import Protocol

import numpy as np
from matplotlib.figure import Figure
from numpy.typing import NDArray

__all__ = ["plot_identification"]

Array = NDArray[np.float64]

_NAMES = ("J_eq", "beta_eq", "beta_s")
_UNITS = ("kg m^2", "N m s/rad", "N m")


class Replay(Protocol):
    """A model replayed on a log (:class:`motosim.identification.Validation`)."""

    @property
    def nrmse(self) -> float:
        """Normalised RMS error of the replay."""

    @property
    def t(self) -> Array:
        """Sample times [s]."""

    @property
    def theta_h(self) -> Array:
        """Simulated angle [rad]."""

    @property
    def theta_h_measured(self) -> Array:
        """Measured angle [rad]."""

    @property
    def current(self) -> Array:
        """Input current [A]."""


def _parameters(estimate: Array, confidence: Array | None) -> str:
    parts = []
    for k, (name, unit) in enumerate(zip(_NAMES, _UNITS, strict=True)):
        text = f"{name} = {estimate[k]:.4g} {unit}"
        if confidence is not None:
            half = 0.5 * (confidence[k, 1] - confidence[k, 0])
            text = f"{name} = {estimate[k]:.4g} +/- {half:.2g} {unit}"
        parts.append(text)
    suffix = " (95 % intervals)" if confidence is not None else ""
    return ", ".join(parts) + suffix


def plot_identification(
    *,
    fit: Replay,
    estimate: Array,
    validation: Replay | None = None,
    confidence: Array | None = None,
    history_t: Array | None = None,
    history: Array | None = None,
    title: str = "",
) -> Figure:
    """The identified model against the measured angle, on the fit log and on validation.

    Columns: the identification log, then the validation log if given. Rows: measured and
    simulated angle, the residual (simulated - measured), the input current; for the
    adaptive methods a last row with the estimates over adaptation time. The title gives
    the parameters with units and 95 % intervals; each angle panel gives its NRMSE,
    ||simulated - measured|| / ||measured - mean(measured)|| over one open-loop replay.

    Parameters
    ----------
    fit : Replay
        The model replayed on the identification log.
    estimate : ndarray, shape (3,)
        J_eq [kg*m^2], beta_eq [N*m*s/rad], beta_s [N*m].
    validation : Replay, optional
        The model replayed on a second log.
    confidence : ndarray, shape (3, 2), optional
        95 % intervals of the estimate.
    history_t, history : ndarray, shapes (m,) and (m, 3), optional
        Estimates after each update, for the adaptive methods.
    title : str
        First line of the title.

    Returns
    -------
    Figure
    """
    replays = [("identification log", fit)]
    if validation is not None:
        replays.append(("validation log", validation))
    adaptive = history is not None and history_t is not None
    rows = 4 if adaptive else 3
    fig = Figure(figsize=(5.0 * len(replays) + 2.0, 2.3 * rows + 1.0), layout="constrained")
    grid = fig.add_gridspec(rows, len(replays) * 3, height_ratios=[2.0, 1.0, 1.0, 1.2][:rows])
    for c, (label, replay) in enumerate(replays):
        cols = slice(3 * c, 3 * c + 3)
        ax = fig.add_subplot(grid[0, cols])
        measured, model = np.rad2deg(replay.theta_h_measured), np.rad2deg(replay.theta_h)
        ax.plot(replay.t, measured, color="k", lw=1.0, label="measured")
        ax.plot(replay.t, model, color="tab:red", lw=1.0, ls="--", label="model")
        ax.set_title(f"{label}: NRMSE {replay.nrmse:.3f}", fontsize=9, loc="left")
        ax.set_ylabel("handlebar angle theta_h [deg]")
        ax.legend(
            loc="lower right",
            bbox_to_anchor=(1.0, 1.0),
            ncols=2,
            fontsize=8,
            frameon=False,
            borderaxespad=0.2,
        )
        ax.grid(True, alpha=0.3)
        err = fig.add_subplot(grid[1, cols], sharex=ax)
        err.plot(replay.t, model - measured, color="tab:red", lw=0.8)
        err.set_ylabel("model - measured [deg]")
        err.grid(True, alpha=0.3)
        inp = fig.add_subplot(grid[2, cols], sharex=ax)
        inp.plot(replay.t, replay.current, color="tab:blue", lw=0.8)
        inp.set_ylabel("motor current i_m [A]")
        inp.set_xlabel("time [s]")
        inp.grid(True, alpha=0.3)
    if history is not None and history_t is not None:
        width = len(replays)
        for k, (name, unit) in enumerate(zip(_NAMES, _UNITS, strict=True)):
            axk = fig.add_subplot(grid[3, k * width : (k + 1) * width])
            axk.plot(history_t, history[:, k], color="tab:blue", lw=1.0)
            axk.axhline(estimate[k], color="tab:red", ls="--", lw=1.0)
            axk.set_xlabel("adaptation time [s]")
            axk.set_title(f"{name} [{unit}]", fontsize=9)
            axk.grid(True, alpha=0.3)
    fig.suptitle(
        f"{title or 'Handlebar identification'}\n{_parameters(estimate, confidence)}", fontsize=10
    )
    return fig
