"""Reading YAML files (arenas, configurations, worlds, sweep specs, door tables) safely.

One loader for every YAML file the project reads:

* ``yaml.SafeLoader`` (no Python objects), with a key repeated in one mapping refused;
* numbers as YAML 1.2 reads them: ``1e-9`` and ``5E3`` are numbers (YAML 1.1, hence
  PyYAML, needs a dot and reads them as strings);
* aliases (``*name``) are refused: a few lines of aliases can stand for billions of
  nodes;
* control characters (a binary file that happens to be UTF-8) are refused with their
  line;
* bounded: a file larger than its kind's limit, nesting deeper than :data:`MAX_DEPTH`,
  or a number of more digits than Python converts (4300) is refused with a one-line
  error, in bounded time and memory.

Every problem is one line ``source: line N: problem`` of the caller's error class.

:func:`dump_yaml` writes with the same rule, so a string that the reader would take for a
number (a goal named ``1e3``) is quoted and reads back as the string it was.

>>> parse_yaml("a: 1e-9\\nb: [1, 2]", "demo.yaml")
{'a': 1e-09, 'b': [1, 2]}
>>> parse_yaml(dump_yaml({"name": "1e3"}), "demo.yaml")
{'name': '1e3'}
>>> parse_yaml("a: 1\\na: 2", "demo.yaml")
Traceback (most recent call last):
...
koolio_pymunk.store.errors.KoolioError: demo.yaml: line 2: not valid YAML: duplicate key 'a'
"""

from __future__ import annotations

import contextlib
import re
from pathlib import Path
from typing import NoReturn

import yaml

from .errors import KoolioError, located
from .files import read_text

#: Deepest nesting of lists and mappings accepted (the shipped files need 4).
MAX_DEPTH = 64
#: Default size limit of a YAML file, bytes.
MAX_BYTES = 4 * 1024 * 1024

#: YAML 1.2 core schema floats (PyYAML's YAML 1.1 resolver wants a dot in ``1.0e-9``).
_FLOAT_12 = re.compile(
    r"^[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?$"
    r"|^[-+]?\.(?:inf|Inf|INF)$|^\.(?:nan|NaN|NAN)$"
)


class SafeLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` with the rules of the module doc."""

    def compose_node(self, parent, index):  # type: ignore[no-untyped-def]
        if self.check_event(yaml.AliasEvent):
            event = self.peek_event()
            raise yaml.composer.ComposerError(
                None, None, "aliases (*name) are not supported", event.start_mark
            )
        self._depth = getattr(self, "_depth", 0) + 1
        try:
            if self._depth > MAX_DEPTH:
                raise yaml.composer.ComposerError(
                    None,
                    None,
                    f"nested more than {MAX_DEPTH} levels deep",
                    self.peek_event().start_mark,
                )
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


def _construct_unique_mapping(loader: SafeLoader, node: yaml.MappingNode) -> dict:
    loader.flatten_mapping(node)
    seen: set = set()
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=True)
        with contextlib.suppress(TypeError):
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r}", key_node.start_mark
                )
            seen.add(key)
    return loader.construct_mapping(node, deep=True)


SafeLoader.add_constructor(
    yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_unique_mapping
)
SafeLoader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT_12, list("-+0123456789."))


class SafeDumper(yaml.SafeDumper):
    """``yaml.SafeDumper`` that quotes every string :class:`SafeLoader` reads as a number."""


SafeDumper.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT_12, list("-+0123456789."))


def dump_yaml(data: object, **options: object) -> str:
    """YAML text of ``data`` that :func:`parse_yaml` reads back as ``data``
    (``options``: those of ``yaml.dump``, e.g. ``sort_keys=False``)."""
    return yaml.dump(data, Dumper=SafeDumper, **options)  # type: ignore[call-overload]


def _fail(error: type[KoolioError], source: str, item: str, problem: str) -> NoReturn:
    raise error(located(source, item, problem).replace("\n", " "))


def parse_yaml(text: str, source: str, error: type[KoolioError] = KoolioError) -> object:
    """Parse YAML ``text``; any problem is a one-line ``error``."""
    try:
        return yaml.load(text, Loader=SafeLoader)
    except yaml.reader.ReaderError as exc:  # a control character: a binary file
        line = text.count("\n", 0, exc.position) + 1
        char = exc.character if isinstance(exc.character, int) else ord(exc.character)
        _fail(error, source, f"line {line}", f"control character U+{char:04X}: not a text file")
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f"line {mark.line + 1}" if mark is not None else ""
        problem = exc.problem or exc.context or "syntax error"
        _fail(error, source, where, f"not valid YAML: {problem}")
    except yaml.YAMLError as exc:
        _fail(error, source, "", f"not valid YAML: {exc}")
    except RecursionError:
        _fail(error, source, "", "not valid YAML: nested too deeply")
    except ValueError as exc:  # e.g. an integer of more than 4300 digits
        problem = str(exc).split(";")[0] if "digits" in str(exc) else "a value is out of range"
        _fail(error, source, "", f"not valid YAML: {problem}")
    except OverflowError:
        _fail(error, source, "", "not valid YAML: a number is out of range")


def read_yaml(
    path: str | Path,
    source: str | None = None,
    error: type[KoolioError] = KoolioError,
    limit: int = MAX_BYTES,
    what: str = "YAML file",
) -> object:
    """Read and parse a YAML file of at most ``limit`` bytes; one-line ``error`` if bad."""
    source = str(path) if source is None else source
    try:
        text = read_text(path, limit, what)
    except KoolioError as exc:
        message = str(exc)
        if source != str(path) and message.startswith(str(path)):
            message = source + message[len(str(path)) :]
        raise error(message) from None
    return parse_yaml(text, source, error)
