"""The compiled episode against the Python episode loop, episode by episode.

:func:`compare_episodes` runs the same seeded training twice side by side, once with
:class:`~koolio_pymunk.learning.episodes.Episodes`' Python steps (the reference) and once
compiled (:mod:`koolio_pymunk.learning.episode_kernel`), and compares after every
episode its log row, the robot's pose and state, and the whole Q-table, bit for bit. Used
by ``tests/learning/test_episode_kernel.py`` (a few episodes) and by
``tools/agreement.py --episodes N`` (long runs).

>>> r = compare_episodes(episodes=2, max_steps=30)
>>> r.episodes, r.mismatches, r.steps > 0
(2, 0, True)
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from typing import Any

from ..store.config import load_config
from ..task.env import KoolioEnv
from .algorithms import make_learner
from .episodes import Episodes
from .qtable import QTable


@dataclass
class EpisodeAgreement:
    """What :func:`compare_episodes` found."""

    arena: str
    world: str
    episodes: int
    steps: int
    mismatches: int
    """Episodes after which the row, the pose, the state or the table differed."""
    first_mismatch: int
    """The first such episode (-1: none)."""
    states: int
    """Rows of the table at the end."""
    seconds: float

    def as_dict(self) -> dict[str, Any]:
        """The row's fields by name (``tools/agreement.py``'s JSON)."""
        return asdict(self)


def _side(arena: str, world: str | None, overrides: dict, seed: int, compiled: bool):
    env = KoolioEnv(arena, config=load_config(overrides=overrides, world=world))
    table = QTable(env.layout, {}, env.config.learner.q_init)
    agent = make_learner(table, env.config.learner, None)
    loop = Episodes(env, agent, seed, compiled=compiled)
    if compiled and loop.compiled is None:
        raise ValueError(f"this configuration does not run compiled: {loop.compiled_reason}")
    return env, table, loop


def compare_episodes(
    arena: str = "hallway",
    world: str | None = None,
    episodes: int = 10,
    seed: int = 0,
    max_steps: int | None = None,
    overrides: dict | None = None,
) -> EpisodeAgreement:
    """Train ``episodes`` episodes of ``arena`` (in ``world``; ``overrides`` laid over the
    configuration, ``max_steps`` the step cap) both ways and compare (module doc)."""
    over = dict(overrides or {})
    if max_steps is not None:
        over["episode"] = {**over.get("episode", {}), "max_steps": max_steps}
    t = time.perf_counter()
    ref_env, ref_table, ref = _side(arena, world, over, seed, compiled=False)
    env, table, fast = _side(arena, world, over, seed, compiled=True)
    steps = mismatches = 0
    first = -1
    for e in range(episodes):
        ref.begin(e)
        fast.begin(e)
        a, b = ref.run(), fast.run()
        steps += a.steps
        same = (
            a.row() == b.row()
            and ref_env.world.pose(0) == env.world.pose(0)
            and ref_env.state_key == env.state_key
            and ref_table.rows == table.rows
        )
        if not same:
            mismatches += 1
            first = e if first < 0 else first
    return EpisodeAgreement(
        arena,
        world or "ideal",
        episodes,
        steps,
        mismatches,
        first,
        len(table.rows),
        round(time.perf_counter() - t, 1),
    )
