"""Robots sharing one arena as a PettingZoo ``ParallelEnv``: :class:`KoolioParallelEnv`.

Made by :func:`koolio_pymunk.parallel_env` (needs the ``multi`` extra: ``pip install
'koolio-pymunk[multi]'``). Multi-agent libraries (RLlib, TorchRL / BenchMARL, MARLlib)
take this API.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from ..world.arena import Arena
from .env import KoolioEnv
from .shared_arena import SharedArena


class KoolioParallelEnv(ParallelEnv):
    """``robots`` Koolio robots in one arena, each an agent (``robot_0``, ``robot_1``, ...).

    **Arena, configuration, world, goal** as :class:`~koolio_pymunk.task.env.KoolioEnv`'s
    (``arena``, ``config``, ``world``, ``goal``: ``"random"`` draws a door per robot per
    episode); the configuration's ``shared`` section gives robots their own starts and
    goals and sizes the start areas. The rules of a shared arena (who moves first, what a
    robot is to another, ``robot_bump``, starts) are
    :mod:`koolio_pymunk.task.shared_arena`'s.

    **Spaces.** Each agent's observation and action spaces are the single env's
    (``MultiDiscrete`` readings in keyword order, ``Discrete(5)``), the same object at
    every call.

    **reset(seed, options)** puts every robot on a free start spot, robot 0 first; with a
    seed, robot ``k``'s env is reset with :func:`robot_seed` ``(seed, k)`` (all of an
    episode's randomness, starts, noise and rescues, comes from the robots' generators, so
    the same seed gives the same episode). ``options`` is accepted
    for PettingZoo's API and not used: the starts come from the start areas.

    **step(actions)** takes an action for every agent still in :attr:`agents` and steps
    them in index order (robot ``k`` moves against robots ``0 .. k-1`` where this step
    left them); a missing action or one outside ``Discrete(5)`` is refused with
    ``ValueError`` before anything moves. It returns per-agent observations, rewards,
    terminations, truncations and ``info`` (the single env's keys, ``reward_terms`` naming
    the winning term, ``robot_bump`` included, plus ``robot``: the agent's index). An
    agent whose episode ended (goal, end of world, step cap) leaves the arena after its
    step and :attr:`agents`; the episode ends when every agent has left. (The project's
    trainers restart a robot that left; PettingZoo's agents do not come back within an
    episode.)

    **Rendering.** ``render_mode`` ``"rgb_array"`` or ``"human"``: the arena with every
    robot in its own colour and number, the sensors, HUD and status of robot 0.

    Steps run the Python reference (:class:`KoolioEnv` over pymunk and the compiled
    sensors); ``koolio-pm train --shared-arena`` runs the same steps on the compiled step
    engine, bit for bit (``tools/agreement.py --shared-arena``).

    >>> import koolio_pymunk
    >>> env = koolio_pymunk.parallel_env(robots=2, arena="room")
    >>> obs, infos = env.reset(seed=0)
    >>> env.agents, obs["robot_1"].shape
    (['robot_0', 'robot_1'], (12,))
    >>> obs, rewards, term, trunc, infos = env.step({"robot_0": 3, "robot_1": 1})
    >>> sorted(infos["robot_1"]["reward_terms"])[:3], infos["robot_1"]["robot"]
    (['bump', 'end_of_world', 'forward'], 1)
    """

    metadata = {"render_modes": ["human", "rgb_array"], "name": "koolio_shared_v0"}

    def __init__(
        self,
        robots: int = 2,
        arena: str | Path | Arena = "hallway",
        goal: str | None = None,
        config: Any = None,
        world: str | Path | None = None,
        render_mode: str | None = None,
        max_steps: int | None = None,
    ) -> None:
        if not isinstance(robots, int) or robots < 1:
            raise ValueError(f"robots: a number of robots >= 1, got {robots!r}")
        self.envs: list[KoolioEnv] = SharedArena.envs(
            robots, arena, config, goal, world, render_mode=render_mode
        )
        if max_steps is not None:
            for env in self.envs:
                env.config.episode.max_steps = int(max_steps)
        self.render_mode = render_mode
        self.possible_agents = [f"robot_{k}" for k in range(robots)]
        self.agents: list[str] = []
        self._index = {a: k for k, a in enumerate(self.possible_agents)}

    def observation_space(self, agent: str) -> spaces.Space:
        """The agent's observation space: its env's, the same object at every call."""
        return self.envs[self._index[agent]].observation_space

    def action_space(self, agent: str) -> spaces.Space:
        """The agent's action space: its env's, the same object at every call."""
        return self.envs[self._index[agent]].action_space

    def reset(
        self, seed: int | None = None, options: dict | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, dict]]:
        for env in self.envs:
            env.leave()
        obs, infos = {}, {}
        for k, (agent, env) in enumerate(zip(self.possible_agents, self.envs)):
            env.reset(seed=None if seed is None else robot_seed(seed, k))
            if env.waiting:  # the capacity check makes this impossible: say so if not
                raise RuntimeError(f"{agent}: no free start spot at the reset")
            obs[agent], infos[agent] = self._observe(k)
        self.agents = list(self.possible_agents)
        if self.render_mode == "human":
            self.render()
        return obs, infos

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        missing = [a for a in self.agents if a not in actions]
        if missing:
            raise ValueError(f"actions: no action for {missing[0]} (every agent acts)")
        for agent in self.agents:
            if not self.envs[self._index[agent]].action_space.contains(actions[agent]):
                raise ValueError(f"actions: {agent}: {actions[agent]!r} is not an action (0..4)")
        obs, rewards, terms, truncs, infos = {}, {}, {}, {}, {}
        for agent in self.agents:
            k = self._index[agent]
            env = self.envs[k]
            _, reward, terminated, truncated = env.transition(int(actions[agent]))
            if terminated or truncated:
                env.leave()
            obs[agent], infos[agent] = self._observe(k)
            rewards[agent] = float(reward)
            terms[agent], truncs[agent] = bool(terminated), bool(truncated)
        self.agents = [a for a in self.agents if not (terms[a] or truncs[a])]
        if self.render_mode == "human":
            self.render()
        return obs, rewards, terms, truncs, infos

    def render(self) -> np.ndarray | None:
        """Robot 0's picture, every robot in it (:meth:`KoolioEnv.render`)."""
        return self.envs[0].render() if self.render_mode is not None else None

    def close(self) -> None:
        for env in self.envs:
            env.close()

    def _observe(self, k: int) -> tuple[np.ndarray, dict[str, Any]]:
        """Robot ``k``'s observation and ``info`` (its env's, and ``robot``: ``k``)."""
        obs, info = self.envs[k].observe()
        return obs, {**info, "robot": k}


def robot_seed(seed: int, k: int) -> int:
    """Robot ``k``'s env seed when the parallel env is reset with ``seed``: one number
    of ``SeedSequence([seed, k])``, so robots' streams never coincide.

    >>> robot_seed(0, 0) != robot_seed(0, 1) != robot_seed(1, 0)
    True
    """
    return int(np.random.SeedSequence([seed, k]).generate_state(1)[0])


#: PettingZoo's convention: ``parallel_env(...)`` makes the env (the class's arguments).
parallel_env = KoolioParallelEnv
