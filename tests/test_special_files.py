"""Special files where a regular one is expected: a FIFO, a device, a socket or a folder
given for any file of any command is refused with one line before it is opened for reading
(opening a FIFO for reading waits for a writer for ever), and a FIFO given as a file to
write (a log, a policy, a table's backup) is refused too, never opened for writing.

Each case runs under an alarm: a hang fails the test instead of stopping the suite.
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
from inputs import expect_error, snapshot

from koolio_pymunk import robot_runtime as rt
from koolio_pymunk.apps import cli
from koolio_pymunk.store import files
from koolio_pymunk.store.errors import FileError

ROOT = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="POSIX special files")


@contextmanager
def no_hang(seconds: int = 20) -> Iterator[None]:
    """Fail (instead of waiting for ever) when the block takes more than ``seconds``."""

    def ring(signum, frame):
        raise TimeoutError(f"still running after {seconds} s: it hangs")

    old = signal.signal(signal.SIGALRM, ring)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


@pytest.fixture
def work(tiny_run, tmp_path, monkeypatch) -> Path:
    """A folder with a table, its log, a policy, an arena, a configuration, and ``fifo``,
    ``f.csv``, ``f.yaml``, ``f.qtable``, ``f.json``, ``f.txt`` that are FIFOs."""
    shutil.copy(tiny_run / "q.qtable", tmp_path / "q.qtable")
    shutil.copy(tiny_run / "log.csv", tmp_path / "q.csv")
    shutil.copy(tiny_run / "tiny.yaml", tmp_path / "tiny.yaml")
    shutil.copy(ROOT / "arenas" / "room.yaml", tmp_path / "room.yaml")
    monkeypatch.chdir(tmp_path)
    assert cli.main(["export", "--qtable", "q.qtable", "--out", "p.json"]) == 0
    for name in ("fifo", "f.csv", "f.yaml", "f.qtable", "f.json", "f.txt"):
        os.mkfifo(tmp_path / name)
    return tmp_path


TRAIN = ["train", "--arena", "room", "--config", "tiny.yaml", "--episodes", "1", "--quiet"]

#: Every file a command reads, given as a FIFO: (argv, the file named in the line).
READS = [
    (["check-arena", "f.yaml"], "f.yaml"),
    ([*TRAIN[:2], "f.yaml", "--qtable", "n.qtable", "--log", "n.csv"], "f.yaml"),
    (["train", "--arena", "room", "--config", "f.yaml", "--qtable", "n.qtable"], "f.yaml"),
    ([*TRAIN, "--world", "f.yaml", "--qtable", "n.qtable", "--log", "n.csv"], "f.yaml"),
    ([*TRAIN, "--qtable", "f.qtable", "--log", "n.csv"], "f.qtable"),
    ([*TRAIN, "--qtable", "q.qtable", "--log", "f.csv"], "f.csv"),
    ([*TRAIN, "--qtable", "n.qtable", "--log", "n.csv", "--init-qtable", "f.json"], "f.json"),
    ([*TRAIN, "--qtable", "n.qtable", "--log", "n.csv", "--init-qtable", "f.qtable"], "f.qtable"),
    (["eval", "--arena", "room", "--config", "tiny.yaml", "--qtable", "f.qtable"], "f.qtable"),
    (["eval", "--arena", "room", "--qtable", "q.qtable", "--config", "f.yaml"], "f.yaml"),
    (["info", "--config", "f.yaml"], "f.yaml"),
    (["info", "--qtable", "f.qtable"], "f.qtable"),
    (["plot", "--log", "f.csv", "--out", "c.png"], "f.csv"),
    (["plot", "f.csv", "--out", "c.png"], "f.csv"),
    (["export", "--qtable", "f.qtable", "--out", "o.json"], "f.qtable"),
    (["export", "--qtable", "f.json", "--out", "o.json"], "f.json"),
    (["export", "--qtable", "q.qtable", "--out", "o.json", "--config", "f.yaml"], "f.yaml"),
    (["export", "--qtable", "q.qtable", "--out", "o.json", "--world", "f.yaml"], "f.yaml"),
    (["sweep", "f.yaml"], "f.yaml"),
    (["view", "--steps", "2", "--arena", "f.yaml"], "f.yaml"),
    (["view", "--steps", "2", "--arena", "room", "--qtable", "v.qtable", "--log", "f.csv"],
     "f.csv"),
    (["view", "--steps", "2", "--arena", "room", "--qtable", "f.qtable", "--greedy"], "f.qtable"),
    (["edit", "f.yaml", "--screenshot", "e.png"], "f.yaml"),
    (["edit", "--script", "f.txt"], "f.txt"),
    (["edit", "--new", "n.yaml", "--doors", "f.yaml", "--screenshot", "e.png"], "f.yaml"),
    (["transfer", "--arena", "room", "--qtable", "f.qtable", "--out", "tr"], "f.qtable"),
    (["transfer", "--arena", "room", "--config", "f.yaml", "--out", "tr"], "f.yaml"),
    (["transfer", "--arena", "room", "--world", "f.yaml", "--out", "tr"], "f.yaml"),
]  # fmt: skip


@pytest.mark.parametrize(("argv", "name"), READS, ids=[" ".join(a) for a, _ in READS])
def test_a_fifo_for_any_file_is_refused_at_once(work, capsys, monkeypatch, argv, name):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    words = f"{name}: is a FIFO (named pipe), not a regular file"
    if argv[0] == "edit":  # in a process of its own: the editor quits pygame when it ends
        before = snapshot(work)
        p = subprocess.run(
            [sys.executable, "-m", "koolio_pymunk", *argv],
            cwd=work,
            capture_output=True,
            text=True,
            timeout=120,
            env={**os.environ, "PYTHONPATH": str(ROOT)},
        )
        assert p.returncode == 2 and p.stderr == f"koolio-pm: error: {words}\n", p.stderr
        assert snapshot(work) == before
        return
    with no_hang():
        expect_error(capsys, work, argv, words)


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["export", "--qtable", "q.qtable", "--out", "f.json"], "f.json: cannot write: is a FIFO"),
        (["export", "--qtable", "q.qtable", "--out", "f.qtable"], "f.qtable: cannot write"),
        (["plot", "--log", "q.csv", "--out", "fifo.png"], "fifo.png: cannot write: is a FIFO"),
        ([*TRAIN, "--qtable", "fifo.qtable", "--log", "n.csv"], "fifo.qtable.bak: is a FIFO"),
    ],
)
def test_a_fifo_is_never_written_through(work, capsys, argv, words):
    os.mkfifo(work / "fifo.png")
    os.mkfifo(work / "fifo.qtable.bak")
    with no_hang():
        expect_error(capsys, work, argv, words)
    assert (work / "fifo.png").is_fifo() and (work / "f.json").is_fifo()


def test_devices_sockets_and_folders_are_refused(work, capsys):
    with socket.socket(socket.AF_UNIX) as sock:
        sock.bind("s.yaml")  # relative: a socket's path is short
        with no_hang():
            expect_error(capsys, work, ["check-arena", "s.yaml"], "s.yaml: is a socket")
    with no_hang():
        expect_error(capsys, work, ["info", "--config", "/dev/zero"], "is a character device")
        expect_error(capsys, work, ["plot", "--log", "/dev/null"], "is a character device")
        expect_error(capsys, work, [*TRAIN, "--log", "/dev/null"], "/dev/null: is a character")
    os.mkdir(work / "d.yaml")
    expect_error(capsys, work, ["check-arena", "d.yaml"], "d.yaml: is a folder, not a file")


def test_read_bytes_refuses_before_reading(work):
    with no_hang(), pytest.raises(FileError, match=r"^fifo: is a FIFO \(named pipe\), not a"):
        files.read_bytes("fifo")
    with no_hang(), pytest.raises(FileError, match="is a character device"):
        files.read_text("/dev/zero", 100)
    files.check_regular("missing")  # a file to be created
    with pytest.raises(FileError, match=r"f\.csv: is a FIFO"):
        files.check_regular("f.csv")


def test_the_robot_runtime_refuses_fifos(work, capsys):
    with no_hang():
        with pytest.raises(rt.PolicyError, match=r"^f\.json: is a FIFO \(named pipe\)"):
            rt.Policy.load("f.json")
        with pytest.raises(rt.PolicyError, match=r"^f\.csv: is a FIFO"):
            rt.EpisodeLog("f.csv")
        policy = rt.Policy.load("p.json")
        before = snapshot(work)
        with pytest.raises(rt.PolicyError, match=r"^fifo: is a FIFO"):
            policy.save("fifo")
        assert snapshot(work) == before
        expect_error(
            capsys, work, ["f.json"], "f.json: is a FIFO", run=rt.main, prefix="robot_runtime: "
        )


def test_a_fifo_log_does_not_hang_a_real_process(work):
    """End to end, as the issue reported it: ``mkfifo x.csv; koolio-pm train --log x.csv``."""
    os.mkfifo(work / "x.csv")
    argv = [sys.executable, "-m", "koolio_pymunk", *TRAIN, "--qtable", "n.qtable"]
    proc = subprocess.run(
        [*argv, "--log", "x.csv"], capture_output=True, text=True, timeout=120, cwd=work
    )
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr == "koolio-pm: error: x.csv: is a FIFO (named pipe), not a regular file\n"
    assert not (work / "n.qtable").exists()
