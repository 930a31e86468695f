"""User-facing errors.

Every problem caused by input (an arena file, a configuration file, a Q-table file, a
command-line flag) is raised as a :class:`KoolioError` whose message is a single line
naming the file, the item and the problem, for example::

    arenas/bad.yaml: walls[3]: repeated point (10, 20), same as walls[1]

The command line prints that line as ``koolio-pm: error: <message>`` and exits with
status 2, without a traceback.
"""

from __future__ import annotations


class KoolioError(Exception):
    """Bad input: one line, naming the file, the item and the problem."""


class ArenaError(KoolioError):
    """A malformed or invalid arena file."""


class ConfigError(KoolioError):
    """A malformed or invalid configuration (file, YAML section or flag)."""


class QTableError(KoolioError):
    """A corrupt, truncated or mismatched Q-table file."""


class FileError(KoolioError):
    """A file that cannot be read or written (disk full, permissions, a folder in the way,
    too large ...). ``errno`` is the operating system's error number, when there is one."""

    errno: int | None = None


class InUseError(KoolioError):
    """A file another process is writing (its lock is held)."""


def located(source: str, item: str, problem: str) -> str:
    """Format the one-line message ``source: item: problem`` (item may be empty)."""
    return f"{source}: {item}: {problem}" if item else f"{source}: {problem}"


def shown(value: object, limit: int = 40) -> str:
    """A bad value as an error message shows it: its ``repr`` on one line, cut to ``limit``
    characters.

    >>> shown("a" * 50)
    "'aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa..."
    >>> shown([1, 2])
    '[1, 2]'
    """
    text = repr(value).replace("\n", " ")
    return text if len(text) <= limit else text[: limit - 3] + "..."
