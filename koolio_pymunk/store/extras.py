"""Optional extras: a missing one is named in one line, never a raw ``ModuleNotFoundError``.

The base install (``pip install koolio-pymunk``) trains, evaluates, exports and sweeps.
Drawing needs the ``view`` extra (``pip install 'koolio-pymunk[view]'``): pygame-ce for
the window, ``env.render()`` and the arena editor, pygame-gui for their widgets,
matplotlib for ``koolio-pm plot`` and a sweep's ``curves.png``. PettingZoo's API for robots
sharing an arena (``koolio_pymunk.parallel_env``) needs the ``multi`` extra.

Code that needs the extra imports it inside :func:`view_extra`; a missing module of the
extra becomes :class:`MissingExtra`, which is both a
:class:`~koolio_pymunk.store.errors.KoolioError` (the command line prints its one line and
exits 2) and Gymnasium's ``DependencyNotInstalled`` (what ``env.render()`` raises, as
Gymnasium's own environments do):

>>> import sys
>>> saved = sys.modules.get("pygame")
>>> sys.modules["pygame"] = None  # as if pygame-ce were not installed
>>> try:
...     with view_extra("render"):
...         import pygame
... except MissingExtra as exc:
...     print(exc)
render: pygame-ce is not installed: pip install 'koolio-pymunk[view]'
>>> if saved is None:
...     del sys.modules["pygame"]
... else:
...     sys.modules["pygame"] = saved
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from gymnasium.error import DependencyNotInstalled

from .errors import KoolioError

VIEW_INSTALL = "pip install 'koolio-pymunk[view]'"
"""The command that installs the drawing extra."""
VIEW_MODULES = {"pygame": "pygame-ce", "pygame_gui": "pygame-gui", "matplotlib": "matplotlib"}
"""Top-level modules of the ``view`` extra and the distributions that provide them."""
MULTI_INSTALL = "pip install 'koolio-pymunk[multi]'"
"""The command that installs the multi-agent extra (PettingZoo)."""
MULTI_MODULES = {"pettingzoo": "pettingzoo"}
"""Top-level modules of the ``multi`` extra and the distributions that provide them."""


class MissingExtra(KoolioError, DependencyNotInstalled):
    """A module of an optional extra is not installed; the message names the extra."""


def missing_extra(
    exc: ImportError,
    what: str,
    modules: dict[str, str] = VIEW_MODULES,
    install: str = VIEW_INSTALL,
) -> MissingExtra | None:
    """The :class:`MissingExtra` for ``exc`` if it is a missing module of the extra
    (``modules``, installed by ``install``: the ``view`` extra by default), else None.

    Only the extra's own top-level modules count: a module missing *inside* an installed
    package is a broken install, not a missing extra, and stays a traceback.
    """
    if not isinstance(exc, ModuleNotFoundError) or exc.name is None:
        return None
    top = exc.name.partition(".")[0]
    if exc.name != top or top not in modules:
        return None
    return MissingExtra(f"{what}: {modules[top]} is not installed: {install}")


@contextlib.contextmanager
def view_extra(
    what: str, modules: dict[str, str] = VIEW_MODULES, install: str = VIEW_INSTALL
) -> Iterator[None]:
    """Turn a missing ``view`` module imported in the block into :class:`MissingExtra`
    (``modules`` and ``install``: another extra's)."""
    try:
        yield
    except ModuleNotFoundError as exc:
        missing = missing_extra(exc, what, modules, install)
        if missing is None:
            raise
        raise missing from None


def multi_extra(what: str) -> contextlib.AbstractContextManager[None]:
    """:func:`view_extra` for the ``multi`` extra (PettingZoo)."""
    return view_extra(what, MULTI_MODULES, MULTI_INSTALL)
