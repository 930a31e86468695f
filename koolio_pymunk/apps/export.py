"""Export a Q-table as a policy file for the robot (koolio-policy JSON, version 1).

``koolio-pm export --qtable FILE --out POLICY`` writes the Q-table in the paper's keyword
format: every Table 12 keyword with its Q value, the greedy action of every visited state,
the keyword layout, and the sensor thresholds the robot needs to encode raw readings
(see :func:`koolio_pymunk.robot_runtime.validate_document` for every field, and
``docs/handoff.md``). ``koolio_pymunk/robot_runtime.py`` (standard library only) runs and
keeps learning that policy on the robot and saves it back in the same format.

The robot's learning settings (``learner``: alpha, gamma, epsilon, and the algorithm with
its parameters when it is not one-step Q) come from ``--config``, like the rewards: the
configuration the table was learned with (:func:`~koolio_pymunk.store.run_identity.check`,
purpose ``export``: another keyword layout, sensor signature, algorithm or choice rule is
refused, another world is said). A
Dyna-Q model is never exported (it describes the simulated world, and the robot builds its
own from real steps), nor read back from a policy file.

The input may be a ``.qtable`` file or a policy file (e.g. one back from the robot); an
``--out`` name ending in ``.qtable`` writes the simulator's binary format instead, so a
table learned on the robot can be evaluated or viewed with the other commands.

``--out`` replaces an earlier policy file, and nothing else (:func:`check_replaceable`):
a ``.qtable`` output is always a new file, since an exported table cannot be told from
a trained one.

:func:`load_any_table` reads either format (``koolio-pm train --init-qtable``).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import stat
from pathlib import Path
from typing import Any

from .. import robot_runtime as rt
from ..store import run_identity
from ..store.config import Config, load_config
from ..store.errors import FileError, QTableError, located
from ..store.files import atomic_write, check_path, read_bytes
from ..store.keyword import KeywordLayout
from ..store.locks import FileLock
from ..store.qtable import (
    MAGIC,
    MAX_TABLE_BYTES,
    RECORD_KEYS,
    QTable,
    backup_path,
    with_journal,
)
from ..store.run_identity import RunIdentity, algorithm_record
from ..store.table_journal import journal_path

WRITTEN_BY = "koolio-pm export"


def add_arguments(p: argparse.ArgumentParser) -> None:
    from .flags import SEED_LIMIT, file_name, int_type

    p.add_argument(
        "--qtable",
        type=file_name,
        default="runs/hallway.qtable",
        help="table to export: a .qtable file or a policy file (default runs/hallway.qtable)",
    )
    p.add_argument(
        "--out",
        type=file_name,
        required=True,
        help="policy file to write (JSON; an earlier policy file is replaced, no other "
        "file); a name ending in .qtable writes the binary format to a new file",
    )
    p.add_argument(
        "--config",
        type=file_name,
        default=None,
        help="YAML configuration or profile the table was learned with: its learner (alpha, "
        "gamma, epsilon, algorithm) and rewards go into the policy as the robot's defaults; "
        "a table of another keyword layout, sensors or algorithm is refused, as eval "
        "refuses it (default: built-in defaults)",
    )
    p.add_argument(
        "--world",
        type=file_name,
        default=None,
        help="the world (profile or file) the policy is meant for; recorded in the policy",
    )
    p.add_argument(
        "--episode",
        type=int_type(0, SEED_LIMIT - 1),
        default=None,
        help="episode whose epsilon (from the schedule) is the robot's default "
        "(default: the table's episode count)",
    )
    p.add_argument(
        "--robot",
        type=int_type(0, 1 << 16),
        default=None,
        metavar="K",
        help="of a table that holds each robot's own rows (train --tables each): robot K's "
        "rows alone, as one robot's table (a policy, or a .qtable that eval, view and "
        "transfer read)",
    )


def run(args: argparse.Namespace) -> int:
    table = load_any_table(args.qtable)
    if args.robot is not None:
        try:
            table = table.robot_table(args.robot)
        except ValueError as e:
            raise QTableError(located(args.qtable, "--robot", str(e))) from None
    out = check_path(args.out, "--out")
    if out.is_dir():  # before its lock file's name is made from it
        raise FileError(located(str(out), "", "cannot write: is a folder, not a file"))
    if out.suffix == ".qtable":  # a table: not while a run writes it
        with FileLock(out, WRITTEN_BY):
            check_replaceable(out, "table")
            atomic_write(out, table.to_bytes())
        print(f"wrote {out}: {len(table)} states, {table.meta.get('episodes', 0)} episodes")
        return 0
    cfg = load_config(args.config, world=args.world)
    run_identity.check(table, RunIdentity.of_config(cfg, args.world), "export", args.qtable)
    doc = policy_document(table, cfg, episode=args.episode, source=args.qtable)
    if args.world is not None:
        doc["world"] = str(args.world)
    with FileLock(out, WRITTEN_BY):
        check_replaceable(out, "policy")
        write_policy(doc, out)
    lay = doc["layout"]
    print(
        f"wrote {out}: {rt.FORMAT} v{rt.VERSION}, {doc['n_states']} states, "
        f"{len(doc['entries'])} keywords ({lay['total_bits']}-bit), "
        f"{doc['episodes']} episodes, {out.stat().st_size:,} bytes"
    )
    return 0


def check_replaceable(out: Path, kind: str) -> None:
    """Refuse to write ``out`` where it would replace a file that is not an earlier export
    of ``kind`` (FileError, one line; nothing changed).

    ``"policy"``: an existing ``out`` must be a koolio-policy file (an earlier export,
    replaced); a log, a configuration, a Q-table or anyone's document is refused.
    ``"table"`` (``--out X.qtable``): ``out`` must be new, and so must its backup
    ``X.qtable.bak``: an exported table's bytes are those of a trained one, so no
    existing ``.qtable`` file can be told to be an earlier export, and a table's place
    (its file, or the backup a run would resume from) is never taken.

    >>> import tempfile
    >>> notes = Path(tempfile.mkdtemp()) / "notes.json"
    >>> _ = notes.write_text('{"todo": 1}')
    >>> check_replaceable(notes, "policy")
    Traceback (most recent call last):
    koolio_pymunk.store.errors.FileError: .../notes.json: --out: exists and is not a koolio-po...
    """
    if kind == "table":
        for path in (out, backup_path(out)):
            if _is_regular(path):
                problem = (
                    "exists, and export writes a .qtable file only under a new name (it "
                    "never replaces a Q-table): choose another name or remove it"
                )
                if path != out:
                    problem = f"a table's backup {path} exists beside it: choose another name"
                raise FileError(located(str(out), "--out", problem))
        return
    if not _is_regular(out):
        return  # missing (a new file), a FIFO, a device...: the write says what it is
    want = f"a {rt.FORMAT} file"
    try:
        data = read_bytes(out, rt.MAX_POLICY_BYTES, want)
    except FileError:  # unreadable, too large, not a regular file: not ours to replace
        data = b""
    if not _is_policy(data):
        problem = f"exists and is not {want}: choose another name or remove it"
        raise FileError(located(str(out), "--out", problem))


def _is_regular(path: Path) -> bool:
    """``path`` is an existing regular file (or a link to one)."""
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except OSError:  # missing, or the write itself says why
        return False


def _is_policy(data: bytes) -> bool:
    """``data`` is a JSON object whose ``format`` is the policy format."""
    if data.lstrip()[:1] != b"{":
        return False
    try:
        doc = json.loads(data)
    except ValueError:  # not JSON, or not UTF-8
        return False
    return isinstance(doc, dict) and doc.get("format") == rt.FORMAT


def policy_document(
    table: QTable, cfg: Config | None = None, episode: int | None = None, source: str = "<table>"
) -> dict[str, Any]:
    """The koolio-policy document of ``table`` (validated by the robot runtime's reader).

    The sensor encoding comes from the table's own sensor signature (what it was learned
    with); ``cfg`` supplies the robot's default learner settings and the rewards.
    """
    sensors = table.meta.get("sensors")
    if not isinstance(sensors, dict) or not sensors:
        raise QTableError(located(source, "sensors", "the table names no sensor layout"))
    check_sensor_signature(sensors, source)
    cfg = cfg or Config()
    n_camera = len(sensors["camera_sensors_deg"])
    episodes = int(table.meta.get("episodes", 0))
    eps_episode = episodes if episode is None else episode
    for state, row in table.rows.items():
        if not all(math.isfinite(q) for q in row):
            raise QTableError(located(source, f"state {state}", "non-finite Q value"))
    encoding = {
        "thresholds": {
            "sonar": [float(t) for t in sensors["sonar_thresholds"]],
            "camera": [float(t) for t in sensors["camera_thresholds"]],
        },
        "sonar_groups": [list(g) for g in sensors["sonar_groups"]],
        "n_sonar": len(sensors["sonar_sensors_deg"]),
        "n_camera": n_camera,
        "max_camera_view": float(sensors["max_camera_view"]),
        "compass_in_state": bool(sensors["compass_in_state"]),
    }
    if cfg.sensors.sonar.pings != 1:  # how the robot reads its sonar (not in the signature)
        encoding["sonar_pings"] = cfg.sensors.sonar.pings
    if isinstance(sensors.get("memory"), dict):
        encoding["memory"] = dict(sensors["memory"])
        if encoding["memory"].get("goal_bearing"):  # the cameras the bearing starts from
            encoding["memory"]["camera_deg"] = [float(d) for d in sensors["camera_sensors_deg"]]
    lay = table.layout
    doc: dict[str, Any] = {
        "format": rt.FORMAT,
        "version": rt.VERSION,
        "written_by": WRITTEN_BY,
        "layout": lay.to_json(),
        "actions": list(rt.ACTION_NAMES[: lay.n_actions]),
        "encoding": rt.encoding_json(rt.Encoder(encoding)),
        "sensors": sensors,
        "learner": {
            "alpha": cfg.learner.alpha,
            "gamma": cfg.learner.gamma,
            "epsilon": cfg.learner.epsilon.at(max(0, eps_episode)),
        }
        | _algorithm(cfg),
        # the robot's events (a robot alone meets no other: no ``robot_bump``)
        "rewards": {k: cfg.rewards.value(k) for k in rt.EVENTS},
        "q_init": float(table.q_init),
        "episodes": episodes,
    }
    if isinstance(table.meta.get("arena"), dict):  # where it was learned (kept by the robot)
        doc["arena"] = table.meta["arena"]
    for key in RECORD_KEYS:  # what for and in which world, when not the arena's default
        if isinstance(table.meta.get(key), str):
            doc[key] = table.meta[key]
    for key in ("run_id", "provenance"):  # where it came from (the runtime keeps both)
        if key in table.meta:
            doc[key] = table.meta[key]
    doc.update(rt.rows_json(table.rows, lay.action_bits))
    try:
        rt.validate_document(doc, source)
    except rt.PolicyError as exc:
        raise QTableError(str(exc)) from None
    return doc


#: What a policy needs of a table's sensor signature (``run_identity.sensor_signature``).
_SIGNATURE_LISTS = (
    "sonar_sensors_deg",
    "camera_sensors_deg",
    "sonar_thresholds",
    "camera_thresholds",
)


def check_sensor_signature(sensors: dict[str, Any], source: str) -> None:
    """The items of a sensor signature a policy is built from, with their types."""

    def bad(key: str, what: str) -> QTableError:
        return QTableError(located(source, f"sensors.{key}", f"must be {what}"))

    for key in _SIGNATURE_LISTS:
        value = sensors.get(key)
        if not isinstance(value, list) or not all(rt.is_number(v) for v in value):
            raise bad(key, "a list of numbers")
    groups = sensors.get("sonar_groups")
    if not isinstance(groups, list) or not all(
        isinstance(g, list) and all(isinstance(i, int) and not isinstance(i, bool) for i in g)
        for g in groups
    ):
        raise bad("sonar_groups", "a list of lists of sonar indices")
    if not rt.is_number(sensors.get("max_camera_view")):
        raise bad("max_camera_view", "a number")
    if not isinstance(sensors.get("compass_in_state"), bool):
        raise bad("compass_in_state", "true or false")


def _algorithm(cfg: Config) -> dict[str, Any]:
    """The ``learner`` keys of a non-default algorithm or choice rule (none for one-step
    Q without the no-undo rule). The Dyna-Q model is not exported: it describes the
    simulated world; the robot builds its own."""
    rec = algorithm_record(cfg.learner)
    if rec is None:
        return {}
    return {"algorithm": rec.pop("name")} | rec


def write_policy(doc: dict[str, Any], out: Path) -> None:
    """Write a policy document atomically (:class:`~koolio_pymunk.store.errors.FileError` if it
    cannot be written)."""
    atomic_write(out, rt.dump_document(doc).encode("utf-8"))


def table_from_policy(policy: rt.Policy) -> QTable:
    """The simulator's QTable of a loaded policy (layout, sensors, episodes, rows)."""
    lay = policy.layout
    layout = KeywordLayout(tuple(zip(lay.names, lay.levels)), lay.n_actions)
    meta: dict[str, Any] = {"sensors": policy.sensors, "episodes": policy.episodes}
    arena = policy.extra.get("arena")
    if isinstance(arena, dict) and all(isinstance(arena.get(k), str) for k in ("name", "sha256")):
        meta["arena"] = {"name": arena["name"], "sha256": arena["sha256"]}
    for key in RECORD_KEYS:
        if isinstance(policy.extra.get(key), str):
            meta[key] = policy.extra[key]
    if isinstance(policy.extra.get("provenance"), dict):
        meta["provenance"] = policy.extra["provenance"]
    if isinstance(policy.extra.get("run_id"), str):
        meta["run_id"] = policy.extra["run_id"]
    if policy.algorithm != "q" or policy.no_undo:  # the robot's Dyna-Q model stays there
        params = {k: policy.learner[k] for k in rt.ALGORITHMS[policy.algorithm]}
        rule = {"no_undo": True} if policy.no_undo else {}
        meta["algorithm"] = {"name": policy.algorithm} | params | rule
    rows = {k: list(v) for k, v in policy.rows.items()}
    return QTable(layout, meta, policy.q_init, rows)


def load_any_table(path: str | Path) -> QTable:
    """Read a ``.qtable`` file or a koolio-policy file; QTableError (one line) if bad.

    The caller checks what it is for (:func:`~koolio_pymunk.store.run_identity.check`).
    """
    p = check_path(path, "--qtable")
    try:
        os.lstat(p)
    except FileNotFoundError:
        raise QTableError(located(str(p), "", "cannot read: no such file or folder")) from None
    except OSError:  # read_bytes says why
        pass
    try:
        data = read_bytes(p, max(MAX_TABLE_BYTES, rt.MAX_POLICY_BYTES), "Q-table or policy file")
    except FileError as exc:
        raise QTableError(str(exc)) from None
    if data[: len(MAGIC)] == MAGIC:  # with its journal, as every reader of a table
        try:
            return with_journal(QTable.from_bytes(data, str(p)), data, journal_path(p))
        except FileError as exc:
            raise QTableError(str(exc)) from None
    if data.lstrip()[:1] != b"{":
        raise QTableError(
            located(str(p), "", "neither a .qtable file nor a koolio-policy (JSON) file")
        )
    try:
        return table_from_policy(rt.Policy.loads(_policy_text(data, str(p)), str(p)))
    except rt.PolicyError as exc:
        raise QTableError(str(exc)) from None


def _policy_text(data: bytes, source: str) -> str:
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise rt.PolicyError(f"{source}: not a policy file (not UTF-8 text)") from None
