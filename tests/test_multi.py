"""Many robots, one shared Q-table (koolio_pymunk/multi.py): order, numbering, physics."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from koolio_pymunk.arena import load_arena
from koolio_pymunk.config import Config
from koolio_pymunk.env import KoolioEnv
from koolio_pymunk.geometry import point_in_polygon, segments_intersect
from koolio_pymunk.multi import PoseReader, _Run, train_many
from koolio_pymunk.qtable import QTableStore, load_qtable
from koolio_pymunk.training import LOG_FIELDS
from koolio_pymunk.world import Action, World

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
    tick = _Run._tick

    def interrupting(self):
        calls["n"] += 1
        if calls["n"] == 30:
            raise KeyboardInterrupt
        tick(self)

    monkeypatch.setattr(_Run, "_tick", interrupting)
    q, log, res = run(tmp_path, "a", episodes=50, robots=3)
    assert res.interrupted
    rows = list(csv.DictReader(log.open()))
    assert [r["outcome"] for r in rows].count("interrupted") == 3
    assert load_qtable(q).rows == res.table.rows


def _crosses(world: World, p: tuple, q: tuple) -> bool:
    return any(segments_intersect(p, q, a, b) for a, b in world.segments)


def test_many_robot_world_keeps_every_robot_in_its_arena() -> None:
    """Random actions for 5 robots at once (sleeping non-movers): walls hold for all,
    a robot that does not move stays exactly put, the batch pose reader agrees."""
    arena = load_arena("obstacles")
    w = World.from_arena(arena, R, n_robots=5)
    reader = PoseReader(w)
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
        assert np.array_equal(reader.xy(), np.array([w.pose(i)[:2] for i in range(5)]))
    assert -MAX_OVERLAP <= worst < 0.5


@pytest.mark.parametrize("robots", [1, 2])
def test_train_many_accepts_any_robot_count(tmp_path, robots: int) -> None:
    _, _, res = run(tmp_path, f"r{robots}", episodes=3, robots=robots)
    assert res.episodes_run == 3
