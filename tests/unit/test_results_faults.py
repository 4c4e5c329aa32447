"""Results survive every stop: SIGTERM, SIGKILL, a second run, a failed overwrite, a full disk."""

import csv
import fcntl
import os
import re
import shutil
import signal
import stat
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import h5py
import numpy as np
import pytest

from motosim.cli._common import finish_files_on_stop
from motosim.errors import MotosimError
from motosim.io.files import FolderLock, is_locked, lock_file, write_whole
from motosim.io.results import ResultWriter, load_result, partial_folder

NAMES = ("t", "phi")

# A child process writing 10-row blocks forever, SIGTERM handled as a command does; it
# prints "ready" after the fifth block.
_WRITER = """
import sys, time, numpy as np
from motosim.cli._common import finish_files_on_stop
from motosim.io.results import ResultWriter
with finish_files_on_stop() as stop:
    with ResultWriter(sys.argv[1], ("t", "phi"), {"seed": 3}, stop=stop) as w:
        for k in range(10**6):
            w.append(np.column_stack([np.arange(10 * k, 10 * k + 10) * 1e-3, np.ones(10)]))
            if k == 4:
                print("ready", flush=True)
            time.sleep(0.01)
"""


def _block(start: int, m: int) -> np.ndarray:
    return np.column_stack([(start + np.arange(m)) * 1e-3, np.ones(m)])


def _start_writer(folder: Path) -> subprocess.Popen[str]:
    child = subprocess.Popen(
        [sys.executable, "-c", _WRITER, str(folder)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert child.stdout is not None and child.stdout.readline().strip() == "ready"
    return child


def _plainly_readable(folder: Path) -> int:
    """Rows of the result, read with plain h5py (no SWMR) and the csv module."""
    with h5py.File(folder / "result.h5", "r") as h5:
        rows = h5["signals"].shape[0]
        assert not h5.attrs["complete"]
    csv_file = folder / "result.partial.csv"
    with csv_file.open(newline="") as handle:
        table = list(csv.reader(handle))
    assert table[0] == list(NAMES) and all(len(row) == 2 for row in table)
    assert len(table) - 1 == rows
    return rows


def test_sigterm_closes_the_files_like_ctrl_c(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    child = _start_writer(folder)
    child.send_signal(signal.SIGTERM)
    _, err = child.communicate(timeout=30)
    assert child.returncode != 0 and "KeyboardInterrupt" in err
    rows = _plainly_readable(folder)  # no previous result: the rows moved to the folder
    assert rows >= 50 and not lock_file(folder).exists()
    assert load_result(folder).t.size == rows


def test_sigkill_leaves_a_plainly_readable_partial_result(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    child = _start_writer(folder)
    child.kill()
    child.communicate(timeout=30)
    assert not folder.exists()
    with pytest.raises(MotosimError, match=r"stopped, has its rows in .*run\.partial"):
        load_result(folder)
    rows = _plainly_readable(partial_folder(folder))
    assert rows >= 50 and load_result(partial_folder(folder)).t.size == rows
    # the lock died with the process: a rerun goes ahead and replaces the partial rows
    with ResultWriter(folder, NAMES, {}) as writer:
        writer.append(_block(0, 3))
    assert load_result(folder).complete and not partial_folder(folder).exists()


def test_a_second_run_of_the_same_folder_is_refused(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    child = _start_writer(folder)
    try:
        for overwrite in (False, True):
            with pytest.raises(MotosimError, match=r"another run \(pid \d+\) is writing"):
                ResultWriter(folder, NAMES, {}, overwrite=overwrite)
    finally:
        child.terminate()
        child.communicate(timeout=30)
    assert load_result(folder).t.size >= 50


def test_a_failed_overwrite_keeps_the_previous_result(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    with ResultWriter(folder, NAMES, {"run": 1}) as writer:
        writer.append(_block(0, 7))

    def diverging_run() -> None:
        with ResultWriter(folder, NAMES, {"run": 2}, overwrite=True) as w:
            w.append(_block(0, 2))
            raise RuntimeError("the model diverged")

    with pytest.raises(RuntimeError):
        diverging_run()
    kept = load_result(folder)
    assert kept.complete and kept.metadata == {"run": 1} and kept.t.size == 7
    assert load_result(partial_folder(folder)).metadata == {"run": 2}
    with ResultWriter(folder, NAMES, {"run": 3}, overwrite=True) as writer:
        writer.append(_block(0, 1))
    assert load_result(folder).metadata == {"run": 3} and not partial_folder(folder).exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def test_a_failed_run_replaces_an_earlier_partial_result(tmp_path: Path) -> None:
    """Module notes: a stopped run's rows go where one looks when no complete result is
    there; an earlier stopped run's rows are no result to keep (the real-time guide: DIR.partial
    only beside a complete result). Seen with motosim run: a second faulted run left its rows in
    DIR.partial and the first one's in DIR, which motosim report then read."""
    folder = tmp_path / "run"

    def failed_run(number: int, rows: int) -> None:
        with ResultWriter(folder, NAMES, {"run": number}) as w:
            w.append(_block(0, rows))
            raise RuntimeError("safety fault")

    for number, rows in ((1, 4), (2, 6)):
        with pytest.raises(RuntimeError, match="safety fault"):
            failed_run(number, rows)
    kept = load_result(folder)
    assert not kept.complete and kept.metadata == {"run": 2} and kept.t.size == 6
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def test_a_folder_of_other_files_is_refused(tmp_path: Path) -> None:
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(MotosimError, match="holds files that are not a motosim result"):
        ResultWriter(tmp_path, NAMES, {})
    with pytest.raises(MotosimError, match="is the current folder or one of its parents"):
        ResultWriter(Path.cwd(), NAMES, {})


def test_not_enough_space_is_refused_before_the_run(tmp_path: Path) -> None:
    with pytest.raises(MotosimError) as info:
        ResultWriter(tmp_path / "run", NAMES, {}, expected_rows=10**15)
    assert "MB are free" in str(info.value) and not (tmp_path / "run.partial").exists()


def test_a_full_disk_is_one_line_and_keeps_the_rows(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    folder = tmp_path / "run"
    real = shutil.disk_usage
    with ResultWriter(folder, NAMES, {}) as writer:
        writer.append(_block(0, 100))
        # the disk fills up (another process) down to 10 MB
        full = real(tmp_path)._replace(free=10_000_000)
        monkeypatch.setattr(shutil, "disk_usage", lambda _: full)
        with pytest.raises(MotosimError) as info:
            writer.append(_block(100, 100))
    message = str(info.value)
    assert "\n" not in message and "the disk is full (10.0 MB free" in message
    assert f"100 rows (t <= 0.099 s) kept in {folder}" in message
    assert _plainly_readable(folder) == 100


def test_leaving_no_stale_lock_after_an_error_in_the_constructor(tmp_path: Path) -> None:
    with pytest.raises(MotosimError):
        ResultWriter(tmp_path / "run", ("x",), {})
    with ResultWriter(tmp_path / "run", NAMES, {}) as writer:
        writer.append(_block(0, 1))
    assert not lock_file(tmp_path / "run").exists()
    time.sleep(0)
    assert os.listdir(tmp_path) == ["run"]


def _swallowed_sigterm() -> None:
    """Run the SIGTERM handler where Python ignores exceptions (a finaliser, a weakref callback)."""
    try:
        signal.getsignal(signal.SIGTERM)(signal.SIGTERM, None)  # type: ignore[operator]
    except KeyboardInterrupt:
        pass  # what Python does there: prints "Exception ignored" and goes on


def _write_through_a_swallowed_sigterm(folder: Path, blocks_after: int) -> None:
    """Five rows, a swallowed SIGTERM, then ``blocks_after`` blocks of five rows."""
    with finish_files_on_stop() as stop, ResultWriter(folder, NAMES, {}, stop=stop) as w:
        w.append(_block(0, 5))
        _swallowed_sigterm()
        for k in range(blocks_after):
            w.append(_block(5 * (k + 1), 5))


def test_a_sigterm_swallowed_by_a_finaliser_still_stops_the_run_at_the_next_block(
    tmp_path: Path,
) -> None:
    """Seen in the wild: the handler's raise landed in a WeakValueDictionary callback, Python
    ignored it and the run completed with exit 0. The writer remembers the signal and stops at
    the next block, keeping the rows and marking the result partial."""
    folder = tmp_path / "run"
    with pytest.raises(KeyboardInterrupt, match="SIGTERM"):
        _write_through_a_swallowed_sigterm(folder, blocks_after=2)  # one written, then the stop
    # no previous result: the partial one is published in the folder, marked so
    with h5py.File(folder / "result.h5", "r") as h5:
        assert h5["signals"].shape[0] == 10 and not h5.attrs["complete"]


def test_a_sigterm_swallowed_after_the_last_block_marks_the_result_partial(
    tmp_path: Path,
) -> None:
    folder = tmp_path / "run"
    with pytest.raises(KeyboardInterrupt, match="SIGTERM"):
        _write_through_a_swallowed_sigterm(folder, blocks_after=0)
    with h5py.File(folder / "result.h5", "r") as h5:
        assert h5["signals"].shape[0] == 5 and not h5.attrs["complete"]
    assert (folder / "result.partial.csv").exists() and not (folder / "result.csv").exists()


@pytest.mark.parametrize("stop", [signal.SIGTERM, signal.SIGINT])
def test_a_stop_signal_between_the_two_files_waits_for_the_block(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, stop: signal.Signals
) -> None:
    """Seen under load: a SIGTERM that came after a block reached result.h5 and before it
    reached the CSV left 6000 rows in one and 5000 in the other. The signal is held while a
    block is written: both files get the block, then the run stops."""
    import motosim.io.results as results

    write_all = results._write_all
    sent = []

    def signalled_first(fd: int, data: bytes) -> None:
        if not sent and b"\n" in data and not data.startswith(b"t,"):  # a block, not the header
            sent.append(stop)
            signal.getsignal(stop)(stop, None)  # type: ignore[operator]  # the signal arrives
        write_all(fd, data)

    monkeypatch.setattr(results, "_write_all", signalled_first)
    # Ctrl-C is held only where Python's own handler is installed (not where the test runner
    # was started with SIGINT ignored, or another handler was left): install it here
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    folder = tmp_path / "run"

    def run() -> None:
        with finish_files_on_stop() as stop, ResultWriter(folder, NAMES, {}, stop=stop) as w:
            w.append(_block(0, 5))
            w.append(_block(5, 5))  # not reached

    try:
        with pytest.raises(KeyboardInterrupt, match=stop.name):
            run()
    finally:
        signal.signal(signal.SIGINT, previous)
    with h5py.File(folder / "result.h5", "r") as h5:
        assert h5["signals"].shape[0] == 5 and not h5.attrs["complete"]
    with (folder / "result.partial.csv").open(newline="") as handle:
        assert len(list(csv.reader(handle))) - 1 == 5


def _filling_after(calls: int, written: list[str]) -> object:
    """A ``write`` that writes ``calls`` pieces, then fails as a full disk does."""

    def write(temporary: Path) -> None:
        with temporary.open("w", encoding="utf-8") as handle:
            for k in range(calls):
                handle.write(f"piece {k}\n")
                handle.flush()
                written.append(temporary.name)
            raise OSError(28, "No space left on device")

    return write


def test_write_whole_keeps_the_previous_file_when_the_disk_fills(tmp_path: Path) -> None:
    target = tmp_path / "log.csv"
    target.write_text("t,theta_h\n0.0,1.0\n", encoding="utf-8")
    written: list[str] = []
    with pytest.raises(MotosimError, match="No space left on device; the previous file"):
        write_whole(target, _filling_after(3, written))  # type: ignore[arg-type]
    # the pieces went to a hidden sibling, which is gone; the old file is as it was
    assert written and re.fullmatch(r"\.log\.csv\.\w{8}\.tmp", written[0]), written
    assert target.read_text(encoding="utf-8") == "t,theta_h\n0.0,1.0\n"
    assert [p.name for p in tmp_path.iterdir()] == ["log.csv"]


_KILLED_WRITER = """
import sys, time
from pathlib import Path
from motosim.io.files import write_whole

def write(temporary: Path) -> None:
    temporary.write_text("half a log", encoding="utf-8")
    print(temporary.name, flush=True)
    time.sleep(600)  # killed here, before the rename

write_whole(Path(sys.argv[1]), write)
"""


def _writer_stopped_in_its_write(target: Path) -> tuple[subprocess.Popen[str], str]:
    """A process writing ``target`` through write_whole, held before the rename; with the
    name of its temporary file."""
    child = subprocess.Popen(
        [sys.executable, "-c", _KILLED_WRITER, str(target)], stdout=subprocess.PIPE, text=True
    )
    assert child.stdout is not None
    name = child.stdout.readline().strip()
    assert name, "the writer did not start"
    return child, name


def _try_lock(path: Path) -> bool:
    """Whether an exclusive lock on ``path`` is free (opened for writing, as NFS needs)."""
    fd = os.open(path, os.O_RDWR)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return True
    except BlockingIOError:
        return False
    finally:
        os.close(fd)


def test_write_whole_writes_a_lone_unlocked_temporary_beside_the_file(tmp_path: Path) -> None:
    # the file written holds no lock (on SMB/CIFS a lock is mandatory, and the writes, made
    # through descriptors of their own, would fail, man 2 flock) and nothing else is created
    seen: list[tuple[list[str], bool]] = []

    def write(temporary: Path) -> None:
        with temporary.open("w", encoding="utf-8") as handle:  # a descriptor of its own
            handle.write("new")
        seen.append((sorted(p.name for p in tmp_path.iterdir()), _try_lock(temporary)))

    write_whole(tmp_path / "log.csv", write, durable=True)
    assert len(seen) == 1 and len(seen[0][0]) == 1 and seen[0][1]
    assert re.fullmatch(r"\.log\.csv\.\w{8}\.tmp", seen[0][0][0])
    assert (tmp_path / "log.csv").read_text(encoding="utf-8") == "new"
    assert [p.name for p in tmp_path.iterdir()] == ["log.csv"]


def _left_long_ago(path: Path) -> None:
    """Date ``path`` past the age of a write going on, as a write killed earlier left it."""
    from motosim.io.files import STALE_AFTER

    old = time.time() - STALE_AFTER - 60.0
    os.utime(path, (old, old))


def test_write_whole_removes_a_killed_writers_leftover_and_keeps_a_running_ones(
    tmp_path: Path,
) -> None:
    # SIGKILL during a write leaves .NAME.XXXXXXXX.tmp beside the file; a later write of the
    # same file deletes it, and never the file of a write going on (the second writer here
    # started while the first one was writing)
    target = tmp_path / "log.csv"
    target.write_text("old", encoding="utf-8")
    running, live_name = _writer_stopped_in_its_write(target)
    killed, dead_name = _writer_stopped_in_its_write(target)
    killed.kill()
    killed.communicate()
    _left_long_ago(tmp_path / dead_name)
    unrelated = tmp_path / ".other.csv.abcdefgh.tmp"  # another file's
    unrelated.write_text("another file's", encoding="utf-8")
    _left_long_ago(unrelated)
    try:
        write_whole(target, lambda temporary: temporary.write_text("new", encoding="utf-8"))
        assert target.read_text(encoding="utf-8") == "new"
        assert not (tmp_path / dead_name).exists()
        assert (tmp_path / live_name).read_text(encoding="utf-8") == "half a log"  # kept
        assert unrelated.is_file()
    finally:
        running.kill()
        running.communicate()
    _left_long_ago(tmp_path / live_name)  # killed too: the next run removes it
    write_whole(target, lambda temporary: temporary.write_text("newer", encoding="utf-8"))
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["log.csv", unrelated.name])


def test_write_whole_interrupted_keeps_the_previous_file_and_no_temporary(
    tmp_path: Path,
) -> None:
    target = tmp_path / "report.html"
    target.write_text("old", encoding="utf-8")

    def interrupted(temporary: Path) -> None:
        temporary.write_text("half a page", encoding="utf-8")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_whole(target, interrupted)
    assert target.read_text(encoding="utf-8") == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["report.html"]


def test_write_log_on_a_full_disk_keeps_the_previous_log(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import csv as csv_module

    from motosim.io import logs
    from motosim.timeseries import TimeSeries

    target = tmp_path / "excite.csv"
    old = TimeSeries(np.array([0.0, 0.01]), np.array([[1.0], [2.0]]), ("i_cmd",))
    logs.write_log(target, old)
    before = target.read_bytes()
    real = csv_module.writer

    class Filling:  # the third row does not fit
        def __init__(self, handle: object) -> None:
            self._writer = real(handle)  # type: ignore[arg-type]
            self._rows = 0

        def writerow(self, row: object) -> None:
            self._rows += 1
            if self._rows > 2:
                raise OSError(28, "No space left on device")
            self._writer.writerow(row)  # type: ignore[arg-type]

    monkeypatch.setattr(logs.csv, "writer", Filling)
    longer = TimeSeries(np.arange(5) * 0.01, np.ones((5, 1)), ("i_cmd",))
    with pytest.raises(MotosimError, match=r"cannot write .*No space left on device"):
        logs.write_log(target, longer)
    # the old log as it was, not truncated with rows of the new one in it as if complete
    assert target.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["excite.csv"]


def test_folder_lock_refuses_a_second_writer_and_is_released(tmp_path: Path) -> None:
    out = tmp_path / "campaign"
    with FolderLock(out) as lock:
        assert lock.path == lock_file(out.absolute())
        with pytest.raises(MotosimError, match=rf"another run \(pid {os.getpid()}\) is writing"):
            with FolderLock(out):
                pass
        with pytest.raises(MotosimError, match="another run"):  # a result writer too
            ResultWriter(out, NAMES, {})
    with FolderLock(out):  # released on leaving
        pass
    assert not lock.path.exists()


_READER = """
import fcntl, os, sys
fd = os.open(sys.argv[1], os.O_RDONLY)
fcntl.flock(fd, fcntl.LOCK_SH)  # as is_locked does, for an instant
print("reading", flush=True)
sys.stdin.read()
"""


def _dead_pid() -> int:
    """The pid of a process that has ended (reaped)."""
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def test_folder_lock_names_no_dead_pid_when_a_reader_holds_a_stale_lock(tmp_path: Path) -> None:
    # the finding: a killed campaign's stale lock file says "pid 99999"; a status reader
    # (is_locked) holding its shared lock made the folder lock say that a dead pid was writing
    out = tmp_path / "campaign"
    stale = lock_file(out.absolute())
    stale.write_text(f"pid {_dead_pid()}\n", encoding="ascii")
    with subprocess.Popen(
        [sys.executable, "-c", _READER, str(stale)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    ) as reader:
        try:
            assert reader.stdout is not None and reader.stdout.readline().strip() == "reading"
            with pytest.raises(MotosimError) as info:
                with FolderLock(out):
                    pass
        finally:
            reader.kill()
    message = str(info.value)
    assert "another process is writing this result or reading its status" in message
    assert "pid" not in message and "\n" not in message
    with FolderLock(out):  # the reader gone, the stale file is taken over
        assert stale.read_text(encoding="ascii") == f"pid {os.getpid()}\n"


def test_folder_lock_waits_out_a_readers_instant(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # is_locked holds a shared lock for microseconds; a writer trying in that instant was
    # refused at once. Here the lock is busy for the first three tries, as if a reader held it
    from motosim.io import files

    real = fcntl.flock
    tries: list[int] = []

    def busy_at_first(fd: int, operation: int) -> None:
        if operation & fcntl.LOCK_EX and len(tries) < 3:
            tries.append(fd)
            raise BlockingIOError(11, "Resource temporarily unavailable")
        real(fd, operation)

    monkeypatch.setattr(files.fcntl, "flock", busy_at_first)
    out = tmp_path / "campaign"
    with FolderLock(out) as lock:
        assert lock.path.read_text(encoding="ascii") == f"pid {os.getpid()}\n"
    assert len(tries) == 3


def test_a_folder_lock_handed_to_its_writer_is_held_to_the_end(tmp_path: Path) -> None:
    # what simulate and cueing hold while they write the result, then its report or figures
    import threading

    out = tmp_path / "run"
    refused: list[str] = []

    def other_thread() -> None:
        try:
            ResultWriter(out, NAMES, {}, overwrite=True)
        except MotosimError as err:
            refused.append(str(err))

    with FolderLock(out) as lock:
        with ResultWriter(out, NAMES, {}, lock=lock) as writer:  # handed: not refused
            writer.append(np.array([[0.0, 1.0]]))
        assert lock.path.exists() and is_locked(out)  # the writer closed; still locked
        thread = threading.Thread(target=other_thread)
        thread.start()
        thread.join()
        assert len(refused) == 1 and "another run" in refused[0]
        fd = os.open(lock.path, os.O_RDWR)  # as another process sees it: locked
        try:
            with pytest.raises(BlockingIOError):
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        finally:
            os.close(fd)
    assert not lock.path.exists() and not is_locked(out)
    with FolderLock(out):  # released at the end of the block
        pass
    with pytest.raises(MotosimError, match="not the held lock of this folder"):
        ResultWriter(out, NAMES, {}, overwrite=True, lock=lock)  # no longer held


def test_write_whole_writes_through_a_link_and_keeps_the_files_permissions(tmp_path: Path) -> None:
    # renaming the temporary over the link replaced the link by a file (the file it named left
    # as it was) and made a private (0600) file readable by everyone (0644)
    real = tmp_path / "real.csv"
    real.write_text("old", encoding="utf-8")
    real.chmod(0o600)
    link = tmp_path / "link.csv"
    link.symlink_to(real)
    write_whole(link, lambda p: p.write_text("new", encoding="utf-8"))
    assert link.is_symlink() and real.read_text(encoding="utf-8") == "new"
    assert stat.S_IMODE(real.stat().st_mode) == 0o600
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.csv", "real.csv"]


def _stopped_run(
    folder: Path,
    rows: int,
    writers: list[ResultWriter],
    meanwhile: Callable[[], None] | None = None,
) -> None:
    """A run of ``rows`` rows into ``folder`` stopped by Ctrl-C, after ``meanwhile()``."""
    with ResultWriter(folder, NAMES, {}) as writer:
        writers.append(writer)
        writer.append(_block(0, rows))
        if meanwhile is not None:
            meanwhile()
        raise KeyboardInterrupt


def test_a_stopped_run_never_replaces_a_folder_of_other_files(tmp_path: Path) -> None:
    # files another program (a campaign of a version that locked inside its folder) put in
    # the result folder while the run went: _abort published over any folder that was not a
    # complete result, and the rename deleted them
    folder = tmp_path / "run"

    def campaign_meanwhile() -> None:
        folder.mkdir()
        (folder / "manifest.json").write_text("{}\n", encoding="utf-8")

    writers: list[ResultWriter] = []
    with pytest.raises(KeyboardInterrupt):
        _stopped_run(folder, 5, writers, campaign_meanwhile)
    writer = writers[0]
    assert [p.name for p in folder.iterdir()] == ["manifest.json"]
    assert writer.location == partial_folder(folder)
    assert load_result(partial_folder(folder)).t.size == 5
    assert not lock_file(folder).exists()


def test_a_completed_run_never_replaces_a_folder_of_other_files(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    with ResultWriter(folder, NAMES, {}) as writer:
        writer.append(_block(0, 5))
        folder.mkdir()
        (folder / "manifest.json").write_text("{}\n", encoding="utf-8")
        with pytest.raises(MotosimError) as caught:
            writer.close()
    message = str(caught.value)
    assert "\n" not in message and "not a motosim result" in message
    assert str(partial_folder(folder)) in message
    assert [p.name for p in folder.iterdir()] == ["manifest.json"]
    kept = load_result(partial_folder(folder))
    assert kept.complete and kept.t.size == 5
    assert not lock_file(folder).exists()


def test_a_stopped_run_still_replaces_an_empty_folder_or_a_stopped_result(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    folder.mkdir()  # empty: as before
    for rows in (3, 4):  # the second replaces the first run's rows
        writers: list[ResultWriter] = []
        with pytest.raises(KeyboardInterrupt):
            _stopped_run(folder, rows, writers)
        assert writers[0].location == folder and load_result(folder).t.size == rows
