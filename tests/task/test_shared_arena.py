"""Robots sharing one arena: start spots, the robot bump, leaving and entering, the engine's
twin, PettingZoo's API, and a fuzz of 8 robots per arena."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest
from move_agreement import generated_arenas

import koolio_pymunk
from koolio_pymunk.store.config import load_config
from koolio_pymunk.store.errors import ConfigError, KoolioError
from koolio_pymunk.task.shared_arena import SharedArena
from koolio_pymunk.world.physics import COLLISION_SLOP, World
from koolio_pymunk.world.start_area import StartArea

_spec = importlib.util.spec_from_file_location(
    "agreement", Path(__file__).resolve().parents[2] / "tools" / "agreement.py"
)
agreement = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(agreement)

BOX = [((0, 0), (200, 0)), ((200, 0), (200, 100)), ((200, 100), (0, 100)), ((0, 100), (0, 0))]


def test_start_spots_of_a_hand_built_box() -> None:
    """Spots 28 in apart (diameter 20 + gap 8) within 40 in of (50, 50), 8 in clear of the
    walls: the 5 grid points at distance 0 and 28 (the diagonals, 39.6 in, too; the
    points 28 in below and above stand 12 in from a wall)."""
    world = World(BOX, radius=10, n_robots=3, shared=True)
    area = StartArea(world, (50.0, 50.0), spread=40.0, gap=8.0)
    assert area.spots.tolist() == [
        [50.0, 50.0],
        [22.0, 50.0],
        [50.0, 22.0],
        [50.0, 78.0],
        [78.0, 50.0],
        [22.0, 22.0],
        [22.0, 78.0],
        [78.0, 22.0],
        [78.0, 78.0],
    ]
    world.place(0, (60.0, 50.0), 0.0)  # covers the start and (78, 50): 10 and 18 in away
    assert area.free(1) == [1, 2, 3, 5, 6, 7, 8]
    assert area.free(0) == list(range(9))  # a robot never covers a spot for itself
    world.park(0)
    assert area.free(1) == list(range(9))  # a robot that left covers nothing


def test_spots_stay_out_of_walls_end_zones_and_what_the_start_cannot_see() -> None:
    """The hallway: one row of spots along its centre line, none in the end-of-world zone
    at x < 0 and none beyond the walls (the T's arms are out of sight of the start)."""
    env = SharedArena.envs(2, "hallway")[0]
    spots = env.share.areas[0].spots
    assert spots.tolist() == [[72, 44], [44, 44], [100, 44], [16, 44], [128, 44], [156, 44]]


def test_more_robots_than_the_start_area_holds_are_refused_in_one_line() -> None:
    with pytest.raises(ConfigError) as e:
        SharedArena.envs(7, "hallway")
    assert "7 robots start from (72, 44), whose start area holds 6" in str(e.value)
    assert "\n" not in str(e.value)
    cfg = load_config(overrides={"shared": {"start_spread": 200}})
    assert len(SharedArena.envs(8, "hallway", cfg)) == 8


def test_robot_goals_and_starts_of_the_configuration() -> None:
    cfg = load_config(overrides={"shared": {"starts": [[1560, 44]], "goals": ["302", "311"]}})
    envs = SharedArena.envs(3, "hallway", cfg, goal="316")
    assert [e.goal_name for e in envs] == ["302", "311", "316"]
    assert envs[0].share.areas[0].start == (1560.0, 44.0)
    assert envs[1].share.areas[1].start == envs[2].share.areas[2].start == (72.0, 44.0)
    with pytest.raises(ConfigError, match=r"shared.goals\[1\]: no goal named '999'"):
        SharedArena.envs(2, "hallway", load_config(overrides={"shared": {"goals": ["311", "999"]}}))


@pytest.mark.parametrize(
    ("point", "problem"),
    [
        ([5000, 44], "point (5000, 44) is outside the walls"),
        ([400, 5], "the robot (radius 10) at (400, 5) overlaps or touches edge"),
    ],
)
def test_a_robot_start_outside_the_hallway_is_one_line(point, problem) -> None:
    """``shared.starts`` is held to the arena's own start rule: inside the walls, clear of
    every edge (else robots would start outside the building, reading nothing)."""
    cfg = load_config(overrides={"shared": {"starts": [point]}})
    with pytest.raises(KoolioError) as e:
        SharedArena.envs(2, "hallway", cfg)
    assert "shared.starts[0]: " + problem in str(e.value)
    assert "\n" not in str(e.value)


def test_driving_into_another_robot_is_a_robot_bump() -> None:
    """Robot 1 stands 40 in ahead of robot 0 in the hallway; robot 0 drives Forward until
    its sonar reads the other robot as Bump: the event is ``robot_bump`` with the configured
    reward, the move stopped short of the other robot."""
    cfg = load_config(overrides={"rewards": {"robot_bump": -13.0}})
    envs = SharedArena.envs(2, "hallway", cfg)
    a, b = envs
    a.reset(seed=0, options={"heading": 0.0})
    b.reset(seed=1)
    a.world.place(0, (400.0, 44.0), 0.0)
    b.world.place(1, (440.0, 44.0), math.pi)
    events = []
    for _ in range(4):
        _, reward, *_ = a.simulate(3)
        events.append((a.judgement.event, reward))
    assert events[-1] == ("robot_bump", -13.0)
    assert ("bump", -5.0) not in events
    x = a.world.pose(0)[0]
    assert 440.0 - x >= 20.0 - 1e-6  # stopped at the other robot, not through it
    assert a.observe()[1]["reward_terms"]["robot_bump"] == -13.0


def test_a_finished_robot_leaves_and_a_new_episode_waits_for_a_free_spot() -> None:
    """Three spots (``start_spread`` 28: x = 44, 72, 100 on the centre line); robots 0 and
    1 stand between them and cover all three, so robot 2's episode waits outside (no draw
    made) until robot 1 has driven 28 in away from the spot at x = 100."""
    cfg = load_config(overrides={"shared": {"start_spread": 28}})
    a, b, c = SharedArena.envs(3, "hallway", cfg)
    assert a.share.areas[0].spots.tolist() == [[72, 44], [44, 44], [100, 44]]
    a.reset(seed=0)
    b.reset(seed=1, options={"heading": 0.0})
    a.world.place(0, (58.0, 44.0), 0.0)
    b.world.place(1, (114.0, 44.0), 0.0)
    c.reset(seed=2)
    assert c.waiting and c.world.present.tolist() == [True, True, False]
    state = c.np_random.bit_generator.state
    assert not c.enter() and c.np_random.bit_generator.state == state
    b.simulate(3)
    assert not c.enter()  # 26 in from the spot at x = 100: still covered
    b.simulate(3)
    assert c.enter() and not c.waiting
    assert c.world.pose(2)[:2] == (100.0, 44.0)
    b.leave()
    assert c.world.present.tolist() == [True, False, True]


#: Three spots for three robots and short episodes: robots wait for a spot (the premise test).
CROWDED = {"shared": {"start_spread": 28}}


@pytest.mark.parametrize(
    ("arena", "world", "overrides", "n", "max_steps"),
    [
        ("hallway", None, {}, 4, 300),
        (
            "room",
            "koolio-real",
            {"rescue": {"max_steps_before_rescue": 3, "rescue_chance": 0.5}},
            3,
            300,
        ),
        ("hallway", None, {"learner": {"algorithm": "q", "no_undo": False}}, 5, 300),
        ("obstacles", "koolio-real-dr", {}, 3, 300),
        ("hallway", None, CROWDED, 3, 40),
    ],
)
def test_robots_of_a_shared_arena_on_the_engine_are_the_python_ticks(
    arena, world, overrides, n, max_steps
):
    """The compiled step engine against ``episodes.Robots`` with the robots in one arena:
    log rows, the table, every robot's pose, presence, waiting, state and generators, bit
    for bit."""
    r = agreement.compare_robots(arena, world, 40, 2, n, overrides, max_steps, shared=True)
    assert r["steps"] > 1000
    assert (r["mismatches"], r["first_mismatch"]) == (0, -1)


def test_robots_of_a_shared_arena_meet_wait_and_bump_each_other() -> None:
    """The premise of the comparisons: in 4 robots' training the robots read each other as
    Bump, and some episode begins while every spot is covered."""
    from koolio_pymunk.learning.algorithms import make_learner
    from koolio_pymunk.learning.episodes import Robots
    from koolio_pymunk.store.qtable import QTable

    cfg = load_config(overrides={**CROWDED, "episode": {"max_steps": 40}})
    envs = SharedArena.envs(3, "hallway", cfg)
    table = QTable(envs[0].layout, {}, cfg.learner.q_init)
    loop = Robots(envs, [make_learner(table, cfg.learner, None) for _ in envs], seed=0)
    events: list[str] = []
    waits = 0
    for r in range(3):
        loop.begin(r, r)
    started = 3
    for _ in range(3000):
        for r, env in enumerate(envs):
            if not loop.running[r]:
                continue
            if env.waiting:
                waits += 1
            if loop.loops[r].step() is not None:
                loop.running[r] = False
                loop.begin(r, started)
                started += 1
            elif env.judgement is not None:
                events.append(env.judgement.event)
    assert events.count("robot_bump") > 10
    assert waits > 0


def test_parallel_env_passes_pettingzoo_api_and_seed_tests() -> None:
    from pettingzoo.test import parallel_api_test, parallel_seed_test

    parallel_api_test(koolio_pymunk.parallel_env(robots=3, max_steps=150), num_cycles=200)
    parallel_seed_test(
        lambda: koolio_pymunk.parallel_env(robots=3, arena="room", world="koolio-real"),
        num_cycles=100,
    )


def test_parallel_env_refuses_bad_actions_before_moving() -> None:
    env = koolio_pymunk.parallel_env(robots=2, arena="room")
    env.reset(seed=0)
    poses = [e.world.pose(e.robot) for e in env.envs]
    with pytest.raises(ValueError, match="no action for robot_1"):
        env.step({"robot_0": 3})
    with pytest.raises(ValueError, match="robot_1: 7 is not an action"):
        env.step({"robot_0": 3, "robot_1": 7})
    assert [e.world.pose(e.robot) for e in env.envs] == poses


def test_parallel_env_agents_leave_when_their_episode_ends() -> None:
    env = koolio_pymunk.parallel_env(robots=3, arena="room", max_steps=30)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    gone: set[str] = set()
    while env.agents:
        _, _, term, trunc, info = env.step({a: int(rng.integers(5)) for a in env.agents})
        ended = {a for a in term if term[a] or trunc[a]}
        for a in ended:
            assert not env.envs[info[a]["robot"]].world.present[info[a]["robot"]]
        gone |= ended
        assert not gone & set(env.agents)
    assert gone == set(env.possible_agents)


def test_parallel_env_draws_every_robot() -> None:
    env = koolio_pymunk.parallel_env(robots=3, arena="room", render_mode="rgb_array")
    env.reset(seed=0)
    img = env.render()
    assert img.ndim == 3 and img.shape[2] == 3
    from koolio_pymunk.task.drawing import ROBOT_PALETTE

    colours = {tuple(c) for c in img.reshape(-1, 3).tolist()}
    assert ROBOT_PALETTE[1] in colours and ROBOT_PALETTE[2] in colours


#: The shipped arenas, then four held-out style generated ones (jittered and turned
#: shipped arenas, star-shaped rooms with obstacles: ``tools/move_agreement.py``).
ARENAS = ["hallway", "room", "obstacles", 0, 1, 2, 3]


@pytest.mark.parametrize("arena", ARENAS)
def test_fuzz_eight_robots_never_leave_overlap_or_stick(arena) -> None:
    """8 robots, 10,000 robot-steps of random actions (compiled sensors, rescues on): no
    robot leaves the arena's walls, no two in the arena overlap by more than the slop, and
    none stays in one place for good (every robot moves in each stretch of 500 ticks)."""
    if isinstance(arena, int):
        arena = generated_arenas(4, seed=11)[arena]
    cfg = load_config(overrides={"shared": {"start_spread": 300}})
    envs = SharedArena.envs(8, arena, cfg)
    rng = np.random.default_rng(5)
    for k, env in enumerate(envs):
        env.reset(seed=k)
    world = envs[0].world
    last_moved = [0] * 8
    where = [env.world.pose(k)[:2] for k, env in enumerate(envs)]
    for tick in range(1250):
        for k, env in enumerate(envs):
            if env.waiting:
                env.enter()
                continue
            if not world.present[k]:
                env.reset()
                continue
            _, _, term, trunc = env.transition(int(rng.choice([0, 1, 2, 3, 3, 3, 4])))
            if term or trunc:
                env.leave()
                continue
            assert world.wall_clearance(k) > -COLLISION_SLOP
            assert world.overlaps(k) == []
            pose = world.pose(k)[:2]
            if math.dist(pose, where[k]) > 1.0:
                last_moved[k], where[k] = tick, pose
        assert tick - min(last_moved) < 500


# -- the commands ------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["train", "--shared-arena"], ["--shared-arena: needs --robots N with N >= 2"]),
        (["train", "--shared-arena", "--robots", "1"], ["needs --robots N"]),
        (["eval", "--shared-arena", "--qtable", "t.qtable"], ["needs --robots N"]),
        (["train", "--shared-arena", "--robots", "7"], ["hallway.yaml", "start area holds 6"]),
        (
            [
                "train",
                "--shared-arena",
                "--robots",
                "3",
                "--arena",
                "room",
                "--config",
                "tight.yaml",
            ],
            ["room.yaml", "3 robots start from", "holds 1"],
        ),
    ],
)
def test_bad_shared_arena_runs_are_one_line_before_any_file(here, capsys, argv, words) -> None:
    from inputs import expect_error

    (here / "tight.yaml").write_text("shared: {start_spread: 0}\n")
    expect_error(capsys, here, argv, *words)


def test_train_and_eval_in_a_shared_arena(here, capsys) -> None:
    """``train --robots 3 --shared-arena`` writes its table and log; ``eval`` with the
    robots in the arena prints each robot's goal rate; the same seed gives the same bytes."""
    from inputs import run

    argv = ["train", "--robots", "3", "--shared-arena", "--episodes", "12", "--quiet"]
    assert run(capsys, *argv, "--config", "tiny.yaml", "--qtable", "a.qtable")[0] == 0
    assert run(capsys, *argv, "--config", "tiny.yaml", "--qtable", "b.qtable")[0] == 0
    assert (here / "a.csv").read_bytes().split(b"\n", 1)[1] == (here / "b.csv").read_bytes().split(
        b"\n", 1
    )[1]
    code, out, _ = run(capsys, "eval", "--robots", "3", "--shared-arena", "--episodes", "6",
                       "--config", "tiny.yaml", "--qtable", "a.qtable")  # fmt: skip
    assert code == 0
    assert "3 robots sharing the arena" in out
    assert "by robot in the shared arena: robot 0 (goal 311)" in out


def test_a_bad_robot_start_is_one_line_before_any_file(here, capsys) -> None:
    from inputs import expect_error

    (here / "far.yaml").write_text("shared: {starts: [[5000, 44]]}\n")
    argv = ["train", "--robots", "2", "--shared-arena", "--config", "far.yaml"]
    expect_error(capsys, here, argv, "hallway.yaml: shared.starts[0]: point (5000, 44)")
