"""Where a run comes from: the versions, the checkout and the command line that made it.

A Q-table records it when it is made (:mod:`koolio_pymunk.store.run_identity`), as
Stable-Baselines3 keeps a ``system_info.txt`` beside a saved model; a sweep's
``run.json`` records it too. ``koolio-pm info --qtable`` shows it.

>>> p = of_run({"learner": {"alpha": 0.1}})
>>> sorted(k for k in p if k not in ("git",))
['command', 'configuration', 'gymnasium', 'koolio_pymunk', 'numba', 'numpy', 'pymunk', 'python']
"""

from __future__ import annotations

import functools
import importlib.metadata
import platform
import subprocess
from pathlib import Path
from typing import Any

#: The libraries whose versions are recorded.
LIBRARIES = ("numpy", "pymunk", "numba", "gymnasium")

#: The command line of this process's run, as ``koolio-pm`` received it (its arguments
#: after the program's name; None: a run made from Python): the command line interface
#: sets it.
COMMAND: list[str] | None = None


def of_run(configuration: dict[str, Any], command: list[str] | None = None) -> dict[str, Any]:
    """The provenance of a run of ``configuration`` (the resolved configuration, as a
    mapping): this package's version, Python's and :data:`LIBRARIES`', the checkout's
    commit and whether it had changes (when the package runs from a git checkout), the
    command line (``command``, or :data:`COMMAND`) and the configuration."""
    from .._version import __version__

    out: dict[str, Any] = {"koolio_pymunk": __version__, "python": platform.python_version()}
    for lib in LIBRARIES:
        try:
            out[lib] = importlib.metadata.version(lib)
        except importlib.metadata.PackageNotFoundError:
            out[lib] = None
    git = checkout()
    if git is not None:
        out["git"] = git
    argv = command if command is not None else COMMAND
    out["command"] = None if argv is None else [str(a) for a in argv]
    out["configuration"] = configuration
    return out


@functools.lru_cache(maxsize=1)
def checkout() -> dict[str, Any] | None:
    """The commit of the checkout the package runs from, and whether its package files
    have uncommitted changes; None outside a git checkout (an installed package) or
    without git."""
    root = Path(__file__).resolve().parents[2]
    if not (root / ".git").exists():
        return None
    try:
        run = {"cwd": root, "capture_output": True, "text": True, "timeout": 10}
        head = subprocess.run(["git", "rev-parse", "HEAD"], check=True, **run).stdout.strip()
        status = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no", "--", "koolio_pymunk"],
            check=True,
            **run,
        ).stdout
    except (OSError, subprocess.SubprocessError):
        return None
    return {"commit": head, "changed": bool(status.strip())}
