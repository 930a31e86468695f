"""Motion errors of a real differential drive (``realism.motion``), off by default.

A Forward or Reverse move drifts by ``drift_deg`` (plus a Gaussian ``drift_sigma_deg``)
and travels ``1 + N(0, slip_sigma)`` of its distance; a turn is off by
``N(0, turn_sigma_deg)``. The world then drives the arc
(:meth:`~koolio_pymunk.world.physics.World.drive`): its chord is a swept move like any
other, stopped and slid by the walls pymunk reports. Every draw comes from the episode's
generator, and only for the models that are on.
"""

from __future__ import annotations

import math

import numpy as np

from ..store.realism_config import MotionRealism


class MotionErrors:
    """Motion errors of one robot: what a Forward, Reverse or turn really does.

    :meth:`perturb` turns an action into ``(distance, heading change during the move,
    turn error)``; draws come from ``rng`` only for the random parts that are on (a
    move: one call of 2 normals when ``drift_sigma_deg`` or ``slip_sigma`` is on; a turn:
    one normal when ``turn_sigma_deg`` is on).
    """

    def __init__(self, cfg: MotionRealism) -> None:
        self.configure(cfg)

    def configure(self, cfg: MotionRealism) -> None:
        self.drift = math.radians(cfg.drift_deg)
        self.drift_sigma = math.radians(cfg.drift_sigma_deg)
        self.slip_sigma = cfg.slip_sigma
        self.turn_sigma = math.radians(cfg.turn_sigma_deg)
        self.random_move = self.drift_sigma > 0.0 or self.slip_sigma > 0.0

    def move(self, sign: float, distance: float, rng: np.random.Generator) -> tuple[float, float]:
        """``(signed distance, heading change)`` of a move of ``sign * distance``."""
        turn = sign * self.drift
        if self.random_move:
            e = rng.standard_normal(2)
            turn += self.drift_sigma * float(e[0])
            distance = max(0.0, distance * (1.0 + self.slip_sigma * float(e[1])))
        return sign * distance, turn

    def turn(self, arc: float, rng: np.random.Generator) -> float:
        """The rotation a turn of ``arc`` radians really makes."""
        if self.turn_sigma > 0.0:
            return arc + self.turn_sigma * float(rng.standard_normal())
        return arc
