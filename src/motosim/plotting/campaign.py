"""Figures of a campaign: a metric against each factor, a heat map, where runs failed.

The functions take plain arrays (one entry per run), so that they do not depend on how the
results were stored; :mod:`motosim.report.campaign` reads the results and calls them.
Non-numeric factors (booleans, strings) are drawn at the positions of their distinct values.
"""

from collections.abc import Mapping

import numpy as np
from matplotlib.figure import Figure
from numpy.typing import NDArray

__all__ = ["plot_failures", "plot_heatmap", "plot_metric_vs_factors"]


def _numeric(values: NDArray[np.generic]) -> tuple[NDArray[np.float64], list[str]]:
    """Positions of ``values`` and, for categories, their labels (empty for numbers)."""
    if values.dtype.kind in "iuf":
        return values.astype(np.float64), []
    labels = sorted({str(v) for v in values})
    return np.array([labels.index(str(v)) for v in values], dtype=np.float64), labels


def plot_metric_vs_factors(
    factors: Mapping[str, NDArray[np.generic]],
    metric: NDArray[np.float64],
    failed: NDArray[np.bool_],
    *,
    label: str,
) -> Figure:
    """One panel per factor: the metric of each run against the factor's value.

    Parameters
    ----------
    factors : Mapping of str to ndarray, each shape (n,)
        Each factor's value in each run.
    metric : ndarray, shape (n,)
        The metric of each run (NaN for failed runs).
    failed : ndarray of bool, shape (n,)
        Failed runs, drawn as red crosses (along the top of each panel when their metric is
        NaN).
    label : str
        The metric's name and unit.

    Returns
    -------
    matplotlib.figure.Figure
    """
    n = len(factors)
    cols = min(n, 3)
    rows = -(-n // cols)
    fig = Figure(figsize=(4.2 * cols, 3.2 * rows), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    finite = metric[np.isfinite(metric)]
    top = float(finite.max()) if finite.size else 1.0
    for ax, (name, values) in zip(axes, factors.items(), strict=False):
        x, labels = _numeric(values)
        ax.plot(x[~failed], metric[~failed], ".", ms=3, alpha=0.6, color="C0", label="ok")
        if failed.any():
            shown = np.where(np.isfinite(metric[failed]), metric[failed], top)
            ax.plot(x[failed], shown, "x", color="C3", label="failed")
        if labels:
            ax.set_xticks(range(len(labels)), labels)
        ax.set_xlabel(name)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    for ax in axes[n:]:
        ax.set_visible(False)
    if failed.any():
        axes[0].legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize="small", frameon=False)
    return fig


def plot_heatmap(
    x: NDArray[np.generic],
    y: NDArray[np.generic],
    z: NDArray[np.float64],
    *,
    xlabel: str,
    ylabel: str,
    zlabel: str,
    bins: int = 8,
) -> Figure:
    """The mean of ``z`` over a grid of bins of ``x`` and ``y`` (NaN values left out).

    Returns
    -------
    matplotlib.figure.Figure
    """
    xs, _ = _numeric(x)
    ys, _ = _numeric(y)
    ok = np.isfinite(z)
    fig = Figure(figsize=(5.5, 4.2), layout="constrained")
    ax = fig.subplots()
    x_edges = np.linspace(xs.min(), xs.max() + 1e-12, bins + 1)
    y_edges = np.linspace(ys.min(), ys.max() + 1e-12, bins + 1)
    total, _, _ = np.histogram2d(xs[ok], ys[ok], bins=(x_edges, y_edges), weights=z[ok])
    count, _, _ = np.histogram2d(xs[ok], ys[ok], bins=(x_edges, y_edges))
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(count > 0, total / np.maximum(count, 1), np.nan)
    mesh = ax.pcolormesh(x_edges, y_edges, mean.T, cmap="viridis")
    fig.colorbar(mesh, ax=ax, label=f"mean {zlabel}")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    return fig


def plot_failures(
    x: NDArray[np.generic],
    y: NDArray[np.generic],
    failed: NDArray[np.bool_],
    *,
    xlabel: str,
    ylabel: str,
) -> Figure:
    """Every run in the plane of two factors, the failed ones in red: the failure region.

    Returns
    -------
    matplotlib.figure.Figure
    """
    xs, x_labels = _numeric(x)
    ys, y_labels = _numeric(y)
    fig = Figure(figsize=(5.5, 4.2), layout="constrained")
    ax = fig.subplots()
    ax.plot(xs[~failed], ys[~failed], ".", ms=3, color="0.6", label="ok")
    ax.plot(xs[failed], ys[failed], "x", color="C3", label=f"failed ({int(failed.sum())})")
    if x_labels:
        ax.set_xticks(range(len(x_labels)), x_labels)
    if y_labels:
        ax.set_yticks(range(len(y_labels)), y_labels)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize="small", frameon=False)
    return fig
