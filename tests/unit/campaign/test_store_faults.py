"""A campaign's parts and manifest on a full disk: one line naming the file, nothing cut left."""

from pathlib import Path

import pytest

from motosim.campaign.results import ResultStore, load_results
from motosim.errors import MotosimError

pytest.importorskip("pyarrow")


def _columns(run_id: str) -> dict[str, list[object]]:
    return {
        "run_id": [run_id],
        "index": [0],
        "seed": [1],
        "design": [""],
        "status": ["ok"],
        "reason": [""],
        "failed_at": [float("nan")],
        "elapsed": [0.1],
        "x": [1.0],
        "rms": [2.0],
    }


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


def test_running_is_read_as_stopped_once_no_process_holds_the_lock(tmp_path: Path) -> None:
    # a campaign killed (SIGKILL, an OOM kill, a power cut) or stopped by a full disk before
    # its last manifest write left "running" in the file for good
    import subprocess
    import sys

    from motosim.campaign.results import read_manifest

    folder = tmp_path / "c"
    store = ResultStore(folder, fingerprint="f", factors=[("x", float)], metrics=["rms"])
    store.write_manifest({"fingerprint": "f", "status": "running"})
    with subprocess.Popen(  # the campaign's process, holding the folder's lock
        [
            sys.executable,
            "-c",
            "import sys\nfrom motosim.io.files import FolderLock\n"
            "with FolderLock(sys.argv[1]):\n    print('held', flush=True)\n    sys.stdin.read()\n",
            str(folder),
        ],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    ) as holder:
        try:
            assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
            assert read_manifest(folder)["status"] == "running"
        finally:
            holder.kill()  # as SIGKILL ends a campaign: the lock dies with it
            holder.wait()
    assert read_manifest(folder)["status"] == "stopped"
    store.write_manifest({"fingerprint": "f", "status": "complete"})
    assert read_manifest(folder)["status"] == "complete"
    again = ResultStore(folder, fingerprint="f", factors=[("x", float)], metrics=["rms"])
    assert again.previous == "complete"
