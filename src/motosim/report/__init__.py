"""Reports from saved results only: HTML with the metrics and the figures of a run.

:func:`build_report` and :func:`metrics` are imported on first use (PEP 562): the metrics'
units and summary lines (:mod:`motosim.report.units`) come without matplotlib.
"""

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from motosim.report.html import build_report, metrics

__all__ = ["build_report", "metrics"]


def __getattr__(name: str) -> Any:
    """:func:`build_report` and :func:`metrics`, imported from :mod:`motosim.report.html`."""
    if name in __all__:
        from motosim.report import html

        value = getattr(html, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
