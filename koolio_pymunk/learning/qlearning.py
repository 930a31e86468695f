"""Episodic Q-learning (paper §5.4.6, Table 11), and the interface of every learner.

One step: choose an action epsilon-greedily, perform it, find the reward, read and encode
the next state, then update::

    NewQ = CurrentQ + alpha * (reward + gamma * max(NextQ) - CurrentQ)

``max(NextQ)`` is taken as 0 when the step ended the episode (goal or end of world): there
is no next state to value. A truncated episode (step cap) still bootstraps.

**The interface** the loops call (``koolio-pm train``, the window's learning), the same
for every algorithm of ``learner.algorithm`` (:func:`make_learner`):

* :meth:`QLearner.begin_episode` ``(episode, rng)``: the episode's generator and epsilon;
* :meth:`QLearner.act` ``(state)``: the action to take;
* :meth:`QLearner.observe` ``(state, action, reward, next_state, terminal)``: learn from
  the step just taken (``next_state`` is the state the action led to, before any rescue).

:class:`QLearner` is one-step Q (``q``, the paper's);
:class:`~koolio_pymunk.learning.qlambda.QLambda` and
:class:`~koolio_pymunk.learning.dyna.DynaQ` are the others.

>>> import numpy as np
>>> from koolio_pymunk.store.config import LearnerConfig
>>> from koolio_pymunk.store.qtable import KeywordLayout, QTable
>>> table = QTable(KeywordLayout((("A", 3),)))
>>> agent = QLearner(table, LearnerConfig(alpha=0.5, gamma=0.9), np.random.default_rng(0))
>>> table.row(1)[:] = [0.0, 0.0, 4.0, 0.0, 0.0]
>>> agent.update(0, 3, -1.0, 1, terminal=False)  # 0 + 0.5 * (-1 + 0.9 * 4 - 0)
1.3
"""

from __future__ import annotations

import numpy as np

from ..store.config import LearnerConfig
from ..store.qtable import QTable
from ..task.action_rules import NONE, allowed, allowed_action, barred


class QLearner:
    """One-step Q-learning: epsilon-greedy action choice with random tie-breaking, and the
    Table 11 update after every step."""

    name = "q"
    #: Table sections (:attr:`QTable.sections`) this algorithm keeps between sessions.
    sections: tuple[str, ...] = ()

    def __init__(self, table: QTable, cfg: LearnerConfig, rng: np.random.Generator) -> None:
        self.table = table
        self.cfg = cfg
        self.rng = rng
        self.alpha = cfg.alpha
        self.gamma = cfg.gamma
        self.epsilon = cfg.epsilon.start
        self.n_actions = table.layout.n_actions
        self.no_undo = bool(cfg.no_undo)
        self.last = NONE
        """The action taken last (``learner.no_undo`` bars its undo); NONE at an episode's
        start and after a rescue."""

    def begin_episode(self, episode: int, rng: np.random.Generator) -> None:
        """Start ``episode`` (0-based): its generator, and epsilon from the schedule."""
        self.rng = rng
        self.epsilon = self.cfg.epsilon.at(episode)
        self.last = NONE

    def relocated(self, state: int) -> None:
        """An auto rescue moved the robot: the next action undoes nothing."""
        self.last = NONE

    def act(self, state: int) -> int:
        """A uniform random action with probability epsilon, else a greedy one."""
        if self.epsilon > 0.0 and self.rng.random() < self.epsilon:
            action = self.explore(state)
        else:
            action = self.greedy(state)
        self.last = action
        return action

    @property
    def bar(self) -> int:
        """The action the no-undo rule bars now (-1: none)."""
        return barred(self.last) if self.no_undo else -1

    def explore(self, state: int) -> int:
        """The exploratory choice: a uniform random action (of those allowed)."""
        return self._any_action()

    def _any_action(self) -> int:
        bar = self.bar
        if bar < 0:
            return int(self.rng.integers(self.n_actions))
        return allowed_action(int(self.rng.integers(self.n_actions - 1)), bar)

    def greedy(self, state: int) -> int:
        """An action of highest Q (of those allowed); ties broken uniformly at random."""
        row = self.table.peek(state)
        if row is None:
            return self._any_action()
        choices = allowed(self.n_actions, self.bar)
        best = max(row[a] for a in choices)
        ties = [a for a in choices if row[a] == best]
        if len(ties) == 1:
            return ties[0]
        return ties[int(self.rng.integers(len(ties)))]

    def observe(
        self, state: int, action: int, reward: float, next_state: int, terminal: bool
    ) -> None:
        """Learn from one step: here the Table 11 update."""
        self.update(state, action, reward, next_state, terminal)

    def update(
        self, state: int, action: int, reward: float, next_state: int, terminal: bool
    ) -> float:
        """Table 11 update of Q(state, action); returns the new value."""
        row = self.table.row(state)
        target = td_target(
            reward, self.table.peek(next_state), self.table.q_init, self.gamma, terminal
        )
        row[action] += td_step(row[action], target, self.alpha)
        return row[action]


def td_target(
    reward: float, next_row: list[float] | None, q_init: float, gamma: float, terminal: bool
) -> float:
    """Table 11's target, ``reward + gamma * max(NextQ)``: the reward alone after a terminal
    step (goal, end of world), and ``q_init`` for a next state never visited.

    This and :func:`td_step` are the reference of the update: every learner here uses
    them; the step engine's kernels (:mod:`koolio_pymunk.learning.table_kernel`) and
    ``robot_runtime.py`` repeat them and are held to them bit for bit by the tests.

    >>> td_target(-1.0, [0.0, 4.0], -30.0, 0.9, terminal=False)
    2.6
    >>> td_target(-1.0, None, -30.0, 0.5, terminal=False), td_target(100.0, None, 0, 0.9, True)
    (-16.0, 100.0)
    """
    if terminal:
        return reward
    return reward + gamma * (max(next_row) if next_row is not None else q_init)


def td_step(q: float, target: float, alpha: float) -> float:
    """Table 11's change of ``Q``: ``alpha * (target - Q)`` (``NewQ = Q + td_step``).

    >>> td_step(1.0, 3.0, 0.25)
    0.5
    """
    return alpha * (target - q)
