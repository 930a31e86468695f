"""Locks: one writer per Q-table, log or sweep folder at a time.

Two ``koolio-pm train`` runs on the same ``--qtable`` would each load the table, learn,
and overwrite each other's saves: one run's episodes would silently vanish. So a writer
(``train``, ``view`` while learning, ``sweep``) first takes an advisory lock on a lock
file beside what it writes (``runs/hallway.qtable.lock``, ``runs/hallway.csv.lock``,
``sweeps/NAME/.sweep.lock``); a second writer gets the one-line error
``runs/hallway.qtable: in use by process 4242 (koolio-pm train) ...``. Readers (``eval``,
``export``, ``view --greedy``, ``info``) take no lock: every write is atomic, so they
always read a whole file.

The lock is the operating system's (``flock`` on POSIX, ``msvcrt.locking`` on Windows),
held by an open file: it goes away with the process however it ends, SIGKILL included,
so a crash never leaves a stale lock. The lock file itself stays (deleting it would let
two processes lock two different files of one name); it holds the holder's process id
and command for the message above, and can be deleted whenever no process runs.

>>> import pathlib, tempfile
>>> table = pathlib.Path(tempfile.mkdtemp()) / "t.qtable"
>>> with FileLock(table, "demo"):
...     FileLock(table, "second").acquire()  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
koolio_pymunk.errors.InUseError: ...t.qtable: in use by process ... (demo)...
"""

from __future__ import annotations

import contextlib
import os
import sys
from pathlib import Path

from .errors import FileError, InUseError, located
from .files import make_parent, os_problem

if sys.platform == "win32":  # pragma: no cover - exercised on Windows only
    import msvcrt

    def _try_lock(fd: int) -> bool:
        os.lseek(fd, 0, os.SEEK_SET)
        try:
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
        except OSError:
            return False
        return True

    def _unlock(fd: int) -> None:
        os.lseek(fd, 0, os.SEEK_SET)
        msvcrt.locking(fd, msvcrt.LK_UNLCK, 1)

else:
    import fcntl

    def _try_lock(fd: int) -> bool:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return False
        return True

    def _unlock(fd: int) -> None:
        fcntl.flock(fd, fcntl.LOCK_UN)


#: The holder's note starts after this byte (Windows locks byte 0 against reading).
_NOTE_AT = 1


def lock_path(target: str | Path) -> Path:
    """The lock file of ``target``: ``<target>.lock`` beside it (beside the file a symbolic
    link points to, so that two names of one file share one lock)."""
    target = Path(target)
    if target.is_symlink():
        target = Path(os.path.realpath(target))
    return target.with_name(target.name + ".lock")


class FileLock:
    """An exclusive advisory lock on ``target`` (module doc); also a context manager.

    ``purpose`` (e.g. ``koolio-pm train``) is shown to a process that finds it held.
    """

    def __init__(self, target: str | Path, purpose: str = "koolio-pm", path: Path | None = None):
        self.target = Path(target)
        self.path = path if path is not None else lock_path(self.target)
        self.purpose = purpose
        self._fd: int | None = None

    @property
    def held(self) -> bool:
        return self._fd is not None

    def acquire(self) -> FileLock:
        """Take the lock; :class:`InUseError` naming the holder when another has it."""
        if self._fd is not None:
            return self
        make_parent(self.path)
        try:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o666)
        except OSError as exc:
            raise FileError(
                located(
                    str(self.target),
                    "",
                    f"cannot create its lock file {self.path}: {os_problem(exc)}",
                )
            ) from None
        try:
            locked = _try_lock(fd)
        except OSError:  # a file system without locks: go on unprotected
            locked = True
        if not locked:
            holder = _read_note(fd)
            os.close(fd)
            raise InUseError(
                located(
                    str(self.target),
                    "",
                    f"in use by {holder}; wait for it to finish or stop it (lock file {self.path})",
                )
            )
        self._fd = fd
        _write_note(fd, f"process {os.getpid()} ({self.purpose})")
        return self

    def release(self) -> None:
        """Give the lock up (closing the file releases it too)."""
        fd, self._fd = self._fd, None
        if fd is None:
            return
        with contextlib.suppress(OSError):
            _unlock(fd)
        os.close(fd)

    def __enter__(self) -> FileLock:
        return self.acquire()

    def __exit__(self, *exc: object) -> None:
        self.release()

    def __del__(self) -> None:
        self.release()


def _write_note(fd: int, note: str) -> None:
    with contextlib.suppress(OSError):  # the note is a courtesy: the lock holds without it
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, b"#" + note.encode("utf-8", "replace") + b"\n")


def _read_note(fd: int) -> str:
    try:
        os.lseek(fd, _NOTE_AT, os.SEEK_SET)
        text = os.read(fd, 200).decode("utf-8", "replace").strip()
    except OSError:
        text = ""
    return text or "another process"
