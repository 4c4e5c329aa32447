"""A self-contained HTML report of one run, built from its saved result only.

:func:`build_report` reads ``folder/result.h5`` with :func:`motosim.io.results.load_result`,
computes the metrics (:func:`metrics`) unless the run stored them, draws the figures of
:mod:`motosim.plotting.closed_loop` (:mod:`motosim.report.figures`: here, or in worker
processes started before the run) and writes ``folder/report.html`` with the figures
embedded (SVG; PNG for those a command saved beside the result): one file, no external
resources, no JavaScript.
"""

import base64
import html
import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from motosim.io.files import write_whole
from motosim.io.results import SimResult, load_result
from motosim.plotting.images import SVG_DATA
from motosim.report.figures import FIGURES, draw_figure
from motosim.report.units import METRICS, shown
from motosim.sim.metrics import run_metrics

if TYPE_CHECKING:
    from motosim.report.figures import FigureWorkers

__all__ = ["build_report", "metrics"]

_REPORT_NAME = "report.html"


_SAVED_FIGURES = (
    ("perception.png", "Perceived motion, motorcycle against platform (motosim cueing)"),
    ("commands.png", "Platform commands against their limits (motosim cueing)"),
)
_FLAGS = {
    "flag_oscillation": "sustained oscillation: the motor current buzzes above 3 Hz",
    "flag_saturation": "the motor current was at its limit more than half the time",
    "flag_fall": "the motorcycle fell (roll beyond 45 deg)",
    "flag_out_of_range": "the speed left the model's range (3 to 60 m/s)",
}


def metrics(result: SimResult) -> dict[str, float]:
    """Summary numbers of a saved run: :func:`motosim.sim.metrics.run_metrics` of its signals."""
    return run_metrics(result.t, result.get, complete=result.complete)


_CSS = """
body { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; color: #222;
       max-width: 1000px; margin: 2em auto; padding: 0 1em; line-height: 1.45; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; }
h2 { font-size: 1.2em; margin-top: 1.8em; border-bottom: 1px solid #ddd; padding-bottom: 0.2em; }
.status { display: inline-block; padding: 0.1em 0.6em; border-radius: 0.3em; font-size: 0.9em; }
.complete { background: #e3f4e1; color: #1d5c17; }
.interrupted { background: #fde8e8; color: #8a1c1c; }
table { border-collapse: collapse; margin: 0.5em 0; }
th, td { border: 1px solid #ddd; padding: 0.3em 0.8em; text-align: left; }
th { background: #f5f5f5; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
figure { margin: 1.2em 0; }
figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption { font-size: 0.9em; color: #555; }
pre { background: #f7f7f7; padding: 0.8em; overflow-x: auto; font-size: 0.85em; }
.note { color: #666; font-size: 0.9em; }
"""


def _esc(value: object) -> str:
    return html.escape(str(value), quote=True)


def _format(value: Any) -> str:
    if isinstance(value, bool) or value is None:
        return str(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list | dict):
        return json.dumps(value)
    return str(value)


def _is_scalar(value: Any) -> bool:
    return value is None or isinstance(value, bool | int | float | str)


_ESTIMATOR_NAMES = {
    "walcott_zak": "Walcott-Zak observer (the paper's)",
    "inverse_dynamics": "inverse dynamics of the handlebar (no observer)",
    "kalman": "Kalman filter",
    "torque_sensor": "a torque sensor's measured torque (no observer)",
}
_CONTROLLER_NAMES = {
    "ours": "ours: H-infinity loop shaping",
    "paper": "the paper's, eq. (26)",
    "none": "none (open loop)",
}


def _stack_rows(meta: Mapping[str, Any], scenario: Mapping[str, Any]) -> list[tuple[str, str]]:
    """The rider-torque estimator and the controller the run used, named.

    The run's metadata holds the observer's and the controller's gains only when they came
    from a design file (``observer`` is None otherwise: the gains were designed for the
    scenario's nominal handlebar); which estimator ran is the scenario's ``[estimator]``.
    """
    rows = []
    estimator = scenario.get("estimator")
    if isinstance(estimator, dict) and "name" in estimator:
        name = str(estimator["name"])
        if name == "torque_sensor":  # nothing designed: the sensor's reading, filtered or not
            sensor = scenario.get("sensor")
            torque = sensor.get("torque") if isinstance(sensor, dict) else None
            corner = torque.get("low_pass", 0.0) if isinstance(torque, dict) else 0.0
            source = f"through a {corner:g} Hz low-pass" if corner else "as measured"
        elif isinstance(meta.get("observer"), dict):
            source = "gains from the scenario's design file"
        else:
            source = "designed for the nominal handlebar at the run's rate"
        rows.append(("observer", f"{_ESTIMATOR_NAMES.get(name, name)}; {source}"))
    controller = scenario.get("controller")
    if isinstance(controller, dict) and "kind" in controller:
        kind = str(controller["kind"])
        text = _CONTROLLER_NAMES.get(kind, kind)
        if kind == "ours" and "order" in controller:
            text += f", order {controller['order']}"
        if controller.get("design"):
            text += f"; design file {controller['design']}"
        rows.append(("controller", text))
    return rows


def _run_rows(result: SimResult, folder: Path) -> list[tuple[str, str]]:
    """Key facts of the run: folder, scenario, seed, version, rates, then scalar metadata."""
    meta = result.metadata
    scenario = meta.get("scenario")
    scenario_map: Mapping[str, Any] = scenario if isinstance(scenario, dict) else {}
    name = scenario_map.get("name", scenario if isinstance(scenario, str) else None)
    rows = [("folder", str(folder))]
    if name is not None:
        rows.append(("scenario", _format(name)))
    for key in ("seed", "version"):
        value = meta.get(key, scenario_map.get(key))
        if value is not None:
            rows.append((key, _format(value)))
    if result.t.size > 1:
        step = float(np.median(np.diff(result.t)))
        rows.append(("recording rate (median)", f"{1.0 / step:.6g} Hz (dt = {step:.6g} s)"))
    rows += _stack_rows(meta, scenario_map)
    shown = {"scenario", "seed", "version", "observer", "controller"}
    rows += [(k, _format(v)) for k, v in meta.items() if k not in shown and _is_scalar(v)]
    rows += [
        (f"scenario.{k}", _format(v))
        for k, v in scenario_map.items()
        if k not in shown | {"name"} and _is_scalar(v)
    ]
    return rows


def _metric_rows(
    result: SimResult, computed: Mapping[str, float]
) -> tuple[list[tuple[str, str, str]], str]:
    """Rows (metric, value, unit) and a note saying where they come from; ``computed`` the
    result's :func:`metrics`."""
    values: dict[str, Any] = dict(computed)
    values.update(result.summary)
    rows = []
    for key, value in values.items():
        info = METRICS.get(key)
        if info is not None and isinstance(value, int | float) and not isinstance(value, bool):
            text, unit = shown(key, value)
            rows.append((info.label, text, unit))
        else:
            rows.append((key, _format(value), ""))
    if result.summary:
        note = "Stored by the run, completed by values computed from the saved signals."
    else:
        note = "Computed from the saved signals (the run stored no summary)."
    return rows, note


def _table(header: tuple[str, ...], rows: list[tuple[str, ...]], numeric: int = -1) -> str:
    head = "".join(f"<th>{_esc(h)}</th>" for h in header)
    body = []
    for row in rows:
        cells = "".join(
            f'<td class="num">{_esc(c)}</td>' if j == numeric else f"<td>{_esc(c)}</td>"
            for j, c in enumerate(row)
        )
        body.append(f"<tr>{cells}</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def _safety_fault(folder: Path) -> str | None:
    """The safety fault that stopped a real-time run, from the ``timing.json`` that
    ``motosim run`` writes beside its rows (None without one, or without a fault).

    Its rows are closed marked partial, like an interrupted run's; the fault is said here.
    """
    timing = folder / "timing.json"
    try:
        recorded = json.loads(timing.read_text(encoding="utf-8"))
    except (OSError, ValueError, UnicodeDecodeError):
        return None  # no real-time run, or a damaged file: the rows still tell the run
    if not isinstance(recorded, dict) or recorded.get("fault") in (None, "NONE"):
        return None
    return f"safety fault: {recorded.get('fault_reason') or recorded['fault']}"


def _start_figures(
    result: SimResult, source: Path, workers: "FigureWorkers | None"
) -> Callable[[], Sequence[str | None]]:
    """A function that returns the base64 SVG of each of :data:`FIGURES` (None where the
    signals lack): drawn by ``workers`` when given and able, which start on them here, else
    drawn in this process when it is called."""
    if not result.t.size:
        return lambda: [None] * len(FIGURES)
    names = [name for _, name in FIGURES]
    waiting = workers.start(source, names) if workers is not None else None

    def drawn() -> Sequence[str | None]:
        images = waiting() if waiting is not None else None
        if images is not None:
            return images
        return [draw_figure(result, name) for name in names]

    return drawn


def build_report(folder: str | Path, *, workers: "FigureWorkers | None" = None) -> Path:
    """Write ``folder/report.html`` from the result saved in ``folder``.

    Parameters
    ----------
    folder : str or Path
        A result folder written by :class:`motosim.io.results.ResultWriter`.
    workers : FigureWorkers, optional
        Processes that draw the figures (:class:`motosim.report.figures.FigureWorkers`,
        started before the run); by default, or when they cannot, the figures are drawn here.

    Returns
    -------
    Path
        The report file: title, run facts (scenario, seed, version, rates), metrics table
        (the stored summary, completed by :func:`metrics`), the figures of
        :mod:`motosim.plotting.closed_loop` that the signals allow, embedded as SVG, and the
        full metadata as JSON.

    Raises
    ------
    MotosimError
        One line naming the path: no readable result, or a report that cannot be written.
    """
    source = Path(folder)
    result = load_result(source)
    figures = _start_figures(result, source, workers)  # the workers draw while the tables are made
    run_rows = _run_rows(result, source)
    scenario = next((v for k, v in run_rows if k == "scenario"), source.name or str(source))
    title = f"motosim run: {scenario}"
    failed = result.summary.get("failure") or _safety_fault(source)
    if failed:
        status = f'<span class="status interrupted">run failed: {_esc(str(failed))}</span>'
    elif result.complete:
        status = '<span class="status complete">complete</span>'
    else:
        status = '<span class="status interrupted">interrupted: partial result</span>'

    computed = metrics(result)
    metric_rows, note = _metric_rows(result, computed)
    values = {**computed, **result.summary}
    raised = [text for key, text in _FLAGS.items() if values.get(key)]
    checked = [key for key in _FLAGS if key in values]
    if raised:
        flags = "".join(
            f'<p class="status interrupted">warning: {_esc(text)}</p>' for text in raised
        )
    elif len(checked) == len(_FLAGS):
        flags = '<p class="note">No flag: no buzz, no saturation, no fall, speed within range.</p>'
    elif checked:
        flags = f'<p class="note">No flag raised of those checked: {", ".join(checked)}.</p>'
    else:
        flags = '<p class="note">No flag checked: the result has none of their signals.</p>'

    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{_esc(title)}</title><style>{_CSS}</style></head><body>",
        f"<h1>{_esc(title)}</h1><p>{status}</p>",
        flags,
        "<h2>Run</h2>",
        _table(("item", "value"), list(run_rows)),
        "<h2>Metrics</h2>",
        _table(("metric", "value", "unit"), list(metric_rows), numeric=1),
        f'<p class="note">{_esc(note)} Angles shown in degrees.</p>',
        "<h2>Figures</h2>",
    ]
    drawn = 0
    for (caption, _), image in zip(FIGURES, figures(), strict=True):
        if image is not None:
            parts.append(
                f'<figure><img alt="{_esc(caption)}" src="{SVG_DATA}{image}">'
                f"<figcaption>{_esc(caption)}</figcaption></figure>"
            )
            drawn += 1
    for name, caption in _SAVED_FIGURES:  # written beside the result by its command
        saved = source / name
        if source.is_dir() and saved.is_file():
            image = base64.b64encode(saved.read_bytes()).decode("ascii")
            parts.append(
                f'<figure><img alt="{_esc(caption)}" src="data:image/png;base64,{image}">'
                f"<figcaption>{_esc(caption)}</figcaption></figure>"
            )
            drawn += 1
    if not drawn:
        parts.append('<p class="note">No figure: the run has no recorded signals to draw.</p>')
    signals = ", ".join(result.names) or "none"
    parts += [
        "<h2>Signals</h2>",
        f"<p>{_esc(signals)}</p>",
        "<details><summary>Full metadata (JSON)</summary>",
        f"<pre>{_esc(json.dumps(result.metadata, indent=2))}</pre></details>",
        "</body></html>",
    ]
    target = source / _REPORT_NAME if source.is_dir() else source.with_name(_REPORT_NAME)
    text = "\n".join(parts) + "\n"
    return write_whole(target, lambda temporary: temporary.write_text(text, encoding="utf-8"))
