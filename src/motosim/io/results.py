"""Result files of closed-loop runs: HDF5 for the program, CSV for people and PlotJuggler.

A run is recorded in one folder while it goes, so that an interrupted run (Ctrl-C, crash)
leaves a readable file with every row computed so far:

- ``result.h5``: one resizable, chunked float64 dataset ``signals`` of shape ``(n, k)``,
  time-first, column ``j`` being the signal ``names[j]`` (attribute ``names`` of the dataset;
  ``t`` [s] comes first). Root attributes: ``format`` (``"motosim-result"``),
  ``format_version``, ``metadata`` (JSON: parameters, scenario, seed, version as given by the
  caller), ``complete`` (False until :meth:`ResultWriter.close`) and, once closed, ``summary``
  (JSON metrics).
- ``result.csv``: header ``t,...`` then one row per instant, full float precision, strictly
  increasing ``t``; pandas and PlotJuggler read it as is.

The HDF5 file is written in single-writer/multiple-reader (SWMR) mode and flushed after each
block: a reader (a live plot, :func:`load_result`) can open it while the run goes, and a file
left by a killed process stays consistent. Such a file keeps HDF5's "open for writing" flag;
:func:`load_result` reads it regardless, other tools may need ``h5clear -s result.h5`` first.

Units are those of :mod:`motosim.signals`: SI, angles in radians.
"""

import json
import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass, fields, is_dataclass
from pathlib import Path
from types import TracebackType
from typing import Any, Self

import h5py
import numpy as np
from numpy.typing import ArrayLike

from motosim import __version__
from motosim.errors import MotosimError
from motosim.timeseries import TimeSeries

__all__ = ["ResultWriter", "SimResult", "load_result"]

_log = logging.getLogger(__name__)

_H5_NAME = "result.h5"
_CSV_NAME = "result.csv"
_FORMAT = "motosim-result"
_FORMAT_VERSION = 1
_CHUNK_BYTES = 64 * 1024


def _jsonable(value: Any, where: str) -> Any:
    """Convert ``value`` to plain JSON types (dataclasses, numpy values, paths included)."""
    if value is None or isinstance(value, bool | int | str):
        return value
    if isinstance(value, float):
        return value
    if isinstance(value, np.generic):
        return _jsonable(value.item(), where)
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist(), where)
    if isinstance(value, Path):
        return str(value)
    if is_dataclass(value) and not isinstance(value, type):
        return {
            f.name: _jsonable(getattr(value, f.name), f"{where}.{f.name}") for f in fields(value)
        }
    if isinstance(value, Mapping):
        out = {}
        for key, item in value.items():
            if not isinstance(key, str):
                raise MotosimError(f"{where}: key {key!r} is not a string; expected str keys")
            out[key] = _jsonable(item, f"{where}.{key}")
        return out
    if isinstance(value, list | tuple):
        return [_jsonable(item, f"{where}[{i}]") for i, item in enumerate(value)]
    raise MotosimError(
        f"{where}: value of type {type(value).__name__} cannot be stored; expected numbers, "
        "strings, booleans, None, arrays, sequences, mappings or dataclasses of those"
    )


def _to_json(value: Mapping[str, Any], where: str) -> str:
    return json.dumps(_jsonable(value, where), sort_keys=False)


def _check_names(names: tuple[str, ...]) -> tuple[str, ...]:
    names = tuple(names)
    if not names or names[0] != "t":
        raise MotosimError(
            f"result names {names[:3]}...; expected 't' first, then the signal names"
        )
    for name in names:
        if not isinstance(name, str) or not name or any(c in name for c in ',"\n\r '):
            raise MotosimError(
                f"result signal name {name!r}; expected a non-empty string without commas, "
                "quotes, spaces or line breaks"
            )
    if len(set(names)) != len(names):
        seen = [n for i, n in enumerate(names) if n in names[:i]]
        raise MotosimError(f"result signal name {seen[0]!r} appears twice; expected unique names")
    return names


class ResultWriter:
    """Record a run as it goes into ``folder/result.h5`` and ``folder/result.csv``.

    Parameters
    ----------
    folder : str or Path
        Created if needed (with its parents).
    names : tuple of str
        Column names, ``"t"`` [s] first, then signal names of :mod:`motosim.signals`.
    metadata : Mapping of str to Any
        What produced the run (parameters, scenario, seed, version...), stored as JSON.
        Values may be numbers, strings, booleans, None, numpy arrays, sequences, mappings and
        dataclasses of those.
    overwrite : bool
        Replace a result already in ``folder``; by default that is an error.

    Raises
    ------
    MotosimError
        One line naming the path or value: bad names, metadata that cannot be stored, a
        result already there, a file that cannot be created.

    Notes
    -----
    Each :meth:`append` writes its rows to both files and flushes them, so an interrupted run
    leaves both readable with every appended row. :meth:`close` stores the summary and marks
    the result complete; leaving the ``with`` block on an exception closes the files without
    marking them complete.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     with ResultWriter(tmp, ("t", "theta_h"), {"seed": 1}) as writer:
    ...         writer.append(np.array([[0.0, 0.1], [0.001, 0.2]]))
    ...         writer.close({"rms": 0.5})
    ...     result = load_result(tmp)
    >>> result["theta_h"], result.complete, result.summary
    (array([0.1, 0.2]), True, {'rms': 0.5})
    """

    def __init__(
        self,
        folder: str | Path,
        names: tuple[str, ...],
        metadata: Mapping[str, Any],
        *,
        overwrite: bool = False,
    ) -> None:
        self._names = _check_names(names)
        metadata_json = _to_json(metadata, "metadata")
        self._folder = Path(folder)
        self._h5_path = self._folder / _H5_NAME
        self._csv_path = self._folder / _CSV_NAME
        self._rows = 0
        self._last_t = -math.inf
        self._closed = False
        k = len(self._names)
        try:
            self._folder.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise MotosimError(f"cannot create result folder {folder}: {err.strerror}") from None
        if not overwrite:
            for path in (self._h5_path, self._csv_path):
                if path.exists():
                    raise MotosimError(
                        f"{path}: a result is already there; choose another folder or overwrite"
                    )
        try:
            self._h5 = h5py.File(self._h5_path, "w", libver="latest")
        except OSError as err:
            raise MotosimError(f"cannot create {self._h5_path}: {_first_line(err)}") from None
        try:
            dataset = self._h5.create_dataset(
                "signals",
                shape=(0, k),
                maxshape=(None, k),
                chunks=(max(1, _CHUNK_BYTES // (8 * k)), k),
                dtype="f8",
                fillvalue=np.nan,
            )
            dataset.attrs["names"] = list(self._names)
            self._h5.attrs["format"] = _FORMAT
            self._h5.attrs["format_version"] = _FORMAT_VERSION
            self._h5.attrs["motosim_version"] = __version__
            self._h5.attrs["metadata"] = metadata_json
            self._h5.attrs["complete"] = False
            self._h5.swmr_mode = True
            self._h5.flush()
            self._dataset = dataset
            self._csv = self._csv_path.open("w", newline="", encoding="utf-8")
        except OSError as err:
            self._h5.close()
            raise MotosimError(f"cannot create a result in {folder}: {_first_line(err)}") from None
        try:
            self._csv.write(",".join(self._names) + "\n")
            self._csv.flush()
        except OSError as err:
            self._abort()
            raise MotosimError(f"cannot write {self._csv_path}: {err.strerror}") from None

    @property
    def folder(self) -> Path:
        """The result folder."""
        return self._folder

    @property
    def names(self) -> tuple[str, ...]:
        """Column names, ``"t"`` first."""
        return self._names

    @property
    def rows(self) -> int:
        """Rows written so far."""
        return self._rows

    def append(self, block: ArrayLike) -> None:
        """Write rows to both files and flush them.

        Parameters
        ----------
        block : array_like, shape (m, k)
            ``m`` instants, columns in the order of ``names`` (``t`` [s] first). Times are
            finite, strictly increasing and later than every row already written.

        Raises
        ------
        MotosimError
            A block of the wrong shape, times that do not strictly increase, a closed writer,
            a write that fails (naming the file).
        """
        if self._closed:
            raise MotosimError(f"{self._folder}: result writer is closed; cannot append")
        rows = np.asarray(block, dtype=np.float64)
        k = len(self._names)
        if rows.ndim != 2 or rows.shape[1] != k:
            raise MotosimError(f"result block of shape {rows.shape}; expected (m, {k})")
        if rows.shape[0] == 0:
            return
        t = rows[:, 0]
        if not np.all(np.isfinite(t)):
            bad = int(np.argmin(np.isfinite(t)))
            raise MotosimError(
                f"result row {self._rows + bad}: t = {float(t[bad])}; expected finite"
            )
        steps = np.diff(np.concatenate(([self._last_t], t)))
        if np.any(steps <= 0):
            bad = int(np.argmax(steps <= 0))
            before = self._last_t if bad == 0 else float(t[bad - 1])
            raise MotosimError(
                f"result row {self._rows + bad}: t = {float(t[bad])!r} s after {before!r} s; "
                "expected strictly increasing t"
            )
        m = rows.shape[0]
        try:
            self._dataset.resize(self._rows + m, axis=0)
            self._dataset[self._rows :] = rows
            self._h5.flush()
        except OSError as err:
            raise MotosimError(f"cannot write {self._h5_path}: {_first_line(err)}") from None
        text = "".join(",".join(map(repr, row)) + "\n" for row in rows.tolist())
        try:
            self._csv.write(text)
            self._csv.flush()
        except OSError as err:
            raise MotosimError(f"cannot write {self._csv_path}: {err.strerror}") from None
        self._rows += m
        self._last_t = float(t[-1])

    def close(self, summary: Mapping[str, Any] | None = None) -> None:
        """Store the summary, mark the result complete and close both files.

        Parameters
        ----------
        summary : Mapping of str to Any, optional
            Metrics of the run (for example from :func:`motosim.report.metrics`), stored as
            JSON in the attribute ``summary``.

        Raises
        ------
        MotosimError
            A summary that cannot be stored or a write that fails (naming the file).

        Notes
        -----
        Closing a closed writer does nothing.
        """
        if self._closed:
            return
        summary_json = _to_json(summary or {}, "summary")
        self._abort()
        try:
            with h5py.File(self._h5_path, "r+") as h5:
                h5.attrs["summary"] = summary_json
                h5.attrs["complete"] = True
        except OSError as err:
            raise MotosimError(f"cannot complete {self._h5_path}: {_first_line(err)}") from None

    def _abort(self) -> None:
        """Close both files without marking the result complete."""
        self._closed = True
        try:
            self._csv.close()
        except (OSError, AttributeError) as err:
            _log.warning("closing %s: %s", self._csv_path, err)
        try:
            self._h5.close()
        except OSError as err:
            _log.warning("closing %s: %s", self._h5_path, _first_line(err))

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if exc_type is None:
            self.close()
        elif not self._closed:
            _log.warning(
                "run interrupted by %s: %s keeps %d rows, marked incomplete",
                exc_type.__name__,
                self._folder,
                self._rows,
            )
            self._abort()


def _first_line(err: BaseException) -> str:
    lines = str(err).strip().splitlines()
    return lines[0] if lines else type(err).__name__


@dataclass(frozen=True, slots=True)
class SimResult(TimeSeries):
    """A recorded run, as read back by :func:`load_result`: a time series and its provenance.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Strictly increasing time [s].
    data : ndarray, shape (n, k)
        Every signal but ``t``: column ``j`` is ``names[j]``, in the unit of
        :mod:`motosim.signals` (SI, radians).
    names : tuple of str
        Signal names, without ``t``.
    metadata : dict
        What produced the run, as given to :class:`ResultWriter`.
    summary : dict
        Metrics stored at :meth:`ResultWriter.close`; empty when there are none.
    complete : bool
        False for an interrupted run.

    Examples
    --------
    >>> r = SimResult(np.array([0.0, 0.5]), np.array([[1.0], [2.0]]), ("phi",), {}, {}, True)
    >>> r["phi"], r["t"]
    (array([1., 2.]), array([0. , 0.5]))
    """

    metadata: dict[str, Any]
    summary: dict[str, Any]
    complete: bool

    def __post_init__(self) -> None:
        TimeSeries.__post_init__(self)
        if "t" in self.names:
            raise MotosimError("SimResult: 't' among the signal names; expected it apart")


def load_result(folder: str | Path) -> SimResult:
    """Read a result written by :class:`ResultWriter`, complete or interrupted.

    Parameters
    ----------
    folder : str or Path
        The result folder (or its ``result.h5`` file).

    Returns
    -------
    SimResult
        Every row written; for an interrupted run, those flushed before the interruption.

    Raises
    ------
    MotosimError
        One line naming the path: missing folder or file, a file that is not HDF5 or not a
        motosim result, unreadable metadata.
    """
    path = Path(folder)
    if not path.exists():
        raise MotosimError(f"{folder}: no such result folder")
    file = path / _H5_NAME if path.is_dir() else path
    if not file.is_file():
        raise MotosimError(f"{folder}: no {_H5_NAME}; expected a folder written by ResultWriter")
    try:
        h5 = h5py.File(file, "r", swmr=True)
    except OSError as err:
        raise MotosimError(f"{file}: not a readable HDF5 file ({_first_line(err)})") from None
    with h5:
        if h5.attrs.get("format") != _FORMAT or not isinstance(h5.get("signals"), h5py.Dataset):
            raise MotosimError(f"{file}: not a motosim result (no {_FORMAT!r} format marker)")
        dataset = h5["signals"]
        names = tuple(str(n) for n in dataset.attrs.get("names", ()))
        if dataset.ndim != 2 or dataset.shape[1] != len(names) or names[:1] != ("t",):
            raise MotosimError(
                f"{file}: signals {dataset.shape} with names {names[:3]}...; expected (n, "
                f"{len(names)}) with 't' first"
            )
        table = np.asarray(dataset[()], dtype=np.float64)
        metadata = _read_json(h5, "metadata", file)
        summary = _read_json(h5, "summary", file)
        complete = bool(h5.attrs.get("complete", False))
    # Rows whose time is still the NaN fill value were reserved but never written.
    written = np.flatnonzero(np.isfinite(table[:, 0]))
    table = table[: written[-1] + 1] if written.size else table[:0]
    return SimResult(
        table[:, 0].copy(),
        table[:, 1:].copy(),
        names[1:],
        metadata,
        summary,
        complete,
    )


def _read_json(h5: h5py.File, key: str, file: Path) -> dict[str, Any]:
    text = h5.attrs.get(key)
    if text is None:
        return {}
    if isinstance(text, bytes):
        text = text.decode("utf-8")
    try:
        value = json.loads(str(text))
    except json.JSONDecodeError as err:
        raise MotosimError(f"{file}: attribute {key!r} is not JSON ({err.msg})") from None
    if not isinstance(value, dict):
        raise MotosimError(f"{file}: attribute {key!r} is {type(value).__name__}; expected a map")
    return value
