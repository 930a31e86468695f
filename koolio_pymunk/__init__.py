"""koolio-pymunk: the Koolio delivery robot (FCRAR 2008) on pymunk, learning by Q-learning.

Importing the package registers ``koolio_pymunk/Hallway-v0`` (the paper's hallway) with
Gymnasium::

    import gymnasium as gym
    import koolio_pymunk

    env = gym.make("koolio_pymunk/Hallway-v0")
"""

from __future__ import annotations

import gymnasium as gym

from .env import KoolioEnv

__all__ = ["KoolioEnv"]
__version__ = "0.1.0"

gym.register(
    id="koolio_pymunk/Hallway-v0",
    entry_point="koolio_pymunk.env:KoolioEnv",
    kwargs={"arena": "hallway"},
)
