"""Several robots in one arena (``--shared-arena``): :class:`SharedArena`.

Without it, ``--robots N`` puts each robot alone in its own copy of the arena (parallel
data collection). A :class:`SharedArena` holds N robots in one arena as bodies to each
other: one :class:`~koolio_pymunk.world.physics.World` with ``shared=True`` whose robot
``k`` is :class:`~koolio_pymunk.task.env.KoolioEnv` number ``k`` of :meth:`SharedArena.envs`
(each env keeps its own sensors, memory, generator and episode). The rules
(docs/multi-robot.md has each with its reason and measured effect):

* **Who moves first.** The robots step one after another in index order, each a whole
  step (act, move, read, judge, rescue), against the others where they stand then: robot
  ``k``'s move sees robots ``0 .. k-1`` after their move of this tick and the others
  before theirs. (The episode loops, :class:`~koolio_pymunk.learning.episodes.Robots`
  and the step engine, tick this way.)
* **What a robot is to another.** A wall: a move stops at it and slides along it, sonar
  rays end on its surface, it blocks a camera's sight line (the world and sensing floors).
* **Touching one** is a bump of its own: a sonar that reads Bump from a robot's surface
  makes the step's event ``robot_bump`` (``rewards.robot_bump``, by default the wall
  bump's value), before the wall ``bump`` in the rules' order (:mod:`.rules`).
* **Starts.** Robot ``k`` starts from ``shared.starts[k]`` or the arena's start point, on a
  free spot of that point's :class:`~koolio_pymunk.world.start_area.StartArea` drawn by its
  own generator; more robots from one point than its area holds are refused here, before
  anything runs.
* **Leaving.** A robot whose episode ended (goal, end of world, step cap) leaves the
  arena after its step (:meth:`KoolioEnv.leave`); its next episode enters at a free
  spot, or waits outside until one is free (:meth:`KoolioEnv.enter`).
* **Goals.** Robot ``k`` delivers to ``shared.goals[k]`` or the run's goal; with
  ``goal="random"`` each robot draws its own door at each episode from its generator.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..store.config import Config
from ..store.errors import ConfigError
from ..world.arena import Arena, check_start_point
from ..world.physics import World
from ..world.start_area import StartArea
from .end_zones import EndZones
from .env import KoolioEnv


class SharedArena:
    """``n_robots`` robots in ``arena`` under ``config`` (its ``shared`` section): the
    world they share and each robot's start area (module doc). Bad input (a start area
    that holds fewer robots than start there, a goal the arena lacks) is refused with
    :class:`~koolio_pymunk.store.errors.ConfigError`, one line."""

    def __init__(self, arena: Arena, config: Config, n_robots: int) -> None:
        if n_robots < 1:
            raise ValueError("a shared arena needs at least one robot")
        self.n_robots = n_robots
        self.world = World.from_arena(arena, config.robot.radius, n_robots, shared=True)
        sh = config.shared
        starts = [
            (float(sh.starts[k][0]), float(sh.starts[k][1])) if k < len(sh.starts) else
            (float(arena.start.at[0]), float(arena.start.at[1]))
            for k in range(n_robots)
        ]  # fmt: skip
        for k in range(min(n_robots, len(sh.starts))):
            check_start_point(
                arena, starts[k], config.robot.radius, arena.source, f"shared.starts[{k}]"
            )
        zones = EndZones(arena.to_world(), config.robot.radius)
        areas: dict[tuple[float, float], StartArea] = {}
        for point in starts:
            if point not in areas:
                areas[point] = StartArea(
                    self.world,
                    point,
                    sh.start_spread,
                    sh.start_gap,
                    keep=lambda p: not zones.contains(p[0], p[1]),
                )
        for point, area in areas.items():
            count = starts.count(point)
            if count > area.capacity:
                raise ConfigError(
                    f"{arena.source}: shared.start_spread: {count} robots start from "
                    f"({point[0]:g}, {point[1]:g}), whose start area holds {area.capacity} "
                    f"(spots {area.spacing:g} in apart within {sh.start_spread:g} in, "
                    f"{sh.start_gap:g} in clear of the walls, outside the end zones): use "
                    "fewer robots, a larger shared.start_spread or shared.starts"
                )
        self.areas = [areas[p] for p in starts]
        """Robot ``k``'s start area."""
        names = arena.goal_names()
        for k, name in enumerate(sh.goals):
            if name not in names:
                raise ConfigError(
                    f"{arena.source}: shared.goals[{k}]: no goal named {name!r} "
                    f"(goals: {', '.join(names)})"
                )
        self.goals: list[str | None] = [
            sh.goals[k] if k < len(sh.goals) else None for k in range(n_robots)
        ]
        """Robot ``k``'s own goal (None: the run's)."""

    @classmethod
    def envs(
        cls,
        n_robots: int,
        arena: str | Path | Arena = "hallway",
        config: Any = None,
        goal: str | None = None,
        world: str | Path | None = None,
        observe_goal: bool = False,
        render_mode: str | None = None,
    ) -> list[KoolioEnv]:
        """``n_robots`` envs, one per robot, sharing one arena (``KoolioEnv``'s
        arguments; ``render_mode`` for robot 0's, which draws them all)."""
        first = KoolioEnv(arena, config, goal, world=world, observe_goal=observe_goal)
        return cls.of(first, n_robots, render_mode)

    @classmethod
    def of(cls, env: KoolioEnv, n_robots: int, render_mode: str | None = None) -> list[KoolioEnv]:
        """``n_robots`` envs like ``env`` (its arena, configuration, world and goal,
        ``random`` included) sharing one arena: the robots of ``--shared-arena``
        (``render_mode`` for robot 0's, which draws them all)."""
        share = cls(env.arena, env.config, n_robots)
        goal = "random" if env.random_goal else env.goal_name
        return [
            share.robot_env(k, env, goal, render_mode if k == 0 else None) for k in range(n_robots)
        ]

    def robot_env(
        self, k: int, like: KoolioEnv, goal: str | None, render_mode: str | None = None
    ) -> KoolioEnv:
        """Robot ``k``'s env: ``like``'s arena, configuration and world, in this arena."""
        env = KoolioEnv(
            like.arena,
            config=like.config,
            goal=self.goals[k] or goal,
            render_mode=render_mode,
            observe_goal=like.observe_goal,
            share=self,
            robot=k,
        )
        env.world_name = like.world_name
        env.home_goal = like.home_goal  # the arena file's own goal, as a sibling keeps it
        return env
