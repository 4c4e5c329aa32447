"""Reports from saved results only: HTML with the metrics and the figures of a run."""

from motosim.report.html import build_report, metrics

__all__ = ["build_report", "metrics"]
