"""The window's learning session is the training loop: same rows, same bytes, every world."""

from __future__ import annotations

import pytest

from koolio_pymunk.apps.viewer.session import Session
from koolio_pymunk.learning.training import train
from koolio_pymunk.store.config import load_config, profile_names
from koolio_pymunk.store.qtable import QTableStore
from koolio_pymunk.task.env import KoolioEnv

#: The ideal world and every shipped world profile.
WORLDS = [None, *(n for n in profile_names() if n.startswith("koolio-real"))]


def make_env(world: str | None) -> KoolioEnv:
    cfg = load_config(overrides={"episode": {"max_steps": 40}})
    return KoolioEnv("room", config=cfg, world=world)


def test_every_shipped_world_is_covered() -> None:
    assert WORLDS == [None, "koolio-real", "koolio-real-dr"]


@pytest.mark.parametrize("world", WORLDS)
def test_window_then_train_equals_train_alone(tmp_path, world) -> None:
    """Learn 3 episodes in the window, then 2 more with ``train`` on the same table and
    log: the files are byte-identical to 5 episodes of ``train`` alone (the window's rows
    carry the ``realism.*`` columns of domain randomization like ``train``'s)."""
    a_table, a_log = tmp_path / "a.qtable", tmp_path / "a.csv"
    session = Session(make_env(world), a_table, seed=4, episodes=3, log=a_log)
    while session.step():
        pass
    assert session.done and len(session.results) == 3
    session.exit()
    result = train(make_env(world), QTableStore(a_table), 2, seed=4, log_path=a_log, report=None)
    assert result.episodes_run == 2

    b_table, b_log = tmp_path / "b.qtable", tmp_path / "b.csv"
    train(make_env(world), QTableStore(b_table), 5, seed=4, log_path=b_log, report=None)
    assert a_log.read_bytes() == b_log.read_bytes()
    assert a_table.read_bytes() == b_table.read_bytes()
    header = b_log.read_text().splitlines()[1]  # after the run line
    assert ("realism." in header) == (world == "koolio-real-dr")
