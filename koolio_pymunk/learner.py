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

:class:`QLearner` is one-step Q (``q``, the paper's); :class:`~koolio_pymunk.qlambda.QLambda`
and :class:`~koolio_pymunk.dyna.DynaQ` are the others.

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

from typing import Any

import numpy as np

from .config import LearnerConfig
from .errors import QTableError, located
from .qtable import QTable

#: Parameters of each algorithm recorded in the Q-table header (none for ``q``).
PARAMETERS: dict[str, tuple[str, ...]] = {
    "q": (),
    "qlambda": ("trace_decay", "trace_cutoff"),
    "dyna": ("planning_steps",),
}


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

    def begin_episode(self, episode: int, rng: np.random.Generator) -> None:
        """Start ``episode`` (0-based): its generator, and epsilon from the schedule."""
        self.rng = rng
        self.epsilon = self.cfg.epsilon.at(episode)

    def act(self, state: int) -> int:
        """A uniform random action with probability epsilon, else a greedy one."""
        if self.epsilon > 0.0 and self.rng.random() < self.epsilon:
            return self.explore(state)
        return self.greedy(state)

    def explore(self, state: int) -> int:
        """The exploratory choice: a uniform random action."""
        return int(self.rng.integers(self.n_actions))

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
        if terminal:
            target = reward
        else:
            nxt = self.table.peek(next_state)
            target = reward + self.gamma * (max(nxt) if nxt is not None else self.table.q_init)
        row[action] += self.alpha * (target - row[action])
        return row[action]


def make_learner(
    table: QTable, cfg: LearnerConfig, rng: np.random.Generator, source: str = "<table>"
) -> QLearner:
    """The learner of ``cfg.algorithm`` on ``table`` (``source`` names the table's file in
    errors about the data it keeps there)."""
    if cfg.algorithm == "qlambda":
        from .qlambda import QLambda

        return QLambda(table, cfg, rng)
    if cfg.algorithm == "dyna":
        from .dyna import DynaQ

        return DynaQ(table, cfg, rng, source)
    return QLearner(table, cfg, rng)


def algorithm_record(cfg: LearnerConfig) -> dict[str, Any] | None:
    """What a Q-table header records of ``cfg``'s algorithm: None for one-step Q.

    >>> algorithm_record(LearnerConfig(algorithm="dyna", planning_steps=5))
    {'name': 'dyna', 'planning_steps': 5}
    >>> algorithm_record(LearnerConfig()) is None
    True
    """
    if cfg.algorithm == "q":
        return None
    return {"name": cfg.algorithm} | {k: getattr(cfg, k) for k in PARAMETERS[cfg.algorithm]}


def table_algorithm(table: QTable, source: str) -> str:
    """The algorithm a table was learned with (``q`` when its header names none)."""
    rec = table.meta.get("algorithm")
    if rec is None:
        return "q"
    if not isinstance(rec, dict) or rec.get("name") not in PARAMETERS:
        raise QTableError(located(source, "algorithm", f"unknown learning algorithm {rec!r}"))
    return str(rec["name"])


def attach(table: QTable, cfg: LearnerConfig, source: str) -> None:
    """Check a run of ``cfg``'s algorithm may continue ``table``, and record it.

    A table that has learned something continues only with the algorithm it was learned
    with, so that a resumed run continues exactly (its model, if any, is in the table);
    parameters may change. ``--init-qtable`` starts a new table from another's Q values
    with any algorithm (:func:`adopt`).
    """
    theirs = table_algorithm(table, source)
    learned = bool(table.rows) or int(table.meta.get("episodes", 0)) > 0
    if learned and theirs != cfg.algorithm:
        raise QTableError(
            located(
                source,
                "algorithm",
                f"table learned with {theirs}, this run uses {cfg.algorithm} (start a new "
                f"table from its Q values: --init-qtable {source} --qtable NEW)",
            )
        )
    _record(table, cfg)


def adopt(table: QTable, cfg: LearnerConfig, source: str) -> None:
    """Make ``table`` (e.g. ``--init-qtable``'s) a table of ``cfg``'s algorithm: its Q
    values are kept, data of another algorithm (a Dyna model) is dropped."""
    if table_algorithm(table, source) != cfg.algorithm:
        table.sections.clear()
    _record(table, cfg)


def _record(table: QTable, cfg: LearnerConfig) -> None:
    rec = algorithm_record(cfg)
    if rec is None:
        table.meta.pop("algorithm", None)
    else:
        table.meta["algorithm"] = rec
