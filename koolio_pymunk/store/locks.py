"""Locks: one writer per Q-table, log or sweep folder at a time.

Two ``koolio-pm train`` runs on the same ``--qtable`` would each load the table, learn,
and overwrite each other's saves: one run's episodes would silently vanish. So a writer
(``train``, ``view`` while learning, ``sweep``) first takes an advisory lock on a lock
file beside what it writes (``runs/hallway.qtable.lock``, ``sweeps/NAME/.sweep.lock``); a
second writer gets the one-line error
``runs/hallway.qtable: in use by process 4242 (koolio-pm train) ...``. Readers (``eval``,
``export``, ``view --greedy``, ``info``) take no lock: every write is atomic, so they
always read a whole file.

**One lock file per run.** The files of a run are named after its table ``X.qtable``: its
log ``X.csv``, the checks' ``X.evals.csv`` and the best table ``X.best.qtable``. They share
the table's lock file, ``X.qtable.lock`` (:func:`lock_path`), so a run leaves one lock
file, not four, and a second run is still refused whichever of them it names: a log
``X.csv`` of another table ``Y.qtable`` (``--log`` given) takes ``Y.qtable.lock`` and
``X.qtable.lock``, and is refused while the run of ``X.qtable`` goes on. A run's file
whose table's lock this process already holds is covered by it (the lock is counted and
the operating system's lock given back at the last release); a second lock of the table
itself is refused within one process as between two.

The lock is the operating system's (``flock`` on POSIX, ``msvcrt.locking`` on Windows),
held by an open file: it goes away with the process however it ends, SIGKILL included,
so a crash never leaves a stale lock. The lock file itself stays (deleting it would let
two processes lock two different files of one name); it holds the holder's process id
and command for the message above, and can be deleted whenever no process runs.

**Only a plain lock file is used.** The lock file is opened without following a symbolic
link (``O_NOFOLLOW``) and without blocking, and must be a regular file with one name
(not a hard link of the table), holding nothing but a holder's note (``#process ...``,
a few dozen bytes): anything else at its name (a link to the table, a FIFO, a folder,
a file of other data) is refused with one line and left as it is, never truncated or
written through.

>>> import pathlib, tempfile
>>> table = pathlib.Path(tempfile.mkdtemp()) / "t.qtable"
>>> with FileLock(table, "demo"):
...     FileLock(table, "second").acquire()  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
koolio_pymunk.store.errors.InUseError: ...t.qtable: in use by process ... (demo)...
"""

from __future__ import annotations

import contextlib
import os
import sys
from pathlib import Path

from .errors import FileError, InUseError, located
from .files import make_parent, os_problem, special_kind

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


#: A run's files and the table whose lock file they share (module doc), longest first.
RUN_FILES = ((".best.qtable", ".qtable"), (".evals.csv", ".qtable"), (".csv", ".qtable"))


def lock_path(target: str | Path) -> Path:
    """The lock file of ``target``: ``<table>.lock`` beside it, where ``<table>`` is the
    target itself, or for a run's file (:data:`RUN_FILES`) the table it is named after
    (module doc); beside the file a symbolic link points to, so that two names of one
    file share one lock (beside the link itself when it points nowhere: no folder is made
    where a dangling link points).

    >>> [lock_path(n).name for n in ("r.qtable", "r.csv", "r.evals.csv", "r.best.qtable", "p.json")]
    ['r.qtable.lock', 'r.qtable.lock', 'r.qtable.lock', 'r.qtable.lock', 'p.json.lock']
    """
    target = Path(target)
    with contextlib.suppress(OSError):  # unreachable: acquire() says why
        if target.is_symlink() and target.exists():
            target = Path(os.path.realpath(target))
    name = target.name
    for suffix, table in RUN_FILES:
        if name.endswith(suffix) and len(name) > len(suffix):
            name = name[: -len(suffix)] + table
            break
    return target.with_name(name + ".lock")


#: The lock files this process holds: their absolute path -> ``[fd, times taken, pid, the
#: table itself among them]`` (the pid: a forked child holds nothing of its parent's).
_HELD: dict[str, list[int]] = {}


def _held(path: Path) -> list[int] | None:
    """This process's hold on the lock file ``path`` (None: it holds none)."""
    held = _HELD.get(os.path.abspath(path))
    return held if held is not None and held[2] == os.getpid() else None


def _shares(target: Path, path: Path) -> list[int] | None:
    """This process's hold on ``path`` when ``target`` may share it (module doc): a run's
    file always, the table only when its run's files alone hold it so far."""
    held = _held(path)
    if held is None or (not is_run_file(target) and held[3]):
        return None
    return held


def is_run_file(target: str | Path) -> bool:
    """``target`` is a run's file named after its table (:data:`RUN_FILES`).

    >>> is_run_file("r.csv"), is_run_file("r.best.qtable"), is_run_file("r.qtable")
    (True, True, False)
    """
    name = Path(target).name
    return any(name.endswith(suffix) and len(name) > len(suffix) for suffix, _ in RUN_FILES)


#: How a holder's note starts (``#process <pid> (<purpose>)``).
NOTE_START = b"#process "
#: Largest lock file taken as one (a note is ``#process <pid> (<purpose>)``).
MAX_NOTE_BYTES = 4096
#: Flags of the lock file's open: created if missing, never through a symbolic link,
#: never waiting (a FIFO), not inherited by child processes.
_LOCK_FLAGS = (
    os.O_RDWR
    | os.O_CREAT
    | getattr(os, "O_NOFOLLOW", 0)
    | getattr(os, "O_NONBLOCK", 0)
    | getattr(os, "O_CLOEXEC", 0)
)


class FileLock:
    """An exclusive advisory lock on ``target`` (module doc); also a context manager.

    ``purpose`` (e.g. ``koolio-pm train``) is shown to a process that finds it held.
    """

    _fd: int | None = None

    def __init__(self, target: str | Path, purpose: str = "koolio-pm", path: Path | None = None):
        self._fd = None
        self.target = Path(target)
        self.path = path if path is not None else lock_path(self.target)
        self.purpose = purpose

    @property
    def held(self) -> bool:
        return self._fd is not None

    def acquire(self) -> FileLock:
        """Take the lock; :class:`InUseError` naming the holder when another has it, a
        :class:`FileError` when the lock file cannot be made or is not a plain lock file."""
        if self._fd is not None:
            return self
        held = _shares(self.target, self.path)
        if held is not None:  # one run's files: the table's lock, already ours
            held[1] += 1
            held[3] = held[3] or not is_run_file(self.target)
            self._fd = held[0]
            return self
        make_parent(self.path)
        fd = self._open()
        try:
            locked = _try_lock(fd)
        except OSError:  # a file system without locks: go on unprotected
            locked = True
        if not locked:
            holder = _read_note(fd)
            os.close(fd)
            raise _in_use(self.target, self.path, holder)
        try:
            self._check_content(fd)
        except BaseException:
            with contextlib.suppress(OSError):
                _unlock(fd)
            os.close(fd)
            raise
        self._fd = fd
        _HELD[os.path.abspath(self.path)] = [fd, 1, os.getpid(), not is_run_file(self.target)]
        _write_note(fd, f"process {os.getpid()} ({self.purpose})")
        return self

    def _open(self) -> int:
        """The lock file, opened as a plain lock file (module doc) or refused."""
        try:
            fd = os.open(self.path, _LOCK_FLAGS, 0o666)
        except OSError as exc:
            if os.path.islink(self.path):
                raise _refuse(self.target, self.path, _LINK) from None
            _refuse_special(self.target, self.path)  # e.g. a socket cannot be opened
            raise FileError(
                located(
                    str(self.target),
                    "",
                    f"cannot create its lock file {self.path}: {os_problem(exc)}",
                )
            ) from None
        try:
            _check_opened(fd, self.target, self.path)
        except BaseException:
            os.close(fd)
            raise
        return fd

    def _check_content(self, fd: int) -> None:
        """Under the lock: the file holds a holder's note or nothing (it is about to be
        truncated: nothing else may be)."""
        _check_note(fd, self.target, self.path)

    def release(self) -> None:
        """Give the lock up (closing the file releases it too)."""
        fd, self._fd = self._fd, None
        if fd is None:
            return
        held = _held(self.path)
        if held is not None and held[0] == fd:
            held[1] -= 1
            held[3] = held[3] and is_run_file(self.target)
            if held[1] > 0:
                return
            del _HELD[os.path.abspath(self.path)]
        with contextlib.suppress(OSError):
            _unlock(fd)
        with contextlib.suppress(OSError):
            os.close(fd)

    def __enter__(self) -> FileLock:
        return self.acquire()

    def __exit__(self, *exc: object) -> None:
        self.release()

    def __del__(self) -> None:
        self.release()


_LINK = "is a symbolic link, not a lock file: remove it (no run is using it)"


def _refuse(target: Path, path: Path, problem: str) -> FileError:
    return FileError(located(str(target), "", f"its lock file {path} {problem}"))


def _refuse_special(target: Path, path: Path) -> None:
    """Refuse ``path`` when it is there and not a regular file (nothing if unreachable)."""
    try:
        kind = special_kind(os.lstat(path).st_mode)
    except OSError:
        return
    if kind is not None:
        raise _refuse(target, path, f"is {kind}, not a lock file: remove it")


def _check_opened(fd: int, target: Path, path: Path) -> None:
    """A lock file is a regular file of one name (not a hard link of the table)."""
    st = os.fstat(fd)
    kind = special_kind(st.st_mode)
    if kind is not None:
        raise _refuse(target, path, f"is {kind}, not a lock file: remove it")
    if st.st_nlink > 1:
        raise _refuse(
            target,
            path,
            f"has {st.st_nlink} names (a hard link, perhaps of the table itself), "
            "not a lock file of its own: remove that name",
        )


def _check_note(fd: int, target: Path, path: Path) -> None:
    """A lock file holds a holder's note (``#process ...``, at most
    :data:`MAX_NOTE_BYTES`) or nothing (a log's first line also starts with ``#``)."""
    size = os.fstat(fd).st_size
    if size == 0:
        return
    try:
        head = os.pread(fd, len(NOTE_START), 0)
    except OSError:
        head = b""
    if size > MAX_NOTE_BYTES or head != NOTE_START:
        raise _refuse(
            target,
            path,
            "holds other data than a lock note (it does not start with '#process ' or it "
            f"is over {MAX_NOTE_BYTES} bytes): move that file away",
        )


def check_lock_file(target: str | Path, path: Path | None = None) -> None:
    """Refuse, before anything is read or written, a lock file of ``target`` that could
    not be taken (module doc: a link, a special file, a hard link, other data) or that
    another process holds now (:class:`InUseError`, as :meth:`FileLock.acquire` would
    say it later); a missing or unreachable one is left to :meth:`FileLock.acquire`."""
    target = Path(target)
    path = path if path is not None else lock_path(target)
    if _shares(target, path) is not None:
        return  # the run's lock, this process's: checked when it was taken
    if os.path.islink(path):
        raise _refuse(target, path, _LINK)
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(path, flags)
    except OSError:
        _refuse_special(target, path)  # e.g. a socket cannot be opened
        return
    try:
        _check_opened(fd, target, path)
        _check_note(fd, target, path)
        _check_free(fd, target, path)
    finally:
        os.close(fd)


def _check_free(fd: int, target: Path, path: Path) -> None:
    """Nobody holds the lock of ``fd`` now (taken and given back at once)."""
    try:
        free = _try_lock(fd)
    except OSError:  # a file system without locks: as FileLock.acquire, go on
        return
    if not free:
        raise _in_use(target, path, _read_note(fd))
    with contextlib.suppress(OSError):
        _unlock(fd)


def _in_use(target: Path, path: Path, holder: str) -> InUseError:
    problem = f"in use by {holder}; wait for it to finish or stop it (lock file {path})"
    return InUseError(located(str(target), "", problem))


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
