"""The arena editor driven through its own event handling (posted keys and clicks), headless."""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

os.environ["SDL_VIDEODRIVER"] = "dummy"
os.environ["SDL_AUDIODRIVER"] = "dummy"

import pygame

from koolio_pymunk.apps.editor import view
from koolio_pymunk.apps.editor.app import EditorApp
from koolio_pymunk.apps.editor.model import EditorModel
from koolio_pymunk.apps.editor.script import ScriptError, parse_script, run_text
from koolio_pymunk.world.arena import load_arena

REPO = Path(__file__).resolve().parents[3]
ROOM = REPO / "arenas" / "room.yaml"


def app_for(path: Path | None = None, size: tuple[int, int] = (1000, 600)) -> EditorApp:
    model = EditorModel.blank("lab") if path is None else EditorModel.from_file(path)
    return EditorApp(model, size)


def copy_room(tmp_path: Path) -> Path:
    path = tmp_path / "room.yaml"
    shutil.copy(ROOM, path)
    return path


BUILD = """\
view 120 96 2
key w
click 0 0
click 240 0
click 240 192
click 0 192
snap 1
key g
click 100 190
type 201
key return
snap 24
key e
click 200 96
key s
click 48 48
click 100 48 shift
key o
click 96 72
click 144 72
click 144 120
click 96 120
click 96 72
select end_of_world[0]
key z
click 216 72
click 240 72
click 240 120
key return
expect_valid
key ctrl+s
type {out}
key return
screenshot {png}
"""

EXPECTED = """\
name: lab
walls:
- [0, 0]
- [240, 0]
- [240, 192]
- [0, 192]
obstacles:
- - [96, 72]
  - [144, 72]
  - [144, 120]
  - [96, 120]
goals:
- name: '201'
  at: [100, 190]
active_goal: '201'
end_of_world:
- at: [192, 96]
  zone:
  - [216, 72]
  - [240, 72]
  - [240, 120]
start:
  at: [48, 48]
  heading_deg: 0
rotate_deg: 0
"""


def test_build_an_arena_with_the_mouse_and_save_it(tmp_path: Path) -> None:
    app = app_for(size=(1000, 600))
    out, png = tmp_path / "lab.yaml", tmp_path / "lab.png"
    run_text(app, BUILD.format(out=out, png=png))
    text = out.read_text()
    assert text.split("\n", 1)[1] == EXPECTED
    assert load_arena(out).obstacles == (((96, 72), (144, 72), (144, 120), (96, 120)),)
    image = pygame.image.load(str(png))
    assert image.get_size() == (1000, 600)
    cam = app.camera
    assert image.get_at(cam.to_screen((60, 150)))[:3] == (250, 250, 246)  # floor
    assert image.get_at(cam.to_screen((130, 100)))[:3] == (120, 124, 134)  # obstacle
    assert image.get_at(cam.to_screen((250, 170)))[:3] == (208, 212, 218)  # outside
    wall = image.get_at(cam.to_screen((60, 0)))[:3]  # under the grid's x axis: darkened
    assert max(wall) < 120
    assert app.message == f"saved {out}" and not app.model.dirty


def test_select_drag_delete_undo_redo_keys(tmp_path: Path) -> None:
    app = app_for(copy_room(tmp_path))
    run_text(app, "view 144 96 2\nkey v\ndrag 240 72 264 72\n")
    assert app.model.arena.walls[2] == (264, 72) and app.selection == ("walls", 2)
    assert app.message == "move walls[2] to (264, 72)"
    run_text(app, "key delete\n")
    assert len(app.model.arena.walls) == 7 and app.selection is None
    run_text(app, "key ctrl+z\n")
    assert app.model.arena.walls[2] == (264, 72) and app.message == "undo: delete walls[2]"
    run_text(app, "key ctrl+z\n")
    assert app.model.arena.walls[2] == (240, 72)
    run_text(app, "key ctrl+y\nkey ctrl+shift+z\n")
    assert len(app.model.arena.walls) == 7
    run_text(app, "key ctrl+z ctrl+z\n")
    assert app.model.arena.walls == load_arena(ROOM).walls and not app.model.dirty
    # dragging an obstacle-free floor pans; a tiny press-release moves nothing
    centre = app.camera.center
    run_text(app, "drag 100 100 124 100\n")
    assert app.camera.center == (centre[0] - 24, centre[1])
    n = len(app.model.undo_stack)
    run_text(app, "click 102 191\n")
    assert app.selection == ("goals", 0) and len(app.model.undo_stack) == n


def test_insert_tool_inserts_on_the_clicked_edge(tmp_path: Path) -> None:
    app = app_for(copy_room(tmp_path))
    run_text(app, "view 144 96 2\nkey i\nclick 130 1\n")
    assert app.model.arena.walls[:3] == ((0, 0), (120, 0), (240, 0))
    assert app.selection == ("walls", 1)
    run_text(app, "drag 0 100 0 120\n")  # the left wall: between walls[8] and walls[0]
    assert app.model.arena.walls[-1] == (0, 120)
    with pytest.raises(ScriptError, match="insert: click on an edge"):
        run_text(app, "click 120 100\n")


def test_obstacle_zone_and_default_zone_tools(tmp_path: Path) -> None:
    app = app_for(copy_room(tmp_path))
    run_text(
        app,
        "view 144 96 2\nkey o\nclick 72 120\nclick 120 120\nclick 96 168\nclick 72 120\n"
        "click 168 48\nclick 192 48\nclick 192 72\nkey return\nexpect_valid\n",
    )
    assert app.model.arena.obstacles == (
        ((72, 120), (120, 120), (96, 168)),
        ((168, 48), (192, 48), (192, 72)),
    )
    run_text(app, "key z\nclick 240 72\nclick 288 72\nclick 288 96\nkey return\n")
    assert app.model.arena.end_of_world[0].zone == ((240, 72), (288, 72), (288, 96))
    run_text(app, "key v\nclick 264 96\nkey d\n")
    assert app.model.arena.end_of_world[0].zone is None
    run_text(app, "undo\n")
    assert len(app.model.arena.end_of_world[0].zone) == 3


def test_goal_prompt_rename_and_active_goal_from_the_panel(tmp_path: Path) -> None:
    app = app_for(copy_room(tmp_path))
    run_text(app, "view 144 96 2\nsnap 1\nkey g\nclick 150 100\n")
    assert app.prompt is not None and app.prompt.text == "202"  # the proposed name
    run_text(app, "type 7\nkey backspace\ntype 205\nkey return\n")
    assert app.model.arena.goal_names() == ["201", "205"]
    run_text(app, 'key r\nkey backspace\ntype "Lab B"\nkey return\n')
    assert app.model.arena.goal_names() == ["201", "Lab B"]
    rect, name = app.goal_rows[1]
    assert name == "Lab B"
    run_text(app, f"click_screen {rect.x + 5} {rect.y + 5}\n")
    assert app.model.arena.active_goal == "Lab B"
    run_text(app, "key tab\n")
    assert app.model.arena.active_goal == "201"
    run_text(app, "key p\nkey backspace\ntype 160 100\nkey return\n")
    assert app.model.arena.goals[1].at == (160, 100)


def test_saving_an_invalid_arena_asks_first(tmp_path: Path) -> None:
    path = copy_room(tmp_path)
    good = path.read_bytes()
    app = app_for(path)
    run_text(app, "move_vertex goals[0] 102 200\nkey ctrl+s\n")
    assert app.prompt is not None and app.prompt.kind == "confirm"
    assert app.prompt.label == (
        f"INVALID: {path}: goals[0].at: point (102, 200) is outside the walls (or on them) "
        f"-- write {path} anyway (the valid file is kept as .bak)?"
    )
    run_text(app, "key n\n")
    assert app.prompt is None and path.read_bytes() == good and app.message == "cancelled"
    with pytest.raises(ScriptError, match=r"save: not saved: .* \(save! writes it anyway\)$"):
        run_text(app, "save\n")
    assert path.read_bytes() == good
    run_text(app, "key ctrl+s\nkey y\n")
    assert (tmp_path / "room.yaml.bak").read_bytes() == good
    assert (
        app.message == f"saved invalid arena {path} (the previous valid file is kept as {path}.bak)"
    )
    assert EditorModel.from_file(path).arena.goals[0].at == (102, 200)


def test_the_offending_item_is_highlighted_in_red(tmp_path: Path) -> None:
    app = app_for(copy_room(tmp_path))
    png = tmp_path / "shot.png"
    run_text(app, f"view 144 96 2\nscreenshot {png}\n")
    red = (205, 0, 0)
    assert not _pixels(pygame.image.load(str(png)), red)
    run_text(app, f"move_goal 201 120 210\nscreenshot {png}\n")
    image = pygame.image.load(str(png))
    sx, sy = app.camera.to_screen((120, 210))
    ring = [(x, y) for x, y in _pixels(image, red) if abs(x - sx) <= 16 and abs(y - sy) <= 16]
    assert len(ring) > 40  # the ring around the goal
    status = pygame.Rect(app.status_rect)
    assert any(status.collidepoint(p) for p in _pixels(image, red))  # the message
    assert app.model.problem().paths == (("goals", 0),)
    # an edge named by the message is drawn in red too
    run_text(app, f"undo\nstart 235 30\nscreenshot {png}\n")
    assert app.model.problem().edges == ((("walls",), 1),)
    image = pygame.image.load(str(png))
    ex, ey = app.camera.to_screen((240, 50))
    assert image.get_at((ex, ey))[:3] == red


def _pixels(image: pygame.Surface, colour: tuple[int, int, int]) -> list[tuple[int, int]]:
    """Every pixel ``(x, y)`` of exactly ``colour``."""
    rgb = pygame.surfarray.array3d(image)  # indexed [x, y, channel]
    xs, ys = np.nonzero((rgb == np.array(colour)).all(axis=2))
    return list(zip(xs.tolist(), ys.tolist()))


def test_test_drive_uses_the_core(tmp_path: Path) -> None:
    app = app_for(copy_room(tmp_path))
    run_text(app, "drive forward 2\n")
    cfg = app.drive.env.config
    d, arc = cfg.actions.move_action_distance, math.radians(cfg.actions.rotate_action_arc_deg)
    assert app.drive.pose == pytest.approx((48 + 2 * d, 48, 0), abs=1e-9)  # start: (48, 48)
    assert app.drive.steps == 2
    assert app.message == f"Forward: forward, reward {cfg.rewards.forward:g}"
    run_text(app, "key left\nkey up\nkey space\n")
    expected = (48 + 2 * d + d * math.cos(arc), 48 + d * math.sin(arc), arc)
    assert app.drive.pose == pytest.approx(expected, abs=1e-9)
    assert app.drive.steps == 5
    run_text(app, "key return\n")
    assert app.drive.pose == (48.0, 48.0, 0.0) and app.drive.steps == 0
    run_text(app, "drive forward 30\n")  # into the east wall: pymunk stops it
    x, _, _ = app.drive.pose
    assert abs(x - 230) <= 0.011 and app.drive.robot_state() == "bump"
    run_text(app, "key escape\n")
    assert app.drive is None
    run_text(app, "move_vertex goals[0] 102 200\n")
    with pytest.raises(ScriptError, match=r"cannot drive an invalid arena: .*goals\[0\]\.at"):
        run_text(app, "drive forward\n")


def test_snap_zoom_and_ruler(tmp_path: Path) -> None:
    app = app_for(copy_room(tmp_path))
    run_text(app, "view 144 96 2\nkey x\n")
    assert app.model.snap_step == 12 and app.message == "snap 12 in"
    run_text(app, "key x x x\n")
    assert app.model.snap_step is None
    run_text(app, "key x\nmove 120 88\n")
    assert app.model.snap_step == 24
    assert app.ruler_text() == "cursor (120, 96) in = (5, 4) tiles"
    run_text(app, "snap 1\nmove 120 89\n")
    assert app.ruler_text() == "cursor (120, 89) in = (5, 3.71) tiles"
    run_text(app, "move 120 1\n")
    assert app.ruler_text() == (
        "cursor (120, 1) in = (5, 0.04) tiles   walls[0]-walls[1] 240 in = 10 tiles"
    )
    run_text(app, "wheel 2 120 96\n")
    assert app.camera.zoom == pytest.approx(2 * 1.44)
    assert view.fmt_len(88, 24) == "88 in = 3.67 tiles"


def test_quit_asks_when_there_are_unsaved_changes(tmp_path: Path) -> None:
    app = app_for(copy_room(tmp_path))
    run_text(app, "key ctrl+q\n")
    assert not app.running
    app = app_for(copy_room(tmp_path))
    run_text(app, "name other\nkey ctrl+q\n")
    assert app.running and app.prompt.label == "Unsaved changes: quit anyway?"
    run_text(app, "key y\n")
    assert not app.running


def test_script_errors_name_the_line() -> None:
    with pytest.raises(
        ScriptError, match=r"^s\.txt:2: unknown command 'add_gaol' \(did you mean 'add_goal'\?\)$"
    ):
        parse_script("new\nadd_gaol 1 2 3\n", "s.txt")
    app = app_for()
    with pytest.raises(ScriptError, match=r"^<script>:1: add_goal: expected 3 arguments, got 2$"):
        run_text(app, "add_goal 1 2\n")
    with pytest.raises(ScriptError, match=r"^<script>:2: move_vertex: not a number: 'x'$"):
        run_text(app, "# comment\nmove_vertex walls[0] x 1\n")
    with pytest.raises(
        ScriptError, match=r"^<script>:1: walls\[0\]: no such item \(there are 0\)$"
    ):
        run_text(app, "move_vertex walls[0] 1 1\n")
    with pytest.raises(ScriptError, match=r"^<script>:1: key: unknown key 'nokey'$"):
        run_text(app, "key nokey\n")


def test_command_line_script_and_screenshot(tmp_path: Path) -> None:
    script = tmp_path / "s.txt"
    out, png = tmp_path / "lab.yaml", tmp_path / "lab.png"
    script.write_text(BUILD.format(out=out, png=tmp_path / "mid.png"))
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    tool = str(REPO / "tools" / "arena_editor.py")
    result = subprocess.run(
        [sys.executable, tool, "--new", "--script", str(script), "--screenshot", str(png),
         "--size", "1000x600"],
        capture_output=True, text=True, env=env, check=False,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert out.read_text().split("\n", 1)[1] == EXPECTED.replace("name: lab", "name: untitled")
    assert pygame.image.load(str(png)).get_size() == (1000, 600)
    script.write_text("open arenas/room.yaml\nmove_vertex walls[1] 1 2 3\n")
    result = subprocess.run(
        [sys.executable, tool, "--script", str(script)],
        capture_output=True, text=True, env=env, check=False, cwd=REPO,
    )  # fmt: skip
    assert result.returncode == 2
    assert (
        result.stderr == f"koolio-pm: error: {script}:2: move_vertex: expected 3 arguments, got 4\n"
    )


def test_the_documented_example_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    doc = (REPO / "docs" / "editor.md").read_text()
    example = doc[doc.index("new lab\n") : doc.index("screenshot lab.png\n")]
    monkeypatch.chdir(tmp_path)
    app = app_for()
    run_text(app, example + "screenshot lab.png\n")
    assert load_arena("lab.yaml").walls == ((0, 0), (240, 0), (240, 192), (0, 192))
    d = app.drive.env.config.actions.move_action_distance
    assert app.drive.pose[:2] == pytest.approx((48 + 3 * d, 48))
    assert (tmp_path / "lab.png").is_file()


@pytest.mark.parametrize(
    "size, view_line",
    [
        ((1280, 720), "view fit"),
        ((1000, 600), "view fit"),
        ((1600, 900), "view fit"),
        ((1280, 720), "view 1200 92 1.2"),
        ((1280, 720), "view 800 44 3"),
    ],
)
def test_edge_lengths_keep_clear_of_the_door_labels(size: tuple[int, int], view_line: str) -> None:
    """Issue 20: with --doors the lengths of the long hallway walls covered the labels of
    doors 311 and 312. The door labels' places (computed as the viewer draws them) are
    checked against the drawn pixels, then no length may touch one."""
    from koolio_pymunk.task import drawing

    app = EditorApp(EditorModel.blank(), size)
    run_text(app, f"import_doors {REPO / 'arenas' / 'hallway_doors.yaml'}\n{view_line}\n")
    app.show_lengths = False
    app.render()
    doors = app.drawn_labels["doors"]
    assert len(doors) == 2 * len(app.model.arena.doors)
    canvas = pygame.Rect(app.camera.viewport)
    labels = doors[1::2]  # plate, label, plate, label ...
    shown = [r for r in labels if canvas.contains(r)]
    assert len(shown) >= 2
    for r in shown:  # the label's 1-pixel frame is where it was computed to be
        for inside, outside in (
            (r.topleft, (r.left - 1, r.top - 1)),
            ((r.right - 1, r.bottom - 1), (r.right, r.bottom)),
        ):
            frame = app.screen.get_at(inside)[:3]  # (the grid darkens it a little)
            assert max(abs(a - b) for a, b in zip(frame, drawing.PLATE_TEXT)) <= 15, (r, inside)
            if not any(q.collidepoint(outside) for q in doors):  # labels may touch
                assert sum(app.screen.get_at(outside)[:3]) > 300, (r, outside)  # the floor
    app.show_lengths = True
    app.render()
    lengths = app.drawn_labels["lengths"]
    assert len(lengths) >= 2
    for r in lengths:
        assert r.collidelist(doors) < 0, (r, doors[r.collidelist(doors)])
        assert r.collidelist([q for q in lengths if q is not r]) < 0


def test_a_screenshot_is_a_png_or_refused(tmp_path: Path) -> None:
    """``--screenshot`` and the script's ``screenshot`` write only ``.png`` names (they
    replaced any file with an image: newcomer audit), as ``view`` and ``plot`` do."""
    victim = tmp_path / "notes.md"
    victim.write_text("keep me\n")
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    tool = str(REPO / "tools" / "arena_editor.py")
    result = subprocess.run(
        [sys.executable, tool, "arenas/room.yaml", "--screenshot", str(victim)],
        capture_output=True, text=True, env=env, check=False, cwd=REPO,
    )  # fmt: skip
    assert result.returncode == 2
    assert result.stderr == f"koolio-pm: error: --screenshot: {victim}: must end in .png\n"
    assert victim.read_text() == "keep me\n"
    with pytest.raises(ScriptError, match=r"screenshot: .*notes\.md: must end in \.png$"):
        run_text(app_for(), f"screenshot {victim}\n")
    assert victim.read_text() == "keep me\n"
