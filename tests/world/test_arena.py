"""Arena files: loading, every rejection, built-in names, round trip, atomic save."""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import pytest
import yaml

from koolio_pymunk.store.errors import ArenaError, FileError
from koolio_pymunk.world import arena as arena_mod
from koolio_pymunk.world.arena import (
    Arena,
    Goal,
    Marker,
    Start,
    arena_path,
    arena_to_dict,
    load_arena,
    parse_arena,
    save_arena,
    validate_arena,
)

ZONE = [[80, 80], [120, 80], [120, 100], [80, 100]]
BASE: dict = {
    "name": "box",
    "walls": [[0, 0], [200, 0], [200, 100], [0, 100]],
    "goals": [{"name": "a", "at": [190, 50]}, {"name": 317, "at": [150, 50]}],
    "end_of_world": [{"at": [100, 90], "zone": ZONE}],
    "start": {"at": [30, 50], "heading_deg": None},
}
PILLAR = [[60, 20], [80, 20], [80, 40], [60, 40]]


def write(tmp_path: Path, data: object, name: str = "x.yaml") -> Path:
    path = tmp_path / name
    text = data if isinstance(data, str) else yaml.safe_dump(data, sort_keys=False)
    path.write_text(text, encoding="utf-8")
    return path


def error_of(path: Path | str) -> str:
    with pytest.raises(ArenaError) as info:
        load_arena(path)
    message = str(info.value)
    assert "\n" not in message
    return message


def variant(change: Callable[[dict], None]) -> dict:
    data = copy.deepcopy(BASE)
    change(data)
    return data


def test_base_loads(tmp_path: Path) -> None:
    path = write(tmp_path, BASE)
    arena = load_arena(str(path))
    assert arena.source == str(path)
    assert arena.goal_names() == ["a", "317"]  # int names become strings
    assert arena.active_goal == "a"
    assert arena.start == Start((30.0, 50.0), None)
    assert arena.end_of_world[0].zone is not None and len(arena.end_of_world[0].zone) == 4


def test_omitted_zone_and_boundary_zone_are_fine(tmp_path: Path) -> None:
    def change(d: dict) -> None:
        d["end_of_world"] = [
            {"at": [100, 90]},
            {"at": [10, 10], "zone": [[0, 0], [20, 0], [20, 20], [0, 20]]},
        ]

    arena = load_arena(write(tmp_path, variant(change)))
    assert arena.end_of_world[0] == Marker((100.0, 90.0), None)


def _set(path: tuple, value: object) -> Callable[[dict], None]:
    def change(d: dict) -> None:
        target = d
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value

    return change


def _drop(key: str) -> Callable[[dict], None]:
    return lambda d: d.pop(key)


def _add_obstacles(*polys: list) -> Callable[[dict], None]:
    return _set(("obstacles",), list(polys))


CASES: list[tuple[str, Callable[[dict], None], str, list[str]]] = [
    ("unknown top key", lambda d: d.update(gaols=[]), "gaols", ["unknown key", "'goals'"]),
    ("unknown goal key", _set(("goals", 1, "nmae"), "b"), "goals[1].nmae", ["'name'"]),
    (
        "unknown marker key",
        _set(("end_of_world", 0, "zoen"), ZONE),
        "end_of_world[0].zoen",
        ["unknown key", "'zone'"],
    ),
    ("unknown start key", _set(("start", "heading"), 3), "start.heading", ["'heading_deg'"]),
    (
        "unknown door key",
        _set(("doors",), [{"name": 1, "a": [0, 0], "b": [0, 9], "plate": [3, 3], "plat": 1}]),
        "doors[0].plat",
        ["unknown key", "'plate'"],
    ),
    ("missing name", _drop("name"), "name", ["missing required key"]),
    ("missing walls", _drop("walls"), "walls", ["missing required key"]),
    ("missing goals", _drop("goals"), "goals", ["missing required key"]),
    ("missing start", _drop("start"), "start", ["missing required key"]),
    ("missing goal at", lambda d: d["goals"][1].pop("at"), "goals[1].at", ["missing"]),
    (
        "coordinate text",
        _set(("goals", 1, "at"), [1, "abc"]),
        "goals[1].at",
        ["not a number: 'abc'"],
    ),
    ("coordinate bool", _set(("walls", 2), [True, 3]), "walls[2]", ["not a number: True"]),
    ("coordinate nan", _set(("walls", 1), [float("nan"), 0]), "walls[1]", ["not a finite"]),
    ("coordinate inf", _set(("start", "at"), [30, float("inf")]), "start.at", ["not a finite"]),
    ("not a pair", _set(("walls", 2), [1, 2, 3]), "walls[2]", ["not a point"]),
    ("scalar point", _set(("walls", 2), 7), "walls[2]", ["not a point"]),
    ("walls not a list", _set(("walls",), "square"), "walls", ["not a list"]),
    ("two wall points", _set(("walls",), [[0, 0], [10, 0]]), "walls", ["fewer than 3"]),
    (
        "repeated point",
        _set(("walls",), [[0, 0], [10, 20], [200, 0], [10, 20], [0, 100]]),
        "walls[3]",
        ["repeated point (10, 20), same as walls[1]"],
    ),
    (
        "zero-length edge",
        _set(("walls",), [[0, 0], [200, 0], [200, 0], [200, 100], [0, 100]]),
        "walls[2]",
        ["repeated point (200, 0)", "zero-length"],
    ),
    (
        "bow-tie walls",
        _set(("walls",), [[0, 0], [200, 100], [200, 0], [0, 100]]),
        "walls[2]",
        ["self-intersecting", "walls[0]-walls[1]"],
    ),
    (
        "folded walls",
        _set(("walls",), [[0, 0], [200, 0], [100, 0]]),
        "walls[1]",
        ["self-intersecting", "walls[1]-walls[2] meets edge walls[0]-walls[1]"],
    ),
    (
        "obstacle repeated point",
        _add_obstacles([[60, 20], [80, 20], [60, 20], [60, 40]]),
        "obstacles[0][2]",
        ["repeated point (60, 20)"],
    ),
    (
        "obstacle self-intersecting",
        _add_obstacles([[60, 20], [80, 40], [80, 20], [60, 40]]),
        "obstacles[0][2]",
        ["self-intersecting"],
    ),
    ("obstacle two points", _add_obstacles([[60, 20], [80, 20]]), "obstacles[0]", ["fewer than 3"]),
    (
        "obstacle outside",
        _add_obstacles([[300, 20], [320, 20], [320, 40]]),
        "obstacles[0][0]",
        ["outside the walls"],
    ),
    (
        "obstacle crossing walls",
        _add_obstacles([[60, 50], [80, 50], [80, 120], [60, 120]]),
        "obstacles[0][2]",
        ["outside the walls"],
    ),
    (
        "obstacle spanning the room",
        _add_obstacles([[-10, 40], [210, 40], [210, 60], [-10, 60]]),
        "obstacles[0][0]",
        ["outside the walls"],
    ),
    (
        "obstacle touching walls",
        _add_obstacles([[60, 0], [80, 20], [60, 20]]),
        "obstacles[0][0]",
        ["outside the walls (or on them)"],
    ),
    (
        "obstacles crossing",
        _add_obstacles(PILLAR, [[70, 30], [90, 30], [90, 45], [70, 45]]),
        "obstacles[1]",
        ["crosses or touches obstacles[0]"],
    ),
    (
        "obstacle inside obstacle",
        _add_obstacles(PILLAR, [[65, 25], [75, 25], [75, 35]]),
        "obstacles[1]",
        ["inside obstacles[0]"],
    ),
    (
        "obstacle around obstacle",
        _add_obstacles([[65, 25], [75, 25], [75, 35]], PILLAR),
        "obstacles[1]",
        ["contains obstacles[0]"],
    ),
    ("goal outside", _set(("goals", 1, "at"), [250, 50]), "goals[1].at", ["outside the walls"]),
    ("goal on the wall", _set(("goals", 0, "at"), [200, 50]), "goals[0].at", ["outside the walls"]),
    (
        "goal in obstacle",
        lambda d: (d.update(obstacles=[PILLAR]), d["goals"][1].update(at=[70, 30])),
        "goals[1].at",
        ["inside obstacles[0]"],
    ),
    (
        "goal on obstacle edge",
        lambda d: (d.update(obstacles=[PILLAR]), d["goals"][1].update(at=[60, 30])),
        "goals[1].at",
        ["inside obstacles[0]"],
    ),
    (
        "marker outside",
        _set(("end_of_world", 0, "at"), [100, 120]),
        "end_of_world[0].at",
        ["outside the walls"],
    ),
    (
        "marker in obstacle",
        lambda d: (d.update(obstacles=[PILLAR]), d["end_of_world"][0].update(at=[70, 30])),
        "end_of_world[0].at",
        ["inside obstacles[0]"],
    ),
    (
        "zone two points",
        _set(("end_of_world", 0, "zone"), [[80, 80], [120, 80]]),
        "end_of_world[0].zone",
        ["fewer than 3"],
    ),
    (
        "zone self-intersecting",
        _set(("end_of_world", 0, "zone"), [[80, 80], [120, 100], [120, 80], [80, 100]]),
        "end_of_world[0].zone[2]",
        ["self-intersecting"],
    ),
    (
        "zone outside",
        _set(("end_of_world", 0, "zone"), [[80, 80], [120, 80], [120, 110]]),
        "end_of_world[0].zone[2]",
        ["outside the walls"],
    ),
    ("start outside", _set(("start", "at"), [-30, 50]), "start.at", ["outside the walls"]),
    (
        "start in obstacle",
        lambda d: (d.update(obstacles=[PILLAR]), d["start"].update(at=[70, 30])),
        "start.at",
        ["inside obstacles[0]"],
    ),
    (
        "start touching wall",
        _set(("start", "at"), [10, 50]),
        "start.at",
        ["overlaps or touches", "walls[3]-walls[0]"],
    ),
    (
        "start overlapping wall",
        _set(("start", "at"), [30, 95]),
        "start.at",
        ["overlaps or touches", "walls[2]-walls[3]"],
    ),
    (
        "start touching obstacle",
        lambda d: (d.update(obstacles=[PILLAR]), d["start"].update(at=[70, 50])),
        "start.at",
        ["overlaps or touches", "obstacles[0][2]-obstacles[0][3]"],
    ),
    (
        "door plate outside",
        _set(("doors",), [{"name": 1, "a": [0, 40], "b": [0, 60], "plate": [-1, 65]}]),
        "doors[0].plate",
        ["outside the walls"],
    ),
    (
        "duplicate goal",
        _set(("goals", 0, "name"), "317"),
        "goals[1].name",
        ["duplicate goal name '317'", "goals[0]"],
    ),
    (
        "unknown active goal",
        _set(("active_goal",), 371),
        "active_goal",
        ["unknown goal '371'", "did you mean '317'?"],
    ),
    (
        "heading text",
        _set(("start", "heading_deg"), "north"),
        "start.heading_deg",
        ["not a number or null"],
    ),
    (
        "heading nan",
        _set(("start", "heading_deg"), float("nan")),
        "start.heading_deg",
        ["not a finite"],
    ),
    ("rotate text", _set(("rotate_deg",), "five"), "rotate_deg", ["not a finite number"]),
    ("rotate inf", _set(("rotate_deg",), float("inf")), "rotate_deg", ["not a finite number"]),
    ("rotate bool", _set(("rotate_deg",), True), "rotate_deg", ["not a finite"]),
    ("empty goals", _set(("goals",), []), "goals", ["empty list"]),
    ("goal name float", _set(("goals", 0, "name"), 1.5), "goals[0].name", ["not a name"]),
    ("goal not a mapping", _set(("goals", 0), [1, 2]), "goals[0]", ["not a mapping"]),
    ("name not a string", _set(("name",), ["x"]), "name", ["not a non-empty string"]),
]


@pytest.mark.parametrize(
    ("change", "item", "words"), [c[1:] for c in CASES], ids=[c[0] for c in CASES]
)
def test_rejections(
    tmp_path: Path, change: Callable[[dict], None], item: str, words: list[str]
) -> None:
    path = write(tmp_path, variant(change), "bad.yaml")
    message = error_of(str(path))
    assert message.startswith(f"{path}: {item}: "), message
    for word in words:
        assert word in message, message


def test_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "nope.yaml"
    message = error_of(str(path))
    assert message == f"{path}: file not found"


def test_not_yaml(tmp_path: Path) -> None:
    path = write(tmp_path, "name: box\nwalls: [[0, 0], [1, 2]\ngoals: x\n", "broken.yaml")
    message = error_of(path)
    assert message.startswith(f"{path}: line ")
    assert "not valid YAML" in message


def test_not_yaml_tab_line_number(tmp_path: Path) -> None:
    path = write(tmp_path, "name: box\nwalls:\n\t- [0, 0]\n", "tab.yaml")
    assert f"{path}: line 3: not valid YAML" in error_of(path)


def test_duplicate_key(tmp_path: Path) -> None:
    text = yaml.safe_dump(BASE, sort_keys=False) + "goals: []\n"
    path = write(tmp_path, text)
    line = text.count("\n")
    assert error_of(path) == f"{path}: line {line}: not valid YAML: duplicate key 'goals'"


def test_duplicate_key_nested(tmp_path: Path) -> None:
    text = yaml.safe_dump(BASE, sort_keys=False).replace("heading_deg: null", "at: [1, 2]")
    assert "not valid YAML: duplicate key 'at'" in error_of(write(tmp_path, text))


@pytest.mark.parametrize("text", ["- 1\n- 2\n", "just text\n", "42\n"])
def test_not_a_mapping(tmp_path: Path, text: str) -> None:
    path = write(tmp_path, text)
    message = error_of(path)
    assert message.startswith(f"{path}: not a mapping")


def test_empty_file(tmp_path: Path) -> None:
    path = write(tmp_path, "")
    assert error_of(path).startswith(f"{path}: empty file")


def test_unknown_key_without_suggestion(tmp_path: Path) -> None:
    path = write(tmp_path, variant(lambda d: d.update(zzzzzz=1)))
    message = error_of(path)
    assert f"{path}: zzzzzz: unknown key (valid keys: name, walls," in message


def test_validate_arena_on_objects() -> None:
    good = Arena(
        name="t",
        walls=((0.0, 0.0), (100.0, 0.0), (100.0, 100.0), (0.0, 100.0)),
        goals=(Goal("g", (90.0, 50.0)),),
        end_of_world=(Marker((50.0, 90.0)),),
        start=Start((50.0, 50.0)),
        source="editor",
    )
    validate_arena(good)
    with pytest.raises(ArenaError, match=r"^editor: start\.at: the robot \(radius 60\)"):
        validate_arena(good, robot_radius=60)
    bad = Arena(**{**good.__dict__, "goals": (Goal("g", (150.0, 50.0)),)})
    with pytest.raises(ArenaError, match=r"^editor: goals\[0\]\.at: point \(150, 50\) is out"):
        validate_arena(bad)


def test_parse_arena_source_prefix() -> None:
    with pytest.raises(ArenaError, match=r"^live: walls: missing required key$"):
        parse_arena({k: v for k, v in BASE.items() if k != "walls"}, "live")


# -- built-in names ---------------------------------------------------------------------
@pytest.mark.parametrize("name", ["hallway", "room", "obstacles"])
def test_builtin_names(name: str) -> None:
    path = arena_path(name)
    assert path.name == f"{name}.yaml" and path.is_file()
    arena = load_arena(name)
    assert arena.name == name
    assert arena.source == str(path)


def test_names_that_are_paths() -> None:
    assert arena_path("x.yaml") == Path("x.yaml")
    assert arena_path("x.yml") == Path("x.yml")
    assert arena_path("dir/hallway") == Path("dir/hallway")
    assert arena_path(Path("hallway")) == Path("hallway")


def test_unknown_builtin_name() -> None:
    with pytest.raises(ArenaError) as info:
        load_arena("halway")
    assert "halway: no such arena" in str(info.value)
    assert "did you mean 'hallway'?" in str(info.value)


def test_wheel_dir_comes_first(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    wheel = tmp_path / "_arenas"
    wheel.mkdir()
    write(wheel, variant(_set(("name",), "from-wheel")), "room.yaml")
    repo = Path(__file__).resolve().parents[2] / "arenas"
    monkeypatch.setattr(arena_mod, "builtin_arena_dirs", lambda: [wheel, repo])
    assert load_arena("room").name == "from-wheel"
    assert load_arena("hallway").name == "hallway"  # falls back to the repo


def test_default_dirs() -> None:
    dirs = arena_mod.builtin_arena_dirs()
    package = Path(arena_mod.__file__).resolve().parents[1]
    assert dirs == [package / "_arenas", package.parent / "arenas"]


# -- round trip and saving ------------------------------------------------------------------
@pytest.mark.parametrize("name", ["hallway", "room", "obstacles"])
def test_round_trip_shipped(tmp_path: Path, name: str) -> None:
    first = load_arena(name)
    out = tmp_path / f"{name}.yaml"
    save_arena(first, out)
    second = load_arena(out)
    assert second.source == str(out)
    assert replace(second, source=first.source) == first
    assert arena_to_dict(second) == arena_to_dict(first)


def test_round_trip_keeps_floats_and_heading(tmp_path: Path) -> None:
    data = variant(_set(("start", "heading_deg"), 90.5))
    data["goals"][0]["at"] = [190.25, 50.125]
    data["rotate_deg"] = 5
    data["obstacles"] = [PILLAR]
    first = load_arena(write(tmp_path, data))
    save_arena(first, tmp_path / "y.yaml")
    second = load_arena(tmp_path / "y.yaml")
    assert second.goals == first.goals and second.start.heading_deg == 90.5
    assert replace(second, source=first.source) == first


def test_saved_key_order(tmp_path: Path) -> None:
    arena = load_arena("obstacles")
    save_arena(arena, tmp_path / "o.yaml", header="made by a test")
    text = (tmp_path / "o.yaml").read_text()
    assert text.startswith("# made by a test\n")
    keys = list(yaml.safe_load(text))
    assert keys == [
        "name",
        "walls",
        "obstacles",
        "goals",
        "active_goal",
        "end_of_world",
        "start",
        "doors",
        "rotate_deg",
    ]


def test_atomic_save_keeps_old_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = write(tmp_path, BASE, "keep.yaml")
    before = path.read_text()
    arena = load_arena(path)

    def boom(*args: object, **kwargs: object) -> str:
        raise RuntimeError("serialisation failed")

    monkeypatch.setattr(yaml, "dump", boom)  # what yamlfile.dump_yaml calls
    with pytest.raises(RuntimeError):
        save_arena(arena, path)
    assert path.read_text() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.yaml"]


def test_atomic_save_failed_write_leaves_no_temp(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = write(tmp_path, BASE, "keep.yaml")
    before = path.read_text()
    arena = load_arena(path)

    def bad_replace(src: str, dst: str) -> None:
        raise OSError("disk full")

    monkeypatch.setattr(arena_mod.os, "replace", bad_replace)
    with pytest.raises(FileError, match=r"keep\.yaml: cannot write: disk full$"):
        save_arena(arena, path)
    assert path.read_text() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.yaml"]


# -- rotation ----------------------------------------------------------------------------
def test_to_world_rotates_clockwise_5_degrees(tmp_path: Path) -> None:
    data = {
        "name": "rot",
        "walls": [[-200, -200], [200, -200], [200, 200], [-200, 200]],
        "goals": [{"name": "g", "at": [100, 50]}],
        "end_of_world": [{"at": [0, -150]}],
        "start": {"at": [0, 0], "heading_deg": 90},
        "rotate_deg": 5,
    }
    world = load_arena(write(tmp_path, data)).to_world()
    # clockwise by 5 deg: x' = x cos5 + y sin5, y' = -x sin5 + y cos5
    # cos5 = 0.9961946980917455, sin5 = 0.0871557427476582
    gx, gy = world.goal("g").at
    assert math.isclose(gx, 99.61946980917455 + 4.35778713738291, rel_tol=1e-12)
    assert math.isclose(gy, -8.71557427476582 + 49.80973490458728, rel_tol=1e-12)
    mx, my = world.end_of_world[0].at
    assert math.isclose(mx, -13.07336141214873, rel_tol=1e-12)  # -150 sin5
    assert math.isclose(my, -149.4292047137618, rel_tol=1e-12)  # -150 cos5
    assert world.start.heading_deg == 85.0
    assert world.rotate_deg == 0.0
    assert world.walls[1][0] == pytest.approx(200 * 0.9961946980917455 - 200 * 0.0871557427476582)


@pytest.mark.parametrize("change", [_drop("end_of_world"), _set(("end_of_world",), [])])
def test_an_arena_without_end_of_world_markers_is_valid(
    tmp_path: Path, change: Callable[[dict], None]
) -> None:
    """The paper: "any number" of end-of-world markers; none makes a closed room."""
    arena = load_arena(write(tmp_path, variant(change)))
    assert arena.end_of_world == ()


def test_a_door_table_given_as_an_arena_says_what_it_is() -> None:
    """``--arena hallway_doors`` is the hallway's door table: one line saying so and how
    to make an arena of it (it was an unknown key 'hallway': API audit)."""
    with pytest.raises(ArenaError) as info:
        arena_mod.load_arena("hallway_doors")
    assert str(info.value).endswith(
        "hallway_doors.yaml: a door table, not an arena (koolio-pm edit --doors FILE or "
        "tools/make_hallway.py makes an arena of it; the built-in hallway is --arena hallway)"
    )
