"""Panels of the window: the HUD (encoded readings), Stats, the live learning curve, tags
and the help overlay (paper §5.4.5, §5.4.9).

Each ``draw_*`` function draws into a screen rectangle of ``surface`` (clipped to it) and
returns a dict naming the rectangles it drew that tests and the app may want (for
example the Bump flag). Text comes from :func:`koolio_pymunk.viewer.draw.text` (the
bundled font, cached).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pygame

from ..env import KoolioEnv
from ..plotting import moving_average
from ..sensors import CAMERA_LEVELS, COMPASS_LEVELS, SONAR_LEVELS, compass_code
from ..world import ACTION_NAMES
from .draw import text
from .session import Session

Color = tuple[int, int, int]

PANEL_BG: Color = (243, 244, 247)
PANEL_EDGE: Color = (150, 156, 168)
TITLE: Color = (30, 40, 70)
INK: Color = (25, 25, 25)
DIM: Color = (110, 110, 120)
BUMP_ON: Color = (255, 105, 180)
"""The Bump flag when set (the robot's Bump colour)."""
BUMP_OFF: Color = (222, 224, 230)
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
CURVE_AXES: Color = (90, 90, 100)
CURVE_RUN_START: Color = (200, 120, 0)
TAG_COLOURS: dict[str, Color] = {
    "AUTO-RESCUE": (40, 130, 70),
    "CLOCKLESS": (30, 90, 170),
    "RESCUED": (200, 60, 30),
    "PAUSED": (110, 110, 110),
    "GREEDY": (120, 60, 150),
    "DONE": (0, 0, 0),
    "FOLLOW": (70, 120, 140),
}

TITLE_SIZE = 20
ROW_SIZE = 17
ROW_H = 17


def panel(surface: pygame.Surface, rect: pygame.Rect, title: str) -> pygame.Rect:
    """A framed panel with a title; returns the content rectangle below the title."""
    pygame.draw.rect(surface, PANEL_BG, rect)
    pygame.draw.rect(surface, PANEL_EDGE, rect, width=1)
    surface.blit(text(title, TITLE_SIZE, TITLE), (rect.x + 8, rect.y + 5))
    return pygame.Rect(rect.x + 8, rect.y + 26, rect.w - 16, rect.h - 32)


def _fmt_distance(d: float, far: float) -> str:
    return "not seen" if d >= far else f"{d:6.1f} in"


def _deg(angle: float) -> str:
    return f"{angle:+.0f}°" if angle else "0°"


def hud_rows(env: KoolioEnv) -> list[tuple[str, str, str]]:
    """``(field name, encoded level, distance)`` of every state field, keyword order."""
    s, r = env.sensors, env.readings
    cam = s.cfg.camera.camera_sensors_deg
    son = s.cfg.sonar.sonar_sensors_deg
    rows: list[tuple[str, str, str]] = []
    codes = env.codes
    i = 0
    for c in range(s.n_camera):
        rows.append(
            (f"GoalCam{c} {_deg(cam[c])}", CAMERA_LEVELS[codes[i]], _fmt_distance(r.goal[c], s.far))
        )
        i += 1
    for c in range(s.n_camera):
        rows.append(
            (f"EoWCam{c} {_deg(cam[c])}", CAMERA_LEVELS[codes[i]], _fmt_distance(r.eow[c], s.far))
        )
        i += 1
    for g in s.groups:
        name = "Sonar" + "-".join(str(k) for k in g)
        angles = ",".join(_deg(son[k]) for k in g)
        d = float(np.mean(r.sonar[g]))
        rows.append((f"{name} {angles}", SONAR_LEVELS[codes[i]], _fmt_distance(d, s.far)))
        i += 1
    if s.cfg.compass.in_state:
        rows.append(("Compass", COMPASS_LEVELS[codes[i]], f"{r.compass:5.1f} /256"))
    return rows


def draw_hud(surface: pygame.Surface, rect: pygame.Rect, env: KoolioEnv) -> dict[str, pygame.Rect]:
    """Show HUD: every encoded reading by name, its level and distance, and the Bump flag."""
    clip = surface.get_clip()
    surface.set_clip(rect)
    inner = panel(surface, rect, "HUD: encoded readings")
    x0, y = inner.x, inner.y
    col_level = x0 + 150
    col_dist = col_level + 66
    for name, level, dist in hud_rows(env):
        surface.blit(text(name, ROW_SIZE, INK), (x0, y))
        cell = pygame.Rect(col_level - 3, y - 1, 60, ROW_H - 1)
        pygame.draw.rect(surface, LEVEL_COLOURS.get(level, PANEL_BG), cell)
        surface.blit(text(level, ROW_SIZE, INK), (col_level, y))
        surface.blit(text(dist, ROW_SIZE, DIM), (col_dist, y))
        y += ROW_H
    bump = env.sensors.bump(env.readings)
    flag = pygame.Rect(x0, y + 4, 90, 22)
    pygame.draw.rect(surface, BUMP_ON if bump else BUMP_OFF, flag)
    pygame.draw.rect(surface, PANEL_EDGE, flag, width=1)
    label = text("BUMP" if bump else "no bump", ROW_SIZE + 1, INK if bump else DIM)
    surface.blit(label, label.get_rect(center=flag.center))
    compass = env.readings.compass
    surface.blit(
        text(f"compass {COMPASS_LEVELS[compass_code(compass)]} ({compass:.0f}/256)", ROW_SIZE, DIM),
        (flag.right + 10, flag.y + 4),
    )
    y = flag.bottom + 6
    j = env.judgement
    if j is not None and env.last_action is not None:
        line = f"last: {ACTION_NAMES[env.last_action]} -> {j.event} ({j.reward:+g})"
    else:
        line = "last: (episode start)"
    surface.blit(text(line, ROW_SIZE, INK), (x0, y))
    surface.set_clip(clip)
    return {"panel": rect, "bump_flag": flag}


def _num(v: float, fmt: str = "{:.1f}") -> str:
    return "-" if isinstance(v, float) and math.isnan(v) else fmt.format(v)


def stats_rows(session: Session, steps_per_s: float) -> list[tuple[str, str]]:
    """``(label, value)`` lines of the Stats panel; ``("", heading)`` starts a section."""
    env, st = session.env, session.stats
    ep = session.episode + (0 if not session.episode_over else -1)
    rows = [
        ("", f"This episode (#{ep}, goal {env.goal_name})"),
        ("reward", f"{env.episode_reward:g}"),
        ("steps", f"{env.steps}"),
        ("bumps", f"{env.bumps}"),
        ("", "All episodes of this run"),
        ("episodes", f"{st.episodes}"),
        ("at the goal", f"{st.goals}" + ("" if not st.episodes else f" ({st.goal_rate:.0%})")),
        ("avg reward / ep", _num(st.mean(st.reward_sum))),
        ("avg steps / ep", _num(st.mean(st.steps_sum))),
        ("avg bumps / ep", _num(st.mean(st.bumps_sum))),
        ("", "Learner"),
        ("epsilon", f"{session.agent.epsilon:.3f}" + ("" if session.learn else " (greedy)")),
        ("table", f"{len(session.table)} states, {session.table.meta.get('episodes', 0)} eps"),
        ("speed", f"{steps_per_s:,.0f} steps/s"),
    ]
    return rows


def draw_stats(
    surface: pygame.Surface, rect: pygame.Rect, session: Session, steps_per_s: float = 0.0
) -> dict[str, pygame.Rect]:
    """Show Stats: this episode's reward, steps and bumps; totals and per-episode averages."""
    clip = surface.get_clip()
    surface.set_clip(rect)
    inner = panel(surface, rect, "Stats")
    y = inner.y
    for label, value in stats_rows(session, steps_per_s):
        if not label:
            y += 3
            surface.blit(text(value, ROW_SIZE, TITLE), (inner.x, y))
        else:
            surface.blit(text(label, ROW_SIZE, DIM), (inner.x + 8, y))
            surface.blit(text(value, ROW_SIZE, INK), (inner.x + 125, y))
        y += ROW_H
    surface.set_clip(clip)
    return {"panel": rect}


def _nice_range(lo: float, hi: float) -> tuple[float, float]:
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return -1.0, 1.0
    if hi - lo < 1e-9:
        return lo - 1.0, hi + 1.0
    pad = (hi - lo) * 0.05
    return lo - pad, hi + pad


def draw_curve(
    surface: pygame.Surface,
    rect: pygame.Rect,
    returns: Sequence[float],
    run_start: int = 0,
    window: int = 25,
) -> dict[str, pygame.Rect]:
    """The live learning curve: return per episode (light) and its moving average (dark)
    against the episode number, with the y range labelled and a legend. A dashed orange
    line marks where this run began when earlier episodes came from the log."""
    clip = surface.get_clip()
    surface.set_clip(rect)
    inner = panel(surface, rect, "Learning curve")
    narrow = inner.w < 360  # the legend takes two lines
    plot = pygame.Rect(inner.x + 44, inner.y + 4, inner.w - 50, inner.h - (54 if narrow else 40))
    pygame.draw.rect(surface, (255, 255, 255), plot)
    pygame.draw.rect(surface, CURVE_AXES, plot, width=1)
    n = len(returns)
    if n == 0:
        msg = text("no finished episode yet", 15, DIM)
        surface.blit(msg, msg.get_rect(center=plot.center))
        lo, hi = -1.0, 1.0
    else:
        avg = moving_average(returns, window).tolist()
        lo, hi = _nice_range(min(returns), max(returns))
        _polyline(surface, plot, returns, lo, hi, CURVE_RETURN, 1)
        _polyline(surface, plot, avg, lo, hi, CURVE_AVERAGE, 3)
        if 0 < run_start < n:
            sx = plot.x + round(run_start / max(1, n - 1) * (plot.w - 1))
            for yy in range(plot.y, plot.bottom, 8):
                pygame.draw.line(surface, CURVE_RUN_START, (sx, yy), (sx, min(yy + 4, plot.bottom)))
    for v, yy in ((hi, plot.y), (lo, plot.bottom - 12)):
        surface.blit(text(f"{v:.0f}", 15, DIM), (inner.x, yy))
    surface.blit(text("return", 15, DIM), (inner.x, plot.centery - 6))
    x_lab = text(f"episode (1..{n})", 15, DIM)
    surface.blit(x_lab, (plot.centerx - x_lab.get_width() // 2, plot.bottom + 3))
    ly = plot.bottom + 19
    pygame.draw.line(surface, CURVE_RETURN, (plot.x, ly + 6), (plot.x + 18, ly + 6), 2)
    surface.blit(text("return per episode", 15, INK), (plot.x + 22, ly))
    lx, ly = (plot.x, ly + 14) if narrow else (plot.x + 150, ly)
    pygame.draw.line(surface, CURVE_AVERAGE, (lx, ly + 6), (lx + 18, ly + 6), 3)
    surface.blit(text(f"moving average ({window})", 15, INK), (lx + 22, ly))
    surface.set_clip(clip)
    return {"panel": rect, "plot": plot}


def _polyline(
    surface: pygame.Surface,
    plot: pygame.Rect,
    ys: Sequence[float],
    lo: float,
    hi: float,
    colour: Color,
    width: int,
) -> None:
    n = len(ys)
    # At most one point per pixel column: drawing stays cheap for long runs.
    step = max(1, n // max(1, plot.w))
    idx = range(0, n, step)
    pts = [
        (
            plot.x + round(i / max(1, n - 1) * (plot.w - 1)),
            plot.bottom - 1 - round((ys[i] - lo) / (hi - lo) * (plot.h - 2)),
        )
        for i in idx
    ]
    if len(pts) == 1:
        pygame.draw.circle(surface, colour, pts[0], max(2, width))
    else:
        pygame.draw.lines(surface, colour, False, pts, width)


def draw_tags(
    surface: pygame.Surface, topleft: tuple[int, int], tags: Sequence[str]
) -> dict[str, pygame.Rect]:
    """Badges in a row (AUTO-RESCUE, CLOCKLESS, RESCUED, ...); returns each one's rect."""
    x, y = topleft
    out: dict[str, pygame.Rect] = {}
    for tag in tags:
        label = text(tag, ROW_SIZE, (255, 255, 255))
        box = pygame.Rect(x, y, label.get_width() + 12, label.get_height() + 6)
        pygame.draw.rect(surface, TAG_COLOURS.get(tag, (60, 60, 60)), box, border_radius=4)
        surface.blit(label, (x + 6, y + 3))
        out[tag] = box
        x = box.right + 6
    return out


def draw_help(
    surface: pygame.Surface, rect: pygame.Rect, lines: Sequence[tuple[str, str]]
) -> dict[str, pygame.Rect]:
    """The help overlay: ``(key, what it does)`` lines on a translucent sheet."""
    sheet = pygame.Surface(rect.size, pygame.SRCALPHA)
    sheet.fill((20, 24, 34, 242))
    surface.blit(sheet, rect.topleft)
    y = rect.y + 12
    surface.blit(text("Keyboard and mouse", 24, (255, 255, 255)), (rect.x + 16, y))
    y += 30
    half = (len(lines) + 1) // 2
    for i, (key, what) in enumerate(lines):
        col = rect.x + 16 + (i // half) * (rect.w // 2)
        row = y + (i % half) * 20
        surface.blit(text(key, 18, (255, 220, 120)), (col, row))
        surface.blit(text(what, 18, (235, 235, 235)), (col + 120, row))
    return {"help": rect}
