"""Property-style fuzz of the input loaders: no malformed file may end in anything but the
project's own one-line error.

Random mutations of the shipped files (arenas, the configuration profile, a Q-table's
header, an exported policy), seeded and bounded in count, go through the loaders the
commands use. Each must either load or raise :class:`~koolio_pymunk.store.errors.KoolioError`
(``robot_runtime.PolicyError`` for the robot's own reader) whose message is one line
naming the file; any other exception fails the test with the seed and the input.

Two kinds of mutation: *structural* (parse the file, replace, drop or duplicate a random
node with an awkward value: a 400-digit integer, ``1e999``, NaN, deep nesting, a string,
a list...) and *textual* (flip, drop, repeat or insert bytes and tokens in the text).
``KOOLIO_FUZZ_N`` (default 150) sets the number of cases per loader and kind; the
default keeps the module to a few seconds. ``KOOLIO_FUZZ_SEED`` (default empty) is added
to every seed, for other cases than the usual ones; a failure names its label, and the
same two settings replay it.
"""

from __future__ import annotations

import copy
import json
import os
import random
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml
from inputs import header_of, small_table, with_header

from koolio_pymunk import robot_runtime as rt
from koolio_pymunk.apps.export import load_any_table, policy_document
from koolio_pymunk.store.config import Config, apply_world, load_config
from koolio_pymunk.store.errors import KoolioError
from koolio_pymunk.store.qtable import QTable
from koolio_pymunk.world.arena import load_arena

REPO = Path(__file__).resolve().parent.parent
N = int(os.environ.get("KOOLIO_FUZZ_N", "150"))
SEED = os.environ.get("KOOLIO_FUZZ_SEED", "")
ARENAS = sorted((REPO / "arenas").glob("*.yaml"))
PROFILES = sorted((REPO / "koolio_pymunk" / "profiles").glob("*.yaml"))

#: Values a structural mutation puts in place of a node.
AWKWARD: list[Callable[[random.Random], Any]] = [
    lambda r: None,
    lambda r: True,
    lambda r: 0,
    lambda r: -1,
    lambda r: int("9" * 400),
    lambda r: -(10**30),
    lambda r: 2**64,
    lambda r: float("inf"),
    lambda r: float("nan"),
    lambda r: 1e-300,
    lambda r: r.uniform(-1e6, 1e6),
    lambda r: "",
    lambda r: "abc",
    lambda r: "1e-9",
    lambda r: [],
    lambda r: {},
    lambda r: [r.uniform(-10, 10)] * r.choice([1, 2, 3, 1100]),
    lambda r: {"x": 1},
    lambda r: [[[[[[[[[[1]]]]]]]]]],
    lambda r: {"a": {"b": {"c": [1, [2, [3]]]}}},
    lambda r: [[0, 0], [0, 0]],
]

#: Tokens a textual mutation inserts.
TOKENS = [
    "[",
    "]",
    "{",
    "}",
    ":",
    ",",
    "- ",
    "#",
    "'",
    '"',
    "!",
    "~",
    "null",
    "\n",
    "\t",
    "&a ",
    "*a",
    "!!python/object:os.system ",
    "1e999",
    "-1e-9",
    "9" * 400,
    "9" * 5000,
    "-",
    ".nan",
    "\\u0000",
    "\x00",
    "\xff",
    "[" * 70,
    "[" * 200,
    "key: value\n",
]


# -- mutation --------------------------------------------------------------------------
def _nodes(value: Any, path: tuple = ()) -> list[tuple]:
    """Paths of every node of a parsed document (the root is ``()``)."""
    out = [path]
    if isinstance(value, dict):
        for k, v in value.items():
            out += _nodes(v, (*path, k))
    elif isinstance(value, list):
        for i, v in enumerate(value[:50]):
            out += _nodes(v, (*path, i))
    return out


def _at(doc: Any, path: tuple) -> Any:
    for key in path:
        doc = doc[key]
    return doc


def mutate_structure(doc: Any, rng: random.Random) -> Any:
    """A deep copy of ``doc`` with one to three nodes replaced, dropped or duplicated."""
    doc = copy.deepcopy(doc)
    for _ in range(rng.randint(1, 3)):
        paths = [p for p in _nodes(doc) if p]
        if not paths:
            return rng.choice(AWKWARD)(rng)
        leaves = [p for p in paths if not isinstance(_at(doc, p), (dict, list))]
        path = rng.choice(leaves if leaves and rng.random() < 0.7 else paths)
        parent, key = _at(doc, path[:-1]), path[-1]
        action = rng.random()
        if action < 0.7:
            parent[key] = rng.choice(AWKWARD)(rng)
        elif action < 0.85:
            del parent[key]
        elif isinstance(parent, list):
            parent.insert(key, copy.deepcopy(parent[key]))
        else:
            parent[f"{key}_extra"] = copy.deepcopy(parent[key])
    return doc


def mutate_text(text: str, rng: random.Random) -> str:
    """``text`` with one to four bytes or tokens flipped, dropped, repeated or inserted."""
    for _ in range(rng.randint(1, 4)):
        if not text:
            text = rng.choice(TOKENS)
            continue
        i = rng.randrange(len(text))
        j = min(len(text), i + rng.randint(1, 40))
        action = rng.random()
        if action < 0.3:
            text = text[:i] + rng.choice(TOKENS) + text[i:]
        elif action < 0.5:
            text = text[:i] + text[j:]
        elif action < 0.65:
            text = text[:j] + text[i:j] + text[j:]
        elif action < 0.8:
            text = text[:i] + chr(rng.randrange(1, 0x250)) + text[i + 1 :]
        elif action < 0.9:
            text = text[: rng.randrange(len(text))]
        else:
            digits = "".join(rng.choice("0123456789") for _ in range(rng.randint(1, 400)))
            text = text[:i] + digits + text[i:]
    return text


def _check(
    load: Callable[[], Any], errors: tuple[type[Exception], ...], label: str, path: Path
) -> None:
    """``load()`` loads, or raises one of ``errors`` with a one-line message naming
    ``path``."""
    try:
        load()
    except errors as exc:
        message = str(exc)
        assert "\n" not in message, f"{label}: not one line: {message!r}"
        assert message.startswith(f"{path}: "), f"{label}: does not name the file: {message!r}"
    except Exception as exc:  # anything else is the bug the fuzz looks for
        pytest.fail(f"{label}: {type(exc).__name__}: {exc}")


def _write_yaml(path: Path, doc: Any) -> None:
    dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
    text = yaml.dump(doc, Dumper=dumper, sort_keys=False, allow_unicode=True)
    path.write_text(text, encoding="utf-8")


# -- YAML files --------------------------------------------------------------------------
def yaml_cases(sources: dict[str, str], kind: str, path: Path) -> Iterator[str]:
    """Write ``N`` mutations of ``sources`` (name -> text) to ``path`` one after the other,
    yielding the label of each."""
    rng = random.Random(f"{kind}-{','.join(sorted(sources))}{SEED}")
    docs = {name: yaml.safe_load(text) for name, text in sources.items()}
    for case in range(N):
        name = rng.choice(sorted(sources))
        if kind == "structure":
            _write_yaml(path, mutate_structure(docs[name], rng))
        else:
            path.write_bytes(mutate_text(sources[name], rng).encode("utf-8", "surrogatepass"))
        yield f"{name} {kind} case {case}"


@pytest.mark.parametrize("kind", ["structure", "text"])
def test_fuzz_arena_loader(tmp_path: Path, kind: str) -> None:
    sources = {p.name: p.read_text(encoding="utf-8") for p in ARENAS}
    path = tmp_path / "fuzz.yaml"
    for label in yaml_cases(sources, kind, path):
        _check(lambda: load_arena(path), (KoolioError,), f"arena {label}", path)


@pytest.mark.parametrize("kind", ["structure", "text"])
def test_fuzz_configuration_loader(tmp_path: Path, kind: str) -> None:
    sources = {p.name: p.read_text(encoding="utf-8") for p in PROFILES}
    sources["defaults.yaml"] = Config().to_yaml()
    path = tmp_path / "fuzz.yaml"
    for label in yaml_cases(sources, kind, path):
        _check(lambda: load_config(path), (KoolioError,), f"config {label}", path)
        _check(lambda: apply_world(Config(), path), (KoolioError,), f"world {label}", path)


# -- Q-table headers ---------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["structure", "text"])
def test_fuzz_table_header(tmp_path: Path, kind: str) -> None:
    rng = random.Random(f"table-{kind}{SEED}")
    data = small_table().to_bytes()
    header = header_of(data)
    text = json.dumps(header, sort_keys=True)
    path = tmp_path / "fuzz.qtable"
    for case in range(N):
        if kind == "structure":
            raw = json.dumps(mutate_structure(header, rng), allow_nan=True).encode()
        else:
            raw = mutate_text(text, rng).encode("utf-8", "surrogatepass")
        path.write_bytes(with_header(data, raw))
        label = f"table header {kind} case {case}"
        _check(lambda: QTable.from_bytes(path.read_bytes(), str(path)), (KoolioError,), label, path)
        _check(lambda: load_any_table(path), (KoolioError,), label + " (any table)", path)


# -- policy files ------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["structure", "text"])
def test_fuzz_policy_loaders(tmp_path: Path, kind: str) -> None:
    rng = random.Random(f"policy-{kind}{SEED}")
    doc = policy_document(small_table())
    text = rt.dump_document(doc)
    path = tmp_path / "fuzz.json"
    for case in range(N):
        if kind == "structure":
            out = json.dumps(mutate_structure(doc, rng), allow_nan=True)
        else:
            out = mutate_text(text, rng)
        path.write_bytes(out.encode("utf-8", "surrogatepass"))
        label = f"policy {kind} case {case}"
        _check(lambda: rt.Policy.load(str(path)), (rt.PolicyError,), label + " (robot)", path)
        _check(lambda: load_any_table(path), (KoolioError,), label + " (simulator)", path)
        try:
            policy = rt.Policy.load(str(path))
        except rt.PolicyError:
            continue
        says_what_it_holds(json.loads(path.read_bytes()), policy, label)


def says_what_it_holds(doc: dict, policy: rt.Policy, label: str) -> None:
    """A policy that loads holds no derived item (``n_states``, ``greedy``, the layout's
    bits and shifts) other than its entries and fields make it: a reader may act on that
    item alone (audit: ``greedy[0].action: 9``, ``layout.total_bits: 99`` and a wrong
    ``n_states`` loaded)."""
    again = policy.to_document()
    assert "n_states" not in doc or doc["n_states"] == again["n_states"], f"{label}: n_states"
    if "greedy" in doc:  # other keys of an item are a later version's: not read
        pairs = [(g["state"], g["action"]) for g in doc["greedy"]]
        assert pairs == [(g["state"], g["action"]) for g in again["greedy"]], f"{label}: greedy"
    lay, want = doc["layout"], again["layout"]
    for key in ("action_bits", "total_bits", "n_actions"):
        assert key not in lay or lay[key] == want[key], f"{label}: layout.{key} {lay[key]!r}"
    for i, (field, fwant) in enumerate(zip(lay["fields"], want["fields"], strict=True)):
        for key in ("bits", "shift", "levels"):
            assert key not in field or field[key] == fwant[key], f"{label}: fields[{i}].{key}"


def test_mutations_are_seeded() -> None:
    """The same seed gives the same cases (a failure can be replayed)."""
    doc = yaml.safe_load(ARENAS[0].read_text(encoding="utf-8"))
    runs = [mutate_structure(doc, random.Random("s")) for _ in range(2)]
    texts = [mutate_text(ARENAS[0].read_text(encoding="utf-8"), random.Random(7)) for _ in "ab"]
    assert repr(runs[0]) == repr(runs[1]) and texts[0] == texts[1]
