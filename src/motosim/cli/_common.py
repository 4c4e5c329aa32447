"""Helpers shared by the subcommands: option parsing, output files, JSON, figures, progress.

Every command checks what it reads and writes *before* any heavy import (SciPy, numba, h5py,
the compiled stack) or work: its inputs with :func:`check_input` (and a scenario's named files
with :func:`check_scenario_inputs`), its outputs with :func:`check_output` (a file) or
:func:`check_output_folder` (a folder):

* an input must be there, be a file (or a folder where one is meant), be readable, not be a
  symbolic link loop, and a text input must be UTF-8 text;
* an existing output is refused unless ``--overwrite`` is given;
* an output file's name ending in ``/`` names a folder, and is refused where a file is meant;
* the folder that receives the output must exist (nothing is created silently) and take a
  file: a probe file is created and removed there, so that ``/proc``, a read-only mount or a
  folder without write permission is refused at once rather than after the work;
* files are written beside their target under a temporary name and renamed over it only when
  complete (:func:`write_text`, :func:`save_figure`), so a failure (a full disk) leaves the
  previous file intact and reports one line.
"""

import codecs
import json
import math
import os
import signal
import sys
import tempfile
import threading
import warnings
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from types import FrameType
from typing import Any, NamedTuple

from motosim.errors import MotosimError, MotosimWarning, StopFlag, stop_signals, warn
from motosim.params.checks import path_problem, short_repr

__all__ = [
    "TYPICAL_OPTIONS",
    "check_figure_path",
    "check_folder_target",
    "check_input",
    "check_named_input",
    "check_output",
    "check_output_folder",
    "check_result_folder",
    "check_result_input",
    "check_scenario_inputs",
    "check_scenario_values",
    "deferred_warnings",
    "finish_files_on_stop",
    "parse_float_list",
    "parse_range",
    "print_json",
    "refuse_inside",
    "refuse_special",
    "save_figure",
    "show_progress",
    "warn_atypical",
    "write_text",
]

MAX_LIST_ITEMS = 10_000
"""Most values accepted in one comma-separated option."""

_FIGURE_FORMATS = (".png", ".svg", ".pdf")


class Typical(NamedTuple):
    """The typical range of a numeric option: legal values outside it are warned about."""

    low: float
    high: float
    unit: str
    why: str


_SPEEDS = Typical(
    3.0,
    55.0,
    "m/s",
    "of a ride the model represents (Sharp 1971: the machine falls below 3, "
    "wobble is unstable above 55)",
)
_MODES_SWEEP = Typical(
    2.0,
    60.0,
    "m/s",
    "of a modes sweep (the weave unstable at walking pace, the wobble above 55 m/s)",
)
_LOOP_RATE = Typical(
    100.0,
    10_000.0,
    "Hz",
    "of a handlebar loop (100 Hz over the paper's CAN link, up to a drive's 10 kHz)",
)
_TURNS = Typical(
    5.0, 50.0, "m/s", "of a steady turn on a road (a roundabout at 5, a motorway bend at 50)"
)
_REPLAY = Typical(0.1, 10.0, "", "replay speeds a person follows")

TYPICAL_OPTIONS: dict[tuple[str, str], Typical] = {
    ("excite", "--duration"): Typical(10.0, 600.0, "s", "of an identification run (tens of s)"),
    ("excite", "--rate"): _LOOP_RATE,
    ("excite", "--current-noise"): Typical(
        0.0, 1.0, "A", "of a current sensor's noise (tens of mA)"
    ),
    ("excite", "--amplitude"): Typical(0.1, 48.0, "V", "of a handlebar motor's supply"),
    ("excite", "--counts"): Typical(
        100.0, 1e7, "", "counts per revolution of a motor encoder (hundreds to millions)"
    ),
    ("modes", "--speeds"): _MODES_SWEEP,
    ("modes", "--range"): _MODES_SWEEP,
    ("trim", "--speed"): _TURNS,
    ("trim", "--speeds"): _TURNS,
    ("design", "--speeds"): _SPEEDS,
    ("design", "--rate"): _LOOP_RATE,
    ("design", "--bandwidth"): Typical(
        1.0, 50.0, "Hz", "of a steering feel (the rider's steering is below 5 Hz)"
    ),
    ("fidelity", "--speed"): _SPEEDS,
    ("fidelity", "--duration"): Typical(
        20.0, 300.0, "s", "of a feel measurement (a chirp over 0.1-5 Hz)"
    ),
    ("fidelity", "--amplitude"): Typical(0.5, 50.0, "N*m", "of a rider's steering torque"),
    ("rt-check", "--rate"): _LOOP_RATE,
    ("rt-check", "--duration"): Typical(1.0, 3600.0, "s", "of a latency check"),
    ("rig", "--rate"): _LOOP_RATE,
    ("rig", "--duration"): Typical(1.0, 14_400.0, "s", "of a session on the rig"),
    ("run", "--duration"): Typical(1.0, 3600.0, "s", "of a ride on the simulator"),
    ("cueing", "--rate"): Typical(50.0, 1000.0, "Hz", "of a motion platform's loop"),
    ("view", "--rate"): _REPLAY,
    ("telemetry", "--rate"): _REPLAY,
}
"""Typical range of each numeric option, by (command, option). A legal value outside it is
accepted with one line ``motosim: warning: ...`` (:func:`warn_atypical`); values outside the
legal range are refused by the command."""


def warn_atypical(command: str, option: str, values: float | Iterable[float] | None) -> None:
    """Warn once, in one line, when a legal ``option`` value is outside its typical range.

    Parameters
    ----------
    command : str
        The subcommand, e.g. ``"excite"``.
    option : str
        The option, a key of :data:`TYPICAL_OPTIONS` with ``command``.
    values : float, iterable of float or None
        The option's value (or values of a list option), already checked legal; None (the
        option not given) warns nothing.
    """
    if values is None:
        return
    typical = TYPICAL_OPTIONS[(command, option)]
    numbers = [float(values)] if isinstance(values, int | float) else [float(v) for v in values]
    odd = sorted({v for v in numbers if not typical.low <= v <= typical.high})
    if not odd:
        return
    shown = ", ".join(f"{v:g}" for v in odd[:5]) + (", ..." if len(odd) > 5 else "")
    unit = f" {typical.unit}" if typical.unit else ""
    verb = "is" if len(odd) == 1 else "are"
    warn(
        f"{option} {shown}{unit} {verb} legal but outside the typical {typical.low:g} to "
        f"{typical.high:g}{unit} {typical.why}; check the value and its unit"
    )


@contextmanager
def deferred_warnings() -> Iterator[None]:
    """Hold the warnings raised in the block; show them when it ends, unless it is refused.

    A refused command prints only its error: the warnings of a scenario read before a later
    check (a missing CSV profile, design or safety table) refuses it would be more lines.
    Interrupted (Ctrl-C), the block's warnings are shown.

    Yields
    ------
    None
        Nothing: the block runs with the warnings held.
    """
    refused = False
    caught: list[warnings.WarningMessage] = []
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", MotosimWarning)
            try:
                yield
            except MotosimError:
                refused = True
                raise
    finally:
        for item in [] if refused else caught:
            warnings.warn_explicit(item.message, item.category, item.filename, item.lineno)


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
    span = (stop - start) / step  # inf for a subnormal step
    if not span < max_points:
        raise MotosimError(
            f"{option} {short_repr(text)} gives {span + 1:.3g} points; expected at most "
            f"{max_points}"
        )
    count = math.floor(span + 1e-9) + 1
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


_SNIFF_BYTES = 65_536
"""Bytes of a text input read to tell it from a binary or non-UTF-8 file."""


def check_input(path: str | Path, what: str, *, folder: bool = False, text: bool = False) -> Path:
    """Refuse an input the command cannot read, before any work, in one line naming it.

    Parameters
    ----------
    path : str or Path
        The file or folder to read.
    what : str
        What it should be, for messages ("scenario file", "result folder", ...).
    folder : bool, optional
        Whether a folder is meant (else a regular file).
    text : bool, optional
        Whether the file is text: its first bytes must then be UTF-8 without NUL bytes.

    Returns
    -------
    Path
        The input.

    Raises
    ------
    MotosimError
        If it is missing, a symbolic link loop or a link to nothing, a folder where a file is
        meant (or the reverse), a device, unreadable, or (``text``) binary or not UTF-8.
    """
    source = Path(path)
    problem = path_problem(source, what, folder=folder)
    if problem is not None:
        raise MotosimError(problem)
    if text:
        try:
            with source.open("rb") as handle:
                head = handle.read(_SNIFF_BYTES)
        except OSError as err:
            raise MotosimError(f"{path}: cannot read the {what}: {err.strerror}") from None
        _refuse_binary(head, str(path), what)
    return source


def _refuse_binary(head: bytes, origin: str, what: str) -> None:
    """Refuse the first bytes of a text file that are UTF-16, binary or not UTF-8."""
    if head.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise MotosimError(
            f"{origin}: the {what} is UTF-16 text; expected UTF-8 (save it again as UTF-8)"
        )
    nul = head.find(b"\0")
    if nul >= 0:
        raise MotosimError(
            f"{origin}: the {what} is binary (a NUL byte at offset {nul}); expected a UTF-8 "
            "text file"
        )
    try:
        # a multi-byte character cut at the end of the sample is not an error
        decoder = codecs.getincrementaldecoder("utf-8")()
        decoder.decode(head, final=len(head) < _SNIFF_BYTES)
    except UnicodeDecodeError as err:
        raise MotosimError(
            f"{origin}: the {what} is not UTF-8 text (byte 0x{head[err.start]:02x} at offset "
            f"{err.start}); expected a UTF-8 text file (convert it, e.g. iconv -f latin1 -t "
            "utf-8)"
        ) from None


def check_result_input(path: str | Path, what: str = "result folder") -> Path:
    """Refuse a result folder (or its ``result.h5``) the command cannot read, before h5py.

    A missing folder whose run was stopped (its rows in ``NAME.partial``) is left to
    :func:`motosim.io.results.load_result`, whose message names that folder.

    Parameters
    ----------
    path : str or Path
        The result folder, or the file in it.
    what : str, optional
        What it should be, for messages.

    Returns
    -------
    Path
        The input.

    Raises
    ------
    MotosimError
        What :func:`check_input` refuses of a folder (a file is taken as the result file).
    """
    source = Path(path)
    if not os.path.lexists(source) and source.with_name(source.name + ".partial").is_dir():
        return source
    if source.is_file():
        return check_input(source, what)
    return check_input(source, what, folder=True)


def check_named_input(name: str | Path, what: str) -> None:
    """Check ``name`` as a file when it names one (a ``.toml`` suffix or a folder in it).

    A packaged set's or platform's name (``simacom_handlebar``) is left to its loader.

    Parameters
    ----------
    name : str or Path
        A packaged name or a file.
    what : str
        What the file should be, for messages ("platform file").

    Raises
    ------
    MotosimError
        What :func:`check_input` refuses, for a name that is a file's.
    """
    text = str(name)
    if text.lower().endswith(".toml") or os.sep in text or "/" in text:
        check_input(text, what, text=True)


def check_scenario_inputs(path: str | Path) -> Path:
    """Check a scenario file and the files it names before the scenario model is imported.

    The scenario is read as TOML (a light module); its design file (``[controller] design``),
    parameter files (``[motorcycle] params``, ``[handlebar] true`` and ``nominal`` when they
    name a ``.toml`` file rather than a packaged set), CSV profiles (``kind = "csv"``,
    ``file``) and OpenDRIVE road (``[rider] path``, ``file``) are looked for as
    :func:`motosim.io.runs.resolve` reads them, relative to its folder. The
    scenario's values are checked afterwards, by :func:`check_scenario_values`.

    Parameters
    ----------
    path : str or Path
        The scenario file.

    Returns
    -------
    Path
        The scenario file.

    Raises
    ------
    MotosimError
        One line naming the first file that cannot be read (:func:`check_input`), or the
        scenario's TOML error.
    """
    from motosim.params.toml import read_toml

    source = check_input(path, "scenario file", text=True)
    data = read_toml(source, what="scenario file")
    base = source.parent

    def named_file(name: str, what: str) -> None:
        # as motosim.io.runs.parameter_source: a .toml beside the scenario, else the name
        candidate = base / name
        if candidate.suffix == ".toml" and candidate.is_file():
            check_input(candidate, what, text=True)
        elif name.lower().endswith(".toml") or "/" in name or os.sep in name:
            check_input(name if os.path.lexists(name) else candidate, what, text=True)

    controller = data.get("controller")
    if isinstance(controller, dict) and isinstance(controller.get("design"), str):
        named_file(controller["design"], "design file")
    for table, key in (("motorcycle", "params"), ("handlebar", "true"), ("handlebar", "nominal")):
        section = data.get(table)
        if isinstance(section, dict) and isinstance(section.get(key), str):
            named_file(section[key], "parameter file")
    from motosim.choices import MOTORCYCLE_PROFILES

    for table, keys in (
        ("motorcycle", MOTORCYCLE_PROFILES),
        ("road", ("friction",)),
        ("rider", ("profile", "probe", "path")),
    ):
        section = data.get(table)
        if not isinstance(section, dict):
            continue
        for key in keys:
            spec = section.get(key)
            if not (isinstance(spec, dict) and isinstance(spec.get("file"), str)):
                continue
            what = "OpenDRIVE file" if key == "path" else "log file (CSV)"
            if spec.get("kind") in ("csv", "opendrive"):
                check_input(base / spec["file"], what, text=True)
    return source


def check_scenario_values(path: str | Path) -> None:
    """Check a scenario's values before the numerical stack is imported.

    The file, already checked by :func:`check_scenario_inputs`, is parsed by
    :func:`motosim.sim.scenario.parse_scenario`, which imports NumPy but neither SciPy,
    numba nor h5py, so that a value out of range is refused in one line before the work. Its
    ``[realtime]`` table is left to the commands that read it.

    Raises
    ------
    MotosimError
        One line naming the table, the key, the value and the expected range.
    """
    from motosim.params.toml import read_toml
    from motosim.sim.scenario import parse_scenario

    data = read_toml(Path(path), what="scenario file")
    parse_scenario({k: v for k, v in data.items() if k != "realtime"}, origin=str(path))


def refuse_special(target: Path, option: str, expected: str) -> None:
    """Refuse an output path that is a broken or looping link, or a device, pipe or socket.

    Writing beside such a path and renaming over it would replace the link or the device
    node (``/dev/null``) itself; writing through it would hang (a pipe) or fail late.
    """
    if os.path.lexists(target) and not target.exists():
        raise MotosimError(
            f"{option} {target} is a symbolic link that leads nowhere or to itself; expected "
            f"{expected}"
        )
    if target.exists() and not (target.is_file() or target.is_dir()):
        raise MotosimError(
            f"{option} {target} is a device, a pipe or a socket; expected {expected}"
        )


def refuse_inside(
    output: str | Path,
    source: str | Path,
    what: str,
    option: str = "--out",
    expected: str = "",
) -> None:
    """Refuse an output that is, or holds, an input the command reads.

    Replacing it (``--overwrite`` replaces a result folder whole) would delete the input:
    ``cueing RUN --out RUN`` would replace the run it cues, ``simulate runs/s.toml --out
    runs`` would delete the scenario.

    Parameters
    ----------
    output : str or Path
        The output file or folder.
    source : str or Path
        The input; a name that is not a path (a packaged parameter set) is not checked.
    what : str
        What the input is, for the message ("scenario", "log", ...).
    option : str, optional
        The option that named the output.
    expected : str, optional
        What the option expects ("a result folder"); by default "another file" or "another
        folder" after the input's kind.

    Raises
    ------
    MotosimError
        If ``output`` is ``source`` or one of its parent folders.
    """
    if not Path(source).exists():  # a packaged set's name, or refused as missing elsewhere
        return
    out, src = Path(output).resolve(), Path(source).resolve()
    same = src == out or (out.exists() and os.path.samefile(src, out))
    if same or out in src.parents:
        kind = "file" if same and src.is_file() else "folder"
        raise MotosimError(
            f"{option} {output} {'is' if same else 'holds'} the {what} {source} it reads; "
            f"expected {expected or 'another ' + kind} (writing there would replace it)"
        )


def check_folder_target(
    path: str | Path,
    option: str,
    expected: str,
    *,
    reads: Sequence[tuple[str, str | Path]] = (),
) -> Path:
    """Refuse an output folder that cannot be one, before any work: a special file, one that
    is or holds an input the command reads, a file, or one whose parent does not exist.

    Parameters
    ----------
    path : str or Path
        The folder to write.
    option : str
        The option that named it, for messages.
    expected : str
        What the option expects, with its article ("a result folder").
    reads : sequence of (str, str or Path), optional
        The inputs the command reads, ``(what, path)`` (:func:`refuse_inside`).

    Returns
    -------
    Path
        The folder.

    Raises
    ------
    MotosimError
        One line for the first of these that applies.
    """
    target = Path(path)
    refuse_special(target, option, expected)
    for what, source in reads:
        refuse_inside(target, source, what, option, "another " + expected.removeprefix("a "))
    if target.exists() and not target.is_dir():
        raise MotosimError(f"{option} {target} is a file; expected {expected}")
    _refuse_missing_parent(target, option)
    # the lock beside the folder is written in its parent, the files in the folder
    _refuse_unwritable(target.parent, option, target)
    if target.is_dir():
        _refuse_unwritable(target, option, target)
    return target


def check_result_folder(folder: str | Path, scenario: str | Path, *, overwrite: bool) -> Path:
    """Check a run's result folder (``simulate``, ``run``) before any work is done.

    Parameters
    ----------
    folder : str or Path
        The result folder (``--out``); its parent must exist.
    scenario : str or Path
        The scenario file the run reads: the folder must not be it or hold it.
    overwrite : bool
        Whether a complete result there may be replaced (``--overwrite``); a partial one
        (an interrupted run's) always may.

    Returns
    -------
    Path
        The folder.

    Raises
    ------
    MotosimError
        If the folder is a special file or a file, is or holds the scenario, its parent does
        not exist, or it holds a complete result and ``overwrite`` is false.
    """
    target = check_folder_target(
        folder, "--out", "a result folder", reads=(("scenario", scenario),)
    )
    if not overwrite and target.is_dir():
        from motosim.io.results import is_complete_result  # h5py: only for a folder there

        if is_complete_result(target):
            raise MotosimError(
                f"{target}: already holds a result; give --overwrite or another --out"
            )
    return target


def _refuse_missing_parent(target: Path, option: str) -> None:
    parent = target.parent
    if not parent.is_dir():
        raise MotosimError(
            f"{option} {target}: the folder {parent} does not exist; expected an existing "
            "folder (create it first)"
        )


def _refuse_unwritable(folder: Path, option: str, target: Path) -> None:
    """Refuse a folder that takes no file, found by creating and removing a probe file in it.

    ``os.access`` alone answers yes for ``/proc`` and ``/sys`` to root; the probe is what a
    write then meets: a read-only mount, a pseudo file system, a missing permission.
    """
    try:
        handle, name = tempfile.mkstemp(dir=folder, prefix=".motosim-probe-")
    except OSError as err:
        raise MotosimError(
            f"{option} {target}: cannot write in the folder {folder} ({err.strerror}); "
            "expected a folder this user may write (not /proc, /sys or a read-only mount)"
        ) from None
    os.close(handle)
    os.unlink(name)


def _refuse_folder_name(path: str | Path, option: str) -> None:
    """Refuse a file output whose name ends in ``/``: it names a folder, not a file."""
    text = str(path)
    if text.endswith(("/", os.sep)) and text.strip("/" + os.sep):
        raise MotosimError(
            f"{option} {text} ends in /, which names a folder; expected a file name (such as "
            f"{text}NAME)"
        )


def check_output(
    path: str | Path,
    *,
    overwrite: bool,
    option: str = "--out",
    suffixes: tuple[str, ...] = (),
    reads: Sequence[tuple[str, str | Path]] = (),
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
    reads : sequence of (str, str or Path), optional
        The inputs the command reads, ``(what, path)``: an output that is one of them is
        refused first (:func:`refuse_inside`), even with ``overwrite``.

    Returns
    -------
    Path
        The target.

    Raises
    ------
    MotosimError
        If the name ends in ``/`` or its suffix is not admitted, the target is a folder, its
        folder does not exist or takes no file, or it exists and ``overwrite`` is false.
    """
    if not str(path).strip():
        raise MotosimError(f"{option} is empty; expected a file name")
    _refuse_folder_name(path, option)
    target = Path(path)
    if suffixes and target.suffix.lower() not in suffixes:
        raise MotosimError(
            f"{option} {short_repr(str(path))}; expected a name ending in {', '.join(suffixes)}"
        )
    if target.is_dir():
        raise MotosimError(f"{option} {target} is a folder; expected a file name")
    for what, source in reads:
        refuse_inside(target, source, what, option)
    refuse_special(target, option, "a file name")
    _refuse_missing_parent(target, option)
    if target.exists() and not overwrite:
        raise MotosimError(f"{option} {target} exists; give --overwrite to replace it")
    _refuse_unwritable(target.parent, option, target)
    return target


def check_output_folder(
    path: str | Path,
    *,
    overwrite: bool,
    option: str = "--out",
    reads: Sequence[tuple[str, str | Path]] = (),
) -> Path:
    """Check an output folder before any work is done: absent or empty, or ``overwrite``.

    Parameters
    ----------
    path : str or Path
        The folder to write; its parent must exist.
    overwrite : bool
        Whether a folder holding files may be written into (``--overwrite``).
    option : str, optional
        The option that named it, for messages.
    reads : sequence of (str, str or Path), optional
        The inputs the command reads, ``(what, path)``: a folder that is or holds one of
        them is refused first (:func:`refuse_inside`), even with ``overwrite``.

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
    target = check_folder_target(path, option, "a folder", reads=reads)
    if target.is_dir() and any(target.iterdir()) and not overwrite:
        raise MotosimError(
            f"{option} {target} is not empty; give --overwrite to replace what it holds"
        )
    return target


def _atomic_write(target: Path, write: Callable[[Path], object]) -> Path:
    """Write through ``write`` into a temporary sibling, then rename it over ``target``."""
    from motosim.io.files import write_whole

    _refuse_missing_parent(target, "output")
    return write_whole(target, write)


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


@contextmanager
def finish_files_on_stop() -> Iterator[StopFlag]:
    """Within the block, SIGTERM, SIGHUP and Ctrl-C request a stop on the flag yielded.

    For a command that writes a result: it hands the flag to the writer
    (:class:`motosim.io.results.ResultWriter`, ``stop``), which holds the stop while a block
    of rows goes to both files and raises :class:`KeyboardInterrupt` after it, so the files
    are closed, readable, marked partial. Ctrl-C is taken only where Python's own handler is
    installed (a loop that handles it itself keeps it); outside the main thread, where
    Python cannot install handlers, the block runs unchanged. The previous handlers are
    restored on leaving.

    Examples
    --------
    >>> with finish_files_on_stop() as stop:
    ...     stop.check()
    """
    stop = StopFlag()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def request(signum: int, frame: FrameType | None) -> None:
        stop.request(signal.Signals(signum).name)

    stops = stop_signals()
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        stops.append(signal.SIGINT)
    previous = {sig: signal.signal(sig, request) for sig in stops}
    try:
        yield stop
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


class StopHandler:
    """The SIGINT handler of a long real-time command: Ctrl-C becomes a stop request.

    Until a target is given (:meth:`aim`) the presses are counted, never raised: while the
    compiled code loads, numba and llvmlite call back into Python from C, and a
    KeyboardInterrupt raised in such a callback is printed ("Exception ignored") and lost.
    :meth:`check` acts on them outside any callback. Once aimed, the first press calls the
    target's ``request_stop`` and the next ones its ``emergency_stop``. After :meth:`release`
    a press raises KeyboardInterrupt (the run is over; what is left can be interrupted).
    Installed with :meth:`installed`, which gives the previous handler back.
    """

    def __init__(self) -> None:
        self.count = 0
        self._target: Any = None
        self._released = False

    def __call__(self, signum: int, frame: object) -> None:
        self.count += 1
        if self._released:
            raise KeyboardInterrupt
        if self._target is not None:
            if self.count == 1:
                self._target.request_stop()
            else:
                self._target.emergency_stop()

    def check(self) -> None:
        """Raise KeyboardInterrupt if Ctrl-C was pressed before a target was given."""
        if self.count and self._target is None:
            raise KeyboardInterrupt

    def aim(self, target: Any) -> None:
        """From now on Ctrl-C asks ``target`` to stop (``request_stop``, then
        ``emergency_stop``); presses counted so far are passed on at once."""
        self._target = target
        for press in range(self.count):
            (target.request_stop if press == 0 else target.emergency_stop)()

    def release(self) -> None:
        """From now on Ctrl-C raises KeyboardInterrupt."""
        self._target = None
        self._released = True

    @contextmanager
    def installed(self) -> Iterator["StopHandler"]:
        """Install this handler for SIGINT within the block."""
        import signal

        previous = signal.signal(signal.SIGINT, self)
        try:
            yield self
        finally:
            signal.signal(signal.SIGINT, previous)
