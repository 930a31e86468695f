"""``python -m koolio_pymunk``: the ``koolio-pm`` command line."""

import sys

from .apps.cli import main

if __name__ == "__main__":
    sys.exit(main())
