"""Files: every file koolio-pymunk writes, and most it reads, go through here.

**Atomic writes.** A write goes to a temporary file in the same folder
(``.<name>.<pid>.<random>.tmp``), is flushed and fsynced, then renamed over the target
with ``os.replace``; a crash at any moment leaves either the old file or the new one,
never a torn mixture, and a failed write leaves no temporary file. A process killed in
the middle of a write (SIGKILL, power loss) leaves its temporary file behind: the next
write of the same target removes the temporary files of processes that no longer run
(:func:`remove_stale_temps`).

**Backups without a second write.** :func:`staged_write` is the same write with a step
between the fsync and the rename, and :func:`atomic_link` gives a file a second name
atomically (a hard link under a temporary name, renamed): the file about to be replaced
becomes its backup there, its bytes already on disk, with no second write and no second
fsync (:class:`~koolio_pymunk.store.qtable.QTableStore`).

**Reading.** Every input file (arenas, configurations, worlds, door tables, logs, sweep
specs, Q-tables, policies, editor scripts) is read by :func:`read_bytes` /
:func:`read_text`: opened without blocking (``O_NONBLOCK``: opening a FIFO for reading
would otherwise wait for a writer for ever), checked to be a regular file (a FIFO, a
device, a socket or a folder is refused with one line before a byte is read), and read
up to its kind's size limit. :func:`check_regular` refuses the same for a file about to
be written (a log that is a FIFO would block its writer).

>>> import os, pathlib, tempfile
>>> fifo = pathlib.Path(tempfile.mkdtemp()) / "x.csv"
>>> os.mkfifo(fifo)
>>> read_text(fifo)  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
koolio_pymunk.store.errors.FileError: ...x.csv: is a FIFO (named pipe), not a regular file

**One-line errors.** Every operating-system failure (disk full, read-only folder,
permission denied, a folder where a file should be, a path under a regular file, an empty
path ...) becomes a :class:`~koolio_pymunk.store.errors.FileError` naming the file:
``runs/x.qtable: cannot write: disk full (no space left on device)``. The target is never
damaged: a failed write leaves the old file as it was.

>>> p = pathlib.Path(tempfile.mkdtemp()) / "note.txt"
>>> atomic_write_text(p, "hello")
>>> p.read_text()
'hello'
>>> atomic_write_text(p.parent, "x")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
koolio_pymunk.store.errors.FileError: ...: cannot write: is a folder, not a file
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import secrets
import stat
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

from .errors import FileError, located

#: Plain words for the errors people meet; anything else uses the system's message.
_WORDS = {
    errno.ENOSPC: "disk full (no space left on device)",
    errno.EDQUOT: "disk quota exceeded",
    errno.EACCES: "permission denied",
    errno.EPERM: "operation not permitted",
    errno.EROFS: "read-only file system",
    errno.EISDIR: "is a folder, not a file",
    errno.ENOTDIR: "a part of the path is a file, not a folder",
    errno.ENOENT: "no such file or folder",
    errno.ENAMETOOLONG: "file name too long",
    errno.EEXIST: "a file is in the way",
    errno.EIO: "input/output error",
    errno.EFBIG: "file too large",
    errno.ETXTBSY: "file in use",
}


def os_problem(exc: OSError) -> str:
    """A short plain description of an operating-system error.

    >>> os_problem(OSError(28, "No space left on device"))
    'disk full (no space left on device)'
    """
    return _WORDS.get(exc.errno or 0) or exc.strerror or str(exc) or type(exc).__name__


def file_error(path: str | Path, action: str, exc: OSError) -> FileError:
    """The :class:`FileError` ``path: cannot <action>: <problem>`` of ``exc``."""
    err = FileError(located(_name(path), "", f"cannot {action}: {os_problem(exc)}"))
    err.errno = exc.errno
    return err


def _name(path: str | Path) -> str:
    text = str(path)
    return text if text else "''"


def check_path(path: str | Path, item: str = "") -> Path:
    """``path`` as a Path; an empty name is a :class:`FileError` (``Path('')`` is ``.``)."""
    if str(path).strip() == "":
        raise FileError(located(item or "''", "", "empty file name"))
    return Path(path)


def make_parent(path: str | Path) -> None:
    """Create the folder that will hold ``path`` (and its parents) if missing."""
    parent = Path(path).parent
    with contextlib.suppress(OSError):  # unreachable: mkdir below says why
        if parent.is_dir():
            return
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise FileError(
            located(_name(path), "", f"cannot create the folder {parent}: a file is in the way")
        ) from None
    except OSError as exc:
        raise FileError(
            located(_name(path), "", f"cannot create the folder {parent}: {os_problem(exc)}")
        ) from None


def atomic_write(path: str | Path, data: bytes, make_parents: bool = True) -> None:
    """Replace ``path`` with ``data`` atomically; :class:`FileError` on any failure.

    The target keeps its permissions (a new file gets what ``open()`` would give it).
    """
    with staged_write(path, data, make_parents):
        pass


@contextlib.contextmanager
def staged_write(
    path: str | Path, data: bytes, make_parents: bool = True, durable: bool = True
) -> Iterator[os.stat_result]:
    """:func:`atomic_write` in two stages: ``data`` is written to the temporary file and
    fsynced on entry, and renamed over ``path`` when the block ends without an exception
    (an exception removes the temporary file and leaves ``path`` as it was). Yields the
    temporary file's ``fstat``: the target's :func:`identity` once renamed. The block
    runs between the two: a backup of the file about to be replaced is made there
    (:func:`atomic_link`), after the new data is safely on disk.

    ``durable`` False skips the fsync: the replace is still atomic for every process (a
    killed one included), but a power loss may leave the file empty or torn; with True,
    :func:`fsync_dir` after the block makes the new name itself survive one."""
    path = _writable(path, make_parents)
    mode = _mode_for(path)
    try:
        fd, tmp = tempfile.mkstemp(
            prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp", dir=path.parent
        )
    except OSError as exc:
        raise file_error(path, "write", exc) from None
    with _temporary(tmp, path):
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fchmod(fh.fileno(), mode)
            if durable:
                os.fsync(fh.fileno())
            written = os.fstat(fh.fileno())
        yield written
        os.replace(tmp, path)


@contextlib.contextmanager
def fsync_dir(folder: str | Path) -> None:
    """Make the names of ``folder`` (a rename, a new link, an unlink) survive a power loss
    (POSIX: fsync of the directory). Best effort: a file system that cannot (some network
    or virtual ones) is left as it is."""
    try:
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


@contextlib.contextmanager
def _temporary(tmp: str | Path, path: Path) -> Iterator[None]:
    """A block that ends with the temporary file ``tmp`` renamed over ``path``: on any
    exception ``tmp`` is removed, and an ``OSError`` becomes ``path``'s one-line
    :class:`FileError`."""
    try:
        yield
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if isinstance(exc, OSError):
            raise file_error(path, "write", exc) from None
        raise


def check_writable(path: str | Path) -> Path:
    """``path`` checked as the target of an atomic write, changing nothing: not a folder,
    a FIFO, a device or a socket (:class:`FileError`); a caller that writes it later asks
    first, so that a refusal comes before any other file is written."""
    path = check_path(path)
    if path.is_dir():
        raise FileError(located(_name(path), "", "cannot write: is a folder, not a file"))
    _check_target(path)
    return path


def _writable(path: str | Path, make_parents: bool) -> Path:
    """``path`` checked as the target of an atomic write (not a folder, a FIFO, a device
    or a socket), its folder made, the stale temporary files of its writes removed."""
    path = check_writable(path)
    if make_parents:
        make_parent(path)
    remove_stale_temps(path)
    return path


def identity(st: os.stat_result) -> tuple[int, int, int, int]:
    """What tells one file from another, and a file from itself after it changed: device,
    inode, size, modification time (ns). A file whose identity is the one recorded when
    it was written still holds what was written (every write is atomic: a new inode)."""
    return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)


def atomic_link(src: str | Path, dst: str | Path) -> bool:
    """Make ``dst`` another name of the file ``src`` atomically (a hard link made under a
    temporary name, then renamed over ``dst``): ``dst`` then holds ``src``'s bytes
    without writing them again. ``dst`` is checked as :func:`atomic_write` checks its
    target (:class:`FileError`: a FIFO, a device, a socket, a folder; a failed rename).

    Returns False, changing nothing, when a link cannot stand for a copy written by
    :func:`atomic_write`: the file system has no hard links (or refuses this one), or
    ``dst`` would get other permissions than a written copy (its own, or a new file's).
    The caller then writes the copy. True when ``dst`` is already ``src``'s file.
    """
    dst = _writable(dst, True)
    try:
        st = os.stat(src)
    except OSError:
        return False
    with contextlib.suppress(OSError):
        if os.path.samestat(st, os.stat(dst)):
            return True  # renaming a name onto another name of its file does nothing
    if st.st_mode & 0o7777 != _mode_for(dst):
        return False
    tmp = dst.parent / f".{dst.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp"
    try:
        os.link(src, tmp)
    except OSError:
        return False
    with _temporary(tmp, dst):
        os.replace(tmp, dst)
    return True


def _check_target(path: Path) -> None:
    """Refuse to replace a FIFO, a device or a socket by a file (it is not ours to
    replace; a symbolic link to a regular file is replaced as it always was)."""
    try:
        mode = os.stat(path).st_mode
    except OSError:  # missing, or unreachable: the write itself says why
        return
    if not stat.S_ISREG(mode) and not stat.S_ISDIR(mode):
        raise FileError(
            located(_name(path), "", f"cannot write: is {special_kind(mode)}, not a regular file")
        )


def _mode_for(path: Path) -> int:
    """The target's current permissions, or what ``open()`` would give a new file (mkstemp
    alone would leave 0600)."""
    try:
        return path.stat().st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def atomic_write_text(path: str | Path, text: str) -> None:
    """Replace ``path`` with ``text`` (UTF-8) atomically."""
    atomic_write(path, text.encode("utf-8"))


# -- temporary files of interrupted writes --------------------------------------------------
_cleaned: set[str] = set()


def _temp_pattern(name: str) -> re.Pattern[str]:
    """``.<name>.<pid>.<random>.tmp`` (this module) or ``.<name>.<random>.tmp`` (older)."""
    return re.compile(rf"^\.{re.escape(name)}\.(?:(\d+)\.)?[A-Za-z0-9_]{{6,12}}\.tmp$")


def remove_stale_temps(path: str | Path, owned: bool = False) -> list[Path]:
    """Remove the temporary files that interrupted writes of ``path`` left behind.

    A temporary file named after a process that no longer runs is stale. With ``owned``
    (the caller holds the file's lock, so no other process writes it) every temporary
    file of ``path`` but this process's own is stale, including older unnamed ones.
    Looks once per target and process; returns the files removed.
    """
    path = Path(path)
    key = str(path.absolute())
    if key in _cleaned and not owned:
        return []
    _cleaned.add(key)
    pattern = _temp_pattern(path.name)
    removed: list[Path] = []
    try:
        names = os.listdir(path.parent)
    except OSError:
        return removed
    for name in names:
        m = pattern.match(name)
        if m is None:
            continue
        pid = int(m.group(1)) if m.group(1) else None
        if pid == os.getpid():
            continue
        if owned or (pid is not None and not process_alive(pid)):
            with contextlib.suppress(OSError):
                os.unlink(path.parent / name)
                removed.append(path.parent / name)
    return removed


def process_alive(pid: int) -> bool:
    """True when process ``pid`` runs (or might: on Windows this is not checked)."""
    if sys.platform == "win32":  # os.kill there would terminate the process
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # e.g. PermissionError: it runs, as another user
        return True
    return True


# -- reading ------------------------------------------------------------------------------
def special_kind(mode: int) -> str | None:
    """What a file of ``st_mode`` ``mode`` is when it is not a regular file (None if it is).

    >>> special_kind(stat.S_IFIFO), special_kind(stat.S_IFREG) is None
    ('a FIFO (named pipe)', True)
    """
    if stat.S_ISREG(mode):
        return None
    for test, words in (
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
        (stat.S_ISLNK, "a symbolic link"),
    ):
        if test(mode):
            return words
    return "a special file"


def not_regular(path: str | Path, mode: int) -> FileError:
    """The :class:`FileError` of a path that is no regular file (``is a folder, not a
    file`` for a folder, as the operating system's message says it)."""
    kind = special_kind(mode) or "a special file"
    if kind == "a folder":
        return FileError(located(_name(path), "", "is a folder, not a file"))
    return FileError(located(_name(path), "", f"is {kind}, not a regular file"))


def check_regular(path: str | Path) -> None:
    """Refuse an existing ``path`` that is not a regular file (following links): a file
    about to be written or appended to must not be a FIFO (its writer would wait for a
    reader for ever), a device or a socket. A missing path is fine (it will be created),
    and so is one that cannot be looked at (the write that follows says why it fails)."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return
    if not stat.S_ISREG(mode):
        raise not_regular(path, mode)


#: Flags of every open for reading: never wait (a FIFO without a writer), never take a
#: terminal as the controlling one, never leak into child processes.
_READ_FLAGS = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)


def _open_nonblocking(path: str, flags: int) -> int:
    """``open()``'s opener for input files: :data:`_READ_FLAGS`, whatever mode was asked."""
    return os.open(path, _READ_FLAGS | getattr(os, "O_CLOEXEC", 0))


def read_bytes(path: str | Path, limit: int | None = None, what: str = "file") -> bytes:
    """The bytes of ``path``, the one way input files are read (module doc):
    :class:`FileError` when missing, unreadable, not a regular file or over ``limit``."""
    path = check_path(path)
    try:
        with open(path, "rb", opener=_open_nonblocking) as fh:
            st = os.fstat(fh.fileno())
            if not stat.S_ISREG(st.st_mode):
                raise not_regular(path, st.st_mode)
            if limit is not None and st.st_size > limit:
                raise FileError(
                    located(
                        _name(path),
                        "",
                        f"too large: {human_size(st.st_size)} (the limit for {what}s is "
                        f"{human_size(limit)})",
                    )
                )
            data = fh.read() if limit is None else fh.read(limit + 1)
    except FileNotFoundError:
        raise FileError(located(_name(path), "", "file not found")) from None
    except IsADirectoryError:
        raise FileError(located(_name(path), "", "is a folder, not a file")) from None
    except OSError as exc:  # e.g. a socket cannot be opened (ENXIO): say what it is
        with contextlib.suppress(OSError):
            mode = os.stat(path).st_mode
            if not stat.S_ISREG(mode):
                raise not_regular(path, mode) from None
        raise file_error(path, "read", exc) from None
    if limit is not None and len(data) > limit:  # grew while read
        raise FileError(
            located(_name(path), "", f"too large (the limit for {what}s is {human_size(limit)})")
        )
    return data


def read_text(path: str | Path, limit: int | None = None, what: str = "text file") -> str:
    """UTF-8 text of ``path``; :class:`FileError` as :func:`read_bytes`, or not UTF-8."""
    data = read_bytes(path, limit, what)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise FileError(
            located(_name(path), "", f"not a UTF-8 {what} (byte {exc.start} is not text)")
        ) from None


def human_size(n: int) -> str:
    """``4 MiB``-style size.

    >>> human_size(4 * 1024 * 1024), human_size(1536), human_size(12)
    ('4 MiB', '1.5 KiB', '12 B')
    """
    value = float(n)
    for unit in ("B", "KiB", "MiB", "GiB"):
        if value < 1024 or unit == "GiB":
            return f"{value:.3g} {unit}" if unit != "B" else f"{int(value)} B"
        value /= 1024
    raise AssertionError("unreachable")
