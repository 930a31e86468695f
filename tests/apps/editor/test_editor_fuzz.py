"""Fuzz of the editor's inputs: script commands and ``koolio-pm edit`` flags with hostile
values (1e300, NaN, inf, 1e-300, 40-digit integers, non-ASCII digits, names with control
characters, paths past the end ...).

Each script case opens a copy of ``arenas/room.yaml``, runs a few random commands, then
``save!`` over that copy. Within a time limit it must either run to the end, and then
the file it saved opens again (the editor never writes a file the simulator's parser
refuses), or stop at a line with one line ``<script>:LINE: ...`` (a
:class:`~koolio_pymunk.store.errors.KoolioError`), and then the arena file is byte for
byte what it was. Any other exception, or a case running over its time, fails the test
with the case's label and lines.

The flags are fuzzed on their readers (``window_size``, ``grid_inches``) in process, and a
fixed set of hostile command lines runs through ``koolio-pm edit`` itself in a separate
interpreter: exit status 2, one line ``koolio-pm: error: --flag: ...``, the arena file and
the folder unchanged (the script given would have overwritten the arena).

``KOOLIO_FUZZ_N`` (default 150, as ``tests/test_fuzz.py``) sets the number of script
cases and of flag values; ``KOOLIO_FUZZ_SEED`` (default empty) is added to every seed. A
failure names its label; the same two settings replay it.
"""

from __future__ import annotations

import json
import math
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

os.environ["SDL_VIDEODRIVER"] = "dummy"
os.environ["SDL_AUDIODRIVER"] = "dummy"

from koolio_pymunk.apps.editor import limits
from koolio_pymunk.apps.editor.app import EditorApp
from koolio_pymunk.apps.editor.launch import grid_inches, window_size
from koolio_pymunk.apps.editor.model import EditorModel
from koolio_pymunk.apps.editor.script import COMMANDS, run_text
from koolio_pymunk.store.errors import KoolioError
from koolio_pymunk.world.arena import load_arena

REPO = Path(__file__).resolve().parents[3]
ROOM = REPO / "arenas" / "room.yaml"
N = int(os.environ.get("KOOLIO_FUZZ_N", "150"))
SEED = os.environ.get("KOOLIO_FUZZ_SEED", "")
CASE_SECONDS = 30.0
"""Time a script case may take (the slowest normal case takes well under a second)."""

NUMBERS = [
    "0", "-1", "1", "24", "0.01", "0.05", "20", "100", "101", "360", "361", "10000",
    "10001", "1000000", "-1000000", "1000000.01", "-2000001", "1e6", "1e7", "1e300",
    "-1e300", "1e-300", "1e-12", "1e400", "nan", "inf", "-inf", "NaN", "1_000", "0x10",
    "9" * 40, "-" + "9" * 25, "\u0661\u0662", "\u00b2", "", "-", "1e", ".", "1.2.3",
]  # fmt: skip
INTEGERS = ["0", "1", "2", "3", "-1", "7", "1000000000", "9" * 40, "1e9", "x", "\u0663", ""]
PATHS = [
    "walls", "walls[0]", "walls[7]", "walls[99]", "walls[-1]", "walls[" + "9" * 30 + "]",
    "obstacles[0]", "obstacles[0][1]", "goals[0]", "goals[0].at", "end_of_world[0]",
    "end_of_world[0].zone", "end_of_world[0].zone[0]", "start", "doors[0].plate",
    "nonsense", "walls[0", "[0]", "",
]  # fmt: skip
NAMES = ["201", "202", "Lab B", "x" * 100, "x" * 101, "a\x01b", "", " ", "\u00e9t\u00e9", "lab"]
KEYS = [
    "v", "w", "i", "o", "g", "e", "z", "s", "delete", "backspace", "return", "escape",
    "x", "l", "f", "+", "-", "up", "down", "left", "right", "shift+right", "h", "[", "]",
    "d", "tab", "p", "n", "r", "a", "f5", "space", "ctrl+z", "ctrl+y", "ctrl+shift+z",
]  # fmt: skip
"""Keys a case presses (not those that write files or quit: Ctrl+S, F12, Ctrl+Q)."""
ACTIONS = ["forward", "reverse", "left", "right", "stop", "reset", "off", "jump"]


def _num(r: random.Random) -> str:
    if r.random() < 0.35:
        return f"{r.uniform(-300, 300):.6g}"
    return r.choice(NUMBERS)


def _nums(r: random.Random, n: int) -> list[str]:
    return [_num(r) for _ in range(n)]


def _q(word: str) -> str:
    """A word quoted for the script's shell-like splitting."""
    return "'" + word.replace("'", "") + "'"


GENERATORS = {
    "new": lambda r: [_q(r.choice(NAMES))],
    "name": lambda r: [_q(r.choice(NAMES))],
    "rotate_deg": lambda r: [_num(r)],
    "add_wall_vertex": lambda r: _nums(r, 2),
    "add_vertex": lambda r: [r.choice(PATHS), *_nums(r, 2)],
    "insert_vertex": lambda r: [r.choice(PATHS), r.choice(INTEGERS), *_nums(r, 2)],
    "move_vertex": lambda r: [r.choice(PATHS), *_nums(r, 2)],
    "move_by": lambda r: [r.choice(PATHS), *_nums(r, 2)],
    "delete": lambda r: [r.choice(PATHS)],
    "add_obstacle": lambda r: _nums(r, 2 * r.randint(1, 5)),
    "add_goal": lambda r: [_q(r.choice(NAMES)), *_nums(r, 2)],
    "move_goal": lambda r: [_q(r.choice(NAMES)), *_nums(r, 2)],
    "rename_goal": lambda r: [_q(r.choice(NAMES)), _q(r.choice(NAMES))],
    "delete_goal": lambda r: [_q(r.choice(NAMES))],
    "active_goal": lambda r: [_q(r.choice(NAMES))],
    "add_marker": lambda r: _nums(r, 2 * r.randint(1, 4)),
    "set_zone": lambda r: [r.choice(INTEGERS), *(["default"] if r.random() < 0.2 else _nums(r, 6))],
    "start": lambda r: _nums(r, r.choice([2, 3])),
    "heading": lambda r: [r.choice(["random", _num(r)])],
    "undo": lambda r: [r.choice(INTEGERS)] if r.random() < 0.8 else [],
    "redo": lambda r: [r.choice(INTEGERS)] if r.random() < 0.8 else [],
    "snap": lambda r: [r.choice(["off", _num(r)])],
    "grid": lambda r: [_num(r)],
    "tool": lambda r: [r.choice(["select", "wall", "zone", "start", "lasso"])],
    "select": lambda r: [r.choice([*PATHS, "none"])],
    "view": lambda r: ["fit"] if r.random() < 0.2 else _nums(r, 3),
    "drive": lambda r: [r.choice(ACTIONS), *([r.choice(INTEGERS)] if r.random() < 0.7 else [])],
    "expect_valid": lambda r: [],
    "expect_error": lambda r: [_q(r.choice(["walls", "goal", "x"]))],
    "key": lambda r: r.sample(KEYS, r.randint(1, 4)),
    "type": lambda r: [_q(r.choice([*NUMBERS, *NAMES, "x" * 1001, "1e300 5"]))],
    "click": lambda r: [*_nums(r, 2), *r.sample(["shift", "right", "middle"], r.randint(0, 1))],
    "click_screen": lambda r: [r.choice([*INTEGERS, "500", "999", "1000"]) for _ in range(2)],
    "drag": lambda r: _nums(r, 4) + (["right"] if r.random() < 0.3 else []),
    "move": lambda r: _nums(r, 2),
    "wheel": lambda r: [r.choice([*INTEGERS, "100", "-100", "101", "100000"]), *_nums(r, 2)],
}
"""Arguments for every script command except those that name files (open, import_doors,
save, save!, screenshot: the files are another family, tested with store.files)."""
FILE_COMMANDS = {"open", "import_doors", "save", "save!", "screenshot"}


def test_every_script_command_is_fuzzed() -> None:
    assert set(COMMANDS) == set(GENERATORS) | FILE_COMMANDS


def script_case(r: random.Random, room: Path) -> str:
    """``open`` the room, a few hostile or ordinary commands, ``save!`` over the room."""
    lines = [f"open {room}"]
    if r.random() < 0.5:  # start from a sensible view most of the time
        lines.append("view 120 96 2")
    for _ in range(r.randint(1, 5)):
        name = r.choice(sorted(GENERATORS))
        lines.append(" ".join([name, *GENERATORS[name](r)]))
    lines.append("save!")
    return "\n".join(lines) + "\n"


class CaseTimeout(Exception):
    pass


def _expired(*_: object) -> None:
    raise CaseTimeout


def _reset(app: EditorApp) -> None:
    """Between cases: no question open, no test drive, the select tool."""
    app.cancel_prompt()
    app.stop_drive()
    app.set_tool("select")


def run_case(app: EditorApp, text: str, room: Path, original: bytes, label: str) -> str:
    """Run one case; ``ran`` or ``refused``, or fail the test."""
    old = signal.signal(signal.SIGALRM, _expired)
    signal.setitimer(signal.ITIMER_REAL, CASE_SECONDS)
    start = time.perf_counter()
    try:
        run_text(app, text)
        outcome = "ran"
    except KoolioError as exc:
        message = str(exc)
        assert "\n" not in message and message.startswith("<script>:"), (label, text, message)
        assert room.read_bytes() == original, (label, text, "the arena file changed")
        outcome = "refused"
    except CaseTimeout:
        pytest.fail(f"{label}: still running after {CASE_SECONDS} s:\n{text}")
    except Exception as exc:
        pytest.fail(f"{label}: {type(exc).__name__}: {exc}\n{text}")
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    assert time.perf_counter() - start < CASE_SECONDS
    if outcome == "ran":
        reopened = EditorModel.from_file(room)  # what was saved reads back
        if reopened.problem() is None:
            load_arena(room)  # and a valid one loads in the simulator
    app.render()
    return outcome


def test_script_commands_with_hostile_values(tmp_path: Path) -> None:
    room = tmp_path / "room.yaml"
    outcomes = {"ran": 0, "refused": 0}
    app = None
    for i in range(N):
        label = f"script case {i} (KOOLIO_FUZZ_SEED={SEED!r})"
        r = random.Random(f"{SEED}editor-script-{i}")
        shutil.copy(ROOM, room)
        original = room.read_bytes()
        if app is None or i % 25 == 0:
            app = EditorApp(EditorModel.from_file(room), (1000, 600))
        _reset(app)
        outcomes[run_case(app, script_case(r, room), room, original, label)] += 1
    # the premise: both outcomes occur (the fuzz is neither all refusals nor all runs)
    assert outcomes["ran"] >= N // 20 and outcomes["refused"] >= N // 4, outcomes


def _flag_value(r: random.Random) -> str:
    if r.random() < 0.3:
        return f"{r.uniform(-2000, 2000):.6g}"
    return r.choice(NUMBERS)


def test_grid_and_size_flags_with_hostile_values() -> None:
    for i in range(N):
        r = random.Random(f"{SEED}editor-flags-{i}")
        label = f"flag case {i} (KOOLIO_FUZZ_SEED={SEED!r})"
        text = _flag_value(r)
        try:
            value = float(text)  # as argparse's type=float reads --grid
        except ValueError:
            value = None
        if value is not None:
            try:
                assert grid_inches(value) == value, label
                assert limits.MIN_GRID <= value <= limits.MAX_GRID, label
            except KoolioError as exc:
                assert str(exc).startswith("--grid: ") and "\n" not in str(exc), label
                assert not limits.MIN_GRID <= value <= limits.MAX_GRID or math.isnan(value)
        size = f"{_flag_value(r)}{r.choice(['x', 'X', '*', ''])}{_flag_value(r)}"
        try:
            w, h = window_size(size)
            assert 400 <= w <= 7680 and 300 <= h <= 4320, (label, size)
        except KoolioError as exc:
            assert str(exc).startswith("--size: ") and len(str(exc)) < 120, (label, size)


#: Command lines of ``koolio-pm edit`` with a hostile flag, each refused in one line.
REFUSED_FLAGS = [
    (["--grid", "0.001"], "--grid: 0.001 in is out of range (1 to 1,000 in)"),
    (["--grid", "1e300"], "--grid: 1e+300 in is out of range (1 to 1,000 in)"),
    (["--grid", "nan"], "--grid: nan in is out of range (1 to 1,000 in)"),
    (["--grid=-inf"], "--grid: -inf in is out of range (1 to 1,000 in)"),
    (["--size", "100000x100000"], "--size: at most 7680x4320 (an 8K screen), got '100000x100000'"),
    (["--size", "1e3x720"], "--size: expected WxH like 1280x720, got '1e3x720'"),
    (["--size", "9" * 5000 + "x1"], "--size: expected WxH like 1280x720, got '99999"),
    (["--size", "399x300"], "--size: at least 400x300, got '399x300'"),
]

DRIVER = """\
import contextlib, io, json, os, sys
from koolio_pymunk.apps import cli
out = []
for argv in json.loads(sys.argv[1]):
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        try:
            rc = cli.main(argv)
        except SystemExit as exc:
            rc = exc.code
    out.append([rc, err.getvalue()])
print(json.dumps(out))
"""


def test_hostile_flags_are_refused_in_one_line_and_write_nothing(tmp_path: Path) -> None:
    """Through ``koolio-pm edit`` itself (a separate interpreter: the editor ends pygame
    when it ends). The script given would overwrite the arena if it ran."""
    room = tmp_path / "room.yaml"
    shutil.copy(ROOM, room)
    script = tmp_path / "s.txt"
    script.write_text("move_vertex walls[1] 100 0\nsave!\nscreenshot shot.png\n")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    runs = [
        ["edit", str(room), "--script", str(script), "--screenshot", "end.png", *flags]
        for flags, _ in REFUSED_FLAGS
    ]
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    result = subprocess.run(
        [sys.executable, "-c", DRIVER, json.dumps(runs)],
        capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300, check=False,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    for (rc, err), (flags, message) in zip(json.loads(result.stdout), REFUSED_FLAGS):
        assert rc == 2, (flags, err)
        assert err.count("\n") == 1 and err.startswith(f"koolio-pm: error: {message}"), (flags, err)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
