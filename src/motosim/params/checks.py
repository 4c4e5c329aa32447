"""One check for every value that comes from a file or an option.

:func:`check_number` is the single place where a value read from a file or typed on the
command line becomes a ``float``: it refuses booleans, strings, lists, tables, integers too
large for a float, NaN, infinities and values outside a stated range, each in one line that
names the value and what was expected. :func:`check_keys` refuses unknown (misspelled) keys
with the closest known one as a suggestion, :func:`check_text` anything but a short string
where a name goes, and :func:`check_table` anything but a table where a table goes.
"""

import difflib
import errno
import math
import os
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from motosim.errors import MotosimError

__all__ = [
    "check_keys",
    "check_number",
    "check_table",
    "check_text",
    "describe_range",
    "path_problem",
    "short_repr",
    "suggestion",
]

MAX_TEXT = 10_000
"""Longest string accepted where a name, a title or a source goes [characters]."""


def _kind(value: Any) -> str:
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, Mapping):
        return "a table"
    if isinstance(value, list | tuple):
        return "a list"
    if isinstance(value, int | float):
        return "a number"
    return f"a {type(value).__name__}"


def suggestion(name: str, known: Iterable[str]) -> str:
    """``"; did you mean 'x'?"`` for the closest known name, or ``""`` if none is close."""
    close = difflib.get_close_matches(name, list(known), n=1, cutoff=0.7)
    return f"; did you mean {close[0]!r}?" if close else ""


def check_keys(table: Mapping[str, Any], known: Iterable[str], *, where: str, what: str) -> None:
    """Refuse the first key of ``table`` that is not in ``known``, suggesting the closest.

    Parameters
    ----------
    table : Mapping
        The table read.
    known : iterable of str
        The admitted keys.
    where : str
        Names the table in the message, e.g. ``"p.toml: [set]"``.
    what : str
        What a key is, e.g. ``"key"``, ``"table"`` or ``"parameter"``.

    Raises
    ------
    MotosimError
        ``{where}: unknown {what} 'x'; did you mean 'y'? (expected one of ...)``.
    """
    names = list(known)
    for key in table:
        if key not in names:
            raise MotosimError(
                f"{where}: unknown {what} {short_repr(key)}{suggestion(key, names)} "
                f"(expected one of {', '.join(names)})"
            )


def check_text(value: Any, *, where: str, limit: int = MAX_TEXT, one_line: bool = True) -> str:
    """Return ``value`` if it is a string of at most ``limit`` characters.

    Parameters
    ----------
    value : Any
        What was read.
    where : str
        Names the value in the message.
    limit : int, optional
        Longest string admitted [characters].
    one_line : bool, optional
        Refuse line breaks (names, models); free text such as a source may have them.

    Returns
    -------
    str
        The value.

    Raises
    ------
    MotosimError
        If ``value`` is a number, a list, a table, too long or (``one_line``) holds a line
        break.
    """
    if not isinstance(value, str):
        raise MotosimError(f"{where} = {short_repr(value)} is {_kind(value)}; expected a string")
    if len(value) > limit:
        raise MotosimError(
            f"{where} is a string of {len(value)} characters; expected at most {limit}"
        )
    if one_line and ("\n" in value or "\r" in value):
        raise MotosimError(f"{where} = {short_repr(value)}; expected a single line")
    return value


def check_table(value: Any, *, where: str) -> Mapping[str, Any]:
    """Return ``value`` if it is a table (a mapping), else refuse it in one line."""
    if not isinstance(value, Mapping):
        raise MotosimError(f"{where} = {short_repr(value)} is {_kind(value)}; expected a table")
    return value


_REPR_LIMIT = 40


def path_problem(path: str | Path, what: str, *, folder: bool = False) -> str | None:
    """Why ``path`` cannot be read as ``what``, in one line naming it; None when it can.

    The cases, in the order they are told apart: a symbolic link loop, a link to nothing,
    nothing there, a folder where a file is meant (or a file where a folder is), a device, a
    pipe or a socket, and what the process may not read.

    Parameters
    ----------
    path : str or Path
        The input.
    what : str
        What it should be, for the message, e.g. ``"scenario file"`` or ``"result folder"``.
    folder : bool, optional
        Whether a folder is meant (else a regular file).

    Returns
    -------
    str or None
        The message, e.g. ``"x.toml: no such scenario file"``.

    Examples
    --------
    >>> path_problem("/no/such.toml", "scenario file")
    '/no/such.toml: no such scenario file'
    """
    origin = str(path)
    article = "an" if what[:1].lower() in "aeiou" else "a"
    try:
        os.stat(origin)
    except OSError as err:
        if err.errno == errno.ELOOP:
            return (
                f"{origin}: is a symbolic link loop (it leads back to itself); expected "
                f"{article} {what}"
            )
        if os.path.islink(origin):
            return (
                f"{origin}: is a symbolic link to {os.readlink(origin)}, which does not exist; "
                f"expected {article} {what}"
            )
        if err.errno in (errno.ENOENT, errno.ENOTDIR):
            return f"{origin}: no such {what}"
        return f"{origin}: cannot read the {what}: {err.strerror}"
    target = Path(origin)
    if folder and not target.is_dir():
        kind = "a file" if target.is_file() else "a device, a pipe or a socket"
        return f"{origin}: is {kind}; expected {article} {what}"
    if not folder and target.is_dir():
        return f"{origin}: is a directory; expected {article} {what}"
    if not folder and not target.is_file():
        return f"{origin}: is a device, a pipe or a socket; expected {article} {what}"
    if not os.access(origin, os.R_OK | (os.X_OK if folder else 0)):
        return f"{origin}: cannot read the {what}: Permission denied"
    return None


def short_repr(value: Any, limit: int = _REPR_LIMIT) -> str:
    """``repr(value)`` cut to ``limit`` characters, so a 400-digit number stays one short line.

    Parameters
    ----------
    value : Any
        The value to show.
    limit : int, optional
        Maximum number of characters kept.

    Returns
    -------
    str
        The representation, with ``...`` and the full length when cut.
    """
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 10**30:
        text = f"an integer of {len(str(abs(value)))} digits"
        return text
    text = repr(value)
    text = text.replace("\n", "\\n").replace("\r", "\\r")
    if len(text) > limit:
        return f"{text[:limit]}... ({len(text)} characters)"
    return text


def describe_range(
    lower: float = -math.inf,
    upper: float = math.inf,
    *,
    lower_closed: bool = True,
    upper_closed: bool = True,
    unit: str = "",
) -> str:
    """Describe an interval in words, e.g. ``a finite number > 0 and <= 10 [m]``.

    Parameters
    ----------
    lower, upper : float, optional
        Bounds; infinite bounds are left out.
    lower_closed, upper_closed : bool, optional
        Whether each bound is admitted.
    unit : str, optional
        The SI unit, shown in brackets when given.

    Returns
    -------
    str
        The description.
    """
    parts = []
    if lower > -math.inf:
        parts.append(f"{'>=' if lower_closed else '>'} {lower:g}")
    if upper < math.inf:
        parts.append(f"{'<=' if upper_closed else '<'} {upper:g}")
    bounds = " and ".join(parts)
    text = f"a finite number{' ' + bounds if bounds else ''}"
    return f"{text} [{unit}]" if unit else text


def check_number(
    value: Any,
    *,
    where: str,
    lower: float = -math.inf,
    upper: float = math.inf,
    lower_closed: bool = True,
    upper_closed: bool = True,
    unit: str = "",
) -> float:
    """Return ``value`` as a float if it is a finite number in the interval, else refuse it.

    Parameters
    ----------
    value : Any
        What was read: it must be an ``int`` or ``float`` (not a ``bool``), or a NumPy scalar.
    where : str
        Names the value in the message, e.g. ``"sharp.toml: parameter m_f"``.
    lower, upper : float, optional
        The admissible interval (unbounded by default).
    lower_closed, upper_closed : bool, optional
        Whether each bound is admitted (both by default).
    unit : str, optional
        SI unit shown in the message.

    Returns
    -------
    float
        The value.

    Raises
    ------
    MotosimError
        One line ``{where} = {value}; expected a finite number ...`` when the value is not a
        number, is too large for a float, is NaN or infinite, or is out of the interval.

    Examples
    --------
    >>> check_number(2, where="m", lower=0.0, lower_closed=False)
    2.0
    """
    expected = describe_range(
        lower, upper, lower_closed=lower_closed, upper_closed=upper_closed, unit=unit
    )
    if isinstance(value, bool) or not hasattr(value, "__float__") or isinstance(value, str):
        raise MotosimError(f"{where} = {short_repr(value)} is {_kind(value)}; expected {expected}")
    try:
        number = float(value)
    except (OverflowError, TypeError, ValueError):
        raise MotosimError(f"{where} = {short_repr(value)}; expected {expected}") from None
    if not math.isfinite(number):
        raise MotosimError(f"{where} = {short_repr(value)}; expected {expected}")
    above = number >= lower if lower_closed else number > lower
    below = number <= upper if upper_closed else number < upper
    if not (above and below):
        raise MotosimError(f"{where} = {short_repr(value)}; expected {expected}")
    return number
