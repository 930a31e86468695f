"""World-to-screen conversion: the one place where inches become pixels.

The world is in inches with y up (the paper: 1 inch = 1 pixel); the screen is in pixels
with y down. A :class:`Camera` maps a world rectangle onto a viewport rectangle with a
zoom (pixels per inch) and a centre, and supports the viewer's scroll, zoom and
follow-the-robot. Pure arithmetic: no pygame needed.

>>> cam = Camera(viewport=(0, 0, 200, 100), center=(50.0, 25.0), zoom=2.0)
>>> cam.to_screen((50.0, 25.0))
(100, 50)
>>> cam.to_screen((60.0, 30.0))
(120, 40)
>>> cam.to_world((120, 40))
(60.0, 30.0)
"""

from __future__ import annotations

from dataclasses import dataclass

Point = tuple[float, float]


@dataclass
class Camera:
    viewport: tuple[int, int, int, int]
    """Screen rectangle ``(left, top, width, height)`` in pixels."""
    center: Point = (0.0, 0.0)
    """World point shown at the viewport's centre, inches."""
    zoom: float = 1.0
    """Pixels per inch."""
    min_zoom: float = 0.05
    max_zoom: float = 20.0

    def to_screen(self, p: Point) -> tuple[int, int]:
        """World point (inches, y up) -> integer screen pixel (y down)."""
        left, top, width, height = self.viewport
        sx = left + width / 2.0 + (p[0] - self.center[0]) * self.zoom
        sy = top + height / 2.0 - (p[1] - self.center[1]) * self.zoom
        return (round(sx), round(sy))

    def to_world(self, s: tuple[float, float]) -> Point:
        """Screen pixel -> world point (inverse of :meth:`to_screen`, before rounding)."""
        left, top, width, height = self.viewport
        x = self.center[0] + (s[0] - left - width / 2.0) / self.zoom
        y = self.center[1] - (s[1] - top - height / 2.0) / self.zoom
        return (x, y)

    def scale(self, length: float) -> int:
        """A world length in inches -> pixels (at least 1)."""
        return max(1, round(length * self.zoom))

    def fit(self, bounds: tuple[float, float, float, float], margin: float = 0.05) -> None:
        """Zoom and centre so that ``(xmin, ymin, xmax, ymax)`` fills the viewport."""
        xmin, ymin, xmax, ymax = bounds
        _, _, width, height = self.viewport
        w = max(1e-9, (xmax - xmin) * (1 + 2 * margin))
        h = max(1e-9, (ymax - ymin) * (1 + 2 * margin))
        self.zoom = self._clamp(min(width / w, height / h))
        self.center = ((xmin + xmax) / 2.0, (ymin + ymax) / 2.0)

    def pan_pixels(self, dx: float, dy: float) -> None:
        """Drag the view by a screen displacement (the world moves with the mouse)."""
        self.center = (self.center[0] - dx / self.zoom, self.center[1] + dy / self.zoom)

    def zoom_at(self, screen: tuple[float, float], factor: float) -> None:
        """Zoom by ``factor`` keeping the world point under ``screen`` fixed (mouse wheel)."""
        before = self.to_world(screen)
        self.zoom = self._clamp(self.zoom * factor)
        after = self.to_world(screen)
        self.center = (self.center[0] + before[0] - after[0], self.center[1] + before[1] - after[1])

    def follow(self, p: Point) -> None:
        """Centre on ``p`` (follow-the-robot)."""
        self.center = (float(p[0]), float(p[1]))

    def _clamp(self, z: float) -> float:
        return min(self.max_zoom, max(self.min_zoom, z))
