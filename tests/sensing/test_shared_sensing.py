"""What a robot senses of the others in a shared arena: hand-built scenes with exact
numbers (a sonar ray ends on another robot, a camera cannot see a plate behind one, a
parked robot is invisible, the incidence on a robot's circle), the compiled readings
(``ray_kernel.sense_among``, ``realism_kernel.sense_realism_among``,
``reading_kernel.sense_reading_among``) against the pymunk reference bit for bit, and an
isolated robot's readings unchanged."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
from sensing_agreement import compare_backends, cone_disagreement, free_poses

from koolio_pymunk.sensing.reading_kernel import (
    ReadingArrays,
    robot_bump,
    robot_group,
    robot_others,
    sense_reading_among,
)
from koolio_pymunk.sensing.realism import SensorRealism, robot_sources
from koolio_pymunk.sensing.realism_kernel import sonar_sources
from koolio_pymunk.sensing.suite import SensorSuite
from koolio_pymunk.store.config import Config, SensorConfig, apply_world
from koolio_pymunk.store.realism_config import RealismConfig
from koolio_pymunk.world.arena import load_arena
from koolio_pymunk.world.physics import World

R = 10.0
FAR = SensorConfig().really_long_distance
BACKENDS = ("pymunk", "fast")
SHIPPED = ("hallway", "room", "obstacles")
BOX = [((0, 0), (300, 0)), ((300, 0), (300, 100)), ((300, 100), (0, 100)), ((0, 100), (0, 0))]


def quiet() -> SensorConfig:
    cfg = SensorConfig()
    cfg.noise.model = "none"
    return cfg


def scene(*places: tuple, n: int | None = None) -> World:
    """A shared 300 x 100 box, robot ``i`` at ``places[i]`` (the rest parked)."""
    w = World(BOX, R, n or len(places), shared=True)
    for i, p in enumerate(places):
        w.place(i, p, 0.0)
    return w


def suite(world: World, backend: str, robot: int = 0, **kw) -> SensorSuite:
    kw.setdefault("goal", (150, 50))
    kw.setdefault("markers", [])
    return SensorSuite(quiet(), world, robot=robot, backend=backend, **kw)


# -- hand-built scenes ---------------------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_sonar_ray_ends_on_another_robot(backend: str) -> None:
    """Robot 1 is 50 in ahead: the front sonar's centre ray ends on its surface 40 in
    from robot 0's centre (the sonar reads 30, from robot 1), the ray 5 degrees off
    where the circle's chord begins; the side sonars read the walls."""
    w = scene((50, 50), (100, 50))
    g = suite(w, backend).geometry(50.0, 50.0, 0.0)
    assert g.rays[0, 5] == pytest.approx(40.0, abs=1e-12)
    a = math.radians(5.0)
    chord_start = 50 * math.cos(a) - math.sqrt(100 - (50 * math.sin(a)) ** 2)
    assert g.rays[0, 4] == pytest.approx(chord_start, abs=1e-9)
    assert g.raw[0] == pytest.approx(30.0, abs=1e-12)
    assert g.ray_robot[0].tolist() == [-1, -1, -1, 1, 1, 1, 1, 1, -1, -1, -1]
    assert g.sonar_robot.tolist() == [1, -1, -1, -1, -1, -1, -1, -1]
    assert g.raw[2] == pytest.approx(40.0, abs=1e-12)  # sonar 2, at 90 degrees: the wall


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_other_robot_sees_the_first(backend: str) -> None:
    """Robot 1's own rays skip its body and meet robot 0's, 50 in behind it."""
    w = scene((50, 50), (100, 50))
    g = suite(w, backend, robot=1).geometry(100.0, 50.0, math.pi)
    assert g.raw[0] == pytest.approx(30.0, abs=1e-12) and g.sonar_robot[0] == 0


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_camera_cannot_see_a_plate_behind_a_robot(backend: str) -> None:
    """The goal plate at (150, 50) and a marker at (200, 50) are behind robot 1: the
    front camera sees neither; parked, robot 1 hides nothing (edge distances 90 and
    140)."""
    w = scene((50, 50), (100, 50))
    s = suite(w, backend, markers=[(200, 50)])
    g = s.geometry(50.0, 50.0, 0.0)
    assert (g.raw[8], g.raw[11], g.targets[0]) == (FAR, FAR, -1)
    w.park(1)
    g = s.geometry(50.0, 50.0, 0.0)
    assert (g.raw[8], g.raw[11], g.targets[0]) == (90.0, 140.0, 0)
    side = 50.0 / math.sin(math.radians(25.0)) - R  # its outer rays meet the side walls
    assert g.raw[0] == pytest.approx(side, abs=1e-9) and g.sonar_robot[0] == -1


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_parked_robot_is_invisible_and_a_placed_one_seen(backend: str) -> None:
    w = scene((50, 50), (100, 50), (120, 50))
    s = suite(w, backend)
    w.park(1)
    g = s.geometry(50.0, 50.0, 0.0)
    assert g.raw[0] == pytest.approx(50.0, abs=1e-12) and g.sonar_robot[0] == 2
    w.park(2)
    assert s.geometry(50.0, 50.0, 0.0).sonar_robot.tolist() == [-1] * 8
    w.place(1, (80, 50), 0.0)
    g = s.geometry(50.0, 50.0, 0.0)
    assert g.raw[0] == pytest.approx(10.0, abs=1e-12) and g.sonar_robot[0] == 1


@pytest.mark.parametrize("backend", BACKENDS)
def test_incidence_on_a_robot_is_on_its_circle(backend: str) -> None:
    """The centre ray along y = 50 meets a robot at (100, 56) at (92, 50), where the
    circle's normal is (-0.8, -0.6): incidence cosine 0.8 (the realism incidence model)."""
    w = scene((50, 50), (100, 56))
    real = RealismConfig()
    real.sonar.max_incidence_deg = 60.0
    g = suite(w, backend, realism=real).geometry(50.0, 50.0, 0.0)
    assert g.rays[0, 5] == pytest.approx(42.0, abs=1e-12)
    assert g.ray_cos[0, 5] == pytest.approx(0.8, abs=1e-12) and g.ray_robot[0, 5] == 1


def test_the_cone_model_reads_the_nearest_point_of_a_robot() -> None:
    """With ``sensors.backend: cone`` the front sonar reads robot 1's nearest point, 30 in
    from robot 0's edge; off to the side, a robot whose centre is outside the cone but
    whose circle crosses its edge is read where it crosses."""
    w = scene((50, 50), (100, 50))
    s = suite(w, "cone")
    g = s.geometry(50.0, 50.0, 0.0)
    assert g.raw[0] == 30.0 and g.sonar_robot[0] == 1 and (g.ray_robot[0] == 1).all()
    w.place(1, (50 + 50 * math.cos(0.6), 50 + 50 * math.sin(0.6)), 0.0)  # 34.4 deg left
    g = s.geometry(50.0, 50.0, 0.0)
    edge = math.radians(27.5)  # the front cone's left edge
    along, across = 50 * math.cos(0.6 - edge), 50 * math.sin(0.6 - edge)
    assert g.raw[0] == pytest.approx(along - math.sqrt(100 - across**2) - R, abs=1e-9)
    assert g.sonar_robot[0] == 1


def test_robot_bump() -> None:
    """A robot 4 in ahead (edge to edge) is a Bump from a robot; a wall 4 in away is a
    Bump, not a robot's."""
    w = scene((50, 50), (74, 50))
    s = suite(w, "fast")
    for backend_suite in (s, suite(w, "pymunk")):
        _, bump, _ = backend_suite.sense((50.0, 50.0, 0.0), np.random.default_rng(0))
        r = backend_suite.last()[0]
        assert bump and backend_suite.robot_bump(r) and r.sonar_robot[0] == 1
    w.park(1)
    s.sense((14.0, 50.0, math.pi), np.random.default_rng(0))
    r = s.last()[0]
    assert s.bump(r) and not s.robot_bump(r)


def test_robot_sources_follow_the_echo_and_the_crosstalk() -> None:
    """Two sonars: sonar 0's nearest ray hits robot 3 but does not echo (grazing), its
    echo is a wall's; sonar 1 takes sonar 0's echo by crosstalk, then its source is sonar
    0's. The reference and the compiled twin agree."""
    cfg = RealismConfig()
    cfg.sonar.crosstalk = 0.5
    cfg.sonar.max_incidence_deg = 60.0
    model = SensorRealism(cfg, [0.0, 40.0], 1, R, 260.0, FAR, 240.0)
    rays = np.array([[30.0, 40.0], [50.0, 60.0]])
    echo = np.array([[False, True], [True, True]])
    crossed = np.array([False, True])
    ray_robot = np.array([[3, -1], [2, 2]])
    draws = np.zeros(model.n_draws)
    draws[4 * 1 + 3] = 0.1  # below chance / 2: the first neighbour, sonar 0
    ideal = np.array([3, 2])
    want = robot_sources(model, rays, echo, crossed, ray_robot, draws, ideal)
    assert want.tolist() == [-1, -1]
    crossed[1] = False
    assert robot_sources(model, rays, echo, crossed, ray_robot, draws, ideal).tolist() == [-1, 2]
    crossed[1] = True
    got = ideal.copy()
    sonar_sources(rays, echo, crossed, ray_robot, draws, 0, model.params, model.flags,
                  model.neighbours, got)  # fmt: skip
    assert got.tolist() == want.tolist()


# -- the compiled readings against pymunk --------------------------------------------------


@pytest.mark.parametrize("world", [None, "koolio-real"])
@pytest.mark.parametrize("name", SHIPPED)
def test_shared_readings_equal_the_reference(name: str, world: str | None) -> None:
    """8 robots, 150 random poses per arena (``compare_backends(..., others=7)``): every
    distance, incidence, plate, marker, robot hit, state and reading after the realism
    models and noise bit-identical; most poses see a robot."""
    r = compare_backends(name, 150, seed=4, world=world, others=7, noise="uniform")
    assert r.distance_mismatches == 0 and r.state_mismatches == 0, r
    assert r.bit_identical == r.poses and r.robot_readings > 0.7 * r.poses, r


def test_the_engines_cast_and_sight_lines_equal_pymunks() -> None:
    """``FastRays.cast`` and ``line_of_sight`` of a shared world (the viewer's rays:
    ``segment_query.cast_among``, ``line_of_sight_among``) are ``PymunkRays``', bit for
    bit, on 200 random poses of 8 robots in the obstacles arena."""
    arena = load_arena("obstacles").to_world()
    w = World(arena.segments(), R, 8, shared=True)
    ref, fast = suite(w, "pymunk"), suite(w, "fast")
    poses = free_poses("obstacles", R, 1800, 8)
    blocked = hits = 0
    for k in range(200):
        x, y, h = poses[k]
        w.place(0, (x, y), h)
        for j in range(1, 8):
            at = poses[200 + 7 * k + j - 1][:2]
            w.park(j) if w.robot_clearance(j, at) <= 0.0 else w.place(j, at, 0.0)
        dirs = ref.ray_dirs(h)
        want = ref.engine.cast(x, y, dirs, ref.ray_length)
        assert np.array_equal(fast.engine.cast(x, y, dirs, ref.ray_length), want)
        hits += int((ref.engine.cast_hits(x, y, dirs, ref.ray_length)[2] >= 0).sum())
        for j in range(1, 8):  # past each other robot, 30 in beyond its centre
            tx, ty = w.xy[j] + 30.0 * (w.xy[j] - (x, y)) / max(1.0, math.dist(w.xy[j], (x, y)))
            seen = ref.engine.line_of_sight(x, y, tx, ty)
            assert fast.engine.line_of_sight(x, y, tx, ty) == seen
            blocked += w.present[j] and not seen
    assert hits > 1000 and blocked > 300, (hits, blocked)


@pytest.mark.parametrize("name", SHIPPED)
def test_the_cone_sees_a_robot_no_farther_than_the_sub_arcs(name: str) -> None:
    assert cone_disagreement(name, 150, seed=4, others=7).cone_not_nearer == 0


def test_shared_agreement_can_fail() -> None:
    """The comparison sees the other robots moved by 1e-9 in (in the compiled reading's
    positions only): many readings differ from pymunk's."""
    arena = load_arena("room").to_world()
    w = World(arena.segments(), R, 8, shared=True)
    ref, fast = suite(w, "pymunk"), suite(w, "fast")
    poses = free_poses("room", R, 800, 9)
    differ = seen = 0
    for k, (x, y, h) in enumerate(poses[:100]):
        w.place(0, (x, y), h)
        for j in range(1, 8):
            at = poses[100 + 7 * k + j - 1][:2]
            w.park(j) if w.robot_clearance(j, at) <= 0.0 else w.place(j, at, 0.0)
        want = ref.geometry(x, y, h)
        assert np.array_equal(fast.geometry(x, y, h).rays, want.rays)
        w.xy[1:] += 1e-9
        got = fast.geometry(x, y, h)
        w.xy[1:] -= 1e-9
        seen += bool((want.ray_robot >= 0).any())
        differ += not np.array_equal(got.rays, want.rays)
    assert seen > 50 and differ > 30, (seen, differ)


@pytest.mark.parametrize("backend", ["pymunk", "fast", "cone"])
@pytest.mark.parametrize("world", [None, "koolio-real"])
def test_alone_in_a_shared_arena_reads_as_isolated(backend: str, world: str | None) -> None:
    """A robot alone in a shared arena (the others parked) reads what an isolated robot
    reads, bit for bit: geometry, state, readings."""
    cfg = Config()
    if world is not None:
        cfg = apply_world(cfg, world)
    if backend == "cone":
        cfg.realism.sonar.max_incidence_deg = 90.0
    arena = load_arena("obstacles").to_world()
    kw = dict(goal=arena.goal().at, markers=[m.at for m in arena.end_of_world],
              backend=backend, realism=cfg.realism)  # fmt: skip
    alone = World(arena.segments(), R)
    crowd = World(arena.segments(), R, 3, shared=True)
    a = SensorSuite(cfg.sensors, alone, **kw)
    b = SensorSuite(cfg.sensors, crowd, **kw)
    for i, (x, y, h) in enumerate(free_poses("obstacles", R, 60, 2)):
        crowd.place(0, (x, y), h)
        ga, gb = a.geometry(x, y, h), b.geometry(x, y, h)
        for f in ("raw", "rays", "ray_cos", "decoy", "ray_robot", "sonar_robot"):
            assert np.array_equal(getattr(ga, f), getattr(gb, f)), f
        want = a.sense((x, y, h), np.random.default_rng(i))
        assert b.sense((x, y, h), np.random.default_rng(i)) == want
        ra, rb = a.last()[0], b.last()[0]
        assert np.array_equal(ra.sonar, rb.sonar) and np.array_equal(ra.echo, rb.echo)


@numba.njit
def _read(r, x, y, h, rng, shared, rows, robots, present, robot_rows):
    sense = robot_group(r, shared, rows)
    others = robot_others(r, robots, present, robot_rows)
    key, bump, close = sense_reading_among(x, y, h, rng, sense, others)
    return key, bump, close, robot_bump(sense, others)


@pytest.mark.parametrize("world", [None, "koolio-real"])
def test_reading_arrays_read_as_the_suites(world: str | None) -> None:
    """The engine's path (``robot_group``, ``robot_others``, ``sense_reading_among``) for
    4 robots of one hallway gives each robot's suite's reading: key, Bump, goal close,
    Bump from a robot, noised readings and sonar sources, from the same draws."""
    cfg = Config() if world is None else apply_world(Config(), world)
    arena = load_arena("hallway").to_world()
    w = World(arena.segments(), R, 4, shared=True)
    plates = [g.at for g in arena.goals if g.name != arena.active_goal]
    markers = [m.at for m in arena.end_of_world]
    suites = [
        SensorSuite(cfg.sensors, w, arena.goal().at, markers, robot=r, realism=cfg.realism,
                    plates=plates)
        for r in range(4)
    ]  # fmt: skip
    arrays = ReadingArrays(suites)
    for r, s in enumerate(suites):
        arrays.load(r, s)
    poses = free_poses("hallway", R, 400, 6)
    robot_bumps = 0
    for k in range(80):
        for r in range(4):  # four robots side by side, 22 in apart
            x, y, h = poses[k]
            w.place(r, (x + 22.0 * r, y), h)
        for r in range(4):
            x, y, h = w.pose(r)
            want = suites[r].sense((x, y, h), np.random.default_rng([k, r]))
            got = _read(r, x, y, h, np.random.default_rng([k, r]), arrays.shared, arrays.rows,
                        w.xy, w.present, arrays.robot_rows)  # fmt: skip
            readings = suites[r].last()[0]
            assert got == (*want, suites[r].robot_bump(readings)), (k, r)
            assert np.array_equal(arrays.rows[17][r], suites[r].kernel.out)
            assert np.array_equal(arrays.robot_rows[1][r], readings.sonar_robot)
            robot_bumps += got[3]
    assert robot_bumps > 20
