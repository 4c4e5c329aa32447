"""Figures of closed-loop runs, drawn from a :class:`motosim.io.results.SimResult`.

Each function draws the columns of its figure that the result has, and raises
:class:`motosim.errors.MotosimError` when it has none of them. Angles are stored in radians
and shown in degrees; every axis names its unit.

The figures of a run's report (:data:`motosim.report.figures.FIGURES`) place their axes at
fixed margins (:func:`_fixed_grid`), not by a layout engine: matplotlib's constrained layout
measures every tick label and text of a figure before it draws it, which costs more than
drawing it.
"""

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.gridspec import GridSpec
from matplotlib.ticker import FuncFormatter, NullLocator, ScalarFormatter
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.io.results import SimResult
from motosim.signals import SIGNALS

__all__ = [
    "plot_comparison",
    "plot_feel",
    "plot_motor_torque",
    "plot_motorcycle",
    "plot_rate",
    "plot_spectrum",
    "plot_torque",
    "plot_tracking",
]

_EXTRA_UNITS = {"e_y": "m"}
_LABELS = {
    "tau_r": "rider torque tau_r",
    "tau_r_hat": "estimate tau_r_hat",
    "tau_m": "motor torque tau_m = N k_t i_m",
    "theta_h": "handlebar theta_h",
    "delta": "virtual steer delta (reference)",
    "theta_h_dot": "true rate theta_h_dot",
    "theta_h_dot_hat": "differentiator theta_h_dot_hat",
}
_QUANTITIES = {
    "tau_r": "rider torque",
    "tau_r_hat": "rider torque",
    "theta_h": "handlebar and steer angle",
    "delta": "handlebar and steer angle",
    "theta_h_dot": "handlebar rate",
    "theta_h_dot_hat": "handlebar rate",
}
_STYLES: dict[str, dict[str, Any]] = {
    "tau_r": {"color": "k", "lw": 1.0},
    "theta_h": {"color": "k", "lw": 1.0},
    "theta_h_dot": {"color": "k", "lw": 1.0},
    "tau_r_hat": {"color": "tab:red", "lw": 1.0, "ls": "--"},
    "delta": {"color": "tab:blue", "lw": 1.0, "ls": "--"},
    "theta_h_dot_hat": {"color": "tab:red", "lw": 1.0, "ls": "--"},
    "tau_m": {"color": "tab:green", "lw": 1.0},
}


# Fixed margins and gaps around the report figures' axes [in], sized for the texts they
# hold at matplotlib's default font sizes: on the left of an axes its y tick labels (up to
# seven characters) and its y label; below, the x tick labels and the x label; above, the
# figure's title, and a row of legend above the axes (8 pt) where there is one.
_LEFT = 1.0
_RIGHT = 0.25
_BOTTOM = 0.6
_TITLE = 0.45
_LEGEND_ROW = 0.2
_TICKS_BELOW = 0.35


def _fixed_grid(
    fig: Figure,
    rows: int,
    columns: int,
    *,
    top: float = _TITLE,
    bottom: float = _BOTTOM,
    left: float = _LEFT,
    right: float = _RIGHT,
    wgap: float = _LEFT,
    hgap: float = _TICKS_BELOW,
    **ratios: Any,
) -> GridSpec:
    """A grid of ``rows`` x ``columns`` axes at fixed margins and gaps [in].

    Parameters
    ----------
    fig : Figure
        A figure without a layout engine, its size set.
    rows, columns : int
        The grid's shape.
    top, bottom, left, right : float
        The margins between the grid and the figure's edges [in].
    wgap, hgap : float
        The gaps between two columns and between two rows of axes [in].
    **ratios
        ``width_ratios`` and ``height_ratios`` of :meth:`matplotlib.figure.Figure.add_gridspec`.

    Returns
    -------
    GridSpec
    """
    width, height = fig.get_size_inches()
    # matplotlib's wspace and hspace are fractions of the mean axes width and height
    mean_width = (width - left - right - wgap * (columns - 1)) / columns
    mean_height = (height - top - bottom - hgap * (rows - 1)) / rows
    return fig.add_gridspec(
        rows,
        columns,
        left=left / width,
        right=1.0 - right / width,
        bottom=bottom / height,
        top=1.0 - top / height,
        wspace=wgap / mean_width,
        hspace=hgap / mean_height,
        **ratios,
    )


def _unit(name: str) -> str:
    if name in SIGNALS:
        return SIGNALS[name].unit
    return _EXTRA_UNITS.get(name, "")


def _display(name: str, values: NDArray[np.float64]) -> tuple[NDArray[np.float64], str]:
    """Values and unit label for display: radians become degrees."""
    unit = _unit(name)
    if unit.startswith("rad"):
        return np.rad2deg(values), "deg" + unit[3:]
    return values, unit.replace("*", " ")


def _present(result: SimResult, names: Sequence[str], figure: str) -> list[str]:
    """The names the result has; an error when it has none."""
    have = [n for n in names if n in result]
    if not have:
        raise MotosimError(
            f"{figure}: the result has none of the signals {', '.join(names)}; "
            f"it has {', '.join(result.names) or 'none'}"
        )
    return have


def _legend_above(ax: Axes, *, columns: int = 3, fontsize: float = 8) -> None:
    """The legend in a row above the axes, off the data."""
    ax.legend(
        loc="lower left",
        bbox_to_anchor=(0.0, 1.0),
        ncols=columns,
        fontsize=fontsize,
        frameon=False,
        borderaxespad=0.2,
    )


# a y axis whose data span less than _FLAT times the magnitude of their middle (at least
# one) shows a flat signal, or rounding; it is widened to the larger of _FLAT_SPAN [its
# display unit] and _FLAT_RELATIVE_SPAN times that magnitude
_FLAT = 1e-6
_FLAT_SPAN = 1e-2
_FLAT_RELATIVE_SPAN = 1e-4


def _finish(fig: Figure) -> Figure:
    """Plain tick labels on every linear axis: no offset or power notation to decode.

    A y axis of a flat signal (or of the difference of two signals equal but for rounding)
    is widened about its middle (:data:`_FLAT`), so that its tick labels stay short instead
    of spelling the rounding out in fifteen digits.
    """
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            formatter = axis.get_major_formatter()
            if isinstance(formatter, ScalarFormatter):
                formatter.set_useOffset(False)
                formatter.set_scientific(False)
        if ax.get_yscale() == "linear":
            low, high = ax.get_ylim()
            middle = 0.5 * (low + high)
            if abs(high - low) < _FLAT * max(1.0, abs(middle)):
                half = 0.5 * max(_FLAT_SPAN, _FLAT_RELATIVE_SPAN * abs(middle))
                ax.set_ylim(
                    (middle - half, middle + half)
                    if high >= low
                    else (middle + half, middle - half)
                )
    return fig


def _time_panel(
    ax: Axes, result: SimResult, names: Sequence[str], ylabel: str, *, legend: bool = True
) -> None:
    for name in names:
        values, _ = _display(name, result[name])
        ax.plot(result.t, values, label=_LABELS.get(name, name), **_STYLES.get(name, {}))
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    if legend:
        _legend_above(ax)


def _zoom_window(t: NDArray[np.float64], error: NDArray[np.float64]) -> tuple[float, float]:
    """A window of a twentieth of the run (at least 0.2 s) around the largest error [s]."""
    span = max(0.2, 0.05 * float(t[-1] - t[0]))
    centre = float(t[int(np.argmax(np.abs(error)))])
    start = min(max(centre - 0.5 * span, float(t[0])), max(float(t[-1]) - span, float(t[0])))
    return start, start + span


def _title(result: SimResult, title: str) -> str:
    if result.complete:
        return title
    return f"{title} (interrupted run)"


def _pair_figure(
    result: SimResult,
    pair: tuple[str, str],
    *,
    figure: str,
    title: str,
    error_label: str,
    quantity: str,
) -> Figure:
    """Two signals against time and, when both exist, their difference below.

    ``quantity`` names what both signals are, for the y axes (``"rider torque"``).
    """
    have = _present(result, pair, figure)
    _, unit = _display(have[0], result[have[0]])
    both = len(have) == 2
    if not both or result.t.size < 8:
        fig = Figure(figsize=(9.0, 3.4))
        ax = fig.add_subplot(_fixed_grid(fig, 1, 1, top=_TITLE + _LEGEND_ROW)[0, 0])
        _time_panel(ax, result, have, f"{quantity} [{unit}]")
        ax.set_xlabel("time [s]")
        fig.suptitle(_title(result, title))
        return _finish(fig)
    # the whole run on the left, a zoom where the error is largest on the right: chatter and
    # encoder steps that a whole run's scale hides show there
    fig = Figure(figsize=(11.0, 5.4))
    grid = _fixed_grid(
        fig, 2, 2, top=_TITLE + _LEGEND_ROW, width_ratios=[2.2, 1.0], height_ratios=[2, 1]
    )
    main = fig.add_subplot(grid[0, 0])
    error_ax = fig.add_subplot(grid[1, 0], sharex=main)
    zoom = fig.add_subplot(grid[:, 1])
    first, _ = _display(pair[0], result[pair[0]])
    second, _ = _display(pair[1], result[pair[1]])
    error = second - first
    _time_panel(main, result, have, f"{quantity} [{unit}]")
    error_ax.plot(result.t, error, color="tab:purple", lw=0.8)
    error_ax.set_ylabel(f"{error_label} [{unit}]")
    error_ax.grid(True, alpha=0.3)
    error_ax.set_xlabel("time [s]")
    low, high = _zoom_window(result.t, error)
    inside = (result.t >= low) & (result.t <= high)
    for name, values in ((pair[0], first), (pair[1], second)):
        zoom.plot(result.t[inside], values[inside], **_STYLES.get(name, {}))
    zoom.set_title(f"zoom {low:.2f}-{high:.2f} s", fontsize=9)
    zoom.set_xlabel("time [s]")
    zoom.set_ylabel(f"{quantity} [{unit}]")
    zoom.grid(True, alpha=0.3)
    for ax in (main, error_ax):
        ax.axvspan(low, high, color="0.85", zorder=0)
    fig.suptitle(_title(result, title))
    return _finish(fig)


def plot_torque(result: SimResult, *, title: str = "Rider torque and its estimate") -> Figure:
    """Rider torque ``tau_r`` and its estimate ``tau_r_hat`` [N*m] against time.

    Figs. 11 and 14 of Nehaoua, Arioui & Mammar (2012). When both exist, a second panel shows
    the estimation error ``tau_r_hat - tau_r``.

    Parameters
    ----------
    result : SimResult
        A run with ``tau_r`` and/or ``tau_r_hat``.
    title : str
        Figure title.

    Returns
    -------
    Figure

    Raises
    ------
    MotosimError
        If the result has neither signal.
    """
    return _pair_figure(
        result,
        ("tau_r", "tau_r_hat"),
        figure="plot_torque",
        title=title,
        error_label="tau_r_hat - tau_r",
        quantity="rider torque",
    )


def plot_tracking(
    result: SimResult, *, title: str = "Handlebar angle against the virtual steer angle"
) -> Figure:
    """Handlebar angle ``theta_h`` and its reference ``delta`` [deg] against time.

    Fig. 13 (left) of Nehaoua, Arioui & Mammar (2012). When both exist, a second panel shows
    the tracking error ``theta_h - delta``.

    Parameters
    ----------
    result : SimResult
        A run with ``theta_h`` and/or ``delta``.
    title : str
        Figure title.

    Returns
    -------
    Figure

    Raises
    ------
    MotosimError
        If the result has neither signal.
    """
    return _pair_figure(
        result,
        ("delta", "theta_h"),
        figure="plot_tracking",
        title=title,
        error_label="theta_h - delta",
        quantity="steer and handlebar angle",
    )


def plot_rate(result: SimResult, *, title: str = "Handlebar rate and its estimate") -> Figure:
    """True handlebar rate ``theta_h_dot`` and the differentiator's ``theta_h_dot_hat``.

    Fig. 13 (right) and Fig. 17 of Nehaoua, Arioui & Mammar (2012), in [deg/s]. The
    differentiator reads the encoder's angle, quantised to q = 2 pi / 2^bits rad: one count
    between two samples reads as a rate of q / dt, so while the handlebar creeps its output
    steps by about that much, which no differentiator of the quantised angle can resolve. The
    figure draws that resolution, +/- q / dt (when the result's scenario gives the encoder and
    the measurement rate), the differentiator's output faint and its centred moving average
    over 20 ms (at least 5 samples) over it, so the rate it follows reads under the steps;
    below, the error of both; on the right, a zoom where the averaged error is largest.

    Parameters
    ----------
    result : SimResult
        A run with ``theta_h_dot`` and/or ``theta_h_dot_hat``.
    title : str
        Figure title.

    Returns
    -------
    Figure

    Raises
    ------
    MotosimError
        If the result has neither signal.
    """
    names = ("theta_h_dot", "theta_h_dot_hat")
    have = _present(result, names, "plot_rate")
    if len(have) < 2 or result.t.size < 8:
        return _pair_figure(
            result,
            names,
            figure="plot_rate",
            title=title,
            error_label="estimate - true",
            quantity="handlebar rate",
        )
    true = np.rad2deg(result["theta_h_dot"])
    raw = np.rad2deg(result["theta_h_dot_hat"])
    dt = float(np.median(np.diff(result.t)))
    width = max(5, round(0.02 / dt))
    smooth = _moving_average(raw, width)
    encoder = _encoder(result)
    step = None if encoder is None else encoder[0] * encoder[1]
    fig = Figure(figsize=(11.0, 5.8))
    # above, the legend's two rows; between the columns, the error's legend beside it; below,
    # the two lines on the encoder's step
    grid = _fixed_grid(
        fig,
        2,
        2,
        top=_TITLE + 2 * _LEGEND_ROW,
        bottom=_BOTTOM + (0.35 if step else 0.0),
        wgap=_LEFT + 0.8,
        width_ratios=[2.2, 1.0],
        height_ratios=[2, 1],
    )
    main = fig.add_subplot(grid[0, 0])
    error_ax = fig.add_subplot(grid[1, 0], sharex=main)
    zoom = fig.add_subplot(grid[:, 1])
    average = f"differentiator, {1e3 * width * dt:.0f} ms moving average"
    low, high = _zoom_window(result.t, smooth - true)
    inside = (result.t >= low) & (result.t <= high)
    for ax, part in ((main, slice(None)), (zoom, inside)):
        t = result.t[part]
        if step is not None:
            band = f"+/- one encoder count per sample, q/dt = {step:.3g} deg/s"
            ax.axhspan(-step, step, color="tab:orange", alpha=0.12, lw=0, label=band)
        ax.plot(
            t,
            raw[part],
            color="tab:red",
            lw=0.6,
            alpha=0.3,
            label="differentiator theta_h_dot_hat (each sample)",
        )
        ax.plot(t, smooth[part], color="tab:red", lw=1.2, label=average)
        ax.plot(t, true[part], color="k", lw=1.0, ls="--", label="true rate theta_h_dot")
        ax.set_ylabel("handlebar rate [deg/s]")
        ax.grid(True, alpha=0.3)
    _legend_above(main, columns=2)
    zoom.set_title(f"zoom {low:.2f}-{high:.2f} s", fontsize=9)
    zoom.set_xlabel("time [s]")
    error_ax.plot(result.t, raw - true, color="tab:purple", lw=0.5, alpha=0.3, label="each sample")
    error_ax.plot(result.t, smooth - true, color="tab:purple", lw=1.0, label="averaged")
    if step is not None:
        for sign in (-1.0, 1.0):
            error_ax.axhline(sign * step, color="tab:orange", lw=0.8, ls=":")
    error_ax.set_ylabel("estimate - true [deg/s]")
    error_ax.set_xlabel("time [s]")
    error_ax.grid(True, alpha=0.3)
    error_ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=7, frameon=False)
    for ax in (main, error_ax):
        ax.axvspan(low, high, color="0.85", zorder=0)
    if encoder is not None and step is not None:
        fig.supxlabel(
            f"The encoder's step q is {encoder[0]:.3g} deg: one count between two "
            f"measurements {1e3 / encoder[1]:.3g} ms apart reads as {step:.3g} deg/s, the "
            "steps of the differentiator's output while the handlebar creeps\n(the shaded "
            "band); "
            "averaged, the output follows the true rate.",
            fontsize=8,
            color="0.3",
        )
    fig.suptitle(_title(result, title))
    return _finish(fig)


def _moving_average(values: NDArray[np.float64], width: int) -> NDArray[np.float64]:
    """Centred moving average over ``width`` samples, the ends averaged over what there is."""
    kernel = np.ones(width)
    total = np.convolve(values, kernel, mode="same")
    count = np.convolve(np.ones_like(values), kernel, mode="same")
    out: NDArray[np.float64] = total / count
    return out


def _encoder(result: SimResult) -> tuple[float, float] | None:
    """The run's encoder step q [deg] and measurement rate [Hz], when its scenario says."""
    scenario = result.metadata.get("scenario")
    if not isinstance(scenario, dict):
        return None
    measurement, rates = scenario.get("measurement"), scenario.get("rates")
    if not isinstance(measurement, dict) or not isinstance(rates, dict):
        return None
    bits, rate = measurement.get("encoder_bits"), rates.get("measurement")
    if not isinstance(bits, int) or bits <= 0 or not isinstance(rate, int | float) or rate <= 0:
        return None
    return float(np.rad2deg(2.0 * np.pi / 2**bits)), float(rate)


def plot_motor_torque(
    result: SimResult, *, title: str = "Estimated rider torque and motor torque"
) -> Figure:
    """Estimated rider torque ``tau_r_hat`` and motor torque ``tau_m = N k_t i_m`` [N*m].

    Fig. 18 of Nehaoua, Arioui & Mammar (2012); the motor current ``i_m`` [A], when present,
    is drawn in a second panel.

    Parameters
    ----------
    result : SimResult
        A run with ``tau_r_hat`` and/or ``tau_m`` (and optionally ``i_m``).
    title : str
        Figure title.

    Returns
    -------
    Figure

    Raises
    ------
    MotosimError
        If the result has none of ``tau_r_hat``, ``tau_m``, ``i_m``.
    """
    _present(result, ("tau_r_hat", "tau_m", "i_m"), "plot_motor_torque")
    torques = [n for n in ("tau_r_hat", "tau_m") if n in result]
    panels = int(bool(torques)) + int("i_m" in result)
    fig = Figure(figsize=(9.0, 2.4 * panels + 0.8))
    # the panels share their time axis: the upper one's tick labels are hidden
    top = _TITLE + (_LEGEND_ROW if torques else 0.0)
    grid = _fixed_grid(fig, panels, 1, top=top, hgap=0.15)
    axes = grid.subplots(sharex=True, squeeze=False)[:, 0]
    if torques:
        _time_panel(axes[0], result, torques, "torque [N m]")
    if "i_m" in result:
        axes[-1].plot(result.t, result["i_m"], color="tab:green", lw=0.8)
        axes[-1].set_ylabel("motor current i_m [A]")
        axes[-1].grid(True, alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(_title(result, title))
    return _finish(fig)


def plot_motorcycle(result: SimResult, *, title: str = "Virtual motorcycle") -> Figure:
    """Path seen from above, roll angle, speed and lateral path error of the virtual rider.

    The path ``x``-``y`` [m] is drawn with equal axes; ``y`` points to the right of the start
    heading, so the ``y`` axis is drawn downwards and the path looks as seen from above.
    Beside it, against time: roll ``phi`` [deg], forward speed ``v_x`` [m/s] and the lateral
    path error ``e_y`` [m], each when present.

    Parameters
    ----------
    result : SimResult
        A run with some of ``x``, ``y``, ``phi``, ``v_x``, ``e_y``.
    title : str
        Figure title.

    Returns
    -------
    Figure

    Raises
    ------
    MotosimError
        If the result has neither the path (``x`` and ``y``) nor any of the others.
    """
    has_path = "x" in result and "y" in result
    series = [n for n in ("phi", "v_x", "e_y") if n in result]
    if not has_path and not series:
        raise MotosimError(
            "plot_motorcycle: the result has neither x and y nor any of phi, v_x, e_y; "
            f"it has {', '.join(result.names) or 'none'}"
        )
    ylabels = {"phi": "roll phi [deg]", "v_x": "speed v_x [m/s]", "e_y": "path error e_y [m]"}
    rows = max(len(series), 1)
    fig = Figure(figsize=(11.0 if has_path else 8.0, 2.2 * rows + 1.0))
    grid = _fixed_grid(
        fig,
        rows,
        2 if has_path and series else 1,
        top=_TITLE + (_LEGEND_ROW if has_path else 0.0),
        width_ratios=[1.0, 1.3] if has_path and series else None,
    )
    axes: dict[str, Axes] = {}
    if has_path:
        axes["path"] = fig.add_subplot(grid[:, 0])
    for i, name in enumerate(series):
        axes[name] = fig.add_subplot(grid[i, -1], sharex=axes[series[0]] if i > 0 else None)
    if has_path:
        ax = axes["path"]
        x, y = result["x"], result["y"]
        if "e_y" in result:  # the path the rider follows: y less the lateral path error
            ax.plot(x, y - result["e_y"], color="tab:blue", lw=2.5, alpha=0.4, label="path")
        ax.plot(x, y, color="k", lw=1.0, label="motorcycle")
        ax.plot(x[:1], y[:1], "o", color="tab:green", label="start")
        ax.plot(x[-1:], y[-1:], "s", color="tab:red", label="end")
        span_x = float(np.ptp(x))
        span_y = float(np.ptp(y))
        if span_y >= 0.2 * span_x:  # a turn: true shape
            ax.set_aspect("equal", adjustable="datalim")
            view = "path seen from above"
        else:  # a straight or a lane change: a lateral scale where metres show
            middle = 0.5 * float(np.max(y) + np.min(y))
            half = max(1.0, 0.65 * span_y)
            ax.set_ylim(middle - half, middle + half)
            view = "path seen from above, lateral axis stretched"
        ax.invert_yaxis()
        ax.set_xlabel(f"x [m] ({view})")
        ax.set_ylabel("y [m] (right of start heading)")
        _legend_above(ax, columns=4)
        ax.grid(True, alpha=0.3)
    for i, name in enumerate(series):
        ax = axes[name]
        values, _ = _display(name, result[name])
        ax.plot(result.t, values, color="tab:blue", lw=1.0)
        ax.set_ylabel(ylabels[name])
        ax.grid(True, alpha=0.3)
        if i == len(series) - 1:
            ax.set_xlabel("time [s]")
    fig.suptitle(_title(result, title))
    return _finish(fig)


def plot_comparison(
    results: Mapping[str, SimResult],
    signal_pairs: Sequence[tuple[str, str]],
    *,
    title: str = "Comparison of runs",
) -> Figure:
    """Several runs side by side: one panel per run and pair of signals.

    For Figs. 11 and 14 of Nehaoua, Arioui & Mammar (2012): nominal against perturbed plant,
    friction compensation on and off. One column per run and one row per pair, the rows
    sharing their y axis: in each panel the first signal of the pair (the truth) in black
    over the second (its estimate or reference) in the run's colour, the legend beside.

    Parameters
    ----------
    results : Mapping of str to SimResult
        Run label to result.
    signal_pairs : sequence of (str, str)
        For example ``[("tau_r", "tau_r_hat"), ("delta", "theta_h")]``. The two signals of a
        pair share a unit.
    title : str
        Figure title.

    Returns
    -------
    Figure

    Raises
    ------
    MotosimError
        No runs or no pairs, a pair whose signals have different units, a signal that no run
        has.
    """
    if not results or not signal_pairs:
        raise MotosimError(
            f"plot_comparison: {len(results)} runs and {len(signal_pairs)} signal pairs; "
            "expected at least one of each"
        )
    for first, second in signal_pairs:
        if _unit(first) != _unit(second):
            raise MotosimError(
                f"plot_comparison: {first} [{_unit(first)}] and {second} [{_unit(second)}] "
                "have different units; expected a pair with one unit"
            )
        if not any(first in r or second in r for r in results.values()):
            raise MotosimError(f"plot_comparison: no run has {first} or {second}")
    rows, columns = len(signal_pairs), len(results)
    fig = Figure(figsize=(4.6 * columns + 1.0, 2.6 * rows + 1.0), layout="constrained")
    axes = fig.subplots(rows, columns, sharex=True, sharey="row", squeeze=False)
    colours = [f"C{i % 10}" for i in range(columns)]
    for row, (first, second) in enumerate(signal_pairs):
        _, unit = _display(first, np.zeros(1))
        for column, (label, result) in enumerate(results.items()):
            ax = axes[row, column]
            # the second (the estimate, the reference) in the run's colour under the first
            # (the truth, the handlebar) in black: two series a panel, each told by colour
            if second in result:
                values, _ = _display(second, result[second])
                ax.plot(
                    result.t,
                    values,
                    color=colours[column],
                    lw=0.9,
                    label=_LABELS.get(second, second),
                )
            if first in result:
                values, _ = _display(first, result[first])
                ax.plot(result.t, values, color="k", lw=1.1, label=_LABELS.get(first, first))
            ax.grid(True, alpha=0.3)
            if row == 0:  # above the legend, which is above the data
                ax.set_title(label, fontsize=9, pad=16)
            if column == 0:
                ax.set_ylabel(f"{_QUANTITIES.get(first, first)} [{unit}]")
            _legend_above(ax, columns=2, fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    fig.suptitle(title)
    return _finish(fig)


_SUPERSCRIPTS = str.maketrans(
    "-0123456789", "\u207b\u2070\u00b9\u00b2\u00b3\u2074\u2075\u2076\u2077\u2078\u2079"
)


def _power_of_ten(value: float, _position: int | None = None) -> str:
    """A log axis's tick label: ``value`` as 10 to an integer power in superscript digits,
    or no label where ``value`` is not a power of ten."""
    exponent = round(float(np.log10(value))) if value > 0 else None
    if exponent is None or not np.isclose(value, 10.0**exponent, rtol=1e-9):
        return ""
    return "10" + str(exponent).translate(_SUPERSCRIPTS)


def plot_spectrum(
    result: SimResult, *, title: str = "Spectra: motor current and tracking error"
) -> Figure:
    """Amplitude spectra of the motor current and of theta_h - delta, whole run and last 2 s.

    A buzz that an RMS hides (a sustained oscillation of the loop) shows as a peak here; the
    dotted line is where the run metrics start counting current content as a buzz.
    """
    from motosim.sim.metrics import BUZZ_CUTOFF

    if not {"i_m", "theta_h", "delta"} <= set(result.names) or result.t.size < 16:
        raise MotosimError("plot_spectrum: the result has no i_m, theta_h and delta to analyse")
    dt = float(np.median(np.diff(result.t)))
    fig = Figure(figsize=(9.0, 6.0))
    # on the right, each panel's legend beside it
    axes = _fixed_grid(fig, 2, 1, right=1.15).subplots(squeeze=False)[:, 0]
    series = (
        ("i_m", result["i_m"], "A"),
        ("theta_h - delta", np.degrees(result["theta_h"] - result["delta"]), "deg"),
    )
    tail = result.t >= result.t[-1] - 2.0
    highest = min(50.0, 0.5 / dt)  # [Hz]: the axis's end
    for ax, (name, values, unit) in zip(axes, series, strict=True):
        top = 0.0
        for part, label, style in ((slice(None), "whole run", "-"), (tail, "last 2 s", "--")):
            x = values[part]
            amplitude = 2.0 * np.abs(np.fft.rfft(x - np.mean(x))) / max(x.size, 1)
            freqs = np.fft.rfftfreq(x.size, dt)
            # the lines up to one point past the axis's end: the same figure, fewer points
            drawn = slice(1, int(np.searchsorted(freqs, highest, side="right")) + 1)
            shown = np.where(amplitude[drawn] > 0, amplitude[drawn], np.nan)
            ax.plot(freqs[drawn], shown, style, lw=1.0, label=label)
            top = max(top, float(np.max(amplitude[1:], initial=0.0)))
        if top > 0:  # log scale, five decades under the highest peak (rounding stays out)
            ax.set_yscale("log")
            ax.set_ylim(top * 1e-5, top * 2.0)
            # a tick and a grid line per decade, labelled in plain text: matplotlib's
            # default labels are typeset as mathematics and its minor ticks are many objects,
            # together most of the figure's drawing time
            ax.yaxis.set_major_formatter(FuncFormatter(_power_of_ten))
            ax.yaxis.set_minor_locator(NullLocator())
        ax.axvline(BUZZ_CUTOFF, color="0.5", ls=":", lw=1.0)
        ax.set_xlim(0.0, highest)
        ax.set_ylabel(f"{name} amplitude [{unit}]")
        ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize="small", frameon=False)
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("frequency [Hz]")
    fig.suptitle(_title(result, title))
    return fig


def plot_feel(feel: Any, *, speed: float) -> Figure:
    """Bode plot of the rendered feel theta_h / tau_r against the motorcycle's delta / tau_r.

    ``feel`` is a :class:`motosim.sim.fidelity.FeelResponse`. The measured responses are
    marked at each frequency when there are few (a multisine's lines), so that the lines
    drawn between them are not read as measured.
    """
    fig = Figure(figsize=(9.0, 6.0), layout="constrained")
    mag, phase = fig.subplots(2, 1, sharex=True)
    marks = {"marker": "o", "ms": 3.5} if feel.frequency.size <= 100 else {}
    curves = (
        (feel.model, "motorcycle model delta / tau_r", {"color": "k", "lw": 1.5}),
        (feel.steer, "virtual motorcycle in the run", {"color": "tab:blue", "ls": "--", **marks}),
        (feel.rendered, "handlebar theta_h / tau_r (rendered)", {"color": "tab:red", **marks}),
    )
    for values, label, style in curves:
        mag.semilogx(feel.frequency, 20 * np.log10(np.abs(values)), label=label, **style)
        phase.semilogx(feel.frequency, np.degrees(np.angle(values)), **style)
    mag.set_ylabel("magnitude [dB rad/(N m)]")
    phase.set_ylabel("phase [deg]")
    phase.set_xlabel("frequency [Hz]")
    mag.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize="small", frameon=False)
    for ax in (mag, phase):
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"Rendered steering feel at {speed:g} m/s")
    return fig
