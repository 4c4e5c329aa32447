"""Files written whole or not at all, folders published in one rename, and a folder's lock.

- :func:`write_whole` writes a file through a temporary sibling made by
  :func:`tempfile.mkstemp` in the file's folder, then :func:`os.replace` puts it in place: a
  reader sees the previous file or the new one, never half of one.
- :func:`replace_folder` moves a finished staging folder to its place, a previous folder
  aside first: a result folder appears whole.
- :class:`FolderLock` is one exclusive ``flock`` on ``.NAME.lock`` beside a folder, held by
  the caller for as long as it writes there and handed to what writes inside; the operating
  system releases it when the process ends, however it ends.

Why this way, and the options weighed, are in ``docs/organisation.md`` (file safety).
"""

import contextlib
import fcntl
import os
import re
import shutil
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Self

from motosim.errors import MotosimError

__all__ = [
    "STALE_AFTER",
    "FolderLock",
    "is_locked",
    "lock_file",
    "reason",
    "replace_folder",
    "write_whole",
]

STALE_AFTER = 3600.0
"""Age [s] past which a temporary file of :func:`write_whole` not written to is a killed
write's: every write going on writes its file sooner than that."""

_PATIENCE = 0.05
"""How long a writer tries a folder's lock before it is refused [s]: a status reader
(:func:`is_locked`) holds it for an instant."""


def reason(err: BaseException) -> str:
    """The system's reason for a failed write, e.g. ``No space left on device``."""
    if isinstance(err, OSError) and err.strerror:
        return err.strerror
    found = re.search(r"error message = '([^']+)'", str(err))
    if found:
        return found.group(1)
    lines = str(err).strip().splitlines()
    return lines[0] if lines else type(err).__name__


def _remove_stale_temporaries(real: Path) -> None:
    """Delete the temporary files of ``real`` left by processes killed while writing it.

    Only ``.NAME.*.tmp`` files not written to for :data:`STALE_AFTER` are deleted, so a write
    going on, in any process on any machine sharing the folder, is never touched.
    """
    mine = re.compile(rf"\.{re.escape(real.name)}\.\w{{8}}\.tmp")
    stale = time.time() - STALE_AFTER
    try:
        entries = [e for e in os.scandir(real.parent) if mine.fullmatch(e.name)]
    except OSError:
        return
    for entry in entries:
        with contextlib.suppress(OSError):
            if entry.stat(follow_symlinks=False).st_mtime < stale:
                os.unlink(entry.path)


def write_whole(
    path: str | Path, write: Callable[[Path], object], *, durable: bool = False
) -> Path:
    """Write a file whole or not at all: through ``write`` into a hidden sibling, then renamed.

    Parameters
    ----------
    path : str or Path
        The file. Until ``write`` has returned, a previous file there is left as it was; a
        symbolic link is followed (the file it names is replaced, the link kept), and a
        previous file's permissions are kept.
    write : callable
        Called with the temporary path to write (``.NAME.XXXXXXXX.tmp`` beside the file; it
        exists, empty, and may be written over).
    durable : bool
        Flush the new file to the disk before the rename (:func:`os.fsync`), so that after a
        power cut the name holds the old file or the new one, never an empty one.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    MotosimError
        One line naming the file and the system's reason (a full disk, a read-only folder);
        the temporary file is deleted, as it is when ``write`` is interrupted.

    Notes
    -----
    A process killed while it writes (SIGKILL, a power cut) leaves its temporary file; a
    write of the same file an hour later (:data:`STALE_AFTER`) deletes it.
    """
    target = Path(path)
    real = Path(os.path.realpath(target))
    _remove_stale_temporaries(real)
    temporary: Path | None = None
    try:
        fd, name = tempfile.mkstemp(prefix=f".{real.name}.", suffix=".tmp", dir=real.parent)
        os.close(fd)
        temporary = Path(name)
        if real.exists():
            shutil.copymode(real, temporary)
        else:
            _default_mode(temporary)
        write(temporary)
        if durable:
            _fsync(temporary)
        os.replace(temporary, real)
    except BaseException as err:
        if temporary is not None:
            temporary.unlink(missing_ok=True)
        if isinstance(err, OSError):
            raise MotosimError(
                f"cannot write {target}: {reason(err)}; the previous file, if any, is kept"
            ) from None
        raise
    return target


def _default_mode(path: Path) -> None:
    """Give a new file the permissions ``open`` would (0666 less the umask; mkstemp's are 0600)."""
    mask = os.umask(0o022)
    os.umask(mask)
    path.chmod(0o666 & ~mask)


def _fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def replace_folder(staging: Path, folder: Path) -> None:
    """Move the finished folder ``staging`` to ``folder``, a previous ``folder`` replaced.

    The previous folder is renamed aside (``.NAME.old``), the new one renamed in, then the old
    one deleted: at every instant ``folder`` is the previous folder, missing, or the new one.
    """
    old = folder.with_name(f".{folder.name}.old")
    if old.exists():
        shutil.rmtree(old)
    if folder.exists():
        os.replace(folder, old)
    os.replace(staging, folder)
    shutil.rmtree(old, ignore_errors=True)


def lock_file(folder: str | Path) -> Path:
    """The lock held while a process writes ``folder``: ``.NAME.lock`` beside it."""
    target = Path(folder)
    return target.with_name(f".{target.name}.lock")


def _live_holder(text: str) -> int | None:
    """The pid written in a lock file (``pid N``) if a process of that number is alive."""
    found = re.fullmatch(r"\s*pid (\d+)\s*", text)
    if found is None or int(found.group(1)) <= 0:
        return None
    pid = int(found.group(1))
    try:
        os.kill(pid, 0)
    except PermissionError:  # another user's process
        return pid
    except (OverflowError, OSError):
        return None
    return pid


def _lock_within(fd: int, patience: float) -> bool:
    """Take an exclusive ``flock`` on ``fd``, trying for ``patience`` [s]; whether it was taken."""
    deadline = time.monotonic() + patience
    while True:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return True
        except BlockingIOError:
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.005)


class FolderLock:
    """An exclusive ``flock`` on ``.NAME.lock`` beside ``folder``, held within ``with``.

    The process that writes a folder holds its lock from the first file to the last (a
    result, then its report) and hands it to what writes inside
    (:class:`motosim.io.results.ResultWriter` takes it as ``lock``); a second holder, in this
    process or another, is refused in one line. The operating system releases the lock when
    the process ends, however it ends; leaving the block deletes the lock file.

    Parameters
    ----------
    folder : str or Path
        The folder written; its parent is created if needed.

    Raises
    ------
    MotosimError
        On entering: another holder still has it after 50 ms (naming the run's pid when the
        lock file names a live one), or the lock cannot be created (naming the folder).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     with FolderLock(Path(tmp) / "out") as lock:
    ...         print(lock.path.name, is_locked(lock.folder))
    .out.lock True
    """

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder).absolute()
        self.path = lock_file(self.folder)
        self._fd: int | None = None

    @property
    def held(self) -> bool:
        """Whether this object holds the lock now."""
        return self._fd is not None

    def __enter__(self) -> Self:
        try:
            self.folder.parent.mkdir(parents=True, exist_ok=True)
            self._fd = self._acquire()
        except OSError as err:
            raise MotosimError(
                f"{self.folder}: cannot create the lock {self.path}: {reason(err)}; nothing "
                "was written"
            ) from None
        return self

    def _acquire(self) -> int:
        """The descriptor of the lock file, locked, with this process's pid in it."""
        for _ in range(10):  # again if the holder before us deleted the file we opened
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            if not _lock_within(fd, _PATIENCE):
                holder = _live_holder(os.read(fd, 64).decode("ascii", "replace"))
                os.close(fd)
                who = "another process is writing this result or reading its status"
                if holder is not None:
                    who = f"another run (pid {holder}) is writing this result"
                raise MotosimError(
                    f"{self.folder}: {who}; wait for it to end or choose another folder"
                )
            try:
                if os.fstat(fd).st_ino == os.stat(self.path).st_ino:
                    os.ftruncate(fd, 0)
                    os.write(fd, f"pid {os.getpid()}\n".encode())
                    return fd
            except FileNotFoundError:
                pass
            except OSError:
                os.close(fd)
                raise
            os.close(fd)
        raise MotosimError(f"{self.folder}: could not lock {self.path}; try again")

    def __exit__(self, *exc: object) -> None:
        """Delete the lock file, then release the lock (in that order, so no one races in)."""
        if self._fd is None:
            return
        self.path.unlink(missing_ok=True)
        os.close(self._fd)
        self._fd = None


def is_locked(folder: str | Path) -> bool:
    """Whether a process holds the lock of ``folder`` (:class:`FolderLock`).

    Tries the lock without waiting and, if it gets it, lets it go at once; writes nothing (a
    missing lock file is no holder). A writer that tries the lock in that instant tries again
    for 50 ms before it is refused.

    Parameters
    ----------
    folder : str or Path
        The folder (its lock is ``.NAME.lock`` beside it).

    Returns
    -------
    bool
        True while a process, this one included, holds it.
    """
    path = lock_file(Path(folder).absolute())
    for _ in range(10):  # again if the file taken was a finished holder's, replaced meanwhile
        try:
            fd = os.open(path, os.O_RDONLY)
        except FileNotFoundError:
            return False
        except OSError:  # unreadable: say held rather than stopped
            return True
        try:
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
            same = os.fstat(fd).st_ino == os.stat(path).st_ino
        except BlockingIOError:
            return True
        except FileNotFoundError:  # its holder ended meanwhile
            return False
        finally:
            os.close(fd)
        if same:
            return False
    return True
