"""The compiled step (task/step_kernel.py) against the Python code it twins: the end
zones, the reward rules, an action's move, a whole step and its rescue."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from koolio_pymunk.sensing.reading_kernel import robot_group
from koolio_pymunk.store.config import RewardConfig, load_config
from koolio_pymunk.task.batch import EnvBatch
from koolio_pymunk.task.end_zones import EndZones
from koolio_pymunk.task.env import KoolioEnv
from koolio_pymunk.task.rules import judge
from koolio_pymunk.task.step_kernel import (
    EVENTS,
    F_H,
    F_X,
    F_Y,
    I_RESCUED,
    I_STATE,
    in_zone,
    judge_code,
    rescue_check,
    reward_array,
    simulate,
    zone_arrays,
)
from koolio_pymunk.world.arena import load_arena
from koolio_pymunk.world.physics import Action
from koolio_pymunk.world.segment_query import wall_array
from koolio_pymunk.world.swept_move import act, world_group

R = 10.0


@pytest.mark.parametrize("name", ["hallway", "room", "obstacles"])
def test_in_zone_matches_end_zones_contains(name) -> None:
    zones = EndZones(load_arena(name).to_world(), R)
    args = zone_arrays(zones)
    rng = np.random.default_rng(1)
    pts = [tuple(p) for p in rng.uniform(-60, 1700, (3000, 2))]
    pts += [tuple(map(float, v)) for poly in zones.polygons for v in poly]  # corners
    for poly in zones.polygons:  # edge midpoints: on the boundary, so outside
        pts += [((a[0] + b[0]) / 2, (a[1] + b[1]) / 2) for a, b in itertools.pairwise(poly)]
    got = [in_zone(x, y, *args) for x, y in pts]
    assert got == [zones.contains(x, y) for x, y in pts]
    assert any(got)


@pytest.mark.parametrize("goal_close", [False, True])
@pytest.mark.parametrize("eow", [False, True])
@pytest.mark.parametrize("bump", [False, True])
@pytest.mark.parametrize("robot_hit", [False, True])
def test_judge_code_is_the_rules_priority(goal_close, eow, bump, robot_hit) -> None:
    rw = RewardConfig(stop=-2.5, reverse=-3.5, turn=-1.25, forward=-0.75, robot_bump=-7.0)
    zones = zone_arrays(EndZones(load_arena("room").to_world(), R))
    x, y = (264.0, 96.0) if eow else (100.0, 100.0)  # the room's exit stub, or not
    robot_hit = robot_hit and bump  # a Bump read from a robot is a Bump
    for action in range(5):
        j = judge(action, goal_close, eow, bump, rw, robot_hit)
        code = judge_code(action, goal_close, x, y, bump, zones, robot_hit)
        assert EVENTS[code] == j.event and reward_array(rw)[code] == j.reward
        assert (j.event == "robot_bump") == (robot_hit and not eow and not (goal_close and
                                                                          action == 0))  # fmt: skip


def test_a_robot_bump_is_worth_the_wall_bump_unless_set() -> None:
    assert reward_array(RewardConfig(bump=-3.0))[EVENTS.index("robot_bump")] == -3.0
    assert reward_array(RewardConfig(robot_bump=-20.0))[EVENTS.index("robot_bump")] == -20.0


@pytest.mark.parametrize("arena_name", ["obstacles", "room", "hallway"])
@pytest.mark.parametrize("errors", [False, True])
def test_act_moves_as_the_pymunk_world_does(arena_name, errors) -> None:
    """``swept_move.act`` against ``KoolioEnv``'s own moves (``World.act``, or with the
    motion errors of koolio-real ``MotionErrors`` and ``World.drive``): the same pose bit
    for bit, the same draws, over random actions with many wall contacts."""
    env = KoolioEnv(arena_name, world="koolio-real" if errors else None)
    env.reset(seed=3)
    walls = wall_array(env.world)
    world = world_group(walls, env.world.radius, env.move_distance, env.turn_arc)
    m = env.motion
    motion = np.zeros(5) if m is None else np.array(
        [1.0, m.drift, m.drift_sigma, m.slip_sigma, m.turn_sigma])  # fmt: skip
    twin = np.random.default_rng(7)
    env.np_random.bit_generator.state = twin.bit_generator.state
    rng = np.random.default_rng(11)
    contacts = 0
    for _ in range(400):
        a = Action.FORWARD if rng.random() < 0.5 else int(rng.integers(5))
        x, y, h = env.world.pose(0)
        want = act(int(a), x, y, h, twin, world, motion)
        if env.motion is None:
            env.world.act((int(a),), env.move_distance, env.turn_arc)
        else:
            env._act_with_errors(int(a))
        assert env.world.pose(0) == want
        contacts += a in (Action.FORWARD, Action.REVERSE) and math.dist((x, y), want[:2]) < 11.9
    assert env.np_random.random() == twin.random()  # the same draws made
    assert contacts > 20  # the premise: many moves met a wall


@pytest.mark.parametrize("world", [None, "koolio-real-dr"])
def test_simulate_and_rescue_check_are_the_env_s(world) -> None:
    """A robot of a batch stepped by the kernel and the same env stepped by
    ``KoolioEnv.simulate`` and ``rescue_check``: the same state, pose, reward, event and
    rescues at every step, eager rescues included."""
    over = {"rescue": {"max_steps_before_rescue": 2, "rescue_chance": 0.6}}
    cfg = load_config(overrides=over, world=world)
    ref = KoolioEnv("room", config=cfg, max_steps=400)
    twin = KoolioEnv("room", config=cfg, max_steps=400)
    batch = EnvBatch([twin])
    ref.reset(seed=5)
    batch.reset(0, 5)
    rng = np.random.default_rng(2)
    rescues = 0
    for _ in range(300):
        a = int(rng.integers(5))
        nxt, reward, term, trunc = ref.simulate(a)
        got = simulate(0, a, batch.generators.items[0],
                       robot_group(0, *batch.reading_args), batch.world, batch.motion,
                       batch.task, batch.memory, batch.ints, batch.floats, batch.mem,
                       None)  # fmt: skip
        assert (got[0], [*EVENTS, "wrong_door"][got[1]], got[2], got[3], got[4]) == (
            nxt,
            ref.judgement.event,
            reward,
            term,
            trunc,
        )
        rescued = ref.rescue_check()
        got_rescue = rescue_check(0, batch.generators.items[0],
                                  robot_group(0, *batch.reading_args), batch.world, batch.task,
                                  batch.memory, batch.ints, batch.floats, batch.mem,
                                  None)  # fmt: skip
        assert rescued == got_rescue == bool(batch.ints[0, I_RESCUED])
        rescues += rescued
        f = batch.floats[0]
        assert (f[F_X], f[F_Y], f[F_H]) == ref.world.pose(0)
        assert batch.ints[0, I_STATE] == ref.state_key
        if term or trunc:
            ref.reset(seed=6)
            batch.reset(0, 6)
    assert rescues >= 2  # the premise: the rescue path ran
