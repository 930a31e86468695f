"""The editor's camera: the viewer's :class:`~koolio_pymunk.task.viewport.Camera` held to
the editor's ranges (:mod:`~koolio_pymunk.apps.editor.limits`).

The zoom stays within 0.05 to 20 pixels per inch and the centre within the coordinate
range, however often a key repeats, however far the wheel turns or the view is dragged;
so every point of an arena maps to a screen pixel well inside the 32-bit range pygame
draws with. Pure arithmetic: no pygame.

>>> cam = EditorCamera(viewport=(0, 0, 200, 100))
>>> cam.zoom_at((100, 50), 1e300)
>>> cam.zoom
20.0
>>> cam.pan_pixels(-1e300, 0)
>>> cam.center
(1000000.0, 0.0)
"""

from __future__ import annotations

from dataclasses import dataclass

from ...task.viewport import Camera, Point
from . import limits


@dataclass
class EditorCamera(Camera):
    """A :class:`~koolio_pymunk.task.viewport.Camera` whose zoom and centre stay in range."""

    min_zoom: float = limits.MIN_ZOOM
    max_zoom: float = limits.MAX_ZOOM

    def fit(self, bounds: tuple[float, float, float, float], margin: float = 0.05) -> None:
        """Zoom and centre so that ``bounds`` fills the viewport (within the ranges)."""
        super().fit(bounds, margin)
        self._hold_center()

    def pan_pixels(self, dx: float, dy: float) -> None:
        """Drag the view by a screen displacement (the centre stays in range)."""
        super().pan_pixels(dx, dy)
        self._hold_center()

    def zoom_at(self, screen: tuple[float, float], factor: float) -> None:
        """Zoom by ``factor`` about ``screen`` (the zoom and the centre stay in range)."""
        super().zoom_at(screen, factor)
        self._hold_center()

    def follow(self, p: Point) -> None:
        """Centre on ``p`` (held to the range)."""
        super().follow(p)
        self._hold_center()

    def show(self, center: Point, zoom: float) -> None:
        """Centre on ``center`` at ``zoom`` pixels per inch (both held to their ranges)."""
        self.center = (float(center[0]), float(center[1]))
        self.zoom = limits.clamp(float(zoom), self.min_zoom, self.max_zoom)
        self._hold_center()

    def _hold_center(self) -> None:
        self.center = limits.clamp_point(self.center)
