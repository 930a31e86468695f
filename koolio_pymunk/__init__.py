"""koolio-pymunk: the Koolio delivery robot (FCRAR 2008) on pymunk, learning by Q-learning.

Importing the package registers its Gymnasium ids (:mod:`koolio_pymunk.task.registry`:
every shipped arena, world and profile, e.g. ``koolio_pymunk/Hallway-v0``, the paper's
hallway, with Gymnasium's ``TimeLimit`` at the default 1500-step cap; docs/envs.md lists
them)::

    import gymnasium as gym
    import koolio_pymunk

    env = gym.make("koolio_pymunk/Hallway-v0")

Robots sharing one arena are a PettingZoo ``ParallelEnv``
(``koolio_pymunk.parallel_env(robots=4)``, the ``multi`` extra; docs/multi-robot.md).

The import is light: :class:`KoolioEnv` (and with it pymunk and the numba-compiled
sensing kernels) is loaded on first use, so the command line's ``--help``, ``info``,
``check-arena``, ``export`` and ``plot`` start without compiling anything.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ._version import __version__
from .task.registry import register_envs

if TYPE_CHECKING:
    from .task.env import KoolioEnv

__all__ = ["KoolioEnv", "__version__", "parallel_env"]

register_envs()


def __getattr__(name: str) -> Any:
    """``koolio_pymunk.KoolioEnv`` imports :mod:`koolio_pymunk.task.env` on first use."""
    if name == "KoolioEnv":
        from .task.env import KoolioEnv

        return KoolioEnv
    if name == "parallel_env":
        from .store.extras import multi_extra

        with multi_extra("parallel_env"):
            from .task.parallel_env import parallel_env

        return parallel_env
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
