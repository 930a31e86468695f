"""Sensors on hand-built scenes: exact noise-free distances and codes (Tables 6 and 7)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from koolio_pymunk.sensing.suite import SensorSuite, compass_code
from koolio_pymunk.store.config import Config, SensorConfig, state_fields
from koolio_pymunk.world.physics import World

R = 10.0
FAR = 10_000.0


def box(w: float, h: float) -> list:
    return [((0, 0), (w, 0)), ((w, 0), (w, h)), ((w, h), (0, h)), ((0, h), (0, 0))]


def quiet() -> SensorConfig:
    cfg = SensorConfig()
    cfg.noise.model = "none"
    return cfg


def suite(segs, pose, goal=(1e3, 1e3), markers=(), cfg=None) -> tuple[SensorSuite, World]:
    w = World(segs, R)
    w.place(0, pose[:2], pose[2])
    return SensorSuite(cfg or quiet(), w, goal, list(markers)), w


def read(s: SensorSuite, w: World, seed: int = 0):
    return s.read(w.pose(0), np.random.default_rng(seed))


def test_sonar_distances_in_a_box_match_hand_computation() -> None:
    s, w = suite(box(100, 100), (50, 50, 0.0))
    r = read(s, w)
    # Sonar 0 (front) and 4 (rear): the sub-arc through the cone's centre hits at 50.
    assert r.sonar[0] == pytest.approx(40.0, abs=1e-9)
    assert r.sonar[4] == pytest.approx(40.0, abs=1e-9)
    # Sonar 1 at 40 deg: sub-arc centres 15, 20, ..., 65 deg; nearest of the two walls.
    centres = np.radians(40 + np.arange(-25, 26, 5))
    expected = min(min(50 / math.cos(a), 50 / math.sin(a)) for a in centres) - R
    assert r.sonar[1] == pytest.approx(expected, abs=1e-9)
    assert expected == pytest.approx(50 / math.cos(math.radians(15)) - R)


def test_sonar_takes_nearest_sub_arc_not_centre_ray() -> None:
    # A small pillar 30 in ahead but 20 deg off the front: only side sub-arcs see it.
    pillar = [
        ((80, 68), (84, 68)),
        ((84, 68), (84, 72)),
        ((84, 72), (80, 72)),
        ((80, 72), (80, 68)),
    ]
    s, w = suite(box(300, 300) + pillar, (50, 58, 0.0))
    r = read(s, w)
    assert r.sonar[0] < 40 - R  # nearer than the centre ray alone would see
    assert r.rays[0].min() == pytest.approx(r.sonar[0] + R)


def test_sonar_cannot_see_through_walls() -> None:
    # A wall at x = 70 hides the far wall at x = 200.
    s, w = suite(box(200, 100) + [((70, 10), (70, 90))], (50, 50, 0.0))
    assert read(s, w).sonar[0] == pytest.approx(10.0, abs=1e-9)


def test_sonar_beyond_max_range_is_really_long() -> None:
    s, w = suite(box(1000, 1000), (500, 500, 0.0))
    assert read(s, w).sonar.tolist() == [FAR] * 8  # every wall >= 490 in > max_range 240
    s, w = suite(box(1000, 1000), (260, 500, 0.0))  # rear wall 250 from the edge: too far
    assert read(s, w).sonar[4] == FAR
    s, w = suite(box(1000, 1000), (249, 500, 0.0))  # 239 from the edge: seen
    assert read(s, w).sonar[4] == pytest.approx(239.0)


@pytest.mark.parametrize(
    ("distance", "code"),
    [(5.99, 0), (6.0, 1), (23.99, 1), (24.0, 2), (59.99, 2), (60.0, 3), (FAR, 3)],
)
def test_table6_sonar_encoding(distance: float, code: int) -> None:
    s, w = suite(box(100, 100), (50, 50, 0.0))
    r = read(s, w)
    r.sonar[:] = distance
    assert s.encode(r)[6:] == (code,) * 6


@pytest.mark.parametrize(
    ("distance", "code"), [(35.99, 0), (36.0, 1), (95.99, 1), (96.0, 2), (FAR, 2)]
)
def test_table7_camera_encoding(distance: float, code: int) -> None:
    s, w = suite(box(100, 100), (50, 50, 0.0))
    r = read(s, w)
    r.goal[:] = distance
    r.eow[:] = distance
    assert s.encode(r)[:6] == (code,) * 6


def test_sonar_groups_are_averaged_before_encoding() -> None:
    s, w = suite(box(100, 100), (50, 50, 0.0))
    r = read(s, w)
    r.sonar[:] = 100.0
    r.sonar[1], r.sonar[2] = 4.0, 50.0  # mean 27 -> Medium, though sonar 1 alone is Bump
    codes = s.encode(r)
    assert codes[7] == 2
    assert s.bump(r)  # the Bump reward looks at single sonars


def test_camera_sees_goal_in_arc_with_edge_distance() -> None:
    s, w = suite(box(300, 300), (50, 50, 0.0), goal=(150, 50))
    r = read(s, w)
    assert r.goal.tolist() == [pytest.approx(90.0), FAR, FAR]  # front only
    s.set_goal((50 + 100 / math.sqrt(2), 50 + 100 / math.sqrt(2)))  # the left camera, +45
    r = read(s, w)
    assert r.goal.tolist() == [FAR, pytest.approx(90.0), FAR]
    s.set_goal((50, 150))  # straight left: outside every camera's arc
    assert read(s, w).goal.tolist() == [FAR, FAR, FAR]


def test_camera_arc_edges() -> None:
    # Half arc 22.5 deg: a goal at 22 deg is seen, at 23 deg it is not.
    for deg, seen in ((22.0, True), (23.0, False)):
        a = math.radians(deg)
        s, w = suite(
            box(300, 300), (50, 50, 0.0), goal=(50 + 60 * math.cos(a), 50 + 60 * math.sin(a))
        )
        assert bool(read(s, w).goal[0] < FAR) is seen


def test_camera_max_view() -> None:
    s, w = suite(box(600, 100), (50, 50, 0.0), goal=(299, 50))  # 239 from the edge
    assert read(s, w).goal[0] == pytest.approx(239.0)
    s.set_goal((301, 50))  # 241 > max_camera_view 240
    assert read(s, w).goal[0] == FAR


def test_camera_blocked_by_wall_segment() -> None:
    s, w = suite(box(300, 300) + [((100, 30), (100, 70))], (50, 50, 0.0), goal=(150, 50))
    assert read(s, w).goal[0] == FAR


def test_wall_line_crossing_outside_segment_does_not_block() -> None:
    """The paper's bug: the wall's infinite line crosses the sight line, its segment doesn't."""
    # Segment from (100, 60) to (100, 90): its line x = 100 crosses the sight line y = 50.
    s, w = suite(box(300, 300) + [((100, 60), (100, 90))], (50, 50, 0.0), goal=(150, 50))
    assert read(s, w).goal[0] == pytest.approx(90.0)


def test_eow_camera_reports_nearest_visible_marker() -> None:
    markers = [(200, 50), (120, 55), (90, 150)]  # third is outside the front arc
    s, w = suite(box(300, 300), (50, 50, 0.0), markers=markers)
    r = read(s, w)
    assert r.eow[0] == pytest.approx(math.hypot(70, 5) - R)
    assert r.eow_target[0] == 1


def test_noise_is_uniform_ten_percent_and_seeded() -> None:
    cfg = SensorConfig()
    s, w = suite(box(100, 100), (50, 50, 0.0), goal=(90, 50), cfg=cfg)
    a = read(s, w, seed=5)
    b = read(s, w, seed=5)
    c = read(s, w, seed=6)
    assert a.sonar.tolist() == b.sonar.tolist()
    assert a.sonar.tolist() != c.sonar.tolist()
    assert 36.0 <= a.sonar[0] <= 44.0 and a.sonar[0] != 40.0
    assert 27.0 <= a.goal[0] <= 33.0


def test_adding_a_sonar_and_a_camera_is_configuration_only() -> None:
    cfg = quiet()
    cfg.sonar.sonar_sensors_deg = [*cfg.sonar.sonar_sensors_deg, 100.0]
    cfg.sonar.groups = [*cfg.sonar.groups, [8]]
    cfg.camera.camera_sensors_deg = [0.0, 90.0, -90.0, 180.0]
    s, w = suite(box(100, 100), (50, 50, math.pi / 2), goal=(50, 5), cfg=cfg)
    r = read(s, w)
    codes = s.encode(r)
    assert len(codes) == 4 + 4 + 7
    assert len(state_fields(cfg)) == 15
    assert r.sonar[8] == pytest.approx(40.0)  # its cone 75..125 deg holds the 90 deg ray
    assert r.goal[3] == pytest.approx(35.0)  # the new rear camera sees the goal behind


def test_default_state_fields_are_the_papers_twelve() -> None:
    fields = state_fields(Config().sensors)
    assert [n for n, _ in fields] == [
        "GoalCam0",
        "GoalCam1",
        "GoalCam2",
        "EoWCam0",
        "EoWCam1",
        "EoWCam2",
        "Sonar0",
        "Sonar1-2",
        "Sonar3",
        "Sonar4",
        "Sonar5-6",
        "Sonar7",
    ]
    assert [lv for _, lv in fields] == [3] * 6 + [4] * 6


def test_compass_code_boundaries() -> None:
    assert [compass_code(u) for u in (0, 31.9, 32.1, 96.1, 160.1, 224.1)] == [0, 0, 1, 2, 3, 0]
    # 150 units = 210.9 deg (West); 160 units = 225 deg, exactly SW: South
    assert [compass_code(u) for u in (100, 150, 160, 255)] == [2, 2, 3, 0]
