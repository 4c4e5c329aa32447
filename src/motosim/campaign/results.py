"""A campaign's result folder: one Parquet part per task, and a manifest.

``DIR/parts/part-*.parquet`` hold one row per run: ``run_id``, ``index`` (position in the
sample), ``seed``, ``design``, ``status`` (``"ok"`` or ``"failed"``), ``reason`` (why it
failed, else empty), ``failed_at`` [s] (NaN when unknown or ok), ``elapsed`` (computing time
of the run [s]), one column per factor (named by its key) and one per kept metric (NaN for a
failed run). Read them with pandas (``pandas.read_parquet("DIR/parts")``), polars, duckdb or
:func:`load_results`. A part is written to a hidden file and renamed, so an interrupted
campaign leaves only whole parts (a full disk is one line naming the part);
``DIR/manifest.json`` says what the campaign was (its file, base scenario, fingerprint,
package version), how far it got, how long it took and how its last call ended (``status``);
``"running"`` there is true only while a process holds the folder's lock, and
:func:`read_manifest` reads it as ``"stopped"`` when none does.
"""

import hashlib
import json
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motosim import __version__
from motosim.campaign.series import SERIES
from motosim.errors import MotosimError
from motosim.io.files import is_locked, write_whole

__all__ = [
    "FOREIGN",
    "MANIFEST",
    "PARTS",
    "ResultStore",
    "check_store_folder",
    "load_results",
    "read_manifest",
]

MANIFEST = "manifest.json"
"""File name of the manifest in a result folder."""
PARTS = "parts"
"""Folder of the Parquet parts in a result folder."""


def _arrow_type(kind: type) -> Any:
    import pyarrow as pa

    return {float: pa.float64(), int: pa.int64(), bool: pa.bool_(), str: pa.string()}[kind]


def read_manifest(folder: str | Path) -> dict[str, Any]:
    """The manifest of a result folder, its ``status`` as it is now.

    A manifest's ``"running"`` is true only while a process holds the folder's lock (the
    campaign running it: :class:`motosim.io.files.FolderLock`). A campaign stopped without
    its last manifest write (SIGKILL, an OOM kill, a power cut, a full disk) left
    ``"running"`` in the file: when no process holds the lock (this call takes it without
    waiting, and lets it go at once), the status read is ``"stopped"``. Running the campaign
    again resumes it.

    Raises
    ------
    MotosimError
        If the folder holds no campaign results.
    """
    path = Path(folder) / MANIFEST
    if not path.is_file():
        raise MotosimError(
            f"{folder}: no {MANIFEST}; expected a folder written by motosim campaign"
        )
    try:
        manifest: dict[str, Any] = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise MotosimError(f"{path}: not a JSON manifest ({err})") from None
    if manifest.get("status") == "running" and not is_locked(folder):
        manifest["status"] = "stopped"
    return manifest


def load_results(folder: str | Path) -> dict[str, NDArray[Any]]:
    """Every run written so far, as columns (see the module docstring), sorted by ``index``.

    Parameters
    ----------
    folder : str or Path
        A campaign's result folder.

    Returns
    -------
    dict of str to ndarray
        One 1-D array per column; strings as object arrays.
    """
    import pyarrow.parquet as pq

    parts = Path(folder) / PARTS
    files = sorted(parts.glob("part-*.parquet")) if parts.is_dir() else []
    if not files:
        return {}
    table = pq.read_table(files)
    order = np.argsort(table.column("index").to_numpy(), kind="stable")
    out: dict[str, NDArray[Any]] = {}
    for name in table.column_names:
        column = table.column(name)
        values = column.to_numpy(zero_copy_only=False)
        out[name] = np.asarray(values)[order]
    return out


FOREIGN = ("report.html", "result.h5", "result.csv", SERIES)
"""Files a campaign would write over (its report, its series store) or that are another
command's result (``motosim simulate``'s): a folder holding one without a campaign's
manifest or parts is refused."""


def check_store_folder(folder: str | Path) -> None:
    """Refuse a folder that holds another command's result or a file the campaign would write
    over (:data:`FOREIGN`) but no campaign's results.

    Anything else may sit beside the campaign's files: its campaign and scenario files, a
    ``.gitkeep``.

    Parameters
    ----------
    folder : str or Path
        The campaign's ``--out``.

    Raises
    ------
    MotosimError
        One line naming the folder and the files.
    """
    folder = Path(folder)
    if (folder / MANIFEST).is_file() or (folder / PARTS).is_dir():
        return
    clash = [name for name in FOREIGN if os.path.lexists(folder / name)]
    if clash:
        raise MotosimError(
            f"{folder}: holds {', '.join(clash)} but no campaign's results (no {MANIFEST}, no "
            f"{PARTS}); expected a new folder, one without another result, or a campaign's "
            "to resume"
        )


class ResultStore:
    """Writes a campaign's parts and manifest; knows the runs already written.

    Parameters
    ----------
    folder : str or Path
        The result folder (created).
    fingerprint : str
        The campaign's fingerprint; a folder holding another campaign is refused.
    factors : Sequence of (str, type)
        Factor column names and Python types, in order.
    metrics : Sequence of str
        Metric column names.

    Attributes
    ----------
    previous : str or None
        How the campaign's last call ended, from its manifest (None for a new folder). The
        store is opened by the holder of the folder's lock (:func:`run_campaign
        <motosim.campaign.execute.run_campaign>`), so no other process runs the campaign: a
        ``"running"`` left in the manifest is read as ``"stopped"`` (a call stopped without
        its last manifest write), and the campaign resumes.

    Raises
    ------
    MotosimError
        If the folder holds results of a campaign with another fingerprint, or other files
        (a result of motosim simulate, say) and no campaign's.
    """

    def __init__(
        self,
        folder: str | Path,
        *,
        fingerprint: str,
        factors: Sequence[tuple[str, type]],
        metrics: Sequence[str],
    ) -> None:
        self.folder = Path(folder)
        self.parts = self.folder / PARTS
        check_store_folder(self.folder)
        self.previous: str | None = None
        if (self.folder / MANIFEST).is_file():
            found = read_manifest(self.folder)
            status = str(found.get("status"))
            self.previous = "stopped" if status == "running" else status  # see the docstring
            previous = found.get("fingerprint")
            if previous != fingerprint:
                raise MotosimError(
                    f"{self.folder}: holds results of another campaign or version "
                    f"(fingerprint {previous}, this one {fingerprint}); give another --out"
                )
        self.parts.mkdir(parents=True, exist_ok=True)
        self.factors = tuple(factors)
        self.metrics = tuple(metrics)
        self.done: set[str] = set()
        files = sorted(self.parts.glob("part-*.parquet"))
        if files:
            import pyarrow.parquet as pq

            ids = pq.read_table(files, columns=["run_id"]).column("run_id").to_pylist()
            self.done = {str(i) for i in ids}

    def schema(self) -> Any:
        """The parts' Arrow schema."""
        import pyarrow as pa

        fixed = [
            ("run_id", pa.string()),
            ("index", pa.int64()),
            ("seed", pa.int64()),
            ("design", pa.string()),
            ("status", pa.string()),
            ("reason", pa.string()),
            ("failed_at", pa.float64()),
            ("elapsed", pa.float64()),
        ]
        factors = [(name, _arrow_type(kind)) for name, kind in self.factors]
        metrics = [(name, pa.float64()) for name in self.metrics]
        return pa.schema(fixed + factors + metrics)

    def write_part(self, columns: Mapping[str, Sequence[Any]]) -> Path:
        """Write one task's rows as a part (atomically) and remember its run ids."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        ids = [str(i) for i in columns["run_id"]]
        name = hashlib.sha256(" ".join(ids).encode()).hexdigest()[:16]
        path = self.parts / f"part-{name}.parquet"
        table = pa.table({k: list(columns[k]) for k in self.schema().names}, schema=self.schema())
        write_whole(path, lambda hidden: pq.write_table(table, hidden))
        self.done.update(ids)
        return path

    def write_manifest(self, payload: Mapping[str, Any]) -> Path:
        """Write ``manifest.json`` (atomically) with the package version added."""
        text = json.dumps({"version": __version__, **payload}, indent=2, default=str)
        return write_whole(
            self.folder / MANIFEST, lambda hidden: hidden.write_text(text + "\n", encoding="utf-8")
        )
