"""Result files of closed-loop runs: HDF5 for the program, CSV for people and PlotJuggler.

A result is a folder holding:

- ``result.h5``: one resizable, chunked float64 dataset ``signals`` of shape ``(n, k)``,
  time-first, column ``j`` being the signal ``names[j]`` (attribute ``names`` of the dataset;
  ``t`` [s] comes first). Root attributes: ``format`` (``"motosim-result"``),
  ``format_version``, ``metadata`` (JSON: parameters, scenario, seed, version as given by the
  caller), ``complete`` (False until :meth:`ResultWriter.close`) and, once closed, ``summary``
  (JSON metrics).
- ``result.csv``: header ``t,...`` then one row per instant, full float precision, strictly
  increasing ``t``; pandas and PlotJuggler read it as is. While a run goes, and in a run that
  did not complete, this file is called ``result.partial.csv``: its name says it is partial.

How a result is never lost or corrupted (the choices are in ``docs/organisation.md``, files
that survive every stop):

- **Lock.** While a run writes ``NAME`` it holds its :class:`~motosim.io.files.FolderLock`
  (``.NAME.lock`` beside it), its own or the caller's (``lock``, kept by a command that
  writes more there after the result); a second writer of the folder is refused.
- **Staging.** The run writes into ``NAME.partial``; only :meth:`ResultWriter.close` renames
  it to ``NAME``, a previous result replaced (:func:`~motosim.io.files.replace_folder`). A
  run that fails or is interrupted leaves a previous complete result untouched; with none,
  or an earlier stopped run's, its rows move to ``NAME`` marked partial (``complete`` False,
  ``result.partial.csv``), which a rerun replaces without ``overwrite``. A ``NAME`` holding
  files that are not a motosim result is never moved aside: the result stays in
  ``NAME.partial``, and the run says so.
- **Every stop.** Each :meth:`ResultWriter.append` writes its rows to both files (one
  ``write`` a block, so no row is cut short) and flushes them; an exception leaving the
  ``with`` block closes both, readable, marked partial. Without SWMR, after SIGKILL or a
  power cut ``NAME.partial/result.h5`` opens with plain h5py, pandas or HDFView and holds
  every row flushed before the kill.
- **Full disk.** ``expected_rows`` refuses a run the free space cannot hold before it
  starts; a write that fails anyway is one :class:`MotosimError` line saying how many rows
  were kept, and where.

Units are those of :mod:`motosim.signals`: SI, angles in radians.
"""

import json
import logging
import math
import os
import shutil
from collections.abc import Mapping
from dataclasses import dataclass, fields, is_dataclass
from pathlib import Path
from typing import Any, NoReturn, Self

import h5py
import numpy as np
from numpy.typing import ArrayLike

from motosim import __version__
from motosim.errors import MotosimError, RunFailedError, StopFlag
from motosim.io.files import FolderLock, reason, replace_folder
from motosim.timeseries import TimeSeries

__all__ = [
    "RESERVE_BYTES",
    "ResultWriter",
    "SimResult",
    "is_complete_result",
    "load_result",
    "partial_folder",
]

_log = logging.getLogger(__name__)

_H5_NAME = "result.h5"
_CSV_NAME = "result.csv"
_CSV_PARTIAL = "result.partial.csv"
_PARTIAL = ".partial"

RESERVE_BYTES = 16_000_000
"""Free disk space a run leaves untouched [bytes], so that its files can always be closed."""
_FORMAT = "motosim-result"
_FORMAT_VERSION = 1
_CHUNK_BYTES = 64 * 1024


def _jsonable(value: Any, where: str) -> Any:
    """Convert ``value`` to plain JSON types (dataclasses, numpy values, paths included)."""
    if value is None or isinstance(value, bool | int | float | str):
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


def partial_folder(folder: str | Path) -> Path:
    """Where a run of ``folder`` writes, and where a stopped run leaves its rows: NAME.partial."""
    target = Path(folder)
    return target.with_name(target.name + _PARTIAL)


def is_complete_result(folder: str | Path) -> bool:
    """Whether ``folder`` holds a completed result (its ``result.csv`` is renamed at the end).

    A ``result.h5`` marked complete counts too, its CSV (the larger file) deleted or not.
    """
    folder = Path(folder)
    if (folder / _CSV_NAME).is_file():
        return True
    h5_path = folder / _H5_NAME
    if not h5_path.is_file():
        return False
    try:
        with h5py.File(h5_path, "r") as h5:
            return bool(h5.attrs.get("complete", False))
    except (OSError, ValueError):  # not HDF5, truncated: no result to keep
        return False


class ResultWriter:
    """Record a run as it goes, then publish it as ``folder/result.h5`` and ``result.csv``.

    Parameters
    ----------
    folder : str or Path
        The result folder. Its parent is created if needed; the folder itself must be new,
        empty, hold an earlier partial result, or (with ``overwrite``) a complete one.
    names : tuple of str
        Column names, ``"t"`` [s] first, then signal names of :mod:`motosim.signals`.
    metadata : Mapping of str to Any
        What produced the run (parameters, scenario, seed, version...), stored as JSON.
        Values may be numbers, strings, booleans, None, numpy arrays, sequences, mappings and
        dataclasses of those.
    overwrite : bool
        Replace a complete result already in ``folder``; by default that is an error.
    expected_rows : int, optional
        Rows the run will write; when given, a run the free disk space cannot hold is refused
        before it starts.
    lock : FolderLock, optional
        The caller's lock of ``folder``, held (the caller keeps it after :meth:`close`, for
        what it writes beside the result); by default the writer takes the lock itself and
        releases it once the files are closed.
    stop : StopFlag, optional
        The stop the command's signal handlers request: held while a block goes to both
        files, raised at the next block.

    Raises
    ------
    MotosimError
        One line naming the path or value: bad names, metadata that cannot be stored, a
        result already there, another run writing the folder, not enough disk space, a file
        that cannot be created.

    Notes
    -----
    Use it in a ``with`` block: leaving the block on an exception (Ctrl-C, a stop from
    ``stop``) closes the files without marking them complete (see the module notes for where
    the rows go). After an interruption :attr:`location` says where the rows are. Leaving the
    block normally completes the result (without summary if :meth:`close` was not called).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     with ResultWriter(Path(tmp) / "run", ("t", "theta_h"), {"seed": 1}) as writer:
    ...         writer.append(np.array([[0.0, 0.1], [0.001, 0.2]]))
    ...         writer.close({"rms": 0.5})
    ...     result = load_result(Path(tmp) / "run")
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
        expected_rows: int | None = None,
        lock: FolderLock | None = None,
        stop: StopFlag | None = None,
    ) -> None:
        self._names = _check_names(names)
        metadata_json = _to_json(metadata, "metadata")
        self._folder = _check_folder(folder, overwrite=overwrite)
        self._staging = partial_folder(self._folder)
        self._location = self._staging
        self._rows = 0
        self._last_t = -math.inf
        self._closed = False
        self._stop = stop if stop is not None else StopFlag()
        if lock is not None and (not lock.held or lock.folder != self._folder):
            raise MotosimError(
                f"{folder}: the lock given is not the held lock of this folder ({lock.folder}); "
                "expected the lock of the result folder, entered"
            )
        self._own_lock = FolderLock(self._folder) if lock is None else None
        if self._own_lock is not None:
            self._own_lock.__enter__()
        try:
            # checked again under the lock: another run may have completed meanwhile
            _check_folder(self._folder, overwrite=overwrite)
            _check_space(self._folder.parent, expected_rows or 0, len(self._names))
            if self._staging.exists():
                _log.warning("replacing the partial result left in %s", self._staging)
                shutil.rmtree(self._staging)
            self._staging.mkdir()
            self._h5_path = self._staging / _H5_NAME
            self._csv_path = self._staging / _CSV_PARTIAL
            self._open(metadata_json)
        except OSError as err:
            self._release()
            raise MotosimError(f"cannot create a result in {folder}: {reason(err)}") from None
        except BaseException:
            self._release()
            raise

    def _release(self) -> None:
        """Release the lock if the writer took it itself."""
        if self._own_lock is not None:
            self._own_lock.__exit__(None, None, None)

    def _open(self, metadata_json: str) -> None:
        k = len(self._names)
        self._h5 = h5py.File(self._h5_path, "w")
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
            self._h5.flush()
            self._dataset = dataset
            self._csv = os.open(self._csv_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
            _write_all(self._csv, (",".join(self._names) + "\n").encode())
        except BaseException:
            self._h5.close()
            raise

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
            a write that fails (naming the file and what was kept; the writer is then
            closed, the result partial).
        """
        if self._closed:
            raise MotosimError(f"{self._folder}: the result is closed; cannot add rows")
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
        text = "".join(",".join(map(repr, row)) + "\n" for row in rows.tolist()).encode()
        self._check_reserve(len(text) + rows.nbytes)
        with self._stop.held():  # a stop signal now would leave the files with other rows
            try:
                self._dataset.resize(self._rows + m, axis=0)
                self._dataset[self._rows :] = rows
                self._h5.flush()
            except (OSError, RuntimeError) as err:  # HDF5 reports a failed write as either
                self._fail(self._h5_path, err)
            try:
                _write_all(self._csv, text)
            except OSError as err:
                self._fail(self._csv_path, err)
            self._rows += m
            self._last_t = float(t[-1])
        self._stop.check()  # a stop signal held, or whose raise was swallowed, stops here

    def _check_reserve(self, block_bytes: int) -> None:
        """Stop while the files can still be closed cleanly, before the disk is full.

        HDF5 does not recover from a write refused by a full disk (its file can no longer be
        closed, and the process may crash on exit), so the writer stops first, keeping
        :data:`RESERVE_BYTES` free.
        """
        try:
            free = shutil.disk_usage(self._staging).free
        except OSError:
            return
        if free < RESERVE_BYTES + 2 * block_bytes:
            raise MotosimError(
                f"{self._staging}: the disk is full ({free / 1e6:.1f} MB free, "
                f"{RESERVE_BYTES / 1e6:.0f} MB kept in reserve); {self._kept()}"
            )

    def _fail(self, path: Path, err: OSError | RuntimeError) -> NoReturn:
        """A write failed (full disk...): close what can be closed, say what was kept."""
        why = reason(err)
        raise MotosimError(f"cannot write {path.name}: {why}; {self._kept()}") from None

    def _kept(self) -> str:
        """Close the files as a partial result (:meth:`_abort`); what was kept, and where."""
        self._abort()
        upto = f" (t <= {self._last_t:g} s)" if self._rows else ""
        return f"the result is partial, {self._rows} rows{upto} kept in {self._location}"

    def close(self, summary: Mapping[str, Any] | None = None) -> None:
        """Store the summary, mark the result complete and publish it in the result folder.

        Parameters
        ----------
        summary : Mapping of str to Any, optional
            Metrics of the run (for example from :func:`motosim.report.metrics`), stored as
            JSON in the attribute ``summary``.

        Raises
        ------
        MotosimError
            A summary that cannot be stored or a write that fails (naming the file); the
            result is then left partial and a previous result untouched.

        Notes
        -----
        Closing a closed writer does nothing.
        """
        if self._closed:
            return
        summary_json = _to_json(summary or {}, "summary")
        try:
            self._h5.attrs["summary"] = summary_json
            self._h5.attrs["complete"] = True
            self._h5.close()
            os.fsync(self._csv)
            os.close(self._csv)
            os.replace(self._csv_path, self._staging / _CSV_NAME)
            self._publish()
        except _OccupiedError:
            self._closed = True
            self._release()
            raise MotosimError(
                f"{self._folder}: holds files that are not a motosim result, written there while "
                f"the run went; they are left as they are, and the complete result is in "
                f"{self._staging}"
            ) from None
        except OSError as err:
            self._fail(self._h5_path, err)
        self._closed = True
        self._location = self._folder
        self._release()

    def _publish(self) -> None:
        """Move the staging folder to the result folder (:func:`replace_folder`); raise
        :class:`_OccupiedError`, moving nothing, if the result folder now holds other files
        (written there while the run went, by a program that does not take the lock)."""
        if not _replaceable(self._folder):
            raise _OccupiedError(self._folder)
        replace_folder(self._staging, self._folder)

    def _abort(self) -> None:
        """Close both files without marking the result complete; keep the rows where they help."""
        if self._closed:
            return
        self._closed = True
        try:
            os.close(self._csv)
        except OSError as err:
            _log.warning("closing %s: %s", self._csv_path, err)
        del self._dataset  # no HDF5 object may outlive its file (a crash at exit otherwise)
        try:
            self._h5.close()
        except (OSError, RuntimeError) as err:
            _log.warning("closing %s: %s", self._h5_path, reason(err))
        try:
            if not is_complete_result(self._folder):
                # no previous result, or an earlier stopped run's: the partial one goes where
                # one looks (never over a folder of other files: _publish refuses it)
                self._publish()
                self._location = self._folder
        except _OccupiedError:
            _log.warning(
                "%s holds files that are not a motosim result: left as it is, the rows kept in %s",
                self._folder,
                self._staging,
            )
        except OSError as err:
            _log.warning("keeping %s: %s", self._staging, err)
        self._release()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: object
    ) -> None:
        if exc_type is None and self._stop.name is not None and not self._closed:
            exc_type = KeyboardInterrupt  # a stop signal whose raise was swallowed
        if exc_type is None:
            self.close()
        elif not self._closed:
            # a run that failed or was interrupted says where its rows are itself
            expected = issubclass(exc_type, RunFailedError | KeyboardInterrupt)
            self._abort()
            _log.log(
                logging.INFO if expected else logging.WARNING,
                "run interrupted by %s: %d rows kept in %s, marked partial",
                exc_type.__name__,
                self._rows,
                self._location,
            )
        if exc is None:
            self._stop.check()

    @property
    def location(self) -> Path:
        """Where the rows are now: the staging folder while running, then where they were kept."""
        return self._location

    @property
    def rows(self) -> int:
        """Rows written so far."""
        return self._rows


class _OccupiedError(OSError):
    """The result folder holds files that are not a motosim result: it is not replaced."""


def _replaceable(folder: Path) -> bool:
    """Whether publishing may move ``folder`` aside: it is missing, empty, or a motosim
    result, complete or stopped (its ``result.h5`` there, as :func:`_check_folder` sees it)."""
    try:
        return not folder.exists() or (folder / _H5_NAME).is_file() or not any(folder.iterdir())
    except NotADirectoryError:
        return False


def _write_all(fd: int, data: bytes) -> None:
    """Write ``data`` whole (one call unless the system splits it)."""
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view) :]


def _check_folder(folder: str | Path, *, overwrite: bool) -> Path:
    """The result folder if a run may write it (see :class:`ResultWriter`), else refuse."""
    target = Path(folder).absolute()
    if not target.name or target == Path.cwd() or target in Path.cwd().parents:
        raise MotosimError(
            f"{folder}: is the current folder or one of its parents; expected a result folder"
        )
    if target.exists() and not target.is_dir():
        raise MotosimError(f"{folder}: is a file; expected a result folder")
    if is_complete_result(target):
        if not overwrite:
            raise MotosimError(
                f"{folder}: a result is already there; choose another folder or overwrite"
            )
    elif target.is_dir() and any(target.iterdir()) and not (target / _H5_NAME).exists():
        raise MotosimError(
            f"{folder}: holds files that are not a motosim result; expected a new or empty folder"
        )
    return target


def _check_space(parent: Path, rows: int, columns: int) -> None:
    """Refuse a run whose files would not fit in the free space of ``parent``."""
    # HDF5 8 bytes a value; CSV about 24 characters a value (repr of a float64 and a comma)
    need = int(rows * columns * (8 + 24) * 1.05) + RESERVE_BYTES
    free = shutil.disk_usage(parent).free
    if need > free:
        raise MotosimError(
            f"{parent}: a run of {rows} rows of {columns} signals needs about "
            f"{need / 1e6:.0f} MB with the {RESERVE_BYTES / 1e6:.0f} MB reserve; only "
            f"{free / 1e6:.0f} MB are free"
        )


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
        Every row written; for an interrupted or killed run, those flushed before the stop
        (read ``NAME.partial`` for a run killed before it completed).

    Raises
    ------
    MotosimError
        One line naming the path: missing folder or file, a file that is not HDF5 or not a
        motosim result, unreadable metadata.
    """
    file = _result_file(Path(folder))
    with _open_h5(file) as h5:
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
        table[:, 0].copy(), table[:, 1:].copy(), names[1:], metadata, summary, complete
    )


def _result_file(path: Path) -> Path:
    """The ``result.h5`` of the result folder ``path`` (or ``path``, a file), which exists."""
    if not path.exists():
        stopped = partial_folder(path)
        hint = (
            f"; a run writing it, or one that was stopped, has its rows in {stopped}"
            if stopped.is_dir()
            else ""
        )
        raise MotosimError(f"{path}: no such result folder{hint}")
    file = path / _H5_NAME if path.is_dir() else path
    if not file.is_file():
        raise MotosimError(f"{path}: no {_H5_NAME}; expected a folder written by motosim")
    return file


def _open_h5(file: Path) -> h5py.File:
    """``file`` opened for reading: plainly; else without HDF5's file lock (a run in progress
    in another process); else as SWMR, in which motosim <= 0.1 wrote its results."""
    failure: OSError | None = None
    for options in ({}, {"locking": False}, {"swmr": True, "locking": False}):
        try:
            return h5py.File(file, "r", **options)
        except OSError as err:
            failure = err
    why = reason(failure) if failure else "unknown"
    raise MotosimError(f"{file}: not a readable HDF5 file ({why})")


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
