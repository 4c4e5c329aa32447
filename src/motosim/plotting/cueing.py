"""Motion cueing: what the rider would perceive on the motorcycle and on the platform."""

import math

from matplotlib.figure import Figure

from motosim.cueing.pipeline import CueingRun
from motosim.cueing.vestibular import CHANNELS

__all__ = ["plot_commands", "plot_perception"]

_LABELS = {
    "roll": ("perceived roll rate", "deg/s", 180 / math.pi),
    "pitch": ("perceived pitch rate", "deg/s", 180 / math.pi),
    "yaw": ("perceived yaw rate", "deg/s", 180 / math.pi),
    "surge": ("perceived longitudinal force", "m/s^2", 1.0),
    "sway": ("perceived lateral force", "m/s^2", 1.0),
}


def plot_perception(run: CueingRun, *, thresholds: tuple[float, ...], title: str = "") -> Figure:
    """Perceived motion, vehicle against platform, one panel per vestibular channel.

    Parameters
    ----------
    run : CueingRun
        From :func:`motosim.cueing.cue`.
    thresholds : tuple of float
        Perception thresholds of :data:`~motosim.cueing.vestibular.CHANNELS` (SI), drawn as
        a grey band.
    title : str, optional
        Figure title.

    Returns
    -------
    Figure
    """
    fig = Figure(figsize=(9.0, 10.0), layout="constrained")
    axes = fig.subplots(len(CHANNELS), 1, sharex=True)
    t = run.perceived_vehicle.t
    for ax, name, thr in zip(axes, CHANNELS, thresholds, strict=True):
        label, unit, scale = _LABELS[name]
        ax.axhspan(-thr * scale, thr * scale, color="0.9", lw=0)
        ax.plot(t, run.perceived_vehicle[name] * scale, color="k", lw=1.0, label="motorcycle")
        ax.plot(
            t,
            run.perceived_platform[name] * scale,
            color="tab:red",
            lw=1.0,
            label=f"platform ({run.algorithm})",
        )
        cs = run.score.channels[name]
        ax.set_ylabel(f"{name} [{unit}]")
        ax.set_title(
            f"{label}: false cues {100 * cs.false_cue_share:.1f} %, missing "
            f"{100 * cs.missing_cue_share:.1f} %",
            fontsize=9,
            loc="left",
        )
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8, frameon=False)
    axes[-1].set_xlabel("t [s]")
    if title:
        fig.suptitle(title)
    return fig


def plot_commands(run: CueingRun, *, limits: tuple[float, float, float], title: str = "") -> Figure:
    """Platform commands and their angle limits, with the visual-horizon roll.

    Parameters
    ----------
    run : CueingRun
        From :func:`motosim.cueing.cue`.
    limits : tuple of float
        Roll, pitch, yaw angle limits [rad].
    title : str, optional
        Figure title.

    Returns
    -------
    Figure
    """
    fig = Figure(figsize=(9.0, 6.5), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    t = run.commands.t
    deg = 180 / math.pi
    for ax, name, limit in zip(axes, ("phi_s", "theta_s", "psi_s"), limits, strict=True):
        ax.plot(t, run.commands[name] * deg, color="tab:red", lw=1.0, label=name)
        ax.axhline(limit * deg, color="0.5", ls=":", lw=1.0)
        ax.axhline(-limit * deg, color="0.5", ls=":", lw=1.0)
        ax.set_ylabel(f"{name} [deg]")
        ax.grid(alpha=0.3)
    axes[0].plot(t, run.commands["phi_vis"] * deg, color="tab:blue", lw=1.0, label="phi_vis")
    axes[1].plot(t, run.vehicle["theta"] * deg, color="k", lw=0.8, label="motorcycle pitch")
    for ax in axes[:2]:
        ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8, frameon=False)
    axes[-1].set_xlabel("t [s]")
    if title:
        fig.suptitle(title)
    return fig
