"""The robot's memory: a few fields of its own recent history in the state (``sensors.memory``).

The paper's state is what the sensors read now. With side cameras at +-90 degrees it
aliases: between the cameras' arcs a door plate the robot has just turned away from and
one it has not reached yet read the same, and no policy that sees only the present can
be right in both. A memory field remembers what a real robot's controller can: what it
saw and what it did (``MemoryConfig``):

* ``GoalMemory``: the camera that last saw the goal plate (0: none; ``1 + c`` for camera
  ``c``). A camera *sees* a target when its reading is not "nothing seen", i.e. below
  ``really_long_distance`` (within ``max_camera_view`` after noise); when several see it
  the nearest reading wins, ties to the lower camera. With ``forget_after`` K > 0 a
  sighting is forgotten after K steps in which no camera saw it.
* ``EoWMemory``: the same for the end-of-world markers.
* ``LastAction``: the action just taken (0: none yet in this episode; ``1 + action``).

The memory is updated at every reading: at the start of an episode (cleared first), after
every action, and after a rescue (which records sightings but neither ages them nor
changes the last action: the robot did not choose the rescue's moves). Its fields come
after the sensors' in the keyword (:func:`~koolio_pymunk.store.config.state_fields`);
``robot_runtime.Memory`` is its standard-library twin (``tests/test_robot_runtime.py``).

>>> from koolio_pymunk.store.config import MemoryConfig
>>> mem = Memory(MemoryConfig(goal_camera=True, forget_after=2, previous_action=True),
...              n_camera=3, far=10_000.0)
>>> mem.reset()
>>> mem.update([10_000.0, 80.0, 60.0], [10_000.0] * 3, None).codes
(3, 0)
>>> mem.update([10_000.0] * 3, [10_000.0] * 3, 3).codes   # forward, nothing seen: age 1
(3, 4)
>>> mem.update([10_000.0] * 3, [10_000.0] * 3, 1).codes   # age 2: forgotten
(0, 2)
>>> mem.key(0b101, [2, 3]) == (0b101 << 5) | (0 << 3) | 2  # then 2 + 3 bits
True
"""

from __future__ import annotations

from collections.abc import Sequence

from ..store.config import MemoryConfig


class Memory:
    """What one robot remembers (module doc); :attr:`codes` are its state fields' codes."""

    def __init__(self, cfg: MemoryConfig, n_camera: int, far: float) -> None:
        self.cfg = cfg
        self.n_camera = n_camera
        self.far = far
        self.on = cfg.goal_camera or cfg.eow_camera or cfg.previous_action
        """Any memory field in the state."""
        self.goal = 0
        self.eow = 0
        self.action = 0
        self._goal_age = 0
        self._eow_age = 0

    def reset(self) -> None:
        """A new episode: nothing seen, no action yet."""
        self.goal = self.eow = self.action = 0
        self._goal_age = self._eow_age = 0

    def update(self, goal: Sequence[float], eow: Sequence[float], action: int | None) -> Memory:
        """Remember a reading (``goal``, ``eow``: the cameras' distances) made after
        ``action`` (None: after a reset or a rescue, no action of the robot's own)."""
        moved = action is not None
        self.goal, self._goal_age = self._sighting(goal, self.goal, self._goal_age, moved)
        self.eow, self._eow_age = self._sighting(eow, self.eow, self._eow_age, moved)
        if moved:
            self.action = 1 + int(action)
        return self

    def _sighting(
        self, readings: Sequence[float], held: int, age: int, moved: bool
    ) -> tuple[int, int]:
        """The remembered camera and its age after one reading."""
        best, best_d = 0, self.far
        for c in range(self.n_camera):
            d = readings[c]
            if d < best_d:
                best, best_d = 1 + c, d
        if best:
            return best, 0
        if not moved or not held:
            return held, age
        age += 1
        k = self.cfg.forget_after
        return (0, 0) if k > 0 and age >= k else (held, age)

    @property
    def codes(self) -> tuple[int, ...]:
        """The memory's codes in keyword order (only the fields that are on)."""
        cfg = self.cfg
        out: list[int] = []
        if cfg.goal_camera:
            out.append(self.goal)
        if cfg.eow_camera:
            out.append(self.eow)
        if cfg.previous_action:
            out.append(self.action)
        return tuple(out)

    def key(self, sensor_key: int, bits: Sequence[int]) -> int:
        """The state key: ``sensor_key`` followed by the memory's codes, each in its
        field's ``bits`` (the keyword layout's, in order)."""
        key = sensor_key
        for code, b in zip(self.codes, bits):
            key = (key << b) | code
        return key
