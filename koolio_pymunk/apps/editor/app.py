"""The editor window: pygame events -> :class:`~koolio_pymunk.apps.editor.model.EditorModel`.

Start it with ``koolio-pm edit [FILE] [--new] [--doors TABLE] [--script FILE]
[--screenshot PNG] [--size WxH] [--grid INCHES]`` (the flags are in
:mod:`~koolio_pymunk.apps.editor.command`). The keys are listed in the side panel and in
``docs/editor.md``.

Everything the user does arrives as a pygame event and goes through
:meth:`EditorApp.handle`, whether it comes from the keyboard and mouse or was posted by a
scripted session (:mod:`~koolio_pymunk.apps.editor.script`), so scripts exercise the real
editor. Headless with ``SDL_VIDEODRIVER=dummy``.
"""

from __future__ import annotations

import io
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path as FilePath

import pygame
import pygame_gui

from ...store.config import Config
from ...store.errors import KoolioError
from ...store.files import atomic_write, check_path
from ...task.display import init_display
from ...world.arena import Point
from ..flags import check_png
from . import dialogs, items, limits, view
from .camera import EditorCamera
from .dialogs import Prompt
from .drive import TestDrive
from .items import EditError, Path
from .model import EditorModel, SaveResult

PANEL_WIDTH = 340
STATUS_HEIGHT = 92
PICK_PIXELS = 8
"""How close (screen pixels) the cursor must be to pick a point or an edge."""
DRAG_PIXELS = 3
"""A press moves its item only after the cursor has moved this far."""
SNAP_FRACTIONS = (1.0, 0.5, 0.25, 1.0 / 24.0, None)
"""Snap steps cycled by X, as fractions of a tile (1/24 of a 24 in tile = 1 in; None off)."""
TOOL_KEYS = {
    pygame.K_v: "select",
    pygame.K_w: "wall",
    pygame.K_i: "insert",
    pygame.K_o: "obstacle",
    pygame.K_g: "goal",
    pygame.K_e: "marker",
    pygame.K_z: "zone",
    pygame.K_s: "start",
}
TOOLS = tuple(TOOL_KEYS.values())
DRIVE_KEYS = {
    pygame.K_UP: "forward",
    pygame.K_DOWN: "reverse",
    pygame.K_LEFT: "left",
    pygame.K_RIGHT: "right",
    pygame.K_SPACE: "stop",
}


@dataclass
class Drag:
    """A mouse drag in progress."""

    kind: str  # "point", "translate" or "pan"
    path: Path | None
    start_screen: tuple[int, int]
    start_world: Point
    moved: bool = False
    last_screen: tuple[int, int] = field(default=(0, 0))


class EditorApp:
    """The arena editor's window, state and event handling."""

    def __init__(
        self,
        model: EditorModel,
        size: tuple[int, int] = (1280, 720),
        config: Config | None = None,
    ) -> None:
        init_display()  # without libwayland's XDG_RUNTIME_DIR line (task/display.py)
        pygame.font.init()
        pygame.display.set_caption("koolio arena editor")
        self.screen = pygame.display.set_mode(size)
        self.model = model
        self.config = config
        w, h = size
        canvas_w = max(200, w - PANEL_WIDTH)
        self.camera = EditorCamera(viewport=(0, 0, canvas_w, max(100, h - STATUS_HEIGHT)))
        self.panel_rect = (canvas_w, 0, w - canvas_w, h)
        self.status_rect = (0, h - STATUS_HEIGHT, canvas_w, STATUS_HEIGHT)
        self.tool = "select"
        self.selection: Path | None = None
        self.hover: Path | None = None
        self.hover_edge: tuple[Path, int, Point] | None = None
        self.building: Path | None = None
        self.cursor: Point | None = None
        self.mouse_screen: tuple[int, int] | None = None
        self.drag: Drag | None = None
        self.prompt: Prompt | None = None
        self.drive: TestDrive | None = None
        self.show_lengths = True
        self.message = ""
        self.message_is_error = False
        self.goal_rows: list[tuple[pygame.Rect, str]] = []
        self.running = True
        self._prompt_opened = False
        self.drawn_labels: dict[str, list[pygame.Rect]] = {}
        """Rectangles of the edge-length labels and goal names of the last frame."""
        self.ui = pygame_gui.UIManager(size)
        """pygame-gui: the questions (text, yes / no, files) are its windows."""
        self.fit()

    # =====================================================================================
    # Loop
    # =====================================================================================
    def run(self) -> None:
        """The interactive loop (until quit)."""
        clock = pygame.time.Clock()
        while self.running:
            self.process(pygame.event.get())
            self.ui.update(clock.get_time() / 1000.0)
            self.render()
            pygame.display.flip()
            clock.tick(60)

    def process(self, events: Iterable[pygame.event.Event]) -> None:
        """Handle one batch of events (one frame)."""
        self._prompt_opened = False
        for event in events:
            self.handle(event)

    def pump(self) -> None:
        """Process the queued (e.g. posted) events, and the events the widgets post in
        reply, then redraw: one frame, no waiting."""
        for _ in range(5):
            events = pygame.event.get()
            if not events:
                break
            self.process(events)
        self.ui.update(0.0)
        self.render()

    def render(self) -> None:
        view.draw_frame(self)

    def screenshot(self, path: str | FilePath) -> None:
        """Draw and save the window as a PNG image, atomically."""
        check_png(path, "screenshot")
        self.render()
        path = check_path(path, "--screenshot")
        buf = io.BytesIO()
        try:
            pygame.image.save(self.screen, buf, path.name or "png")
        except pygame.error as exc:
            raise KoolioError(f"{path}: cannot save an image: {exc}") from None
        atomic_write(path, buf.getvalue())

    # =====================================================================================
    # Events
    # =====================================================================================
    def handle(self, event: pygame.event.Event) -> None:
        """Dispatch one event; a refused edit becomes an error message, never a crash."""
        try:
            self._dispatch(event)
        except KoolioError as exc:
            self.model.cancel_drag()
            self.drag = None
            self.say(str(exc), error=True)

    def _dispatch(self, event: pygame.event.Event) -> None:
        if event.type == pygame.QUIT:
            self.request_quit()
            return
        if event.type == pygame.TEXTINPUT and self._prompt_opened:
            return  # the key that opened the question is no answer to it
        if self.prompt is not None and event.type == pygame.KEYDOWN and self._prompt_key(event):
            return
        consumed = self.ui.process_events(event)
        if self._gui_event(event) or consumed:
            return
        if self.prompt is not None and event.type in (pygame.KEYDOWN, pygame.TEXTINPUT):
            return  # keys go to the question while it is open
        if event.type == pygame.KEYDOWN:
            self.on_key(event.key, getattr(event, "mod", 0))
        elif event.type == pygame.MOUSEMOTION:
            self.on_motion(tuple(event.pos))
        elif event.type == pygame.MOUSEBUTTONDOWN:
            self.on_press(tuple(event.pos), event.button, getattr(event, "mod", None))
        elif event.type == pygame.MOUSEBUTTONUP:
            self.on_release(tuple(event.pos), event.button)
        elif event.type == pygame.MOUSEWHEEL:
            self.on_wheel(getattr(event, "y", 0))

    def say(self, message: str, error: bool = False) -> None:
        self.message, self.message_is_error = message, error

    # -- keys ---------------------------------------------------------------------------------
    def on_key(self, key: int, mod: int) -> None:
        ctrl = bool(mod & pygame.KMOD_CTRL)
        shift = bool(mod & pygame.KMOD_SHIFT)
        if ctrl:
            self._ctrl_key(key, shift)
        elif self.drive is not None:
            self._drive_key(key)
        else:
            self._edit_key(key, shift)

    def _ctrl_key(self, key: int, shift: bool) -> None:
        if key == pygame.K_z and not shift:
            self.undo()
        elif key == pygame.K_y or (key == pygame.K_z and shift):
            self.redo()
        elif key == pygame.K_s:
            if shift or self.model.path is None:
                self.save_as_prompt()
            else:
                self.save()
        elif key == pygame.K_o:
            self.ask_file("Open arena file", self.open_file, str(self.model.path or ""), True)
        elif key == pygame.K_n:
            self._unless_dirty("start a new arena", lambda: self._new())
        elif key == pygame.K_d:
            self.ask_file("Import door table", self.import_doors, "arenas/hallway_doors.yaml", True)
        elif key == pygame.K_q:
            self.request_quit()

    def _edit_key(self, key: int, shift: bool) -> None:
        sel = self.selection
        if key in TOOL_KEYS:
            self.set_tool(TOOL_KEYS[key])
        elif key in (pygame.K_DELETE, pygame.K_BACKSPACE):
            self.delete_selection()
        elif key in (pygame.K_RETURN, pygame.K_KP_ENTER, pygame.K_ESCAPE):
            self._finish_or_cancel(key == pygame.K_ESCAPE)
        elif key == pygame.K_F5:
            self.start_drive()
        elif key == pygame.K_F12:
            self._screenshot_next()
        elif key == pygame.K_r and sel is not None and sel[0] == "goals":
            old = self.model.arena.goals[sel[1]].name
            self.ask_text(
                f"Rename goal {old} to:", lambda s: self.model.rename_goal(old, s), old, "Rename"
            )
        elif key == pygame.K_a and sel is not None and sel[0] == "goals":
            self.model.set_active_goal(self.model.arena.goals[sel[1]].name)
        elif key == pygame.K_TAB:
            self._next_active_goal()
        elif key == pygame.K_p:
            self._type_position()
        elif key == pygame.K_n:
            self.ask_text("Arena name:", self.model.set_name, self.model.arena.name, "Rename")
        elif key == pygame.K_h:
            heading = self.model.arena.start.heading_deg
            self.model.set_heading(0.0 if heading is None else None)
        elif key in (pygame.K_LEFTBRACKET, pygame.K_RIGHTBRACKET):
            heading = self.model.arena.start.heading_deg or 0.0
            self.model.set_heading(heading + (15.0 if key == pygame.K_LEFTBRACKET else -15.0))
        elif key == pygame.K_d:
            self._default_zone()
        elif key == pygame.K_x:
            self.cycle_snap()
        elif key == pygame.K_l:
            self.show_lengths = not self.show_lengths
        elif key == pygame.K_f:
            self.fit()
        elif key in (pygame.K_PLUS, pygame.K_EQUALS, pygame.K_KP_PLUS):
            self.camera.zoom_at(self._canvas_centre(), 1.25)
        elif key in (pygame.K_MINUS, pygame.K_KP_MINUS):
            self.camera.zoom_at(self._canvas_centre(), 0.8)
        elif key in (pygame.K_UP, pygame.K_DOWN, pygame.K_LEFT, pygame.K_RIGHT):
            self._arrow(key, shift)

    def _drive_key(self, key: int) -> None:
        if key in DRIVE_KEYS:
            self.drive_step(DRIVE_KEYS[key])
        elif key in (pygame.K_RETURN, pygame.K_KP_ENTER):
            self.drive.reset()
            self.say("back at the start")
        elif key in (pygame.K_ESCAPE, pygame.K_F5):
            self.stop_drive()
        elif key == pygame.K_F12:
            self._screenshot_next()

    def _prompt_key(self, event: pygame.event.Event) -> bool:
        """Keys that answer the open question; True when ``event`` was one."""
        key = event.key
        if key == pygame.K_ESCAPE:
            self.cancel_prompt()
            return True
        if self.prompt.kind != "confirm":
            return False  # the text line takes the keys (Enter: its FINISHED event)
        if key == pygame.K_y:
            self.answer_prompt("y")
        elif key == pygame.K_n:
            self.cancel_prompt()
        return True

    def _gui_event(self, event: pygame.event.Event) -> bool:
        """The open question's widgets: OK, Cancel, Enter in its text line, its window
        closed. True when ``event`` was one of these."""
        prompt = self.prompt
        if prompt is None:
            return False
        element = getattr(event, "ui_element", None)
        if event.type == pygame_gui.UI_TEXT_ENTRY_FINISHED and element is prompt.entry:
            self._enter_pressed(prompt)
        elif event.type == pygame_gui.UI_BUTTON_PRESSED and prompt.kind == "text":
            if element is prompt.ok:
                self.answer_prompt(prompt.text.strip())
            elif element is prompt.cancel:
                self.cancel_prompt()
            else:
                return False
        elif event.type == pygame_gui.UI_CONFIRMATION_DIALOG_CONFIRMED and element is prompt.window:
            self.answer_prompt("y")
        elif event.type == pygame_gui.UI_FILE_DIALOG_PATH_PICKED and element is prompt.window:
            self.answer_prompt(event.text)
        elif event.type == pygame_gui.UI_WINDOW_CLOSE and element is prompt.window:
            self.prompt = None
            self.say("cancelled")
        else:
            return False
        return True

    def _enter_pressed(self, prompt: Prompt) -> None:
        if prompt.kind == "text":
            self.answer_prompt(prompt.text.strip())
            return
        picked = dialogs.picked_file(prompt)
        if picked is not None:
            self.answer_prompt(picked)
        else:  # a folder: the dialog now lists it
            dialogs.select_all(self.ui, prompt.entry)

    def answer_prompt(self, answer: str) -> None:
        """Close the open question and act on ``answer``."""
        prompt, self.prompt = self.prompt, None
        if prompt is None:
            return
        prompt.close()
        prompt.on_done(answer)

    def cancel_prompt(self) -> None:
        prompt, self.prompt = self.prompt, None
        if prompt is not None:
            prompt.close()
            self.say("cancelled")

    def _canvas_rect(self) -> pygame.Rect:
        return pygame.Rect(self.camera.viewport)

    def ask_text(
        self, label: str, on_done: Callable[[str], None], default: str = "", title: str = ""
    ) -> None:
        """Ask for a line of text in a pygame-gui window, ``default`` proposed and
        selected (Enter or OK confirms, Esc or Cancel cancels)."""
        self._open_prompt(
            dialogs.text_prompt(
                self.ui,
                self._canvas_rect(),
                title or "Koolio arena editor",
                label,
                default,
                on_done,
            )
        )

    def ask_yes_no(self, label: str, on_yes: Callable[[], None], action: str = "Yes") -> None:
        """Ask yes or no in a pygame-gui confirmation dialog (Y confirms; N or Esc
        cancels)."""
        self._open_prompt(
            dialogs.confirm_prompt(self.ui, self._canvas_rect(), label, action, on_yes)
        )

    def ask_file(
        self, title: str, on_done: Callable[[str], None], path: str, existing: bool
    ) -> None:
        """Ask for an arena or door-table file in a pygame-gui file dialog."""
        self._open_prompt(
            dialogs.file_prompt(self.ui, self._canvas_rect(), title, path, existing, on_done)
        )

    def _open_prompt(self, prompt: Prompt) -> None:
        if self.prompt is not None:
            self.prompt.close()
        self.prompt = prompt
        self._prompt_opened = True

    # -- mouse --------------------------------------------------------------------------------
    def on_motion(self, pos: tuple[int, int]) -> None:
        self.mouse_screen = pos
        if not self._in_canvas(pos):
            self.cursor = None
            self.hover = self.hover_edge = None
            return
        world = self.camera.to_world(pos)
        if self.drag is None and self.tool in ("goal", "marker"):
            self.cursor = self.model.snap_inside(world)
        else:
            self.cursor = self.model.snap(world, self._tol(), self._exclude())
        if self.drag is not None:
            self._drag_to(pos, world)
        elif self.drive is None:
            self._update_hover(world)

    def on_wheel(self, clicks: float) -> None:
        """Zoom by 1.2 per wheel click, about the point under the cursor (at most
        :data:`~koolio_pymunk.apps.editor.limits.MAX_WHEEL_CLICKS` clicks an event count:
        fewer already cross the whole zoom range)."""
        most = limits.MAX_WHEEL_CLICKS
        clicks = limits.clamp(float(clicks), -most, most)
        if self.mouse_screen is not None and self._in_canvas(self.mouse_screen):
            self.camera.zoom_at(self.mouse_screen, 1.2**clicks)

    def on_press(self, pos: tuple[int, int], button: int, mod: int | None) -> None:
        self.on_motion(pos)
        if button in (4, 5):  # old-style wheel buttons
            return
        if not self._in_canvas(pos):
            if button == 1:
                self._panel_click(pos)
            return
        world = self.camera.to_world(pos)
        if button in (2, 3) or self.drive is not None:
            self.drag = Drag("pan", None, pos, world, last_screen=pos)
            return
        if self.prompt is not None:
            return
        if mod is None:
            mod = pygame.key.get_mods()
        self._tool_press(pos, world, bool(mod & pygame.KMOD_SHIFT))

    def on_release(self, pos: tuple[int, int], button: int) -> None:
        self.on_motion(pos)
        drag, self.drag = self.drag, None
        if drag is None or drag.kind == "pan":
            return
        if not drag.moved:
            self.model.cancel_drag()
            return
        where = items.get_point(self.model.arena, drag.path) if drag.kind == "point" else None
        label = f"move {items.path_str(drag.path)}"
        if where is not None:
            label += f" to ({where[0]:g}, {where[1]:g})"
        if self.model.end_drag(label):
            self.say(label)

    def _drag_to(self, pos: tuple[int, int], world: Point) -> None:
        drag = self.drag
        if drag.kind == "pan":
            dx, dy = pos[0] - drag.last_screen[0], pos[1] - drag.last_screen[1]
            self.camera.pan_pixels(dx, dy)
            drag.last_screen = pos
            return
        far = math.dist(pos, drag.start_screen) >= DRAG_PIXELS
        if not (drag.moved or far):
            return
        drag.moved = True
        if (
            drag.kind == "point"
            and drag.path[0] in ("goals", "end_of_world")
            and len(drag.path) == 2
        ):
            self.model.drag_move(drag.path, self.model.snap_inside(world))
        elif drag.kind == "point":
            self.model.drag_move(drag.path, self.model.snap(world, self._tol(), drag.path))
        else:
            dx = self.model.snap_value(world[0] - drag.start_world[0])
            dy = self.model.snap_value(world[1] - drag.start_world[1])
            self.model.drag_translate(drag.path, dx, dy)

    def _tool_press(self, pos: tuple[int, int], world: Point, shift: bool) -> None:
        """A left click on the canvas with the current tool."""
        snapped = self.model.snap(world, self._tol(), self._exclude())
        tool = self.tool
        if tool == "select":
            self._select_press(pos, world)
        elif tool == "wall":
            self.selection = self.model.add_vertex(("walls",), snapped)
        elif tool == "insert":
            self._insert_press(pos, world)
        elif tool in ("obstacle", "zone"):
            self._polygon_press(tool, snapped)
        elif tool == "goal":
            at = self.model.snap_inside(world)
            self.ask_text(
                f"Name (room number) of the goal at ({at[0]:g}, {at[1]:g}):",
                lambda s: self._add_goal(s, at),
                self.model.next_goal_name(),
                "New goal",
            )
        elif tool == "marker":
            self.selection = self.model.add_marker(self.model.snap_inside(world))
        elif tool == "start":
            if shift:
                sx, sy = self.model.arena.start.at
                deg = round(math.degrees(math.atan2(world[1] - sy, world[0] - sx)))
                self.model.set_heading(deg)
            else:
                self.model.set_start(snapped)
            self.selection = ("start",)

    def _select_press(self, pos: tuple[int, int], world: Point) -> None:
        arena, tol = self.model.arena, self._tol()
        prefer = self._selected_polygon()
        path = items.pick_point(arena, world, tol, prefer)
        kind = "point"
        if path is None:
            edge = items.pick_segment(arena, world, tol)
            path = edge[0] if edge is not None else items.pick_area(arena, world)
            kind = "translate"
        self.selection = path
        if path is None:
            self.drag = Drag("pan", None, pos, world, last_screen=pos)
            return
        if not items.is_movable(path):
            return
        self.model.begin_drag()
        self.drag = Drag(kind, path, pos, world)

    def _insert_press(self, pos: tuple[int, int], world: Point) -> None:
        edge = items.pick_segment(self.model.arena, world, self._tol())
        if edge is None:
            self.say("insert: click on an edge of the walls, an obstacle or a zone", error=True)
            return
        poly, i, foot = edge
        p = self.model.snap(foot)
        pts = items.get_polygon(self.model.arena, poly)
        a, b = pts[i], pts[(i + 1) % len(pts)]
        if math.dist(p, items.closest_point(p, a, b)) > 0.5:
            p = (round(foot[0], 2), round(foot[1], 2))
        self.selection = self.model.insert_vertex(poly, i, p)
        self.model.begin_drag()
        self.drag = Drag("point", self.selection, pos, world)

    def _polygon_press(self, tool: str, p: Point) -> None:
        """Obstacle and zone tools: each click adds a vertex; clicking the first closes."""
        building = self.building
        if building is not None:
            pts = self._polygon_or_none(building)
            if pts is None:
                building = None
            elif len(pts) >= 3 and self._near_screen(pts[0], p):
                self._finish_or_cancel(False)
                return
        if building is not None:
            self.selection = self.model.add_vertex(building, p)
            return
        if tool == "obstacle":
            self.building = self.model.add_obstacle([p])
            self.selection = (*self.building, 0)
            self.say("obstacle: click its corners; Enter or a click on the first corner ends it")
            return
        marker = self._target_marker()
        if marker is None:
            self.say("zone: add an end-of-world marker first (E) and select it", error=True)
            return
        self.model.set_zone(marker, [p])
        self.building = ("end_of_world", marker, "zone")
        self.selection = (*self.building, 0)
        self.say(f"zone of end_of_world[{marker}]: click its corners; Enter ends it")

    def _panel_click(self, pos: tuple[int, int]) -> None:
        if self.drive is not None or self.prompt is not None:
            return
        for rect, name in self.goal_rows:
            if rect.collidepoint(pos):
                self.model.set_active_goal(name)
                self.say(f"active goal {name}")
                return

    # =====================================================================================
    # Commands (keys and scripts)
    # =====================================================================================
    def set_tool(self, tool: str) -> None:
        if tool not in TOOLS:
            raise EditError(f"tool: unknown tool {tool!r} (tools: {', '.join(TOOLS)})")
        self._finish_or_cancel(False, quiet=True)
        self.tool = tool
        self.say(f"tool: {tool}")

    def undo(self, times: int = 1) -> None:
        """Undo ``times`` edits (stops at the history's start at once)."""
        label = self.model.undo(times)
        self._after_history()
        self.say(f"undo: {label}" if label else "nothing to undo")

    def redo(self, times: int = 1) -> None:
        """Redo ``times`` undone edits (stops at the history's end at once)."""
        label = self.model.redo(times)
        self._after_history()
        self.say(f"redo: {label}" if label else "nothing to redo")

    def delete_selection(self) -> None:
        if self.selection is None:
            self.say("nothing selected", error=True)
            return
        if self.selection == ("walls",):
            self.say("select a wall vertex to delete it (the walls stay)", error=True)
            return
        what = items.path_str(self.selection)
        self.model.delete(self.selection)
        self.selection = None
        self.drop_stale()
        self.say(f"deleted {what}")

    def cycle_snap(self) -> None:
        steps = [None if f is None else f * self.model.tile for f in SNAP_FRACTIONS]
        try:
            k = steps.index(self.model.snap_step)
        except ValueError:
            k = -1
        self.model.set_snap(steps[(k + 1) % len(steps)])
        step = self.model.snap_step
        self.say(f"snap {'off' if step is None else f'{step:g} in'}")

    def fit(self) -> None:
        arena = self.model.arena
        pts = list(arena.walls) + [arena.start.at] + [g.at for g in arena.goals]
        if len(arena.walls) < 2:
            pts += [(0.0, 0.0), (10 * self.model.tile, 8 * self.model.tile)]
        xs, ys = [p[0] for p in pts], [p[1] for p in pts]
        self.camera.fit((min(xs), min(ys), max(xs), max(ys)), margin=0.06)

    def save(self, path: str | None = None, confirm: bool = False) -> SaveResult | None:
        """Save; an invalid arena asks first (scripts confirm with ``save!``)."""
        result = self.model.save(path, confirm=confirm)
        if result.needs_confirmation:
            self.ask_yes_no(
                f"INVALID: {result.message} -- write {result.path} anyway"
                + (" (the valid file is kept as .bak)?" if result.path.exists() else "?"),
                lambda: self._report_save(self.model.save(path, confirm=True)),
                "Write anyway",
            )
            return result
        self._report_save(result)
        return result

    def save_as_prompt(self) -> None:
        default = str(self.model.path or f"{self.model.arena.name or 'arena'}.yaml")
        self.ask_file("Save arena as", lambda s: self.save(s) if s else None, default, False)

    def start_drive(self) -> None:
        problem = self.model.problem()
        if problem is not None:
            self.say(f"cannot drive an invalid arena: {problem.message}", error=True)
            return
        self._finish_or_cancel(False, quiet=True)
        self.drive = TestDrive(self.model.arena, self.config)
        self.selection = self.hover = self.hover_edge = None
        self.say("test drive: arrows drive, Space stops, Enter restarts, Esc ends")

    def stop_drive(self) -> None:
        self.drive = None
        self.say("back to editing")

    def drive_step(self, action: str) -> str | None:
        if self.drive is None:
            self.start_drive()
            if self.drive is None:
                return None
        event = self.drive.step(action)
        self.say(f"{self.drive.last_action}: {event}, reward {self.drive.last_reward:g}")
        return event

    def request_quit(self) -> None:
        self._unless_dirty("quit", self._quit)

    # -- helpers --------------------------------------------------------------------------------
    def _quit(self) -> None:
        self.running = False

    def _unless_dirty(self, what: str, action: Callable[[], None]) -> None:
        if self.model.dirty and (self.model.arena.walls or self.model.path is not None):
            self.ask_yes_no(f"Unsaved changes: {what} anyway?", action, what.capitalize())
        else:
            action()

    def _new(self) -> None:
        self.model.new()
        self.after_file("new arena")

    def open_file(self, path: str) -> None:
        self.model.open(path)
        self.after_file(f"opened {path}")

    def import_doors(self, path: str) -> None:
        self.model.import_door_table(path)
        self.after_file(f"built a hallway from {path}: save it with Ctrl+S")

    def after_file(self, message: str) -> None:
        self.selection = self.hover = self.hover_edge = self.building = None
        self.drive = None
        self.fit()
        self.say(message)

    def _report_save(self, result: SaveResult) -> None:
        self.say(result.message, error=not result.saved)

    def _add_goal(self, name: str, p: Point) -> None:
        self.selection = self.model.add_goal(name, p)

    def _after_history(self) -> None:
        self.building = None
        self.drop_stale()

    def drop_stale(self) -> None:
        """Forget a selection or hover that no longer names an item."""
        for attr in ("selection", "hover"):
            path = getattr(self, attr)
            if path is not None and not self.has_item(path):
                setattr(self, attr, None)
        self.hover_edge = None

    def has_item(self, path: Path) -> bool:
        try:
            if items.is_polygon_path(path):
                return bool(items.get_polygon(self.model.arena, path)) or path == ("walls",)
            items.get_point(self.model.arena, path)
        except EditError:
            return False
        return True

    def _finish_or_cancel(self, escape: bool, quiet: bool = False) -> None:
        """Enter / Esc: finish the polygon being drawn; Esc also drops the selection."""
        self.model.cancel_drag()
        self.drag = None
        if self.building is not None:
            pts = self._polygon_or_none(self.building)
            name = items.path_str(self.building)
            self.building = None
            if not quiet:
                self.say(f"{name}: {len(pts or ())} points")
        elif escape:
            self.selection = None

    def _polygon_or_none(self, path: Path) -> tuple[Point, ...] | None:
        try:
            return items.get_polygon(self.model.arena, path)
        except EditError:
            return None

    def _target_marker(self) -> int | None:
        sel = self.selection
        if sel is not None and sel[0] == "end_of_world":
            return sel[1]
        n = len(self.model.arena.end_of_world)
        return n - 1 if n else None

    def _selected_polygon(self) -> Path | None:
        sel = self.selection
        if sel is None:
            return None
        if items.is_polygon_path(sel):
            return sel
        return sel[:-1] if items.is_vertex_path(sel) else None

    def _default_zone(self) -> None:
        sel = self.selection
        marker = sel[1] if sel is not None and sel[0] == "end_of_world" else None
        if marker is None:
            self.say("D: select an end-of-world marker first", error=True)
            return
        self.model.set_zone(marker, None)
        self.say(f"end_of_world[{marker}]: default zone (a disc of one robot diameter)")

    def _next_active_goal(self) -> None:
        names = self.model.arena.goal_names()
        if not names:
            return
        active = self.model.arena.active_goal
        k = names.index(active) if active in names else -1
        self.model.set_active_goal(names[(k + 1) % len(names)])
        self.say(f"active goal {self.model.arena.active_goal}")

    def _type_position(self) -> None:
        sel = self.selection
        if sel is None or items.is_polygon_path(sel):
            self.say("P: select a point first", error=True)
            return
        x, y = items.get_point(self.model.arena, sel)

        def done(s: str) -> None:
            parts = s.replace(",", " ").split()
            try:
                p = (float(parts[0]), float(parts[1]))
            except (ValueError, IndexError):
                raise EditError(f"position: expected two numbers 'x y', got {s!r}") from None
            self.model.move_point(sel, limits.check_point(p, "position"))

        self.ask_text(
            f"Move {items.path_str(sel)} to (x y, inches):", done, f"{x:g} {y:g}", "Position"
        )

    def _arrow(self, key: int, shift: bool) -> None:
        dx = {pygame.K_LEFT: -1, pygame.K_RIGHT: 1}.get(key, 0)
        dy = {pygame.K_DOWN: -1, pygame.K_UP: 1}.get(key, 0)
        sel = self.selection
        if sel is not None and items.is_movable(sel):
            step = 1.0 if shift or self.model.snap_step is None else self.model.snap_step
            self.model.translate(sel, dx * step, dy * step)
            return
        _, _, w, h = self.camera.viewport
        self.camera.pan_pixels(-dx * w * 0.1, dy * h * 0.1)

    def _screenshot_next(self) -> None:
        k = 1
        while FilePath(f"editor-{k}.png").exists():
            k += 1
        self.screenshot(f"editor-{k}.png")
        self.say(f"saved editor-{k}.png")

    def _update_hover(self, world: Point) -> None:
        arena, tol = self.model.arena, self._tol()
        self.hover = items.pick_point(arena, world, tol, self._selected_polygon())
        self.hover_edge = None
        if self.hover is None and self.tool in ("select", "insert"):
            self.hover_edge = items.pick_segment(arena, world, tol)

    def _near_screen(self, a: Point, b: Point) -> bool:
        return math.dist(self.camera.to_screen(a), self.camera.to_screen(b)) <= PICK_PIXELS

    def _tol(self) -> float:
        return PICK_PIXELS / self.camera.zoom

    def _exclude(self) -> Path | None:
        return self.drag.path if self.drag is not None else None

    def _in_canvas(self, pos: tuple[int, int]) -> bool:
        return pygame.Rect(self.camera.viewport).collidepoint(pos)

    def _canvas_centre(self) -> tuple[int, int]:
        left, top, w, h = self.camera.viewport
        return (left + w // 2, top + h // 2)

    # -- readouts ---------------------------------------------------------------------------------
    def adjacent_edges(self, vertex: Path) -> list[tuple[Point, Point, str]]:
        """The edges that meet at a polygon vertex: ``(a, b, name)``."""
        poly = items.get_polygon(self.model.arena, vertex[:-1])
        n, i = len(poly), vertex[-1]
        base = items.path_str(vertex[:-1])
        out = []
        for j in ((i - 1) % n, i):
            if n >= 2 and (n >= 3 or j == 0):
                out.append((poly[j], poly[(j + 1) % n], f"edge {base}[{j}]-{base}[{(j + 1) % n}]"))
        return out

    def ruler_text(self) -> str:
        """Cursor position and the length of the edge under (or being drawn to) the cursor."""
        tile = self.model.tile
        if self.cursor is None:
            return f"zoom {self.camera.zoom:.3g} px/in   (move the mouse over the arena)"
        out = f"cursor {view.world_label(self.cursor, tile)}"
        arena = self.model.arena
        poly = self.building or (("walls",) if self.tool == "wall" else None)
        if poly is not None and self.drive is None:
            pts = self._polygon_or_none(poly) or ()
            if pts:
                out += f"   new edge {view.fmt_len(math.dist(pts[-1], self.cursor), tile)}"
        elif self.hover_edge is not None:
            p, i, _ = self.hover_edge
            pts = items.get_polygon(arena, p)
            a, b = pts[i], pts[(i + 1) % len(pts)]
            name = f"{items.path_str(p)}[{i}]-{items.path_str(p)}[{(i + 1) % len(pts)}]"
            out += f"   {name} {view.fmt_len(math.dist(a, b), tile)}"
        return out
