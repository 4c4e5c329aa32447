"""The one reader of motosim's TOML files: parameter sets, scenarios, design files.

Every TOML file goes through :func:`read_toml` (or :func:`parse_toml` for packaged text), so
that the classes of bad input are refused in one place and in one line naming the file:

* the size is checked before the file is read (:data:`MAX_FILE_BYTES`);
* the text must be UTF-8 (a UTF-8 byte-order mark is accepted); binary, Latin-1 or UTF-16
  content is refused with the offset of the first bad byte;
* a syntax error is the parser's own one-line message with its line and column;
* nesting deeper than :data:`MAX_DEPTH` is refused (a deeply nested array would otherwise
  exhaust Python's recursion limit);
* integers beyond TOML's 64-bit range, non-finite floats (``nan``, ``inf``) and floats of
  magnitude above :data:`MAX_MAGNITUDE` are refused with their key path (integers, such as
  a seed, may use the whole 64-bit range). No quantity of
  motosim in SI units comes near that bound (the largest, a tyre stiffness, is about
  1e5 N/rad; 1e15 s is thirty million years), so such a number is a typo or an attack,
  never data. Values inside it are then checked against their own physical range by the
  reader of each kind of file.

TOML itself is specified at https://toml.io/en/v1.0.0 (64-bit signed integers, UTF-8).
"""

import math
import tomllib
from pathlib import Path
from typing import Any

from motosim.errors import MotosimError
from motosim.params.checks import path_problem, short_repr

__all__ = [
    "MAX_DEPTH",
    "MAX_FILE_BYTES",
    "MAX_MAGNITUDE",
    "parse_toml",
    "read_limited",
    "read_toml",
]

MAX_FILE_BYTES = 1_000_000
"""Largest TOML file read [bytes]; motosim's files are a few kilobytes."""

MAX_DEPTH = 16
"""Deepest nesting of tables and arrays accepted."""

MAX_MAGNITUDE = 1e15
"""Largest absolute value of a number in a TOML file, in SI units."""

_INT_LIMIT = 2**63
_BOM = "\ufeff"


def _decode(raw: bytes, origin: str, what: str) -> str:
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise MotosimError(
            f"{origin}: the {what} is UTF-16 text; expected UTF-8 (save it again as UTF-8)"
        )
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        raise MotosimError(
            f"{origin}: the {what} is not UTF-8 text (byte 0x{raw[err.start]:02x} at offset "
            f"{err.start}); expected a UTF-8 TOML file"
        ) from None
    return text.removeprefix(_BOM)


def _key(path: tuple[str | int, ...]) -> str:
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else part)
    return text or "(top level)"


def _check_tree(data: dict[str, Any], origin: str) -> None:
    """Walk the parsed document without recursion, refusing depth and number overflows."""
    stack: list[tuple[tuple[str | int, ...], Any]] = [((), data)]
    while stack:
        path, node = stack.pop()
        if len(path) > MAX_DEPTH:
            raise MotosimError(
                f"{origin}: {_key(path[:MAX_DEPTH])} is nested more than {MAX_DEPTH} levels deep"
            )
        if isinstance(node, dict):
            stack.extend(((*path, str(k)), v) for k, v in node.items())
        elif isinstance(node, list):
            stack.extend(((*path, i), v) for i, v in enumerate(node))
        elif isinstance(node, bool):
            continue
        elif isinstance(node, int):
            if abs(node) >= _INT_LIMIT:  # larger integers (seeds) are left to their checks
                raise MotosimError(
                    f"{origin}: {_key(path)} = {short_repr(node)}; expected an integer of "
                    "magnitude below 2^63 (TOML's 64-bit range)"
                )
        elif isinstance(node, float):
            if not math.isfinite(node):
                raise MotosimError(f"{origin}: {_key(path)} = {node!r}; expected a finite number")
            if abs(node) > MAX_MAGNITUDE:
                raise MotosimError(
                    f"{origin}: {_key(path)} = {node!r}; expected a number of magnitude "
                    f"<= {MAX_MAGNITUDE:g}"
                )


def parse_toml(text: str, *, origin: str) -> dict[str, Any]:
    """Parse TOML text with the checks of :func:`read_toml` (all but size and encoding).

    Parameters
    ----------
    text : str
        The document.
    origin : str
        Where it came from, the prefix of error messages.

    Returns
    -------
    dict of str to Any
        The parsed document.

    Raises
    ------
    MotosimError
        One line naming ``origin``: a syntax error with its line and column, nesting deeper
        than :data:`MAX_DEPTH`, an integer beyond 64 bits, a non-finite or huge number.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        message = " ".join(str(err).split())
        raise MotosimError(f"{origin}: not valid TOML: {message}") from None
    except RecursionError:
        raise MotosimError(
            f"{origin}: not valid TOML: nested more than {MAX_DEPTH} levels deep"
        ) from None
    except ValueError as err:  # an integer of more than 4300 digits
        message = " ".join(str(err).split())
        raise MotosimError(f"{origin}: not valid TOML: {message}") from None
    _check_tree(data, origin)
    return data


def read_limited(path: Path, *, what: str, max_bytes: int) -> bytes:
    """The bytes of the regular file ``path``, at most ``max_bytes`` of them.

    The size is checked before reading, and again on what was read (a file that grew
    meanwhile, or a special file that claims no size).

    Parameters
    ----------
    path : Path
        The file.
    what : str
        What the file should be, for messages, e.g. ``"parameter file"``.
    max_bytes : int
        Largest size read [bytes].

    Raises
    ------
    MotosimError
        One line naming the file: missing, a directory, unreadable or larger than
        ``max_bytes``.
    """
    origin = str(path)
    problem = path_problem(path, what)
    if problem is not None:
        raise MotosimError(problem)
    try:
        size = path.stat().st_size
        if size > max_bytes:
            raise MotosimError(
                f"{origin}: the {what} is {size} bytes; expected at most {max_bytes} bytes"
            )
        with path.open("rb") as handle:
            raw = handle.read(max_bytes + 1)
    except OSError as err:
        raise MotosimError(f"{origin}: cannot read the {what}: {err.strerror}") from None
    if len(raw) > max_bytes:  # grew while we looked, or a special file
        raise MotosimError(
            f"{origin}: the {what} is over {max_bytes} bytes; expected at most {max_bytes} bytes"
        )
    return raw


def read_toml(path: Path, *, what: str, max_bytes: int = MAX_FILE_BYTES) -> dict[str, Any]:
    """Read a UTF-8 TOML file, refusing in one line whatever is not a sane document.

    Parameters
    ----------
    path : Path
        The file.
    what : str
        What the file should be, for messages, e.g. ``"parameter file"``.
    max_bytes : int, optional
        Largest size read; checked before reading.

    Returns
    -------
    dict of str to Any
        The parsed document; its floats are finite, of magnitude <= :data:`MAX_MAGNITUDE`.

    Raises
    ------
    MotosimError
        One line naming the file: missing, a directory, unreadable, larger than
        ``max_bytes``, not UTF-8, not valid TOML, too deeply nested, or holding an
        out-of-range number (with its key path).

    Examples
    --------
    >>> from importlib import resources
    >>> path = resources.files("motosim.params") / "data" / "sharp1971.toml"
    >>> read_toml(Path(str(path)), what="parameter file")["set"]["model"]
    'sharp'
    """
    origin = str(path)
    raw = read_limited(path, what=what, max_bytes=max_bytes)
    return parse_toml(_decode(raw, origin, what), origin=origin)
