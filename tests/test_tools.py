"""tools/irsim_compare.py without ir-sim (not a dependency, not installed in CI): the one
line saying how to install it and exit 2, the world file it writes for IR-SIM, and
bench.py's IR-SIM row skipped with a note, and every section of bench.py run on tiny
budgets. Its timings are never asserted.

The subprocess's import system cannot find ``irsim`` (a finder first in
``sys.meta_path`` raises ``ModuleNotFoundError`` for it, as an interpreter without it
does), so these tests hold whether or not ir-sim is installed.
"""

from __future__ import annotations

import contextlib
import doctest
import importlib
import io
import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
import yaml

from koolio_pymunk.world.arena import load_arena
from koolio_pymunk.world.geometry import point_in_polygon

REPO = Path(__file__).resolve().parents[1]
TOOL = REPO / "tools" / "irsim_compare.py"
INCH = 0.0254

WITHOUT_IRSIM = textwrap.dedent(
    """
    import importlib.abc, runpy, sys

    class _NotInstalled(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name.partition(".")[0] == "irsim":
                raise ModuleNotFoundError(f"No module named {name!r}", name=name)
            return None

    sys.meta_path.insert(0, _NotInstalled())
    sys.modules.pop("irsim", None)
    """
)


def tool_without_irsim(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    code = WITHOUT_IRSIM + (
        f"sys.argv = [{str(TOOL)!r}, *{args!r}]\nrunpy.run_path({str(TOOL)!r}, run_name='__main__')"
    )
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=cwd, timeout=300
    )


@pytest.fixture()
def tools(monkeypatch: pytest.MonkeyPatch):
    """The ``irsim_world`` and ``bench`` modules, imported from tools/ (ir-sim hidden)."""
    monkeypatch.syspath_prepend(str(REPO / "tools"))
    monkeypatch.setitem(sys.modules, "irsim", None)  # ``import irsim`` fails
    return importlib.import_module("irsim_world"), importlib.import_module("bench")


def test_without_irsim_one_line_and_exit_2(tmp_path: Path) -> None:
    p = tool_without_irsim([], tmp_path)
    assert p.returncode == 2, p.stderr
    assert p.stdout == ""
    assert p.stderr == (
        "tools/irsim_compare.py: ir-sim is not installed: pip install -e '.[compare]'\n"
    )
    assert not list(tmp_path.iterdir())  # nothing timed, nothing written


def test_the_world_file_is_the_hallway_in_metres(tmp_path: Path) -> None:
    """``--write-world`` needs no ir-sim; the file holds the hallway's walls, koolio's
    robot, an 88-beam lidar as long as the sonar's reach from the centre, and moves of 12
    in and 30 degrees a step."""
    p = tool_without_irsim(["--write-world", "w.yaml", "--collision", "stop"], tmp_path)
    assert p.returncode == 0, p.stderr
    world = yaml.safe_load((tmp_path / "w.yaml").read_text())
    arena = load_arena("hallway")
    (wall,) = world["obstacle"]
    ring = [*arena.walls, arena.walls[0]]
    assert wall["shape"]["name"] == "linestring"
    got = [c for v in wall["shape"]["vertices"] for c in v]
    assert got == pytest.approx([c * INCH for v in ring for c in v])
    assert wall["state"] == [0.0, 0.0, 0.0]  # IR-SIM would shift it to [1, 1] otherwise
    (robot,) = world["robot"]
    assert robot["shape"] == {"name": "circle", "radius": pytest.approx(10 * INCH)}
    assert robot["state"][:2] == pytest.approx([72 * INCH, 44 * INCH])
    assert robot["vel_max"] == pytest.approx([12 * INCH, 0.5235987756])
    (lidar,) = robot["sensors"]
    assert lidar["number"] == 88 and lidar["range_max"] == pytest.approx(250 * INCH)
    assert world["world"]["step_time"] == 1.0 and world["world"]["collision_mode"] == "stop"
    x0, y0 = world["world"]["offset"]
    assert x0 < -48 * INCH and x0 + world["world"]["width"] > 1680 * INCH
    assert y0 < -48 * INCH and y0 + world["world"]["height"] > 136 * INCH


def test_contact_walls_are_slabs_outside_the_hallway(tools) -> None:
    irsim_world, _ = tools
    world = irsim_world.hallway_world("contact")
    arena = load_arena("hallway")
    slabs = [o["shape"] for o in world["obstacle"]]
    assert len(slabs) == len(arena.walls) and {s["name"] for s in slabs} == {"polygon"}
    for k, slab in enumerate(slabs):
        a, far_a, far_b, b = [(x / INCH, y / INCH) for x, y in slab["vertices"]]
        wall = (arena.walls[k], arena.walls[(k + 1) % len(arena.walls)])
        assert [*a, *b] == pytest.approx([*wall[0], *wall[1]])
        middle = ((far_a[0] + far_b[0]) / 2, (far_a[1] + far_b[1]) / 2)
        assert not point_in_polygon(middle, arena.walls)  # behind the wall, not inside


def test_the_tool_doctests(tools) -> None:
    irsim_world, _ = tools
    assert doctest.testmod(irsim_world).failed == 0


def test_bench_skips_its_irsim_row_with_a_note(tools, tmp_path: Path) -> None:
    _, bench = tools
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert bench.irsim_row(10, {"per_cpu_s": 1}, tmp_path) is None
    assert out.getvalue() == (
        "  IR-SIM row skipped: tools/irsim_compare.py: ir-sim is not installed: "
        "pip install -e '.[compare]'\n"
    )


def test_bench_runs_every_section_on_tiny_budgets(tools, tmp_path: Path) -> None:
    """``tools/bench.py --quick --scale 0.02``: every section but ``baseline`` (which needs
    an earlier checkout) runs and writes its rows; the figures themselves are not
    asserted."""
    _, bench = tools
    out = tmp_path / "bench.json"
    args = ["--quick", "--scale", "0.02", "--seeds", "0", "--max-episodes", "25",
            "--robots", "4", "--out", str(out)]  # fmt: skip
    with contextlib.redirect_stdout(io.StringIO()) as printed:
        assert bench.main(args) == 0
    report = json.loads(out.read_text())
    ran = set(report["section_seconds"])
    assert ran == set(bench.SECTIONS) - {"baseline"}
    keys = ("one_robot", "koolio_real", "paper_memory", "train", "eval", "checks", "robots",
            "vector", "motion", "algorithms", "step_costs", "competence", "profile",
            "arena_check", "agreement_sample")  # fmt: skip
    assert set(keys) <= set(report)
    assert report["one_robot"]["engine"]["compiled"]
    assert not report["one_robot"]["python_loop"]["compiled"]
    assert set(report["train"]) == {"fsync_second", "fsync_episode", "save_every_100",
                                    "fsync_episode_save_every_100"}  # fmt: skip
    assert report["vector"]["compiled"]["class_name"] == "KoolioVectorEnv"
    assert report["vector"]["sync"]["class_name"] == "SyncVectorEnv"
    assert report["checks"]["checks"] >= 1
    assert report["checks"]["greedy_steps"] > 0  # the checks' greedy steps were counted
    assert report["checks"]["greedy_to_training_cost_for_15"] > 0
    assert set(report["competence"]) == {"default", "one-step-q"}
    assert "engine.run" in " ".join(report["robots"]["where"]["parts"])
    assert "IR-SIM row skipped" in printed.getvalue()


def test_learning_targets_refuses_a_bad_setting_in_one_line(tmp_path: Path) -> None:
    """A mistyped ``--set`` key is one line and exit 2 before any worker starts (it was
    a worker's traceback)."""
    p = subprocess.run(
        [sys.executable, str(REPO / "tools" / "learning_targets.py"), "default",
         "--set", "learner.lambda=0.7", "--seeds", "0"],
        capture_output=True, text=True, cwd=tmp_path, timeout=300,
    )  # fmt: skip
    assert p.returncode == 2, p.stderr
    assert p.stdout == ""
    assert p.stderr == (
        "learning_targets: error: <defaults>: learner.lambda: unknown key (did you mean "
        "'trace_decay'?)\n"
    )
