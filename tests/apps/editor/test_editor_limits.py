"""The editor's ranges (koolio_pymunk/apps/editor/limits.py): every number a user gives
the editor is checked where it is read. A script value out of range fails its line with
one message and does nothing; an edit that would leave the range is refused and changes
nothing; what comes from the keyboard and the mouse is clamped (zoom, pan, wheel) or
refused in the status bar (a typed position, an arrow past the range), never a traceback
or a hang; drawing stays on the canvas, so a frame costs the same at any zoom."""

from __future__ import annotations

import math
import os
import shutil
import signal
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import pytest

os.environ["SDL_VIDEODRIVER"] = "dummy"
os.environ["SDL_AUDIODRIVER"] = "dummy"

import pygame

from koolio_pymunk.apps.editor import clip, limits
from koolio_pymunk.apps.editor.app import EditorApp
from koolio_pymunk.apps.editor.items import EditError
from koolio_pymunk.apps.editor.launch import grid_inches, window_size
from koolio_pymunk.apps.editor.model import EditorModel
from koolio_pymunk.apps.editor.script import ScriptError, parse_script, run_text
from koolio_pymunk.store.errors import ArenaError, KoolioError
from koolio_pymunk.world.arena import Arena, Door, Goal, Start, load_arena

REPO = Path(__file__).resolve().parents[3]
ROOM = REPO / "arenas" / "room.yaml"
DOORS = REPO / "arenas" / "hallway_doors.yaml"


@contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    """Fail (instead of hanging) when the block runs longer than ``seconds``."""

    def expired(*_: object) -> None:
        raise TimeoutError(f"still running after {seconds} s")

    old = signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def room_app(tmp_path: Path, size: tuple[int, int] = (1000, 600)) -> tuple[EditorApp, Path]:
    path = tmp_path / "room.yaml"
    shutil.copy(ROOM, path)
    return EditorApp(EditorModel.from_file(path), size), path


def key(app: EditorApp, k: int, mod: int = 0, text: str = "") -> None:
    """A key press handled as the window would (no script in between)."""
    app.handle(pygame.event.Event(pygame.KEYDOWN, key=k, mod=mod, unicode=text, scancode=0))


# -- script values ------------------------------------------------------------------------------
REFUSED = [
    ("view 0 0 1e-12", "view: zoom 1e-12 px/in is out of range (0.05 to 20 px/in)"),
    ("view 0 0 1e300", "view: zoom 1e+300 px/in is out of range (0.05 to 20 px/in)"),
    ("view 1e300 0 1", "view: coordinate 1e+300 in is out of range (-1,000,000 to 1,000,000 in)"),
    ("move_vertex walls[0] 1e300 0", "move_vertex: coordinate 1e+300 in is out of range"),
    ("move_vertex walls[0] 1000000.5 0", "move_vertex: coordinate 1,000,000.5 in is out of"),
    ("add_wall_vertex 0 -1e7", "add_wall_vertex: coordinate -10,000,000 in is out of range"),
    ("move_by obstacles[0] 1e308 0", "move_by: move 1e+308 in is out of range"),
    ("move_by walls[0] 1999999 0", "walls[0]: (1999999, 0) is out of range"),
    ("add_marker 1e300 0", "add_marker: coordinate 1e+300 in is out of range"),
    ("set_zone 0 1 1 2 2 nan 3", "set_zone: not a number: 'nan'"),
    ("start 10 10 inf", "start: not a number: 'inf'"),
    ("start 10 10 1e400", "start: not a finite number: '1e400'"),
    ("heading 1e300", "heading: 1e+300 deg is out of range (-360 to 360 deg)"),
    ("rotate_deg -361", "rotate_deg: -361 deg is out of range (-360 to 360 deg)"),
    ("grid 0.001", "grid: 0.001 in is out of range (1 to 1,000 in)"),
    ("grid 1e300", "grid: 1e+300 in is out of range (1 to 1,000 in)"),
    ("snap 0.001", "snap: 0.001 in is out of range (0.01 to 1,000 in)"),
    ("snap 1e300", "snap: 1e+300 in is out of range (0.01 to 1,000 in)"),
    ("wheel 100000 100 100", "wheel: 100,000 clicks is out of range (-100 to 100 clicks)"),
    ("wheel -101", "wheel: -101 clicks is out of range (-100 to 100 clicks)"),
    ("drive forward 1000000000", "drive: 1,000,000,000 steps is out of range (1 to 10,000 steps)"),
    ("drive forward 0", "drive: 0 steps is out of range (1 to 10,000 steps)"),
    ("undo 0", "undo: N must be 1 or more, got 0"),
    ("redo -5", "redo: N must be 1 or more, got -5"),
    ("undo 1e9", "undo: not a whole number: '1e9'"),
    ("undo " + "9" * 5000, "undo: not a whole number: '9999"),
    ("undo \u0661\u0662", "undo: not a whole number: '\u0661\u0662'"),  # Arabic-Indic digits
    ("move_vertex walls[0] 1_000 0", "move_vertex: not a number: '1_000'"),
    ("click_screen 99999999999999999999 1", "click_screen: x 1e+20 px is out of range (0 to 999"),
    ("click_screen -1 5", "click_screen: x -1 px is out of range (0 to 999 px)"),
    ("click 1e300 0", "click: coordinate 1e+300 in is out of range"),
    ("add_goal " + "x" * 101 + " 100 100", "goals: a name of 101 characters (at most 100)"),
    ('add_goal "a\tb" 100 100', "goals: control characters in the name 'a\\tb'"),
    ('name "a\x01b"', "name: control characters in the name 'a\\x01b'"),
    ('new "lab\x07"', "name: control characters in the name 'lab\\x07'"),
    ("type " + "x" * 1001, "type: 1,001 characters (at most 1,000)"),
]


@pytest.mark.parametrize("line, message", REFUSED, ids=[r[0][:40] for r in REFUSED])
def test_a_script_value_out_of_range_fails_its_line_and_does_nothing(
    tmp_path: Path, line: str, message: str
) -> None:
    app, _ = room_app(tmp_path)
    before, cam = app.model.arena, (app.camera.center, app.camera.zoom)
    snap, tile, history = app.model.snap_step, app.model.tile, len(app.model.undo_stack)
    with time_limit(20), pytest.raises(ScriptError) as err:
        run_text(app, line + "\n")
    text = str(err.value)
    assert "\n" not in text and text.startswith("<script>:1: ")
    assert message in text, text
    assert app.model.arena is before and (app.camera.center, app.camera.zoom) == cam
    assert (app.model.snap_step, app.model.tile) == (snap, tile)
    assert len(app.model.undo_stack) == history


def test_a_script_too_large_is_refused_before_anything_runs() -> None:
    with pytest.raises(ScriptError, match=r"^s\.txt:10001: more than 10,000 commands"):
        parse_script("undo\n" * 10_001, "s.txt")
    with pytest.raises(ScriptError, match=r"^s\.txt:2: a line of 65,537 characters"):
        parse_script("new\nname " + "x" * 65_532 + "\n", "s.txt")
    assert len(parse_script("undo\n" * 10_000, "s.txt")) == 10_000


def test_values_at_the_ends_of_the_ranges_are_accepted(tmp_path: Path) -> None:
    app, _ = room_app(tmp_path)
    run_text(
        app,
        "grid 1\ngrid 1000\nsnap 0.01\nsnap 1000\nsnap off\nview 0 0 0.05\n"
        "view -1000000 1000000 20\nview 0 0 20\nwheel 100 0 0\nwheel -100 0 0\n"
        "heading -360\nrotate_deg 360\n"
        "rotate_deg 0\nadd_obstacle -1000000 -1000000 1000000 -1000000 0 1000000\n"
        "move_by obstacles[0] 0 0\nundo\nclick_screen 999 599\n",
    )
    assert app.camera.zoom == limits.MIN_ZOOM  # 100 clicks back from 20
    assert app.model.arena.start.heading_deg == 0.0


def test_undo_and_redo_a_billion_times_stop_at_the_ends_at_once(tmp_path: Path) -> None:
    app, _ = room_app(tmp_path)
    original = app.model.arena
    run_text(app, "move_vertex walls[1] 100 0\nstart 60 60\nheading 90\n")
    edited = app.model.arena
    start = time.perf_counter()
    with time_limit(20):
        run_text(app, "undo 1000000000\n")
        assert app.model.arena == original and app.message == "undo: move walls[1] to (100, 0)"
        run_text(app, "undo 1000000000\n")
        assert app.model.arena == original and app.message == "nothing to undo"
        run_text(app, "redo 2\n")
        assert app.model.arena.start.at == (60, 60) and app.model.arena.start.heading_deg is None
        run_text(app, "redo 1000000000\n")
        assert app.model.arena == edited and app.message == "redo: start heading 90 deg"
        run_text(app, "undo 2\nredo\nredo\n")
        assert app.model.arena == edited
    assert time.perf_counter() - start < 5  # a loop of 1e9 would take hours


# -- edits ----------------------------------------------------------------------------------------
def test_an_edit_beyond_the_coordinate_range_is_refused_and_changes_nothing() -> None:
    m = EditorModel.from_file(ROOM)
    before = m.arena
    for edit in (
        lambda: m.move_point(("walls", 0), (1e7, 0)),
        lambda: m.move_point(("start",), (float("nan"), 0)),
        lambda: m.translate(("end_of_world", 0), 0, -2e6),
        lambda: m.add_goal("7", (0, 1e300)),
        lambda: m.add_obstacle([(0, 0), (1, 1), (float("inf"), 0)]),
        lambda: m.set_zone(0, [(0, 0), (10, 0), (10, 1e6 + 1)]),
    ):
        with pytest.raises(EditError, match=r"is out of range \(coordinates -1,000,000 to 1,"):
            edit()
        assert m.arena is before and not m.undo_stack
    m.move_point(("walls", 0), (-1e6, -1e6))  # the end of the range itself is fine
    assert m.arena.walls[0] == (-1e6, -1e6)


def test_more_points_or_entries_than_the_simulator_loads_are_refused() -> None:
    n = limits.MAX_POLYGON_POINTS
    ring = tuple(
        (
            round(1000 * math.cos(2 * math.pi * k / n), 6),
            round(1000 * math.sin(2 * math.pi * k / n), 6),
        )
        for k in range(n)
    )
    m = EditorModel(
        Arena(name="big", walls=ring, goals=(Goal("1", (0.0, 0.0)),), end_of_world=(),
              start=Start((0.0, 0.0), None))
    )  # fmt: skip
    with pytest.raises(EditError, match=r"^walls: 10,001 points \(the limit is 10,000\)$"):
        m.add_vertex(("walls",), (5.0, 5.0))
    m.add_obstacle([(0, 0)] * n)
    with pytest.raises(EditError, match=r"20,001 points in walls, obstacles and zones"):
        m.add_obstacle([(1, 1)])
    assert len(m.arena.obstacles) == 1
    m = EditorModel.blank("goals")
    for k in range(limits.MAX_ENTRIES):
        m.add_goal(str(k), (1.0, 1.0))
    with pytest.raises(EditError, match=r"^goals: 1,001 entries \(the limit is 1,000\)$"):
        m.add_goal("x", (1.0, 1.0))


def test_a_hallway_beyond_the_range_is_refused(tmp_path: Path) -> None:
    table = tmp_path / "long.yaml"
    table.write_text(DOORS.read_text().replace("length_tiles: 68", "length_tiles: 100000000"))
    m = EditorModel.blank()
    with pytest.raises(ArenaError) as err:
        m.import_door_table(table)
    assert str(err.value) == (
        f"{table}: the hallway it builds: walls[1]: (2400000000, 0) is out of range "
        "(coordinates -1,000,000 to 1,000,000 in)"
    )
    assert m.arena.walls == ()


def test_the_grid_and_size_flags(tmp_path: Path) -> None:
    assert grid_inches(24.0) == 24.0 and grid_inches(1.0) == 1.0 and grid_inches(1000) == 1000
    for bad in (0.001, 0.0, -24.0, 1000.5, 1e300, math.inf, math.nan):
        with pytest.raises(KoolioError, match=r"^--grid: .* is out of range \(1 to 1,000 in\)"):
            grid_inches(bad)
    assert window_size("1280x720") == (1280, 720) and window_size(" 400 X 300 ") == (400, 300)
    assert window_size("7680x4320") == (7680, 4320)
    for bad, problem in (
        ("100000x100000", "at most 7680x4320"),
        ("7681x720", "at most 7680x4320"),
        ("399x300", "at least 400x300"),
        ("1e3x720", "expected WxH"),
        ("1280x720x3", "expected WxH"),
        ("\u0661\u0662\u0668\u0660x720", "expected WxH"),  # not ASCII digits
        ("9" * 5000 + "x720", "expected WxH"),
        ("", "expected WxH"),
    ):
        with pytest.raises(KoolioError, match=rf"^--size: {problem}") as err:
            window_size(bad)
        assert len(str(err.value)) < 120


# -- the window: clamped or refused in the status bar -------------------------------------------
def test_wheel_keys_and_pans_are_clamped(tmp_path: Path) -> None:
    app, _ = room_app(tmp_path)
    app.handle(
        pygame.event.Event(pygame.MOUSEMOTION, pos=(300, 300), rel=(0, 0), buttons=(0, 0, 0))
    )
    app.handle(pygame.event.Event(pygame.MOUSEWHEEL, x=0, y=100_000, flipped=False))
    assert app.camera.zoom == limits.MAX_ZOOM and not app.message_is_error
    app.handle(pygame.event.Event(pygame.MOUSEWHEEL, x=0, y=-(10**30), flipped=False))
    assert app.camera.zoom == limits.MIN_ZOOM
    for _ in range(200):
        key(app, pygame.K_PLUS)
    assert app.camera.zoom == limits.MAX_ZOOM
    for _ in range(200):
        key(app, pygame.K_MINUS)
    with time_limit(20):
        for _ in range(2000):  # 10 % of the canvas a press: 1,320 in at 0.05 px/in
            key(app, pygame.K_RIGHT)
        assert app.camera.center[0] == limits.MAX_COORDINATE
        for _ in range(200):  # right-drags: 12,800 in left and 9,800 in up each
            app.handle(pygame.event.Event(pygame.MOUSEBUTTONDOWN, pos=(10, 10), button=3, mod=0))
            app.handle(
                pygame.event.Event(
                    pygame.MOUSEMOTION, pos=(650, 500), rel=(0, 0), buttons=(0, 0, 1)
                )
            )
            app.handle(pygame.event.Event(pygame.MOUSEBUTTONUP, pos=(650, 500), button=3))
        app.render()
    assert app.camera.center == (-limits.MAX_COORDINATE, limits.MAX_COORDINATE)


def test_a_typed_position_or_an_arrow_out_of_range_is_refused_in_the_status_bar(
    tmp_path: Path,
) -> None:
    app, _ = room_app(tmp_path)
    run_text(app, "select start\n")
    for typed in ("1e300 5", "nan 5", "5 inf", "1000001 0", "-1e400 0"):
        for event in (
            pygame.event.Event(pygame.KEYDOWN, key=pygame.K_p, mod=0, unicode="p", scancode=0),
            pygame.event.Event(pygame.TEXTINPUT, text=typed),
            pygame.event.Event(pygame.KEYDOWN, key=pygame.K_RETURN, mod=0, unicode="", scancode=0),
        ):
            pygame.event.post(event)
            app.pump()
        assert app.prompt is None
        assert app.message_is_error and "is out of range" in app.message, app.message
        assert app.model.arena.start.at == (48, 48)
        app.render()
    run_text(app, "move_vertex walls[1] 999990 0\nselect walls[1]\n")
    key(app, pygame.K_RIGHT)  # one snap step (24 in) past the range
    assert app.message_is_error
    assert app.message.startswith("walls[1]: (1000014, 0) is out of range")
    assert app.model.arena.walls[1] == (999990, 0)
    key(app, pygame.K_RIGHT, pygame.KMOD_SHIFT)  # 1 in: still inside
    assert app.model.arena.walls[1] == (999991, 0)
    app.render()


def test_a_click_past_the_range_lands_on_its_edge(tmp_path: Path) -> None:
    app, _ = room_app(tmp_path)
    run_text(app, f"view {limits.MAX_COORDINATE:g} 0 0.05\nkey w\n")
    app.handle(pygame.event.Event(pygame.MOUSEBUTTONDOWN, pos=(650, 300), button=1, mod=0))
    app.handle(pygame.event.Event(pygame.MOUSEBUTTONUP, pos=(650, 300), button=1, mod=0))
    assert not app.message_is_error
    assert app.model.arena.walls[-1][0] == limits.MAX_COORDINATE


# -- drawing ------------------------------------------------------------------------------------
BIG = """\
name: big
walls: [[-1000000, -1000000], [1000000, -1000000], [1000000, 1000000], [-1000000, 1000000]]
obstacles: [[[-999000, -999000], [999000, -999000], [0, -998000]]]
goals: [{name: "1", at: [0, 0]}]
end_of_world: [{at: [500000, 0], zone: [[400000, -10], [600000, -10], [600000, 10]]}]
start: {at: [100, 100], heading_deg: 45}
doors: [{name: "1", a: [-999999, 1000000], b: [999999, 1000000], plate: [0, 999999]}]
"""


def test_drawing_stays_near_the_canvas_at_every_zoom(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """pygame walks every pixel of what it is given: a wall 40 million pixels long took
    the better part of a second a frame. Everything handed to pygame.draw stays within
    clip.SAFE_PIXELS of the canvas."""
    path = tmp_path / "big.yaml"
    path.write_text(BIG)
    app = EditorApp(EditorModel.from_file(path), (1000, 600))
    far = clip.SAFE_PIXELS + 1000
    seen: list[float] = []

    def coords(value: object) -> Iterator[float]:
        if isinstance(value, (int, float)):
            yield float(value)
        elif isinstance(value, (tuple, list)):
            for v in value:
                yield from coords(v)
        elif isinstance(value, pygame.Rect):
            yield from (value.left, value.top, value.right, value.bottom)

    # What pygame walks pixel by pixel (circles and rectangles are cheap anywhere).
    shapes = {"line": slice(0, 2), "lines": slice(1, 2), "polygon": slice(0, 1)}
    for name, where in shapes.items():
        real = getattr(pygame.draw, name)

        def spy(surface, colour, *args, _real=real, _where=where, **kw):
            seen.extend(abs(v) for v in coords(args[_where]))
            return _real(surface, colour, *args, **kw)

        monkeypatch.setattr(pygame.draw, name, spy)
    for line in (
        "view fit", "view 0 0 20", "view 999990 0 20", "view 500000 0 20",
        "view 0 1000000 20", "select walls", "select obstacles[0]",
        "select end_of_world[0].zone", "view 0 -998500 20", "key w", "move 0 -998500",
    ):  # fmt: skip
        seen.clear()
        start = time.perf_counter()
        run_text(app, line + "\n")
        app.render()
        assert seen and max(seen) < far, (line, max(seen))
        assert time.perf_counter() - start < 5, line  # before: about 0.7 s a frame


def test_the_clipped_arena_looks_the_same_on_the_canvas(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Cut polygons fill the same pixels of the canvas as the whole ones."""
    path = tmp_path / "wide.yaml"
    path.write_text(BIG.replace("1000000", "30000").replace("999000", "29000"))
    app = EditorApp(EditorModel.from_file(path), (1000, 600))
    run_text(app, "view 0 -29000 1\n")  # within SAFE_PIXELS: drawn whole
    app.show_lengths = False
    app.render()
    whole = pygame.image.tobytes(app.screen, "RGB")
    left, top, w, h = app.camera.viewport
    m = clip.MARGIN_PIXELS
    (x0, y1), (x1, y0) = (
        app.camera.to_world((left - m, top - m)),
        app.camera.to_world((left + w + m, top + h + m)),
    )
    box = (x0, y0, x1, y1)
    cut = clip.drawable_arena(app.model.arena, box, box)  # everything cut
    assert cut.walls != app.model.arena.walls and len(cut.obstacles[0]) > 3
    real = clip.drawable_arena
    monkeypatch.setattr(clip, "drawable_arena", lambda arena, safe, c: real(arena, box, box))
    app.render()
    assert pygame.image.tobytes(app.screen, "RGB") == whole


def test_long_names_from_a_file_are_drawn_cut(tmp_path: Path) -> None:
    """The simulator accepts names of up to 200 characters (the arena loader's bound); the
    panel draws them cut (it once measured a 100,000-character door name one character at
    a time, minutes a frame)."""
    text = (REPO / "arenas" / "hallway.yaml").read_text()
    long = "3" * 200
    path = tmp_path / "long.yaml"
    path.write_text(
        text.replace("'312'", f"'{long}'").replace("name: hallway", "name: " + "h" * 200)
    )
    arena = load_arena(path)
    assert long in arena.goal_names()
    with time_limit(30):
        app = EditorApp(EditorModel.from_file(path), (1000, 600))
        app.model.set_active_goal(long)
        app.selection = ("goals", app.model.goal_index(long))
        app.render()
    assert max(r.w for r in app.drawn_labels["doors"]) < 400


def test_a_door_beyond_the_walls_and_empty_clips_draw(tmp_path: Path) -> None:
    arena = load_arena(REPO / "arenas" / "hallway.yaml")
    door = Door("9", (5000.0, 5000.0), (5036.0, 5000.0), (5000.0, 4999.0))
    m = EditorModel(replace(arena, doors=(*arena.doors, door)))
    app = EditorApp(m, (1000, 600))
    for line in ("view 5000 5000 20", "view 0 0 20", "view 800 44 20", "view fit"):
        run_text(app, line + "\n")
        app.render()
