"""The fast sensing backend agrees with the pymunk reference (docs/speed.md).

Tiny budgets: a sample of poses per arena here; ``tools/agreement.py`` runs 100k per arena.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from sensing_agreement import compare_backends, free_poses

from koolio_pymunk.learning.training import train
from koolio_pymunk.sensing.ray_engines import FastRays, PymunkRays
from koolio_pymunk.sensing.ray_kernel import _ray_directions, new_trig
from koolio_pymunk.sensing.suite import SensorSuite, sonar_ray_offsets, turned, unit_vectors
from koolio_pymunk.store import run_identity
from koolio_pymunk.store.config import Config, SensorConfig
from koolio_pymunk.store.qtable import QTableStore, load_qtable
from koolio_pymunk.store.run_identity import sensor_signature
from koolio_pymunk.task.env import KoolioEnv
from koolio_pymunk.world.arena import load_arena
from koolio_pymunk.world.physics import World
from koolio_pymunk.world.segment_query import hypot

ARENAS = ("hallway", "room", "obstacles")


@pytest.mark.parametrize("arena", ARENAS)
def test_fast_backend_agrees_on_random_poses(arena: str) -> None:
    """Noise off: every distance bit for bit (the kernel repeats Chipmunk's operations;
    docs/speed.md says so), the same markers, the same encoded state."""
    got = compare_backends(arena, 150, seed=3)
    assert (got.distance_mismatches, got.state_mismatches) == (0, 0)
    assert got.bit_identical == 150 and got.max_abs_diff == 0.0


def test_fast_backend_agrees_with_noise_on() -> None:
    """Same noise draws in the same order: the same readings bit for bit, the same state,
    Bump and goal-close."""
    got = compare_backends("hallway", 100, seed=4, noise="uniform")
    assert (got.distance_mismatches, got.state_mismatches, got.bit_identical) == (0, 0, 100)
    got = compare_backends("room", 60, seed=5, noise="gaussian")
    assert (got.distance_mismatches, got.state_mismatches, got.bit_identical) == (0, 0, 60)


@pytest.mark.parametrize("arena", ARENAS)
def test_fast_backend_agrees_in_the_realistic_world(arena: str) -> None:
    """koolio-real's realism models (incidence, range, beam model, missed and misread
    plates) with the paper's noise: the same readings, echoes and flags, bit for bit."""
    got = compare_backends(arena, 60, seed=12, noise="uniform", world="koolio-real")
    assert (got.distance_mismatches, got.state_mismatches) == (0, 0)
    assert got.bit_identical == 60


def test_comparison_detects_a_moved_wall() -> None:
    """The check can fail: shift one wall of the fast engine by 1e-3 in."""
    cfg = SensorConfig()
    cfg.noise.model = "none"
    box = [((0, 0), (100, 0)), ((100, 0), (100, 80)), ((100, 80), (0, 80)), ((0, 80), (0, 0))]
    world = World(box, 10.0)
    ref = SensorSuite(cfg, world, (90, 40), [], backend="pymunk")
    fast = SensorSuite(cfg, world, (90, 40), [], backend="fast")
    fast.engine.walls[1, [0, 2]] += 1e-3  # the east wall, x = 100 -> 100.001
    fast.kernel.walls = fast.engine.walls
    raw_r = ref.raw(50.0, 40.0, 0.0)[0]
    raw_f = fast.raw(50.0, 40.0, 0.0)[0]
    assert raw_f[0] - raw_r[0] == pytest.approx(1e-3, abs=1e-9)


def test_ray_directions_are_the_references_bit_for_bit() -> None:
    """The kernel turns the sonar ring's unit vectors by the heading exactly as
    ``suite.turned`` does (the same four products and two sums), and the turned vectors
    are the rays' directions to within 2e-15 (``h + offset`` itself rounds by up to 4e-16)."""
    offsets = sonar_ray_offsets([0.0, 40.0, -135.0], 55.0, 11)
    units = unit_vectors(offsets)
    trig = new_trig(offsets.size)
    rng = np.random.default_rng(4)
    for h in np.concatenate([rng.uniform(0.0, 2.0 * math.pi, 500), [0.0, math.pi / 6]]):
        row = _ray_directions(float(h), units, trig)
        want = turned(float(h), units)
        assert np.array_equal(row[1 : 1 + offsets.size], want[0].ravel())
        assert np.array_equal(row[1 + offsets.size :], want[1].ravel())
        assert np.allclose(want[0], np.cos(h + offsets), rtol=0.0, atol=2e-15)
        assert np.allclose(want[1], np.sin(h + offsets), rtol=0.0, atol=2e-15)


def test_engines_cast_and_line_of_sight_agree() -> None:
    """The engine API (cast, line_of_sight) of both engines on hand-picked rays."""
    box = [((0, 0), (100, 0)), ((100, 0), (100, 80)), ((100, 80), (0, 80)), ((0, 80), (0, 0))]
    corners = [(40, 30), (60, 30), (60, 50), (40, 50)]
    pillar = [(corners[i], corners[(i + 1) % 4]) for i in range(4)]
    world = World(box + pillar, 10.0)
    ref, fast = PymunkRays(world), FastRays(world)
    dirs = unit_vectors(np.linspace(0.0, 2.0 * math.pi, 37))
    want = ref.cast(20.0, 40.0, dirs, 250.0)
    assert np.array_equal(fast.cast(20.0, 40.0, dirs, 250.0), want)
    assert want[0] == pytest.approx(20.0)  # straight into the pillar's west face at x = 40
    assert np.array_equal(fast.cast(20.0, 40.0, dirs, 10.0), ref.cast(20.0, 40.0, dirs, 10.0))
    for target, seen in (((90.0, 40.0), False), ((30.0, 75.0), True), ((20.0, 5.0), True)):
        assert ref.line_of_sight(20.0, 40.0, *target) is seen
        assert fast.line_of_sight(20.0, 40.0, *target) is seen


def test_hypot_matches_python() -> None:
    rng = np.random.default_rng(7)
    pts = rng.uniform(-2000.0, 2000.0, (20_000, 2))
    assert all(hypot(a, b) == math.hypot(a, b) for a, b in pts)


def test_large_sonar_groups_encode_like_numpy() -> None:
    """Group means of 1..11 sonars (numpy's pairwise summation from 8 values on)."""
    cfg = Config()
    so = cfg.sensors.sonar
    so.sonar_sensors_deg = [float(a) for a in range(-165, 180, 15)]  # 23 sonars
    so.groups = [[0], [1, 2, 3], list(range(4, 12)), list(range(12, 23))]
    cfg.validate()
    world = World([((0, 0), (300, 0)), ((300, 0), (150, 200)), ((150, 200), (0, 0))], 10.0)
    ref = SensorSuite(cfg.sensors, world, (150, 100), [], backend="pymunk")
    fast = SensorSuite(cfg.sensors, world, (150, 100), [], backend="fast")
    rng = np.random.default_rng(0)
    for i in range(40):
        pose = (float(rng.uniform(60, 240)), float(rng.uniform(20, 60)), float(rng.uniform(0, 6)))
        want = ref.sense(pose, np.random.default_rng(i))
        assert fast.sense(pose, np.random.default_rng(i)) == want
        assert ref.last()[1] == fast.last()[1]
        assert np.array_equal(ref.last()[0].sonar, fast.last()[0].sonar)


def test_training_with_either_backend_gives_the_same_table(tmp_path) -> None:
    tables = []
    for backend in ("pymunk", "fast"):
        cfg = Config()
        cfg.sensors.backend = backend
        cfg.episode.max_steps = 150
        env = KoolioEnv("room", config=cfg)
        store = QTableStore(tmp_path / f"{backend}.qtable")
        train(env, store, 3, seed=11, report=None)  # the same but the configuration
        tables.append(run_identity.learned_digest(load_qtable(store.path)))
    assert tables[0] == tables[1]


def test_free_poses_fit_the_robot() -> None:
    poses = free_poses("obstacles", 10.0, 50, seed=1)
    world = World.from_arena(load_arena("obstacles"), 10.0)
    for x, y, h in poses:
        world.place(0, (x, y), h)
        assert world.wall_clearance(0) >= -0.011


def test_cone_model_is_the_limit_of_dense_rays() -> None:
    """The exact cone reads the nearest wall point in the whole arc: never farther than
    the sub-arc rays, and what 2001 rays spanning the arc edge to edge converge to."""
    cfg = SensorConfig()
    cfg.noise.model = "none"
    arena = load_arena("obstacles").to_world()
    world = World(arena.segments(), 10.0)
    cone = SensorSuite(cfg, world, arena.goal().at, [], backend="cone")
    sub = SensorSuite(cfg, world, arena.goal().at, [], backend="fast")
    rays = FastRays(world)
    half = math.radians(cfg.sonar.sonar_arc_deg) / 2.0
    fan = np.linspace(-half, half, 2001)
    for x, y, h in free_poses("obstacles", 10.0, 40, seed=2):
        c = cone.raw(x, y, h)[0][: cone.n_sonar]
        s = sub.raw(x, y, h)[0][: sub.n_sonar]
        assert (c <= s + 1e-9).all()
        for k, deg in enumerate(cfg.sonar.sonar_sensors_deg):
            dirs = unit_vectors(h + math.radians(deg) + fan)
            dense = rays.cast(x, y, dirs, cone.ray_length).min()
            want = 10_000.0 if dense > cone.ray_length - 1e-9 else dense - 10.0
            assert c[k] <= want + 1e-9
            assert c[k] == pytest.approx(want, abs=0.05)


def test_cone_backend_keeps_its_tables_apart() -> None:
    cfg = Config()
    plain = sensor_signature(cfg)
    cfg.sensors.backend = "cone"
    assert sensor_signature(cfg) == plain | {"sonar_model": "cone"}
    cfg.sensors.backend = "pymunk"
    assert sensor_signature(cfg) == plain
