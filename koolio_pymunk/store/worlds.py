"""The name of the world a run is in: what a Q-table records (``world``) and ``eval``,
``train`` and the window print.

Realism can be turned on two ways: a world laid over the configuration (``--world NAME``)
or a configuration whose own ``realism`` section is on (``--config koolio-real``, a
configuration file, a sweep's settings). Either way the table records the world the run
really ran in, so a table learned with realism on never resumes quietly in the ideal world
and a table learned in the ideal world never resumes quietly in a realistic one
(:func:`koolio_pymunk.store.qtable.check_record` compares the names):

1. realism off: ``ideal`` (the table records nothing);
2. ``--world W`` that decides the realism alone (the configuration's own realism is off,
   or W lays the same realism over it as over the defaults): W's name, as it always was;
3. realism equal to a shipped world profile's (``--config koolio-real`` and ``--world
   koolio-real`` are one world): the profile's name;
4. any other realism (a configuration file's own, a world over it that changes only part
   of it, a sweep's grid, a ``Config`` built in Python): ``realism-`` and 8 hex digits of
   a hash of the whole ``realism`` section. The content, not a file's name: every run of a
   sweep has a ``config.yaml``, and an edited file is another world.

The sensor noise (``sensors.noise``), which a world may also set, is the robot's own
paper-era noise and is not part of the name, as before.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
from pathlib import Path
from typing import Any

from .config import Config, apply_world, load_config, world_names
from .errors import KoolioError
from .realism_config import RealismConfig, realism_on

#: The world of a run without realism (a table records no ``world`` for it).
IDEAL = "ideal"


def world_label(world: str | Path | None) -> str:
    """How a table records the world ``--world`` named: a profile's name, a world file's
    name without its folders (two spellings of one path agree), ``ideal`` for none.

    >>> world_label(None), world_label("koolio-real"), world_label("worlds/lab.yaml")
    ('ideal', 'koolio-real', 'lab.yaml')
    """
    if world is None or str(world) == IDEAL:
        return IDEAL
    text = str(world)
    return Path(text).name if text.endswith((".yaml", ".yml")) or "/" in text else text


def world_name(
    cfg: Config, world: str | Path | None = None, own: RealismConfig | None = None
) -> str:
    """The world a run with the configuration ``cfg`` is in (see the module docstring):
    ``world`` is the world laid over the configuration (``--world``, None: none), ``own``
    the configuration's realism before it (None: ``cfg``'s).

    >>> world_name(load_config()), world_name(load_config("koolio-real"))
    ('ideal', 'koolio-real')
    >>> world_name(load_config(world="koolio-real"), "koolio-real")
    'koolio-real'
    >>> real = load_config("koolio-real")
    >>> real.realism.motion.drift_deg = 1.0
    >>> world_name(real)  # doctest: +ELLIPSIS
    'realism-...'
    """
    own = cfg.realism if own is None else own
    if world is not None and (not realism_on(own) or _same(cfg.realism, _world_alone(world))):
        return str(world)
    if world is None and not realism_on(cfg.realism):
        return IDEAL
    realism = _plain(cfg.realism)
    for name, theirs in _profile_worlds():
        if realism == theirs:
            return name
    return realism_digest(cfg.realism)


def realism_digest(realism: RealismConfig) -> str:
    """``realism-`` and 8 hex digits: the name of a realism that is no shipped world's."""
    text = json.dumps(_plain(realism), sort_keys=True, separators=(",", ":"))
    return "realism-" + hashlib.sha256(text.encode()).hexdigest()[:8]


def _plain(realism: RealismConfig) -> dict[str, Any]:
    return dataclasses.asdict(realism)


def _same(a: RealismConfig, b: RealismConfig) -> bool:
    return _plain(a) == _plain(b)


def _world_alone(world: str | Path) -> RealismConfig:
    """The realism ``world`` lays over the default configuration."""
    return apply_world(Config(), world).realism


@functools.lru_cache(maxsize=1)
def _profile_worlds() -> tuple[tuple[str, dict[str, Any]], ...]:
    """The shipped worlds (:func:`~.config.world_names`) that turn realism on, with their
    realism (read once)."""
    out = []
    for name in world_names():
        try:
            realism = load_config(name).realism
        except KoolioError:  # an unreadable profile names no world
            continue
        if realism_on(realism):
            out.append((name, _plain(realism)))
    return tuple(out)
