"""The editor's questions are pygame-gui windows (text line with the proposal selected,
confirmation dialog, file dialog); goals and markers placed by the mouse land inside the
walls; goal names stay clear of the edge lengths. Headless, through posted events."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

os.environ["SDL_VIDEODRIVER"] = "dummy"
os.environ["SDL_AUDIODRIVER"] = "dummy"

import pygame
from pygame_gui.elements import UIWindow
from pygame_gui.windows import UIConfirmationDialog, UIFileDialog

from koolio_pymunk.apps.editor.app import EditorApp
from koolio_pymunk.apps.editor.model import EditorModel
from koolio_pymunk.apps.editor.script import run_text
from koolio_pymunk.world import geometry

REPO = Path(__file__).resolve().parents[3]
ROOM = REPO / "arenas" / "room.yaml"


def selected(prompt) -> str:
    """The selected part of a question's answer (the proposal, when the question opens)."""
    if prompt.entry is None:
        return ""
    a, b = sorted(prompt.entry.select_range)
    return prompt.text[a:b]


def room_app(tmp_path: Path) -> tuple[EditorApp, Path]:
    path = tmp_path / "room.yaml"
    shutil.copy(ROOM, path)
    return EditorApp(EditorModel.from_file(path), (1000, 600)), path


def test_text_question_shows_its_proposal_selected(tmp_path: Path) -> None:
    app, _ = room_app(tmp_path)
    run_text(app, "view 144 96 2\nsnap 1\nkey g\nclick 150 100\n")
    prompt = app.prompt
    assert prompt.kind == "text" and isinstance(prompt.window, UIWindow)
    assert prompt.text == "202" and selected(prompt) == "202"  # highlighted: Backspace wipes it
    assert prompt.entry.is_focused
    # The question is drawn over the canvas: its window covers the canvas's centre.
    shot = tmp_path / "q.png"
    run_text(app, f"screenshot {shot}\n")
    assert prompt.window.rect.collidepoint(pygame.Rect(app.camera.viewport).center)
    image = pygame.image.load(str(shot))
    x, y = prompt.entry.rect.center
    assert image.get_at((x, y))[:3] != (250, 250, 246)  # not the floor
    run_text(app, "key backspace\n")
    assert prompt.text == "" and selected(prompt) == ""
    run_text(app, "type 2 0 9\nkey return\n")
    assert app.prompt is None and app.model.arena.goal_names() == ["201", "2 0 9"]
    assert not prompt.window.alive()


def test_text_question_ok_cancel_and_escape(tmp_path: Path) -> None:
    app, _ = room_app(tmp_path)
    run_text(app, "select goals[0]\nkey r\n")
    assert app.prompt.text == "201"
    run_text(app, "key escape\n")
    assert app.prompt is None and app.message == "cancelled"
    run_text(app, "key r\ntype 301\n")
    ok = app.prompt.ok
    run_text(app, f"click_screen {ok.rect.centerx} {ok.rect.centery}\n")
    assert app.prompt is None and app.model.arena.goal_names() == ["301"]
    run_text(app, "key n\n")  # arena name: Cancel with the mouse
    cancel = app.prompt.cancel
    run_text(app, f"click_screen {cancel.rect.centerx} {cancel.rect.centery}\n")
    assert app.prompt is None and app.model.arena.name == "room"


def test_confirmation_dialog_yes_only_with_y(tmp_path: Path) -> None:
    app, path = room_app(tmp_path)
    good = path.read_bytes()
    run_text(app, "move_vertex goals[0] 102 200\nkey ctrl+s\n")
    assert isinstance(app.prompt.window, UIConfirmationDialog)
    run_text(app, "key return\nkey space\n")  # neither answers: nothing is written
    assert app.prompt is not None and path.read_bytes() == good
    run_text(app, "key y\n")
    assert app.prompt is None and path.read_bytes() != good


def test_file_dialog_opens_a_typed_path(tmp_path: Path) -> None:
    app, path = room_app(tmp_path)
    other = tmp_path / "obstacles.yaml"
    shutil.copy(REPO / "arenas" / "obstacles.yaml", other)
    run_text(app, "key ctrl+o\n")
    prompt = app.prompt
    assert isinstance(prompt.window, UIFileDialog) and prompt.kind == "file"
    assert prompt.text == str(path) and selected(prompt) == str(path)  # all of it selected
    run_text(app, f"type {other}\nkey return\n")
    assert app.prompt is None and app.model.arena.name == "obstacles"
    assert app.message == f"opened {other}"


def test_file_dialog_save_as_and_a_folder_keeps_it_open(tmp_path: Path) -> None:
    app, _ = room_app(tmp_path)
    run_text(app, "key ctrl+shift+s\n")
    run_text(app, f"type {tmp_path}\nkey return\n")  # a folder: the dialog lists it
    assert app.prompt is not None and selected(app.prompt) == app.prompt.text
    run_text(app, f"type {tmp_path / 'copy.yaml'}\nkey return\n")
    assert app.prompt is None and (tmp_path / "copy.yaml").exists()


def test_goals_and_markers_placed_near_a_wall_land_inside_it(tmp_path: Path) -> None:
    """With the default 24 in snap a click near the north wall lands on the grid point
    (96, 192), on the wall; the goal goes 1 in inside instead, and is valid."""
    app, _ = room_app(tmp_path)
    assert app.model.snap_step == 24
    run_text(app, "view 144 96 2\nkey g\nmove 100 188\n")
    assert app.cursor == (96, 191)
    run_text(app, "click 100 188\nkey return\nexpect_valid\n")
    assert app.model.arena.goals[1].at == (96, 191)
    run_text(app, "key e\nclick 3 50\nexpect_valid\n")  # near the west wall
    assert app.model.arena.end_of_world[1].at == (1, 48)
    run_text(app, "key v\ndrag 96 191 140 -5\nexpect_valid\n")  # dragged past the wall
    assert app.model.arena.goals[1].at == (144, 1)
    run_text(app, "key g\nclick 120 96\nkey return\n")  # away from walls: the grid point
    assert app.model.arena.goals[-1].at == (120, 96)


def test_goal_names_keep_clear_of_edge_lengths(tmp_path: Path) -> None:
    app = EditorApp(EditorModel.blank("lab"), (1000, 600))
    run_text(
        app,
        "view 120 96 2\nkey w\nclick 0 0\nclick 240 0\nclick 240 192\nclick 0 192\n"
        "add_goal 1 120 191\nadd_goal 2 1 96\nadd_goal 3 120 1\nadd_goal 4 239 96\n",
    )
    app.render()
    lengths, names = app.drawn_labels["lengths"], app.drawn_labels["goals"]
    assert len(lengths) == 4 and len(names) == 4
    for r in names:
        assert r.collidelist(lengths) < 0
        assert r.collidelist([q for q in names if q is not r]) < 0
    walls = app.model.arena.walls
    for r in lengths:  # beside the walls, outside them: no goal or marker is covered
        assert not geometry.point_in_polygon(app.camera.to_world(r.center), walls)
