"""A campaign's time series: one Zarr group per run in ``DIR/series.zarr``.

When a campaign names ``series``, the worker that ran a run writes the run's time ``t`` and
those signals, decimated to every ``every``-th recorded instant, as 1-D float64 arrays of one
chunk each in the group ``DIR/series.zarr/RUN_ID`` (Zarr format 3; each array's attribute
``unit`` is its SI unit, the group's attributes name the run, its seed and ``every``). Each
run has its own group and chunks, so workers never write the same file. A group is written
in ``DIR/series.tmp`` and moved into place in one rename: a group in the store is whole. Read
them with zarr itself (``zarr.open_group("DIR/series.zarr", mode="r")[RUN_ID]["theta_h"][:]``)
or :func:`load_series`. A failed run that diverged or had invalid values has no series.
"""

import os
import shutil
import uuid
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.signals import unit_of
from motosim.timeseries import TimeSeries

__all__ = ["SERIES", "SeriesSpec", "load_series", "open_series_store", "runs_with_series"]

SERIES = "series.zarr"
"""Folder of the Zarr store in a result folder."""
_SCRATCH = "series.tmp"


def _zarr() -> Any:
    try:
        import zarr
    except ImportError:
        raise MotosimError(
            "series = [...] needs zarr (>= 3): pip install 'motosim[campaign]'"
        ) from None
    return zarr


@dataclass(frozen=True, slots=True)
class SeriesSpec:
    """Where and what a worker writes after each run.

    Attributes
    ----------
    folder : str
        The result folder (on a cluster, a path every worker can write).
    names : tuple of str
        Recorded signals to keep.
    every : int
        Keep every ``every``-th recorded instant.
    """

    folder: str
    names: tuple[str, ...]
    every: int = 1

    def __post_init__(self) -> None:
        if not self.names:
            raise MotosimError("series: expected at least one signal")
        if self.every < 1:
            raise MotosimError(f"every = {self.every}; expected an integer >= 1")

    def write(self, run_id: str, seed: int, ts: TimeSeries) -> Path:
        """Write one run's series as the group ``series.zarr/RUN_ID`` (replacing it)."""
        zarr = _zarr()
        root = Path(self.folder)
        scratch = root / _SCRATCH / f"{run_id}-{os.getpid()}-{uuid.uuid4().hex[:8]}"
        scratch.parent.mkdir(parents=True, exist_ok=True)
        attrs = {"run_id": run_id, "seed": seed, "every": self.every, "signals": list(self.names)}
        group = zarr.open_group(str(scratch), mode="w", zarr_format=3, attributes=attrs)
        step = slice(None, None, self.every)
        for name in ("t", *self.names):
            values = np.ascontiguousarray((ts.t if name == "t" else ts[name])[step])
            group.create_array(
                name, data=values, chunks=(max(1, values.size),), attributes={"unit": unit_of(name)}
            )
        target = root / SERIES / run_id
        if target.exists():  # a run computed again after an interruption: the same values
            shutil.rmtree(target)
        os.replace(scratch, target)
        return target


def open_series_store(folder: str | Path, names: Sequence[str], every: int) -> Path:
    """Create ``DIR/series.zarr`` (the root group) if missing; return its path.

    Raises
    ------
    MotosimError
        If zarr is not installed.
    """
    zarr = _zarr()
    path = Path(folder) / SERIES
    if not (path / "zarr.json").is_file():
        zarr.open_group(
            str(path),
            mode="a",
            zarr_format=3,
            attributes={"signals": list(names), "every": every, "layout": "one group per run"},
        )
    shutil.rmtree(Path(folder) / _SCRATCH, ignore_errors=True)  # groups left by an interruption
    return path


def runs_with_series(folder: str | Path) -> set[str]:
    """The run ids that have a series group in ``DIR/series.zarr``."""
    path = Path(folder) / SERIES
    if not path.is_dir():
        return set()
    return {p.name for p in path.iterdir() if (p / "zarr.json").is_file()}


def load_series(folder: str | Path, run_id: str) -> dict[str, NDArray[np.float64]]:
    """One run's series: ``t`` and the kept signals, as arrays.

    Parameters
    ----------
    folder : str or Path
        A campaign's result folder.
    run_id : str
        The run.

    Returns
    -------
    dict of str to ndarray

    Raises
    ------
    MotosimError
        If the folder holds no series of that run.
    """
    zarr = _zarr()
    path = Path(folder) / SERIES / run_id
    if not (path / "zarr.json").is_file():
        raise MotosimError(
            f"{folder}: no series of run {run_id!r}; expected a run of a campaign "
            "with series = [...] that did not fail"
        )
    group = zarr.open_group(str(path), mode="r")
    names = ["t", *group.attrs["signals"]]
    return {n: np.asarray(group[n][:], dtype=np.float64) for n in names}
