"""Sensors: sonar ring, cameras and compass (paper §5.4.3), and their interval encoding.

Every distance is in inches from the robot's *edge* (centre distance minus radius), then
noised, then encoded (Tables 6 and 7).

* **Sonar** ``k`` looks along ``heading + sonar_sensors_deg[k]``; its ``sonar_arc_deg``
  cone is split into ``sub_arcs`` smaller arcs and one ray is cast through the centre of
  each (pymunk ``segment_query_first``, walls only). The reading is the nearest hit over
  the sub-arcs (a sonar cannot see through walls), minus the radius, times
  ``1 + noise``. Nothing within ``max_range``: ``really_long_distance``.
* **Camera** ``c`` looks along ``heading + camera_sensors_deg[c]`` with a
  ``camera_arc_deg`` field of view and reports two distances: to the active goal, and to
  the nearest end-of-world marker. A target counts when it lies inside the arc and no
  wall *segment* crosses the sight line (one pymunk query from the centre to the target;
  a wall whose infinite line crosses the sight line beyond the segment's ends does not
  block). The nearest candidate is noised and then compared with ``max_camera_view``;
  beyond it, or with no candidate, the reading is ``really_long_distance``.
* **Compass**: heading / 2pi * 256 with 25 % noise, encoded East/North/West/South.

Sonar groups (paper: 1&2 and 5&6) are averaged before encoding. The state is the tuple
of codes in keyword order: goal cameras, end-of-world cameras, sonar groups (then the
compass if ``compass.in_state``).

Example (noise off, a robot of radius 10 at the centre of a 100 x 100 box)::

    >>> import numpy as np
    >>> from koolio_pymunk.config import SensorConfig
    >>> from koolio_pymunk.world import World
    >>> box = [((0, 0), (100, 0)), ((100, 0), (100, 100)), ((100, 100), (0, 100)),
    ...        ((0, 100), (0, 0))]
    >>> world = World(box, radius=10)
    >>> world.place(0, (50, 50), 0.0)
    >>> cfg = SensorConfig(); cfg.noise.model = "none"
    >>> suite = SensorSuite(cfg, world, goal=(90, 50), markers=[])
    >>> r = suite.read(world.pose(0), np.random.default_rng(0))
    >>> round(float(r.sonar[0]), 6), round(float(r.goal[0]), 6)
    (40.0, 30.0)
    >>> suite.encode(r)[:3]
    (0, 2, 2)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pymunk

from .arena import Point
from .config import SensorConfig
from .world import WALL_ONLY, World

#: Codes of the sonar intervals (Table 6) and camera intervals (Table 7).
SONAR_LEVELS = ("Bump", "Close", "Medium", "Far")
CAMERA_LEVELS = ("Close", "Medium", "Far")
COMPASS_LEVELS = ("East", "North", "West", "South")
BUMP = 0


@dataclass
class Readings:
    """One noised reading of every sensor, plus what the viewer needs to draw them."""

    sonar: np.ndarray
    """Per sonar: distance from the robot's edge, inches (noised)."""
    goal: np.ndarray
    """Per camera: distance to the goal, or ``really_long_distance``."""
    eow: np.ndarray
    """Per camera: distance to the nearest visible end-of-world marker, or really long."""
    compass: float
    """Heading in compass units 0..255 (noised)."""
    rays: np.ndarray
    """Noise-free centre distance of every sonar sub-arc ray (n_sonar x sub_arcs)."""
    eow_target: list[int]
    """Per camera: index of the marker seen (-1: none)."""

    def goal_seen(self, really_long: float) -> list[bool]:
        return [bool(d < really_long) for d in self.goal]

    def eow_seen(self, really_long: float) -> list[bool]:
        return [bool(d < really_long) for d in self.eow]


class SensorSuite:
    """Reads and encodes the sensors of robot ``robot`` of ``world``."""

    def __init__(
        self,
        cfg: SensorConfig,
        world: World,
        goal: Point,
        markers: Sequence[Point],
        robot: int = 0,
    ) -> None:
        self.cfg = cfg
        self.world = world
        self.robot = robot
        self.radius = world.radius
        self.goal = (float(goal[0]), float(goal[1]))
        self.markers = [(float(m[0]), float(m[1])) for m in markers]
        so, ca = cfg.sonar, cfg.camera
        self.n_sonar = len(so.sonar_sensors_deg)
        self.n_camera = len(ca.camera_sensors_deg)
        self.ray_offsets = sonar_ray_offsets(so.sonar_sensors_deg, so.sonar_arc_deg, so.sub_arcs)
        self.ray_length = so.max_range + self.radius
        self.camera_dirs = np.radians(ca.camera_sensors_deg)
        self.camera_half_arc = math.radians(ca.camera_arc_deg) / 2.0
        self.far = cfg.really_long_distance
        self.sonar_thresholds = np.asarray(so.thresholds, dtype=float)
        self.camera_thresholds = np.asarray(ca.thresholds, dtype=float)
        self.groups = [list(g) for g in so.groups]
        scale = 0.0 if cfg.noise.model == "none" else cfg.noise.scale
        self.noise_fracs = np.concatenate(
            [
                np.full(self.n_sonar, so.noise * scale),
                np.full(self.n_camera, ca.noise * scale),
                np.full(self.n_camera, ca.noise * scale),
                [cfg.compass.noise * scale],
            ]
        )

    # -- public API -----------------------------------------------------------------
    @property
    def levels(self) -> list[tuple[str, int]]:
        """``(name, number of codes)`` of every state field, in keyword order."""
        return state_fields(self.cfg)

    def read(self, pose: tuple[float, float, float], rng: np.random.Generator) -> Readings:
        """Read every sensor at ``pose``; all noise is drawn from ``rng``."""
        x, y, h = pose
        rays = self.cast_sonar(x, y, h)
        sonar = rays.min(axis=1) - self.radius
        sonar = np.where(rays.min(axis=1) > self.ray_length - 1e-9, self.far, sonar)
        goal = np.empty(self.n_camera)
        eow = np.empty(self.n_camera)
        targets: list[int] = []
        for c in range(self.n_camera):
            goal[c] = self._camera_distance(x, y, h + self.camera_dirs[c], [self.goal])[0]
            d, k = self._camera_distance(x, y, h + self.camera_dirs[c], self.markers)
            eow[c] = d
            targets.append(k)
        compass = (h / (2.0 * math.pi)) * 256.0
        raw = np.concatenate([sonar, goal, eow, [compass]])
        noised = self.apply_noise(raw, rng)
        n, m = self.n_sonar, self.n_camera
        goal_n = self._camera_limit(noised[n : n + m], goal)
        eow_n = self._camera_limit(noised[n + m : n + 2 * m], eow)
        eow_targets = [k if eow_n[c] < self.far else -1 for c, k in enumerate(targets)]
        return Readings(
            sonar=noised[:n],
            goal=goal_n,
            eow=eow_n,
            compass=float(noised[-1] % 256.0),
            rays=rays,
            eow_target=eow_targets,
        )

    def encode(self, r: Readings) -> tuple[int, ...]:
        """The state: codes in keyword order (Tables 6, 7 and 12)."""
        goal = np.searchsorted(self.camera_thresholds, r.goal, side="right")
        eow = np.searchsorted(self.camera_thresholds, r.eow, side="right")
        grouped = [float(np.mean(r.sonar[g])) for g in self.groups]
        sonar = np.searchsorted(self.sonar_thresholds, grouped, side="right")
        codes = [int(v) for v in goal] + [int(v) for v in eow] + [int(v) for v in sonar]
        if self.cfg.compass.in_state:
            codes.append(compass_code(r.compass))
        return tuple(codes)

    def bump(self, r: Readings) -> bool:
        """True when any single sonar reads Bump (paper: the Bump reward and pink robot)."""
        return bool((r.sonar < self.sonar_thresholds[0]).any())

    def goal_close(self, r: Readings) -> bool:
        """True when the front camera (camera 0) reads the goal Close."""
        return bool(r.goal[0] < self.camera_thresholds[0])

    def set_goal(self, goal: Point) -> None:
        self.goal = (float(goal[0]), float(goal[1]))

    # -- geometry -------------------------------------------------------------------
    def cast_sonar(self, x: float, y: float, h: float) -> np.ndarray:
        """Centre distance of the first wall along every sub-arc ray (ray length if none)."""
        angles = h + self.ray_offsets
        ends_x = x + self.ray_length * np.cos(angles)
        ends_y = y + self.ray_length * np.sin(angles)
        query = self.world.space.segment_query_first
        out = np.full(angles.shape, self.ray_length)
        start = (x, y)
        length = self.ray_length
        for idx in np.ndindex(angles.shape):
            hit = query(start, (float(ends_x[idx]), float(ends_y[idx])), 0.0, WALL_ONLY)
            if hit is not None:
                out[idx] = hit.alpha * length
        return out

    def line_of_sight(self, x: float, y: float, target: Point) -> bool:
        """No wall segment between the centre ``(x, y)`` and ``target``."""
        dist = math.hypot(target[0] - x, target[1] - y)
        if dist < 1e-9:
            return True
        hit: pymunk.SegmentQueryInfo | None = self.world.space.segment_query_first(
            (x, y), target, 0.0, WALL_ONLY
        )
        return hit is None or hit.alpha * dist >= dist - 1e-7

    def _camera_distance(
        self, x: float, y: float, direction: float, targets: Sequence[Point]
    ) -> tuple[float, int]:
        """Noise-free edge distance to the nearest target in the arc and in sight."""
        best, best_k = self.far, -1
        for k, (tx, ty) in enumerate(targets):
            dx, dy = tx - x, ty - y
            rel = (math.atan2(dy, dx) - direction + math.pi) % (2.0 * math.pi) - math.pi
            if abs(rel) > self.camera_half_arc:
                continue
            d = max(0.0, math.hypot(dx, dy) - self.radius)
            if d < best and self.line_of_sight(x, y, (tx, ty)):
                best, best_k = d, k
        return best, best_k

    def _camera_limit(self, noised: np.ndarray, clean: np.ndarray) -> np.ndarray:
        """Paper order: noise first, then the ``MaxCameraView`` check."""
        unseen = (clean >= self.far) | (noised > self.cfg.camera.max_camera_view)
        return np.where(unseen, self.far, noised)

    def apply_noise(self, raw: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """``raw * (1 + e)`` per the noise model; one draw per reading, always drawn."""
        model = self.cfg.noise.model
        if model == "gaussian":
            e = rng.standard_normal(raw.shape) * (self.noise_fracs / 2.0)
        else:
            e = rng.uniform(-1.0, 1.0, raw.shape) * self.noise_fracs
        out = raw * (1.0 + e)
        return np.where(raw >= self.far, raw, out)


def sonar_ray_offsets(angles_deg: Sequence[float], arc_deg: float, sub_arcs: int) -> np.ndarray:
    """Angle (radians, relative to the heading) of the ray through each sub-arc's centre.

    >>> np.degrees(sonar_ray_offsets([0.0], 55.0, 11))[0, [0, 5, 10]].round(6).tolist()
    [-25.0, 0.0, 25.0]
    """
    centres = (np.arange(sub_arcs) + 0.5) / sub_arcs * arc_deg - arc_deg / 2.0
    return np.radians(np.asarray(angles_deg, dtype=float)[:, None] + centres[None, :])


def compass_code(units: float) -> int:
    """East 0, North 1, West 2, South 3; boundaries at NE/NW/SW/SE.

    >>> [compass_code(u) for u in (0, 31.9, 32.1, 100, 160, 224.1, 255)]
    [0, 0, 1, 2, 2, 0, 0]
    """
    deg = (units / 256.0 * 360.0) % 360.0
    return int(((deg + 45.0) % 360.0) // 90.0)


def state_fields(cfg: SensorConfig) -> list[tuple[str, int]]:
    """``(name, levels)`` of each state field in keyword order (Table 12)."""
    n_cam = len(cfg.camera.camera_sensors_deg)
    cam_levels = len(cfg.camera.thresholds) + 1
    son_levels = len(cfg.sonar.thresholds) + 1
    fields = [(f"GoalCam{c}", cam_levels) for c in range(n_cam)]
    fields += [(f"EoWCam{c}", cam_levels) for c in range(n_cam)]
    fields += [("Sonar" + "-".join(str(i) for i in g), son_levels) for g in cfg.sonar.groups]
    if cfg.compass.in_state:
        fields.append(("Compass", len(COMPASS_LEVELS)))
    return fields
