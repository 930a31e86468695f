"""The learning algorithms of ``learner.algorithm``: which class learns, and what a table records.

:func:`make_learner` builds the learner of a configuration (``q``: one-step Q,
:class:`~koolio_pymunk.learning.qlearning.QLearner`; ``qlambda``:
:class:`~koolio_pymunk.learning.qlambda.QLambda`; ``dyna``:
:class:`~koolio_pymunk.learning.dyna.DynaQ`). A Q-table's header records the algorithm
it was learned with (:func:`algorithm_record`); a run continues a table only with that
algorithm (:func:`attach`), and ``--init-qtable`` starts a new table from another's Q
values with any algorithm (:func:`adopt`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..store.config import LearnerConfig
from ..store.errors import QTableError, located
from .qlearning import QLearner
from .qtable import QTable

#: Parameters of each algorithm recorded in the Q-table header (none for ``q``).
PARAMETERS: dict[str, tuple[str, ...]] = {
    "q": (),
    "qlambda": ("trace_decay", "trace_cutoff"),
    "dyna": ("planning_steps",),
}


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
    """What a Q-table header records of ``cfg``'s algorithm: None for one-step Q without
    the no-undo rule (the paper's learner: its tables' bytes are those of tables made
    before these records existed).

    >>> algorithm_record(LearnerConfig())  # the default learner
    {'name': 'qlambda', 'trace_decay': 0.7, 'trace_cutoff': 0.01, 'no_undo': True}
    >>> algorithm_record(LearnerConfig(algorithm="dyna", planning_steps=5, no_undo=False))
    {'name': 'dyna', 'planning_steps': 5}
    >>> algorithm_record(LearnerConfig(algorithm="q", no_undo=False)) is None
    True
    """
    rule = {"no_undo": True} if cfg.no_undo else {}  # absent when off: tables as before
    if cfg.algorithm == "q" and not rule:
        return None
    params = {k: getattr(cfg, k) for k in PARAMETERS[cfg.algorithm]}
    return {"name": cfg.algorithm} | params | rule


def table_rule(table: QTable) -> bool:
    """Whether ``table`` was learned with the no-undo rule (``learner.no_undo``; its
    header's ``algorithm`` record says so)."""
    rec = table.meta.get("algorithm")
    return isinstance(rec, dict) and rec.get("no_undo") is True


def check_rule(table: QTable, cfg: LearnerConfig, source: str, remedy: str) -> None:
    """Refuse to read ``table``'s greedy policy under another choice rule than the one it
    was learned with (QTableError, one line ending in ``(remedy)``): with the no-undo rule
    the greedy action depends on the last one, so a table learned with it and evaluated
    without it (or back) is another policy.

    >>> from koolio_pymunk.store.keyword import KeywordLayout
    >>> rec = {"name": "q", "no_undo": True}
    >>> t = QTable(KeywordLayout((("A", 3),)), {"algorithm": rec, "episodes": 2})
    >>> check_rule(t, LearnerConfig(no_undo=True), "t.qtable", "")
    >>> check_rule(t, LearnerConfig(no_undo=False), "t.qtable", "give its --config")
    Traceback (most recent call last):
    koolio_pymunk.store.errors.QTableError: t.qtable: learner.no_undo: table learned with the ...
    """
    theirs = table_rule(table)
    learned = bool(table.rows) or int(table.meta.get("episodes", 0)) > 0
    if learned and theirs != bool(cfg.no_undo):
        if theirs:
            what = "table learned with the no-undo rule, this run chooses among all actions"
        else:
            what = "table learned choosing among all actions, this run has the no-undo rule"
        raise QTableError(located(source, "learner.no_undo", f"{what} ({remedy})"))


def table_algorithm(table: QTable, source: str) -> str:
    """The algorithm a table was learned with (``q`` when its header names none)."""
    rec = table.meta.get("algorithm")
    if rec is None:
        return "q"
    name = rec.get("name") if isinstance(rec, dict) else None
    if not isinstance(name, str) or name not in PARAMETERS:
        shown = repr(rec) if len(repr(rec)) <= 60 else repr(rec)[:57] + "..."
        raise QTableError(located(source, "algorithm", f"unknown learning algorithm {shown}"))
    return str(rec["name"])


def attach(table: QTable, cfg: LearnerConfig, source: str) -> None:
    """Check a run of ``cfg``'s algorithm may continue ``table``, and record it.

    A table that has learned something continues only with the algorithm it was learned
    with, so that a resumed run continues exactly (its model, if any, is in the table);
    parameters may change. ``--init-qtable`` starts a new table from another's Q values
    with any algorithm (:func:`adopt`).
    """
    remedy = f"start a new table from its Q values: --init-qtable {source} --qtable NEW"
    check_algorithm(table, cfg, source, remedy)
    _record(table, cfg)


def check_algorithm(table: QTable, cfg: LearnerConfig, source: str, remedy: str) -> None:
    """Refuse ``cfg``'s algorithm for a table that has learned something with another
    one (QTableError, one line ending in ``(remedy)``): a run continuing it
    (:func:`attach`), or a policy exported for the robot to continue it.

    >>> from koolio_pymunk.store.keyword import KeywordLayout
    >>> t = QTable(KeywordLayout((("A", 3),)), {"algorithm": {"name": "dyna"}, "episodes": 2})
    >>> check_algorithm(t, LearnerConfig(algorithm="dyna", no_undo=False), "t.qtable", "")
    >>> check_algorithm(t, LearnerConfig(), "t.qtable", "give its --config")
    Traceback (most recent call last):
    koolio_pymunk.store.errors.QTableError: t.qtable: algorithm: table learned with dyna, this ...
    """
    theirs = table_algorithm(table, source)
    learned = bool(table.rows) or int(table.meta.get("episodes", 0)) > 0
    if learned and theirs != cfg.algorithm:
        raise QTableError(
            located(
                source,
                "algorithm",
                f"table learned with {theirs}, this run uses {cfg.algorithm} ({remedy})",
            )
        )
    check_rule(table, cfg, source, remedy)


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
