"""Camera: the one world-to-screen conversion (scroll, zoom, follow)."""

from __future__ import annotations

import pytest

from koolio_pymunk.task.viewport import Camera


def test_to_screen_flips_y_and_to_world_inverts() -> None:
    cam = Camera(viewport=(100, 50, 400, 200), center=(10.0, 20.0), zoom=2.0)
    assert cam.to_screen((10.0, 20.0)) == (300, 150)
    assert cam.to_screen((15.0, 25.0)) == (310, 140)  # world y up = screen y down
    for p in [(0.0, 0.0), (-33.5, 71.25), (1632.0, 88.0)]:
        assert cam.to_world(cam.to_screen(p)) == pytest.approx(p, abs=0.5 / cam.zoom)


def test_zoom_at_keeps_the_point_under_the_mouse() -> None:
    cam = Camera(viewport=(0, 0, 800, 300), center=(500.0, 44.0), zoom=1.0)
    mouse = (650, 80)
    before = cam.to_world(mouse)
    cam.zoom_at(mouse, 1.5)
    assert cam.zoom == 1.5
    assert cam.to_world(mouse) == pytest.approx(before)


def test_zoom_is_clamped() -> None:
    cam = Camera(viewport=(0, 0, 100, 100), zoom=1.0, min_zoom=0.5, max_zoom=4.0)
    cam.zoom_at((50, 50), 100.0)
    assert cam.zoom == 4.0
    cam.zoom_at((50, 50), 1e-6)
    assert cam.zoom == 0.5


def test_pan_moves_the_world_with_the_mouse() -> None:
    cam = Camera(viewport=(0, 0, 400, 200), center=(0.0, 0.0), zoom=2.0)
    p = cam.to_world((100, 100))
    cam.pan_pixels(30, -10)
    assert cam.to_world((130, 90)) == pytest.approx(p)


def test_fit_shows_the_whole_hallway_and_follow_centres() -> None:
    cam = Camera(viewport=(0, 0, 1000, 150))
    cam.fit((-48.0, -48.0, 1680.0, 136.0), margin=0.02)
    for corner in [(-48.0, -48.0), (1680.0, 136.0)]:
        x, y = cam.to_screen(corner)
        assert 0 <= x <= 1000 and 0 <= y <= 150
    assert cam.zoom == pytest.approx(1000 / (1728 * 1.04))
    cam.follow((300.0, 44.0))
    assert cam.to_screen((300.0, 44.0)) == (500, 75)


def test_scale_is_at_least_one_pixel() -> None:
    cam = Camera(viewport=(0, 0, 10, 10), zoom=0.1)
    assert cam.scale(10.0) == 1 and cam.scale(0.1) == 1
    assert Camera(viewport=(0, 0, 10, 10), zoom=3.0).scale(10.0) == 30
