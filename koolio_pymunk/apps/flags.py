"""The types of the command line's number flags: each value is checked where argparse
reads it, and a bad one is one line naming the flag and its range
(``koolio-pm: error: --seed: must be >= 0, got -1 (see koolio-pm train --help)``).

Integers are written in ASCII digits (``int`` alone takes ``1_0`` and ``٣``); floats must
be finite (``nan`` and ``inf`` are refused by every range). The ranges of every flag are
listed in ``docs/robustness.md``.
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Callable
from pathlib import Path

from ..store.errors import KoolioError

#: Seeds are below 2**63 (numpy's generators and the int64 of the tables' files).
SEED_LIMIT = 1 << 63
#: Most episodes one command runs (``--episodes`` of train, eval, view, transfer).
MAX_EPISODES = 10**9
_ASCII_INT = re.compile(r"[-+]?[0-9]{1,30}")


def _parse_int(text: str) -> int:
    """An integer written in ASCII digits (``int`` alone would take ``1_0`` or ``٣``);
    ValueError otherwise (argparse: ``invalid int value``)."""
    if not _ASCII_INT.fullmatch(text.strip()):
        raise ValueError(text)
    return int(text)


def seed_type(text: str) -> int:
    """``--seed``: an integer in 0..2**63 - 1 (numpy seeds are non-negative).

    >>> seed_type("7"), seed_type(str(2**63 - 1)) == 2**63 - 1
    (7, True)
    """
    try:
        value = _parse_int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text[:40]!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {value}")
    if value >= SEED_LIMIT:
        raise argparse.ArgumentTypeError(f"must be < 2**63, got {text[:40]}")
    return value


def int_type(low: int, high: int) -> Callable[[str], int]:
    """An argparse type: an integer in ``low..high`` (one line naming the range).

    >>> int_type(1, 1024)("8")
    8
    >>> int_type(1, 1024)("0")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: must be in 1..1024, got 0
    """

    def parse(text: str) -> int:
        try:
            value = _parse_int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not an integer: {text[:40]!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(
                f"must be in {_num(low)}..{_num(high)}, got {_num(value)}"
            )
        return value

    parse.__name__ = "int"
    return parse


def float_type(low: float, high: float, low_open: bool = False) -> Callable[[str], float]:
    """An argparse type: a finite number in ``[low, high]`` (``(low, high]`` with
    ``low_open``); ``nan`` and ``inf`` are refused.

    >>> float_type(0, 1)("0.5"), float_type(0, 1, low_open=True)("1")
    (0.5, 1.0)
    """
    span = f"({low:g}, {high:g}]" if low_open else f"[{low:g}, {high:g}]"

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text[:40]!r}") from None
        inside = (low < value if low_open else low <= value) and value <= high
        if not inside:  # NaN too
            raise argparse.ArgumentTypeError(f"must be in {span}, got {text[:40]}")
        return value

    parse.__name__ = "float"
    return parse


def _num(value: int) -> str:
    """``1024``, ``1,000,000,000``: commas from five digits on."""
    return f"{value:,}" if abs(value) >= 10_000 else str(value)


def episodes_type(low: int = 0) -> Callable[[str], int]:
    """``--episodes``: an integer in ``low``..:data:`MAX_EPISODES`."""
    return int_type(low, MAX_EPISODES)


def file_name(text: str) -> str:
    """The type of a flag that names a file or a folder: any name but an empty one
    (``Path('')`` is the current folder: ``--out ''`` would write there, ``--script ''``
    would be no script at all).

    >>> file_name("runs/a.csv")
    'runs/a.csv'
    >>> file_name(" ")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: empty file name
    """
    if text.strip() == "":
        raise argparse.ArgumentTypeError("empty file name")
    return text


def check_png(path: str | Path, item: str) -> None:
    """An image to write (``--screenshot``, ``plot --out``): a name ending in ``.png``
    that is not a folder; else :class:`KoolioError` (one line naming ``item``).

    >>> check_png("notes.md", "--screenshot")
    Traceback (most recent call last):
    koolio_pymunk.store.errors.KoolioError: --screenshot: notes.md: must end in .png
    >>> check_png("", "--screenshot")
    Traceback (most recent call last):
    koolio_pymunk.store.errors.KoolioError: --screenshot: empty file name
    """
    if str(path).strip() == "":
        raise KoolioError(f"{item}: empty file name")
    if not str(path).lower().endswith(".png"):
        raise KoolioError(f"{item}: {path}: must end in .png")
    if Path(path).is_dir():
        raise KoolioError(f"{item}: {path}: is a folder, not a file")
