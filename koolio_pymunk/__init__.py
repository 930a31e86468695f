"""koolio-pymunk: the Koolio delivery robot (FCRAR 2008) on pymunk, learning by Q-learning.

Importing the package registers ``koolio_pymunk/Hallway-v0`` (the paper's hallway, with
Gymnasium's ``TimeLimit`` at the default 1500-step cap) with Gymnasium::

    import gymnasium as gym
    import koolio_pymunk

    env = gym.make("koolio_pymunk/Hallway-v0")

The import is light: :class:`KoolioEnv` (and with it pymunk and the numba-compiled
sensing kernels) is loaded on first use, so the command line's ``--help``, ``info``,
``check-arena``, ``export`` and ``plot`` start without compiling anything.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import gymnasium as gym

from ._version import __version__

if TYPE_CHECKING:
    from .task.env import KoolioEnv

__all__ = ["KoolioEnv", "__version__"]

gym.register(
    id="koolio_pymunk/Hallway-v0",
    entry_point="koolio_pymunk.task.env:KoolioEnv",
    vector_entry_point="koolio_pymunk.task.vector_env:KoolioVectorEnv",
    kwargs={"arena": "hallway"},
    # The default ``episode.max_steps`` (tests/task/test_env.py checks they agree); see the
    # KoolioEnv docstring for how the env's own cap and TimeLimit relate.
    max_episode_steps=1500,
)


def __getattr__(name: str) -> Any:
    """``koolio_pymunk.KoolioEnv`` imports :mod:`koolio_pymunk.task.env` on first use."""
    if name == "KoolioEnv":
        from .task.env import KoolioEnv

        return KoolioEnv
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
