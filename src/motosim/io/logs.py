"""Time-series logs as CSV: written by motosim, read from motosim or from a real rig.

motosim writes one header row of signal names and one row per instant, the time ``t`` [s]
first and strictly increasing, so pandas and PlotJuggler read the files as they are. Units
are those of :mod:`motosim.signals`.

:func:`read_log` reads those files and the CSV a rig's logger or a spreadsheet writes:

* the delimiter is found from the header (``,``, ``;`` or tab) and, with ``;`` or tab, a
  decimal comma (``0,25``) is read as a decimal point;
* a UTF-8 byte-order mark (Excel's "CSV UTF-8") is skipped, lines starting with ``#`` and
  blank lines are comments; a file that is not UTF-8 is refused in one line;
* a header may carry units, ``t [s]``, ``theta_h (deg)``, ``i_m [mA]``: the values are
  converted to SI (time s, ms, us; angle rad, deg; current A, mA; voltage V, mV);
* a mapping ``t=time,theta_h=angle_deg:deg,i_m=cur:A`` (:func:`parse_columns`) names the
  file's columns for motosim's signals and may give their units.

:func:`read_rig_log` adds what a log from the hardware needs before identification or
estimation: plausibility checks that refuse, naming the likely cause, an angle that looks
like degrees, a time that looks like milliseconds or a current that is not in amperes; and
the timing (:func:`log_timing`): jitter and dropped samples are reported and the log
resampled onto a uniform grid (:func:`resample`) by linear interpolation, since the
filters and the output-error fit of :mod:`motosim.identification` assume a uniform grid.
"""

import csv
import dataclasses
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError, warn
from motosim.io.files import write_whole
from motosim.params.checks import path_problem
from motosim.timeseries import TimeSeries

__all__ = [
    "MAX_LINE",
    "MAX_LOG_BYTES",
    "MAX_LOG_ROWS",
    "MIN_PERIOD",
    "ColumnSpec",
    "LogTiming",
    "RigLog",
    "log_timing",
    "parse_columns",
    "read_log",
    "read_rig_log",
    "resample",
    "write_log",
]

Array = NDArray[np.float64]

# unit name -> (quantity, factor to SI)
_UNITS: dict[str, tuple[str, float]] = {
    "s": ("time", 1.0),
    "ms": ("time", 1e-3),
    "us": ("time", 1e-6),
    "µs": ("time", 1e-6),
    "rad": ("angle", 1.0),
    "deg": ("angle", math.pi / 180.0),
    "°": ("angle", math.pi / 180.0),
    "a": ("current", 1.0),
    "ma": ("current", 1e-3),
    "v": ("voltage", 1.0),
    "mv": ("voltage", 1e-3),
    "rad/s": ("rate", 1.0),
    "deg/s": ("rate", math.pi / 180.0),
    "n*m": ("torque", 1.0),
    "nm": ("torque", 1.0),
    "n m": ("torque", 1.0),
}
_UNIT_NAMES = "s, ms, us, rad, deg, A, mA, V, mV"  # the units messages list

# motosim's signals with a quantity, for unit checks; others take any unit as SI
_QUANTITY: dict[str, str] = {
    "t": "time",
    "theta_h": "angle",
    "delta": "angle",
    "i_m": "current",
    "i_cmd": "current",
    "u": "voltage",
    "theta_h_dot": "rate",
    "tau_r": "torque",
    "tau_m": "torque",
}

_HEADER = re.compile(r"^\s*(?P<name>[^\[\(]*?)\s*(?:[\[\(]\s*(?P<unit>[^\]\)]*?)\s*[\]\)])?\s*$")

MAX_GAP_PERIODS = 5
"""Longest gap (in sample periods) :func:`read_rig_log` fills by interpolation."""
MIN_PERIOD = 1e-6
"""Shortest median sample period of a rig log [s] (1 MHz: no handlebar drive logs faster)."""

JITTER_TOLERANCE = 0.01
"""Largest deviation of a sample period from the median, as a fraction, left unresampled."""
JITTER_WARNING = 0.05
"""Deviation of a sample period from the median, as a fraction, beyond which a rig log's
resampling is warned about (a drive's clocked log jitters by well under a percent)."""


@dataclass(frozen=True, slots=True)
class ColumnSpec:
    """Where a signal is in a file and in which unit.

    Attributes
    ----------
    source : str
        Column name in the file's header (without its unit).
    unit : str or None
        Unit of the values (``s``, ``ms``, ``us``, ``rad``, ``deg``, ``A``, ``mA``, ``V``,
        ``mV``); None takes the header's unit, or SI.
    """

    source: str
    unit: str | None = None

    def __post_init__(self) -> None:
        if not self.source:
            raise MotosimError("column mapping with an empty source name; expected NAME[:UNIT]")
        if self.unit is not None and self.unit.lower() not in _UNITS:
            raise MotosimError(
                f"unit {self.unit!r} of column {self.source!r}; expected one of {_UNIT_NAMES}"
            )


def parse_columns(text: str) -> dict[str, ColumnSpec]:
    """Parse a column mapping ``signal=column[:unit],...``.

    Parameters
    ----------
    text : str
        For example ``t=time,theta_h=angle_deg:deg,i_m=cur:A``.

    Returns
    -------
    dict of str to ColumnSpec
        Signal name -> its column and unit.

    Raises
    ------
    MotosimError
        On an entry without ``=``, an empty name, a repeated signal or an unknown unit.

    Examples
    --------
    >>> parse_columns("t=time:ms,theta_h=angle")["t"]
    ColumnSpec(source='time', unit='ms')
    """
    mapping: dict[str, ColumnSpec] = {}
    for item in (part.strip() for part in text.split(",")):
        if not item:
            continue
        signal, sep, rest = item.partition("=")
        if not sep or not signal.strip():
            raise MotosimError(
                f"--columns entry {item!r}; expected SIGNAL=COLUMN[:UNIT], e.g. "
                "t=time,theta_h=angle_deg:deg,i_m=cur:A"
            )
        source, _, unit = rest.partition(":")
        if signal.strip() in mapping:
            raise MotosimError(f"--columns gives {signal.strip()!r} twice; expected it once")
        mapping[signal.strip()] = ColumnSpec(source.strip(), unit.strip() or None)
    if not mapping:
        raise MotosimError(f"--columns {text!r}; expected SIGNAL=COLUMN[:UNIT],...")
    return mapping


MAX_LOG_BYTES = 64_000_000
"""Largest log file read [bytes]: checked before reading (about 2 million rows of three
columns as motosim writes them)."""

MAX_LINE = 10_000
"""Longest line of a log [characters]: a row of numbers is a few dozen."""

MAX_LOG_ROWS = 1_000_000
"""Most rows in a log (17 min at 1 kHz), checked before any row is parsed."""


def _decode(source: Path, label: str) -> list[tuple[int, str]]:
    """The file's non-comment, non-blank lines with their line numbers."""
    try:
        size = source.stat().st_size
        if size > MAX_LOG_BYTES:
            raise MotosimError(
                f"{label}: the log is {size} bytes; expected at most {MAX_LOG_BYTES} bytes "
                f"(at most {MAX_LOG_ROWS} rows: cut or decimate it)"
            )
        raw = source.read_bytes()
    except OSError as err:
        raise MotosimError(f"{label}: cannot read the log: {err.strerror or err}") from None
    rows = raw.count(b"\n")
    if rows > MAX_LOG_ROWS + 100:  # the header and a few comment lines besides the rows
        raise MotosimError(
            f"{label}: the log has {rows} lines; expected at most {MAX_LOG_ROWS} rows (cut or "
            "decimate it: identification and estimation need minutes, not hours)"
        )
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise MotosimError(
            f"{label}: the log is UTF-16 text; expected UTF-8 (save it again as UTF-8)"
        )
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        line = raw[: err.start].count(b"\n") + 1
        raise MotosimError(
            f"{label}: byte 0x{raw[err.start]:02X} on line {line} is not UTF-8; expected a "
            "UTF-8 text file (convert it, e.g. iconv -f latin1 -t utf-8)"
        ) from None
    return [
        (k + 1, line)
        for k, line in enumerate(text.splitlines())
        if line.strip() and not line.lstrip().startswith("#")
    ]


def _delimiter(header: str) -> str:
    return next((candidate for candidate in ("\t", ";") if candidate in header), ",")


def _split_header(cell: str) -> tuple[str, str | None]:
    match = _HEADER.match(cell.strip().strip('"').strip("'"))
    if match is None:  # an unclosed bracket, or text after the unit: a name without unit
        return cell.strip(), None
    return match["name"], match["unit"] or None


def read_log(
    path: str | Path,
    *,
    required: Sequence[str],
    min_samples: int = 10,
    columns: Mapping[str, ColumnSpec] | None = None,
    remedy: str | None = None,
) -> TimeSeries:
    """Read and validate a CSV log, converting its columns to SI.

    Parameters
    ----------
    path : str or Path
        The CSV file; its header names the columns, one of which is ``t`` (or is mapped to
        it). The header may carry units (``t [ms]``, ``theta_h (deg)``).
    required : sequence of str
        Signals that must be present besides ``t``.
    min_samples : int
        Fewest rows accepted.
    columns : mapping of str to ColumnSpec, optional
        Signal -> column of the file and unit (:func:`parse_columns`); signals not mapped are
        taken from the column of their own name.
    remedy : str, optional
        What the message of a missing column advises (default: the ``--columns`` option of
        the commands that read logs).

    Returns
    -------
    TimeSeries
        Every column but ``t``, in file order, under the signal names, in SI units.

    Raises
    ------
    MotosimError
        One line naming the file and the problem: missing file or column, a file that is
        not UTF-8, a value that is not a number, NaN, a unit that does not fit the signal,
        a time that does not strictly increase, too few samples.
    """
    lines, delimiter = _lines(Path(path), str(path))
    cells = next(csv.reader([lines[0][1]], delimiter=delimiter))
    parsed = [_split_header(cell) for cell in cells]
    names = [name for name, _ in parsed]
    if len(set(names)) != len(names):
        raise MotosimError(f"{path}: duplicated column names in the header {names}")
    chosen = _chosen_columns(str(path), dict(parsed), names, columns or {})
    missing = [name for name in ("t", *required) if name not in chosen]
    if missing:
        raise MotosimError(
            f"{path}: missing column {missing[0]!r}; expected columns "
            f"{', '.join(('t', *required))} (found {', '.join(names) or 'no header'}; "
            + (remedy or f"map yours with --columns {missing[0]}=NAME[:UNIT]")
            + ")"
        )
    data = _numbers(str(path), lines, names, delimiter)
    if data.shape[0] < min_samples:
        raise MotosimError(f"{path}: {data.shape[0]} samples; expected at least {min_samples}")
    return _series(str(path), data, chosen, lines)


def _series(
    label: str,
    data: Array,
    chosen: Mapping[str, tuple[int, str | None]],
    lines: list[tuple[int, str]],
) -> TimeSeries:
    """The chosen columns of ``data`` in SI units, in file order, ``t`` strictly increasing."""
    converted: dict[str, Array] = {}
    for signal, (index, unit) in chosen.items():
        converted[signal] = data[:, index] * _factor(label, signal, unit)
    t = converted.pop("t")
    steps = np.diff(t)
    if np.any(steps <= 0):
        k = int(np.argmax(steps <= 0))
        kind = "repeats" if steps[k] == 0 else "goes back"
        number = lines[k + 2][0]
        raise MotosimError(
            f"{label}: time {kind} at line {number} (t = {t[k + 1]:g} s after {t[k]:g} s); "
            "expected strictly increasing t"
        )
    order = sorted(converted, key=lambda s: chosen[s][0])
    values = np.column_stack([converted[s] for s in order]) if order else np.empty((t.size, 0))
    return TimeSeries(t.copy(), values, tuple(order))


def _lines(source: Path, label: str) -> tuple[list[tuple[int, str]], str]:
    """The numbered non-blank lines of a log, header first, and its field delimiter."""
    problem = path_problem(source, "log file (CSV)")
    if problem is not None:
        raise MotosimError(problem)
    lines = _decode(source, label)
    if not lines:
        raise MotosimError(f"{label}: empty log; expected a header row and data rows")
    if max(len(text) for _, text in lines) > MAX_LINE:
        number, _ = max(lines, key=lambda item: len(item[1]))
        raise MotosimError(
            f"{label}: line {number} is longer than {MAX_LINE} characters; expected a CSV "
            "row of numbers"
        )
    return lines, _delimiter(lines[0][1])


def _chosen_columns(
    label: str,
    header_units: Mapping[str, str | None],
    names: list[str],
    mapping: Mapping[str, ColumnSpec],
) -> dict[str, tuple[int, str | None]]:
    """Signal -> (index of its column in the file, unit): the mapped ones, then every other
    column under its own name."""
    chosen: dict[str, tuple[int, str | None]] = {}
    for signal, spec in mapping.items():
        if spec.source not in names:
            raise MotosimError(
                f"{label}: --columns maps {signal} to {spec.source!r}, which is not a column; "
                f"expected one of {', '.join(names)}"
            )
        chosen[signal] = (names.index(spec.source), spec.unit or header_units[spec.source])
    mapped_sources = {spec.source for spec in mapping.values()}
    for index, name in enumerate(names):
        if name not in chosen and name not in mapped_sources:
            chosen[name] = (index, header_units[name])
    return chosen


def _numbers(label: str, lines: list[tuple[int, str]], names: list[str], delimiter: str) -> Array:
    """The data rows (every line after the header) as finite numbers, one column a name."""
    rows = list(csv.reader([text for _, text in lines[1:]], delimiter=delimiter))
    data = np.empty((len(rows), len(names)))
    for i, row in enumerate(rows):
        number = lines[i + 1][0]
        if len(row) != len(names):
            raise MotosimError(
                f"{label}: line {number} has {len(row)} fields; expected {len(names)}"
            )
        for j, cell in enumerate(row):
            text = cell.strip()
            if delimiter != ",":  # a decimal comma
                text = text.replace(",", ".")
            try:
                value = float(text)
            except ValueError:
                raise MotosimError(
                    f"{label}: line {number}, column {names[j]}: {cell!r} is not a number"
                ) from None
            if not math.isfinite(value):
                raise MotosimError(
                    f"{label}: line {number}, column {names[j]}: {cell.strip()}; "
                    "expected a finite number"
                )
            data[i, j] = value
    return data


def _factor(label: str, signal: str, unit: str | None) -> float:
    if unit is None:
        return 1.0
    key = unit.strip().lower()
    if key not in _UNITS:
        raise MotosimError(f"{label}: unit {unit!r} of {signal}; expected one of {_UNIT_NAMES}")
    quantity, factor = _UNITS[key]
    expected = _QUANTITY.get(signal)
    if expected is not None and quantity != expected:
        raise MotosimError(
            f"{label}: {signal} given in {unit}, a unit of {quantity}; expected a unit of "
            f"{expected}"
        )
    return factor


@dataclass(frozen=True, slots=True)
class LogTiming:
    """How regularly a log was sampled.

    Attributes
    ----------
    period : float
        Nominal sample period [s]: the mean period, a gap counted as the periods it spans.
    jitter : float
        Largest deviation of a period from the median, excluding gaps, as a fraction of it.
    gaps : int
        Periods longer than 1.5 median periods (dropped samples).
    longest_gap : float
        Longest period [s].
    resampled : bool
        Whether the log was resampled onto a uniform grid.
    """

    period: float
    jitter: float
    gaps: int
    longest_gap: float
    resampled: bool = False

    def describe(self) -> str:
        """One line for the user."""
        text = f"sample period {self.period:.6g} s, jitter {100 * self.jitter:.2g} %"
        if self.gaps:
            text += f", {self.gaps} gap(s) up to {self.longest_gap:.3g} s"
        if self.resampled:
            text += "; resampled onto a uniform grid (linear interpolation)"
        return text


def log_timing(t: Array) -> LogTiming:
    """Median period, jitter and gaps of a strictly increasing time vector [s].

    Examples
    --------
    >>> log_timing(np.array([0.0, 0.01, 0.02, 0.04, 0.05])).gaps
    1
    """
    dt = np.diff(t)
    # the mean period, counting a gap as the whole periods it spans (the median of jittered
    # or float32-rounded periods is off the nominal period by up to the jitter)
    h = float(np.median(dt))
    missing = np.round(dt / h) - 1.0
    h = float(t[-1] - t[0]) / (dt.size + float(np.sum(missing[dt > 1.5 * h])))
    gap = dt > 1.5 * h
    regular = dt[~gap]
    jitter = float(np.max(np.abs(regular - h)) / h) if regular.size else 0.0
    return LogTiming(h, jitter, int(np.count_nonzero(gap)), float(np.max(dt)))


def resample(series: TimeSeries, period: float) -> TimeSeries:
    """Linear interpolation of every column onto t_0 + k ``period``.

    Parameters
    ----------
    series : TimeSeries
        Strictly increasing time.
    period : float
        New sample period [s], > 0.

    Returns
    -------
    TimeSeries
        Uniformly sampled from the first time to the last.
    """
    if not (math.isfinite(period) and period > 0.0):
        raise MotosimError(f"period = {period!r}; expected a finite value > 0 [s]")
    n = math.floor(float(series.t[-1] - series.t[0]) / period * (1.0 + 1e-9)) + 1
    t = series.t[0] + period * np.arange(n)
    data = np.empty((n, len(series.names)))
    for j in range(len(series.names)):
        data[:, j] = np.interp(t, series.t, series.data[:, j])
    return TimeSeries(t, data, series.names)


@dataclass(frozen=True, slots=True)
class RigLog:
    """A log from a rig, checked, in SI, on a uniform grid.

    Attributes
    ----------
    series : TimeSeries
        The signals.
    timing : LogTiming
        The sampling as read, before any resampling.
    """

    series: TimeSeries
    timing: LogTiming


def read_rig_log(
    path: str | Path,
    *,
    required: Sequence[str],
    columns: Mapping[str, ColumnSpec] | None = None,
    min_samples: int = 10,
) -> RigLog:
    """Read a log recorded on the handlebar, check that it is plausible, make it uniform.

    Parameters
    ----------
    path : str or Path
        The CSV file, see :func:`read_log`.
    required : sequence of str
        Signals that must be present besides ``t``.
    columns : mapping of str to ColumnSpec, optional
        Column mapping and units, see :func:`parse_columns`.
    min_samples : int
        Fewest rows accepted.

    Returns
    -------
    RigLog
        The series, resampled when its periods vary by more than 1 % or samples were
        dropped, and its timing as read.

    Raises
    ------
    MotosimError
        Everything :func:`read_log` refuses, and in one line naming the likely cause: a
        sample period of 0.1 s or more (a time in milliseconds or microseconds), an angle
        ``theta_h`` spanning more than pi rad (degrees), a current spanning more than
        200 A (milliamperes), a gap longer than :data:`MAX_GAP_PERIODS` periods.
    """
    series = read_log(path, required=required, min_samples=min_samples, columns=columns)
    timing = log_timing(series.t)
    _check_period(str(path), timing)
    _check_units(str(path), series)
    if timing.longest_gap > MAX_GAP_PERIODS * timing.period:
        k = int(np.argmax(np.diff(series.t)))
        raise MotosimError(
            f"{path}: {timing.longest_gap:.4g} s without samples after t = {series.t[k]:g} s; "
            f"expected gaps of at most {MAX_GAP_PERIODS} sample periods "
            f"({MAX_GAP_PERIODS * timing.period:.3g} s): split the log there"
        )
    if timing.jitter > JITTER_WARNING:
        warn(
            f"{path}: the sample periods deviate by up to {100 * timing.jitter:.0f} % "
            f"({1e3 * timing.jitter * timing.period:.2g} ms) from the "
            f"{1e3 * timing.period:.3g} ms period, timestamps jittered; the log is resampled "
            "onto a uniform grid, which distorts the angle's derivatives: log with the "
            "drive's clock if it can"
        )
    if timing.gaps or timing.jitter > JITTER_TOLERANCE:
        series = resample(series, timing.period)
        timing = dataclasses.replace(timing, resampled=True)
    return RigLog(series, timing)


def _check_period(label: str, timing: LogTiming) -> None:
    """Refuse a sample period a handlebar log cannot have: a time in other units."""
    if timing.period >= 0.1:
        raise MotosimError(
            f"{label}: median sample period {timing.period:g} s ({1 / timing.period:.3g} Hz); "
            "this looks like a time in milliseconds or microseconds: give its unit in the "
            "header (t [ms]) or with --columns t=NAME:ms"
        )
    if timing.period < MIN_PERIOD:
        raise MotosimError(
            f"{label}: median sample period {timing.period:.3g} s ({1 / timing.period:.3g} Hz); "
            f"expected at least {MIN_PERIOD:g} s (a handlebar log is sampled at 1 MHz at most): "
            "check the time column and its unit"
        )


def _check_units(label: str, series: TimeSeries) -> None:
    """Refuse angles that span more than a handlebar turns and currents more than its motor
    draws: degrees and milliamperes read as radians and amperes."""
    for name in ("theta_h", "delta"):
        if name in series.names:
            span = float(np.ptp(series[name]))
            if span > math.pi:
                raise MotosimError(
                    f"{label}: {name} spans {span:.4g} rad ({math.degrees(span):.0f} deg), more "
                    f"than a handlebar turns; this looks like degrees: give {name} [deg] in the "
                    f"header or --columns {name}=NAME:deg"
                )
    for name in ("i_m", "i_cmd"):
        if name in series.names:
            peak = float(np.max(np.abs(series[name])))
            if peak > 200.0:
                raise MotosimError(
                    f"{label}: {name} reaches {peak:.4g} A, more than a handlebar motor draws; "
                    f"this looks like milliamperes: give {name} [mA] in the header or "
                    f"--columns {name}=NAME:mA"
                )


def write_log(path: str | Path, series: TimeSeries) -> Path:
    """Write a series as CSV with ``t`` first, full float precision, whole or not at all.

    A write that fails (a full disk) or is interrupted leaves a previous file as it was
    (:func:`motosim.io.files.write_whole`).

    Raises
    ------
    MotosimError
        If the file cannot be written.
    """
    target = Path(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise MotosimError(f"cannot write {path}: {err.strerror}") from None

    def write(temporary: Path) -> None:
        with temporary.open("w", newline="", encoding="utf-8") as handle:
            writer = csv.writer(handle)
            writer.writerow(("t", *series.names))
            for t, row in zip(series.t, series.data, strict=True):
                writer.writerow([repr(float(t)), *(repr(float(v)) for v in row)])

    return write_whole(target, write)
