"""Agreement of the fast sensing backend with the pymunk reference on random poses.

:func:`compare_backends` places a robot at ``n`` random free poses of an arena (centre
inside the walls, outside every obstacle, at least ``radius - slop`` from every wall;
uniform heading) and reads the sensors with both backends:

* noise-free readings (``SensorSuite.raw``: sonar, cameras, compass), every sub-arc ray
  and the marker each camera sees: counted as a mismatch when any distance differs in any
  bit (the kernels repeat Chipmunk's operations, so the readings are the same bits) or
  any marker differs; the largest difference is kept too;
* the encoded state: the reference ``read`` + ``encode`` of the pymunk backend against the
  fast backend's fused ``sense`` (compiled read-out), both with the same noise draws
  (noise off unless ``noise`` is given, e.g. ``"uniform"``);
* with ``world`` (e.g. ``"koolio-real"``) the realism models of that world are on: the
  incidence cosines and other plates in view are compared too, and the readings after
  the models (the reference :func:`realism.apply_reference` against the compiled
  :func:`realism_kernel.apply_realism`, same draws) must agree bit for bit, with the same
  echoes, missed detections and misread plates.

With ``others`` > 0 the world is shared (``World(..., shared=True)``): at every pose
``others`` more robots stand in the arena (half of them drawn within 80 in of the reader,
overlapping nobody; one in ten parked: :class:`Crowd`), and the robot each ray and each
sonar met (``Geometry.ray_robot``, ``Readings.sonar_robot``) is compared too.

``tests/sensing/test_ray_kernel.py`` runs it on a small sample per shipped arena;
``tools/agreement.py`` on 100k poses per arena. :func:`cone_disagreement` measures how
often the exact-cone sonar model (``sensors.backend: cone``) encodes differently from the
paper's sub-arcs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from koolio_pymunk.sensing.suite import Readings, SensorSuite
from koolio_pymunk.store.config import Config, apply_world
from koolio_pymunk.store.keyword import KeywordLayout
from koolio_pymunk.world.arena import load_arena
from koolio_pymunk.world.geometry import distance_point_segment, point_in_polygon
from koolio_pymunk.world.physics import COLLISION_SLOP, World


@dataclass
class Agreement:
    arena: str
    poses: int
    distance_mismatches: int
    """Poses where a distance differs in any bit or a camera's marker differs."""
    state_mismatches: int
    """Poses whose encoded state, Bump or goal-close, or readings after the realism models
    and noise (with their echoes and camera flags) differ."""
    bit_identical: int
    """Poses whose every distance is bit-identical."""
    max_abs_diff: float
    robot_readings: int = 0
    """Poses where a sonar read another robot (a shared world)."""

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def free_poses(arena_name: str, radius: float, n: int, seed: int) -> np.ndarray:
    """``(n, 3)`` random poses ``x, y, heading`` where a robot of ``radius`` fits."""
    arena = load_arena(arena_name, radius).to_world()
    segs = arena.segments()
    walls = [p for p in arena.walls]
    xmin, ymin, xmax, ymax = arena.bounds()
    rng = np.random.default_rng(seed)
    out: list[tuple[float, float, float]] = []
    while len(out) < n:
        x, y = float(rng.uniform(xmin, xmax)), float(rng.uniform(ymin, ymax))
        if not point_in_polygon((x, y), walls):
            continue
        if any(point_in_polygon((x, y), ob) for ob in arena.obstacles):
            continue
        if min(distance_point_segment((x, y), a, b) for a, b in segs) < radius - COLLISION_SLOP:
            continue
        out.append((x, y, float(rng.uniform(0.0, 2.0 * math.pi))))
    return np.array(out)


class Crowd:
    """The other robots of a shared ``world`` placed round each pose of robot 0 (the
    module doc), at points of ``pool`` (free poses of the arena)."""

    def __init__(self, world: World, pool: np.ndarray, rng: np.random.Generator) -> None:
        self.world = world
        self.pool = pool[:, :2]
        self.rng = rng

    def place(self, x: float, y: float) -> None:
        """Robot 0 at ``(x, y)``, the others round it, overlapping nobody."""
        w, rng = self.world, self.rng
        w.place(0, (x, y), 0.0)
        for j in range(1, w.n_robots):
            w.park(j)
        near = np.flatnonzero(np.hypot(self.pool[:, 0] - x, self.pool[:, 1] - y) < 80.0)
        for j in range(1, w.n_robots):
            choices = near if rng.random() < 0.5 and len(near) else np.arange(len(self.pool))
            for _ in range(20):
                at = self.pool[int(choices[int(rng.integers(len(choices)))])]
                if w.robot_clearance(j, at) > 0.0:
                    w.place(j, at, 0.0)
                    break
            if w.present[j] and rng.random() < 0.1:
                w.park(j)


def compare_backends(
    arena_name: str,
    n: int,
    seed: int = 0,
    noise: str = "none",
    world: str | None = None,
    pings: int = 1,
    others: int = 0,
) -> Agreement:
    """Read both backends at ``n`` random free poses of ``arena_name`` (see module doc),
    each sonar pinged ``pings`` times (``sensors.sonar.pings``), with ``others`` more
    robots in the arena (a shared world)."""
    cfg = Config()
    if world is not None:
        cfg = apply_world(cfg, world)
    cfg.sensors.noise.model = noise
    cfg.sensors.sonar.pings = pings
    radius = cfg.robot.radius
    arena = load_arena(arena_name, radius).to_world()
    space = World(arena.segments(), radius, 1 + others, shared=others > 0)
    crowd = None
    if others:
        pool = free_poses(arena_name, radius, 40 * others + n, seed + 1)
        crowd = Crowd(space, pool, np.random.default_rng([seed, 1]))
    markers = [m.at for m in arena.end_of_world]
    plates = [g.at for g in arena.goals if g.name != arena.active_goal]
    ref, fast = (
        SensorSuite(cfg.sensors, space, arena.goal().at, markers, backend=b,
                    realism=cfg.realism, plates=plates)
        for b in ("pymunk", "fast")
    )  # fmt: skip
    layout_key = KeywordLayout(tuple(ref.levels)).state_key
    dist_bad = state_bad = identical = robot_readings = 0
    worst = 0.0
    for i, (x, y, h) in enumerate(free_poses(arena_name, radius, n, seed)):
        if crowd is not None:
            crowd.place(x, y)
        g_r, g_f = ref.geometry(x, y, h), fast.geometry(x, y, h)
        pairs = [(g_r.raw, g_f.raw), (g_r.rays, g_f.rays)]
        pairs += [(g_r.ray_cos, g_f.ray_cos), (g_r.decoy, g_f.decoy)]
        diff = max(float(np.max(np.abs(a - b))) for a, b in pairs)
        worst = max(worst, diff)
        hits = (g_r.ray_robot, g_f.ray_robot), (g_r.sonar_robot, g_f.sonar_robot)
        same = all(np.array_equal(a, b) for a, b in pairs + list(hits))
        dist_bad += not same or g_r.targets != g_f.targets
        identical += same
        robot_readings += bool((g_r.sonar_robot >= 0).any())
        rng = np.random.default_rng([seed, i])
        r = ref.finish(g_r.raw, g_r.rays, g_r.targets, rng, g_r.ray_cos, g_r.decoy,
                       g_r.ray_robot, g_r.sonar_robot)  # fmt: skip
        codes = ref.encode(r)
        want = (layout_key(codes), ref.bump(r), ref.goal_close(r))
        got = fast.sense((x, y, h), np.random.default_rng([seed, i]))
        state_bad += want != got or codes != fast.last()[1] or not same_readings(r, fast.last()[0])
    return Agreement(arena_name, n, dist_bad, state_bad, identical, worst, robot_readings)


def same_readings(a: Readings, b: Readings) -> bool:
    """Every reading and every realism record of ``a`` and ``b`` bit-identical."""
    arrays = ("sonar", "goal", "eow", "rays", "echo", "crosstalk", "missed", "misread",
              "sonar_robot")  # fmt: skip
    return (
        all(np.array_equal(getattr(a, k), getattr(b, k)) for k in arrays)
        and a.compass == b.compass
        and a.eow_target == b.eow_target
    )


@dataclass
class ConeDisagreement:
    arena: str
    poses: int
    state_differs: float
    """Share of poses whose encoded state differs between the cone and sub-arc models."""
    group_differs: list[float]
    """Per sonar group (keyword order): share of poses whose code differs."""
    cone_not_nearer: int
    """Poses where a cone reading exceeds the sub-arc reading (must be 0: the cone sees
    every direction a sub-arc ray sees)."""

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def cone_disagreement(arena_name: str, n: int, seed: int = 0, others: int = 0) -> ConeDisagreement:
    """How often the exact-cone sonar model encodes differently from the paper's sub-arcs
    (noise off, the fast kernel for both, ``n`` random free poses; with ``others`` more
    robots in the arena, placed as :func:`compare_backends` places them)."""
    cfg = Config()
    cfg.sensors.noise.model = "none"
    radius = cfg.robot.radius
    arena = load_arena(arena_name, radius).to_world()
    world = World(arena.segments(), radius, 1 + others, shared=others > 0)
    crowd = None
    if others:
        pool = free_poses(arena_name, radius, 40 * others + n, seed + 1)
        crowd = Crowd(world, pool, np.random.default_rng([seed, 1]))
    markers = [m.at for m in arena.end_of_world]
    sub = SensorSuite(cfg.sensors, world, arena.goal().at, markers, backend="fast")
    cone = SensorSuite(cfg.sensors, world, arena.goal().at, markers, backend="cone")
    n_groups = len(cfg.sensors.sonar.groups)
    states = 0
    groups = np.zeros(n_groups)
    not_nearer = 0
    for x, y, h in free_poses(arena_name, radius, n, seed):
        if crowd is not None:
            crowd.place(x, y)
        raw_s = sub.raw(x, y, h)[0][: sub.n_sonar]
        raw_c = cone.raw(x, y, h)[0][: cone.n_sonar]
        not_nearer += bool((raw_c > raw_s + 1e-9).any())
        sub.sense((x, y, h), np.random.default_rng(0))
        cone.sense((x, y, h), np.random.default_rng(0))
        a, b = sub.last()[1], cone.last()[1]
        states += a != b
        groups += np.array(a[-n_groups:]) != np.array(b[-n_groups:])
    return ConeDisagreement(
        arena_name, n, states / n, [round(float(g), 4) for g in groups / n], not_nearer
    )
