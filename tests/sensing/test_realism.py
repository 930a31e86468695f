"""The realism models (koolio_pymunk/sensing/realism.py): hand-built scenes with exact numbers,
agreement of the compiled kernel with the reference, reproducibility, and bad input."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest
from inputs import log_body
from sensing_agreement import compare_backends, free_poses, same_readings

from koolio_pymunk.apps.cli import main
from koolio_pymunk.learning.training import train
from koolio_pymunk.sensing.realism import (
    F_BEAM,
    F_CAMERA,
    F_SONAR,
    P_SIGMA,
    SensorRealism,
    apply_reference,
    ring_neighbours,
)
from koolio_pymunk.sensing.realism_kernel import apply_realism
from koolio_pymunk.sensing.suite import SensorSuite
from koolio_pymunk.store import run_identity
from koolio_pymunk.store.config import Config, SensorConfig, load_config
from koolio_pymunk.store.episode_log import LOG_FIELDS, log_rows
from koolio_pymunk.store.errors import ConfigError
from koolio_pymunk.store.qtable import QTable, QTableStore, load_qtable
from koolio_pymunk.store.realism_config import MotionRealism, RealismConfig
from koolio_pymunk.task.env import KoolioEnv
from koolio_pymunk.world.arena import load_arena
from koolio_pymunk.world.motion_errors import MotionErrors
from koolio_pymunk.world.physics import World

FAR = 10_000.0
#: Every model on, strongly (so each one acts on a few poses).
ALL_ON = """realism:
  sonar: {max_incidence_deg: 30, min_range: 1.2, max_range: 118, z_hit: 0.7, z_short: 0.1,
          z_max: 0.1, z_rand: 0.1, sigma_hit: 3.0, lambda_short: 0.01, crosstalk: 0.2}
  camera: {detect_near: 0.95, detect_far: 0.4, misread: 0.3}
  motion: {drift_deg: 1.0, drift_sigma_deg: 0.5, slip_sigma: 0.05, turn_sigma_deg: 2.0}
"""
#: ALL_ON with domain randomization of a parameter of each kind.
ALL_ON_DR = (
    ALL_ON
    + """  randomize:
    sonar.sigma_hit: [0.0, 6.0]
    sonar.z_rand: [0.0, 0.2]
    camera.misread: [0.0, 0.5]
    motion.drift_deg: [-2.0, 2.0]
"""
)
#: Every parameter written out at its neutral (off) value.
ALL_OFF = """realism:
  sonar: {max_incidence_deg: 90, min_range: 0, max_range: null, z_hit: 1, z_short: 0,
          z_max: 0, z_rand: 0, sigma_hit: 0, crosstalk: 0}
  camera: {detect_near: 1, detect_far: 1, misread: 0}
  motion: {drift_deg: 0, drift_sigma_deg: 0, slip_sigma: 0, turn_sigma_deg: 0}
  randomize: {}
"""


def world_file(tmp_path: Path, text: str, name: str = "w.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def one_ray_suite(wall: tuple, limit: float, backend: str) -> SensorSuite:
    """One sonar of one ray along the heading, noise off, robot of radius 10 at (0, 0)."""
    cfg = SensorConfig()
    cfg.noise.model = "none"
    cfg.sonar.sonar_sensors_deg = [0.0]
    cfg.sonar.sub_arcs = 1
    cfg.sonar.sonar_arc_deg = 10.0
    cfg.sonar.groups = [[0]]
    real = RealismConfig()
    real.sonar.max_incidence_deg = limit
    world = World([wall], radius=10.0)
    return SensorSuite(cfg, world, (500.0, 500.0), [], backend=backend, realism=real)


def slanted_wall(incidence_deg: float) -> tuple:
    """A wall through (100, 0) that a ray along +x meets ``incidence_deg`` off its normal."""
    slope = math.radians(90.0 - incidence_deg)  # the wall's direction from the ray
    dx, dy = 200.0 * math.cos(slope), 200.0 * math.sin(slope)
    return ((100.0 - dx, -dy), (100.0 + dx, dy))


@pytest.mark.parametrize("backend", ["pymunk", "fast"])
def test_wall_met_at_80_degrees_with_a_40_degree_limit_reads_the_maximum(backend: str) -> None:
    rng = np.random.default_rng(0)
    grazing = one_ray_suite(slanted_wall(80.0), 40.0, backend)
    r = grazing.read((0.0, 0.0, 0.0), rng)
    assert float(r.sonar[0]) == FAR  # no echo: nothing seen, encodes Far
    assert r.echo.tolist() == [[False]]
    assert grazing.encode(r)[-1] == 3
    steep = one_ray_suite(slanted_wall(30.0), 40.0, backend)
    r = steep.read((0.0, 0.0, 0.0), rng)
    assert float(r.sonar[0]) == pytest.approx(90.0, abs=1e-9)  # 100 in to the wall - radius
    assert r.echo.tolist() == [[True]]
    lenient = one_ray_suite(slanted_wall(80.0), 85.0, backend)
    assert float(lenient.read((0.0, 0.0, 0.0), rng).sonar[0]) == pytest.approx(90.0, abs=1e-9)


def test_parallel_wall_disappears_from_the_side_sonars() -> None:
    """Driving along a wall: the 40-degree sonar (rays 15..65 degrees off the heading)
    meets the wall 25..75 degrees off its normal: with Webots' 22.5-degree limit it hears
    nothing, while the 80-degree sonar (normal inside its arc) still reads the wall."""
    cfg = SensorConfig()
    cfg.noise.model = "none"
    cfg.sonar.sonar_sensors_deg = [40.0, 80.0]
    cfg.sonar.groups = [[0], [1]]
    real = RealismConfig()
    real.sonar.max_incidence_deg = 22.5
    world = World([((-1000.0, 30.0), (1000.0, 30.0))], radius=10.0)
    suite = SensorSuite(cfg, world, (0.0, 500.0), [], realism=real)
    r = suite.read((0.0, 0.0, 0.0), np.random.default_rng(0))
    assert float(r.sonar[0]) == FAR
    assert float(r.sonar[1]) == pytest.approx(20.0, abs=1e-9)  # 30 - radius, ray at 90 degrees


def test_hit_only_beam_model_with_sigma_zero_gives_todays_reading() -> None:
    """The beam model forced on with z_hit 1 and sigma 0, in both implementations, on
    random poses and draws: every reading is the ideal one, bit for bit."""
    cfg = Config()
    arena = load_arena("obstacles").to_world()
    world = World(arena.segments(), 10.0)
    suite = SensorSuite(cfg.sensors, world, arena.goal().at, [m.at for m in arena.end_of_world])
    model = suite.realism
    model.flags[F_BEAM] = model.flags[F_SONAR] = True
    rng = np.random.default_rng(5)
    for x, y, h in free_poses("obstacles", 10.0, 60, seed=4):
        g = suite.geometry(x, y, h)
        draws = rng.random(model.n_draws)
        ref = apply_reference(model, g.raw, g.rays, g.ray_cos, g.decoy, draws)
        assert np.array_equal(ref.raw, g.raw)
        fast = g.raw.copy()
        echo, crossed = np.empty(g.rays.shape, bool), np.empty(8, bool)
        missed, misread = np.empty((3, 2), bool), np.empty(3, bool)
        apply_realism(fast, g.rays, g.ray_cos, g.decoy, draws, model.params, model.flags,
                      model.neighbours, echo, crossed, missed, misread)  # fmt: skip
        assert np.array_equal(fast, g.raw)
    model.params[P_SIGMA] = 2.0  # sigma_hit 2 in: the same draws now move the readings
    ref = apply_reference(model, g.raw, g.rays, g.ray_cos, g.decoy, draws)
    assert not np.array_equal(ref.raw, g.raw)


def test_beam_model_components_exact() -> None:
    """Hand-picked draws select each part of the mixture; exact values."""
    real = RealismConfig()
    so = real.sonar
    so.z_hit, so.z_short, so.z_max, so.z_rand = 0.4, 0.3, 0.2, 0.1
    so.sigma_hit, so.lambda_short, so.max_range = 2.0, 0.05, 100.0
    model = SensorRealism(real, [0.0], 0, 10.0, 250.0, FAR, 240.0)
    raw, rays = np.array([40.0, 0.0]), np.array([[50.0]])
    cos, decoy = np.ones((1, 1)), np.zeros(0)

    def reading(u0: float, u1: float, u2: float) -> float:
        draws = np.array([u0, u1, u2, 0.9])
        return float(apply_reference(model, raw, rays, cos, decoy, draws).raw[0])

    gauss = math.sqrt(-2.0 * math.log(1.0 - 0.3)) * math.cos(2.0 * math.pi * 0.1)
    assert reading(0.1, 0.3, 0.1) == 40.0 + 2.0 * gauss  # hit
    short = -math.log(1.0 - 0.5 * (1.0 - math.exp(-0.05 * 40.0))) / 0.05
    assert reading(0.5, 0.5, 0.0) == short and 0.0 < short < 40.0  # short, below the wall
    assert reading(0.8, 0.5, 0.0) == FAR  # max: a dropout
    assert reading(0.95, 0.25, 0.0) == 25.0  # rand: a quarter of the 100 in range


def test_min_range_and_max_range() -> None:
    real = RealismConfig()
    real.sonar.min_range, real.sonar.max_range = 3.0, 60.0
    model = SensorRealism(real, [0.0, 90.0, 180.0], 0, 10.0, 250.0, FAR, 240.0)
    rays = np.array([[11.0], [69.9], [70.1]])  # edge 1.0, 59.9 and 60.1 in
    raw = np.concatenate([rays[:, 0] - 10.0, [0.0]])
    out = apply_reference(model, raw, rays, np.ones((3, 1)), np.zeros(0), np.zeros(12))
    assert out.raw[:3].tolist() == [3.0, pytest.approx(59.9), FAR]
    assert out.echo[:, 0].tolist() == [True, True, False]


def test_crosstalk_takes_the_nearer_neighbour() -> None:
    assert ring_neighbours([0.0, 90.0, 180.0, -90.0]).tolist() == [[3, 1], [0, 2], [1, 3], [2, 0]]
    real = RealismConfig()
    real.sonar.crosstalk = 0.5
    model = SensorRealism(real, [0.0, 90.0, 180.0, -90.0], 0, 10.0, 250.0, FAR, 240.0)
    rays = np.array([[50.0], [20.0], [80.0], [250.0]])  # sonar 3 hits nothing
    raw = np.array([40.0, 10.0, 70.0, FAR, 0.0])
    u = np.zeros(16)
    u[[3, 7, 11, 15]] = [0.9, 0.1, 0.3, 0.3]  # 0: none; 1: clockwise; 2, 3: anticlockwise
    out = apply_reference(model, raw, rays, np.ones((4, 1)), np.zeros(0), u)
    # 1 hears 0 (40: farther than its own 10), 2 hears 3 (nothing), 3 hears 0 (40)
    assert out.raw[:4].tolist() == [40.0, 10.0, 70.0, 40.0]
    assert out.crosstalk.tolist() == [False, False, False, True]


def test_camera_detection_falls_with_distance_and_misread_plates() -> None:
    real = RealismConfig()
    real.camera.detect_near, real.camera.detect_far, real.camera.misread = 1.0, 0.5, 0.2
    model = SensorRealism(real, [0.0], 2, 10.0, 250.0, FAR, 240.0)
    raw = np.array([30.0, 120.0, FAR, 60.0, 240.0, 0.0])  # sonar, goal x2, eow x2, compass
    decoy = np.array([48.0, FAR])

    def cams(*u: float):
        return apply_reference(model, raw, np.array([[40.0]]), np.ones((1, 1)), decoy,
                               np.array([0.0, 0.0, 0.0, 0.0, *u]))  # fmt: skip

    # camera 0: goal at 120 in is detected with probability 0.75, marker at 60 with 0.875
    out = cams(0.9, 0.74, 0.874, 0.9, 0.0, 0.0)
    assert out.raw[1:5].tolist() == [120.0, FAR, 60.0, 240.0]
    assert out.missed.tolist() == [[False, False], [False, False]]
    out = cams(0.9, 0.75, 0.875, 0.9, 0.0, 0.49)
    assert out.raw[1:5].tolist() == [FAR, FAR, FAR, 240.0]  # 240 in: probability 0.5
    assert out.missed.tolist() == [[True, True], [False, False]]
    out = cams(0.1, 0.0, 0.0, 0.1, 0.0, 0.5)  # camera 0 misreads door plate at 48 in
    assert out.raw[1:5].tolist() == [48.0, FAR, 60.0, FAR]
    assert out.misread.tolist() == [True, False]  # camera 1 has no other plate in view
    assert out.missed.tolist() == [[False, False], [False, True]]


def test_drift_of_d_degrees_per_move_bends_forward_moves_into_an_arc() -> None:
    """n Forward moves of 12 in with 3 degrees of drift each: the arc of radius 12/d
    (in radians), turned by n * 3 degrees, exactly."""
    box = [((-500, -500), (500, -500)), ((500, -500), (500, 500)), ((500, 500), (-500, 500)),
           ((-500, 500), (-500, -500))]  # fmt: skip
    world = World(box, radius=10.0)
    world.place(0, (0.0, 0.0), 0.0)
    motion = MotionErrors(MotionRealism(drift_deg=3.0))
    rng = np.random.default_rng(0)
    for _ in range(10):
        world.drive(0, *motion.move(1.0, 12.0, rng))
    d = math.radians(3.0)
    radius = 12.0 / d
    x, y, h = world.pose(0)
    assert h == pytest.approx(math.radians(30.0), abs=1e-12)
    assert x == pytest.approx(radius * math.sin(10 * d), abs=1e-9)
    assert y == pytest.approx(radius * (1.0 - math.cos(10 * d)), abs=1e-9)
    world.drive(0, *motion.move(-1.0, 12.0, rng))  # Reverse retraces the last arc
    assert world.pose(0)[2] == pytest.approx(math.radians(27.0), abs=1e-12)
    assert world.pose(0)[0] == pytest.approx(radius * math.sin(9 * d), abs=1e-9)


def test_drift_through_the_env_and_no_error_is_the_ideal_move(tmp_path) -> None:
    drift = world_file(tmp_path, "realism: {motion: {drift_deg: 2.0}}\n")
    env = KoolioEnv("hallway", world=drift)
    ideal = KoolioEnv("hallway")
    for e in (env, ideal):
        e.reset(seed=1, options={"heading": 0.0})
        for _ in range(3):
            e.transition(3)
    x0, y0 = ideal.world_arena.start.at
    radius = 12.0 / math.radians(2.0)
    x, y, h = env.world.pose(0)
    assert h == pytest.approx(math.radians(6.0), abs=1e-12)
    assert (x - x0, y - y0) == pytest.approx(
        (radius * math.sin(math.radians(6.0)), radius * (1 - math.cos(math.radians(6.0)))),
        abs=1e-9,
    )
    assert ideal.world.pose(0) == pytest.approx((x0 + 36.0, y0, 0.0), abs=1e-9)
    zero = World.from_arena(ideal.arena, 10.0)  # drive() with no error = act(), bit for bit
    zero.place(0, (x0, y0), 0.7)
    zero.drive(0, -12.0, 0.0)
    ideal.world.place(0, (x0, y0), 0.7)
    ideal.world.act([4], 12.0, 0.5)
    assert zero.pose(0) == ideal.world.pose(0)


def test_fast_kernel_agrees_with_reference_under_every_model(tmp_path) -> None:
    world = world_file(tmp_path, ALL_ON)
    for arena, noise in (("hallway", "uniform"), ("obstacles", "gaussian")):
        got = compare_backends(arena, 80, seed=6, noise=noise, world=str(world))
        assert (got.distance_mismatches, got.state_mismatches) == (0, 0)
        assert got.bit_identical == 80


@pytest.mark.parametrize("pings", [3, 5])
def test_fast_kernel_agrees_with_reference_with_several_pings(tmp_path, pings: int) -> None:
    world = world_file(tmp_path, ALL_ON)
    got = compare_backends("hallway", 60, seed=7, noise="uniform", world=str(world), pings=pings)
    assert (got.distance_mismatches, got.state_mismatches) == (0, 0)
    assert got.bit_identical == 60


def test_pings_read_the_median_of_the_beam_draws() -> None:
    """Three pings of one sonar (one ray, wall at 40 in): the first ping's short echo
    and the third's dropout are outvoted by the second's hit; the draws of the extra
    pings come after the sonar's own four (and the cameras', none here)."""
    real = RealismConfig()
    so = real.sonar
    so.z_hit, so.z_short, so.z_max, so.z_rand = 0.4, 0.3, 0.2, 0.1
    so.sigma_hit, so.lambda_short, so.max_range = 2.0, 0.05, 100.0
    model = SensorRealism(real, [0.0], 0, 10.0, 250.0, FAR, 240.0, pings=3)
    assert model.n_draws == 4 + 3 + 3
    raw, rays = np.array([40.0, 0.0]), np.array([[50.0]])
    cos, decoy = np.ones((1, 1)), np.zeros(0)
    short_draws = (0.5, 0.5, 0.0)  # as test_beam_model_components_exact
    hit_draws, max_draws = (0.1, 0.3, 0.1), (0.8, 0.5, 0.0)
    draws = np.array([*short_draws, 0.9, *hit_draws, *max_draws])
    got = float(apply_reference(model, raw, rays, cos, decoy, draws).raw[0])
    gauss = math.sqrt(-2.0 * math.log(1.0 - 0.3)) * math.cos(2.0 * math.pi * 0.1)
    assert got == 40.0 + 2.0 * gauss
    fast = raw.copy()
    echo, crossed = np.empty((1, 1), bool), np.empty(1, bool)
    apply_realism(fast, rays, cos, decoy, draws, model.params, model.flags, model.neighbours,
                  echo, crossed, np.empty((0, 2), bool), np.empty(0, bool))  # fmt: skip
    assert float(fast[0]) == got
    one = SensorRealism(real, [0.0], 0, 10.0, 250.0, FAR, 240.0)  # one ping: the short echo
    assert float(apply_reference(one, raw, rays, cos, decoy, draws[:4]).raw[0]) < 40.0


def test_several_pings_change_nothing_in_the_ideal_world(tmp_path) -> None:
    """No beam model, no draws: more pings learn the ideal world's table (the values, the
    identity: byte for byte but the provenance, whose configuration differs)."""
    tables = []
    for pings in (1, 5):
        cfg = load_config(overrides={"sensors": {"sonar": {"pings": pings}}})
        env = KoolioEnv("hallway", config=cfg)
        store = QTableStore(tmp_path / f"p{pings}.qtable")
        train(env, store, 20, 3, tmp_path / f"p{pings}.csv", report=None)
        tables.append(run_identity.learned_digest(load_qtable(store.path)))
    assert tables[0] == tables[1]


def test_every_model_acts_on_some_readings(tmp_path) -> None:
    """The agreement above is not vacuous: on the hallway each model changes readings."""
    cfg = load_config(world=world_file(tmp_path, ALL_ON))
    arena = load_arena("hallway").to_world()
    world = World(arena.segments(), 10.0)
    plates = [g.at for g in arena.goals if g.name != arena.active_goal]
    markers = [m.at for m in arena.end_of_world]
    real = SensorSuite(cfg.sensors, world, arena.goal().at, markers, realism=cfg.realism,
                       plates=plates)  # fmt: skip
    seen = {"no echo": 0, "crosstalk": 0, "missed": 0, "misread": 0}
    for i, (x, y, h) in enumerate(free_poses("hallway", 10.0, 300, seed=8)):
        real.sense((x, y, h), np.random.default_rng(i))
        r = real.last()[0]
        seen["no echo"] += int((real.echoes(r.rays) & ~r.echo).any())
        seen["crosstalk"] += int(r.crosstalk.any())
        seen["missed"] += int(r.missed.any())
        seen["misread"] += int(r.misread.any())
    assert all(v > 0 for v in seen.values()), seen


def test_forced_neutral_pipeline_reads_like_the_ideal_world() -> None:
    """Both code paths on the same draws: the realism pipeline run with every model at
    its neutral value gives exactly the ideal reading (the models are pure additions)."""
    cfg = Config()
    arena = load_arena("room").to_world()
    world = World(arena.segments(), 10.0)
    markers = [m.at for m in arena.end_of_world]
    ideal = SensorSuite(cfg.sensors, world, arena.goal().at, markers)
    forced = SensorSuite(cfg.sensors, world, arena.goal().at, markers)
    forced.realism.flags[F_SONAR] = forced.realism.flags[F_CAMERA] = True
    forced.kernel.configure_realism()
    for i, pose in enumerate(free_poses("room", 10.0, 100, seed=9)):
        want = ideal.sense(tuple(pose), np.random.default_rng(i))
        assert forced.sense(tuple(pose), np.random.default_rng(i)) == want
        assert same_readings(forced.last()[0], ideal.last()[0])


def small_run(tmp_path: Path, name: str, world: Path | None, episodes: int, **kw) -> tuple:
    cfg = Config()
    cfg.episode.max_steps = 120
    cfg.sensors.sonar.pings = kw.get("pings", 1)
    env = KoolioEnv("room", config=cfg, world=world)
    store = QTableStore(tmp_path / f"{name}.qtable")
    train(env, store, episodes, seed=kw.get("seed", 4), log_path=tmp_path / f"{name}.csv",
          report=None)  # fmt: skip
    return store.path.read_bytes(), (tmp_path / f"{name}.csv").read_bytes()


def test_every_model_off_gives_the_ideal_tables_and_logs(tmp_path) -> None:
    off = world_file(tmp_path, ALL_OFF)
    (ideal_table, ideal_log), (off_table, off_log) = (
        small_run(tmp_path, "ideal", None, 3),
        small_run(tmp_path, "off", off, 3),
    )
    assert log_body(off_log) == log_body(ideal_log)  # the run lines name other runs
    a, b = QTable.from_bytes(ideal_table), QTable.from_bytes(off_table)
    assert b.meta.pop("world") == off.name  # the header names the world it was given
    for t in (a, b):  # and where each came from (the configurations differ)
        del t.meta["provenance"], t.meta["run_id"]
    assert (a.rows, a.meta, a.sections) == (b.rows, b.meta, b.sections)


def test_seeded_runs_with_every_model_on_are_identical_and_resume_exactly(tmp_path) -> None:
    world = world_file(tmp_path, ALL_ON_DR)
    first = small_run(tmp_path, "a", world, 4)
    assert first == small_run(tmp_path, "b", world, 4)
    small_run(tmp_path, "c", world, 2)
    assert small_run(tmp_path, "c", world, 2) == first  # 2 + 2 resumed = 4 in one go
    assert first != small_run(tmp_path, "ideal", None, 4)
    lines = first[1].decode().splitlines()
    assert lines[0].startswith("# koolio-pymunk run ")  # the run line, then the header
    rows = list(csv.reader(lines[1:]))
    extra = ["realism.camera.misread", "realism.motion.drift_deg"]
    extra += ["realism.sonar.sigma_hit", "realism.sonar.z_rand"]
    assert rows[0] == [*LOG_FIELDS, *extra]
    draws = [[float(v) for v in row[len(LOG_FIELDS) :]] for row in rows[1:]]
    assert len(draws) == 4 and len({tuple(d) for d in draws}) == 4
    for misread, drift, sigma, z_rand in draws:
        assert 0 <= misread <= 0.5 and -2 <= drift <= 2 and 0 <= sigma <= 6 and 0 <= z_rand <= 0.2


def test_several_pings_are_seeded_and_resume_exactly(tmp_path) -> None:
    world = world_file(tmp_path, ALL_ON_DR)
    first = small_run(tmp_path, "a", world, 4, pings=3)
    assert first == small_run(tmp_path, "b", world, 4, pings=3)
    small_run(tmp_path, "c", world, 2, pings=3)
    assert small_run(tmp_path, "c", world, 2, pings=3) == first
    assert first[1] != small_run(tmp_path, "one", world, 4)[1]  # the pings change the run


def test_randomized_episode_parameters_reach_the_models(tmp_path) -> None:
    env = KoolioEnv("room", world=world_file(tmp_path, ALL_ON_DR))
    env.reset(seed=3)
    drawn = dict(env.realism_draw)
    so = env.realism.sonar
    assert so.sigma_hit == drawn["sonar.sigma_hit"] and so.z_rand == drawn["sonar.z_rand"]
    assert so.z_hit == pytest.approx(1.0 - (0.1 + 0.1 + drawn["sonar.z_rand"]))
    assert env.sensors.realism.params[P_SIGMA] == drawn["sonar.sigma_hit"]
    assert env.motion is not None
    assert env.motion.drift == pytest.approx(math.radians(drawn["motion.drift_deg"]))
    assert env.config.realism.sonar.sigma_hit == 3.0  # the base stays
    env.reset(seed=4)
    assert env.realism_draw != drawn


def test_readings_expose_what_the_models_did() -> None:
    env = KoolioEnv("hallway", world="koolio-real")
    env.reset(seed=0)
    r = env.readings
    assert r.echo.shape == (8, 11) and r.missed.shape == (3, 2) and r.misread.shape == (3,)
    assert r.sonar.shape == (8,) and r.goal.shape == (3,) and r.eow.shape == (3,)
    ideal = KoolioEnv("hallway")
    ideal.reset(seed=0)
    assert ideal.readings.echo.shape == (8, 11) and not ideal.readings.missed.any()


def test_compass_noise_is_an_angle() -> None:
    """The same error at every heading: East and a heading just under 360 degrees both
    move by draw * 0.25 * 256 units and wrap into [0, 256); 256.0 never occurs."""

    class Draws:
        def __init__(self, e: float) -> None:
            self.e = e

        def uniform(self, low: float, high: float, n: int) -> np.ndarray:
            return np.full(n, self.e)

        def random(self, n: int) -> np.ndarray:  # pragma: no cover - realism is off
            return np.zeros(n)

    cfg = SensorConfig()
    world = World([((0, 0), (100, 0)), ((100, 0), (100, 100)), ((100, 100), (0, 100)),
                   ((0, 100), (0, 0))], radius=10.0)  # fmt: skip
    for backend in ("pymunk", "fast"):
        suite = SensorSuite(cfg, world, (90.0, 50.0), [], backend=backend)
        for heading, e, want in (
            (0.0, 0.5, 32.0),
            (0.0, -0.5, 224.0),
            (0.0, -1e-18, 0.0),
            (math.pi, 0.5, 160.0),
            (2.0 * math.pi - 1e-12, 0.5, 32.0 - 256.0 * 1e-12 / (2.0 * math.pi)),
        ):
            suite.sense((50.0, 50.0, heading), Draws(e))  # type: ignore[arg-type]
            got = suite.last()[0].compass
            assert got == pytest.approx(want, abs=1e-9) and 0.0 <= got < 256.0


def test_many_robots_learn_in_a_realistic_world(tmp_path, capsys) -> None:
    """The step engine runs every realism model and domain randomization for any number
    of robots (refused before the engine): each row carries its episode's draw."""
    args = ["train", "--arena", "room", "--episodes", "4", "--robots", "2", "--quiet"]
    args += ["--qtable", str(tmp_path / "t.qtable"), "--log", str(tmp_path / "t.csv")]
    assert main([*args, "--world", "koolio-real-dr"]) == 0
    rows = log_rows(tmp_path / "t.csv")
    draws = {r["realism.motion.slip_sigma"] for r in rows}
    assert len(rows) == 4 and len(draws) == 4


@pytest.mark.parametrize(
    ("text", "item", "problem"),
    [
        ("realism: {sonar: {z_hit: 0.9, z_rand: 0.05}}", "realism.sonar.z_hit", "sum to 1"),
        ("realism: {sonar: {sigma_hit: -1}}", "realism.sonar.sigma_hit", "must be >= 0"),
        ("realism: {camera: {misread: 1.5}}", "realism.camera.misread", "in [0, 1]"),
        ("realism: {sonar: {crosstalk: -0.1}}", "realism.sonar.crosstalk", "in [0, 1]"),
        ("realism: {motion: {slip_sigma: -0.1}}", "realism.motion.slip_sigma", ">= 0"),
        ("realism: {sonar: {max_incidence_deg: 120}}", "max_incidence_deg", "(0, 90]"),
        ("realism: {randomize: {sonar.z_hit: [0, 1]}}", "randomize.sonar.z_hit", "not a rand"),
        ("realism: {randomize: {camera.misread: [0, 2]}}", "camera.misread", "high end 2"),
        ("realism: {randomize: {sonar.sigma_hit: [3, 1]}}", "sigma_hit", "low 3 exceeds"),
        ("realism: {randomize: {sonar.sigma_hit: 3}}", "sigma_hit", "expected a list, got 3"),
        ("realism: {sonr: {}}", "realism.sonr", "did you mean 'sonar'"),
    ],
)
def test_bad_realism_configuration_is_one_line_exit_2(tmp_path, capsys, text, item, problem):
    bad = world_file(tmp_path, text + "\n", "bad.yaml")
    args = ["train", "--arena", "room", "--episodes", "1", "--quiet"]
    args += ["--qtable", str(tmp_path / "t.qtable"), "--log", str(tmp_path / "t.csv")]
    assert main([*args, "--world", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"koolio-pm: error: {bad}: "), err
    assert item in err[0] and problem in err[0], err[0]
    assert not (tmp_path / "t.qtable").exists()


def test_unknown_world_profile_is_one_line_exit_2(capsys) -> None:
    assert main(["eval", "--world", "koolio-rael", "--qtable", "none.qtable"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "koolio-pm: error: --world: koolio-rael: no such world profile (did you mean "
        "'koolio-real'?) (worlds: ideal, koolio-real, koolio-real-dr; a file name ends in .yaml)"
    ]
    with pytest.raises(ConfigError):
        load_config(world="koolio-rael")


def test_koolio_real_keeps_the_sensor_signature() -> None:
    """A table learned in the ideal world loads in koolio-real (the transfer depends on it)."""
    from koolio_pymunk.store.run_identity import sensor_signature

    real = load_config(world="koolio-real")
    assert sensor_signature(real) == sensor_signature(Config())
    assert load_config("koolio-real").realism == real.realism


def test_stop_at_a_misread_plate_is_a_wrong_door(tmp_path) -> None:
    """Facing door 304's plate from 19 in with misread certain: the robot's Stop earns
    the goal reward and ends the episode, but the event is wrong_door, not goal."""
    world = world_file(tmp_path, "realism: {camera: {misread: 1.0}}\n")
    for backend in ("fast", "pymunk"):
        cfg = Config()
        cfg.sensors.backend = backend
        cfg.sensors.noise.model = "none"
        env = KoolioEnv("hallway", config=cfg, world=world)
        env.reset(seed=0)
        env.world.place(0, (210.0, 58.0), math.pi / 2)  # plate at (210, 87): 29 - 10 in
        _, reward, terminated, _ = env.transition(0)
        assert env.readings.goal[0] == pytest.approx(19.0) and env.readings.misread[0]
        assert (env.judgement.event, reward, terminated) == ("wrong_door", 100.0, True)
    ideal = KoolioEnv("hallway", config=cfg)
    ideal.reset(seed=0)
    ideal.world.place(0, (210.0, 58.0), math.pi / 2)
    assert ideal.transition(0)[1:3] == (-5.0, False)  # the ideal camera sees no goal there


def test_domain_randomization_profile_is_koolio_real_plus_ranges() -> None:
    real = load_config(world="koolio-real").realism
    dr = load_config(world="koolio-real-dr").realism
    assert dr.randomize and not real.randomize
    dr.randomize = {}
    assert dr == real


def test_robot_runtime_encodes_the_realistic_readings_as_the_simulator(tmp_path) -> None:
    """What ``env.readings`` hands a driver (sonar, goal, eow) gives the runtime the
    simulator's own state at every step of a koolio-real episode (the transfer
    experiment runs the runtime on these readings)."""
    from koolio_pymunk import robot_runtime as rt
    from koolio_pymunk.apps.export import policy_document
    from koolio_pymunk.store.qtable import load_qtable

    cfg = Config()
    cfg.episode.max_steps = 60
    env = KoolioEnv("hallway", config=cfg, world="koolio-real")
    store = QTableStore(tmp_path / "t.qtable")
    train(env, store, 1, seed=0, report=None)
    policy = rt.Policy(policy_document(load_qtable(store.path)))
    env.reset(seed=7)
    rng = np.random.default_rng(7)
    for _ in range(60):
        env.transition(int(rng.integers(5)))
        r = env.readings
        assert policy.encode(r.sonar.tolist(), r.goal.tolist(), r.eow.tolist()) == env.codes
