"""Scripted editor sessions: a text file of editor actions and posted events.

One command per line; ``#`` starts a comment; words are split like a shell's (quote names
with spaces: ``add_goal "Room 5" 100 40``). Coordinates are in inches (world), item paths
are the validator's names (``walls[3]``, ``obstacles[0][2]``, ``end_of_world[1].zone``;
see :mod:`~koolio_pymunk.apps.editor.items`), file names are relative to the current
directory. The first failing line stops the session with ``SCRIPT:LINE: problem``.

**Editor actions** (each edit is one undoable step, exactly as from the keyboard)::

    new [NAME]                      open FILE                   import_doors TABLE
    name NAME                       rotate_deg DEG
    add_wall_vertex X Y             add_vertex POLY X Y         insert_vertex POLY EDGE X Y
    move_vertex PATH X Y            move_by PATH DX DY          delete PATH
    add_obstacle X Y X Y X Y ...
    add_goal NAME X Y               move_goal NAME X Y          rename_goal OLD NEW
    delete_goal NAME                active_goal NAME
    add_marker X Y [X Y ... zone]   set_zone MARKER X Y ... | set_zone MARKER default
    start X Y [HEADING|random]      heading DEG|random
    undo [N]                        redo [N]
    snap INCHES|off                 grid INCHES (tile size; also the snap step)
    tool NAME                       select PATH|none            view fit | view X Y ZOOM
    save [FILE]                     save! [FILE]
    drive forward|reverse|left|right|stop [N]      drive reset      drive off
    screenshot FILE
    expect_valid                    expect_error TEXT

``insert_vertex walls 2 100 44`` puts (100, 44) on edge 2 (from ``walls[2]`` to
``walls[3]``): it becomes ``walls[3]``. ``save`` refuses an invalid arena (the line
fails with the validator's message); ``save!`` writes it anyway, as answering *yes* to
the editor's question does (a valid file it replaces is kept as ``FILE.bak``).

**Posted events** (go through the editor's own event handling, as a user's would)::

    key KEY [KEY ...]               e.g. key w, key ctrl+z, key ctrl+shift+s, key delete
    type TEXT ...                   text typed into the open prompt (words joined by spaces)
    click X Y [shift] [right]       a click at a world point (inches)
    drag X0 Y0 X1 Y1 [right]        press, move, release (right: pan)
    move X Y                        the mouse moves to a world point
    wheel N [X Y]                   N wheel clicks (zoom) over a world point
    click_screen SX SY              a click at a window pixel (the side panel)

``key`` names are pygame's (``pygame.key.key_code``): letters, ``delete``, ``backspace``,
``return``, ``escape``, ``tab``, ``space``, ``up``, ``f5``, ``[`` ...; a key posts no
text, so answer a text prompt with ``type TEXT`` then ``key return``. A posted event
that the editor refuses (a message in red) fails the line.

**Numbers** are plain ASCII decimals (``12``, ``-3.5``, ``1e3``; no ``nan``, ``inf``,
``1_000``), in the editor's ranges (:mod:`~koolio_pymunk.apps.editor.limits`, which says
why): coordinates X Y within +-1,000,000 in (``move_by`` DX DY within +-2,000,000),
``snap`` 0.01 to 1,000 in, ``grid`` 1 to 1,000 in, ``view`` ZOOM 0.05 to 20 pixels per
inch, DEG -360 to 360, ``wheel`` N -100 to 100, ``drive`` N 1 to 10,000, ``undo`` /
``redo`` N 1 and up (more than the history holds stops at its end at once),
``click_screen`` inside the window; names 1 to 100 printable characters, ``type`` at
most 1,000 characters. A script is at most 1 MiB, 10,000 commands and 65,536 characters
a line. A value out of range fails its line (nothing of the line is done).
"""

from __future__ import annotations

import re
import shlex
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path as FilePath

import pygame

from ...store.errors import KoolioError
from ...store.files import read_text
from . import items, limits
from .app import EditorApp
from .drive import ACTIONS


class ScriptError(KoolioError):
    """A script line that cannot be run: ``SCRIPT:LINE: problem``."""


@dataclass(frozen=True)
class Command:
    line: int
    name: str
    args: tuple[str, ...]


def parse_script(text: str, source: str = "<script>") -> list[Command]:
    """The commands of a script (names, line lengths and the number of commands checked;
    arguments are checked when run)."""
    out = []
    for n, raw in enumerate(text.splitlines(), start=1):
        if len(raw) > limits.MAX_SCRIPT_LINE:
            raise ScriptError(
                f"{source}:{n}: a line of {len(raw):,} characters "
                f"(at most {limits.MAX_SCRIPT_LINE:,})"
            )
        try:
            words = shlex.split(raw, comments=True)
        except ValueError as exc:
            raise ScriptError(f"{source}:{n}: {exc}") from None
        if not words:
            continue
        name = words[0]
        if name not in COMMANDS:
            import difflib

            close = difflib.get_close_matches(name, list(COMMANDS), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ScriptError(f"{source}:{n}: unknown command {name!r}{hint}")
        out.append(Command(n, name, tuple(words[1:])))
        if len(out) > limits.MAX_SCRIPT_COMMANDS:
            raise ScriptError(
                f"{source}:{n}: more than {limits.MAX_SCRIPT_COMMANDS:,} commands "
                "(split the session into several scripts)"
            )
    return out


def run_script(app: EditorApp, path: str | FilePath) -> None:
    """Run the script file ``path`` against ``app``."""
    source = str(path)
    try:
        text = read_text(path, limits.MAX_SCRIPT_BYTES, "editor script")
    except KoolioError as exc:
        raise ScriptError(str(exc)) from None
    run_text(app, text, source)


def run_text(app: EditorApp, text: str, source: str = "<script>") -> None:
    """Run the script ``text`` (of the file ``source``) against ``app``."""
    run_commands(app, parse_script(text, source), source)


def run_commands(app: EditorApp, commands: list[Command], source: str = "<script>") -> None:
    runner = _Runner(app)
    app.render()
    for cmd in commands:
        try:
            COMMANDS[cmd.name](runner, cmd.args)
        except ScriptError as exc:
            raise ScriptError(f"{source}:{cmd.line}: {cmd.name}: {exc}") from None
        except KoolioError as exc:
            raise ScriptError(f"{source}:{cmd.line}: {exc}") from None


# =========================================================================================
# Argument helpers
# =========================================================================================
_NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?", re.ASCII)
_WHOLE = re.compile(r"[+-]?[0-9]+", re.ASCII)
_MAX_DIGITS = 30
"""Longest number word read (no range of the editor needs more digits)."""


def _show(word: str) -> str:
    return repr(word) if len(word) <= 40 else repr(word[:37] + "...")


def _num(word: str) -> float:
    """A plain decimal number (no ``nan``, ``inf`` or ``1_000``), finite."""
    if len(word) > _MAX_DIGITS or not _NUMBER.fullmatch(word):
        raise ScriptError(f"not a number: {_show(word)}")
    x = float(word)
    if x in (float("inf"), float("-inf")):
        raise ScriptError(f"not a finite number: {_show(word)}")
    return x


def _int(word: str) -> int:
    """A plain whole number (ASCII digits)."""
    if len(word) > _MAX_DIGITS or not _WHOLE.fullmatch(word):
        raise ScriptError(f"not a whole number: {_show(word)}")
    return int(word)


def _in(x: float, lo: float, hi: float, noun: str = "", unit: str = "") -> float:
    """``x`` when in ``[lo, hi]``, else the line fails: ``[noun ]x is out of range ...``."""
    problem = limits.range_problem(x, lo, hi, unit)
    if problem is not None:
        raise ScriptError(f"{noun} {problem}".strip())
    return x


def _coord(word: str) -> float:
    """A coordinate, inches (within the editor's range)."""
    m = limits.MAX_COORDINATE
    return _in(_num(word), -m, m, "coordinate", " in")


def _delta(word: str) -> float:
    """A displacement, inches."""
    return _in(_num(word), -limits.MAX_MOVE, limits.MAX_MOVE, "move", " in")


def _angle(word: str, noun: str = "") -> float:
    """An angle, degrees (-360 to 360)."""
    return _in(_num(word), -limits.MAX_ANGLE, limits.MAX_ANGLE, noun, " deg")


def _times(args: tuple[str, ...]) -> int:
    """``undo`` / ``redo`` N: 1 and up (more than the history stops at its end)."""
    n = _int(args[0]) if args else 1
    if n < 1:
        raise ScriptError(f"N must be 1 or more, got {n}")
    return n


def _count(args: tuple[str, ...], lo: int, hi: int | None = None) -> None:
    hi = lo if hi is None else hi
    if not lo <= len(args) <= hi:
        want = str(lo) if lo == hi else f"{lo} to {hi}" if hi < 99 else f"at least {lo}"
        raise ScriptError(f"expected {want} arguments, got {len(args)}")


def _points(words: tuple[str, ...]) -> list[tuple[float, float]]:
    if len(words) % 2:
        raise ScriptError("expected pairs of coordinates X Y")
    return [(_coord(words[i]), _coord(words[i + 1])) for i in range(0, len(words), 2)]


def _path(word: str) -> items.Path:
    return items.parse_path(word)


# =========================================================================================
# The runner
# =========================================================================================
class _Runner:
    def __init__(self, app: EditorApp) -> None:
        self.app = app
        self.model = app.model

    def done(self) -> None:
        """Redraw after an action (the screen always shows the current state)."""
        self.app.drop_stale()
        self.app.render()

    # -- posted events -------------------------------------------------------------------
    def post(self, *events: pygame.event.Event) -> None:
        """Post events, let the editor handle them, fail on an error message."""
        self.app.message_is_error = False
        for e in events:
            pygame.event.post(e)
        self.app.pump()
        if self.app.message_is_error:
            raise ScriptError(self.app.message)

    def screen_of(self, x: float, y: float) -> tuple[int, int]:
        pos = self.app.camera.to_screen((x, y))
        if not pygame.Rect(self.app.camera.viewport).collidepoint(pos):
            raise ScriptError(f"({x:g}, {y:g}) is off the canvas (use view fit, or pan)")
        return pos


def _key_event(spec: str) -> tuple[pygame.event.Event, pygame.event.Event]:
    """``ctrl+shift+s`` -> KEYDOWN and KEYUP events."""
    parts = spec.split("+") if spec != "+" else ["+"]
    if parts[-1] == "" and len(parts) > 1:  # "ctrl++"
        parts = [*parts[:-2], "+"]
    mods = {"ctrl": pygame.KMOD_CTRL, "shift": pygame.KMOD_SHIFT, "alt": pygame.KMOD_ALT}
    mod = 0
    for word in parts[:-1]:
        if word.lower() not in mods:
            raise ScriptError(f"unknown modifier {word!r} in {spec!r} (ctrl, shift, alt)")
        mod |= mods[word.lower()]
    name = parts[-1]
    try:
        key = pygame.key.key_code(name)
    except ValueError:
        raise ScriptError(f"unknown key {name!r}") from None
    uni = name if len(name) == 1 else ""
    if mod & pygame.KMOD_SHIFT:
        uni = uni.upper()
    attrs = {"key": key, "mod": mod, "unicode": uni, "scancode": 0}
    return pygame.event.Event(pygame.KEYDOWN, attrs), pygame.event.Event(pygame.KEYUP, attrs)


def _mouse(kind: int, pos: tuple[int, int], button: int = 1, mod: int = 0) -> pygame.event.Event:
    if kind == pygame.MOUSEMOTION:
        return pygame.event.Event(kind, pos=pos, rel=(0, 0), buttons=(0, 0, 0))
    return pygame.event.Event(kind, pos=pos, button=button, mod=mod)


# -- commands: files ------------------------------------------------------------------------
def c_new(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 0, 1)
    r.model.new(*a)
    r.app.after_file("new arena")
    r.done()


def c_open(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1)
    r.app.open_file(a[0])
    r.done()


def c_import_doors(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1)
    r.app.import_doors(a[0])
    r.done()


def c_save(r: _Runner, a: tuple[str, ...], confirm: bool = False) -> None:
    _count(a, 0, 1)
    result = r.model.save(a[0] if a else None, confirm=confirm)
    if result.needs_confirmation:
        raise ScriptError(f"not saved: {result.message} (save! writes it anyway)")
    r.app.say(result.message)
    r.done()


def c_save_confirmed(r: _Runner, a: tuple[str, ...]) -> None:
    c_save(r, a, confirm=True)


def c_screenshot(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1)
    r.app.screenshot(a[0])


# -- commands: edits ------------------------------------------------------------------------
def _edit(fn: Callable[[_Runner, tuple[str, ...]], object]) -> Callable:
    def run(r: _Runner, a: tuple[str, ...]) -> None:
        fn(r, a)
        r.done()

    return run


@_edit
def c_name(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1)
    r.model.set_name(a[0])


@_edit
def c_rotate_deg(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1)
    r.model.set_rotate(_angle(a[0]))


@_edit
def c_add_wall_vertex(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 2)
    r.app.selection = r.model.add_vertex(("walls",), (_coord(a[0]), _coord(a[1])))


@_edit
def c_add_vertex(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 3)
    r.app.selection = r.model.add_vertex(_path(a[0]), (_coord(a[1]), _coord(a[2])))


@_edit
def c_insert_vertex(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 4)
    r.app.selection = r.model.insert_vertex(_path(a[0]), _int(a[1]), (_coord(a[2]), _coord(a[3])))


@_edit
def c_move_vertex(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 3)
    r.model.move_point(_path(a[0]), (_coord(a[1]), _coord(a[2])))


@_edit
def c_move_by(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 3)
    r.model.translate(_path(a[0]), _delta(a[1]), _delta(a[2]))


@_edit
def c_delete(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1)
    r.model.delete(_path(a[0]))


@_edit
def c_add_obstacle(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 2, 999)
    r.app.selection = r.model.add_obstacle(_points(a))


@_edit
def c_add_goal(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 3)
    r.app.selection = r.model.add_goal(a[0], (_coord(a[1]), _coord(a[2])))


@_edit
def c_move_goal(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 3)
    r.model.move_point(("goals", r.model.goal_index(a[0])), (_coord(a[1]), _coord(a[2])))


@_edit
def c_rename_goal(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 2)
    r.model.rename_goal(a[0], a[1])


@_edit
def c_delete_goal(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1)
    r.model.delete(("goals", r.model.goal_index(a[0])))


@_edit
def c_active_goal(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1)
    r.model.set_active_goal(a[0])


@_edit
def c_add_marker(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 2, 999)
    pts = _points(a)
    r.app.selection = r.model.add_marker(pts[0], pts[1:] or None)


@_edit
def c_set_zone(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 2, 999)
    zone = None if a[1:] == ("default",) else _points(a[1:])
    r.model.set_zone(_int(a[0]), zone)


@_edit
def c_start(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 2, 3)
    heading = None if len(a) < 3 or a[2] == "random" else _angle(a[2], "heading")
    r.model.set_start((_coord(a[0]), _coord(a[1])))
    if len(a) == 3:
        r.model.set_heading(heading)


@_edit
def c_heading(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1)
    r.model.set_heading(None if a[0] == "random" else _angle(a[0]))


@_edit
def c_undo(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 0, 1)
    r.app.undo(_times(a))


@_edit
def c_redo(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 0, 1)
    r.app.redo(_times(a))


@_edit
def c_snap(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1)
    r.model.set_snap(None if a[0] == "off" else _num(a[0]))


@_edit
def c_grid(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1)
    r.model.set_grid(_num(a[0]))


@_edit
def c_tool(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1)
    r.app.set_tool(a[0])


@_edit
def c_select(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1)
    if a[0] == "none":
        r.app.selection = None
        return
    path = _path(a[0])
    if not r.app.has_item(path):
        raise ScriptError(f"{a[0]}: no such item")
    r.app.selection = path


@_edit
def c_view(r: _Runner, a: tuple[str, ...]) -> None:
    if a == ("fit",):
        r.app.fit()
        return
    _count(a, 3)
    x, y = _coord(a[0]), _coord(a[1])
    zoom = _in(_num(a[2]), limits.MIN_ZOOM, limits.MAX_ZOOM, "zoom", " px/in")
    r.app.camera.show((x, y), zoom)


def c_drive(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1, 2)
    app = r.app
    if a[0] == "off":
        app.stop_drive()
    elif a[0] == "reset":
        if app.drive is None:
            app.start_drive()
        if app.drive is not None:
            app.drive.reset()
    elif a[0] in ACTIONS:
        n = _int(a[1]) if len(a) > 1 else 1
        _in(n, 1, limits.MAX_DRIVE_STEPS, "", " steps")
        for _ in range(n):
            app.drive_step(a[0])
            if app.drive is None:
                break
    else:
        raise ScriptError(f"unknown action {a[0]!r} ({', '.join(ACTIONS)}, reset, off)")
    if app.message_is_error:
        raise ScriptError(app.message)
    r.done()


def c_expect_valid(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 0)
    problem = r.model.problem()
    if problem is not None:
        raise ScriptError(f"expected a valid arena, got: {problem.message}")


def c_expect_error(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1)
    problem = r.model.problem()
    if problem is None or a[0] not in problem.message:
        got = "a valid arena" if problem is None else problem.message
        raise ScriptError(f"expected a problem with {a[0]!r}, got: {got}")


# -- commands: posted events -----------------------------------------------------------------
def c_key(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1, 999)
    for spec in a:
        r.post(*_key_event(spec))


def c_type(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1, 999)
    text = " ".join(a)
    if len(text) > limits.MAX_TYPED:
        raise ScriptError(f"{len(text):,} characters (at most {limits.MAX_TYPED:,})")
    r.post(pygame.event.Event(pygame.TEXTINPUT, text=text))


def c_click(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 2, 4)
    flags = set(a[2:])
    if not flags <= {"shift", "right"}:
        raise ScriptError(f"unknown click flags {sorted(flags - {'shift', 'right'})}")
    pos = r.screen_of(_coord(a[0]), _coord(a[1]))
    button = 3 if "right" in flags else 1
    mod = pygame.KMOD_SHIFT if "shift" in flags else 0
    r.post(
        _mouse(pygame.MOUSEMOTION, pos),
        _mouse(pygame.MOUSEBUTTONDOWN, pos, button, mod),
        _mouse(pygame.MOUSEBUTTONUP, pos, button, mod),
    )


def c_click_screen(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 2)
    w, h = r.app.screen.get_size()
    pos = (int(_in(_int(a[0]), 0, w - 1, "x", " px")), int(_in(_int(a[1]), 0, h - 1, "y", " px")))
    r.post(
        _mouse(pygame.MOUSEMOTION, pos),
        _mouse(pygame.MOUSEBUTTONDOWN, pos),
        _mouse(pygame.MOUSEBUTTONUP, pos),
    )


def c_drag(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 4, 5)
    if a[4:] not in ((), ("right",)):
        raise ScriptError(f"unknown drag flag {a[4]!r} (right)")
    button = 3 if a[4:] else 1
    p0 = r.screen_of(_coord(a[0]), _coord(a[1]))
    p1 = r.screen_of(_coord(a[2]), _coord(a[3]))
    events = [_mouse(pygame.MOUSEMOTION, p0), _mouse(pygame.MOUSEBUTTONDOWN, p0, button)]
    steps = 8
    for k in range(1, steps + 1):
        pos = (
            round(p0[0] + (p1[0] - p0[0]) * k / steps),
            round(p0[1] + (p1[1] - p0[1]) * k / steps),
        )
        events.append(_mouse(pygame.MOUSEMOTION, pos))
    events.append(_mouse(pygame.MOUSEBUTTONUP, p1, button))
    r.post(*events)


def c_move(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 2)
    r.post(_mouse(pygame.MOUSEMOTION, r.screen_of(_coord(a[0]), _coord(a[1]))))


def c_wheel(r: _Runner, a: tuple[str, ...]) -> None:
    _count(a, 1, 3)
    events = []
    if len(a) == 3:
        events.append(_mouse(pygame.MOUSEMOTION, r.screen_of(_coord(a[1]), _coord(a[2]))))
    elif len(a) == 2:
        raise ScriptError("expected N, or N X Y")
    most = limits.MAX_WHEEL_CLICKS
    clicks = int(_in(_int(a[0]), -most, most, "", " clicks"))
    events.append(pygame.event.Event(pygame.MOUSEWHEEL, x=0, y=clicks, flipped=False))
    r.post(*events)


COMMANDS: dict[str, Callable[[_Runner, tuple[str, ...]], None]] = {
    "new": c_new,
    "open": c_open,
    "import_doors": c_import_doors,
    "save": c_save,
    "save!": c_save_confirmed,
    "screenshot": c_screenshot,
    "name": c_name,
    "rotate_deg": c_rotate_deg,
    "add_wall_vertex": c_add_wall_vertex,
    "add_vertex": c_add_vertex,
    "insert_vertex": c_insert_vertex,
    "move_vertex": c_move_vertex,
    "move_by": c_move_by,
    "delete": c_delete,
    "add_obstacle": c_add_obstacle,
    "add_goal": c_add_goal,
    "move_goal": c_move_goal,
    "rename_goal": c_rename_goal,
    "delete_goal": c_delete_goal,
    "active_goal": c_active_goal,
    "add_marker": c_add_marker,
    "set_zone": c_set_zone,
    "start": c_start,
    "heading": c_heading,
    "undo": c_undo,
    "redo": c_redo,
    "snap": c_snap,
    "grid": c_grid,
    "tool": c_tool,
    "select": c_select,
    "view": c_view,
    "drive": c_drive,
    "expect_valid": c_expect_valid,
    "expect_error": c_expect_error,
    "key": c_key,
    "type": c_type,
    "click": c_click,
    "click_screen": c_click_screen,
    "drag": c_drag,
    "move": c_move,
    "wheel": c_wheel,
}
"""Script command -> handler."""
