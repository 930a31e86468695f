"""The learning algorithms of ``learner.algorithm``: which class learns, and what a table records.

:func:`make_learner` builds the learner of a configuration (``q``: one-step Q,
:class:`~koolio_pymunk.learning.qlearning.QLearner`; ``qlambda``:
:class:`~koolio_pymunk.learning.qlambda.QLambda`; ``dyna``:
:class:`~koolio_pymunk.learning.dyna.DynaQ`). A Q-table's header records the algorithm
it was learned with and the parameters :data:`~koolio_pymunk.store.config.PARAMETERS` names
(:func:`koolio_pymunk.store.run_identity.algorithm_record`); a run continues a table
only with that algorithm, and ``--init-qtable`` starts a new table from another's Q values
with any algorithm (:mod:`~koolio_pymunk.store.run_identity`'s rules).
"""

from __future__ import annotations

import numpy as np

from ..store.config import LearnerConfig
from ..store.qtable import QTable
from .qlearning import QLearner


def make_learner(table: QTable, cfg: LearnerConfig, rng: np.random.Generator) -> QLearner:
    """The learner of ``cfg.algorithm`` on ``table``."""
    if cfg.algorithm == "qlambda":
        from .qlambda import QLambda

        return QLambda(table, cfg, rng)
    if cfg.algorithm == "dyna":
        from .dyna import DynaQ

        return DynaQ(table, cfg, rng)
    return QLearner(table, cfg, rng)
