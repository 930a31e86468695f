"""The editor's door-table importer reproduces the shipped arenas/hallway.yaml."""

from __future__ import annotations

import importlib.util
import os
from dataclasses import replace
from pathlib import Path

import pytest
import yaml

os.environ["SDL_VIDEODRIVER"] = "dummy"
os.environ["SDL_AUDIODRIVER"] = "dummy"

from koolio_pymunk.apps.editor.app import EditorApp
from koolio_pymunk.apps.editor.model import EditorModel, importer_header
from koolio_pymunk.apps.editor.script import ScriptError, run_text
from koolio_pymunk.world.arena import load_arena

REPO = Path(__file__).resolve().parents[3]
DOORS = REPO / "arenas" / "hallway_doors.yaml"
HALLWAY = REPO / "arenas" / "hallway.yaml"


def body(path: Path) -> list[str]:
    """The YAML lines of an arena file (without its comment header)."""
    return [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]


def test_importer_reproduces_the_shipped_hallway(tmp_path: Path) -> None:
    m = EditorModel.blank()
    m.import_door_table(DOORS)
    assert m.problem() is None and m.path is None
    assert replace(m.arena, source="x") == replace(load_arena(HALLWAY), source="x")
    out = tmp_path / "hallway.yaml"
    assert m.save(out).saved
    assert body(out) == body(HALLWAY)  # byte for byte, apart from the comment header
    header = out.read_text().splitlines()[:3]
    assert header == [f"# {line}" for line in importer_header(DOORS).splitlines()]


def test_importer_through_the_editor_keys(tmp_path: Path) -> None:
    app = EditorApp(EditorModel.blank(), (900, 500))
    out = tmp_path / "h.yaml"
    run_text(
        app,
        f"key ctrl+d\nkey backspace\ntype {DOORS}\nkey return\n"
        f"expect_valid\nkey ctrl+s\ntype {out}\nkey return\n",
    )
    assert app.message == f"saved {out}"
    assert body(out) == body(HALLWAY)
    assert len(app.model.arena.goals) == 14 and app.model.arena.active_goal == "311"


def test_a_table_in_inches_gives_the_same_hallway(tmp_path: Path) -> None:
    table = yaml.safe_load(DOORS.read_text())
    for row in table["doors"]:
        row["inches"] = row.pop("tiles") * 24
    inches = tmp_path / "doors_in_inches.yaml"
    inches.write_text(yaml.safe_dump(table, sort_keys=False))
    app = EditorApp(EditorModel.blank(), (900, 500))
    out = tmp_path / "h.yaml"
    run_text(app, f"import_doors {inches}\nsave {out}\n")
    assert body(out) == body(HALLWAY)


def test_a_bad_table_is_refused_with_its_line(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(DOORS.read_text().replace("tiles: 9,", "tiles: 9, inches: 3,"))
    app = EditorApp(EditorModel.blank(), (900, 500))
    with pytest.raises(ScriptError) as info:
        run_text(app, f"new\nimport_doors {bad}\n")
    assert str(info.value) == (
        f"<script>:2: {bad}: doors[1]: give exactly one of tiles or inches "
        "(distance from the hallway's end)"
    )
    assert app.model.arena.walls == ()  # the document is untouched


def test_make_hallway_still_reproduces_the_shipped_file(tmp_path: Path) -> None:
    spec = importlib.util.spec_from_file_location(
        "make_hallway", REPO / "tools" / "make_hallway.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    out = tmp_path / "hallway.yaml"
    cwd = Path.cwd()
    os.chdir(REPO)
    try:
        assert module.main(["--doors", "arenas/hallway_doors.yaml", "--out", str(out)]) == 0
    finally:
        os.chdir(cwd)
    assert out.read_bytes() == HALLWAY.read_bytes()
