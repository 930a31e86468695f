"""Auto rescue (paper §5.4.7): back a bumping robot out and spin it to a random heading.

When ``auto_rescue_toggle`` is on, the episode is past ``max_steps_before_rescue`` steps
and the robot reads Bump, a rescue happens with probability ``rescue_chance``:
``Rescue_Robot`` performs a random number (0..``rescue_max_backup``) of Reverse moves,
each resolved against the walls by pymunk like any other move, then turns the robot to a
uniformly random heading. The episode is marked ``has_been_rescued``. A rescue can also
be forced (the viewer's Rescue button), regardless of the toggle.
"""

from __future__ import annotations

import math

import numpy as np

from ..store.config import RescueConfig
from ..world.physics import World


def wants_rescue(cfg: RescueConfig, steps: int, bump: bool, rng: np.random.Generator) -> bool:
    """Whether auto rescue fires this step (draws from ``rng`` only when eligible)."""
    if not (cfg.auto_rescue_toggle and bump and steps > cfg.max_steps_before_rescue):
        return False
    return bool(rng.random() < cfg.rescue_chance)


def rescue_robot(
    world: World, robot: int, cfg: RescueConfig, distance: float, rng: np.random.Generator
) -> int:
    """``Rescue_Robot``: random reverses then a random spin. Returns the reverses made."""
    backups = int(rng.integers(0, cfg.rescue_max_backup + 1))
    for _ in range(backups):
        world.move(robot, -distance)
    x, y, _ = world.pose(robot)
    world.place(robot, (x, y), float(rng.uniform(0.0, 2.0 * math.pi)))
    return backups
