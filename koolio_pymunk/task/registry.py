"""The registered Gymnasium ids: every shipped arena, world and profile, in one table.

``import koolio_pymunk`` calls :func:`register_envs`, so ``gymnasium.make`` and
``gymnasium.pprint_registry()`` know every id of :data:`ENVS` under the namespace
``koolio_pymunk``. The same function is the package's ``gymnasium.envs`` entry point
(``pyproject.toml``): the plugin mechanism of Gymnasium 0.26-0.29
(``registration.load_env_plugins``, run by ``import gymnasium``), which called every such
entry point inside ``gymnasium.envs.registration.namespace(name)``. Gymnasium 1.0 dropped
the loader (the package needs 1.0 or later), so there the ids come from the import, or
from naming the module in the id: ``gym.make("koolio_pymunk:koolio_pymunk/Room-v0")``.

Each row is the :class:`~koolio_pymunk.task.env.KoolioEnv` keyword arguments of one id;
:func:`register_envs` adds what every id shares (:data:`ENTRY_POINT`,
:data:`VECTOR_ENTRY_POINT`, :data:`MAX_EPISODE_STEPS`). A row may carry other
``gymnasium.register`` arguments under :data:`REGISTER_KEYS`. docs/envs.md describes every id;
tests/task/test_registry.py holds the table to the shipped arenas, worlds and profiles.

This module imports nothing of the package (``import koolio_pymunk`` stays light: no
pymunk, no numba); the env is loaded by ``gymnasium.make``.

>>> import gymnasium as gym
>>> "koolio_pymunk/Room-v0" in gym.registry and gym.spec("koolio_pymunk/Room-v0").kwargs
{'arena': 'room'}
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym

#: The namespace of every id (``koolio_pymunk/Room-v0``); the entry point's name.
NAMESPACE = "koolio_pymunk"
#: What ``gymnasium.make`` builds.
ENTRY_POINT = "koolio_pymunk.task.env:KoolioEnv"
#: What ``gymnasium.make_vec`` builds by default (``vectorization_mode`` left out, or
#: ``"vector_entry_point"``): the envs stepped together on the compiled step engine, with
#: the trajectories and ``info`` of Gymnasium's ``SyncVectorEnv`` of the same envs.
VECTOR_ENTRY_POINT = "koolio_pymunk.task.vector_env:KoolioVectorEnv"
#: Gymnasium's ``TimeLimit`` of every id: the configuration's default ``episode.max_steps``
#: (every shipped profile keeps it; tests/task/test_registry.py checks that they agree).
MAX_EPISODE_STEPS = 1500
#: Keys of a row that are ``gymnasium.register`` arguments, not the env's keyword arguments.
REGISTER_KEYS = ("vector_entry_point", "max_episode_steps", "reward_threshold")

#: Every id (without the namespace) and its row: the env's keyword arguments (and any of
#: :data:`REGISTER_KEYS`). Arenas by name, worlds as ``Hallway<World>``, configuration
#: profiles as ``Hallway<Profile>`` (the profile's name in CamelCase).
ENVS: dict[str, dict[str, Any]] = {
    # the shipped arenas (arenas/*.yaml), ideal world, default configuration
    "Hallway-v0": {"arena": "hallway"},
    "Room-v0": {"arena": "room"},
    "Obstacles-v0": {"arena": "obstacles"},
    # the hallway with a goal door drawn per episode
    "HallwayAnyDoor-v0": {"arena": "hallway", "goal": "random"},
    # the realistic worlds (profiles/koolio-real*.yaml laid over the default configuration)
    "HallwayReal-v0": {"arena": "hallway", "world": "koolio-real"},
    "HallwayRealDR-v0": {"arena": "hallway", "world": "koolio-real-dr"},
    # the configuration profiles (profiles/*.yaml)
    "HallwayPaper-v0": {"arena": "hallway", "config": "paper"},
    "HallwayPaperMemory-v0": {"arena": "hallway", "config": "paper-memory"},
    "HallwayPaperMemoryQLambda-v0": {"arena": "hallway", "config": "paper-memory-qlambda"},
    "HallwayQLambdaNoUndo-v0": {"arena": "hallway", "config": "qlambda-no-undo"},
    "HallwayOneStepQ-v0": {"arena": "hallway", "config": "one-step-q"},
}


def env_id(name: str) -> str:
    """The full id of a row of :data:`ENVS`.

    >>> env_id("Room-v0")
    'koolio_pymunk/Room-v0'
    """
    return f"{NAMESPACE}/{name}"


def register_envs() -> None:
    """Register every id of :data:`ENVS` that is not registered yet (calling it again, as
    an entry-point loader does after the import, changes nothing and warns nothing)."""
    for name, row in ENVS.items():
        full = env_id(name)
        if full in gym.registry:
            continue
        extra = {k: v for k, v in row.items() if k in REGISTER_KEYS}
        extra.setdefault("max_episode_steps", MAX_EPISODE_STEPS)
        extra.setdefault("vector_entry_point", VECTOR_ENTRY_POINT)
        kwargs = {k: v for k, v in row.items() if k not in REGISTER_KEYS}
        gym.register(id=full, entry_point=ENTRY_POINT, kwargs=kwargs, **extra)
