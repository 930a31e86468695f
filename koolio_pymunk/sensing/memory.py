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
* ``GoalBearing``: where the goal plate was last seen, turned with the robot's own turns:
  the seeing camera's angle when a camera sees it, then minus the turn arc at every
  RotateLeft and plus it at every RotateRight (what the controller commanded: dead
  reckoning, blind to the drive's errors and to the moves' sideways shift), in whole
  millidegrees so that every copy computes the same integers; its code is the quarter it
  falls in (:data:`~koolio_pymunk.store.config.BEARINGS`: ahead within 45 degrees of the
  front, left from 45 to 135, right likewise, behind beyond 135 either way). Forgotten
  like the cameras' sightings.

The memory is updated at every reading: at the start of an episode (cleared first), after
every action, and after a rescue (which records sightings but neither ages them, turns
the bearing nor changes the last action: the robot did not choose the rescue's moves).
Its fields come after the sensors' in the keyword
(:func:`~koolio_pymunk.store.config.state_fields`); ``robot_runtime.Memory`` is its
standard-library twin (``tests/test_robot_runtime.py``).

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

The bearing of a plate the left camera (+90 degrees) saw, as the robot turns towards it
by 30 degrees a step (codes: 2 left, 1 ahead, 4 right):

>>> mem = Memory(MemoryConfig(goal_bearing=True), n_camera=3, far=10_000.0,
...              camera_deg=[0.0, 90.0, -90.0], turn_deg=30.0)
>>> mem.reset()
>>> [mem.update([10_000.0, 50.0, 10_000.0], [10_000.0] * 3, None).codes]
[(2,)]
>>> nothing = [10_000.0] * 3
>>> [mem.update(nothing, nothing, 1).codes for _ in range(5)]  # RotateLeft, 5 times
[(2,), (1,), (1,), (1,), (4,)]
"""

from __future__ import annotations

from collections.abc import Sequence

from ..store.config import MemoryConfig
from ..world.physics import Action

ROTATE_LEFT, ROTATE_RIGHT = int(Action.ROTATE_LEFT), int(Action.ROTATE_RIGHT)


#: Millidegrees in a full turn, and the bearing's quarters' edges (``GoalBearing``).
FULL_TURN_MDEG = 360_000
QUARTER_MDEG = 45_000


def millidegrees(deg: float) -> int:
    """An angle in whole millidegrees, as every copy of the bearing counts it."""
    return round(deg * 1000.0)


def turned(bearing: int, action: int, turn: int) -> int:
    """``bearing`` (millidegrees, left positive) after ``action`` by a robot turning
    ``turn`` millidegrees a rotation, in [-180, 180) degrees.

    >>> turned(90_000, ROTATE_LEFT, 30_000), turned(170_000, ROTATE_RIGHT, 30_000)
    (60000, -160000)
    """
    if action == ROTATE_LEFT:
        bearing -= turn
    elif action == ROTATE_RIGHT:
        bearing += turn
    return (bearing + FULL_TURN_MDEG // 2) % FULL_TURN_MDEG - FULL_TURN_MDEG // 2


def bearing_code(bearing: int) -> int:
    """The quarter of ``bearing`` (millidegrees): 1 ahead, 2 left, 3 behind, 4 right
    (:data:`~koolio_pymunk.store.config.BEARINGS`).

    >>> [bearing_code(millidegrees(d)) for d in (0, 44.9, 45, 90, 135, 180, -135, -45)]
    [1, 1, 2, 2, 3, 3, 3, 4]
    """
    if -QUARTER_MDEG < bearing < QUARTER_MDEG:
        return 1
    if QUARTER_MDEG <= bearing < 3 * QUARTER_MDEG:
        return 2
    if -3 * QUARTER_MDEG < bearing <= -QUARTER_MDEG:
        return 4
    return 3


class Memory:
    """What one robot remembers (module doc); :attr:`codes` are its state fields' codes.

    ``camera_deg`` (the cameras' angles) and ``turn_deg`` (the rotation's arc) are the
    bearing's, needed only with ``goal_bearing``."""

    def __init__(
        self,
        cfg: MemoryConfig,
        n_camera: int,
        far: float,
        camera_deg: Sequence[float] = (),
        turn_deg: float = 30.0,
    ) -> None:
        self.cfg = cfg
        self.n_camera = n_camera
        self.far = far
        if cfg.goal_bearing and len(camera_deg) != n_camera:
            raise ValueError(f"goal_bearing needs the {n_camera} cameras' angles (camera_deg)")
        self.camera_mdeg = [millidegrees(d) for d in camera_deg]
        """Each camera's angle, millidegrees."""
        self.turn_mdeg = millidegrees(turn_deg)
        """A rotation's arc, millidegrees."""
        self.on = cfg.on
        """Any memory field in the state."""
        self.reset()

    def reset(self) -> None:
        """A new episode: nothing seen, no action yet."""
        self.goal = self.eow = self.action = self.bearing = 0
        self._goal_age = self._eow_age = self._bearing_age = self.bearing_mdeg = 0

    def update(self, goal: Sequence[float], eow: Sequence[float], action: int | None) -> Memory:
        """Remember a reading (``goal``, ``eow``: the cameras' distances) made after
        ``action`` (None: after a reset or a rescue, no action of the robot's own)."""
        moved = action is not None
        seen = self._nearest(goal)
        self.goal, self._goal_age = self._sighting(seen, self.goal, self._goal_age, moved)
        self.eow, self._eow_age = self._sighting(self._nearest(eow), self.eow, self._eow_age, moved)
        if self.cfg.goal_bearing:
            self._turn_bearing(seen, action)
        if moved:
            self.action = 1 + int(action)  # type: ignore[arg-type]
        return self

    def _nearest(self, readings: Sequence[float]) -> int:
        """The camera that sees the target nearest (0: none; ``1 + c``)."""
        best, best_d = 0, self.far
        for c in range(self.n_camera):
            d = readings[c]
            if d < best_d:
                best, best_d = 1 + c, d
        return best

    def _sighting(self, seen: int, held: int, age: int, moved: bool) -> tuple[int, int]:
        """The remembered camera and its age after one reading that ``seen``."""
        if seen:
            return seen, 0
        if not moved or not held:
            return held, age
        age += 1
        k = self.cfg.forget_after
        return (0, 0) if k > 0 and age >= k else (held, age)

    def _turn_bearing(self, seen: int, action: int | None) -> None:
        """The goal's bearing after one reading (``seen``: the camera that sees it)."""
        if seen:
            self.bearing_mdeg = self.camera_mdeg[seen - 1]
        elif action is not None and self.bearing:
            self.bearing_mdeg = turned(self.bearing_mdeg, action, self.turn_mdeg)
        held, self._bearing_age = self._sighting(
            seen, self.bearing, self._bearing_age, action is not None
        )
        self.bearing = bearing_code(self.bearing_mdeg) if held else 0

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
        if cfg.goal_bearing:
            out.append(self.bearing)
        return tuple(out)

    def key(self, sensor_key: int, bits: Sequence[int]) -> int:
        """The state key: ``sensor_key`` followed by the memory's codes, each in its
        field's ``bits`` (the keyword layout's, in order)."""
        key = sensor_key
        for code, b in zip(self.codes, bits):
            key = (key << b) | code
        return key
