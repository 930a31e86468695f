"""Edit arena files in the arena editor window, and test-drive the robot in them.

``koolio-pm edit [FILE] [--new] [--doors TABLE] [--script FILE [--stay]]
[--screenshot PNG] [--size WxH] [--grid INCHES] [--robot NAME] [--config FILE]``

``FILE`` is an arena file or a built-in arena name (``hallway``, ``room``,
``obstacles``); ``--new FILE`` starts an empty arena that Ctrl+S saves to FILE;
``--doors TABLE`` builds a hallway from a door table (:mod:`koolio_pymunk.world.hallway`). With
``--script`` the editor runs a scripted session (:mod:`koolio_pymunk.apps.editor.script`) and
exits; ``--screenshot`` saves the window at the end. Headless: ``SDL_VIDEODRIVER=dummy``.
The keys are in ``docs/editor.md`` and the editor's side panel; the ranges of every number
the editor takes (flags, script values, typed positions, zoom) and their reasons in
:mod:`koolio_pymunk.apps.editor.limits` (a flag out of range is refused in one line).

This module is the command's wiring only, free of pygame, so that ``koolio-pm --help``
works on a base install; the window is :mod:`koolio_pymunk.apps.editor.app`, which needs the
``view`` extra (without it the command says which extra to install and exits 2).
"""

from __future__ import annotations

import argparse


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The editor's flags."""
    from ..flags import file_name

    p.add_argument(
        "file", nargs="?", type=file_name, help="arena file to open (or a built-in name)"
    )
    p.add_argument("--new", action="store_true", help="start a new arena (saved to FILE)")
    p.add_argument(
        "--doors", type=file_name, metavar="TABLE", help="start from a door table (hallway)"
    )
    p.add_argument(
        "--script", type=file_name, metavar="FILE", help="run a scripted session, then exit"
    )
    p.add_argument("--stay", action="store_true", help="stay open after --script")
    p.add_argument(
        "--screenshot", type=file_name, metavar="PNG", help="save a screenshot at the end, exit"
    )
    p.add_argument(
        "--size",
        default="1280x720",
        help="window size WxH (default 1280x720; 400x300 to 7680x4320)",
    )
    p.add_argument(
        "--grid",
        type=float,
        default=24.0,
        help="grid and snap step, inches (default 24: a tile; 1 to 1000)",
    )
    p.add_argument("--robot", default="koolio", help="robot profile for clearance checks")
    p.add_argument("--config", type=file_name, help="configuration file for the test drive")


def run(args: argparse.Namespace) -> int:
    """``koolio-pm edit``."""
    from ...store.extras import view_extra

    with view_extra("edit"):
        from .launch import run_editor

    return run_editor(args)
