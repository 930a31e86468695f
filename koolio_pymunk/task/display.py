"""pygame's display, started quietly, and whether it shows anything to anybody.

When SDL starts its video it tries the display servers it knows in turn. On Linux
without ``XDG_RUNTIME_DIR`` (a container, a CI runner, a shell with no login session)
its try of Wayland makes libwayland-client write

    error: XDG_RUNTIME_DIR is invalid or not set in the environment.

to the standard error, whatever comes next (X11, or with no display at all SDL's
``offscreen`` driver). The line is neither an error of the command nor one the user can
act on, so :func:`init_display` starts the display with the process's standard error
(file descriptor 2) caught for that moment and writes back every line but that one. No
environment variable is set or changed: the processes a command starts see the user's
environment as it was.

:func:`headless` tells whether the display shows anything (SDL's ``dummy`` driver, asked
for with ``SDL_VIDEODRIVER=dummy``, and ``offscreen``, SDL's choice when there is no
display, show nothing); :func:`no_display` says why in a few words, for the one-line
refusals of commands that would wait for a person who cannot see them. pygame is
imported only when these run (the core never imports it).
"""

from __future__ import annotations

import contextlib
import os
import re
import sys
import tempfile
from collections.abc import Iterator

#: SDL video drivers that show nothing: nobody can see or use a window.
HEADLESS_DRIVERS = ("dummy", "offscreen")
#: Lines of the standard error dropped while the display starts (libwayland-client's,
#: older and newer wording).
NOISE = re.compile(r"error: XDG_RUNTIME_DIR (is invalid or )?not set in the environment\.?")


def init_display() -> str:
    """Start pygame's display (once; again after ``pygame.display.quit()``) without
    libwayland's line about ``XDG_RUNTIME_DIR``; returns SDL's video driver."""
    import pygame

    if not pygame.display.get_init():
        with quiet_stderr():
            pygame.display.init()
    return pygame.display.get_driver()


def headless() -> bool:
    """True when the display shows nothing (SDL's ``dummy`` or ``offscreen`` driver)."""
    return init_display() in HEADLESS_DRIVERS


def no_display() -> str:
    """Why there is no display, in a few words (after :func:`headless` said so)."""
    asked = os.environ.get("SDL_VIDEODRIVER", "")
    if asked in HEADLESS_DRIVERS:
        return f"SDL_VIDEODRIVER={asked}"
    if sys.platform.startswith("linux") and not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    ):
        return "no display: DISPLAY and WAYLAND_DISPLAY are not set"
    return "no display: SDL found none"


@contextlib.contextmanager
def quiet_stderr(noise: re.Pattern[str] = NOISE) -> Iterator[None]:
    """Catch what is written to file descriptor 2 in the block (by C libraries too) and
    write it back at the end, less the whole lines ``noise`` matches."""
    sys.stderr.flush()
    try:
        saved = os.dup(2)
    except OSError:  # no standard error at all: nothing to keep quiet
        yield
        return
    with tempfile.TemporaryFile() as caught:
        os.dup2(caught.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            caught.seek(0)
            text = caught.read().decode("utf-8", "replace")
            kept = [ln for ln in text.splitlines(True) if not noise.fullmatch(ln.strip())]
            if kept:
                sys.stderr.write("".join(kept))
                sys.stderr.flush()
