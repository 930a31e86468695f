"""Watch Koolio learn in the paper's simulator window (pygame-ce + pygame-gui).

``koolio-pm view`` opens a window in which the robot learns live with the machinery of
``koolio-pm train`` (same flags, Q-table file, backup and log; see
:mod:`koolio_pymunk.viewer.session`), or, with ``--greedy``, follows a learned policy
without changing the table.

Layout (default 1280 x 800): for a long arena an overview of the whole arena across the
top (click it to look there); below it the arena view (mouse wheel zooms, drag pans,
Follow keeps the robot in view); below that the HUD, Stats and live learning-curve
panels; on the right the control panel (pygame-gui buttons, check boxes and a slider).
Every control has a keyboard shortcut (F1 shows them).

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
from typing import Any

from ..errors import KoolioError

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


def _speed(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not SPEED_MIN <= v <= SPEED_MAX:
        raise argparse.ArgumentTypeError(f"must be in {SPEED_MIN:g}..{SPEED_MAX:g}, got {v:g}")
    return v


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The flags of ``train`` plus the window's own."""
    from ..cli import add_env_args, add_learning_files_args

    add_env_args(p)
    p.add_argument(
        "--episodes",
        type=int,
        default=None,
        help="episodes to run, then stop stepping (default: no limit)",
    )
    add_learning_files_args(p)
    p.add_argument(
        "--discard-unfinished",
        action="store_true",
        help="closing the window (or the end of --steps) discards the unfinished episode "
        "(Exit Without Save) instead of folding it in (Exit)",
    )
    p.add_argument(
        "--greedy",
        action="store_true",
        help="watch the learned policy (epsilon 0, no updates, nothing written)",
    )
    p.add_argument("--steps", type=int, default=None, help="run N steps, then Exit")
    p.add_argument(
        "--screenshot", default=None, metavar="FILE", help="PNG of the window at the end"
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
        type=_speed,
        default=10.0,
        help=f"clock speed, steps per second ({SPEED_MIN:g}..{SPEED_MAX:g}, default 10)",
    )
    p.add_argument(
        "--paused", action="store_true", help="open paused (press Begin); default: running"
    )


def _check_args(args: argparse.Namespace) -> tuple[int, Path] | None:
    if args.episodes is not None and args.episodes < 0:
        raise KoolioError(f"--episodes: must be >= 0, got {args.episodes}")
    if args.steps is not None and args.steps < 0:
        raise KoolioError(f"--steps: must be >= 0, got {args.steps}")
    if args.screenshot is not None and not args.screenshot.lower().endswith(".png"):
        raise KoolioError(f"--screenshot: {args.screenshot}: must end in .png")
    if args.screenshot is not None and Path(args.screenshot).is_dir():
        raise KoolioError(f"--screenshot: {args.screenshot}: is a folder, not a file")
    if args.screenshot_every is None:
        return None
    k_text, folder = args.screenshot_every
    try:
        k = int(k_text)
    except ValueError:
        raise KoolioError(f"--screenshot-every: K must be an integer, got {k_text!r}") from None
    if k < 1:
        raise KoolioError(f"--screenshot-every: K must be >= 1, got {k}")
    return k, _frames_folder(folder)


def _frames_folder(folder: str) -> Path:
    """``--screenshot-every``'s DIR: a new or empty-of-frames folder (frames of an earlier
    run are never overwritten)."""
    from ..files import check_path

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
    from ..env import KoolioEnv
    from .session import Session

    if _headless():
        if args.steps is None and args.episodes is None:
            raise KoolioError(
                "view: headless (SDL_VIDEODRIVER=dummy) needs --steps N or --episodes N"
            )
        if args.paused:
            raise KoolioError("--paused: a headless window cannot be resumed")
    env = KoolioEnv(arena=args.arena, config=args.config, goal=args.goal, world=args.world)
    session = Session(
        env,
        args.qtable,
        seed=args.seed,
        episodes=args.episodes,
        log=args.log,
        greedy=args.greedy,
    )
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
        )
        app.run()
        if args.screenshot:
            app.draw()
            app.save_screenshot(args.screenshot)
        app.finish()
        say = print
        say(
            f"view: {session.total_steps} steps, {session.stats.episodes} episodes finished "
            f"({session.stats.goals} at the goal)"
            + ("" if session.learn else ", greedy: table unchanged")
            + (f"; screenshot {args.screenshot}" if args.screenshot else "")
        )
    finally:
        if not session.closed:
            session.exit(save=not args.discard_unfinished)
        _quit_pygame()
    return 0


def _headless() -> bool:
    """True when SDL draws to no screen (``SDL_VIDEODRIVER=dummy`` or ``offscreen``)."""
    import pygame

    pygame.display.init()
    return pygame.display.get_driver() in ("dummy", "offscreen")


def _quit_pygame() -> None:
    import pygame

    pygame.display.quit()


# -- layout --------------------------------------------------------------------------------
@dataclass
class Layout:
    """Screen rectangles ``(x, y, w, h)`` of the window's parts."""

    overview: tuple[int, int, int, int] | None
    main: tuple[int, int, int, int]
    hud: tuple[int, int, int, int]
    stats: tuple[int, int, int, int]
    curve: tuple[int, int, int, int]
    controls: tuple[int, int, int, int]

    @classmethod
    def compute(cls, size: tuple[int, int], bounds: tuple[float, float, float, float]) -> Layout:
        """Arena views on the left (overview on top for a long arena), panels below,
        the control panel on the right."""
        w, h = size
        left = w - PANEL_W
        xmin, ymin, xmax, ymax = bounds
        aspect = (ymax - ymin) / max(1e-9, xmax - xmin)
        overview = None
        top = 0
        if aspect < 0.35:
            oh = min(max(70, round(left * aspect * 1.06) + 8), round(h * 0.22))
            overview = (0, 0, left, oh)
            top = oh
        bottom_h = min(330, max(290, round(h * 0.38)))
        main = (0, top, left, h - top - bottom_h)
        y = h - bottom_h
        hud_w = max(320, round(left * 0.36))
        stats_w = max(265, round(left * 0.28))
        hud = (0, y, hud_w, bottom_h)
        stats = (hud_w, y, stats_w, bottom_h)
        curve = (hud_w + stats_w, y, left - hud_w - stats_w, bottom_h)
        return cls(overview, main, hud, stats, curve, (left, 0, PANEL_W, h))


# -- the window -------------------------------------------------------------------------------
def speed_to_slider(speed: float) -> float:
    """Steps per second -> slider position 0..100 (logarithmic)."""
    return 100.0 * math.log(speed / SPEED_MIN) / math.log(SPEED_MAX / SPEED_MIN)


def slider_to_speed(pos: float) -> float:
    """Slider position 0..100 -> steps per second (logarithmic, rounded)."""
    v = SPEED_MIN * (SPEED_MAX / SPEED_MIN) ** (max(0.0, min(100.0, pos)) / 100.0)
    return float(round(v)) if v >= 10 else round(v, 1)


class ViewerApp:
    """The window: arena views, panels, controls, and the loop that steps the session.

    Tests drive it headless: post pygame events, call :meth:`frame`, read the flags and
    :attr:`screen`. Flags: :attr:`running`, :attr:`show_sensors`, :attr:`show_hud`,
    :attr:`show_stats`, :attr:`clockless`, :attr:`follow`, :attr:`help`, :attr:`speed`;
    Auto Rescue is the environment's own ``config.rescue.auto_rescue_toggle``.
    """

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
    ) -> None:
        import pygame
        import pygame_gui

        from .camera import Camera

        self.pg, self.gui = pygame, pygame_gui
        pygame.display.init()
        pygame.font.init()
        self.screen = pygame.display.set_mode(size)
        pygame.display.set_caption(
            "Koolio (pymunk): " + ("greedy" if not session.learn else "learning")
        )
        self.headless = _headless()
        self.session = session
        self.env = session.env
        self.size = size
        self.bounds = self.env.world_arena.bounds()
        self.layout = Layout.compute(size, self.bounds)
        self.overview_cam = Camera(self.layout.overview) if self.layout.overview else None
        if self.overview_cam is not None:
            self.overview_cam.fit(self.bounds, margin=0.02)
        self.camera = Camera(self.layout.main)
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
        self._curve_key: tuple[int, int] | None = None
        self._curve_surf: pygame.Surface | None = None
        self._curve_time = -math.inf
        self._clock = pygame.time.Clock()
        from .render import ArenaLayer

        self._layers = (ArenaLayer(), ArenaLayer())  # overview, arena view
        self.fit_view()
        self.manager = pygame_gui.UIManager(size)
        self._build_controls()
        self.drawn: dict[str, Any] = {}

    # -- controls --------------------------------------------------------------------------
    def _build_controls(self) -> None:
        pg, gui = self.pg, self.gui
        x, y, w, h = self.layout.controls
        self.panel = gui.elements.UIPanel(pg.Rect(x, y, w, h), manager=self.manager)
        bw = w - 24
        row = [8]

        def place(height: int = 30, gap: int = 6) -> pg.Rect:
            r = pg.Rect(10, row[0], bw, height)
            row[0] += height + gap
            return r

        def button(label: str, tip: str) -> Any:
            return gui.elements.UIButton(
                place(), label, manager=self.manager, container=self.panel, tool_tip_text=tip
            )

        def check(label: str, state: bool) -> Any:
            r = place(20, 7)
            return gui.elements.UICheckBox(
                pg.Rect(r.x, r.y, 20, 20),
                label,
                manager=self.manager,
                container=self.panel,
                initial_state=state,
            )

        gui.elements.UILabel(
            place(24, 4), "Koolio controls", manager=self.manager, container=self.panel
        )
        self.b_run = button(self._run_label(), "Begin / Pause learning [Space]")
        self.b_step = button("Step [N]", "one step while paused")
        self.b_rescue = button("Rescue [R]", "force Rescue_Robot now")
        row[0] += 4
        self.checks = {
            "show_sensors": check("Show Sensors [S]", self.show_sensors),
            "show_hud": check("Show HUD [H]", self.show_hud),
            "show_stats": check("Show Stats [T]", self.show_stats),
            "auto_rescue": check("Auto Rescue [A]", self.auto_rescue),
            "clockless": check("Clockless [C]", self.clockless),
            "follow": check("Follow robot [F]", self.follow),
        }
        row[0] += 2
        self.speed_label = gui.elements.UILabel(
            place(22, 2), self._speed_text(), manager=self.manager, container=self.panel
        )
        self.slider = gui.elements.UIHorizontalSlider(
            place(24, 10),
            speed_to_slider(self.speed),
            (0.0, 100.0),
            manager=self.manager,
            container=self.panel,
            click_increment=5,
        )
        third = (bw - 8) // 3
        r = place()
        self.b_zoom_out = gui.elements.UIButton(
            pg.Rect(r.x, r.y, third, r.h), "Zoom -", manager=self.manager, container=self.panel
        )
        self.b_zoom_in = gui.elements.UIButton(
            pg.Rect(r.x + third + 4, r.y, third, r.h),
            "Zoom +",
            manager=self.manager,
            container=self.panel,
        )
        self.b_fit = gui.elements.UIButton(
            pg.Rect(r.x + 2 * (third + 4), r.y, third, r.h),
            "Fit",
            manager=self.manager,
            container=self.panel,
        )
        self.b_help = button("Help [F1]", "keyboard and mouse shortcuts")
        row[0] += 6
        self.b_exit = button("Exit [Q]", "fold the unfinished episode into the Q-table, save, quit")
        self.b_exit_nosave = button(
            "Exit Without Save [Shift+Q]",
            "discard the unfinished episode: the Q-table file stays as after the last episode",
        )
        row[0] += 6
        s = self.session
        info = [
            "mode: " + ("learning" if s.learn else "greedy (table read-only)"),
            f"arena: {self.env.arena.name}  seed: {s.seed}",
            "table: " + _short(str(s.store.path) if s.store else "read-only", 21),
            "log: " + _short(str(s.log.path) if s.log.path else "-", 23),
        ]
        for line in info:
            if row[0] + 20 > h - 4:
                break
            gui.elements.UILabel(place(20, 0), line, manager=self.manager, container=self.panel)
        self.buttons: dict[Any, Callable[[], None]] = {
            self.b_run: self.toggle_running,
            self.b_step: self.single_step,
            self.b_rescue: self.rescue,
            self.b_zoom_in: lambda: self.zoom(1.25),
            self.b_zoom_out: lambda: self.zoom(0.8),
            self.b_fit: self.fit_view,
            self.b_help: self.toggle_help,
            self.b_exit: lambda: self.exit(save=True),
            self.b_exit_nosave: lambda: self.exit(save=False),
        }

    def _run_label(self) -> str:
        return "Pause [Space]" if self.running else "Begin [Space]"

    def _speed_text(self) -> str:
        return f"Clock speed: {self.speed:g} steps/s"

    @property
    def auto_rescue(self) -> bool:
        return bool(self.env.config.rescue.auto_rescue_toggle)

    def set_flag(self, name: str, value: bool) -> None:
        """Set a toggle (``show_sensors``, ``show_hud``, ``show_stats``, ``auto_rescue``,
        ``clockless``, ``follow``) and its check box."""
        if name == "auto_rescue":
            self.env.config.rescue.auto_rescue_toggle = bool(value)
        else:
            setattr(self, name, bool(value))
        box = self.checks[name]
        if box.get_state() != bool(value):
            box.set_state(bool(value))
        if name == "clockless":
            self._debt = 0.0

    def toggle(self, name: str) -> None:
        current = self.auto_rescue if name == "auto_rescue" else getattr(self, name)
        self.set_flag(name, not current)

    def toggle_running(self) -> None:
        self.running = not self.running
        self.b_run.set_text(self._run_label())
        self._debt = 0.0

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
        arena along that axis (a compact arena stays put, a long one scrolls)."""
        x, y, _ = self.env.world.pose(0)
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

    def _handle(self, ev: Any) -> None:
        pg, gui = self.pg, self.gui
        if ev.type == pg.QUIT:
            self.exit(save=not self.discard_on_close)
            return
        if self.manager.process_events(ev):
            return
        if ev.type == gui.UI_BUTTON_PRESSED:
            action = self.buttons.get(ev.ui_element)
            if action is not None:
                action()
            self.manager.set_focus_set(None)
        elif ev.type in (gui.UI_CHECK_BOX_CHECKED, gui.UI_CHECK_BOX_UNCHECKED):
            for name, box in self.checks.items():
                if box is ev.ui_element:
                    self.set_flag(name, ev.type == gui.UI_CHECK_BOX_CHECKED)
            self.manager.set_focus_set(None)
        elif ev.type == gui.UI_HORIZONTAL_SLIDER_MOVED and ev.ui_element is self.slider:
            self.speed = slider_to_speed(float(ev.value))
            self.speed_label.set_text(self._speed_text())
        elif ev.type == pg.KEYDOWN:
            self._key(ev)
        elif ev.type in (pg.MOUSEBUTTONDOWN, pg.MOUSEBUTTONUP, pg.MOUSEMOTION, pg.MOUSEWHEEL):
            self._mouse_event(ev)

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
        self._mouse = ev.pos
        if ev.type == pg.MOUSEBUTTONDOWN and ev.button == 1:
            if self._in(self.layout.main, ev.pos):
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
        if self.clockless:
            return int(self.env.config.episode.clockless_loop_count)
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
        from ..training import SafeInterrupt

        with SafeInterrupt() as guard:
            while not self.finished():
                guard.check()
                self.frame()

    def finish(self) -> None:
        """After the loop: leave as closing the window would (unless Exit already did)."""
        if not self.session.closed:
            self.session.exit(save=not self.discard_on_close)

    # -- drawing ---------------------------------------------------------------------------
    def tags(self) -> list[str]:
        """Tags shown over the arena view."""
        env, s = self.env, self.session
        out = []
        if self.auto_rescue:
            out.append("AUTO-RESCUE")
        if self.clockless:
            out.append("CLOCKLESS")
        if env.has_been_rescued:
            out.append("RESCUED")
        if not s.learn:
            out.append("GREEDY")
        if s.done:
            out.append("DONE")
        elif not self.running:
            out.append("PAUSED")
        return out

    def draw(self, full: bool = True) -> None:
        """Draw the whole window and flip it. The loop passes ``full=False``: the
        learning curve is then redrawn at most every :data:`CURVE_INTERVAL` seconds."""
        from . import hud
        from .render import draw_env

        pg, screen, lay = self.pg, self.screen, self.layout
        if self.follow:
            self._follow_robot()
        drawn: dict[str, Any] = {}
        if self.overview_cam is not None:
            draw_env(screen, self.overview_cam, self.env, lines=False, layer=self._layers[0])
            self._draw_view_box()
            pg.draw.rect(screen, hud.PANEL_EDGE, pg.Rect(lay.overview), width=1)
        draw_env(
            screen, self.camera, self.env, show_sensors=self.show_sensors, layer=self._layers[1]
        )
        pg.draw.rect(screen, hud.PANEL_EDGE, pg.Rect(lay.main), width=1)
        drawn["tags"] = hud.draw_tags(screen, (lay.main[0] + 8, lay.main[1] + 8), self.tags())
        if self.show_hud:
            drawn["hud"] = hud.draw_hud(screen, pg.Rect(lay.hud), self.env)
        else:
            hud.panel(screen, pg.Rect(lay.hud), "HUD hidden [H]")
        if self.show_stats:
            drawn["stats"] = hud.draw_stats(screen, pg.Rect(lay.stats), self.session, self._rate)
            screen.blit(self._curve(full), lay.curve[:2])
        else:
            hud.panel(screen, pg.Rect(lay.stats), "Stats hidden [T]")
            hud.panel(screen, pg.Rect(lay.curve), "")
        self.manager.draw_ui(screen)
        if self.help:
            x, y, w, _ = lay.main
            rect = pg.Rect(x + 20, y + 10, w - 40, lay.hud[1] + lay.hud[3] - y - 20)
            drawn["help"] = hud.draw_help(screen, rect, HELP_LINES)
        self.drawn = drawn
        self.frames_drawn += 1
        pg.display.flip()

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
        key = (len(st.returns), st.run_start)
        now = time.perf_counter()
        due = full or now - self._curve_time >= CURVE_INTERVAL
        if self._curve_surf is None or (key != self._curve_key and due):
            self._curve_time = now
            _, _, w, h = self.layout.curve
            surf = pg.Surface((w, h))
            hud.draw_curve(surf, pg.Rect(0, 0, w, h), st.returns, st.run_start, CURVE_WINDOW)
            self._curve_surf, self._curve_key = surf, key
        return self._curve_surf

    def save_screenshot(self, path: str | Path) -> Path:
        """Write the window as a PNG, atomically (temporary file, then rename)."""
        import io

        from ..files import atomic_write

        path = Path(path)
        buf = io.BytesIO()
        self.pg.image.save(self.screen, buf, "png")
        atomic_write(path, buf.getvalue())
        return path


def _short(path: str, limit: int = 30) -> str:
    return path if len(path) <= limit else "..." + path[-(limit - 3) :]
