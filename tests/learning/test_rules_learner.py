"""Reward priority (paper §5.4.7) and the Q-learner (Table 11, epsilon-greedy)."""

from __future__ import annotations

import numpy as np
import pytest

from koolio_pymunk.learning.qlearning import QLearner
from koolio_pymunk.store.config import EpsilonSchedule, LearnerConfig, RewardConfig
from koolio_pymunk.store.keyword import KeywordLayout
from koolio_pymunk.store.qtable import QTable
from koolio_pymunk.task.rules import TERMS, judge
from koolio_pymunk.world.physics import Action

RW = RewardConfig(
    goal=10, end_of_world=-20, bump=-3, stop=-0.5, reverse=-0.4, turn=-0.3, forward=-0.2
)


@pytest.mark.parametrize(
    ("action", "goal_close", "eow", "bump", "event", "reward", "done"),
    [
        (Action.STOP, True, True, True, "goal", 10, True),
        (Action.FORWARD, True, True, True, "end_of_world", -20, True),  # goal needs Stop
        (Action.STOP, False, True, True, "end_of_world", -20, True),
        (Action.STOP, False, False, True, "bump", -3, False),
        (Action.STOP, False, False, False, "stop", -0.5, False),
        (Action.REVERSE, False, False, False, "reverse", -0.4, False),
        (Action.ROTATE_LEFT, False, False, False, "turn", -0.3, False),
        (Action.ROTATE_RIGHT, True, False, False, "turn", -0.3, False),
        (Action.FORWARD, False, False, False, "forward", -0.2, False),
    ],
)
def test_reward_priority(action, goal_close, eow, bump, event, reward, done) -> None:
    j = judge(action, goal_close, eow, bump, RW)
    assert (j.event, j.reward, j.terminated) == (event, reward, done)
    assert set(j.terms) == set(TERMS)
    assert j.terms[event] == reward
    assert sum(abs(v) for k, v in j.terms.items() if k != event) == 0


def agent(alpha=0.5, gamma=0.9, seed=0) -> tuple[QLearner, QTable]:
    """The paper's learner: one-step Q choosing among all five actions."""
    table = QTable(KeywordLayout((("A", 3), ("B", 4))))
    cfg = LearnerConfig(algorithm="q", alpha=alpha, gamma=gamma, no_undo=False)
    return QLearner(table, cfg, np.random.default_rng(seed)), table


def test_table11_update() -> None:
    a, t = agent()
    t.row(2)[:] = [1.0, 5.0, -2.0, 0.0, 0.0]
    t.row(1)[3] = 2.0
    new = a.update(1, 3, -1.0, 2, terminal=False)
    assert new == pytest.approx(2.0 + 0.5 * (-1.0 + 0.9 * 5.0 - 2.0))
    assert t.get(1, 3) == new


def test_terminal_update_does_not_bootstrap() -> None:
    a, t = agent()
    t.row(2)[:] = [100.0] * 5
    assert a.update(1, 0, 10.0, 2, terminal=True) == pytest.approx(5.0)


def test_unvisited_next_state_counts_q_init() -> None:
    a, t = agent()
    t.q_init = 1.0
    assert a.update(1, 0, 0.0, 9, terminal=False) == pytest.approx(0.5 * (0.9 - 1.0) + 1.0)


def test_greedy_breaks_ties_at_random() -> None:
    a, t = agent()
    a.epsilon = 0.0
    t.row(4)[:] = [0.0, 3.0, 3.0, 1.0, 3.0]
    picks = {a.act(4) for _ in range(200)}
    assert picks == {1, 2, 4}
    t.row(4)[2] = 3.5
    assert {a.act(4) for _ in range(50)} == {2}


def test_epsilon_explores_uniformly() -> None:
    a, t = agent(seed=3)
    a.epsilon = 1.0
    t.row(4)[:] = [9.0, 0, 0, 0, 0]
    counts = np.bincount([a.act(4) for _ in range(5000)], minlength=5)
    assert counts.min() > 850 and counts.max() < 1150


def test_epsilon_schedule() -> None:
    s = EpsilonSchedule(start=0.5, end=0.1, decay_episodes=4)
    assert [s.at(e) for e in range(6)] == pytest.approx([0.5, 0.4, 0.3, 0.2, 0.1, 0.1])
    assert EpsilonSchedule(start=0.3, end=0.0, decay_episodes=0).at(99) == 0.3
