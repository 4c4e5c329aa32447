"""Time-series logs as CSV: one header row of signal names, one row per instant.

The time column ``t`` [s] comes first and is strictly increasing, so pandas and PlotJuggler
read the files as they are. Units are those of :mod:`motosim.signals`.
"""

import csv
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from motosim.errors import MotosimError
from motosim.timeseries import TimeSeries

__all__ = ["read_log", "write_log"]


def read_log(path: str | Path, *, required: Sequence[str], min_samples: int = 10) -> TimeSeries:
    """Read and validate a CSV log.

    Parameters
    ----------
    path : str or Path
        The CSV file; its header names the columns, one of which is ``t`` [s].
    required : sequence of str
        Columns that must be present besides ``t``.
    min_samples : int
        Fewest rows accepted.

    Returns
    -------
    TimeSeries
        Every column but ``t``, in file order.

    Raises
    ------
    MotosimError
        One line naming the file and the problem: missing file or column, a value that is not
        a number, NaN, a time that does not strictly increase, too few samples.
    """
    source = Path(path)
    if not source.is_file():
        raise MotosimError(f"{path}: no such log file")
    with source.open(newline="", encoding="utf-8") as handle:
        reader = csv.reader(handle)
        header = [name.strip() for name in next(reader, [])]
        rows = [row for row in reader if row]
    missing = [name for name in ("t", *required) if name not in header]
    if missing:
        raise MotosimError(
            f"{path}: missing column {missing[0]!r}; expected columns "
            f"{', '.join(('t', *required))} (found {', '.join(header) or 'no header'})"
        )
    if len(set(header)) != len(header):
        raise MotosimError(f"{path}: duplicated column names in the header {header}")
    data = np.empty((len(rows), len(header)))
    for i, row in enumerate(rows):
        if len(row) != len(header):
            raise MotosimError(
                f"{path}: line {i + 2} has {len(row)} fields; expected {len(header)}"
            )
        for j, cell in enumerate(row):
            try:
                value = float(cell)
            except ValueError:
                raise MotosimError(
                    f"{path}: line {i + 2}, column {header[j]}: {cell!r} is not a number"
                ) from None
            if not math.isfinite(value):
                raise MotosimError(
                    f"{path}: line {i + 2}, column {header[j]}: {cell.strip()}; "
                    "expected a finite number"
                )
            data[i, j] = value
    if len(rows) < min_samples:
        raise MotosimError(f"{path}: {len(rows)} samples; expected at least {min_samples}")
    t = data[:, header.index("t")]
    steps = np.diff(t)
    if np.any(steps <= 0):
        k = int(np.argmax(steps <= 0))
        kind = "repeats" if steps[k] == 0 else "goes back"
        raise MotosimError(
            f"{path}: time {kind} at line {k + 3} (t = {t[k + 1]:g} s after {t[k]:g} s); "
            "expected strictly increasing t"
        )
    names = tuple(n for n in header if n != "t")
    columns = [header.index(n) for n in names]
    return TimeSeries(t.copy(), data[:, columns].copy(), names)


def write_log(path: str | Path, series: TimeSeries) -> Path:
    """Write a series as CSV with ``t`` first, full float precision.

    Raises
    ------
    MotosimError
        If the file cannot be written.
    """
    target = Path(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        with target.open("w", newline="", encoding="utf-8") as handle:
            writer = csv.writer(handle)
            writer.writerow(("t", *series.names))
            for t, row in zip(series.t, series.data, strict=True):
                writer.writerow([repr(float(t)), *(repr(float(v)) for v in row)])
    except OSError as err:
        raise MotosimError(f"cannot write {path}: {err.strerror}") from None
    return target
