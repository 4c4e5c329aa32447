"""Closed-loop figures (smoke tests on a tiny result) and the HTML report."""

import base64
import json
from collections.abc import Callable
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Text

from motosim.errors import MotosimError
from motosim.io.results import ResultWriter, SimResult, load_result
from motosim.plotting.closed_loop import (
    plot_comparison,
    plot_motor_torque,
    plot_motorcycle,
    plot_rate,
    plot_spectrum,
    plot_torque,
    plot_tracking,
)
from motosim.report import build_report, metrics
from motosim.signals import RECORDED

# the offline simulator's columns up to the path error, without the active rider torque
NAMES = tuple(n for n in RECORDED[: RECORDED.index("e_y") + 1] if n != "tau_r_active")


def _rows(n: int = 60, dt: float = 0.01) -> np.ndarray:
    t = np.arange(n) * dt
    columns = {name: 0.01 * (j + 1) * np.sin(3 * t + j) for j, name in enumerate(NAMES)}
    columns["t"] = t
    columns["tau_r"] = np.sin(2 * t)
    columns["tau_r_hat"] = np.sin(2 * t) + 0.1
    columns["theta_h"] = np.full(n, 0.02)
    columns["delta"] = np.zeros(n)
    columns["phi"] = np.deg2rad(10.0) * np.sin(t)
    columns["v_x"] = np.full(n, 20.0)
    columns["x"] = 20.0 * t
    columns["y"] = 0.5 * t**2
    columns["e_y"] = -0.3 * t
    return np.column_stack([columns[name] for name in NAMES])


def _result(names: tuple[str, ...] = NAMES, *, complete: bool = True) -> SimResult:
    rows = _rows()[:, [NAMES.index(n) for n in names]]
    return SimResult(rows[:, 0], rows[:, 1:], names[1:], {"seed": 1}, {}, complete)


SUPERSCRIPT_DIGITS = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")

PLOTS: list[Callable[[SimResult], Figure]] = [
    plot_torque,
    plot_tracking,
    plot_rate,
    plot_motor_torque,
    plot_motorcycle,
]


@pytest.mark.parametrize("plot", PLOTS)
def test_plots_return_a_figure(plot: Callable[[SimResult], Figure]) -> None:
    fig = plot(_result(complete=False))
    assert isinstance(fig, Figure) and fig.axes
    fig.canvas.draw()  # layout and drawing raise no warning


@pytest.mark.parametrize("plot", PLOTS)
def test_plots_draw_what_there_is(plot: Callable[[SimResult], Figure]) -> None:
    few = ("t", "tau_r_hat", "theta_h", "theta_h_dot", "i_m", "phi")
    assert isinstance(plot(_result(few)), Figure)
    with pytest.raises(MotosimError) as info:
        plot(_result(("t", "psi")))
    assert "\n" not in str(info.value)


def test_the_spectra_label_each_decade_in_plain_text() -> None:
    # one tick per power of ten on the log axes, written 10 and a superscript exponent, and
    # no label typeset as mathematics
    result = _result()
    data = result.data.copy()
    data[:, result.names.index("theta_h")] = 0.02 * np.sin(5.0 * result.t)
    fig = plot_spectrum(SimResult(result.t, data, result.names, {"seed": 1}, {}, True))
    fig.canvas.draw()
    for ax in fig.axes:
        assert ax.get_yscale() == "log"
        assert not ax.yaxis.get_minorticklocs().size
        low, high = ax.get_ylim()
        shown = [loc for loc in ax.yaxis.get_majorticklocs() if low <= loc <= high]
        labels = [ax.yaxis.get_major_formatter()(loc, k) for k, loc in enumerate(shown)]
        assert len(shown) >= 4
        for loc, label in zip(shown, labels, strict=True):
            exponent = round(np.log10(loc))
            assert loc == pytest.approx(10.0**exponent)
            assert label == "10" + str(exponent).translate(SUPERSCRIPT_DIGITS)


@pytest.mark.parametrize("plot", [*PLOTS, plot_spectrum])
@pytest.mark.parametrize("scale", [1.0, 1e5])
def test_the_report_figures_hold_their_texts_at_fixed_margins(
    plot: Callable[[SimResult], Figure], scale: float
) -> None:
    # no layout engine places the axes: every text drawn (tick labels of up to seven
    # characters at the larger scale, axis labels, titles, legends) lies inside the figure
    result = _result()
    result = SimResult(result.t, scale * result.data, result.names, {"seed": 1}, {}, True)
    fig = plot(result)
    assert fig.get_layout_engine() is None
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    ticks: list[Text] = []
    drawn: set[int] = set()
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                ticks += [tick.label1, tick.label2]
            drawn.update(id(tick.label1) for tick in axis._update_ticks())
    hidden = {id(label) for label in ticks} - drawn  # ticks outside the view are not drawn
    texts = [
        t for t in fig.findobj(Text) if t.get_visible() and t.get_text() and id(t) not in hidden
    ]
    assert texts
    for text in texts:
        box = text.get_window_extent(renderer)
        assert box.x0 >= 0 and box.y0 >= 0, text.get_text()
        assert box.x1 <= fig.bbox.width and box.y1 <= fig.bbox.height, text.get_text()


def test_plot_comparison() -> None:
    runs = {"nominal": _result(), "perturbed": _result(("t", "tau_r", "tau_r_hat", "delta"))}
    fig = plot_comparison(runs, [("tau_r", "tau_r_hat"), ("delta", "theta_h")])
    # one panel per run and pair, each with its two series only, told by colour
    assert isinstance(fig, Figure) and len(fig.axes) == 4
    fig.canvas.draw()
    assert [len(ax.get_lines()) for ax in fig.axes] == [2, 2, 2, 1]
    for ax in fig.axes:
        colours = {str(line.get_color()) for line in ax.get_lines()}
        assert len(colours) == len(ax.get_lines())
    assert fig.axes[0].get_ylabel() == "rider torque [N m]"
    assert fig.axes[2].get_ylabel() == "handlebar and steer angle [deg]"
    with pytest.raises(MotosimError, match="different units"):
        plot_comparison(runs, [("tau_r", "theta_h")])
    with pytest.raises(MotosimError, match="expected at least one of each"):
        plot_comparison({}, [("tau_r", "tau_r_hat")])


def test_metrics() -> None:
    m = metrics(_result())
    assert m["rms_tau_r_error"] == pytest.approx(0.1)
    assert m["rms_tracking_error"] == pytest.approx(0.02)
    assert np.rad2deg(m["max_abs_phi"]) == pytest.approx(10.0 * np.sin(0.59))
    assert m["max_abs_e_y"] == pytest.approx(0.3 * 0.59)
    assert m["duration"] == pytest.approx(0.59) and m["samples"] == 60 and m["complete"] == 1
    assert set(metrics(_result(("t", "psi")))) == {"duration", "samples", "complete"}


def _write(folder: Path, *, interrupt: bool = False) -> None:
    metadata = {"scenario": {"name": "lane <change>", "speed": 20.0}, "seed": 4, "version": "0"}
    with ResultWriter(folder, NAMES, metadata) as writer:
        writer.append(_rows())
        if interrupt:
            raise RuntimeError("solver crashed")
        writer.close({"rms_tau_r_error": 0.1, "solver": "rk4"})


def test_report(tmp_path: Path) -> None:
    _write(tmp_path)
    path = build_report(tmp_path)
    assert path == tmp_path / "report.html"
    text = path.read_text(encoding="utf-8")
    assert "lane &lt;change&gt;" in text and "<change>" not in text  # escaped
    assert "<h2>Metrics</h2>" in text and "RMS of theta_h - delta" in text and "rk4" in text
    assert "100 Hz" in text and "complete" in text
    images = text.split('src="data:image/svg+xml;base64,')[1:]
    assert len(images) == 6  # torque, tracking, rate, motor torque, motorcycle, spectra
    for image in images:
        svg = ElementTree.fromstring(base64.b64decode(image.split('"', 1)[0]))
        assert svg.tag == "{http://www.w3.org/2000/svg}svg"
        assert float(svg.get("width", "0").removesuffix("pt")) > 0
        assert list(svg.iter("{http://www.w3.org/2000/svg}text"))  # the texts kept as text
        links = [e.get("{http://www.w3.org/1999/xlink}href", "") for e in svg.iter()]
        assert all(not link or link.startswith("#") for link in links)  # nothing fetched
    assert "http://" not in text.replace("http://www.w3.org", "") and "<script" not in text


def test_report_of_an_interrupted_run(tmp_path: Path) -> None:
    with pytest.raises(RuntimeError, match="solver crashed"):
        _write(tmp_path, interrupt=True)
    assert not load_result(tmp_path).complete
    text = build_report(tmp_path).read_text(encoding="utf-8")
    assert "interrupted" in text and "computed from the saved signals" in text.lower()


def test_report_without_result(tmp_path: Path) -> None:
    with pytest.raises(MotosimError, match=r"no result\.h5"):
        build_report(tmp_path)


def test_report_of_a_realtime_run_stopped_by_a_safety_fault(tmp_path: Path) -> None:
    # motosim run closes the rows marked partial and writes the fault beside them
    with pytest.raises(RuntimeError):
        _write(tmp_path, interrupt=True)
    timing = {"state": "FAULT", "fault": "ESTOP_CAN", "fault_reason": "emergency stop (t = 3 s)"}
    (tmp_path / "timing.json").write_text(json.dumps(timing), encoding="utf-8")
    text = build_report(tmp_path).read_text(encoding="utf-8")
    assert "run failed: safety fault: emergency stop (t = 3 s)" in text
    assert "interrupted: partial result" not in text
    (tmp_path / "timing.json").write_text(json.dumps(timing | {"fault": "NONE"}), "utf-8")
    assert "interrupted: partial result" in build_report(tmp_path).read_text(encoding="utf-8")
    (tmp_path / "timing.json").write_text("{not json", encoding="utf-8")  # the rows still count
    assert "interrupted: partial result" in build_report(tmp_path).read_text(encoding="utf-8")


def test_report_of_a_cueing_result_shows_its_figures_and_claims_no_flag_check(
    tmp_path: Path,
) -> None:
    # motosim cueing writes the platform's commands and its figures, no closed-loop signal
    t = np.arange(0.0, 1.0, 0.01)
    names = ("t", "phi_s", "theta_s", "psi_s", "phi_vis")
    with ResultWriter(tmp_path, names, {"algorithm": "mpc"}) as writer:
        writer.append(np.column_stack([t, *(0.01 * np.sin(t + k) for k in range(4))]))
        writer.close({"violations": 0})
    png = b"\x89PNG\r\n\x1a\n" + b"\x00" * 16
    for name in ("perception.png", "commands.png"):
        (tmp_path / name).write_bytes(png)
    text = build_report(tmp_path).read_text(encoding="utf-8")
    assert "no buzz, no saturation, no fall" not in text  # none of it was checked
    images = text.split('src="data:image/png;base64,')[1:]
    assert len(images) == 2
    assert all(base64.b64decode(i.split('"', 1)[0]) == png for i in images)


def test_report_names_the_observer_and_shows_units(tmp_path: Path) -> None:
    # a run of the default stack: no design file, so the metadata's observer gains are None
    metadata = {
        "scenario": {
            "name": "lane",
            "estimator": {"name": "walcott_zak"},
            "controller": {"kind": "paper"},
        },
        "observer": None,
        "controller": None,
    }
    with ResultWriter(tmp_path, NAMES, metadata) as writer:
        writer.append(_rows())
        writer.close({"samples": 60.0, "rms_tracking_error": 0.02, "flag_fall": 0.0})
    text = " ".join(build_report(tmp_path).read_text(encoding="utf-8").split())
    assert "<td>observer</td><td>Walcott-Zak observer" in text
    assert "None" not in text.split("<h2>Metrics</h2>")[0]
    assert "the paper&#x27;s, eq. (26)" in text
    assert '<td class="num">60</td>' in text  # a count as an integer, not 60.0 or 6e+01
    assert '<td class="num">1.146</td><td>deg</td>' in text  # 0.02 rad
    assert '<td class="num">no</td>' in text  # the fall flag


@pytest.mark.parametrize(
    ("sensor", "source"),
    [({}, "as measured"), ({"torque": {"low_pass": 50.0}}, "through a 50 Hz low-pass")],
)
def test_report_names_the_torque_sensor_as_no_observer(
    tmp_path: Path, sensor: dict, source: str
) -> None:
    # the estimator torque_sensor designs nothing: the report says so, not "designed for
    # the nominal handlebar"
    metadata = {
        "scenario": {
            "name": "sensed",
            "estimator": {"name": "torque_sensor"},
            "controller": {"kind": "paper"},
            "sensor": sensor,
        },
        "observer": None,
        "controller": None,
    }
    with ResultWriter(tmp_path, NAMES, metadata) as writer:
        writer.append(_rows())
        writer.close({"samples": 60.0})
    text = " ".join(build_report(tmp_path).read_text(encoding="utf-8").split())
    row = text.split("<td>observer</td><td>")[1].split("</td>")[0]
    assert row == f"a torque sensor&#x27;s measured torque (no observer); {source}"


def test_the_rate_figure_shows_the_encoders_resolution() -> None:
    # a 14-bit encoder read at 1 kHz: one count a sample is 2 pi / 2^14 * 1000 rad/s, 21.97
    # deg/s, the band drawn about zero and the step named under the figure
    result = _result()
    scenario = {"measurement": {"encoder_bits": 14}, "rates": {"measurement": 1000.0}}
    shown = SimResult(result.t, result.data, result.names, {"scenario": scenario}, {}, True)
    fig = plot_rate(shown)
    fig.canvas.draw()
    main = fig.axes[0]
    band = [p for p in main.patches if "encoder count" in str(p.get_label())]
    assert len(band) == 1 and "q/dt = 22 deg/s" in str(band[0].get_label())
    labels = [line.get_label() for line in main.get_lines()]
    assert any("moving average" in str(label) for label in labels)
    assert main.get_ylabel() == "handlebar rate [deg/s]"
    assert "0.022 deg" in fig.get_supxlabel()


def test_the_modes_labels_stay_off_the_curves() -> None:
    from motosim.model import sharp
    from motosim.params import load_parameters
    from motosim.plotting.modes import plot_modes

    bike = load_parameters("sharp1971", "sharp")
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = plot_modes(sharp.modes(bike, np.arange(2.0, 60.5, 2.0)))
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    ax = fig.axes[0]
    renderer = canvas.get_renderer()
    texts = [t for t in ax.texts if t.get_text().endswith("unstable")]
    assert {t.get_text() for t in texts} >= {"weave unstable", "wobble unstable"}
    for text in texts:
        box = text.get_window_extent(renderer)
        for line in ax.get_lines():
            xy = ax.transData.transform(line.get_xydata())
            inside = (xy[:, 0] >= box.x0) & (xy[:, 0] <= box.x1)
            assert not np.any(xy[inside, 1] >= box.y0), (text.get_text(), line.get_label())
    assert ax.get_legend() is not None
    legend = ax.get_legend().get_window_extent(renderer)
    assert legend.x0 >= ax.get_window_extent(renderer).x1  # beside the axes


def test_the_papers_figures_are_numbered_once(tmp_path: Path) -> None:
    import re

    from motosim.cli.paper import _figures

    names = (
        "fig11_nominal",
        "fig11_perturbed",
        "fig14_compensated",
        "fig14_uncompensated",
        "fig15_riding",
    )
    written = _figures({name: _result() for name in names}, tmp_path)
    numbers: dict[str, list[str]] = {}
    for file, caption in written:
        assert (tmp_path / file).read_bytes().startswith(b"\x89PNG")
        assert "Figs. " not in caption.split(":")[0], caption  # no range of figures
        found = re.match(r"Fig\. (\d+)( \((left|right)\))?:", caption)
        if found:
            numbers.setdefault(found.group(1), []).append(found.group(3) or "whole")
    # the paper's Figs. 11, 13 (its two halves), 14, 15, 16, 17 and 18, each once
    assert numbers == {
        "11": ["whole"],
        "13": ["left", "right"],
        "14": ["whole"],
        "15": ["whole"],
        "16": ["whole"],
        "17": ["whole"],
        "18": ["whole"],
    }
