"""The arena editor: edit Koolio arena files in a pygame-ce window.

Usage::

    .venv/bin/python tools/arena_editor.py [FILE] [--new] [--doors TABLE]
        [--script FILE [--stay]] [--screenshot PNG] [--size WxH] [--grid INCHES]
        [--robot koolio|tjpro] [--config CONFIG]

``FILE`` is an arena file or a built-in arena name (``hallway``, ``room``,
``obstacles``); ``--new FILE`` starts an empty arena that Ctrl+S saves to FILE;
``--doors TABLE`` builds a hallway from a door table (koolio_pymunk/hallway.py). With
``--script`` the editor runs a scripted session (koolio_pymunk/editor/script.py) and
exits; ``--screenshot`` saves the window at the end. Headless: SDL_VIDEODRIVER=dummy.
Keys: see docs/editor.md or the editor's side panel.
"""

from __future__ import annotations

import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from koolio_pymunk.editor.app import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
