"""A campaign's parts and manifest on a full disk: one line naming the file, nothing cut left."""

from pathlib import Path

import pytest

from motosim.campaign.results import ResultStore, load_results
from motosim.errors import MotosimError

pytest.importorskip("pyarrow")


def _columns(run_id: str) -> dict[str, list[object]]:
    return {
        "run_id": [run_id], "index": [0], "seed": [1], "design": [""], "status": ["ok"],
        "reason": [""], "failed_at": [float("nan")], "elapsed": [0.1], "x": [1.0], "rms": [2.0],
    }  # fmt: skip


def test_a_part_that_does_not_fit_is_one_line_and_leaves_no_cut_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import pyarrow.parquet as pq

    store = ResultStore(tmp_path / "c", fingerprint="f", factors=[("x", float)], metrics=["rms"])
    store.write_manifest({"fingerprint": "f"})
    store.write_part(_columns("a"))
    real = pq.write_table

    def filling(table: object, where: object, **kwargs: object) -> None:
        if table is not None:
            real(table, where, **kwargs)  # type: ignore[arg-type]
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(pq, "write_table", filling)
    # it was "motosim: error: No space left on device": no file named, a hidden .tmp left
    with pytest.raises(MotosimError, match=r"cannot write .*part-.*: No space left on device"):
        store.write_part(_columns("b"))
    monkeypatch.setattr(Path, "write_text", lambda *_, **__: filling(None, None))
    with pytest.raises(MotosimError, match=r"cannot write .*manifest.json: No space left"):
        store.write_manifest({"fingerprint": "f"})
    hidden = [p.name for p in (tmp_path / "c").rglob(".*")]
    assert hidden == [] and list(load_results(tmp_path / "c")["run_id"]) == ["a"]


def test_room_for_the_last_manifest_refused_by_a_full_disk_is_one_line_and_no_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import os

    store = ResultStore(tmp_path / "c", fingerprint="f", factors=[("x", float)], metrics=["rms"])
    store.reserve_space(20_000)
    reserve = tmp_path / "c" / ".motosim.reserve"
    assert reserve.stat().st_size == 20_000  # allocated, freed before the last write
    store.release_space()
    assert not reserve.exists()

    def full(fd: int, offset: int, length: int) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "posix_fallocate", full)
    with pytest.raises(MotosimError, match=r"cannot set aside 20 kB .*No space left on device; no"):
        store.reserve_space(20_000)
    assert not reserve.exists()
