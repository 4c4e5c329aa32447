"""Helpers shared by the subcommands: option parsing, JSON output, figure saving."""

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from motosim.errors import MotosimError

__all__ = [
    "check_figure_path",
    "parse_float_list",
    "parse_range",
    "print_json",
    "save_figure",
    "write_text",
]

_FIGURE_FORMATS = (".png", ".svg", ".pdf")


def parse_float_list(option: str, text: str) -> list[float]:
    """Parse ``"3,5,10"`` into floats, with a one-line error naming the option."""
    try:
        values = [float(item) for item in text.split(",") if item.strip()]
    except ValueError:
        raise MotosimError(
            f"{option} {text!r}; expected comma-separated numbers such as 3,5,10"
        ) from None
    if not values or not all(math.isfinite(x) for x in values):
        raise MotosimError(f"{option} {text!r}; expected finite comma-separated numbers")
    return values


def parse_range(option: str, text: str, *, max_points: int = 100_000) -> list[float]:
    """Parse ``"start:stop:step"`` into an inclusive list of values."""
    parts = text.split(":")
    try:
        start, stop, step = (float(x) for x in parts)
    except ValueError:
        raise MotosimError(
            f"{option} {text!r}; expected start:stop:step such as 2:60:0.5"
        ) from None
    if not all(math.isfinite(x) for x in (start, stop, step)) or step <= 0 or stop < start:
        raise MotosimError(
            f"{option} {text!r}; expected finite start <= stop and a step > 0, e.g. 2:60:0.5"
        )
    count = math.floor((stop - start) / step + 1e-9) + 1
    if count > max_points:
        raise MotosimError(f"{option} {text!r} gives {count} points; expected at most {max_points}")
    return [float(x) for x in start + step * np.arange(count)]


def _finite_or_none(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {key: _finite_or_none(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [_finite_or_none(item) for item in value]
    return value


def print_json(payload: Any) -> None:
    """Print an object as strict JSON on standard output; inf and NaN become null."""
    print(json.dumps(_finite_or_none(payload), indent=2, allow_nan=False))


def write_text(path: str | Path, text: str) -> Path:
    """Write a text file, creating its folder; a one-line error if it cannot be written."""
    target = Path(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text, encoding="utf-8")
    except OSError as err:
        raise MotosimError(f"cannot write {path}: {err.strerror}") from None
    return target


def check_figure_path(path: str) -> Path:
    """Check a figure file name before any work is done; the format follows the suffix."""
    target = Path(path)
    if target.suffix.lower() not in _FIGURE_FORMATS:
        raise MotosimError(
            f"figure file {path!r}; expected a name ending in {', '.join(_FIGURE_FORMATS)}"
        )
    return target


def save_figure(fig: Any, path: str) -> Path:
    """Save a matplotlib figure, creating the folder."""
    target = check_figure_path(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(target, dpi=120)
    except OSError as err:
        raise MotosimError(f"cannot write figure {path!r}: {err.strerror}") from None
    return target
