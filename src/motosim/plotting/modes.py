"""Capsize, weave and wobble against speed."""

from collections.abc import Mapping

import numpy as np
from matplotlib.figure import Figure

from motosim.errors import MotosimError
from motosim.model.sharp import MODE_NAMES, ModeTable

__all__ = ["plot_mode_comparison", "plot_modes"]

_COLOURS = {"capsize": "tab:blue", "weave": "tab:orange", "wobble": "tab:green"}


def _unstable_spans(speeds: np.ndarray, unstable: np.ndarray) -> list[tuple[float, float]]:
    spans = []
    start = None
    for s, flag in zip(speeds, unstable, strict=True):
        if flag and start is None:
            start = s
        if not flag and start is not None:
            spans.append((float(start), float(s)))
            start = None
    if start is not None:
        spans.append((float(start), float(speeds[-1])))
    return spans


def plot_modes(table: ModeTable, *, title: str = "") -> Figure:
    """Real part and frequency of the three modes against speed, unstable ranges shaded.

    Parameters
    ----------
    table : ModeTable
        From :func:`motosim.model.sharp.modes` or :func:`motosim.model.tyred.lateral_modes`.
    title : str
        Figure title.

    Returns
    -------
    Figure
        Two panels sharing the speed axis [m/s].
    """
    order = np.argsort(table.speeds)
    v = table.speeds[order]
    fig = Figure(figsize=(8.0, 6.5), layout="constrained")
    ax_re, ax_f = fig.subplots(2, 1, sharex=True)
    ax_re.scatter(
        np.repeat(v, table.eigenvalues.shape[1]),
        table.eigenvalues[order].real.ravel(),
        s=2,
        color="0.8",
        label="all eigenvalues",
    )
    for name in MODE_NAMES:
        values = table.mode(name)[order]
        unstable = values.real > 0
        ax_re.plot(v, values.real, color=_COLOURS[name], label=name)
        if name != "capsize":
            ax_f.plot(v, ModeTable.frequency_hz(values), color=_COLOURS[name], label=name)
        for lo, hi in _unstable_spans(v, unstable):
            for ax in (ax_re, ax_f):
                ax.axvspan(lo, hi, color=_COLOURS[name], alpha=0.12, lw=0)
            # in a band above every curve (the axis' top fifth, kept free below), not on the
            # zero line the unstable mode's curve crosses
            ax_re.text(
                (lo + hi) / 2,
                0.97,
                f"{name} unstable",
                transform=ax_re.get_xaxis_transform(),
                ha="center",
                va="top",
                fontsize=8,
                color=_COLOURS[name],
            )
    lowest = min(float(np.min(table.mode(n).real)) for n in MODE_NAMES)
    highest = max(float(np.max(table.mode(n).real)) for n in MODE_NAMES)
    bottom, top = min(1.25 * lowest, -1.0), max(1.25 * highest, 1.0)
    ax_re.set_ylim(bottom, top + 0.15 * (top - bottom))
    ax_re.axhline(0.0, color="k", lw=0.8)
    ax_re.set_ylabel("real part of the eigenvalue [1/s]")
    ax_f.set_ylabel("mode frequency [Hz]")
    ax_f.set_xlabel("forward speed [m/s]")
    for ax in (ax_re, ax_f):  # beside the axes, off the curves
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    for ax in (ax_re, ax_f):
        ax.grid(True, alpha=0.3)
    fig.suptitle(title or "Sharp (1971) motorcycle: modes against speed (shaded: unstable)")
    return fig


_STYLES = ("-", "--", ":", "-.")


def plot_mode_comparison(tables: Mapping[str, ModeTable], *, title: str = "") -> Figure:
    """The three modes of several models against speed, one line style per model.

    Parameters
    ----------
    tables : mapping of str to ModeTable
        Each model's modes (:func:`motosim.model.sharp.modes`,
        :func:`motosim.model.tyred.lateral_modes`, ...), by the name the legend shows; at most
        four.
    title : str
        Figure title.

    Returns
    -------
    Figure
        Two panels sharing the speed axis [m/s]: the real parts (above zero: unstable) and the
        weave's and wobble's frequencies [Hz].

    Raises
    ------
    MotosimError
        If there is no table or more than four.
    """
    if not 1 <= len(tables) <= len(_STYLES):
        raise MotosimError(f"mode comparison of {len(tables)} tables; expected 1 to {len(_STYLES)}")
    fig = Figure(figsize=(8.0, 6.5), layout="constrained")
    ax_re, ax_f = fig.subplots(2, 1, sharex=True)
    for style, (label, table) in zip(_STYLES, tables.items(), strict=False):
        order = np.argsort(table.speeds)
        v = table.speeds[order]
        for name in MODE_NAMES:
            values = table.mode(name)[order]
            ax_re.plot(v, values.real, ls=style, color=_COLOURS[name], label=f"{name}, {label}")
            if name != "capsize":
                ax_f.plot(
                    v,
                    ModeTable.frequency_hz(values),
                    ls=style,
                    color=_COLOURS[name],
                    label=f"{name}, {label}",
                )
    ax_re.axhline(0.0, color="k", lw=0.8)
    ax_re.set_ylabel("real part of the eigenvalue [1/s]")
    ax_f.set_ylabel("mode frequency [Hz]")
    ax_f.set_xlabel("forward speed [m/s]")
    for ax in (ax_re, ax_f):
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
        ax.grid(True, alpha=0.3)
    fig.suptitle(title or "Modes against speed (above zero: unstable)")
    return fig
