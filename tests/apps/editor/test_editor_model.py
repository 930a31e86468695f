"""The arena editor's model: round trips, every editing operation, undo/redo, snapping,
validation highlighting and the save rules (no pygame needed)."""

from __future__ import annotations

import doctest
import shutil
from dataclasses import replace
from pathlib import Path

import pytest

from koolio_pymunk.apps import cli
from koolio_pymunk.apps.editor import drive, items, model
from koolio_pymunk.apps.editor.items import EditError
from koolio_pymunk.apps.editor.model import EditorModel, parse_problem, parse_unchecked
from koolio_pymunk.world.arena import Arena, Door, Marker, Start, load_arena, parse_arena
from koolio_pymunk.world.arena import read_yaml as read_arena_yaml

REPO = Path(__file__).resolve().parents[3]
ARENAS = sorted((REPO / "arenas").glob("*.yaml"))
SHIPPED = [p for p in ARENAS if p.name != "hallway_doors.yaml"]


def same(a: Arena, b: Arena) -> bool:
    return replace(a, source="") == replace(b, source="")


def room() -> EditorModel:
    """A valid 240 x 192 room (no file)."""
    m = EditorModel.blank("box")
    for p in [(0, 0), (240, 0), (240, 192), (0, 192)]:
        m.add_vertex(("walls",), p)
    m.add_goal("201", (100, 191))
    m.add_marker((200, 100))
    m.set_start((48, 48))
    return m


def test_doctests() -> None:
    for module in (items, model, drive):
        result = doctest.testmod(module)
        assert result.failed == 0 and result.attempted > 0, module.__name__


# -- files ---------------------------------------------------------------------------------
def test_shipped_arenas_are_all_tested() -> None:
    assert [p.name for p in SHIPPED] == ["hallway.yaml", "obstacles.yaml", "room.yaml"]


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_round_trip_every_shipped_arena(tmp_path: Path, path: Path) -> None:
    m = EditorModel.from_file(path)
    assert m.problem() is None and not m.dirty
    out = tmp_path / path.name
    result = m.save(out)
    assert result.saved and result.backup is None and result.message == f"saved {out}"
    assert same(load_arena(out), load_arena(path))
    # the file's leading comment block is kept; a second round trip is byte-identical
    header = [ln for ln in path.read_text().splitlines() if ln.startswith("#")]
    assert out.read_text().splitlines()[: len(header)] == header[: len(header)]
    again = tmp_path / f"again-{path.name}"
    EditorModel.from_file(out).save(again)
    assert again.read_bytes() == out.read_bytes()


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_parse_unchecked_matches_the_core_parser(path: Path) -> None:
    data = read_arena_yaml(path, str(path))
    assert parse_unchecked(data, str(path)) == parse_arena(data, str(path))


def test_open_keeps_an_invalid_file_and_refuses_a_malformed_one(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    text = (REPO / "arenas" / "room.yaml").read_text().replace("[48, 48]", "[5, 5]")
    bad.write_text(text)
    m = EditorModel.from_file(bad)
    assert m.arena.start.at == (5, 5)
    assert m.problem().item == "start.at"
    broken = tmp_path / "broken.yaml"
    broken.write_text("name: x\nwals: []\n")
    with pytest.raises(model.ArenaError, match=r"broken\.yaml: wals: unknown key"):
        EditorModel.from_file(broken)


# -- editing operations ------------------------------------------------------------------
def test_vertices_add_insert_move_delete() -> None:
    m = room()
    assert m.insert_vertex(("walls",), 1, (240, 96)) == ("walls", 2)
    assert m.arena.walls == ((0, 0), (240, 0), (240, 96), (240, 192), (0, 192))
    assert m.insert_vertex(("walls",), 4, (0, 96)) == ("walls", 5)  # last edge: back to 0
    assert m.arena.walls[-1] == (0, 96)
    m.move_point(("walls", 2), (288, 96))
    assert m.arena.walls[2] == (288, 96)
    m.delete(("walls", 2))
    m.delete(("walls", 4))
    assert m.arena.walls == ((0, 0), (240, 0), (240, 192), (0, 192))
    with pytest.raises(EditError, match=r"^walls: no edge 4 \(there are 4 edges\)$"):
        m.insert_vertex(("walls",), 4, (1, 1))
    with pytest.raises(EditError, match=r"^walls\[9\]: no such item \(there are 4\)$"):
        m.move_point(("walls", 9), (1, 1))


def test_obstacles() -> None:
    m = room()
    assert m.add_obstacle([(96, 72), (144, 72)]) == ("obstacles", 0)
    assert (
        m.problem().message
        == "<untitled>: obstacles[0]: fewer than 3 points (2): not a closed polygon"
    )
    assert m.add_vertex(("obstacles", 0), (120, 120)) == ("obstacles", 0, 2)
    assert m.problem() is None
    m.translate(("obstacles", 0), 24, -24)
    assert m.arena.obstacles == (((120, 48), (168, 48), (144, 96)),)
    m.insert_vertex(("obstacles", 0), 0, (144, 24))
    assert m.arena.obstacles[0][1] == (144, 24)
    for _ in range(4):
        m.delete(("obstacles", 0, 0))
    assert m.arena.obstacles == ()  # the last vertex takes the obstacle with it
    m.add_obstacle([(10, 10), (20, 10), (15, 20)])
    m.delete(("obstacles", 0))
    assert m.arena.obstacles == ()


def test_goals_names_active_and_doors() -> None:
    m = EditorModel.from_file(REPO / "arenas" / "room.yaml")
    assert m.arena.doors == (Door("201", (60, 192), (96, 192), (102, 191)),)
    assert m.add_goal("202", (150, 191)) == ("goals", 1)
    with pytest.raises(EditError, match=r"^goals: there is already a goal named '202'$"):
        m.add_goal("202", (10, 10))
    with pytest.raises(EditError, match=r"^goals: a goal needs a name"):
        m.add_goal("  ", (10, 10))
    m.move_point(("goals", 0), (110, 191))  # the door's plate was on the goal: it follows
    assert m.arena.doors[0].plate == (110, 191)
    m.rename_goal("201", "201A")  # the door and the active goal follow the name
    assert m.arena.goal_names() == ["201A", "202"]
    assert m.arena.doors[0].name == "201A" and m.arena.active_goal == "201A"
    m.set_active_goal("202")
    assert m.arena.active_goal == "202"
    with pytest.raises(EditError, match=r"^goals: no goal named '7' \(goals: 201A, 202\)$"):
        m.set_active_goal("7")
    m.delete(("goals", 1))  # the active goal: the first remaining one becomes active
    assert m.arena.goal_names() == ["201A"] and m.arena.active_goal == "201A"
    assert m.next_goal_name() == "2"
    m.add_goal("317", (50, 50))
    assert m.next_goal_name() == "318"


def test_markers_zones_start_name_rotation() -> None:
    m = room()
    assert m.add_marker((24, 96), [(0, 72), (48, 72), (48, 120)]) == ("end_of_world", 1)
    assert m.arena.end_of_world[1] == Marker((24, 96), ((0, 72), (48, 72), (48, 120)))
    m.translate(("end_of_world", 1, "zone"), 24, 0)
    assert m.arena.end_of_world[1].zone == ((24, 72), (72, 72), (72, 120))
    m.move_point(("end_of_world", 1, "zone", 0), (30, 70))
    assert m.arena.end_of_world[1].zone[0] == (30, 70)
    m.delete(("end_of_world", 1, "zone"))
    assert m.arena.end_of_world[1].zone is None
    m.set_zone(1, [(1, 1), (47, 1), (47, 47)])
    m.set_zone(1, None)
    assert m.arena.end_of_world[1] == Marker((24, 96), None)
    m.move_point(("end_of_world", 1), (30, 90))
    m.delete(("end_of_world", 0))
    assert m.arena.end_of_world == (Marker((30, 90), None),)
    m.set_start((72, 72))
    m.set_heading(370)
    assert m.arena.start == Start((72, 72), 10)
    m.set_heading(None)
    assert m.arena.start.heading_deg is None
    with pytest.raises(EditError, match=r"^start: the start cannot be deleted"):
        m.delete(("start",))
    m.set_name("lab")
    m.set_rotate(5)
    assert (m.arena.name, m.arena.rotate_deg) == ("lab", 5)


def test_item_paths() -> None:
    for text, path in [
        ("walls", ("walls",)),
        ("walls[3]", ("walls", 3)),
        ("obstacles[0][2]", ("obstacles", 0, 2)),
        ("goals[1].at", ("goals", 1)),
        ("start.at", ("start",)),
        ("end_of_world[1].zone[2]", ("end_of_world", 1, "zone", 2)),
    ]:
        assert items.parse_path(text) == path
    assert items.path_str(("end_of_world", 1, "zone", 2)) == "end_of_world[1].zone[2]"
    with pytest.raises(EditError, match=r"^walls\[x\]: not an item path"):
        items.parse_path("walls[x]")


def test_picking() -> None:
    arena = load_arena("room")
    assert items.pick_point(arena, (241, 71), 3) == ("walls", 2)
    assert items.pick_point(arena, (250, 50), 3) is None
    # a zone vertex on a wall corner: the walls win, unless the zone is selected
    assert items.pick_point(arena, (240, 72), 1) == ("walls", 2)
    zone = ("end_of_world", 0, "zone")
    assert items.pick_point(arena, (240, 72), 1, prefer=zone) == (*zone, 0)
    assert items.pick_segment(arena, (120, 2), 3) == (("walls",), 0, (120, 0))
    assert items.pick_area(arena, (260, 100)) == zone


# -- snapping --------------------------------------------------------------------------------
def test_snapping() -> None:
    m = room()
    assert m.snap((37, 13)) == (48, 24)  # default: one tile (24 in)
    m.snap_step = 6
    assert m.snap((37, 13)) == (36, 12)
    m.snap_step = None  # off: 0.01 in
    assert m.snap((37.123, 13.456)) == (37.12, 13.46)
    m.snap_step = 24
    assert m.snap((238, 3), vertex_tol=5) == (240, 0)  # an existing vertex beats the grid
    assert m.snap((238, 3), vertex_tol=5, exclude=("walls", 1)) == (240, 0)  # the grid point
    assert m.snap((101, 189), vertex_tol=5) == (100, 191)  # the goal


# -- undo / redo ----------------------------------------------------------------------------
def test_undo_redo() -> None:
    m = room()
    first = m.arena
    m.move_point(("walls", 1), (264, 0))
    m.add_goal("202", (150, 150))
    m.delete(("goals", 0))
    last = m.arena
    assert [e.label for e in m.undo_stack[-3:]] == [
        "move walls[1] to (264, 0)",
        "add goal '202' at (150, 150)",
        "delete goals[0]",
    ]
    assert m.undo() == "delete goals[0]"
    assert m.undo() == "add goal '202' at (150, 150)"
    assert m.undo() == "move walls[1] to (264, 0)"
    assert m.arena == first
    assert m.redo() == "move walls[1] to (264, 0)"
    m.redo(), m.redo()
    assert m.arena == last and m.redo() is None
    m.undo()
    m.set_name("other")  # a new edit forgets what could be redone
    assert m.redo() is None
    n = len(m.undo_stack)
    m.set_name("other")  # no change, no edit
    m.move_point(("walls", 0), (0, 0))
    assert len(m.undo_stack) == n
    while m.undo():
        pass
    assert m.arena.walls == () and m.arena.name == "box"


def test_drag_is_one_edit() -> None:
    m = room()
    n = len(m.undo_stack)
    m.begin_drag()
    for x in (250, 260, 270, 288):
        m.drag_move(("walls", 1), (x, 0))
    assert m.arena.walls[1] == (288, 0) and len(m.undo_stack) == n
    assert m.end_drag("move walls[1]")
    assert len(m.undo_stack) == n + 1
    m.undo()
    assert m.arena.walls[1] == (240, 0)
    m.begin_drag()
    m.drag_translate(("goals", 0), 10, -10)
    m.cancel_drag()
    assert m.arena.goals[0].at == (100, 191) and len(m.undo_stack) == n


# -- validation highlighting ------------------------------------------------------------------
HIGHLIGHTS = [
    (
        lambda m: m.move_point(("walls", 1), (-10, 100)),
        "walls[3]",
        "self-intersecting polygon: edge walls[3]-walls[0] meets edge walls[1]-walls[2]",
        (("walls", 3),),
        ((("walls",), 3), (("walls",), 1)),
    ),
    (
        lambda m: m.add_obstacle([(200, 20), (260, 20), (230, 60)]),
        "obstacles[0][1]",
        "point (260, 20) is outside the walls (or on them)",
        (("obstacles", 0, 1),),
        (),
    ),
    (
        lambda m: m.add_obstacle([(200, 20), (240, 20), (230, 60)]),
        "obstacles[0][1]",
        "point (240, 20) is outside the walls (or on them)",
        (("obstacles", 0, 1),),
        (),
    ),
    (
        lambda m: (
            m.add_obstacle([(10, 10), (50, 10), (30, 40)]),
            m.add_obstacle([(20, 15), (40, 15), (30, 60)]),
        ),
        "obstacles[1]",
        "crosses or touches obstacles[0]",
        (("obstacles", 1), ("obstacles", 0)),
        (),
    ),
    (
        lambda m: m.add_goal("8", (400, 1)),
        "goals[1].at",
        "point (400, 1) is outside the walls (or on them)",
        (("goals", 1),),
        (),
    ),
    (
        lambda m: m.set_start((5, 100)),
        "start.at",
        "the robot (radius 10) at (5, 100) overlaps or touches edge walls[3]-walls[0] (distance 5)",
        (("start",),),
        ((("walls",), 3),),
    ),
    (
        lambda m: m.set_zone(0, [(190, 90), (210, 90), (250, 110)]),
        "end_of_world[0].zone[2]",
        "point (250, 110) is outside the walls",
        (("end_of_world", 0, "zone", 2),),
        (),
    ),
]


def test_an_arena_without_end_of_world_markers_is_valid() -> None:
    m = room()
    m.delete(("end_of_world", 0))
    assert m.arena.end_of_world == () and m.problem() is None


@pytest.mark.parametrize(("change", "item", "problem", "paths", "edges"), HIGHLIGHTS)
def test_validator_highlighting(change, item, problem, paths, edges) -> None:
    m = room()
    assert m.problem() is None
    change(m)
    found = m.problem()
    assert found.message == f"<untitled>: {item}: {problem}"
    assert (found.item, found.paths, found.edges) == (item, paths, edges)


def test_parse_problem_of_an_obstacle_crossing_the_walls() -> None:
    msg = "a.yaml: obstacles[1]: crosses or touches the walls (edge obstacles[1][2] meets walls[5])"
    p = parse_problem(msg, "a.yaml")
    assert p.paths == (("obstacles", 1),)
    assert p.edges == ((("obstacles", 1), 2), (("walls",), 5))
    dup = parse_problem(
        "a.yaml: goals[3].name: duplicate goal name '1', same as goals[0]", "a.yaml"
    )
    assert dup.paths == (("goals", 3), ("goals", 0))


def test_message_is_the_one_check_arena_prints(tmp_path: Path, capsys) -> None:
    path = tmp_path / "lab.yaml"
    m = room()
    m.move_point(("goals", 0), (100, 200))
    result = m.save(path, confirm=True)
    assert result.saved and result.message == f"saved invalid arena {path}"
    assert cli.main(["check-arena", str(path)]) == 2
    printed = capsys.readouterr().err.strip()
    reopened = EditorModel.from_file(path)
    assert printed == f"koolio-pm: error: {reopened.problem().message}"
    assert m.problem().message == reopened.problem().message
    assert (
        reopened.problem().message
        == f"{path}: goals[0].at: point (100, 200) is outside the walls (or on them)"
    )


# -- saving -------------------------------------------------------------------------------------
def test_saving_an_invalid_arena_asks_and_keeps_the_good_file(tmp_path: Path) -> None:
    path = tmp_path / "room.yaml"
    shutil.copy(REPO / "arenas" / "room.yaml", path)
    good = path.read_bytes()
    m = EditorModel.from_file(path)
    m.move_point(("walls", 1), (-10, 100))
    result = m.save()
    assert not result.saved and result.needs_confirmation
    assert result.message.startswith(f"{path}: walls[7]: self-intersecting polygon")
    assert path.read_bytes() == good and m.dirty
    result = m.save(confirm=True)
    assert result.saved and result.backup == tmp_path / "room.yaml.bak"
    assert (
        result.message
        == f"saved invalid arena {path} (the previous valid file is kept as {result.backup})"
    )
    assert result.backup.read_bytes() == good and not m.dirty
    assert EditorModel.from_file(path).arena.walls[1] == (-10, 100)
    # the file on disk is invalid now: overwriting it again makes no backup of it
    m.move_point(("walls", 2), (250, 80))
    assert m.save(confirm=True).backup is None
    assert result.backup.read_bytes() == good
    # fixed: saved without a question
    m.undo(), m.undo()
    assert m.save() == model.SaveResult(True, path, f"saved {path}")
    assert same(load_arena(path), load_arena("room"))


def test_save_needs_a_file_name_and_names_the_document(tmp_path: Path) -> None:
    m = room()
    with pytest.raises(EditError, match=r"^<untitled>: no file name yet: save as FILE$"):
        m.save()
    m.set_path(tmp_path / "x.yaml")
    m.move_point(("goals", 0), (100, 300))
    assert m.problem().message.startswith(f"{tmp_path / 'x.yaml'}: goals[0].at:")
    m.undo()
    m.save()
    text = (tmp_path / "x.yaml").read_text()
    assert text.startswith(f"# {model.NEW_HEADER}\nname: box\nwalls:\n- [0, 0]\n")


def test_blank_arena() -> None:
    m = EditorModel.blank()
    assert m.arena == Arena("untitled", (), (), (), Start((0, 0)), source="<untitled>")
    assert m.problem().message == "<untitled>: walls: fewer than 3 points (0): not a closed polygon"
    assert m.problem().paths == (("walls",),) and m.dirty


def test_deleting_the_last_marker_leaves_a_valid_closed_room() -> None:
    m = room()
    m.delete(("end_of_world", 0))
    assert m.arena.end_of_world == () and m.problem() is None
