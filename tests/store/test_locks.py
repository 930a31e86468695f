"""Lock files: never followed through a link, never made over something that is not a
plain lock file, and a folder that cannot be searched ends in one line (issue #21)."""

from __future__ import annotations

import builtins
import errno
import gc
import io
import os
import shutil
import socket
import sys
from pathlib import Path

import pytest
from inputs import expect_error, snapshot

from koolio_pymunk.store.errors import FileError
from koolio_pymunk.store.locks import FileLock

TRAIN = ["train", "--arena", "room", "--config", "tiny.yaml", "--episodes", "3", "--quiet"]
FILES = ["--qtable", "q.qtable", "--log", "q.csv"]


@pytest.fixture
def work(tiny_run, tmp_path, monkeypatch) -> Path:
    shutil.copy(tiny_run / "q.qtable", tmp_path / "q.qtable")
    shutil.copy(tiny_run / "log.csv", tmp_path / "q.csv")
    shutil.copy(tiny_run / "tiny.yaml", tmp_path / "tiny.yaml")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _symlink_to_table(work: Path) -> None:
    (work / "q.qtable.lock").symlink_to("q.qtable")


def _hard_link_of_table(work: Path) -> None:
    os.link(work / "q.qtable", work / "q.qtable.lock")


def _other_data(work: Path) -> None:
    shutil.copy(work / "q.csv", work / "q.qtable.lock")


def _fifo(work: Path) -> None:
    os.mkfifo(work / "q.qtable.lock")


def _dangling_link(work: Path) -> None:
    (work / "q.qtable.lock").symlink_to("elsewhere.txt")


def _folder(work: Path) -> None:
    (work / "q.qtable.lock").mkdir()


def _socket(work: Path) -> None:
    with socket.socket(socket.AF_UNIX) as sock:
        sock.bind("q.qtable.lock")  # relative: the current folder is ``work``


@pytest.mark.parametrize(
    ("make", "words"),
    [
        (_symlink_to_table, "q.qtable: its lock file q.qtable.lock is a symbolic link"),
        (_hard_link_of_table, "its lock file q.qtable.lock has 2 names (a hard link"),
        (_other_data, "its lock file q.qtable.lock holds other data than a lock note"),
        (_fifo, "its lock file q.qtable.lock is a FIFO (named pipe), not a lock file"),
        (_dangling_link, "its lock file q.qtable.lock is a symbolic link"),
        (_folder, "its lock file q.qtable.lock is a folder, not a lock file"),
        (_socket, "its lock file q.qtable.lock is a socket, not a lock file"),
    ],
)
def test_only_a_plain_lock_file_is_used(work, capsys, make, words):
    make(work)
    table = (work / "q.qtable").read_bytes()
    expect_error(capsys, work, [*TRAIN, *FILES], words)
    assert (work / "q.qtable").read_bytes() == table  # never truncated through the link
    assert not (work / "elsewhere.txt").exists()


def test_a_lock_file_of_an_earlier_run_is_taken(work, capsys):
    from koolio_pymunk.apps import cli

    (work / "q.qtable.lock").write_text("#process 1 (koolio-pm train)\n")
    assert cli.main([*TRAIN, *FILES]) == 0
    assert (work / "q.qtable.lock").read_text().startswith(f"#process {os.getpid()} ")


def test_a_refused_lock_file_is_not_held(tmp_path):
    lock = tmp_path / "t.lock"
    lock.write_bytes(b"not a note")
    with pytest.raises(FileError, match="holds other data"):
        FileLock(tmp_path / "t", path=lock).acquire()
    lock.unlink()
    with FileLock(tmp_path / "t", path=lock):  # the refused one left nothing locked
        pass


def _deny_folder(monkeypatch, folder: Path) -> None:
    """As a folder without search permission is for any user but root: every system call
    on a path inside it fails with EACCES (the tests may run as root)."""
    inside = str(folder.resolve()) + os.sep

    def deny(fn):
        def call(path, *args, **kwargs):
            if isinstance(path, (str, os.PathLike)) and os.path.abspath(path).startswith(inside):
                raise PermissionError(errno.EACCES, "Permission denied", os.fspath(path))
            return fn(path, *args, **kwargs)

        return call

    for name in ("stat", "lstat", "open", "mkdir", "listdir", "scandir", "unlink", "replace"):
        monkeypatch.setattr(os, name, deny(getattr(os, name)))
    monkeypatch.setattr(builtins, "open", deny(builtins.open))
    monkeypatch.setattr(io, "open", builtins.open)


@pytest.mark.parametrize(
    ("files", "words"),
    [
        (["--qtable", "nd/q.qtable", "--log", "q.csv"], "nd/q.qtable: permission denied"),
        (["--qtable", "nd/q.qtable", "--log", "nd/q.csv"], "nd/q.csv: permission denied"),
        (["--qtable", "q.qtable", "--log", "nd/q.csv"], "nd/q.csv: permission denied"),
    ],
)  # fmt: skip
def test_a_folder_without_search_permission(work, capsys, monkeypatch, files, words):
    unraisable = []
    monkeypatch.setattr(sys, "unraisablehook", unraisable.append)
    (work / "nd").mkdir()
    before = snapshot(work)
    _deny_folder(monkeypatch, work / "nd")
    expect_error(capsys, work, [*TRAIN, *files], words)
    gc.collect()
    monkeypatch.undo()
    assert unraisable == []  # no "Exception ignored in FileLock.__del__"
    assert snapshot(work) == before


def test_dangling_links_make_no_folders_and_one_file_is_not_two(work, capsys):
    """Found by the fuzzer: a table and a log linked to one missing name were taken for
    two files (the log's lock then clashed with the table's after a warning), and the
    lock of a dangling link was made in new folders where the link pointed."""
    (work / "t.qtable").symlink_to("nowhere/at/all")
    (work / "t.csv").symlink_to("nowhere/at/all")
    argv = [*TRAIN, "--qtable", "t.qtable", "--log", "t.csv"]
    expect_error(capsys, work, argv, "t.csv: is the Q-table (t.qtable)")
    assert not (work / "nowhere").exists()
    from koolio_pymunk.store.locks import lock_path

    assert lock_path(work / "t.qtable") == work / "t.qtable.lock"


def test_a_run_leaves_one_lock_file(work, capsys):
    """The log, the checks' file and the best table share the table's lock file."""
    from koolio_pymunk.apps import cli

    argv = [*TRAIN, "--episodes", "4", "--eval-every", "2", "--eval-episodes", "1"]
    assert cli.main([*argv, "--qtable", "r.qtable", "--log", "r.csv"]) == 0
    assert (work / "r.evals.csv").exists() and (work / "r.best.qtable").exists()
    assert sorted(p.name for p in work.glob("r.*lock*")) == ["r.qtable.lock"]


@pytest.fixture
def other_run(work):
    """Another process holding ``q.qtable``'s lock (a run of that table) until the end."""
    import subprocess

    code = (
        "import sys, time\n"
        "from koolio_pymunk.store.locks import FileLock\n"
        "held = FileLock('q.qtable', 'koolio-pm train').acquire()\n"
        "print('held', flush=True)\n"
        "sys.stdin.read()\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", code], cwd=work, stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True)  # fmt: skip
    assert proc.stdout.readline().strip() == "held"
    yield proc.pid
    proc.stdin.close()
    proc.wait(timeout=30)


@pytest.mark.parametrize(
    "files",
    [
        ["--qtable", "y.qtable", "--log", "q.csv"],  # another table, this run's log
        ["--qtable", "q.best.qtable", "--log", "y.csv"],  # this run's best table
    ],
)
def test_a_run_s_files_are_refused_to_another_run(work, capsys, other_run, files):
    before = snapshot(work)
    expect_error(capsys, work, [*TRAIN, *files], f"in use by process {other_run}")
    after = snapshot(work)
    made = set(after) - set(before)
    assert {k: after[k] for k in before} == before  # nothing of the other run touched
    assert made <= {"y.qtable.lock"}  # at most the refused run's own lock file
