"""Many robots, one shared Q-table (koolio_pymunk/learning/fleet.py): order, numbering, physics."""

from __future__ import annotations

import csv
import itertools
import math

import numpy as np
import pytest
from koolio_pymunk.learning.fleet import _Run, train_many

from koolio_pymunk.learning import fleet
from koolio_pymunk.learning.qtable import QTableStore, load_qtable
from koolio_pymunk.learning.training import LOG_FIELDS
from koolio_pymunk.store.config import Config
from koolio_pymunk.task.env import KoolioEnv
from koolio_pymunk.world.arena import load_arena
from koolio_pymunk.world.geometry import point_in_polygon, segments_intersect
from koolio_pymunk.world.physics import Action, World

R = 10.0
MAX_OVERLAP = 0.1


def small_env() -> KoolioEnv:
    cfg = Config()
    cfg.episode.max_steps = 60
    return KoolioEnv("room", config=cfg)


def run(tmp_path, name: str, episodes: int = 7, seed: int = 0, robots: int = 3, **kw):
    q, log = tmp_path / f"{name}.qtable", tmp_path / f"{name}.csv"
    res = train_many(small_env(), QTableStore(q), episodes, seed, log, robots, report=None, **kw)
    return q, log, res


def test_seeded_run_is_reproducible_and_seed_matters(tmp_path) -> None:
    qa, la, _ = run(tmp_path, "a")
    qb, lb, _ = run(tmp_path, "b")
    qc, _, _ = run(tmp_path, "c", seed=1)
    assert qa.read_bytes() == qb.read_bytes()
    assert la.read_bytes() == lb.read_bytes()
    assert qa.read_bytes() != qc.read_bytes()


def test_a_resumed_run_is_seeded_but_not_the_straight_run(tmp_path) -> None:
    """Resuming is reproducible (the same two commands, the same bytes); it is not the
    uninterrupted run, whose robots were mid-episode at the save (docs/robustness.md)."""
    for name in ("a", "b"):
        run(tmp_path, name, episodes=6, robots=3)
        run(tmp_path, name, episodes=6, robots=3)
    straight, _, _ = run(tmp_path, "c", episodes=12, robots=3)
    a, b = (tmp_path / "a.qtable").read_bytes(), (tmp_path / "b.qtable").read_bytes()
    assert a == b
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    assert a != straight.read_bytes()


def test_episodes_numbered_in_completion_order_and_logged(tmp_path) -> None:
    q, log, res = run(tmp_path, "a", episodes=7, robots=3)
    rows = list(csv.DictReader(log.open()))
    assert list(rows[0]) == list(LOG_FIELDS)
    assert [int(r["episode"]) for r in rows] == list(range(7))
    assert res.episodes_run == 7 and res.steps == sum(int(r["steps"]) for r in rows)
    assert all(int(r["steps"]) <= 60 for r in rows)
    table = load_qtable(q)
    assert table.meta["episodes"] == 7 and len(table) > 0
    # Resume: the next run continues the numbering from the table's count.
    _, _, res2 = run(tmp_path, "a", episodes=2, robots=2)
    assert [r.episode for r in res2.results] == [7, 8]


def test_save_every_one_saves_at_every_episode_end(tmp_path, monkeypatch) -> None:
    saves = []
    original = QTableStore.save

    def counting(self, table):
        saves.append(table.meta["episodes"])
        original(self, table)

    monkeypatch.setattr(QTableStore, "save", counting)
    run(tmp_path, "a", episodes=5, robots=2, save_every=1)
    assert saves == [1, 2, 3, 4, 5]
    saves.clear()
    run(tmp_path, "b", episodes=5, robots=2)  # default: every `robots` episodes and last
    assert saves == [2, 4, 5]


def test_ctrl_c_folds_unfinished_episodes(tmp_path, monkeypatch) -> None:
    calls = {"n": 0}
    ticks = _Run._ticks

    def interrupting(self):
        calls["n"] += 1
        if calls["n"] == 30:
            raise KeyboardInterrupt
        ticks(self)

    monkeypatch.setattr(fleet, "CHUNK", 1)  # one tick per compiled call
    monkeypatch.setattr(_Run, "_ticks", interrupting)
    q, log, res = run(tmp_path, "a", episodes=50, robots=3)
    assert res.interrupted
    rows = list(csv.DictReader(log.open()))
    assert [r["outcome"] for r in rows].count("interrupted") == 3
    assert load_qtable(q).rows == res.table.rows


def _crosses(world: World, p: tuple, q: tuple) -> bool:
    return any(segments_intersect(p, q, a, b) for a, b in world.segments)


def test_many_robot_world_keeps_every_robot_in_its_arena() -> None:
    """Random actions for 5 robots at once (sleeping non-movers): walls hold for all,
    a robot that does not move stays exactly put."""
    arena = load_arena("obstacles")
    w = World.from_arena(arena, R, n_robots=5)
    rng = np.random.default_rng(5)
    for i in range(5):
        w.place(i, arena.start.at, float(rng.uniform(0, 2 * math.pi)))
    worst = math.inf
    for _ in range(400):
        actions = [int(a) for a in rng.integers(5, size=5)]
        actions = [Action.FORWARD if rng.random() < 0.5 else a for a in actions]
        before = [w.pose(i) for i in range(5)]
        w.act(actions, 12.0, math.radians(15))
        for i in range(5):
            after = w.pose(i)
            if actions[i] not in (Action.FORWARD, Action.REVERSE):
                assert after[:2] == before[i][:2]
            assert not _crosses(w, before[i][:2], after[:2])
            assert point_in_polygon(after[:2], arena.walls)
            worst = min(worst, w.wall_clearance(i))
    assert -MAX_OVERLAP <= worst < 0.5


@pytest.mark.parametrize("robots", [1, 2])
def test_train_many_accepts_any_robot_count(tmp_path, robots: int) -> None:
    _, _, res = run(tmp_path, f"r{robots}", episodes=3, robots=robots)
    assert res.episodes_run == 3


def test_backend_pymunk_senses_the_same_with_many_robots(tmp_path) -> None:
    """Many robots always sense with the batched kernel: the same table either way."""
    tables = []
    for backend in ("fast", "pymunk"):
        env = small_env()
        env.config.sensors.backend = backend
        env = KoolioEnv("room", config=env.config)
        q = tmp_path / f"{backend}.qtable"
        train_many(env, QTableStore(q), 4, 3, None, 2, report=None)
        tables.append(q.read_bytes())
    assert tables[0] == tables[1]


# -- the compiled loop (fleet_kernel) against the Python code it replaces ------------------------


def test_in_zone_matches_end_zones_contains() -> None:
    from koolio_pymunk.learning.fleet_kernel import in_zone, zone_arrays

    from koolio_pymunk.task.end_zones import EndZones

    for name in ("hallway", "room", "obstacles"):
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


def test_update_and_choose_match_the_learner() -> None:
    from koolio_pymunk.learning.fleet_kernel import SharedTable, choose, update

    from koolio_pymunk.learning.qlearning import QLearner
    from koolio_pymunk.learning.qtable import QTable
    from koolio_pymunk.store.config import LearnerConfig
    from koolio_pymunk.store.keyword import KeywordLayout

    layout = KeywordLayout((("A", 4),))
    ref = QTable(layout, q_init=0.5)
    agent = QLearner(ref, LearnerConfig(alpha=0.3, gamma=0.9), np.random.default_rng(0))
    shared = SharedTable(QTable(layout, q_init=0.5), reserve=2)
    rng = np.random.default_rng(2)
    for _ in range(300):
        s, a, nxt = int(rng.integers(4)), int(rng.integers(5)), int(rng.integers(4))
        reward, terminal = float(rng.normal()), bool(rng.random() < 0.2)
        agent.update(s, a, reward, nxt, terminal)
        shared.reserve(2)
        update(shared.index, shared.args(), 0.3, 0.9, s, a, reward, nxt, terminal)
    ref.row(3)[:] = [1.0, 2.0, 2.0, 0.0, 2.0]  # a three-way tie
    shared.sync()
    shared.table.rows[3] = [1.0, 2.0, 2.0, 0.0, 2.0]
    shared = SharedTable(shared.table)
    assert shared.table.rows == ref.rows
    states = np.array([0, 1, 2, 3, 3, 3, 7], np.int64)
    tie = np.array([0.1, 0.5, 0.9, 0.0, 0.5, 0.99, 0.3])
    explore = np.array([0.9, 0.01, 0.9, 0.9, 0.9, 0.9, 0.9])
    random_action = np.array([4, 4, 4, 4, 4, 4, 4], np.int64)
    actions = np.zeros(7, np.int64)
    choose(shared.index, shared.q, states, np.ones(7, np.bool_), np.full(7, 0.05), explore,
           random_action, tie, actions)  # fmt: skip
    for r, s in enumerate(states.tolist()):
        row = ref.peek(s)
        if explore[r] < 0.05 or row is None:
            want = 4
        else:
            ties = [a for a, q in enumerate(row) if q == max(row)]
            want = ties[int(tie[r] * len(ties))]
        assert actions[r] == want
    assert actions[3:6].tolist() == [1, 2, 4]


@pytest.mark.parametrize("goal_close", [False, True])
@pytest.mark.parametrize("eow", [False, True])
@pytest.mark.parametrize("bump", [False, True])
def test_learn_judges_like_the_rules(goal_close: bool, eow: bool, bump: bool) -> None:
    from koolio_pymunk.learning.fleet_kernel import (
        EVENTS,
        SharedTable,
        learn,
        new_journal,
        reward_array,
        zone_arrays,
    )

    from koolio_pymunk.learning.qtable import QTable
    from koolio_pymunk.store.config import RewardConfig
    from koolio_pymunk.store.keyword import KeywordLayout
    from koolio_pymunk.task.end_zones import EndZones
    from koolio_pymunk.task.rules import judge

    rw = RewardConfig(stop=-2.5, reverse=-3.5, turn=-1.25, forward=-0.75)
    reward = reward_array(rw)
    zones = EndZones(load_arena("room").to_world(), R)
    inside = (264.0, 96.0)  # the room's exit stub
    for action in range(5):
        j = judge(action, goal_close, eow, bump, rw)
        shared = SharedTable(QTable(KeywordLayout((("A", 4),))))
        xy = np.array([inside if eow else (100.0, 100.0)])
        steps, bumps, total, event = (np.zeros(1, np.int64), np.zeros(1, np.int64),
                                      np.zeros(1), np.zeros(1, np.int64))  # fmt: skip
        tick = (
            np.ones(1, np.bool_),
            np.array([action]),
            np.zeros(1, np.int64),
            np.ones(1, np.int64),
            np.array([bump]),
            np.array([goal_close]),
            xy,
        )
        rules = (reward, 0.5, 0.9, zone_arrays(zones), -1, 0)
        r, why = learn(0, tick, rules, (steps, bumps, total, event), new_journal(1, 0),
                       shared.index, shared.args())  # fmt: skip
        assert EVENTS[event[0]] == j.event and total[0] == j.reward
        assert (why == 2) == j.terminated and (r, steps[0], bumps[0]) == (
            0 if j.terminated else 1,
            1,
            bump,
        )


@pytest.mark.parametrize("arena_name", ["obstacles", "room", "hallway"])
def test_move_all_moves_every_robot_as_the_pymunk_world_does(arena_name) -> None:
    """The fleet's compiled moves (each robot in its own copy of the walls) against
    ``World.act`` on the same actions: positions in the copies, arena positions and
    headings equal bit for bit, tick after tick."""
    from koolio_pymunk.learning.fleet_kernel import move_all

    from koolio_pymunk.world.segment_query import wall_array

    arena = load_arena(arena_name)
    n = 6
    w = World.from_arena(arena, R, n_robots=n)
    rng = np.random.default_rng(11)
    for i in range(n):
        w.place(i, arena.start.at, float(rng.uniform(0, 2 * math.pi)))
    walls = np.stack([wall_array(w, k) for k in range(n)])
    offsets = np.asarray(w.offsets, dtype=np.float64)
    copy_xy = np.array([w.copy_position(k) for k in range(n)])
    headings = np.array(w.heading)
    xy = np.empty((n, 2))
    contacts = 0
    for _ in range(300):
        actions = rng.integers(5, size=n)
        actions[rng.random(n) < 0.5] = Action.FORWARD
        before = copy_xy.copy()
        w.act([int(a) for a in actions], 12.0, math.radians(30))
        move_all(actions, copy_xy, headings, walls, offsets, (12.0, math.radians(30), R), xy)
        for k in range(n):
            assert tuple(copy_xy[k]) == w.copy_position(k)
            assert (xy[k, 0], xy[k, 1], headings[k]) == w.pose(k)
            moved = math.dist(before[k], copy_xy[k])
            contacts += actions[k] in (Action.FORWARD, Action.REVERSE) and moved < 11.999
    assert contacts > 20  # the premise: many moves met a wall
