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
* **Compass**: heading / 2pi * 256 in 0..255, encoded East/North/West/South. Its noise
  is an angle: ``compass.noise`` is a fraction of a full turn (the paper's 25 %: up to
  +-64 units, +-90 degrees, whatever the heading), not a fraction of the value.
* **Realism** (:mod:`koolio_pymunk.sensing.realism`, off by default): the sonar and camera
  models act on the noise-free reading before the paper's noise; :class:`Readings`
  records each sub-arc ray's echo and each camera's missed detection or misread plate.

**Ray directions.** A sonar's rays sit at fixed offsets from the heading. Their unit
vectors are those of the offsets (:func:`unit_vectors`, once per sensor suite) turned by
the heading (:func:`turned`: two products and a sum per component, plain IEEE arithmetic
that numpy, Python and the compiled kernel do alike), so a reading takes one ``cos`` and
one ``sin`` of the heading, not one of each per ray. The compiled kernel repeats
:func:`turned` operation for operation (``ray_kernel._ray_directions``), so both engines
cast the same rays bit for bit on any machine (numpy's vectorised ``cos`` need not give
libm's last bit; the heading's ``cos`` and ``sin`` are taken with :mod:`math` on both
sides).

>>> units = unit_vectors(np.radians([0.0, 90.0]))
>>> c, s = turned(math.pi / 2, units)
>>> np.round(c, 12).tolist(), np.round(s, 12).tolist()
([0.0, -1.0], [1.0, 0.0])

**Other robots** (a shared world, ``World(..., shared=True)``): the suite of robot
``robot`` sees the other robots in the arena as the walls are seen: a sonar ray ends on
the nearest surface, wall or robot; a robot blocks a camera's sight line. Each reading
also says, per sonar, which robot its reading came from (:attr:`Readings.sonar_robot`,
-1: a wall or nothing; with the realism models, the echo they chose), and
:meth:`SensorSuite.robot_bump` whether a Bump came from a robot. The reference asks
pymunk (:class:`~.ray_engines.PymunkRays` over the shared space); the compiled path
(:func:`~.ray_kernel.sense_among`) reads the world's :attr:`World.xy
<koolio_pymunk.world.physics.World.xy>` and :attr:`~koolio_pymunk.world.physics.World.present`
at each reading. An isolated world's suite is what it was, bit for bit and in speed.

Sonar groups (paper: 1&2 and 5&6) are averaged before encoding. The state is the tuple
of codes in keyword order: goal cameras, end-of-world cameras, sonar groups (then the
compass if ``compass.in_state``).

Example (noise off, a robot of radius 10 at the centre of a 100 x 100 box)::

    >>> import numpy as np
    >>> from koolio_pymunk.store.config import SensorConfig
    >>> from koolio_pymunk.world.physics import World
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
from dataclasses import dataclass, field

import numpy as np

from ..store.config import SensorConfig, sensor_fields
from ..store.errors import ConfigError
from ..store.realism_config import RealismConfig
from ..world.arena import Point
from ..world.physics import World
from .realism import SensorRealism, apply_reference, robot_sources
from .sensor_arrays import BUFFERS, ENCODING, GEOMETRY, REALISM, bundle

# The compiled kernels (ray_kernel.py, encoding_kernel.py) import numba, which takes a large part of
# a second to load: they are imported when a SensorSuite is made, not with this module, so
# `import koolio_pymunk` and the commands that need no sensing (info, check-arena, export,
# plot) stay light.

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
    echo: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), np.bool_))
    """Per sonar sub-arc ray (n_sonar x sub_arcs): it got an echo (hit a wall in range and,
    with the incidence model, not at a grazing angle)."""
    crosstalk: np.ndarray = field(default_factory=lambda: np.zeros(0, np.bool_))
    """Per sonar: it read a neighbour's echo (realism crosstalk)."""
    missed: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.bool_))
    """Per camera ``[goal, end-of-world]``: a target in view was not detected."""
    misread: np.ndarray = field(default_factory=lambda: np.zeros(0, np.bool_))
    """Per camera: its goal reading is another door's plate."""
    sonar_robot: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    """Per sonar: the robot whose surface its reading came from, in a shared world (-1: a
    wall, or nothing; always -1 in an isolated world)."""


class SensorSuite:
    """Reads and encodes the sensors of robot ``robot`` of ``world``.

    The geometry comes from a ray engine (:mod:`koolio_pymunk.sensing.ray_kernel`) chosen by
    ``cfg.backend``: ``pymunk`` (segment queries, the reference) or ``fast`` (compiled
    kernel, same numbers). :meth:`read` and :meth:`encode` are the reference read-out;
    :meth:`sense` is the learner's hot path (one state key, Bump and goal-close per step)
    and, with the fast backend, runs the whole reading in two compiled calls with the
    same noise draws (:mod:`koolio_pymunk.sensing.encoding_kernel`).
    """

    def __init__(
        self,
        cfg: SensorConfig,
        world: World,
        goal: Point,
        markers: Sequence[Point],
        robot: int = 0,
        backend: str | None = None,
        realism: RealismConfig | None = None,
        plates: Sequence[Point] = (),
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
        self.ray_units = unit_vectors(self.ray_offsets)
        """The rays' offsets as unit vectors, turned by the heading at each reading
        (:func:`turned`)."""
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
        self.backend = backend or cfg.backend
        self.fused = self.backend in ("fast", "cone")
        """The compiled kernel reads the sensors (``fast``, ``cone``), not pymunk."""
        if self.backend == "cone" and so.sonar_arc_deg >= 180.0:
            raise ConfigError(
                f"sensors.backend: the cone sonar model needs sonar_arc_deg < 180, "
                f"got {so.sonar_arc_deg:g}"
            )
        from .encoding_kernel import wrap_compass
        from .ray_engines import make_engine

        self.engine = make_engine(self.backend, world, robot)
        self._wrap_compass = wrap_compass
        self.plates = [(float(p[0]), float(p[1])) for p in plates]
        """The other doors' plates (a misread camera may take one for the goal)."""
        self.realism = SensorRealism(
            realism or RealismConfig(),
            so.sonar_sensors_deg,
            self.n_camera,
            self.radius,
            self.ray_length,
            self.far,
            ca.max_camera_view,
            pings=so.pings,
        )
        """The sonar and camera realism models (:mod:`koolio_pymunk.sensing.realism`)."""
        self._check_realism()
        self.kernel = KernelInputs(self)
        """The compiled kernels' inputs (arrays and buffers; many robots share them)."""
        self._last: tuple[Readings, tuple[int, ...]] | None = None

    # -- public API -----------------------------------------------------------------
    @property
    def levels(self) -> list[tuple[str, int]]:
        """``(name, number of codes)`` of every sensor field, in keyword order (the
        memory's fields follow them in the state: :mod:`koolio_pymunk.sensing.memory`)."""
        return sensor_fields(self.cfg)

    def read(self, pose: tuple[float, float, float], rng: np.random.Generator) -> Readings:
        """Read every sensor at ``pose``; all noise is drawn from ``rng``."""
        x, y, h = pose
        g = self.geometry(x, y, h)
        return self.finish(g.raw, g.rays, g.targets, rng, g.ray_cos, g.decoy, g.ray_robot,
                           g.sonar_robot)  # fmt: skip

    def finish(
        self,
        raw: np.ndarray,
        rays: np.ndarray,
        targets: list[int],
        rng: np.random.Generator,
        ray_cos: np.ndarray | None = None,
        decoy: np.ndarray | None = None,
        ray_robot: np.ndarray | None = None,
        sonar_robot: np.ndarray | None = None,
    ) -> Readings:
        """The realism models, noise and camera limit applied to a :meth:`raw` reading.

        Draw order: the paper's noise (one call), then, with a realism model on, the
        realism uniforms (one call); ``ray_cos`` and ``decoy`` are :meth:`geometry`'s
        (needed with the incidence and misread models), ``ray_robot`` and
        ``sonar_robot`` too (a shared world's robots hit; none: -1)."""
        e = self.draw_noise(rng, raw.shape[0]) * self._noise_scale
        real = None
        if ray_robot is None:
            ray_robot = np.full(rays.shape, -1, np.int64)
        if sonar_robot is None:
            sonar_robot = np.full(self.n_sonar, -1, np.int64)
        if self.realism.on:
            u = rng.random(self.realism.n_draws)
            ray_cos = np.zeros(rays.shape) if ray_cos is None else ray_cos
            decoy = np.full(self.n_camera, self.far) if decoy is None else decoy
            real = apply_reference(self.realism, raw, rays, ray_cos, decoy, u)
            raw = real.raw
            sonar_robot = robot_sources(self.realism, rays, real.echo, real.crosstalk,
                                        ray_robot, u, sonar_robot)  # fmt: skip
        noised = self._noised(raw, e)
        n, m = self.n_sonar, self.n_camera
        goal_n = self._camera_limit(noised[n : n + m], raw[n : n + m])
        eow_n = self._camera_limit(noised[n + m : n + 2 * m], raw[n + m : n + 2 * m])
        eow_targets = [k if eow_n[c] < self.far else -1 for c, k in enumerate(targets)]
        return Readings(
            sonar=noised[:n],
            goal=goal_n,
            eow=eow_n,
            compass=self._wrap_compass(noised[-1]),
            rays=rays,
            eow_target=eow_targets,
            echo=self.echoes(rays) if real is None else real.echo,
            crosstalk=np.zeros(n, np.bool_) if real is None else real.crosstalk,
            missed=np.zeros((m, 2), np.bool_) if real is None else real.missed,
            misread=np.zeros(m, np.bool_) if real is None else real.misread,
            sonar_robot=sonar_robot,
        )

    def echoes(self, rays: np.ndarray) -> np.ndarray:
        """Per sub-arc ray: it hit a wall within range (the ideal world's echo)."""
        return rays <= self.ray_length - 1e-9

    def raw(self, x: float, y: float, h: float) -> tuple[np.ndarray, np.ndarray, list[int]]:
        """Noise-free readings ``[sonar..., goal cam..., end-of-world cam..., compass]``,
        every sub-arc ray's centre distance, and the marker each camera sees (-1: none)."""
        g = self.geometry(x, y, h)
        return g.raw, g.rays, g.targets

    def geometry(self, x: float, y: float, h: float) -> Geometry:
        """:meth:`raw` and what the realism models need (incidence, other plates)."""
        if self.fused:
            k = self.kernel
            g = Geometry(
                np.empty(k.n_raw),
                np.empty(self.ray_offsets.shape),
                [],
                np.zeros(self.ray_offsets.shape),
                np.full(self.n_camera, self.far),
                np.full(self.ray_offsets.shape, -1, np.int64),
                np.full(self.n_sonar, -1, np.int64),
            )
            eow_k = np.empty(self.n_camera, np.int64)
            k.sense(x, y, h, g.raw, g.rays, eow_k, g.ray_cos, g.decoy, g.ray_robot,
                    g.sonar_robot)  # fmt: skip
            g.targets = eow_k.tolist()
            return g
        ray_cos = np.zeros(self.ray_offsets.shape)
        ray_robot = np.full(self.ray_offsets.shape, -1, np.int64)
        if self.world.shared:
            rays, cos, ray_robot = self.engine.cast_hits(x, y, self.ray_dirs(h), self.ray_length)
            if self.realism.incidence:
                ray_cos = cos
        elif self.realism.incidence:
            rays, ray_cos = self.engine.cast_incidence(x, y, self.ray_dirs(h), self.ray_length)
        else:
            rays = self.cast_sonar(x, y, h)
        hitless = rays.min(axis=1) > self.ray_length - 1e-9
        sonar = rays.min(axis=1) - self.radius
        sonar = np.where(hitless, self.far, sonar)
        nearest = ray_robot[np.arange(self.n_sonar), rays.argmin(axis=1)]  # the first nearest
        sonar_robot = np.where(hitless, -1, nearest)
        goal = np.empty(self.n_camera)
        eow = np.empty(self.n_camera)
        decoy = np.full(self.n_camera, self.far)
        targets: list[int] = []
        for c in range(self.n_camera):
            direction = h + self.camera_dirs[c]
            goal[c] = self._camera_distance(x, y, direction, [self.goal])[0]
            d, k = self._camera_distance(x, y, direction, self.markers)
            eow[c] = d
            targets.append(k)
            if self.realism.misread:
                decoy[c] = self._camera_distance(x, y, direction, self.plates)[0]
        compass = (h / (2.0 * math.pi)) * 256.0
        raw = np.concatenate([sonar, goal, eow, [compass]])
        return Geometry(raw, rays, targets, ray_cos, decoy, ray_robot, sonar_robot)

    def sense(
        self, pose: tuple[float, float, float], rng: np.random.Generator
    ) -> tuple[int, bool, bool]:
        """One step's reading: ``(state_key, bump, goal_close)``; same draws as :meth:`read`.

        :meth:`last` gives the :class:`Readings` and codes of this reading (built on demand).
        """
        if not self.fused:
            r = self.read(pose, rng)
            codes = self.encode(r)
            self._last = (r, codes)
            return self.kernel.key(codes), self.bump(r), self.goal_close(r)
        self._last = None
        return self.kernel.sense_readout(pose, rng)

    def sightings(self) -> tuple[np.ndarray, np.ndarray]:
        """The cameras' goal and end-of-world distances of the last :meth:`sense`
        (``really_long_distance``: nothing seen), without building :class:`Readings`."""
        if self._last is None and self.fused:
            out, n, m = self.kernel.out, self.n_sonar, self.n_camera
            return out[n : n + m], out[n + m : n + 2 * m]
        r = self.last()[0]
        return r.goal, r.eow

    def last(self) -> tuple[Readings, tuple[int, ...]]:
        """The :class:`Readings` and state codes of the last :meth:`sense`."""
        if self._last is None:
            self._last = self.kernel.last_readings()
        return self._last

    def forget_last(self) -> None:
        """The compiled kernel's buffers hold a newer reading than :meth:`last` built
        (read elsewhere with this suite's kernel inputs): build it again when asked."""
        self._last = None

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

    def goal_misread(self) -> bool:
        """The front camera's goal reading of the last :meth:`sense` is another door's
        plate (the realism misread model)."""
        if not self.realism.misread:
            return False
        if self.fused:
            return bool(self.kernel.misread[0])
        return bool(self.last()[0].misread[0])

    def bump(self, r: Readings) -> bool:
        """True when any single sonar reads Bump (paper: the Bump reward and pink robot)."""
        return bool((r.sonar < self.sonar_thresholds[0]).any())

    def robot_bump(self, r: Readings) -> bool:
        """True when a sonar that reads Bump read another robot (a shared world; the
        compiled twin is :func:`~.reading_kernel.robot_bump`)."""
        return bool(((r.sonar < self.sonar_thresholds[0]) & (r.sonar_robot >= 0)).any())

    def goal_close(self, r: Readings) -> bool:
        """True when the front camera (camera 0) reads the goal Close."""
        return bool(r.goal[0] < self.camera_thresholds[0])

    def set_goal(self, goal: Point, plates: Sequence[Point] | None = None) -> None:
        """Make ``goal`` the plate the cameras look for; ``plates``: the other plates."""
        self.goal = (float(goal[0]), float(goal[1]))
        self.kernel.goal[:] = self.goal
        if plates is not None:
            self.plates = [(float(p[0]), float(p[1])) for p in plates]
            self.kernel.configure_realism()

    def set_realism(self, cfg: RealismConfig) -> None:
        """Take the sonar and camera models of ``cfg`` (domain randomization)."""
        self.realism.configure(cfg)
        self._check_realism()
        self.kernel.configure_realism()

    def _check_realism(self) -> None:
        if self.backend == "cone" and self.realism.incidence:
            raise ConfigError(
                "realism.sonar.max_incidence_deg: the cone sonar model (sensors.backend: "
                "cone) has no rays to test for incidence; use backend fast or pymunk"
            )

    # -- geometry -------------------------------------------------------------------
    def ray_dirs(self, h: float) -> np.ndarray:
        """Every sub-arc ray's unit vector at heading ``h`` (``[cos, sin]``, each shaped as
        :attr:`ray_offsets`)."""
        return turned(h, self.ray_units)

    def cast_sonar(self, x: float, y: float, h: float) -> np.ndarray:
        """Centre distance of the first wall along every sub-arc ray (ray length if none)."""
        return self.engine.cast(x, y, self.ray_dirs(h), self.ray_length)

    def line_of_sight(self, x: float, y: float, target: Point) -> bool:
        """No wall segment between the centre ``(x, y)`` and ``target``."""
        return self.engine.line_of_sight(x, y, target[0], target[1])

    def camera_target(
        self, pose: tuple[float, float, float], camera: int, targets: Sequence[Point]
    ) -> int:
        """Index in ``targets`` of the nearest one camera ``camera`` has in its arc and in
        sight at ``pose`` (noise-free, no realism), or -1: what the viewer draws a missed
        or misread camera's line to."""
        x, y, h = pose
        return self._camera_distance(x, y, h + float(self.camera_dirs[camera]), targets)[1]

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

    def draw_noise(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """The ``n`` raw noise draws of one reading (uniform (-1, 1) or standard normal)."""
        if self.cfg.noise.model == "gaussian":
            return rng.standard_normal(n)
        return rng.uniform(-1.0, 1.0, n)

    @property
    def _noise_scale(self) -> np.ndarray:
        """Per reading, what a raw draw is multiplied by (halved for the gaussian model)."""
        if self.cfg.noise.model == "gaussian":
            return self.noise_fracs / 2.0
        return self.noise_fracs

    def _noised(self, raw: np.ndarray, e: np.ndarray) -> np.ndarray:
        """``raw * (1 + e)`` for distances (really long ones stay), ``raw + e * 256`` for
        the compass (an angle: a fraction of a full turn), not yet wrapped to 0..256."""
        out = np.where(raw >= self.far, raw, raw * (1.0 + e))
        out[-1] = raw[-1] + e[-1] * 256.0
        return out


@dataclass
class Geometry:
    """A noise-free reading (:meth:`SensorSuite.geometry`)."""

    raw: np.ndarray
    """``[sonar..., goal cam..., end-of-world cam..., compass]``: edge distances, units."""
    rays: np.ndarray
    """Centre distance of every sonar sub-arc ray (the ray length when nothing is hit)."""
    targets: list[int]
    """Per camera: the end-of-world marker seen (-1: none)."""
    ray_cos: np.ndarray
    """Per ray: cosine of its incidence on the wall it hits (0 where not computed)."""
    decoy: np.ndarray
    """Per camera: the nearest other door's plate in view (far: none, or not computed)."""
    ray_robot: np.ndarray | None = None
    """Per ray: the robot it hit in a shared world (-1: a wall, or nothing)."""
    sonar_robot: np.ndarray | None = None
    """Per sonar: the robot its noise-free reading came from (-1: a wall, or nothing)."""


class KernelInputs:
    """Arrays and buffers of one :class:`SensorSuite` for the compiled kernels.

    ``sense(x, y, h, raw, rays, eow_k, ray_cos, decoy)`` is :func:`ray_kernel.sense_one`
    (:func:`ray_kernel.sense_among` in a shared world, with :attr:`others`);
    ``sense_readout(pose, rng)`` adds the noise draws and :func:`encoding_kernel.readout`,
    or, when a realism model is on, is :func:`realism_kernel.sense_realism` (the
    reading, the models and the read-out in one call).
    """

    def __init__(self, s: SensorSuite) -> None:
        self.suite = s
        self.n_raw = s.n_sonar + 2 * s.n_camera + 1
        self.ray_offsets = np.ascontiguousarray(s.ray_offsets, dtype=np.float64)
        self.ray_units = np.ascontiguousarray(s.ray_units, dtype=np.float64)
        cone = 1.0 if s.backend == "cone" else 0.0
        half_sonar = math.radians(s.cfg.sonar.sonar_arc_deg) / 2.0
        self.params = np.array(
            [s.ray_length, s.radius, s.far, s.camera_half_arc, cone, half_sonar, 0.0]
        )
        self.camera_dirs = np.ascontiguousarray(s.camera_dirs, dtype=np.float64)
        self.goal = np.array(s.goal, dtype=np.float64)
        self.markers = np.array(s.markers, dtype=np.float64).reshape(-1, 2)
        self.walls = getattr(s.engine, "walls", None)
        self.gaussian = s.cfg.noise.model == "gaussian"
        self.fracs = s.noise_fracs / 2.0 if self.gaussian else s.noise_fracs.copy()
        self.limits = np.array([s.far, s.cfg.camera.max_camera_view])
        self.group_members = np.array([i for g in s.groups for i in g], dtype=np.int64)
        self.group_sizes = np.array([len(g) for g in s.groups], dtype=np.int64)
        self.bits = np.array(
            [max(1, math.ceil(math.log2(lv))) for _, lv in s.levels], dtype=np.int64
        )
        self.compass_in_state = bool(s.cfg.compass.in_state)
        self.raw = np.empty(self.n_raw)
        self.rays = np.empty(self.ray_offsets.shape)
        self.eow_k = np.empty(s.n_camera, np.int64)
        self.out = np.empty(self.n_raw)
        self.codes = np.empty(len(self.bits), np.int64)
        from .encoding_kernel import readout
        from .ray_kernel import new_trig, new_wall_lists, sense_one
        from .realism_kernel import sense_realism

        self._sense_one = sense_one
        self._readout = readout
        self._sense_realism_kernel = sense_realism
        self.shared = bool(s.world.shared)
        """The suite's robot shares its arena with others (:attr:`others`)."""
        self.ray_robot = np.full(self.ray_offsets.shape, -1, np.int64)
        self.sonar_robot = np.full(s.n_sonar, -1, np.int64)
        self.others = None
        """In a shared world, :func:`ray_kernel.sense_among`'s ``others`` group: the
        world's robots' centres and flags (live), the suite's robot, the buffers
        :attr:`ray_robot` and :attr:`sonar_robot`; None in an isolated world."""
        if self.shared:
            from .ray_kernel import sense_among
            from .realism_kernel import sense_realism_among

            w = s.world
            self.others = (w.xy, w.present, s.robot, self.ray_robot, self.sonar_robot)
            self._sense_among = sense_among
            self._sense_realism_kernel = sense_realism_among
        self.trig = new_trig(self.ray_offsets.size)
        self.wall_lists = new_wall_lists(
            self.walls if self.walls is not None else np.empty((0, 10))
        )
        self.pose = (0.0, 0.0, 0.0)
        self.sonar_thresholds = s.sonar_thresholds
        self.camera_thresholds = s.camera_thresholds
        self.n_sonar = s.n_sonar
        self.geometry = bundle(GEOMETRY, self)
        """The rays' and cameras' group (:data:`~.sensor_arrays.GEOMETRY`)."""
        self.encoding = bundle(ENCODING, self)
        """The read-out's group (:data:`~.sensor_arrays.ENCODING`)."""
        # Realism: inputs and what the models report of the last reading.
        self.ray_cos = np.zeros(self.ray_offsets.shape)
        self.decoy = np.full(s.n_camera, s.far)
        self.echo = np.zeros(self.ray_offsets.shape, np.bool_)
        self.crossed = np.zeros(s.n_sonar, np.bool_)
        self.missed = np.zeros((s.n_camera, 2), np.bool_)
        self.misread = np.zeros(s.n_camera, np.bool_)
        self.buffers = bundle(BUFFERS, self)
        """This suite's reading buffers (:data:`~.sensor_arrays.BUFFERS`)."""
        self.configure_realism()

    def configure_realism(self) -> None:
        """Follow the suite's realism models: ray incidence on or off, the plates the
        cameras may misread (none when the misread model is off: nothing to compute)."""
        from .realism_kernel import new_work

        s, real = self.suite, self.suite.realism
        self.real_on = real.on
        self.params[6] = 1.0 if real.incidence else 0.0
        plates = s.plates if real.misread else []
        self.plates = np.array(plates, dtype=np.float64).reshape(-1, 2)
        self.decoy[:] = s.far
        self.noise = np.zeros(self.n_raw)
        self.realism = bundle(REALISM, self, params=real.params, flags=real.flags,
                              neighbours=real.neighbours,
                              work=new_work(s.n_sonar, real.params))  # fmt: skip
        """The realism models' group (:data:`~.sensor_arrays.REALISM`)."""

    def key(self, codes: Sequence[int]) -> int:
        """The state key of ``codes`` (same as ``KeywordLayout.state_key``)."""
        key = 0
        for code, b in zip(codes, self.bits.tolist()):
            key = (key << b) | code
        return key

    def sense(
        self,
        x: float,
        y: float,
        h: float,
        raw: np.ndarray,
        rays: np.ndarray,
        eow_k: np.ndarray,
        ray_cos: np.ndarray | None = None,
        decoy: np.ndarray | None = None,
        ray_robot: np.ndarray | None = None,
        sonar_robot: np.ndarray | None = None,
    ) -> None:
        if ray_cos is None and decoy is None and raw is self.raw:
            buffers = self.buffers
        else:
            ray_cos = self.ray_cos if ray_cos is None else ray_cos
            decoy = self.decoy if decoy is None else decoy
            buffers = (raw, rays, eow_k, self.trig, ray_cos, decoy, self.wall_lists)
        if self.shared:
            others = self.others
            if ray_robot is not None or sonar_robot is not None:
                ray_robot = self.ray_robot if ray_robot is None else ray_robot
                sonar_robot = self.sonar_robot if sonar_robot is None else sonar_robot
                others = (*others[:3], ray_robot, sonar_robot)
            self._sense_among(float(x), float(y), float(h), self.geometry, self.goal,
                              self.plates, buffers, others)  # fmt: skip
            return
        self._sense_one(float(x), float(y), float(h), self.geometry, self.goal, self.plates,
                        buffers)  # fmt: skip

    def sense_readout(
        self, pose: tuple[float, float, float], rng: np.random.Generator
    ) -> tuple[int, bool, bool]:
        x, y, h = pose
        self.pose = pose
        if self.real_on:
            return self._sense_realism(x, y, h, rng)
        self.sense(x, y, h, self.raw, self.rays, self.eow_k)
        if self.gaussian:
            draws = rng.standard_normal(self.n_raw)
        else:
            draws = rng.uniform(-1.0, 1.0, self.n_raw)  # as draw_noise, one call less
        return self._readout(self.raw, draws, self.encoding, self.out, self.eow_k, self.codes)

    def _sense_realism(
        self, x: float, y: float, h: float, rng: np.random.Generator
    ) -> tuple[int, bool, bool]:
        """:meth:`sense_readout` with realism models on: one compiled call
        (:func:`realism_kernel.sense_realism`); the same draws as the reference (with
        uniform noise, its two calls as one: the generator's stream is the same)."""
        n_draws = self.suite.realism.n_draws
        if self.gaussian:
            self.noise = rng.standard_normal(self.n_raw)
            u = rng.random(n_draws)
        else:
            u = rng.random(self.n_raw + n_draws)
        if self.shared:
            return self._sense_realism_kernel(
                float(x), float(y), float(h), self.geometry, self.goal, self.plates,
                self.buffers, self.noise, u, not self.gaussian, self.realism, self.encoding,
                self.out, self.codes, self.others,
            )  # fmt: skip
        return self._sense_realism_kernel(
            float(x), float(y), float(h), self.geometry, self.goal, self.plates, self.buffers,
            self.noise, u, not self.gaussian, self.realism, self.encoding, self.out, self.codes,
        )  # fmt: skip

    def last_readings(self) -> tuple[Readings, tuple[int, ...]]:
        """:class:`Readings` and codes of the last :meth:`sense_readout` (copies)."""
        n, m = self.suite.n_sonar, self.suite.n_camera
        out = self.out.copy()
        real = self.real_on
        r = Readings(
            sonar=out[:n],
            goal=out[n : n + m],
            eow=out[n + m : n + 2 * m],
            compass=float(out[-1]),
            rays=self.rays.copy(),
            eow_target=self.eow_k.tolist(),
            echo=self.echo.copy() if real else self.suite.echoes(self.rays),
            crosstalk=self.crossed.copy() if real else np.zeros(n, np.bool_),
            missed=self.missed.copy() if real else np.zeros((m, 2), np.bool_),
            misread=self.misread.copy() if real else np.zeros(m, np.bool_),
            sonar_robot=self.sonar_robot.copy(),
        )
        return r, tuple(int(c) for c in self.codes)


def compass_code(compass: float) -> int:
    """The compass field's code (East, North, West, South) of a reading in 0..256 units:
    the compiled kernel's own function (:func:`koolio_pymunk.sensing.encoding_kernel.compass_code`).

    >>> [compass_code(c) for c in (0.0, 64.0, 128.0, 192.0)]
    [0, 1, 2, 3]
    """
    from .encoding_kernel import compass_code as kernel

    return int(kernel(compass))


def unit_vectors(angles: np.ndarray) -> np.ndarray:
    """``[cos(angles), sin(angles)]`` stacked (shape ``(2, *angles.shape)``): rays along
    absolute ``angles`` for an engine's ``cast`` (:mod:`~.ray_engines`), or a sonar
    ring's offsets for :func:`turned`."""
    a = np.asarray(angles, dtype=np.float64)
    return np.stack([np.cos(a), np.sin(a)])


def turned(heading: float, units: np.ndarray) -> np.ndarray:
    """The unit vectors ``units`` (:func:`unit_vectors`) turned by ``heading`` radians:
    ``(c cos h - s sin h, c sin h + s cos h)``, the reference of the compiled kernel's ray
    directions."""
    ch, sh = math.cos(heading), math.sin(heading)
    return np.stack([ch * units[0] - sh * units[1], sh * units[0] + ch * units[1]])


def sonar_ray_offsets(angles_deg: Sequence[float], arc_deg: float, sub_arcs: int) -> np.ndarray:
    """Angle (radians, relative to the heading) of the ray through each sub-arc's centre.

    >>> np.degrees(sonar_ray_offsets([0.0], 55.0, 11))[0, [0, 5, 10]].round(6).tolist()
    [-25.0, 0.0, 25.0]
    """
    centres = (np.arange(sub_arcs) + 0.5) / sub_arcs * arc_deg - arc_deg / 2.0
    return np.radians(np.asarray(angles_deg, dtype=float)[:, None] + centres[None, :])
