"""The HTML report of a campaign, built from its result folder only.

:func:`build_campaign_report` reads ``DIR/manifest.json`` and the Parquet parts
(:func:`motosim.campaign.load_results`) and writes ``DIR/report.html``: what the campaign
was, how many runs succeeded and failed (with the reasons), each kept metric against each
factor, a heat map of the first metric over the two factors most correlated with it (rank
correlation), the failure region in that plane, and the worst runs with the command that
re-runs each one. One file, the figures embedded as SVG, no JavaScript.
"""

import collections
import html
import json
import shlex
from pathlib import Path
from typing import Any

import numpy as np

from motosim.campaign import METRICS, load_results, read_manifest
from motosim.io.files import write_whole
from motosim.plotting.campaign import plot_failures, plot_heatmap, plot_metric_vs_factors
from motosim.plotting.images import SVG_DATA, svg_base64
from motosim.report.html import _CSS, _table

__all__ = ["build_campaign_report"]

_WORST = 10


def _esc(value: object) -> str:
    return html.escape(str(value))


def _figure(figure: Any, caption: str) -> str:
    return (
        f'<figure><img alt="{_esc(caption)}" src="{SVG_DATA}{svg_base64(figure)}">'
        f"<figcaption>{_esc(caption)}</figcaption></figure>"
    )


def build_campaign_report(folder: str | Path) -> Path:
    """Write ``folder/report.html`` from a campaign's result folder.

    Parameters
    ----------
    folder : str or Path
        A folder written by :func:`motosim.campaign.run_campaign`.

    Returns
    -------
    Path
        The report file.

    Raises
    ------
    MotosimError
        If the folder holds no campaign results or the report cannot be written.
    """
    source = Path(folder)
    manifest = read_manifest(source)
    results = load_results(source)
    campaign = manifest.get("campaign", {})
    name = str(manifest.get("name", source.name))
    factors = [str(f["path"]) for f in campaign.get("factors", [])]
    metrics = [str(m) for m in campaign.get("metrics", [])]
    n = int(results["index"].size) if results else 0
    failed = (results["status"] != "ok") if results else np.zeros(0, dtype=bool)
    title = f"motosim campaign: {name}"
    call = manifest.get("last_call", {})
    facts: list[tuple[str, ...]] = [
        ("campaign file", str(manifest.get("campaign_file", ""))),
        ("base scenario", str(campaign.get("scenario", ""))),
        ("sampling", f"{campaign.get('sampling')} , seed {campaign.get('seed')}"),
        ("runs planned / written", f"{manifest.get('runs')} / {n}"),
        ("failed runs", f"{int(failed.sum())}"),
        ("designs", str(len(manifest.get("designs", {})))),
        ("status", str(manifest.get("status"))),
        ("package version", str(manifest.get("version"))),
        ("backend, workers", f"{manifest.get('backend')}, {manifest.get('workers')}"),
    ]
    if call:
        facts.append(
            (
                "last call",
                f"{call.get('computed')} runs in {call.get('wall', 0.0):.2f} s, "
                f"overhead {100 * call.get('overhead', 0.0):.1f} %",
            )
        )
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{_esc(title)}</title><style>{_CSS}</style></head><body>",
        f"<h1>{_esc(title)}</h1>",
        f"<p>{_esc(campaign.get('description', ''))}</p>",
        "<h2>Campaign</h2>",
        _table(("item", "value"), facts),
    ]
    if n:
        ok_rows: list[tuple[str, ...]] = []
        for m in metrics:
            values = results[m][~failed]
            values = values[np.isfinite(values)]
            if values.size:
                ok_rows.append(
                    (
                        m,
                        METRICS.get(m, ""),
                        f"{np.min(values):.4g}",
                        f"{np.median(values):.4g}",
                        f"{np.max(values):.4g}",
                    )
                )
        parts += [
            "<h2>Metrics over the successful runs</h2>",
            _table(("metric", "meaning", "min", "median", "max"), ok_rows),
        ]
        if failed.any():
            reasons = collections.Counter(
                str(r).split(" at t =")[0] for r in results["reason"][failed]
            )
            reason_rows: list[tuple[str, ...]] = [(r, str(c)) for r, c in reasons.most_common()]
            parts += ["<h2>Failures</h2>", _table(("reason", "runs"), reason_rows, numeric=1)]
        columns = {f: results[f] for f in factors if f in results}
        parts.append("<h2>Metrics against the factors</h2>")
        for m in metrics:
            if m in ("samples", "complete", "duration") or not np.isfinite(results[m]).any():
                continue
            parts.append(
                _figure(
                    plot_metric_vs_factors(columns, results[m], failed, label=m),
                    f"{m}: {METRICS.get(m, '')} against each factor (red: failed runs)",
                )
            )
        numeric = [f for f in factors if f in results and results[f].dtype.kind in "iuf"]
        shown = [m for m in metrics if m not in ("samples", "complete", "duration")]
        if len(numeric) >= 2 and shown and np.isfinite(results[shown[0]]).any():
            fx, fy = _strongest(results, numeric, shown[0])
            parts += [
                "<h2>Heat map and failure region</h2>",
                _figure(
                    plot_heatmap(
                        results[fx],
                        results[fy],
                        results[shown[0]],
                        xlabel=fx,
                        ylabel=fy,
                        zlabel=shown[0],
                    ),
                    f"mean {shown[0]} over {fx} and {fy}",
                ),
            ]
            if failed.any():
                parts.append(
                    _figure(
                        plot_failures(results[fx], results[fy], failed, xlabel=fx, ylabel=fy),
                        f"failed runs in the plane of {fx} and {fy}",
                    )
                )
        parts += _worst(manifest, results, factors, shown, failed, source)
    parts += [
        "<details><summary>Manifest (JSON)</summary>",
        f"<pre>{_esc(json.dumps(manifest, indent=2, default=str))}</pre></details>",
        "</body></html>",
    ]
    target = source / "report.html"
    text = "\n".join(parts) + "\n"
    return write_whole(target, lambda temporary: temporary.write_text(text, encoding="utf-8"))


def _rank(values: Any) -> Any:
    return np.argsort(np.argsort(values, kind="stable"), kind="stable").astype(float)


def _strongest(results: dict[str, Any], factors: list[str], metric: str) -> tuple[str, str]:
    """The two factors with the largest rank correlation (Spearman) with ``metric``."""
    ok = np.isfinite(results[metric])
    target = _rank(results[metric][ok])
    strength = []
    for f in factors:
        x = _rank(results[f][ok])
        spread = float(np.std(x) * np.std(target))
        r = float(np.mean((x - x.mean()) * (target - target.mean())) / spread) if spread else 0.0
        strength.append(abs(r))
    order = np.argsort(strength, kind="stable")[::-1]
    return factors[int(order[0])], factors[int(order[1])]


def _worst(
    manifest: dict[str, Any],
    results: dict[str, Any],
    factors: list[str],
    metrics: list[str],
    failed: Any,
    folder: Path,
) -> list[str]:
    """The worst runs by the first metric (failed runs first), with their re-run command."""
    if not metrics:
        return []
    key = metrics[0]
    score = np.where(failed, np.inf, np.nan_to_num(results[key], nan=np.inf))
    order = np.argsort(-score, kind="stable")[:_WORST]
    file = str(manifest.get("campaign_file") or "CAMPAIGN.toml")
    rows: list[tuple[str, ...]] = []
    for j in order:
        run_id = str(results["run_id"][j])
        values = ", ".join(
            f"{f} = {results[f][j]:.4g}"
            if isinstance(results[f][j], float)
            else f"{f} = {results[f][j]}"
            for f in factors
        )
        command = (
            f"motosim campaign {shlex.quote(file)} --out {shlex.quote(str(folder))} "
            f"--rerun {run_id} --write-scenario {run_id}.toml"
        )
        outcome = str(results["reason"][j]) if failed[j] else f"{results[key][j]:.4g}"
        rows.append((run_id, outcome, values, command))
    return [
        f"<h2>Worst runs by {_esc(key)}</h2>",
        '<p class="note">Each command re-runs the run, checks it against the stored metrics '
        "and writes it as a scenario file for <code>motosim simulate</code>.</p>",
        _table(("run", key, "factors", "re-run"), rows),
    ]
