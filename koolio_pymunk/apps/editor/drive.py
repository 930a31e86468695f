"""Test drive: the core's own :class:`~koolio_pymunk.task.env.KoolioEnv` driven by hand.

The editor drops the robot at the arena's start (facing the start heading, or east when
the heading is random) and steps the environment with the paper's five actions, so the
motion, the contacts, the sensors and the rewards are exactly the simulator's.

>>> from koolio_pymunk.world.arena import load_arena
>>> drive = TestDrive(load_arena("room"))
>>> drive.pose[:2]
(48.0, 48.0)
>>> drive.step("forward"), drive.step("right"), drive.step("stop")
('forward', 'turn', 'stop')
>>> drive.steps, drive.pose[0] > 48.0
(3, True)
"""

from __future__ import annotations

import math

from ...sensing.suite import Readings
from ...store.config import Config
from ...store.keyword import CAMERA_LEVELS, SONAR_LEVELS
from ...task.env import KoolioEnv
from ...world.arena import Arena
from ...world.physics import ACTION_NAMES, Action

ACTIONS: dict[str, Action] = {
    "stop": Action.STOP,
    "left": Action.ROTATE_LEFT,
    "right": Action.ROTATE_RIGHT,
    "forward": Action.FORWARD,
    "reverse": Action.REVERSE,
}
"""Test-drive action names (scripts and the HUD) -> the paper's actions."""


class TestDrive:
    """A hand-driven episode in the arena being edited (which must be valid)."""

    __test__ = False  # not a pytest test class

    def __init__(self, arena: Arena, config: Config | None = None, seed: int = 0) -> None:
        self.env = KoolioEnv(arena=arena, config=config or Config())
        self.seed = seed
        self.last_event: str | None = None
        self.total_reward = 0.0
        self.reset()

    def reset(self) -> None:
        """Back to the start (same seed: the same sensor noise every time)."""
        heading = self.env.arena.start.heading_deg
        radians = math.radians(heading) if heading is not None else 0.0
        self.env.reset(seed=self.seed, options={"heading": radians})
        self.last_event = None
        self.total_reward = 0.0
        self.last_action: str | None = None
        self.last_reward = 0.0

    def step(self, action: str | int) -> str | None:
        """Perform one action (a name of :data:`ACTIONS` or its number); the judged
        event (``goal``, ``end_of_world``, ``bump``, or the action's: ``forward`` ...)."""
        act = ACTIONS[action] if isinstance(action, str) else Action(action)
        _, reward, _, _, info = self.env.step(int(act))
        self.last_event = info["event"]
        self.last_action = ACTION_NAMES[act]
        self.last_reward = float(reward)
        self.total_reward += float(reward)
        return self.last_event

    # -- what the view shows ----------------------------------------------------------------
    @property
    def pose(self) -> tuple[float, float, float]:
        """``(x, y, heading radians)`` in the simulator's frame (``rotate_deg`` applied)."""
        return self.env.world.pose(0)

    @property
    def readings(self) -> Readings:
        return self.env.readings

    @property
    def steps(self) -> int:
        return self.env.steps

    @property
    def bumps(self) -> int:
        return self.env.bumps

    def robot_state(self) -> str:
        """``goal``, ``end_of_world``, ``bump`` or ``normal``: the paper's robot colours
        (the rule of :func:`koolio_pymunk.task.drawing.robot_state`)."""
        if self.last_event in ("goal", "end_of_world"):
            return self.last_event
        return "bump" if self.env.sensors.bump(self.readings) else "normal"

    def hud_lines(self) -> list[str]:
        """The encoded readings (paper's Show HUD) and the episode's counters."""
        r = self.readings
        s = self.env.sensors
        codes = s.encode(r)
        m = s.n_camera
        goal = " ".join(CAMERA_LEVELS[c] for c in codes[:m])
        eow = " ".join(CAMERA_LEVELS[c] for c in codes[m : 2 * m])
        sonar = " ".join(SONAR_LEVELS[c] for c in codes[2 * m : 2 * m + len(s.groups)])
        x, y, h = self.pose
        return [
            f"pose ({x:.1f}, {y:.1f}) heading {math.degrees(h):.0f} deg",
            f"goal cams (F L R): {goal}",
            f"end cams (F L R): {eow}",
            f"sonars: {sonar}",
            f"steps {self.steps}  bumps {self.bumps}  reward {self.total_reward:g}"
            + (f"  last: {self.last_action} {self.last_reward:g}" if self.last_action else ""),
        ]
