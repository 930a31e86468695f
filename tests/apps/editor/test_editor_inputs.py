"""The editor's input files: every one (script, arena, door table, configuration, the
file a save replaces) is read through ``koolio_pymunk.store.files``, the one place that
refuses what is not a regular file (a FIFO would block ``open`` for ever); and the
example script the docs show runs as they say."""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

os.environ["SDL_VIDEODRIVER"] = "dummy"
os.environ["SDL_AUDIODRIVER"] = "dummy"

import pygame

from koolio_pymunk.apps.editor.app import EditorApp
from koolio_pymunk.apps.editor.launch import make_model
from koolio_pymunk.apps.editor.model import EditorModel
from koolio_pymunk.apps.editor.script import ScriptError, run_script
from koolio_pymunk.store import files
from koolio_pymunk.store.config import load_config
from koolio_pymunk.store.errors import KoolioError
from koolio_pymunk.task import drawing

REPO = Path(__file__).resolve().parents[3]
ROOM = REPO / "arenas" / "room.yaml"
DOORS = REPO / "arenas" / "hallway_doors.yaml"
EXAMPLE = REPO / "examples" / "editor-script.txt"
PROFILE = REPO / "koolio_pymunk" / "profiles" / "paper.yaml"

# -- every open of a watched file for reading, and whether store/files.py made it ----------
_WATCHED: set[str] = set()
_OPENS: list[tuple[str, bool]] = []


def _reading(mode: object, flags: int) -> bool:
    if isinstance(mode, str):
        return "r" in mode and "+" not in mode
    return flags & os.O_ACCMODE == os.O_RDONLY


def _audit(event: str, args: tuple) -> None:
    if event != "open" or not _WATCHED:
        return
    path, mode, flags = args
    if not isinstance(path, (str, bytes, os.PathLike)) or not _reading(mode, flags or 0):
        return
    name = os.path.abspath(os.fsdecode(path))
    if name not in _WATCHED:
        return
    frame, through_store = sys._getframe(1), False
    while frame is not None:
        if frame.f_code.co_filename == files.__file__:
            through_store = True
            break
        frame = frame.f_back
    _OPENS.append((name, through_store))


sys.addaudithook(_audit)  # inert while nothing is watched


@contextmanager
def watching(*paths: Path) -> Iterator[list[tuple[str, bool]]]:
    _WATCHED.update(os.path.abspath(p) for p in paths)
    _OPENS.clear()
    try:
        yield _OPENS
    finally:
        _WATCHED.clear()


@contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    def expired(*_: object) -> None:
        raise TimeoutError(f"still running after {seconds} s (blocked on a FIFO?)")

    old = signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def edit_args(**kw: object) -> argparse.Namespace:
    base = {"file": None, "new": False, "doors": None, "robot": "koolio", "grid": 24.0}
    return argparse.Namespace(**{**base, **kw})


def test_every_input_is_read_through_store_files(tmp_path: Path) -> None:
    arena, table, config = tmp_path / "a.yaml", tmp_path / "doors.yaml", tmp_path / "c.yaml"
    shutil.copy(ROOM, arena)
    shutil.copy(DOORS, table)
    shutil.copy(PROFILE, config)
    script = tmp_path / "s.txt"
    script.write_text(f"import_doors {table}\nopen {arena}\nstart 5000 5000\nsave! {arena}\n")
    watched = (arena, table, config, script)
    with watching(*watched) as opens:
        make_model(edit_args(file=str(arena)))
        make_model(edit_args(doors=str(table)))
        load_config(str(config))
        app = EditorApp(EditorModel.blank(), (1000, 600))
        run_script(app, script)  # the save! reads the valid file it replaces (.bak)
    assert (tmp_path / "a.yaml.bak").read_bytes() == ROOM.read_bytes()
    read = {name for name, _ in opens}
    assert read == {os.path.abspath(p) for p in watched}, read
    assert all(through for _, through in opens), [name for name, ok in opens if not ok]


def test_the_audit_sees_a_read_that_bypasses_store_files(tmp_path: Path) -> None:
    """The check above can fail."""
    path = tmp_path / "x.yaml"
    path.write_text("x")
    with watching(path) as opens:
        path.read_text()
        files.read_text(path)
    name = os.path.abspath(path)
    assert opens[0] == (name, False)  # the read that bypasses store.files is seen
    assert opens[1:] and all(o == (name, True) for o in opens[1:])  # and store.files' own


def test_a_fifo_where_an_input_is_expected_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    app = EditorApp(EditorModel.blank(), (1000, 600))
    with time_limit(20):
        for args in (edit_args(file=str(fifo)), edit_args(doors=str(fifo))):
            with pytest.raises(KoolioError, match="not a regular file"):
                make_model(args)
        with pytest.raises(ScriptError, match=r"fifo\.yaml: is a FIFO .*not a regular file"):
            run_script(app, fifo)
        for line in (f"open {fifo}", f"import_doors {fifo}"):
            script = tmp_path / "s.txt"
            script.write_text(line + "\n")
            with pytest.raises(ScriptError, match=r"s\.txt:1: .*fifo\.yaml: is a FIFO"):
                run_script(app, script)


def test_koolio_pm_edit_with_a_fifo_script_ends_in_one_line(tmp_path: Path) -> None:
    os.mkfifo(tmp_path / "s.txt")
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    result = subprocess.run(
        [sys.executable, "-m", "koolio_pymunk", "edit", "--script", "s.txt"],
        capture_output=True, text=True, env=env, cwd=tmp_path, timeout=120, check=False,
    )  # fmt: skip
    assert result.returncode == 2
    assert result.stderr == (
        "koolio-pm: error: s.txt: is a FIFO (named pipe), not a regular file\n"
    )


# -- the example script -------------------------------------------------------------------------
def test_the_example_script_runs_as_the_docs_say(tmp_path: Path) -> None:
    """``SDL_VIDEODRIVER=dummy koolio-pm edit --script examples/editor-script.txt
    --screenshot out.png`` (docs/editor.md; the README's line too) from a checkout: a
    picture of the test drive, and nothing else written."""
    command = "koolio-pm edit --script examples/editor-script.txt --screenshot out.png"
    doc = (REPO / "docs" / "editor.md").read_text()
    assert f"SDL_VIDEODRIVER=dummy {command}" in doc
    assert command in EXAMPLE.read_text()
    commands = [line for line in EXAMPLE.read_text().splitlines() if not line.startswith("#")]
    assert "```text\n" + "\n".join(commands) + "\n```" in doc  # the docs show it whole
    (tmp_path / "examples").mkdir()
    shutil.copy(EXAMPLE, tmp_path / "examples")
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    result = subprocess.run(
        [sys.executable, "-m", "koolio_pymunk", *command.split()[1:]],
        capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300, check=False,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["examples", "out.png"]
    image = pygame.image.load(str(tmp_path / "out.png"))
    assert image.get_size() == (1280, 720)
    robot = [  # the test drive's robot, red, somewhere on the canvas
        (x, y) for x in range(0, 940, 4) for y in range(0, 628, 4)
        if image.get_at((x, y))[:3] == drawing.ROBOT_NORMAL
    ]  # fmt: skip
    assert robot, "no robot in the picture"
