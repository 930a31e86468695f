"""Helpers of the attack and fuzz tests: the promise checked on a folder, and well-formed
inputs to break (a small Q-table of the default layout, its header rewritten under a
valid checksum)."""

from __future__ import annotations

import hashlib
import json
import struct
import zlib
from collections.abc import Callable, Sequence
from pathlib import Path

import pytest

from koolio_pymunk.apps import cli
from koolio_pymunk.store import run_identity
from koolio_pymunk.store.config import Config, state_fields
from koolio_pymunk.store.keyword import KeywordLayout
from koolio_pymunk.store.qtable import MAGIC, QTable, QTableStore
from koolio_pymunk.store.run_identity import RunIdentity, sensor_signature
from koolio_pymunk.world.arena import arena_record, load_arena

ROOM = load_arena("room")


# -- the promise ------------------------------------------------------------------------------
def snapshot(folder: Path) -> dict[str, str]:
    """Hash of every file under ``folder`` (lock files aside: they hold only a note)."""
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_file() and not p.name.endswith(".lock"):
            with open(p, "rb") as fh:  # not Path.read_bytes: some tests patch it
                out[str(p.relative_to(folder))] = hashlib.sha256(fh.read()).hexdigest()
    return out


def expect_error(
    capsys: pytest.CaptureFixture[str],
    folder: Path,
    argv: Sequence[str],
    *words: str,
    run: Callable[[list[str]], int] = cli.main,
    prefix: str = "koolio-pm: error: ",
) -> str:
    """Run ``koolio-pm argv`` (or ``run(argv)``, e.g. ``robot_runtime.main``) in ``folder``:
    exit 2, one error line starting with ``prefix`` and holding ``words``, no traceback, no
    file changed or added. Returns the line."""
    before = snapshot(folder)
    try:
        code = run(list(argv))
    except SystemExit as exc:  # argparse
        code = exc.code
    _, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert code == 2, (argv, err)
    assert len(lines) == 1 and lines[0].startswith(prefix), err
    assert "Traceback" not in err
    for w in words:
        assert w in lines[0], lines[0]
    assert snapshot(folder) == before, f"{argv} changed files"
    return lines[0]


# -- tables -----------------------------------------------------------------------------------
def made_for(layout: KeywordLayout, sensors: dict) -> RunIdentity:
    """The identity of a run of ``layout`` and ``sensors`` (no arena; one-step Q): what
    ``inspect`` compares."""
    return RunIdentity(layout, json.dumps(sensors, sort_keys=True), None, None, "ideal", None)


def open_table(
    store: QTableStore,
    layout: KeywordLayout,
    sensors: dict,
    q_init: float,
    arena: dict | None = None,
) -> QTable:
    """``store``'s table, locked: loaded (refused when not of ``layout`` and ``sensors``),
    or a new one created (its files written), as a run opens its table."""

    def new() -> QTable:
        meta: dict = {"sensors": sensors, "episodes": 0}
        if arena is not None:
            meta["arena"] = dict(arena)
        return QTable(layout, meta, q_init)

    def check(t: QTable) -> None:
        run_identity.check(t, made_for(layout, sensors), "inspect", str(store.path))

    table = store.load(new, check)
    if store.fresh:
        store.create(table)
    return table


def learned(path: str | Path) -> tuple[str | None, str]:
    """The run id of the table at ``path`` and a hash of what it learned
    (:func:`~koolio_pymunk.store.run_identity.learned_digest`): equal for two tables of
    the same seeded run made under other command lines (whose files differ in the
    provenance they record)."""
    from koolio_pymunk.store.qtable import load_qtable

    table = load_qtable(path)
    return table.meta.get("run_id"), run_identity.learned_digest(table)


def same_run(a: str | Path, b: str | Path) -> bool:
    """Two files of the same seeded run made under other command lines: a table's run id
    and learned content (:func:`learned`), a policy's document without its provenance,
    any other file's bytes."""
    a, b = Path(a), Path(b)
    if a.suffix == ".qtable":
        return learned(a) == learned(b)
    if a.name.endswith(".json") and a.read_bytes()[:1] == b"{":
        docs = [json.loads(p.read_text()) for p in (a, b)]
        for doc in docs:
            doc.pop("provenance", None)
        return docs[0] == docs[1]
    return a.read_bytes() == b.read_bytes()


def log_body(log: bytes | str | Path) -> str:
    """A log's text without its run line (which names its run: two runs of other
    configurations that log the same rows differ only there)."""
    text = log.decode() if isinstance(log, bytes) else log if isinstance(log, str) else ""
    if isinstance(log, Path):
        text = log.read_text(encoding="utf-8")
    return text.split("\n", 1)[1] if text.startswith("# ") else text


def small_table() -> QTable:
    """Three visited states of the default configuration's layout, 3 episodes, learned in
    the room (every header field a table of this version writes)."""
    cfg = Config()
    layout = KeywordLayout(tuple(state_fields(cfg.sensors)))
    meta = {"sensors": sensor_signature(cfg), "episodes": 3, "arena": arena_record(ROOM)}
    table = QTable(layout, meta, -30.0)
    for codes in ((0,) * 12, (2,) * 6 + (3,) * 6, (1, 0, 2, 1, 0, 2, 3, 0, 1, 2, 3, 0)):
        table.row(layout.state_key(codes))[:] = [-1.5, 0.25, 3.0, -30.0, 7.0]
    return table


def table_file(path: Path, cfg: Config, algorithm: dict | None = None) -> Path:
    """A small table of ``cfg``'s layout and sensors at ``path`` (3 states, 3 episodes;
    ``algorithm``: its header's record of a learner other than one-step Q)."""
    layout = KeywordLayout(tuple(state_fields(cfg.sensors)))
    meta: dict = {"sensors": sensor_signature(cfg), "episodes": 3}
    if algorithm is not None:
        meta["algorithm"] = algorithm
    table = QTable(layout, meta, 0.0)
    for i in range(3):
        codes = [i % levels for _, levels in layout.fields]
        table.row(layout.state_key(codes))[:] = [float(i), -1.0, 2.0, 0.0, 1.0]
    path.write_bytes(table.to_bytes())
    return path


def header_of(data: bytes) -> dict:
    """The JSON header of a table file."""
    (hlen,) = struct.unpack_from("<I", data, len(MAGIC))
    return json.loads(data[len(MAGIC) + 4 : len(MAGIC) + 4 + hlen])


def with_header(data: bytes, header: bytes, rows: bytes | None = None) -> bytes:
    """A table file ``data`` with another JSON header (and rows), under a valid checksum."""
    (hlen,) = struct.unpack_from("<I", data, len(MAGIC))
    rest = data[len(MAGIC) + 4 + hlen : -4] if rows is None else rows
    body = MAGIC + struct.pack("<I", len(header)) + header + rest
    return body + struct.pack("<I", zlib.crc32(body))


def edit_header(data: bytes, **changes: object) -> bytes:
    """``data`` with header fields changed (``layout.n_actions=0`` sets a nested one)."""
    header = header_of(data)
    for key, value in changes.items():
        node = header
        parts = key.split(".")
        for part in parts[:-1]:
            node = node[part]
        node[parts[-1]] = value
    return with_header(data, json.dumps(header).encode())


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    """``koolio-pm argv`` in this process: exit status, stdout, stderr."""
    try:
        code = cli.main(list(argv))
    except SystemExit as exc:
        code = exc.code
    out, err = capsys.readouterr()
    return int(code or 0), out, err
