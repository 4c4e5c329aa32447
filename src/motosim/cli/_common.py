"""Helpers shared by the subcommands: option parsing, output files, JSON, figures, progress.

Every command that writes follows the same rules, checked *before* any work is done by
:func:`check_output` (a file) or :func:`check_output_folder` (a folder):

* an existing output is refused unless ``--overwrite`` is given;
* the folder that receives the output must exist (nothing is created silently);
* files are written beside their target under a temporary name and renamed over it only when
  complete (:func:`write_text`, :func:`save_figure`), so a failure (a full disk) leaves the
  previous file intact and reports one line.
"""

import json
import math
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from motosim.errors import MotosimError
from motosim.params.checks import short_repr

__all__ = [
    "check_figure_path",
    "check_output",
    "check_output_folder",
    "parse_float_list",
    "parse_range",
    "print_json",
    "save_figure",
    "show_progress",
    "write_text",
]

MAX_LIST_ITEMS = 10_000
"""Most values accepted in one comma-separated option."""

_FIGURE_FORMATS = (".png", ".svg", ".pdf")


def parse_float_list(option: str, text: str, *, max_items: int = MAX_LIST_ITEMS) -> list[float]:
    """Parse ``"3,5,10"`` into floats, with a one-line error naming the option.

    The number of items is checked before anything is parsed; an empty list or an empty item
    (``"3,,5"``, ``"3,"``) is refused.
    """
    count = text.count(",") + 1
    if count > max_items:
        raise MotosimError(f"{option} gives {count} values; expected at most {max_items}")
    items = text.split(",")
    if not text.strip() or any(not item.strip() for item in items):
        raise MotosimError(
            f"{option} {short_repr(text)}; expected comma-separated numbers such as 3,5,10, "
            "none empty"
        )
    try:
        values = [float(item) for item in items]
    except ValueError:
        raise MotosimError(
            f"{option} {short_repr(text)}; expected comma-separated numbers such as 3,5,10"
        ) from None
    if not values or not all(math.isfinite(x) for x in values):
        raise MotosimError(f"{option} {short_repr(text)}; expected finite comma-separated numbers")
    return values


def parse_range(option: str, text: str, *, max_points: int = 100_000) -> list[float]:
    """Parse ``"start:stop:step"`` into an inclusive list of values."""
    parts = text.split(":")
    try:
        start, stop, step = (float(x) for x in parts)
    except ValueError:
        raise MotosimError(
            f"{option} {short_repr(text)}; expected start:stop:step such as 2:60:0.5"
        ) from None
    if not all(math.isfinite(x) for x in (start, stop, step)) or step <= 0 or stop < start:
        raise MotosimError(
            f"{option} {short_repr(text)}; expected finite start <= stop and a step > 0, "
            "e.g. 2:60:0.5"
        )
    count = math.floor((stop - start) / step + 1e-9) + 1
    if count > max_points:
        raise MotosimError(
            f"{option} {short_repr(text)} gives {count} points; expected at most {max_points}"
        )
    return [start + step * k for k in range(count)]


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


def show_progress(quiet: bool = False) -> bool:
    """Whether to draw a progress bar: only on a terminal, never with ``--json`` (``quiet``).

    A bar redrawn with carriage returns is junk in a log file or a pipe.
    """
    return not quiet and sys.stderr.isatty()


def _refuse_missing_parent(target: Path, option: str) -> None:
    parent = target.parent
    if not parent.is_dir():
        raise MotosimError(
            f"{option} {target}: the folder {parent} does not exist; expected an existing "
            "folder (create it first)"
        )


def check_output(
    path: str | Path,
    *,
    overwrite: bool,
    option: str = "--out",
    suffixes: tuple[str, ...] = (),
) -> Path:
    """Check an output file before any work is done.

    Parameters
    ----------
    path : str or Path
        The file to write.
    overwrite : bool
        Whether an existing file may be replaced (``--overwrite``).
    option : str, optional
        The option that named it, for messages.
    suffixes : tuple of str, optional
        Admitted suffixes (lower case), e.g. ``(".png", ".svg")``; any when empty.

    Returns
    -------
    Path
        The target.

    Raises
    ------
    MotosimError
        If the suffix is not admitted, the target is a folder, its folder does not exist, or
        it exists and ``overwrite`` is false.
    """
    if not str(path).strip():
        raise MotosimError(f"{option} is empty; expected a file name")
    target = Path(path)
    if suffixes and target.suffix.lower() not in suffixes:
        raise MotosimError(
            f"{option} {short_repr(str(path))}; expected a name ending in {', '.join(suffixes)}"
        )
    if target.is_dir():
        raise MotosimError(f"{option} {target} is a folder; expected a file name")
    _refuse_missing_parent(target, option)
    if target.exists() and not overwrite:
        raise MotosimError(f"{option} {target} exists; give --overwrite to replace it")
    return target


def check_output_folder(path: str | Path, *, overwrite: bool, option: str = "--out") -> Path:
    """Check an output folder before any work is done: absent or empty, or ``overwrite``.

    Parameters
    ----------
    path : str or Path
        The folder to write; its parent must exist.
    overwrite : bool
        Whether a folder holding files may be written into (``--overwrite``).
    option : str, optional
        The option that named it, for messages.

    Returns
    -------
    Path
        The folder.

    Raises
    ------
    MotosimError
        If it is a file, its parent does not exist, or it holds files and ``overwrite`` is
        false.
    """
    if not str(path).strip():
        raise MotosimError(f"{option} is empty; expected a folder name")
    target = Path(path)
    if target.exists() and not target.is_dir():
        raise MotosimError(f"{option} {target} is a file; expected a folder")
    _refuse_missing_parent(target, option)
    if target.is_dir() and any(target.iterdir()) and not overwrite:
        raise MotosimError(
            f"{option} {target} is not empty; give --overwrite to replace what it holds"
        )
    return target


def _atomic_write(target: Path, write: Callable[[Path], object]) -> Path:
    """Write through ``write`` into a temporary sibling, then rename it over ``target``."""
    _refuse_missing_parent(target, "output")
    temporary = target.with_name(f".{target.name}.{os.getpid()}.partial")
    try:
        write(temporary)
        os.replace(temporary, target)
    except OSError as err:
        temporary.unlink(missing_ok=True)
        raise MotosimError(
            f"cannot write {target}: {err.strerror or err}; the previous file, if any, is kept"
        ) from None
    return target


def write_text(path: str | Path, text: str) -> Path:
    """Write a text file whole or not at all; a one-line error if it cannot be written."""
    return _atomic_write(Path(path), lambda tmp: tmp.write_text(text, encoding="utf-8"))


def check_figure_path(path: str, *, overwrite: bool = True, option: str = "--plot") -> Path:
    """Check a figure file name before any work is done; the format follows the suffix."""
    target = Path(path)
    if target.suffix.lower() not in _FIGURE_FORMATS:
        raise MotosimError(
            f"figure file {short_repr(path)}; expected a name ending in "
            f"{', '.join(_FIGURE_FORMATS)}"
        )
    return check_output(target, overwrite=overwrite, option=option)


def save_figure(fig: Any, path: str) -> Path:
    """Save a matplotlib figure whole or not at all, in the format of its suffix."""
    target = Path(path)
    if target.suffix.lower() not in _FIGURE_FORMATS:
        raise MotosimError(
            f"figure file {short_repr(path)}; expected a name ending in "
            f"{', '.join(_FIGURE_FORMATS)}"
        )
    fmt = target.suffix.lower().removeprefix(".")
    return _atomic_write(target, lambda tmp: fig.savefig(tmp, dpi=120, format=fmt))
