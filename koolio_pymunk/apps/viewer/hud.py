"""Panels of the window: the HUD (encoded readings), Stats, the live learning curve, tags
and the help overlay (paper §5.4.5, §5.4.9).

Each ``draw_*`` function draws into a screen rectangle of ``surface`` (clipped to it) and
returns a dict naming the rectangles it drew that tests and the app may want (for
example the Bump flag). Sizes come from a :class:`Style`, made for the window's size by
:func:`style` (fonts and rows grow with the window, 1280 x 800 being 1.0). Text is set in
Noto Sans (shipped with pygame-gui, so the panels and the controls share one face; it has
the degree sign), falling back to pygame's bundled font.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pygame

from ...sensing.suite import compass_code
from ...store.config import BEARINGS
from ...store.keyword import CAMERA_LEVELS, COMPASS_LEVELS, SONAR_LEVELS
from ...task.drawing import ROBOT_PALETTE, Color
from ...task.env import KoolioEnv
from ...world.physics import ACTION_NAMES
from ..plotting import moving_average
from .session import Session

PANEL_BG: Color = (243, 244, 247)
PANEL_EDGE: Color = (150, 156, 168)
TITLE: Color = (20, 30, 70)
INK: Color = (20, 20, 24)
DIM: Color = (72, 76, 88)
"""Labels and secondary values: dark enough to read on the panel (contrast about 8:1)."""
BUMP_ON: Color = (255, 105, 180)
"""The Bump flag when set (the robot's Bump colour)."""
BUMP_OFF: Color = (222, 224, 230)
FLAG_COLOURS: dict[str, Color] = {
    "misread": (240, 150, 240),
    "missed": (170, 195, 255),
    "no echo": (255, 190, 120),
}
"""HUD marks of what the realism models did: a camera that misread another door's plate
(magenta, as its line), one that missed a target in view (blue), a sonar row with a sonar
that heard no echo although its rays met a wall (orange; the distance column shows which:
``none, 52.9``)."""
LEVEL_COLOURS: dict[str, Color] = {
    "Bump": (255, 170, 205),
    "Close": (255, 205, 150),
    "Medium": (255, 240, 170),
    "Far": (222, 236, 222),
}
CURVE_RETURN: Color = (150, 185, 230)
"""Return of each episode (thin, light)."""
CURVE_AVERAGE: Color = (10, 60, 170)
"""Moving average of the return (thick, dark)."""
CURVE_GOAL: Color = (0, 150, 60)
"""Share of recent episodes that ended at the goal (right axis)."""
CURVE_AXES: Color = (90, 90, 100)
CURVE_GRID: Color = (228, 230, 236)
CURVE_ZERO: Color = (200, 202, 210)
"""The return-axis line at 0 (between the grid lines)."""
CURVE_RUN_START: Color = (200, 120, 0)
TAG_COLOURS: dict[str, Color] = {
    "AUTO-RESCUE": (40, 130, 70),
    "CLOCKLESS": (30, 90, 170),
    "RESCUED": (200, 60, 30),
    "PAUSED": (110, 110, 110),
    "GREEDY": (120, 60, 150),
    "DONE": (0, 0, 0),
    "FOLLOW": (70, 120, 140),
    "WAITING": (150, 110, 20),
}


def tag_colour(tag: str) -> Color:
    """A tag's badge colour: ``ROBOT k`` (the selected robot of a shared arena) in robot
    ``k``'s palette colour, the others from :data:`TAG_COLOURS` (grey when not there)."""
    head, _, number = tag.partition(" ")
    if head == "ROBOT" and number.isdigit():
        return ROBOT_PALETTE[int(number) % len(ROBOT_PALETTE)]
    return TAG_COLOURS.get(tag, (60, 60, 60))


# -- sizes and text ----------------------------------------------------------------------------
@dataclass(frozen=True)
class Style:
    """Font sizes and row heights of the panels, in pixels."""

    ui: float = 1.0
    """Scale: 1.0 at 1280 x 800."""

    def px(self, v: float) -> int:
        return max(1, round(v * self.ui))

    @property
    def title(self) -> int:
        return self.px(16)

    @property
    def row(self) -> int:
        return self.px(14)

    @property
    def row_h(self) -> int:
        return self.px(18)

    @property
    def small(self) -> int:
        return self.px(13)

    @property
    def pad(self) -> int:
        return self.px(8)

    @property
    def head_h(self) -> int:
        """Height of a panel's title strip."""
        return self.px(26)


PLAIN = Style()
"""The style at 1280 x 800."""


def scale_for(size: tuple[int, int]) -> float:
    """The UI scale of a window: 1.0 at 1280 x 800, 1.35 at 1920 x 1080 (at most 2)."""
    w, h = size
    return max(1.0, min(2.0, round(min(w / 1280.0, h / 800.0), 2)))


def style(size: tuple[int, int]) -> Style:
    return Style(scale_for(size))


def font_file(bold: bool = False) -> str | None:
    """Noto Sans from pygame-gui's data folder, or None (pygame's bundled font)."""
    try:
        import pygame_gui
    except ImportError:
        return None
    name = "NotoSans-Bold.ttf" if bold else "NotoSans-Regular.ttf"
    path = Path(pygame_gui.__file__).parent / "data" / name
    return str(path) if path.exists() else None


_FONTS: dict[tuple[int, bool], pygame.font.Font] = {}
_TEXT: dict[tuple[str, int, Color, bool], pygame.Surface] = {}


def font(size: int, bold: bool = False) -> pygame.font.Font:
    f = _FONTS.get((size, bold))
    if f is None:
        if not pygame.font.get_init():
            pygame.font.init()
        f = _FONTS[(size, bold)] = pygame.font.Font(font_file(bold), size)
    return f


def text(s: str, size: int, colour: Color = INK, bold: bool = False) -> pygame.Surface:
    """A rendered label in the panels' face, cached (labels repeat from frame to frame)."""
    key = (s, size, colour, bold)
    surf = _TEXT.get(key)
    if surf is None:
        if len(_TEXT) > 4000:
            _TEXT.clear()
        surf = _TEXT[key] = font(size, bold).render(s, True, colour)
    return surf


def plural(n: int, word: str) -> str:
    """``1 episode``, ``2 episodes``.

    >>> plural(1, "episode"), plural(0, "episode"), plural(1501, "episode")
    ('1 episode', '0 episodes', '1,501 episodes')
    """
    return f"{n:,} {word}" + ("" if n == 1 else "s")


def panel(surface: pygame.Surface, rect: pygame.Rect, title: str, st: Style = PLAIN) -> pygame.Rect:
    """A framed panel with a title; returns the content rectangle below the title."""
    pygame.draw.rect(surface, PANEL_BG, rect)
    pygame.draw.rect(surface, PANEL_EDGE, rect, width=1)
    surface.blit(text(title, st.title, TITLE, bold=True), (rect.x + st.pad, rect.y + st.px(4)))
    return pygame.Rect(
        rect.x + st.pad, rect.y + st.head_h, rect.w - 2 * st.pad, rect.h - st.head_h - st.pad
    )


# -- HUD ---------------------------------------------------------------------------------------
def _fmt_distance(d: float, far: float) -> str:
    return "not seen" if d >= far else f"{d:.1f} in"


def group_distance(values: Sequence[float], far: float) -> str:
    """A sonar group's distance: the mean its level comes from; when some of its sonars
    heard nothing and others did (the nothing, ``really_long_distance``, makes the mean
    Far), each sonar's reading instead.

    >>> group_distance([17.6, 20.0], 10000.0), group_distance([10000.0] * 2, 10000.0)
    ('18.8 in', 'not seen')
    >>> group_distance([17.6, 10000.0], 10000.0)
    '17.6, none'
    """
    unseen = sum(v >= far for v in values)
    if unseen in (0, len(values)):
        return _fmt_distance(float(np.mean(values)), far)
    return ", ".join("none" if v >= far else f"{v:.1f}" for v in values)


def _deg(angle: float) -> str:
    return f"{angle:+.0f}°" if angle else "0°"


@dataclass(frozen=True)
class HudRow:
    """One field of the state: name, sensor angles, encoded level, distance behind it,
    (sonar rows) the single sonars of the field that read Bump on their own, and marks of
    what the realism models did (``misread``, ``missed``, ``no echo``)."""

    name: str
    angles: str
    level: str
    distance: str
    bumped: tuple[int, ...] = ()
    flags: tuple[str, ...] = ()


def hud_rows(env: KoolioEnv) -> list[HudRow]:
    """Every state field in keyword order (cameras, sonar groups, compass if in state)."""
    s, r = env.sensors, env.readings
    cam = s.cfg.camera.camera_sensors_deg
    codes = env.codes
    rows: list[HudRow] = []
    for kind, values in (("GoalCam", r.goal), ("EoWCam", r.eow)):
        for c in range(s.n_camera):
            level = CAMERA_LEVELS[codes[len(rows)]]
            flags = camera_flags(env, c, goal=kind == "GoalCam")
            d = _fmt_distance(values[c], s.far)
            rows.append(HudRow(f"{kind}{c}", _deg(cam[c]), level, d, flags=flags))
    bumped = set(bumped_sonars(env))
    deaf = set(deaf_sonars(env))
    son = s.cfg.sonar.sonar_sensors_deg
    for g in s.groups:
        name = "Sonar" + "-".join(str(k) for k in g)
        angles = ",".join(_deg(son[k]) for k in g)
        d = group_distance(r.sonar[g].tolist(), s.far)
        level = SONAR_LEVELS[codes[len(rows)]]
        flags = ("no echo",) if any(k in deaf for k in g) else ()
        rows.append(HudRow(name, angles, level, d, tuple(k for k in g if k in bumped), flags))
    if s.cfg.compass.in_state:
        rows.append(HudRow("Compass", "", COMPASS_LEVELS[codes[len(rows)]], f"{r.compass:.0f}/256"))
    return rows + memory_rows(env)


def memory_rows(env: KoolioEnv) -> list[HudRow]:
    """The memory's state fields (``sensors.memory``): what the robot remembers."""
    mem, cfg = env.memory, env.config.sensors.memory
    cam = env.sensors.cfg.camera.camera_sensors_deg
    rows: list[HudRow] = []

    def camera(name: str, value: int, what: str) -> HudRow:
        """The camera that last saw it: its number as the level, its angle beside."""
        if value == 0:
            return HudRow(name, "", "none", what)
        return HudRow(name, _deg(cam[value - 1]), f"cam {value - 1}", what)

    if cfg.goal_camera:
        rows.append(camera("GoalMemory", mem.goal, "last saw the goal"))
    if cfg.eow_camera:
        rows.append(camera("EoWMemory", mem.eow, "last saw the end"))
    if cfg.previous_action:
        last = "none" if mem.action == 0 else ACTION_NAMES[mem.action - 1]
        rows.append(HudRow("LastAction", "", last, ""))
    if cfg.goal_bearing:
        angle = _deg(mem.bearing_mdeg / 1000) if mem.bearing else ""
        rows.append(HudRow("GoalBearing", angle, BEARINGS[mem.bearing], "dead reckoned"))
    return rows


def camera_flags(env: KoolioEnv, camera: int, goal: bool) -> tuple[str, ...]:
    """``("misread",)`` when the camera's goal reading is another door's plate,
    ``("missed",)`` when it had its target (the goal, or with ``goal`` False an
    end-of-world marker) in view and did not detect it, else ``()``."""
    r = env.readings
    if r.missed.shape != (env.sensors.n_camera, 2):
        return ()
    if goal and r.misread[camera]:
        return ("misread",)
    return ("missed",) if r.missed[camera, 0 if goal else 1] else ()


def deaf_sonars(env: KoolioEnv) -> list[int]:
    """The sonars that heard no echo at all although some of their rays met a wall (the
    realism incidence and range models: the wall is there, the sonar reads past it)."""
    r, s = env.readings, env.sensors
    if r.echo.shape != r.rays.shape:
        return []
    hit = r.rays < s.ray_length - 1e-9
    return [int(k) for k in np.flatnonzero(hit.any(axis=1) & ~r.echo.any(axis=1))]


def bumped_sonars(env: KoolioEnv) -> list[int]:
    """The single sonars that read Bump (the Bump reward and flag use single sonars; a row
    of an averaged pair can read Close while one of its two sonars bumps)."""
    r = env.readings
    return [int(k) for k in np.flatnonzero(r.sonar < env.sensors.sonar_thresholds[0])]


def bump_text(env: KoolioEnv) -> str:
    """The Bump flag's label: ``no bump`` or ``BUMP: sonar 2 (+80°) 4.1 in``."""
    ks = bumped_sonars(env)
    if not ks:
        return "no bump"
    son, r = env.sensors.cfg.sonar.sonar_sensors_deg, env.readings
    if len(ks) == 1:
        k = ks[0]
        return f"BUMP: sonar {k} ({_deg(son[k])}) {r.sonar[k]:.1f} in"
    return "BUMP: sonars " + ", ".join(str(k) for k in ks)


def draw_hud(
    surface: pygame.Surface,
    rect: pygame.Rect,
    env: KoolioEnv,
    st: Style = PLAIN,
    title: str = "HUD: encoded readings",
) -> dict[str, object]:
    """Show HUD: every encoded reading by name, its level and distance; the Bump flag
    naming the sonar that bumped, and that sonar marked in its row.

    The rows close up when a long state (memory fields, a compass) would push the lines
    below them out of the panel: a row is :attr:`Style.row_h` high, or less, down to
    :func:`min_row_step`; if that is not enough, the compass line (not in the state) is
    left out, so that the last action's line stays in view."""
    clip = surface.get_clip()
    surface.set_clip(rect)
    inner = panel(surface, rect, title, st)
    cols = _hud_columns(inner.x, st)
    rows = hud_rows(env)
    below = _below_rows(st)
    show_compass = len(rows) * min_row_step(st) + below <= inner.h
    if not show_compass:
        below -= st.row_h
    step = max(min_row_step(st), min(st.row_h, (inner.h - below) // max(1, len(rows))))
    y = inner.y
    marks: dict[int, pygame.Rect] = {}
    flags: dict[str, pygame.Rect] = {}
    for row in rows:
        mark = _hud_row(surface, row, cols, y, st, step)
        if mark is not None:
            marks.update(dict.fromkeys(row.bumped, mark))
        x = max(cols[4], cols[3] + text(row.distance, st.row, DIM).get_width() + st.px(6))
        x = x if mark is None else mark.right + st.px(4)
        for word in row.flags:
            flags[row.name] = _flag_mark(surface, word, x, y, st, step)
            x = flags[row.name].right + st.px(4)
        y += step
    flag = _bump_flag(surface, env, inner.x, y + st.px(5), st)
    compass = env.readings.compass
    line = f"compass {COMPASS_LEVELS[compass_code(compass)]} ({compass:.0f}/256), not in the state"
    y = flag.bottom + st.px(4)
    if show_compass:
        surface.blit(text(line, st.small, DIM), (inner.x, y))
        y += st.row_h
    j = env.judgement
    if j is not None and env.last_action is not None:
        last = f"last: {ACTION_NAMES[env.last_action]} -> {j.event} ({j.reward:+g})"
    else:
        last = "last: (episode start)"
    shown = text(last, st.row, INK)
    surface.blit(shown, (inner.x, y))
    surface.set_clip(clip)
    return {
        "panel": rect,
        "title": title,
        "bump_flag": flag,
        "bump_marks": marks,
        "flag_marks": flags,
        "row_step": step,
        "compass_line": show_compass,
        "last_line": shown.get_rect(topleft=(inner.x, y)),
    }


def hud_height(n_rows: int, st: Style) -> int:
    """The HUD panel's height that shows ``n_rows`` state fields at full row height, the
    lines below them included (what the window gives it when it can)."""
    return st.head_h + n_rows * st.row_h + _below_rows(st) + st.pad


def _below_rows(st: Style) -> int:
    """The height under the HUD's rows: the Bump flag, the compass and last-action lines."""
    return st.px(5) + st.px(24) + st.px(4) + 2 * st.row_h


def min_row_step(st: Style) -> int:
    """The closest the HUD's rows come together: the height of a row's text."""
    return st.px(15)


def _hud_columns(x0: int, st: Style) -> tuple[int, int, int, int, int]:
    """x of the name, angles, level, distance and bump-mark columns."""
    angles = x0 + st.px(76)
    level = angles + st.px(84)
    dist = level + st.px(66)
    return x0, angles, level, dist, dist + st.px(66)


def _hud_row(
    surface: pygame.Surface, row: HudRow, cols: tuple[int, ...], y: int, st: Style, step: int
) -> pygame.Rect | None:
    x_name, x_ang, x_level, x_dist, x_mark = cols
    ty = y - st.px(1) - (st.row_h - step) // 2
    name = text(row.name, st.row, INK)
    surface.blit(name, (x_name, ty))
    x_ang = max(x_ang, x_name + name.get_width() + st.px(4))  # a long name (EoWMemory)
    surface.blit(text(row.angles, st.small, DIM), (x_ang, ty + st.px(1)))
    level = text(row.level, st.row, INK)  # a memory's level may be wider than the column
    cell = pygame.Rect(
        x_level - st.px(3), y, max(st.px(60), level.get_width() + st.px(6)), step - 1
    )
    pygame.draw.rect(surface, LEVEL_COLOURS.get(row.level, PANEL_BG), cell)
    surface.blit(level, (x_level, ty))
    surface.blit(text(row.distance, st.row, DIM), (max(x_dist, cell.right + st.px(6)), ty))
    if not row.bumped:
        return None
    label = text("bump: " + ",".join(str(k) for k in row.bumped), st.small, INK)
    mark = pygame.Rect(x_mark, y, label.get_width() + st.px(8), step - 1)
    pygame.draw.rect(surface, BUMP_ON, mark, border_radius=3)
    surface.blit(label, label.get_rect(center=mark.center))
    return mark


def _flag_mark(
    surface: pygame.Surface, flag: str, x: int, y: int, st: Style, step: int
) -> pygame.Rect:
    """A realism mark (``misread``, ``missed``, ``no echo``) in its colour at ``x``."""
    label = text(flag, st.small, INK)
    mark = pygame.Rect(x, y, label.get_width() + st.px(8), step - 1)
    colour = FLAG_COLOURS[flag]
    pygame.draw.rect(surface, colour, mark, border_radius=3)
    surface.blit(label, label.get_rect(center=mark.center))
    return mark


def _bump_flag(surface: pygame.Surface, env: KoolioEnv, x: int, y: int, st: Style) -> pygame.Rect:
    label_text = bump_text(env)
    on = label_text != "no bump"
    label = text(label_text, st.row, INK if on else DIM, bold=on)
    flag = pygame.Rect(x, y, max(st.px(90), label.get_width() + st.px(16)), st.px(24))
    pygame.draw.rect(surface, BUMP_ON if on else BUMP_OFF, flag)
    pygame.draw.rect(surface, PANEL_EDGE, flag, width=1)
    surface.blit(label, label.get_rect(center=flag.center))
    return flag


# -- Stats -------------------------------------------------------------------------------------
def _num(v: float, fmt: str = "{:.1f}") -> str:
    return "-" if isinstance(v, float) and math.isnan(v) else fmt.format(v)


def episode_number(session: Session) -> int:
    """The number of the episode on the screen, counted from 1 as everywhere people read
    episode numbers (``train``'s progress, the curve, the checks; the log's ``episode``
    column is this number less one): the one running, or the one just finished while its
    end is still shown. Learning, it is the table's count: a table of 163 episodes
    resumed shows #164 first; watching, the episodes of this window."""
    return session.episode + (0 if session.episode_over else 1)


def stats_rows(session: Session, steps_per_s: float) -> list[tuple[str, str]]:
    """``(label, value)`` lines of the Stats panel; ``("", heading)`` starts a section."""
    env, st = session.env, session.stats
    trained = int(session.table.meta.get("episodes", 0))
    n = session.n_robots
    heading = f"This episode (#{episode_number(session)}, goal {env.goal_name})"
    episodes = f"{st.episodes}"
    if n > 1:  # the selected robot's episode; the run's totals, and its share of them
        k = session.selected
        heading = f"Robot {k}'s episode {session.robot_episodes[k]} (goal {env.goal_name})"
        if env.waiting:
            heading = f"Robot {k}: waiting for a free start spot"
        episodes += f" (robot {k}: {session.robot_stats[k].episodes})"
    rows = [
        ("", heading),
        ("reward", f"{env.episode_reward:g}"),
        ("steps", f"{env.steps}"),
        ("bumps", f"{env.bumps}"),
        ("", "All episodes of this run"),
        ("episodes", episodes),
        ("at the goal", f"{st.goals}" + ("" if not st.episodes else f" ({st.goal_rate:.0%})")),
        ("avg reward / ep", _num(st.mean(st.reward_sum))),
        ("avg steps / ep", _num(st.mean(st.steps_sum))),
        ("avg bumps / ep", _num(st.mean(st.bumps_sum))),
        ("", "Learner"),
        ("epsilon", f"{session.agent.epsilon:.3f}" + ("" if session.learn else " (greedy)")),
        ("Q-table", plural(len(session.table), "state")),
        ("trained", plural(trained, "episode")),
        ("speed", f"{steps_per_s:,.0f} {'steps' if n == 1 else 'ticks'}/s"),
    ]
    return rows


def draw_stats(
    surface: pygame.Surface,
    rect: pygame.Rect,
    session: Session,
    steps_per_s: float = 0.0,
    st: Style = PLAIN,
) -> dict[str, pygame.Rect]:
    """Show Stats: this episode's reward, steps and bumps; totals and per-episode averages."""
    clip = surface.get_clip()
    surface.set_clip(rect)
    inner = panel(surface, rect, "Stats", st)
    y = inner.y
    value_x = inner.x + max(st.px(122), inner.w * 2 // 5)
    for label, value in stats_rows(session, steps_per_s):
        if not label:
            y += st.px(3)
            surface.blit(text(value, st.row, TITLE, bold=True), (inner.x, y - st.px(1)))
        else:
            surface.blit(text(label, st.row, DIM), (inner.x + st.px(8), y - st.px(1)))
            surface.blit(text(value, st.row, INK), (value_x, y - st.px(1)))
        y += st.row_h
    surface.set_clip(clip)
    return {"panel": rect}


# -- the live learning curve -------------------------------------------------------------------
def nice_ticks(lo: float, hi: float, most: int = 6, whole: bool = False) -> list[float]:
    """Round tick values (1, 2, 2.5 or 5 x 10^k apart) inside ``[lo, hi]``: the closest
    spacing that gives at most ``most`` of them; ``whole``: whole numbers only (episodes:
    no 1.5, which a label rounds to a second "2").

    >>> nice_ticks(-2282, 182)
    [-2000.0, -1500.0, -1000.0, -500.0, 0.0]
    >>> nice_ticks(1, 1501, 6)
    [250.0, 500.0, 750.0, 1000.0, 1250.0, 1500.0]
    >>> nice_ticks(1, 3, 6), nice_ticks(1, 3, 6, whole=True)
    ([1.0, 1.5, 2.0, 2.5, 3.0], [1.0, 2.0, 3.0])
    >>> nice_ticks(1, 12, 6, whole=True)
    [2.0, 4.0, 6.0, 8.0, 10.0, 12.0]
    """
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
        return [lo] if math.isfinite(lo) else []
    mag = 10.0 ** math.floor(math.log10((hi - lo) / max(1, most)))
    steps = (m * mag for m in (1.0, 2.0, 2.5, 5.0, 10.0, 20.0, 25.0, 50.0))
    for step in steps if not whole else (s for s in steps if s >= 1 and s == int(s)):
        first, last = math.ceil(lo / step - 1e-9), math.floor(hi / step + 1e-9)
        if last - first + 1 <= most:
            return [float(k * step) for k in range(first, last + 1)]
    return [lo, hi]


def tick_label(v: float, ticks: Sequence[float]) -> str:
    """``v`` with as many decimals as the tick spacing needs, thousands separated.

    >>> tick_label(-1500.0, [-1500.0, -1000.0]), tick_label(45.0, [45.0, 45.5, 46.0])
    ('-1,500', '45.0')
    >>> tick_label(2.5, [0.0, 2.5, 5.0])
    '2.5'
    """
    decimals = next((d for d in range(4) if all(abs(round(t, d) - t) < 1e-9 for t in ticks)), 3)
    return f"{v:,.{decimals}f}"


def robust_range(values: Sequence[float], keep: Sequence[float]) -> tuple[float, float, int]:
    """y range for the return axis: everything in ``keep`` (the moving average) and the
    1st..99.5th percentile of ``values``, padded; and how many values fall outside it.
    A few disastrous episodes (-2,282) then cannot squash the moving average flat."""
    v = np.asarray(values, dtype=float)
    lo_all, hi_all = float(v.min()), float(v.max())
    if len(v) >= 20:
        lo_all, hi_all = (float(x) for x in np.percentile(v, [1.0, 99.5]))
    if len(keep):
        lo_all, hi_all = min(lo_all, float(np.min(keep))), max(hi_all, float(np.max(keep)))
    if hi_all - lo_all < 1e-9:
        lo_all, hi_all = lo_all - 1.0, hi_all + 1.0
    pad = (hi_all - lo_all) * 0.06
    lo, hi = lo_all - pad, hi_all + pad
    outside = int(((v < lo) | (v > hi)).sum())
    return lo, hi, outside


@dataclass(frozen=True)
class _Axes:
    plot: pygame.Rect
    n: int
    lo: float
    hi: float

    def x(self, i: float) -> int:
        """Screen x of episode index ``i`` (0-based)."""
        return self.plot.x + round(i / max(1, self.n - 1) * (self.plot.w - 1))

    def y(self, v: float, lo: float | None = None, hi: float | None = None) -> int:
        lo = self.lo if lo is None else lo
        hi = self.hi if hi is None else hi
        f = (min(max(v, lo), hi) - lo) / (hi - lo)
        return self.plot.bottom - 1 - round(f * (self.plot.h - 1))


def draw_curve(
    surface: pygame.Surface,
    rect: pygame.Rect,
    returns: Sequence[float],
    run_start: int = 0,
    window: int = 25,
    at_goal: Sequence[bool] = (),
    st: Style = PLAIN,
) -> dict[str, object]:
    """The live learning curve: return per episode (light, per-pixel-column extremes) and
    its moving average (dark) on the left axis, the share of the last ``window`` episodes
    that ended at the goal (green) on the right axis, ticks on all three axes. The return
    axis covers the moving average and all but the worst 1 % of returns (a note counts
    the ones beyond it, drawn at the edge). A dashed orange line marks where this run
    began when earlier episodes came from the log."""
    clip = surface.get_clip()
    surface.set_clip(rect)
    inner = panel(surface, rect, "Learning curve", st)
    # room on the left for the return ticks and the x axis's caption beside them
    left = max(st.px(46), text("episode", st.small, DIM).get_width() + st.px(8))
    right = st.px(38)
    plot_w = inner.w - left - right
    legend_h = len(_legend_rows(plot_w, st, window)) * st.row_h + st.px(2)
    plot = pygame.Rect(
        inner.x + left, inner.y + st.px(6), plot_w, inner.h - legend_h - st.row_h - st.px(10)
    )
    pygame.draw.rect(surface, (255, 255, 255), plot)
    n = len(returns)
    out: dict[str, object] = {"panel": rect, "plot": plot}
    if n == 0:
        words = ["no finished episode yet"]
        if text(words[0], st.row, DIM).get_width() > plot.w - st.px(8):  # a narrow plot
            words = ["no finished", "episode yet"]
        for k, line in enumerate(words):
            msg = text(line, st.row, DIM)
            dy = round((k - (len(words) - 1) / 2) * st.row_h)
            surface.blit(msg, msg.get_rect(center=(plot.centerx, plot.centery + dy)))
        ax = _Axes(plot, 1, -1.0, 1.0)
    else:
        avg = moving_average(returns, window)
        lo, hi, outside = robust_range(returns, avg)
        ax = _Axes(plot, n, lo, hi)
        out["y_ticks"] = _grid(surface, ax, st)
        out["y_range"], out["off_scale"], out["y_of"] = (lo, hi), outside, ax.y
        _returns_band(surface, ax, np.asarray(returns, dtype=float))
        _polyline(surface, ax, avg, CURVE_AVERAGE, max(2, st.px(3)))
        if len(at_goal) == n:
            share = 100.0 * moving_average(np.asarray(at_goal, dtype=float), window)
            _polyline(surface, ax, share, CURVE_GOAL, max(2, st.px(2)), (0.0, 100.0))
            out["goal_rate"] = float(share[-1])
        _run_start(surface, ax, run_start)
        if outside:
            worst = float(np.min(returns))
            note = text(f"{outside} off scale (lowest {worst:,.0f})", st.small, DIM)
            surface.blit(note, (plot.right - note.get_width() - 4, plot.bottom - note.get_height()))
    pygame.draw.rect(surface, CURVE_AXES, plot, width=1)
    out["x_ticks"] = _axis_labels(surface, ax, st, n, bool(len(at_goal) == n and n))
    _legend(surface, plot, st, window)
    surface.set_clip(clip)
    return out


def _grid(surface: pygame.Surface, ax: _Axes, st: Style) -> list[float]:
    """Return-axis ticks: labels on the left, light grid lines across; returns the ticks."""
    ticks = nice_ticks(ax.lo, ax.hi, max(3, ax.plot.h // (2 * st.row_h) + 1))
    for v in ticks:
        yy = ax.y(v)
        pygame.draw.line(surface, CURVE_GRID, (ax.plot.x, yy), (ax.plot.right - 1, yy))
        lab = text(tick_label(v, ticks), st.small, DIM)
        surface.blit(lab, (ax.plot.x - lab.get_width() - st.px(4), yy - lab.get_height() // 2))
    if ax.lo < 0 < ax.hi:
        yy = ax.y(0.0)
        pygame.draw.line(surface, CURVE_ZERO, (ax.plot.x, yy), (ax.plot.right - 1, yy))
    return ticks


def _axis_labels(surface: pygame.Surface, ax: _Axes, st: Style, n: int, goal: bool) -> list[float]:
    """Episode ticks under the plot, goal-rate ticks (0, 50, 100 %) on the right; returns
    the episode ticks."""
    plot = ax.plot
    most = max(2, ax.plot.w // st.px(56))
    ticks = nice_ticks(1, max(1, n), most, whole=True) if n > 1 else []
    for e in ticks:
        xx = ax.x(e - 1)
        pygame.draw.line(surface, CURVE_AXES, (xx, plot.bottom), (xx, plot.bottom + st.px(3)))
        lab = text(f"{e:,.0f}", st.small, DIM)
        surface.blit(lab, (xx - lab.get_width() // 2, plot.bottom + st.px(3)))
    if goal:
        for pct in (0, 50, 100):
            yy = ax.y(pct, 0.0, 100.0)
            pygame.draw.line(surface, CURVE_GOAL, (plot.right, yy), (plot.right + st.px(3), yy))
            lab = text(f"{pct}%", st.small, CURVE_GOAL)
            surface.blit(lab, (plot.right + st.px(5), yy - lab.get_height() // 2))
    cap = text("episode", st.small, DIM)  # clear of the first tick's label, at plot.x
    surface.blit(cap, (plot.x - cap.get_width() - st.px(7), plot.bottom + st.px(3)))
    return ticks


def _legend_rows(plot_w: int, st: Style, window: int) -> list[list[tuple]]:
    """The legend's items ``(colour, width, label image, x offset)``, row by row as
    they fit under a plot ``plot_w`` wide (and into its right axis's margin)."""
    items = [  # a long label and the short one of a narrow plot
        (CURVE_RETURN, 2, "return per episode", "return"),
        (CURVE_AVERAGE, 3, f"moving average ({window})", f"average ({window})"),
        (CURVE_GOAL, 2, f"at the goal, % of last {window} (right axis)", "% at the goal (right)"),
    ]
    rows: list[list[tuple]] = [[]]
    x = 0
    for colour, width, label, short in items:
        img = text(label, st.small, INK)
        if st.px(34) + img.get_width() > plot_w + st.px(36):
            img = text(short, st.small, INK)
        w = st.px(22) + img.get_width() + st.px(12)
        if x + w > plot_w + st.px(36) and x > 0:
            rows.append([])
            x = 0
        rows[-1].append((colour, width, img, x))
        x += w
    return rows


def _legend(surface: pygame.Surface, plot: pygame.Rect, st: Style, window: int) -> None:
    y = plot.bottom + st.row_h + st.px(6)
    for row in _legend_rows(plot.w, st, window):
        for colour, width, img, dx in row:
            x, mid = plot.x + dx, y + img.get_height() // 2
            pygame.draw.line(surface, colour, (x, mid), (x + st.px(18), mid), st.px(width))
            surface.blit(img, (x + st.px(22), y))
        y += st.row_h


def _run_start(surface: pygame.Surface, ax: _Axes, run_start: int) -> None:
    if not 0 < run_start < ax.n:
        return
    sx = ax.x(run_start)
    for yy in range(ax.plot.y, ax.plot.bottom, 8):
        pygame.draw.line(surface, CURVE_RUN_START, (sx, yy), (sx, min(yy + 4, ax.plot.bottom)))


def _returns_band(surface: pygame.Surface, ax: _Axes, ys: np.ndarray) -> None:
    """Every return: a polyline, or (more episodes than pixel columns) each column's
    lowest-to-highest extent, so a single bad episode still shows as a spike."""
    n, w = len(ys), ax.plot.w
    if n <= w:
        _polyline(surface, ax, ys, CURVE_RETURN, 1)
        return
    cols = np.minimum((np.arange(n) * w) // n, w - 1)
    lo = np.full(w, np.inf)
    hi = np.full(w, -np.inf)
    np.minimum.at(lo, cols, ys)
    np.maximum.at(hi, cols, ys)
    for c in range(w):
        if math.isfinite(lo[c]):
            xx = ax.plot.x + c
            pygame.draw.line(surface, CURVE_RETURN, (xx, ax.y(lo[c])), (xx, ax.y(hi[c])))


def _polyline(
    surface: pygame.Surface,
    ax: _Axes,
    ys: Sequence[float],
    colour: Color,
    width: int,
    yrange: tuple[float, float] | None = None,
) -> None:
    lo, hi = yrange if yrange is not None else (ax.lo, ax.hi)
    n = len(ys)
    # At most one point per pixel column: drawing stays cheap for long runs.
    step = max(1, n // max(1, ax.plot.w))
    idx = list(range(0, n, step))
    if idx[-1] != n - 1:
        idx.append(n - 1)
    pts = [(ax.x(i), ax.y(float(ys[i]), lo, hi)) for i in idx]
    if len(pts) == 1:
        pygame.draw.circle(surface, colour, pts[0], max(2, width))
    else:
        pygame.draw.lines(surface, colour, False, pts, width)


# -- tags and help -----------------------------------------------------------------------------
def draw_tags(
    surface: pygame.Surface, topleft: tuple[int, int], tags: Sequence[str], st: Style = PLAIN
) -> dict[str, pygame.Rect]:
    """Badges in a row (AUTO-RESCUE, CLOCKLESS, RESCUED, ...); returns each one's rect."""
    x, y = topleft
    out: dict[str, pygame.Rect] = {}
    for tag in tags:
        label = text(tag, st.small, (255, 255, 255), bold=True)
        box = pygame.Rect(x, y, label.get_width() + st.px(12), label.get_height() + st.px(4))
        pygame.draw.rect(surface, tag_colour(tag), box, border_radius=4)
        surface.blit(label, label.get_rect(center=box.center))
        out[tag] = box
        x = box.right + st.px(6)
    return out


def draw_help(
    surface: pygame.Surface,
    rect: pygame.Rect,
    lines: Sequence[tuple[str, str]],
    st: Style = PLAIN,
) -> dict[str, pygame.Rect]:
    """The help overlay: ``(key, what it does)`` lines on a translucent sheet."""
    sheet = pygame.Surface(rect.size, pygame.SRCALPHA)
    sheet.fill((20, 24, 34, 242))
    surface.blit(sheet, rect.topleft)
    y = rect.y + st.px(12)
    surface.blit(text("Keyboard and mouse", st.px(22), (255, 255, 255), True), (rect.x + 16, y))
    y += st.px(34)
    half = (len(lines) + 1) // 2
    for i, (key, what) in enumerate(lines):
        col = rect.x + 16 + (i // half) * (rect.w // 2)
        row = y + (i % half) * st.px(21)
        surface.blit(text(key, st.px(15), (255, 220, 120), True), (col, row))
        surface.blit(text(what, st.px(15), (235, 235, 235)), (col + st.px(130), row))
    return {"help": rect}
