"""Start the arena editor from ``koolio-pm edit``'s flags: the model, the window, a script.

:func:`run_editor` builds the :class:`~koolio_pymunk.apps.editor.model.EditorModel`
(a file, a new arena or a door table), opens the
:class:`~koolio_pymunk.apps.editor.app.EditorApp` window, runs a ``--script`` session
(:mod:`~koolio_pymunk.apps.editor.script`), saves a ``--screenshot``, and stays open
unless a script or a screenshot was all that was asked.
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path as FilePath

import pygame

from ...store.config import ROBOT_PROFILES, load_config
from ...store.errors import KoolioError
from ...task.display import headless, no_display
from ..flags import check_png
from . import limits
from .app import EditorApp
from .model import EditorModel
from .script import run_script

# =========================================================================================
# Entry point
# =========================================================================================
_SIZE = re.compile(r"\s*([0-9]{1,6})\s*[xX]\s*([0-9]{1,6})\s*", re.ASCII)


def window_size(text: str) -> tuple[int, int]:
    """``--size WxH``: 400x300 to 7680x4320 pixels (:mod:`~koolio_pymunk.apps.editor.limits`)."""
    m = _SIZE.fullmatch(text)
    shown = repr(text) if len(text) <= 40 else repr(text[:37] + "...")
    if m is None:
        raise KoolioError(f"--size: expected WxH like 1280x720, got {shown}")
    w, h = int(m.group(1)), int(m.group(2))
    (w0, h0), (w1, h1) = limits.MIN_WINDOW, limits.MAX_WINDOW
    if w < w0 or h < h0:
        raise KoolioError(f"--size: at least {w0}x{h0}, got {shown}")
    if w > w1 or h > h1:
        raise KoolioError(f"--size: at most {w1}x{h1} (an 8K screen), got {shown}")
    return w, h


def grid_inches(value: float) -> float:
    """``--grid INCHES``: 1 to 1,000 in (:mod:`~koolio_pymunk.apps.editor.limits`)."""
    try:
        return limits.check_range(value, limits.MIN_GRID, limits.MAX_GRID, "--grid", " in")
    except KoolioError as exc:  # an EditError: the flag's own one line
        raise KoolioError(str(exc)) from None


def make_model(args: argparse.Namespace) -> EditorModel:
    """The document ``koolio-pm edit``'s flags ask for: a file, a new arena or a door
    table (the robot profile and ``--grid`` checked first)."""
    if args.robot not in ROBOT_PROFILES:
        raise KoolioError(
            f"--robot: unknown profile {args.robot!r} (valid: {', '.join(ROBOT_PROFILES)})"
        )
    kw = {"robot_radius": ROBOT_PROFILES[args.robot], "tile": grid_inches(args.grid)}
    if args.doors or args.new or not args.file:
        if (args.doors or args.new) and args.file and FilePath(args.file).exists():
            raise KoolioError(f"{args.file}: exists: open it, or give a new file name")
        model = EditorModel.blank(**kw)
        if args.doors:
            model.import_door_table(args.doors)
        if args.file:
            model.set_path(args.file)
        return model
    from ...world.arena import arena_path

    return EditorModel.from_file(arena_path(args.file), **kw)


def by_hand(args: argparse.Namespace) -> bool:
    """True when ``koolio-pm edit`` waits for a person: no ``--script`` and no
    ``--screenshot`` (which save and exit), or ``--stay``."""
    return (not args.script and not args.screenshot) or args.stay


def check_display(args: argparse.Namespace) -> None:
    """Refuse in one line to open the editor for a person on a display nobody sees
    (``SDL_VIDEODRIVER=dummy``, or no display at all): it would wait for ever."""
    if by_hand(args) and headless():
        how = "give --script FILE (and --screenshot PNG to see the result)"
        if args.stay:
            how = "leave out --stay"
        raise KoolioError(f"edit: headless ({no_display()}): the editor needs a display; {how}")


def run_editor(args: argparse.Namespace) -> int:
    """Run the editor for the parsed flags of ``koolio-pm edit``
    (:mod:`~koolio_pymunk.apps.editor.command`); bad input raises :class:`KoolioError`."""
    try:
        size = window_size(args.size)
        if args.screenshot is not None:
            check_png(args.screenshot, "--screenshot")
        check_display(args)
        model = make_model(args)
        config = load_config(args.config) if args.config else None
        app = EditorApp(model, size, config)
        if args.script:
            run_script(app, args.script)
        if args.screenshot:
            app.screenshot(args.screenshot)
            print(done_line(args, model))
        elif args.script:
            print(done_line(args, model))
        if by_hand(args):
            app.run()
    finally:
        # The window closes; the font module stays, as the viewer leaves it: the fonts
        # cached by the drawing modules stay valid for a next window in this process.
        pygame.display.quit()
    return 0


def done_line(args: argparse.Namespace, model: EditorModel) -> str:
    """What a scripted or screenshot run did: ``edit: script S run; arena 'office' (not saved
    yet): valid; screenshot X``."""
    problem = model.problem()
    state = "valid" if problem is None else f"invalid ({problem.message})"
    words = [f"script {args.script} run"] if args.script else []
    words.append(f"{model.describe()}: {state}")
    if args.screenshot:
        words.append(f"screenshot {args.screenshot}")
    return "edit: " + "; ".join(words)
