"""The arena editor: ``koolio-pm edit`` run from a checkout (same flags, same behaviour).

Usage::

    .venv/bin/python tools/arena_editor.py [FILE] [--new] [--doors TABLE]
        [--script FILE [--stay]] [--screenshot PNG] [--size WxH] [--grid INCHES]
        [--robot koolio|tjpro] [--config CONFIG]

See ``koolio-pm edit --help`` and docs/editor.md.
"""

from __future__ import annotations

import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from koolio_pymunk.apps.cli import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main(["edit", *sys.argv[1:]]))
