"""Episodic Q-learning (paper §5.4.6, Table 11).

One step: choose an action epsilon-greedily, perform it, find the reward, read and encode
the next state, then update::

    NewQ = CurrentQ + alpha * (reward + gamma * max(NextQ) - CurrentQ)

``max(NextQ)`` is taken as 0 when the step ended the episode (goal or end of world): there
is no next state to value. A truncated episode (step cap) still bootstraps.

>>> import numpy as np
>>> from koolio_pymunk.config import LearnerConfig
>>> from koolio_pymunk.qtable import KeywordLayout, QTable
>>> table = QTable(KeywordLayout((("A", 3),)))
>>> agent = QLearner(table, LearnerConfig(alpha=0.5, gamma=0.9), np.random.default_rng(0))
>>> table.row(1)[:] = [0.0, 0.0, 4.0, 0.0, 0.0]
>>> agent.update(0, 3, -1.0, 1, terminal=False)  # 0 + 0.5 * (-1 + 0.9 * 4 - 0)
1.3
"""

from __future__ import annotations

import numpy as np

from .config import LearnerConfig
from .qtable import QTable


class QLearner:
    """epsilon-greedy action choice with random tie-breaking, and the Table 11 update."""

    def __init__(self, table: QTable, cfg: LearnerConfig, rng: np.random.Generator) -> None:
        self.table = table
        self.cfg = cfg
        self.rng = rng
        self.alpha = cfg.alpha
        self.gamma = cfg.gamma
        self.epsilon = cfg.epsilon.start
        self.n_actions = table.layout.n_actions

    def set_episode(self, episode: int) -> None:
        """Apply the epsilon schedule for ``episode`` (0-based)."""
        self.epsilon = self.cfg.epsilon.at(episode)

    def act(self, state: int) -> int:
        """A uniform random action with probability epsilon, else a greedy one."""
        if self.epsilon > 0.0 and self.rng.random() < self.epsilon:
            return int(self.rng.integers(self.n_actions))
        return self.greedy(state)

    def greedy(self, state: int) -> int:
        """An action of highest Q; ties broken uniformly at random."""
        row = self.table.peek(state)
        if row is None:
            return int(self.rng.integers(self.n_actions))
        best = max(row)
        ties = [a for a, q in enumerate(row) if q == best]
        if len(ties) == 1:
            return ties[0]
        return ties[int(self.rng.integers(len(ties)))]

    def update(
        self, state: int, action: int, reward: float, next_state: int, terminal: bool
    ) -> float:
        """Table 11 update of Q(state, action); returns the new value."""
        row = self.table.row(state)
        if terminal:
            target = reward
        else:
            nxt = self.table.peek(next_state)
            target = reward + self.gamma * (max(nxt) if nxt is not None else self.table.q_init)
        row[action] += self.alpha * (target - row[action])
        return row[action]
