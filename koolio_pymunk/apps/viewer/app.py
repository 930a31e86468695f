"""Watch Koolio learn in the paper's simulator window (pygame-ce + pygame-gui).

``koolio-pm view`` opens a window in which the robot learns live with the machinery of
``koolio-pm train`` (same flags, Q-table file, backup and log; see
:mod:`koolio_pymunk.apps.viewer.session`), or, with ``--greedy``, follows a learned policy
without changing the table. A table that exists is watched (greedy) unless ``--learn``
asks to train it further: a window never changes a table nobody asked it to (the first
and the last line it prints say which table it learns into or watches, and what it
added).

Layout (default 1280 x 800; text and controls scale with the window): for a long arena
an overview of the whole arena across the top (click it to look there); below it the
arena view (mouse wheel zooms, drag pans, Follow keeps the robot in view); below that
the HUD, Stats and live learning-curve panels; on the right the control panel (pygame-gui
buttons, check boxes and a slider), or, with ``--panel-window`` or key P, the same panel
in a window of its own (the paper's future-work floating control panel). Every control
has a keyboard shortcut (F1 shows them).

Robots sharing the hallway (``--robots N --shared-arena``): N robots learn into one table
(or are watched, ``--greedy``) in one arena, stepping in tick order as ``train --robots N
--shared-arena`` does (:class:`~koolio_pymunk.apps.viewer.session.SharedSession`); each
is drawn in its colour with its number. One of them is *selected* (robot 0 at first;
Tab / Shift+Tab or a click on a robot selects another): its sensor lines are drawn, the
HUD and the Stats panel show it, Follow follows it. A step is then a tick: every robot
makes one step.

Pacing: with the clock, steps run at the slider's rate (steps per second). Clockless
runs ``episode.clockless_loop_count`` steps per tick back to back and redraws at most
:data:`DRAW_FPS` times a second and within :data:`DRAW_BUDGET` of the wall time
(``ViewerApp.draw_budget``), so drawing does not throttle learning. Under
``SDL_VIDEODRIVER=dummy`` nobody watches: there is no pacing at all (one tick per frame)
and the run must be bounded by ``--steps`` or ``--episodes``.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ...store.errors import KoolioError
from ...task.display import headless, init_display, no_display
from ..flags import check_png

if TYPE_CHECKING:
    from .hud import Style

#: The screen is redrawn at most this often (frames per second).
DRAW_FPS = 30
#: Clockless: redraws take at most this share of the wall time (fewer frames per second
#: when a redraw is slow or the machine is busy), so drawing never throttles learning.
DRAW_BUDGET = 0.05
#: Frame rate of the loop while paused or pacing with the clock.
IDLE_FPS = 60
#: Clock speed slider: steps per second from SPEED_MIN to SPEED_MAX (logarithmic).
SPEED_MIN, SPEED_MAX = 1.0, 1000.0
DEFAULT_SIZE = (1280, 800)
MIN_SIZE = (1080, 700)
#: Largest window (an 8K screen); a bigger one would only exhaust memory.
MAX_SIZE = (7680, 4320)
PANEL_W = 230
#: Colour of the hint lines (what the control under the pointer does).
HINT = "#ffd870"
NO_HINT = "(point at a control: what it does)"
CURVE_WINDOW = 25
#: While stepping, the learning curve is redrawn at most this often (seconds).
CURVE_INTERVAL = 0.5

HELP_LINES: list[tuple[str, str]] = [
    ("Space", "Begin / Pause"),
    ("N", "one step (while paused)"),
    ("R", "Rescue (forced)"),
    ("S", "Show Sensors"),
    ("H", "Show HUD"),
    ("T", "Show Stats"),
    ("A", "Auto Rescue"),
    ("C", "Clockless"),
    ("F", "Follow the robot"),
    ("Tab / Shift+Tab", "next / previous robot (shared arena)"),
    ("click a robot", "select it (shared arena)"),
    ("P", "control panel: own window / docked"),
    ("] / [", "clock faster / slower"),
    ("+ / -", "zoom in / out"),
    ("0 / Home", "fit the arena"),
    ("Left / Right", "scroll the arena"),
    ("wheel, drag", "zoom, scroll"),
    ("Q", "Exit (fold + save)"),
    ("Shift+Q", "Exit Without Save"),
    ("click overview", "look there"),
    ("F1 / ?", "this help"),
    ("Esc", "close the help"),
]


# -- command line ---------------------------------------------------------------------------
def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, got {text!r}") from None
    if w < MIN_SIZE[0] or h < MIN_SIZE[1]:
        raise argparse.ArgumentTypeError(
            f"window {w}x{h} is smaller than {MIN_SIZE[0]}x{MIN_SIZE[1]}"
        )
    if w > MAX_SIZE[0] or h > MAX_SIZE[1]:
        raise argparse.ArgumentTypeError(
            f"window {w}x{h} is larger than {MAX_SIZE[0]}x{MAX_SIZE[1]}"
        )
    return (w, h)


#: Most steps of ``--steps`` (and the largest ``--screenshot-every`` K).
MAX_STEPS = 10**12


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The flags of ``train`` plus the window's own."""
    from ..cli import add_env_args, add_learning_files_args, add_robots_args, add_tables_arg
    from ..flags import MAX_EPISODES, file_name, float_type, int_type

    add_env_args(p)
    p.add_argument(
        "--episodes",
        type=int_type(0, MAX_EPISODES),
        default=None,
        help="episodes this window runs, then stops stepping (learning: added to those the "
        "table holds; default: no limit)",
    )
    add_learning_files_args(p)
    add_robots_args(
        p,
        "robots in the window, learning into one table or watched (default 1); "
        "several need --shared-arena (robots each in their own copy of the arena are "
        "train's parallel data collection, nothing to watch in one window): select one with "
        "Tab / Shift+Tab or a click, a step is then a tick (every robot one step)",
    )
    add_tables_arg(p)
    p.add_argument(
        "--discard-unfinished",
        action="store_true",
        help="closing the window (or the end of --steps) discards the unfinished episode "
        "(Exit Without Save) instead of folding it in (Exit)",
    )
    p.add_argument(
        "--greedy",
        action="store_true",
        help="watch the learned policy (epsilon 0, no updates, nothing written); the "
        "default when the table exists",
    )
    p.add_argument(
        "--learn",
        action="store_true",
        help="learn into the table even when it exists (default: learn only into a new "
        "table, watch an existing one)",
    )
    p.add_argument(
        "--steps", type=int_type(0, MAX_STEPS), default=None, help="run N steps, then Exit"
    )
    p.add_argument(
        "--screenshot",
        type=file_name,
        default=None,
        metavar="FILE",
        help="PNG of the window at the end",
    )
    p.add_argument(
        "--screenshot-every",
        nargs=2,
        default=None,
        metavar=("K", "DIR"),
        help="a PNG of the window every K steps: DIR/frame_00001.png, ...",
    )
    p.add_argument(
        "--size",
        type=_size,
        default=DEFAULT_SIZE,
        help=f"window size WxH (default {DEFAULT_SIZE[0]}x{DEFAULT_SIZE[1]})",
    )
    p.add_argument("--clockless", action="store_true", help="start in clockless mode")
    p.add_argument(
        "--speed",
        type=float_type(SPEED_MIN, SPEED_MAX),
        default=10.0,
        help=f"clock speed, steps per second ({SPEED_MIN:g}..{SPEED_MAX:g}, default 10)",
    )
    p.add_argument(
        "--paused", action="store_true", help="open paused (press Begin); default: running"
    )
    p.add_argument(
        "--panel-window",
        action="store_true",
        help="the control panel in a window of its own (the paper's floating control panel; "
        "key P floats or docks it)",
    )


def _check_args(args: argparse.Namespace) -> tuple[int, Path] | None:
    if args.robots > 1 and not args.shared_arena:
        raise KoolioError(
            f"view --robots {args.robots}: needs --shared-arena (a window shows the robots "
            "of one arena; robots each in their own copy are train's)"
        )
    if args.greedy and args.learn:
        raise KoolioError("--greedy, --learn: choose one (watch the table, or learn into it)")
    if args.screenshot is not None:
        check_png(args.screenshot, "--screenshot")
    if args.screenshot_every is None:
        return None
    k_text, folder = args.screenshot_every
    try:
        k = int(k_text)
    except ValueError:
        raise KoolioError(f"--screenshot-every: K must be an integer, got {k_text!r}") from None
    if k < 1:
        raise KoolioError(f"--screenshot-every: K must be >= 1, got {k}")
    if k > MAX_STEPS:
        raise KoolioError(f"--screenshot-every: K must be <= {MAX_STEPS:,}, got {k:,}")
    return k, _frames_folder(folder)


def _frames_folder(folder: str) -> Path:
    """``--screenshot-every``'s DIR: a new or empty-of-frames folder (frames of an earlier
    run are never overwritten)."""
    from ...store.files import check_path

    path = check_path(folder, "--screenshot-every")
    if path.exists() and not path.is_dir():
        raise KoolioError(f"--screenshot-every: {folder}: is a file, not a folder")
    if path.is_dir():
        old = sorted(path.glob("frame_*.png"))
        if old:
            raise KoolioError(
                f"--screenshot-every: {folder}: holds frames of an earlier run "
                f"({old[0].name}, ...): give a new or empty folder"
            )
    return path


def run(args: argparse.Namespace) -> int:
    """``koolio-pm view``."""
    every = _check_args(args)
    from ...store.interrupts import deferred
    from ...store.qtable import QTableStore
    from ...store.run_files import RunFiles
    from ...store.run_identity import RunIdentity
    from ...task.env import KoolioEnv
    from ..cli import announce_compile, check_shared_arena
    from .session import Session, SharedSession, watched_table

    if _headless():
        if args.steps is None and args.episodes is None:
            raise KoolioError(f"view: headless ({no_display()}) needs --steps N or --episodes N")
        if args.paused:
            raise KoolioError("--paused: a headless window cannot be resumed")
    env = KoolioEnv(arena=args.arena, config=args.config, goal=args.goal, world=args.world)
    check_shared_arena(args, env)
    store = QTableStore(args.qtable)
    existed = store.exists()
    greedy = args.greedy or (existed and not args.learn)
    if greedy:  # what can be refused is refused before anything is compiled or written
        # and, as eval, a table of no episodes or of another world is said so
        watched_table(env, args.qtable, warn=False, robots=args.robots)
    else:  # a table that holds each robot's own rows is learned as train --tables each
        run = RunIdentity.of_robots(env, args.robots, store.peek(), each=args.tables == "each")
        RunFiles.check(run, store, args.log)
    announce_compile(env)
    shared = {"robots": args.robots, "each": args.tables == "each"} if args.shared_arena else {}
    session = (SharedSession if shared else Session)(
        env,
        args.qtable,
        seed=args.seed,
        episodes=args.episodes,
        log=args.log,
        greedy=greedy,
        **shared,
    )
    print(opening_line(session, existed, asked=args.greedy))
    try:
        app = ViewerApp(
            session,
            size=args.size,
            clockless=args.clockless,
            speed=args.speed,
            running=not args.paused,
            discard_on_close=args.discard_unfinished,
            max_steps=args.steps,
            screenshot_every=every,
            panel_window=args.panel_window,
            config_name=args.config,
        )
        app.run()
        if args.screenshot:
            app.draw()
            app.save_screenshot(args.screenshot)
        with deferred():  # the last save and its log row: never cut by Ctrl-C
            app.finish()
        shot = f"; screenshot {args.screenshot}" if args.screenshot else ""
        print(closing_line(session) + shot)
    finally:
        try:
            with deferred():  # after Ctrl-C too: a second one never cuts the save short
                if not session.closed:
                    session.exit(save=not args.discard_unfinished)
        finally:
            _quit_pygame()
    return 0


def opening_line(session: Any, existed: bool, asked: bool = True) -> str:
    """``view``'s first line: the table it learns into (new, or how many episodes it
    holds) or watches; ``existed``: the table was there before; ``asked``: ``--greedy``
    was given (else say how to learn)."""
    from ...store.keyword import table_robots
    from ..cli import count

    table = session.table_path
    if not session.learn:
        how = "" if asked else "; --learn trains it further"
        return (
            f"view: {robots_words(session)}watching {table} "
            f"({count(session.table.meta.get('episodes', 0), 'episode')}; "
            f"greedy, nothing is written){how}"
        )
    log = f" (log {session.log_path})" if session.log_path else " (no log)"
    held = f"which holds {count(session.first, 'episode')}" if existed else "a new table"
    own = table_robots(session.table.layout) > 0
    rows = " (each robot its own rows)" if own else ""
    return f"view: {robots_words(session)}learning into {table}{rows}, {held}{log}"


def robots_words(session: Any) -> str:
    """``"4 robots sharing the arena, "`` (one robot: nothing)."""
    n = getattr(session, "n_robots", 1)
    return f"{n} robots sharing the arena, " if n > 1 else ""


def closing_line(session: Any) -> str:
    """``view``'s last line: steps, episodes, and what the table gained (or that it is
    unchanged)."""
    from .hud import plural

    n = getattr(session, "n_robots", 1)
    steps = plural(session.total_steps, "step" if n == 1 else "tick")
    line = (
        f"view: {steps}{f' of {n} robots' if n > 1 else ''}, "
        f"{plural(session.stats.episodes, 'episode')} finished "
        f"({session.stats.goals} at the goal)"
    )
    if not session.learn:
        return f"{line}; greedy: {session.table_path} unchanged"
    total = int(session.table.meta.get("episodes", 0))
    folded = any(r.outcome == "interrupted" for r in session.results)
    added = f"{plural(session.stats.episodes, 'episode')} added ({total} in all)"
    if folded:
        whose = "episode's" if n == 1 else "episodes'"
        added += f", and the unfinished {whose} updates (Exit)"
    return f"{line}; {session.table_path}: {added}"


def _headless() -> bool:
    """True when SDL draws to no screen (``SDL_VIDEODRIVER=dummy`` or ``offscreen``);
    the display started without libwayland's ``XDG_RUNTIME_DIR`` line
    (:mod:`koolio_pymunk.task.display`)."""
    return headless()


def _quit_pygame() -> None:
    """Close the display and let the window go.

    pygame_gui keeps the first ``UIManager`` made in a module global (its default
    manager), and the window's manager holds the window (its panel follows the app's
    pointer), so the window, its env, the world and the world's pymunk spaces would
    otherwise stay alive until the interpreter's very last garbage collection. That one
    runs after cffi has stopped calling back into Python: pymunk's finalizer of a space
    then cannot list the space's bodies, frees the space, and a body's finalizer removes
    the body from the freed space: a segfault at exit (``view --episodes 0``, which draws
    nothing, made the collection order that crashes). Without the global the window is
    collected with everything else while the interpreter still runs."""
    import pygame
    from pygame_gui.core.utility import set_default_manager

    set_default_manager(None)
    pygame.display.quit()


# -- layout --------------------------------------------------------------------------------
@dataclass
class Layout:
    """Screen rectangles ``(x, y, w, h)`` of the window's parts (``controls`` is None when
    the control panel floats in a window of its own)."""

    overview: tuple[int, int, int, int] | None
    main: tuple[int, int, int, int]
    hud: tuple[int, int, int, int]
    stats: tuple[int, int, int, int]
    curve: tuple[int, int, int, int]
    controls: tuple[int, int, int, int] | None

    @classmethod
    def compute(
        cls,
        size: tuple[int, int],
        bounds: tuple[float, float, float, float],
        st: Style | None = None,
        *,
        docked: bool = True,
        hud_rows: int = 12,
    ) -> Layout:
        """Arena views on the left (overview on top for a long arena), panels below, the
        control panel on the right (unless it floats: then the views take the width).
        ``st`` scales the panels; ``hud_rows`` is the number of state fields."""
        from .hud import PLAIN, hud_height

        st = st or PLAIN
        w, h = size
        panel_w = st.px(PANEL_W) if docked else 0
        left = w - panel_w
        xmin, ymin, xmax, ymax = bounds
        aspect = (ymax - ymin) / max(1e-9, xmax - xmin)
        overview = None
        top = 0
        if aspect < 0.35:
            oh = min(max(st.px(70), round(left * aspect * 1.06) + 8), round(h * 0.22))
            overview = (0, 0, left, oh)
            top = oh
        hud_h = hud_height(hud_rows, st)
        bottom_h = min(round(h * 0.5), max(hud_h, st.px(290)))  # a long state: up to half
        main = (0, top, left, h - top - bottom_h)
        y = h - bottom_h
        hud_w = max(st.px(372), round(left * 0.34))
        stats_w = max(st.px(250), round(left * 0.25))
        hud = (0, y, hud_w, bottom_h)
        stats = (hud_w, y, stats_w, bottom_h)
        curve = (hud_w + stats_w, y, left - hud_w - stats_w, bottom_h)
        controls = (left, 0, panel_w, h) if docked else None
        return cls(overview, main, hud, stats, curve, controls)


# -- the window -------------------------------------------------------------------------------
def speed_to_slider(speed: float) -> float:
    """Steps per second -> slider position 0..100 (logarithmic)."""
    return 100.0 * math.log(speed / SPEED_MIN) / math.log(SPEED_MAX / SPEED_MIN)


def slider_to_speed(pos: float) -> float:
    """Slider position 0..100 -> steps per second (logarithmic, rounded)."""
    v = SPEED_MIN * (SPEED_MAX / SPEED_MIN) ** (max(0.0, min(100.0, pos)) / 100.0)
    return float(round(v)) if v >= 10 else round(v, 1)


def wrap(s: str, width: int, measure: Callable[[str], int]) -> list[str]:
    """``s`` broken at spaces into lines at most ``width`` wide (``measure`` gives a width).

    >>> wrap("one two three", 9, len)
    ['one two', 'three']
    """
    lines: list[str] = []
    cur = ""
    for word in s.split():
        trial = f"{cur} {word}" if cur else word
        if cur and measure(trial) > width:
            lines.append(cur)
            cur = word
        else:
            cur = trial
    return [*lines, cur] if cur else lines


class ViewerApp:
    """The window: arena views, panels, controls, and the loop that steps the session.

    Tests drive it headless: post pygame events, call :meth:`frame`, read the flags and
    :attr:`screen`. Flags: :attr:`running`, :attr:`show_sensors`, :attr:`show_hud`,
    :attr:`show_stats`, :attr:`clockless`, :attr:`follow`, :attr:`help`, :attr:`speed`;
    Auto Rescue is the environment's own ``config.rescue.auto_rescue_toggle``.

    The control panel sits on the right of the window, or (``panel_window=True``, key P,
    the paper's future-work "floating control panel") in a window of its own,
    :attr:`panel_window` (a ``pygame.Window``); closing that window docks it again.

    Robots sharing an arena (a :class:`~koolio_pymunk.apps.viewer.session.SharedSession`):
    :attr:`env` is the selected robot's (:meth:`select`, Tab / Shift+Tab, a click on a
    robot in the arena view), which the views, the HUD, Stats and Follow show.
    """

    @property
    def env(self) -> Any:
        """The selected robot's env (the only one's, with one robot)."""
        return self.session.env

    @property
    def envs(self) -> list[Any]:
        """Every robot's env."""
        return list(getattr(self.session, "envs", [self.session.env]))

    @property
    def n_robots(self) -> int:
        return int(getattr(self.session, "n_robots", 1))

    def select(self, robot: int) -> None:
        """Show robot ``robot`` (its sensor lines, HUD, Stats; Follow follows it)."""
        self.session.select(robot % self.n_robots)
        if self.follow:
            self._follow_robot()

    def select_next(self, step: int = 1) -> None:
        """The next robot (``step`` -1: the previous one), round the robots."""
        if self.n_robots > 1:
            self.select((self.session.selected + step) % self.n_robots)

    def robot_at(self, pos: tuple[int, int]) -> int | None:
        """The robot drawn under the screen point ``pos`` of the arena view (the nearest
        one within a little more than its radius; None: none there, or one robot)."""
        if self.n_robots < 2:
            return None
        world = self.env.world
        x, y = self.camera.to_world(pos)
        reach = self.env.config.robot.radius * 1.25
        best, best_d = None, reach
        for k in range(self.n_robots):
            if not world.present[k]:
                continue
            px, py, _ = world.pose(k)
            d = math.hypot(px - x, py - y)
            if d <= best_d:
                best, best_d = k, d
        return best

    def __init__(
        self,
        session: Any,
        *,
        size: tuple[int, int] = DEFAULT_SIZE,
        clockless: bool = False,
        speed: float = 10.0,
        running: bool = True,
        discard_on_close: bool = False,
        max_steps: int | None = None,
        screenshot_every: tuple[int, Path] | None = None,
        draw_fps: float = DRAW_FPS,
        panel_window: bool = False,
        config_name: str | None = None,
    ) -> None:
        import pygame
        import pygame_gui

        from ...task.viewport import Camera
        from . import hud

        self.pg, self.gui = pygame, pygame_gui
        init_display()
        pygame.font.init()
        self.screen = pygame.display.set_mode(size)
        pygame.display.set_caption(
            "Koolio (pymunk): " + ("greedy" if not session.learn else "learning")
        )
        self.headless = _headless()
        self.session = session
        self.size = size
        self.style = hud.style(size)
        self.config_name = config_name or "default"
        self.bounds = self.env.world_arena.bounds()
        self.camera = Camera((0, 0, 1, 1))
        self.overview_cam: Any = None
        self.running = running
        self.show_sensors = True
        self.show_hud = True
        self.show_stats = True
        self.clockless = clockless
        self.follow = True
        self.help = False
        self.speed = speed
        self.discard_on_close = discard_on_close
        self.max_steps = max_steps
        self.shot_every, self.shot_dir = screenshot_every or (0, None)
        self.shots = 0
        self.draw_interval = 1.0 / draw_fps
        self.draw_budget = DRAW_BUDGET
        self.quit = False
        self.steps_done = 0
        self.frames_drawn = 0
        self._last_draw = -math.inf
        self._last_draw_done = time.perf_counter()
        self._draw_cost = 0.0
        self._last_time = time.perf_counter()
        self._debt = 0.0
        self._rate = 0.0
        self._rate_t: float | None = None
        self._rate_full = False
        self._rate_steps = 0
        self._drag: tuple[int, int] | None = None
        self._mouse: tuple[int, int] | None = None
        self._panel_mouse: tuple[int, int] | None = None
        self._curve_key: tuple[int, int, int] | None = None
        self._curve_surf: pygame.Surface | None = None
        self._curve_time = -math.inf
        self._clock = pygame.time.Clock()
        self.drawn_curve: dict[str, Any] = {}
        from ...task.render import ArenaLayer

        self._layers = (ArenaLayer(), ArenaLayer())  # overview, arena view
        self.panel_window: Any = None
        self.drawn: dict[str, Any] = {}
        self._arrange(panel_window)
        self.fit_view()

    # -- layout and the control panel ------------------------------------------------------
    def _arrange(self, floating: bool) -> None:
        """Lay the window out with the control panel docked or floating, and build it."""
        from ...task.viewport import Camera

        rows = len(self.env.layout.bits)  # a HUD row per state field, memory included
        self.layout = Layout.compute(
            self.size, self.bounds, self.style, docked=not floating, hud_rows=rows
        )
        self.camera.viewport = self.layout.main
        self.overview_cam = Camera(self.layout.overview) if self.layout.overview else None
        if self.overview_cam is not None:
            self.overview_cam.fit(self.bounds, margin=0.02)
        if floating and self.panel_window is None:
            self.panel_window = self._open_panel_window()
        elif not floating and self.panel_window is not None:
            self.panel_window.destroy()
            self.panel_window = None
        self._panel_mouse = None
        self._build_controls()

    def _open_panel_window(self) -> Any:
        pg = self.pg
        w, h = self.style.px(PANEL_W), self.size[1]
        position: Any = pg.WINDOWPOS_UNDEFINED
        try:
            dw, dh = pg.display.get_desktop_sizes()[0]
            position = (max(0, dw - w - 8), max(0, (dh - h) // 2))
        except (pg.error, IndexError):
            pass
        return pg.Window("Koolio controls", (w, h), position=position)

    @property
    def panel_surface(self) -> Any:
        """The surface the control panel is drawn on: the window's or its own window's."""
        if self.panel_window is not None:
            return self.panel_window.get_surface()
        return self.screen

    def set_panel_window(self, floating: bool) -> None:
        """Float the control panel in a window of its own, or dock it in the window."""
        if floating != (self.panel_window is not None):
            self._arrange(floating)
            self._curve_surf = None
            if self.follow:
                self._follow_robot()

    def _theme(self) -> dict[str, Any]:
        """pygame-gui theme: Noto Sans (the panels' face) at the window's scale, left-aligned
        labels, light text on the dark panel."""
        st = self.style
        font = {"name": "noto_sans", "size": str(st.px(14))}
        light = {"normal_text": "#e8ebf0"}
        left = {"text_horiz_alignment": "left"}
        return {
            "defaults": {"colours": light},
            "button": {"font": font},
            "label": {"font": font, "colours": light, "misc": left},
            "#title": {"font": {**font, "size": str(st.px(16)), "bold": "1"}},
            "#centre": {"misc": {"text_horiz_alignment": "center"}},
            "#hint": {"font": {**font, "size": str(st.px(13))}, "colours": {"normal_text": HINT}},
            "#info": {"font": {**font, "size": str(st.px(13))}},
        }

    def _panel_mouse_position(self) -> tuple[int, int]:
        """Where the pointer is over the control panel's surface ((-1, -1): not over it)."""
        pos = self._panel_mouse if self.panel_window is not None else self._mouse
        return pos if pos is not None else (-1, -1)

    def _build_controls(self) -> None:
        gui = self.gui
        app = self

        class PanelManager(gui.UIManager):  # type: ignore[misc, name-defined]
            """Hover follows the pointer of the panel's own window (there may be two)."""

            def _update_mouse_position(self) -> None:
                self.mouse_position = app._panel_mouse_position()

        surface = self.panel_surface
        self.manager = PanelManager(surface.get_size(), self._theme())
        w, h = surface.get_size()
        x = 0 if self.panel_window is not None else w - self.style.px(PANEL_W)
        self.panel = gui.elements.UIPanel(
            self.pg.Rect(x, 0, self.style.px(PANEL_W), h), manager=self.manager
        )
        self.hints: dict[Any, str] = {}
        _ControlsBuilder(self).build()
        self._hint_shown: Any = None

    def _run_label(self) -> str:
        return "Pause [Space]" if self.running else "Begin [Space]"

    def _panel_label(self) -> str:
        return "Dock panel [P]" if self.panel_window is not None else "Float panel [P]"

    def _speed_text(self) -> str:
        if self.clockless:
            return "Clock: off (clockless)"
        return f"Clock speed: {self.speed:g} steps/s"

    def _sync_speed_control(self) -> None:
        self.speed_label.set_text(self._speed_text())
        if self.clockless:
            self.slider.disable()
        else:
            self.slider.enable()

    def info_lines(self) -> list[str]:
        """The run's set-up, at the bottom of the control panel."""
        s = self.session
        table = str(s.table_path)
        return [
            "mode: " + ("learning" if s.learn else "greedy (read-only table)"),
            f"arena: {self.env.arena.name}   seed: {s.seed}",
            *([f"robots: {self.n_robots}, sharing the arena"] if self.n_robots > 1 else []),
            f"world: {self.env.world_name}",  # a line of its own: a long config path
            *realism_lines(self.env.config),  # shortened to the panel's width hides nothing
            f"config: {self.config_name}",
            "table: " + table,
            "log: " + (str(s.log_path) if s.log_path else "none"),
        ]

    def _update_hint(self) -> None:
        """The hovered control's description in the hint lines (instead of tool tips that
        would cover the controls below it)."""
        hovered = next((e for e in self.hints if getattr(e, "hovered", False)), None)
        if hovered is self._hint_shown:
            return
        self._hint_shown = hovered
        words = self.hints.get(hovered, NO_HINT)
        from . import hud

        f = hud.font(self.style.px(13))
        lines = wrap(words, self.hint_labels[0].rect.w - 4, lambda t: f.size(t)[0])
        for i, label in enumerate(self.hint_labels):
            label.set_text(lines[i] if i < len(lines) else "")

    @property
    def hint(self) -> str:
        """The hint lines' text, joined."""
        return " ".join(t for t in (lab.text for lab in self.hint_labels) if t)

    @property
    def auto_rescue(self) -> bool:
        return bool(self.env.config.rescue.auto_rescue_toggle)

    def set_flag(self, name: str, value: bool) -> None:
        """Set a toggle (``show_sensors``, ``show_hud``, ``show_stats``, ``auto_rescue``,
        ``clockless``, ``follow``) and its check box."""
        if name == "auto_rescue":
            for env in self.envs:
                env.config.rescue.auto_rescue_toggle = bool(value)
        else:
            setattr(self, name, bool(value))
        box = self.checks[name]
        if box.get_state() != bool(value):
            box.set_state(bool(value))
        if name == "clockless":
            self._debt = 0.0
            self._sync_speed_control()

    def toggle(self, name: str) -> None:
        current = self.auto_rescue if name == "auto_rescue" else getattr(self, name)
        self.set_flag(name, not current)

    def toggle_running(self) -> None:
        self.running = not self.running
        self.b_run.set_text(self._run_label())
        self._debt = 0.0

    def toggle_panel(self) -> None:
        self.set_panel_window(self.panel_window is None)

    def single_step(self) -> None:
        if not self.running:
            self._do_steps(1)

    def rescue(self) -> None:
        self.session.rescue()

    def toggle_help(self) -> None:
        self.help = not self.help

    def set_speed(self, speed: float) -> None:
        self.speed = max(SPEED_MIN, min(SPEED_MAX, speed))
        self.speed_label.set_text(self._speed_text())
        self.slider.set_current_value(speed_to_slider(self.speed), warn=False)

    def exit(self, save: bool) -> None:
        """Exit (fold + save) or Exit Without Save, then close the loop."""
        self.session.exit(save=save)
        self.quit = True

    # -- view ------------------------------------------------------------------------------
    def fit_view(self) -> None:
        """Zoom so the arena's height fills the view; follow the robot when it is long."""
        cam = self.camera
        _, ymin, _, ymax = self.bounds
        vh = cam.viewport[3]
        cam.fit(self.bounds, margin=0.04)
        if self.overview_cam is not None:  # long arena: fill the height, follow the robot
            cam.zoom = vh / ((ymax - ymin) * 1.05)
            self._follow_robot()

    def zoom(self, factor: float, at: tuple[float, float] | None = None) -> None:
        x, y, w, h = self.camera.viewport
        self.camera.zoom_at(at or (x + w / 2, y + h / 2), factor)

    def pan(self, dx: float, dy: float) -> None:
        self.camera.pan_pixels(dx, dy)
        if self.follow:
            self.set_flag("follow", False)

    def _follow_robot(self) -> None:
        """Centre on the robot along each axis the arena does not fit in; else centre the
        arena along that axis (a compact arena stays put, a long one scrolls). A robot of a
        shared arena that is outside it (between episodes) leaves the view where it is."""
        env = self.env
        if env.share is not None and not env.world.present[env.robot]:
            return
        x, y, _ = env.world.pose(env.robot)
        xmin, ymin, xmax, ymax = self.bounds
        _, _, vw, vh = self.camera.viewport
        zoom = self.camera.zoom
        cx = (xmin + xmax) / 2.0 if vw / zoom >= (xmax - xmin) * 1.02 else x
        cy = (ymin + ymax) / 2.0 if vh / zoom >= (ymax - ymin) * 1.02 else y
        self.camera.follow((cx, cy))

    # -- events ----------------------------------------------------------------------------
    def handle_events(self) -> None:
        """Process the event queue, including the events the widgets post in reply."""
        pg = self.pg
        for _ in range(4):
            events = pg.event.get()
            if not events:
                break
            for ev in events:
                self._handle(ev)
                if self.quit:
                    return

    def _in_panel_window(self, ev: Any) -> bool:
        win = getattr(ev, "window", None)
        return self.panel_window is not None and win is self.panel_window

    def _handle(self, ev: Any) -> None:
        pg = self.pg
        if ev.type == pg.QUIT:
            self.exit(save=not self.discard_on_close)
            return
        in_panel = self._in_panel_window(ev)
        if self._window_event(ev, in_panel):
            return
        mouse = ev.type in (pg.MOUSEBUTTONDOWN, pg.MOUSEBUTTONUP, pg.MOUSEMOTION, pg.MOUSEWHEEL)
        if ev.type == pg.MOUSEMOTION:
            if in_panel:
                self._panel_mouse = ev.pos
            else:
                self._mouse = ev.pos
        to_panel = self.panel_window is None or in_panel or not mouse
        if to_panel and self.manager.process_events(ev):
            return
        if self._widget_event(ev):
            return
        if ev.type == pg.KEYDOWN:
            self._key(ev)
        elif mouse and not in_panel:
            self._mouse_event(ev)

    def _window_event(self, ev: Any, in_panel: bool) -> bool:
        """Closing a window (the main one: Exit; the panel's: dock it), the pointer
        leaving the panel's window. True when ``ev`` was one of these."""
        pg = self.pg
        if ev.type == pg.WINDOWCLOSE:
            if in_panel:
                self.set_panel_window(False)
            else:
                self.exit(save=not self.discard_on_close)
            return True
        if ev.type == pg.WINDOWLEAVE and in_panel:
            self._panel_mouse = None
            return True
        return False

    def _widget_event(self, ev: Any) -> bool:
        gui = self.gui
        if ev.type == gui.UI_BUTTON_PRESSED:
            action = self.buttons.get(ev.ui_element)
            self.manager.set_focus_set(None)
            if action is not None:
                action()
        elif ev.type in (gui.UI_CHECK_BOX_CHECKED, gui.UI_CHECK_BOX_UNCHECKED):
            for name, box in self.checks.items():
                if box is ev.ui_element:
                    self.set_flag(name, ev.type == gui.UI_CHECK_BOX_CHECKED)
            self.manager.set_focus_set(None)
        elif ev.type == gui.UI_HORIZONTAL_SLIDER_MOVED and ev.ui_element is self.slider:
            self.speed = slider_to_speed(float(ev.value))
            self.speed_label.set_text(self._speed_text())
        else:
            return False
        return True

    def _key(self, ev: Any) -> None:
        pg = self.pg
        k, shift = ev.key, bool(ev.mod & pg.KMOD_SHIFT)
        uni = getattr(ev, "unicode", "")
        simple: dict[int, Callable[[], None]] = {
            pg.K_SPACE: self.toggle_running,
            pg.K_n: self.single_step,
            pg.K_r: self.rescue,
            pg.K_s: lambda: self.toggle("show_sensors"),
            pg.K_h: lambda: self.toggle("show_hud"),
            pg.K_t: lambda: self.toggle("show_stats"),
            pg.K_a: lambda: self.toggle("auto_rescue"),
            pg.K_c: lambda: self.toggle("clockless"),
            pg.K_f: lambda: self.toggle("follow"),
            pg.K_p: self.toggle_panel,
            pg.K_RIGHTBRACKET: lambda: self.set_speed(self.speed * 1.5),
            pg.K_LEFTBRACKET: lambda: self.set_speed(self.speed / 1.5),
            pg.K_EQUALS: lambda: self.zoom(1.25),
            pg.K_PLUS: lambda: self.zoom(1.25),
            pg.K_KP_PLUS: lambda: self.zoom(1.25),
            pg.K_MINUS: lambda: self.zoom(0.8),
            pg.K_KP_MINUS: lambda: self.zoom(0.8),
            pg.K_0: self.fit_view,
            pg.K_HOME: self.fit_view,
            pg.K_LEFT: lambda: self.pan(self.camera.viewport[2] * 0.25, 0),
            pg.K_RIGHT: lambda: self.pan(-self.camera.viewport[2] * 0.25, 0),
            pg.K_F1: self.toggle_help,
        }
        if k == pg.K_q:
            self.exit(save=not shift)
        elif k == pg.K_TAB:
            self.select_next(-1 if shift else 1)
        elif k == pg.K_ESCAPE:
            self.help = False
        elif uni == "?" or (k == pg.K_SLASH and shift):
            self.toggle_help()
        elif k in simple:
            simple[k]()

    def _in(self, rect: tuple[int, int, int, int] | None, pos: tuple[int, int]) -> bool:
        return rect is not None and self.pg.Rect(rect).collidepoint(pos)

    def _mouse_event(self, ev: Any) -> None:
        pg = self.pg
        if ev.type == pg.MOUSEWHEEL:
            pos = self._mouse or pg.mouse.get_pos()
            if self._in(self.layout.main, pos):
                self.zoom(1.15**ev.y, pos)
            return
        if ev.type == pg.MOUSEBUTTONDOWN and ev.button == 1:
            if self._in(self.layout.main, ev.pos):
                hit = self.robot_at(ev.pos)
                if hit is not None:
                    self.select(hit)
                self._drag = ev.pos
            elif self.overview_cam is not None and self._in(self.layout.overview, ev.pos):
                wx, _ = self.overview_cam.to_world(ev.pos)
                self.set_flag("follow", False)
                self.camera.center = (wx, self.camera.center[1])
        elif ev.type == pg.MOUSEBUTTONUP and ev.button == 1:
            self._drag = None
        elif ev.type == pg.MOUSEMOTION and self._drag is not None:
            self.pan(ev.pos[0] - self._drag[0], ev.pos[1] - self._drag[1])
            self._drag = ev.pos

    # -- stepping --------------------------------------------------------------------------
    def _steps_due(self, now: float) -> int:
        elapsed = now - self._last_time
        self._last_time = now
        if not self.running or self.session.done:
            return 0
        if self.clockless:  # several robots: ticks of about as many robot steps
            count = int(self.env.config.episode.clockless_loop_count)
            return max(1, -(-count // self.n_robots))
        if self.headless:
            return 1
        self._debt = min(self._debt + elapsed * self.speed, max(1.0, self.speed * 0.25))
        n = int(self._debt)
        self._debt -= n
        return n

    def _update_rate(self, now: float) -> None:
        """Steps per second over half-second windows (over the run so far, at first)."""
        if self._rate_t is None:  # the first frame's steps have no duration: skip them
            self._rate_t, self._rate_steps = now, 0
        elif now - self._rate_t >= 0.5:
            self._rate = self._rate_steps / (now - self._rate_t)
            self._rate_t, self._rate_steps, self._rate_full = now, 0, True
        elif not self._rate_full and now > self._rate_t:
            self._rate = self._rate_steps / (now - self._rate_t)

    def _do_steps(self, n: int) -> int:
        done = self.session.run(n)
        self.steps_done += done
        self._rate_steps += done
        return done

    def frame(self) -> None:
        """One tick: events, steps, maybe a redraw and a screenshot, pacing."""
        self.handle_events()
        if self.quit:
            return
        now = time.perf_counter()
        n = self._steps_due(now)
        if self.max_steps is not None:
            n = min(n, self.max_steps - self.steps_done)
        if self.shot_every:
            n = min(n, self.shot_every - self.steps_done % self.shot_every)
        done = self._do_steps(n) if n > 0 else 0
        shot = bool(self.shot_every and done and self.steps_done % self.shot_every == 0)
        self._update_rate(now)
        interval = self.draw_interval
        if self.clockless and self.running:
            interval = max(interval, self._draw_cost / self.draw_budget)
        if shot or now - self._last_draw >= interval:
            self._last_draw = now
            self.manager.update(min(0.1, now - self._last_draw_done))
            self._update_hint()
            self.draw(full=shot)
            self._last_draw_done = time.perf_counter()
            self._draw_cost = self._last_draw_done - now
        if shot:
            self.shots += 1
            assert self.shot_dir is not None
            self.save_screenshot(self.shot_dir / f"frame_{self.shots:05d}.png")
        if not self.headless and not (self.clockless and self.running and not self.session.done):
            self._clock.tick(IDLE_FPS)

    def finished(self) -> bool:
        """The loop should stop: Exit pressed, ``--steps`` reached, or (headless) done."""
        if self.quit:
            return True
        if self.max_steps is not None and self.steps_done >= self.max_steps:
            return True
        return self.headless and self.session.done

    def run(self) -> None:
        """The window loop; returns when :meth:`finished`. Ctrl-C in the terminal takes
        effect between frames (never between a save and its log row): the unfinished
        episode is then folded in, or discarded with ``--discard-unfinished``."""
        from ...store.interrupts import SafeInterrupt

        with SafeInterrupt() as guard:
            while not self.finished():
                guard.check()
                self.frame()

    def finish(self) -> None:
        """After the loop: leave as closing the window would (unless Exit already did)."""
        if not self.session.closed:
            self.session.exit(save=not self.discard_on_close)
        if self.panel_window is not None:
            self.panel_window.destroy()
            self.panel_window = None

    # -- drawing ---------------------------------------------------------------------------
    def tags(self) -> list[str]:
        """Tags shown over the arena view."""
        env, s = self.env, self.session
        out = []
        if self.n_robots > 1:
            out.append(f"ROBOT {s.selected}")
            if env.waiting:
                out.append("WAITING")
        if self.auto_rescue:
            out.append("AUTO-RESCUE")
        if self.clockless:
            out.append("CLOCKLESS")
        if env.has_been_rescued:
            out.append("RESCUED")
        if not s.learn:
            out.append("GREEDY")
        if env.world_name != "ideal":
            out.append(f"WORLD: {Path(env.world_name).stem.upper()}")
        if s.done:
            out.append("DONE")
        elif not self.running:
            out.append("PAUSED")
        return out

    def draw(self, full: bool = True) -> None:
        """Draw the whole window (and the panel's own window) and flip. The loop passes
        ``full=False``: the learning curve is then redrawn at most every
        :data:`CURVE_INTERVAL` seconds."""
        from . import hud

        pg, screen, lay, st = self.pg, self.screen, self.layout, self.style
        if self.follow:
            self._follow_robot()
        self._draw_views()
        drawn: dict[str, Any] = {}
        tag_at = (lay.main[0] + st.pad, lay.main[1] + st.pad)
        drawn["tags"] = hud.draw_tags(screen, tag_at, self.tags(), st)
        if self.show_hud:
            title = "HUD: encoded readings"
            if self.n_robots > 1:
                title = f"HUD: robot {self.session.selected}'s encoded readings"
            drawn["hud"] = hud.draw_hud(screen, pg.Rect(lay.hud), self.env, st, title=title)
        else:
            hud.panel(screen, pg.Rect(lay.hud), "HUD hidden [H]", st)
        if self.show_stats:
            drawn["stats"] = hud.draw_stats(
                screen, pg.Rect(lay.stats), self.session, self._rate, st
            )
            screen.blit(self._curve(full), lay.curve[:2])
        else:
            hud.panel(screen, pg.Rect(lay.stats), "Stats hidden [T]", st)
            hud.panel(screen, pg.Rect(lay.curve), "", st)
        if self.panel_window is None:
            self.manager.draw_ui(screen)
        if self.help:
            x, y, w, _ = lay.main
            rect = pg.Rect(x + 20, y + 10, w - 40, lay.hud[1] + lay.hud[3] - y - 20)
            drawn["help"] = hud.draw_help(screen, rect, HELP_LINES, st)
        self.drawn = drawn
        self.frames_drawn += 1
        pg.display.flip()
        if self.panel_window is not None:
            self.manager.draw_ui(self.panel_surface)
            self.panel_window.flip()

    def _draw_views(self) -> None:
        """The overview (long arenas) and the arena view, framed. Without Show Sensors
        the robot is the paper's plain red in both."""
        from ...task.render import draw_env
        from . import hud

        pg, screen, lay = self.pg, self.screen, self.layout
        if self.overview_cam is not None:
            draw_env(
                screen,
                self.overview_cam,
                self.env,
                show_sensors=self.show_sensors,
                lines=False,
                layer=self._layers[0],
                label_size=self.style.px(16),
            )
            self._draw_view_box()
            pg.draw.rect(screen, hud.PANEL_EDGE, pg.Rect(lay.overview), width=1)
        draw_env(
            screen,
            self.camera,
            self.env,
            show_sensors=self.show_sensors,
            layer=self._layers[1],
            label_size=self.style.px(16),
        )
        pg.draw.rect(screen, hud.PANEL_EDGE, pg.Rect(lay.main), width=1)

    def _draw_view_box(self) -> None:
        """The main view's extent as a rectangle on the overview."""
        pg, cam, ov = self.pg, self.camera, self.overview_cam
        assert ov is not None
        x, y, w, h = cam.viewport
        a = ov.to_screen(cam.to_world((x, y)))
        b = ov.to_screen(cam.to_world((x + w, y + h)))
        box = pg.Rect(min(a[0], b[0]), min(a[1], b[1]), abs(b[0] - a[0]), abs(b[1] - a[1]))
        clip = self.screen.get_clip()
        self.screen.set_clip(pg.Rect(ov.viewport))
        pg.draw.rect(self.screen, (0, 120, 200), box, width=2)
        self.screen.set_clip(clip)

    def _curve(self, full: bool = True) -> Any:
        """The learning-curve panel, redrawn only when a new episode has finished."""
        from . import hud

        pg = self.pg
        st = self.session.stats
        _, _, w, h = self.layout.curve
        key = (len(st.returns), st.run_start, w)
        now = time.perf_counter()
        due = full or now - self._curve_time >= CURVE_INTERVAL
        if self._curve_surf is None or (key != self._curve_key and due):
            self._curve_time = now
            surf = pg.Surface((w, h))
            self.drawn_curve = hud.draw_curve(
                surf,
                pg.Rect(0, 0, w, h),
                st.returns,
                st.run_start,
                CURVE_WINDOW,
                at_goal=st.at_goal,
                st=self.style,
            )
            self._curve_surf, self._curve_key = surf, key
        return self._curve_surf

    def panel_image(self) -> Any:
        """The control panel as drawn (a copy of its surface)."""
        x, y, w, h = self.panel.rect
        return self.panel_surface.subsurface(self.pg.Rect(x, y, w, h)).copy()

    def save_screenshot(self, path: str | Path) -> Path:
        """Write the window as a PNG, atomically (temporary file, then rename). With the
        control panel in its own window, the picture shows that window on the right."""
        import io

        from ...store.files import atomic_write

        path = Path(path)
        image = self.screen
        if self.panel_window is not None:
            panel = self.panel_image()
            w, h = self.size
            image = self.pg.Surface((w + 8 + panel.get_width(), max(h, panel.get_height())))
            image.fill((255, 255, 255))
            image.blit(self.screen, (0, 0))
            image.blit(panel, (w + 8, 0))
        buf = io.BytesIO()
        self.pg.image.save(image, buf, "png")
        atomic_write(path, buf.getvalue())
        return path


class _ControlsBuilder:
    """Builds the control panel's widgets (pygame-gui) top to bottom, sized by the style."""

    def __init__(self, app: ViewerApp) -> None:
        self.app, self.pg, self.gui = app, app.pg, app.gui
        st = app.style
        self.st = st
        self.w = app.panel.rect.w - st.px(24)
        self.y = st.px(8)

    def place(self, height: float = 30, gap: float = 6) -> Any:
        st = self.st
        r = self.pg.Rect(st.px(10), self.y, self.w, st.px(height))
        self.y += st.px(height) + st.px(gap)
        return r

    def _kw(self) -> dict[str, Any]:
        return {"manager": self.app.manager, "container": self.app.panel}

    def button(self, label: str, hint: str) -> Any:
        b = self.gui.elements.UIButton(self.place(), label, **self._kw())
        self.app.hints[b] = hint
        return b

    def check(self, label: str, state: bool, hint: str) -> Any:
        r = self.place(20, 7)
        box = self.gui.elements.UICheckBox(
            self.pg.Rect(r.x, r.y, r.h, r.h), label, initial_state=state, **self._kw()
        )
        self.app.hints[box] = hint
        return box

    def label(self, text: str, height: float = 20, gap: float = 0, object_id: str = "") -> Any:
        return self.gui.elements.UILabel(
            self.place(height, gap), text, object_id=object_id or None, **self._kw()
        )

    def build(self) -> None:
        app = self.app
        self.label("Koolio controls", 24, 4, "#title")
        app.b_run = self.button(app._run_label(), "Begin or pause learning.")
        app.b_step = self.button("Step [N]", "One step while paused.")
        app.b_rescue = self.button(
            "Rescue [R]", "Force Rescue_Robot now: random reverses, a random spin."
        )
        self.y += self.st.px(4)
        self._checks()
        self.y += self.st.px(2)
        app.speed_label = self.label(app._speed_text(), 22, 2, "#centre")
        app.slider = self.gui.elements.UIHorizontalSlider(
            self.place(24, 10),
            speed_to_slider(app.speed),
            (0.0, 100.0),
            click_increment=5,
            **self._kw(),
        )
        app.hints[app.slider] = "Clock speed: steps per second, 1 to 1000 ([ and ])."
        app._sync_speed_control()
        self._zoom_row()
        app.b_help = self.button("Help [F1]", "The keyboard and mouse shortcuts.")
        app.b_panel = self.button(
            app._panel_label(),
            "Put these controls in a window of their own, or back in the main window.",
        )
        self.y += self.st.px(6)
        app.b_exit = self.button(
            "Exit [Q]", "Fold the unfinished episode into the Q-table, save it, quit."
        )
        app.b_exit_nosave = self.button(
            "Exit Without Save [Shift+Q]",
            "Discard the unfinished episode: the Q-table file stays as after the last episode.",
        )
        self._hint_and_info()
        app.buttons = {
            app.b_run: app.toggle_running,
            app.b_step: app.single_step,
            app.b_rescue: app.rescue,
            app.b_zoom_in: lambda: app.zoom(1.25),
            app.b_zoom_out: lambda: app.zoom(0.8),
            app.b_fit: app.fit_view,
            app.b_help: app.toggle_help,
            app.b_panel: app.toggle_panel,
            app.b_exit: lambda: app.exit(save=True),
            app.b_exit_nosave: lambda: app.exit(save=False),
        }

    def _checks(self) -> None:
        app = self.app
        rows = [
            ("show_sensors", "Show Sensors [S]", "Sensor lines and the robot's state colours."),
            ("show_hud", "Show HUD [H]", "The encoded readings of the state."),
            ("show_stats", "Show Stats [T]", "Totals and the learning curve."),
            ("auto_rescue", "Auto Rescue [A]", "Rescue a robot stuck bumping (the paper's rule)."),
            ("clockless", "Clockless [C]", "Steps back to back, as fast as they go."),
            ("follow", "Follow robot [F]", "Keep the robot in the arena view."),
        ]
        app.checks = {}
        for name, label, hint in rows:
            state = app.auto_rescue if name == "auto_rescue" else getattr(app, name)
            app.checks[name] = self.check(label, state, hint)

    def _zoom_row(self) -> None:
        app, st = self.app, self.st
        third = (self.w - st.px(8)) // 3
        r = self.place()
        made = []
        for i, (label, hint) in enumerate(
            (
                ("Zoom -", "Zoom out [-]."),
                ("Zoom +", "Zoom in [+]."),
                ("Fit", "Fit the arena [0]."),
            ),
        ):
            rect = self.pg.Rect(r.x + i * (third + st.px(4)), r.y, third, r.h)
            b = self.gui.elements.UIButton(rect, label, **self._kw())
            app.hints[b] = hint
            made.append(b)
        app.b_zoom_out, app.b_zoom_in, app.b_fit = made

    def _hint_and_info(self) -> None:
        app, st = self.app, self.st
        self.y += st.px(4)
        app.hint_labels = [self.label("", 18, 0, "#hint") for _ in range(3)]
        app.hint_labels[0].set_text(NO_HINT)
        self.y += st.px(6)
        h = app.panel.rect.h
        for line in app.info_lines():
            if self.y + st.px(19) > h - 4:
                break
            text = _short_to(line, self.w, app.style)
            self.label(text, 19, 0, "#info")


def realism_lines(cfg: Any) -> list[str]:
    """The realism models a world turns on, and whether it randomizes them: the control
    panel's lines under ``world:`` (none in the ideal world; the models and their values
    are in ``docs/reality-gap.md``).

    >>> from koolio_pymunk.store.config import load_config
    >>> realism_lines(load_config(world="koolio-real-dr"))
    ['realism: sonar, camera, motion', 'randomized: 11 parameters per episode']
    >>> realism_lines(load_config())
    []
    """
    from ...store.realism_config import camera_on, motion_on, sonar_on

    r = cfg.realism
    groups = [
        name
        for name, on in (("sonar", sonar_on(r)), ("camera", camera_on(r)), ("motion", motion_on(r)))
        if on
    ]
    out = ["realism: " + ", ".join(groups)] if groups else []
    if r.randomize:
        out.append(f"randomized: {len(r.randomize)} parameters per episode")
    return out


def _short_to(line: str, width: int, st: Any) -> str:
    """``line`` shortened in its middle with ``...`` to fit ``width`` pixels."""
    from . import hud

    f = hud.font(st.px(13))
    if f.size(line)[0] <= width:
        return line
    head, _, tail = line.partition(": ")
    while tail and f.size(f"{head}: ...{tail}")[0] > width:
        tail = tail[1:]
    return f"{head}: ...{tail}"
