"""Issue #11, tried as an attacker would: malformed input files and value flags.

The companion of ``test_attack.py`` (faults, locks, logs and the cases it already holds):
each case runs ``koolio-pm`` (in this process) in a temporary folder holding good files
next to the bad one and checks the promise of the README with
:func:`inputs.expect_error`: one line ``koolio-pm: error: <file>: <item>: <problem>`` on
stderr, exit status 2, no traceback, and no file changed or added. ``robot_runtime.py``
keeps the same promise with ``robot_runtime: error: ...``.
"""

from __future__ import annotations

import json
import os
import struct
from collections.abc import Callable
from pathlib import Path

import pytest
import yaml
from inputs import edit_header, expect_error, header_of, small_table, with_header

from koolio_pymunk import robot_runtime as rt
from koolio_pymunk.apps import cli
from koolio_pymunk.apps.export import policy_document, write_policy
from koolio_pymunk.apps.sweep import load_spec
from koolio_pymunk.store.config import Config, apply_world
from koolio_pymunk.store.errors import ArenaError, KoolioError
from koolio_pymunk.store.qtable import QTable
from koolio_pymunk.world.arena import (
    MAX_ENTRIES,
    MAX_POLYGON_POINTS,
    MAX_TOTAL_POINTS,
    arena_to_yaml,
    load_arena,
    parse_arena,
)

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

REPO = Path(__file__).resolve().parent.parent
ROOM = (REPO / "arenas" / "room.yaml").read_text(encoding="utf-8")


@pytest.fixture
def here(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A folder with a good table, policy, log, configuration and arena, as the cwd."""
    monkeypatch.chdir(tmp_path)
    table = small_table()
    (tmp_path / "good.qtable").write_bytes(table.to_bytes())
    write_policy(policy_document(table), tmp_path / "good.json")
    (tmp_path / "train.csv").write_text("episode,reward,steps,bumps,outcome,rescued,epsilon,goal\n")
    (tmp_path / "good.yaml").write_text("learner: {alpha: 0.1}\n")
    (tmp_path / "room.yaml").write_text(ROOM)
    return tmp_path


# -- table headers with a valid checksum ---------------------------------------------------
def _edited(**changes: object) -> Callable[[], bytes]:
    return lambda: edit_header(small_table().to_bytes(), **changes)


def _raw_header(old: str, new: str) -> Callable[[], bytes]:
    def make() -> bytes:
        data = small_table().to_bytes()
        text = json.dumps(header_of(data))
        assert old in text
        return with_header(data, text.replace(old, new).encode())

    return make


def _header(raw: bytes) -> Callable[[], bytes]:
    return lambda: with_header(small_table().to_bytes(), raw)


def _without(key: str) -> Callable[[], bytes]:
    def make() -> bytes:
        data = small_table().to_bytes()
        header = header_of(data)
        del header[key]
        return with_header(data, json.dumps(header).encode())

    return make


def _rows(edit: Callable[[list[int], list[float]], None]) -> Callable[[], bytes]:
    def make() -> bytes:
        table = small_table()
        data = table.to_bytes()
        keys = sorted(table.rows)
        values = [q for k in keys for q in table.rows[k]]
        edit(keys, values)
        rows = struct.pack("<Q", len(keys)) + struct.pack(f"<{len(keys)}Q", *keys)
        rows += struct.pack(f"<{len(values)}d", *values)
        return with_header(data, json.dumps(header_of(data)).encode(), rows)

    return make


#: Cases beyond test_attack.py's ``test_table_headers_with_a_valid_checksum_are_checked``.
BAD_TABLES: dict[str, tuple[Callable[[], bytes], str]] = {
    "q_init 400 digits": (
        _raw_header('"q_init": -30.0', '"q_init": ' + "9" * 400),
        "header.q_init: must be a finite number",
    ),
    "q_init NaN": (_raw_header('"q_init": -30.0', '"q_init": NaN'), "unreadable header"),
    "episodes 2.5": (_edited(episodes=2.5), "header.episodes: must be an integer >= 0"),
    "sensors list": (_edited(sensors=[1, 2]), "header.sensors: must be a mapping"),
    "n_actions 1e400": (
        _raw_header('"n_actions": 5', '"n_actions": 1e400'),
        "header.layout.n_actions: must be an integer 1..64, got inf",
    ),
    "n_actions 0": (_edited(**{"layout.n_actions": 0}), "header.layout.n_actions"),
    "fields text": (_edited(**{"layout.fields": "abc"}), "header.layout.fields: must be"),
    "levels 2**40": (
        _edited(**{"layout.fields": [["A", 2**40], ["B", 2**40]]}),
        "header.layout.fields[0]: must be [name, levels 1..65536]",
    ),
    "action_bits wrong": (_edited(**{"layout.action_bits": 9}), "header.layout.action_bits"),
    "layout missing": (_without("layout"), "header.layout: must be a mapping, got None"),
    "header a list": (_header(b"[1, 2]"), "header: not a JSON object"),
    "header nested 5000 deep": (_header(b"[" * 5000 + b"]" * 5000), "unreadable header"),
    "header not UTF-8": (_header(b'{"\xff": 1}'), "unreadable header"),
    "rows out of order": (_rows(lambda k, v: k.reverse()), "rows: state keys not in ascending"),
    "row beyond layout": (_rows(lambda k, v: k.__setitem__(-1, 2**40)), "beyond the 24-bit"),
    "Q value NaN": (_rows(lambda k, v: v.__setitem__(3, float("nan"))), "not a finite number"),
}
TABLE_COMMANDS = {
    "info": ["info", "--qtable", "bad.qtable"],
    "eval": ["eval", "--qtable", "bad.qtable", "--episodes", "1"],
    "export": ["export", "--qtable", "bad.qtable", "--out", "out.json"],
    "train": ["train", "--qtable", "bad.qtable", "--log", "train.csv", "--episodes", "1"],
    "init": ["train", "--init-qtable", "bad.qtable", "--qtable", "new.qtable", "--episodes", "1"],
}


@pytest.mark.parametrize("case", sorted(BAD_TABLES))
def test_malformed_table_in_info(here: Path, capsys, case: str) -> None:
    make, fragment = BAD_TABLES[case]
    (here / "bad.qtable").write_bytes(make())
    expect_error(capsys, here, TABLE_COMMANDS["info"], "bad.qtable: ", fragment)


@pytest.mark.parametrize("command", ["eval", "export", "train", "init"])
@pytest.mark.parametrize("case", ["q_init 400 digits", "sensors list", "n_actions 1e400"])
def test_malformed_table_in_every_command(here: Path, capsys, case: str, command: str) -> None:
    make, fragment = BAD_TABLES[case]
    (here / "bad.qtable").write_bytes(make())
    expect_error(capsys, here, TABLE_COMMANDS[command], "bad.qtable: ", fragment)


@pytest.mark.parametrize(
    ("command", "fragment"),
    [
        ("export", "sensors.sonar_groups: table made for 'x', this run uses [[0], [1, 2]"),
        ("eval", "sensors.sonar_groups: table made for 'x', this run uses [[0], [1, 2]"),
        ("init", "sensors.sonar_groups: table made for 'x'"),
    ],
)
def test_a_sensor_signature_item_of_the_wrong_kind(here: Path, capsys, command, fragment):
    """Each use checks the signature: export, training and evaluation compare it with the
    configuration's; the policy's encoding, built from it, checks its kinds too."""
    data = edit_header(small_table().to_bytes(), **{"sensors.sonar_groups": "x"})
    (here / "bad.qtable").write_bytes(data)
    expect_error(capsys, here, TABLE_COMMANDS[command], "bad.qtable: ", fragment)
    with pytest.raises(KoolioError, match=r"^t\.qtable: sensors\.sonar_groups: must be a list of"):
        policy_document(QTable.from_bytes(data, "t.qtable"), source="t.qtable")


# -- policy files ----------------------------------------------------------------------------
def _policy(edit: Callable[[dict], None]) -> Callable[[], str]:
    def make() -> str:
        doc = policy_document(small_table())
        edit(doc)
        return json.dumps(doc)

    return make


def _policy_text(old: str, new: str) -> Callable[[], str]:
    def make() -> str:
        text = json.dumps(policy_document(small_table()))
        assert old in text
        return text.replace(old, new, 1)

    return make


#: Cases beyond test_attack.py's ``POLICY_CASES`` and ``test_policy_json_attacks``.
BAD_POLICIES: dict[str, tuple[Callable[[], str], str]] = {
    "episodes 400 digits": (
        _policy_text('"episodes": 3', '"episodes": ' + "9" * 400),
        "episodes: must be an integer >= 0",
    ),
    "q_init 400 digits": (
        _policy_text('"q_init": -30.0', '"q_init": ' + "9" * 400),
        "q_init: must be a finite number",
    ),
    "n_sonar 1e999": (
        _policy_text('"n_sonar": 8', '"n_sonar": 1e999'),
        "encoding.n_sonar: must be an integer",
    ),
    "n_camera text": (
        _policy(lambda d: d["encoding"].__setitem__("n_camera", "x")),
        "encoding.n_camera: must be an integer",
    ),
    "encoding a list": (_policy(lambda d: d.__setitem__("encoding", [])), "encoding: must be"),
    "layout 64 fields": (
        _policy(lambda d: d["layout"].__setitem__("fields", [{"name": "A", "levels": 2}] * 64)),
        "layout: a 67-bit keyword does not fit 64 bits",
    ),
    "n_actions huge": (
        _policy(lambda d: d["layout"].__setitem__("n_actions", 10**30)),
        "layout.n_actions: must be an integer 1..64",
    ),
    "not UTF-8": (lambda: '{"format": "koolio-policy", "x": "\udcff"}', "not UTF-8"),
}
POLICY_COMMANDS = {
    "eval": ["eval", "--qtable", "bad.json", "--episodes", "1"],
    "export": ["export", "--qtable", "bad.json", "--out", "out.json"],
    "init": ["train", "--init-qtable", "bad.json", "--qtable", "new.qtable", "--episodes", "1"],
    "info": ["info", "--qtable", "bad.json"],
}


def _write_policy_text(path: Path, text: str) -> None:
    path.write_bytes(text.encode("utf-8", "surrogateescape"))


@pytest.mark.parametrize("case", sorted(BAD_POLICIES))
def test_malformed_policy_in_robot_runtime(here: Path, capsys, case: str) -> None:
    make, fragment = BAD_POLICIES[case]
    _write_policy_text(here / "bad.json", make())
    expect_error(
        capsys, here, ["bad.json"], "bad.json: ", fragment, run=rt.main, prefix="robot_runtime: "
    )


@pytest.mark.parametrize("command", sorted(POLICY_COMMANDS))
@pytest.mark.parametrize("case", sorted(BAD_POLICIES))
def test_malformed_policy_in_every_command(here: Path, capsys, case: str, command: str) -> None:
    make, fragment = BAD_POLICIES[case]
    _write_policy_text(here / "bad.json", make())
    expect_error(capsys, here, POLICY_COMMANDS[command], "bad.json: ", fragment)


@pytest.mark.parametrize(
    ("edit", "fragment"),
    [
        (lambda d: d.__setitem__("format", "x" * 100_000), "format: not a koolio-policy file"),
        (lambda d: d.__setitem__("version", [[0] * 10_000]), "version: unsupported version"),
        (lambda d: d["layout"].__setitem__("action_bits", "3" * 100_000), "layout.action_bits"),
        (lambda d: d["layout"]["fields"][0].__setitem__("bits", [1] * 10_000), "fields[0].bits"),
        (lambda d: d["encoding"]["sonar_groups"].append([99] * 10_000), "bad group [99, 99"),
    ],
    ids=["format", "version", "action_bits", "bits", "sonar_groups"],
)
def test_policy_errors_show_short_values(here: Path, capsys, edit, fragment: str) -> None:
    """A huge value in a policy is shown cut short: the error stays a readable line."""
    _write_policy_text(here / "bad.json", _policy(edit)())
    line = expect_error(capsys, here, ["bad.json"], fragment, run=rt.main, prefix="robot_runtime")
    assert len(line) < 200, line


@pytest.mark.parametrize("command", ["eval", "init"])
def test_policy_sensors_missing_a_key(here: Path, capsys, command: str) -> None:
    _write_policy_text(here / "bad.json", _policy(lambda d: d["sensors"].pop("sub_arcs"))())
    expect_error(
        capsys,
        here,
        POLICY_COMMANDS[command],
        "bad.json: sensors.sub_arcs: table made for none (not recorded), this run uses 11",
    )


# -- configurations, worlds, sweep specs -----------------------------------------------------
def _numbers(n: int) -> bytes:
    return b", ".join(b"%d" % i for i in range(n))


#: Cases beyond test_attack.py's ``test_bad_configurations``.
BAD_CONFIGS: dict[str, tuple[bytes, str]] = {
    "binary with NUL bytes": (b"\x7fELF\x02\x01\x01\x00", "line 1: control character U+007F"),
    "latin-1": ("learner: {alpha: 0.1}  # café\n".encode("latin-1"), "not a UTF-8 configuration"),
    "5000-digit integer": (
        b"episode: {max_steps: " + b"9" * 5000 + b"}\n",
        "Exceeds the limit (4300 digits)",
    ),
    "400-digit float": (b"learner: {alpha: " + b"9" * 400 + b".5}\n", "learner.alpha: must be"),
    "30 sonar groups": (
        b"sensors: {sonar: {sonar_sensors_deg: ["
        + _numbers(30)
        + b"], groups: ["
        + b", ".join(b"[%d]" % i for i in range(30))
        + b"]}}\n",
        "sensors: the keyword would need 75 bits",
    ),
    "clockless 10**9": (
        b"episode: {clockless_loop_count: 1000000000}\n",
        "episode.clockless_loop_count: must be <= 1,000,000 (steps per timer tick of the "
        "window), got 1,000,000,000",
    ),
    "reward -1e308": (
        b"rewards: {forward: -1.0e+308}\n",
        "rewards.forward: must be finite and at most 1e15",
    ),
    "randomize 400 digits": (  # the fuzz: dict values escaped the number checks
        b"realism: {randomize: {sonar.sigma_hit: [0, " + b"9" * 400 + b"]}}\n",
        "realism.randomize.sonar.sigma_hit[1]: must be finite and at most 1e15",
    ),
    "q_init 1e16": (b"learner: {q_init: 1e16}\n", "learner.q_init: must be finite and at most"),
    "a list of 5000": (
        b"sensors: {sonar: {thresholds: [" + _numbers(5000) + b"]}}\n",
        "sensors.sonar.thresholds: 5,000 entries (the limit is 64)",
    ),
    "not a mapping": (b"- 1\n- 2\n", "(top level): must be a mapping"),
}


@pytest.mark.parametrize("case", sorted(BAD_CONFIGS))
def test_malformed_configuration(here: Path, capsys, case: str) -> None:
    data, fragment = BAD_CONFIGS[case]
    (here / "bad.yaml").write_bytes(data)
    expect_error(capsys, here, ["info", "--config", "bad.yaml"], "bad.yaml: ", fragment)


#: Faults of any YAML file (the shared reader), tried on worlds and sweep specs.
BAD_YAML: dict[str, tuple[bytes, str]] = {
    "binary": (bytes(range(256)), "not a UTF-8"),
    "latin-1": ("realism: {}  # café\n".encode("latin-1"), "not a UTF-8"),
    "duplicate keys": (b"realism: {}\nrealism: {}\n", "line 2: not valid YAML: duplicate key"),
    "nested 50000 deep": (b"realism: " + b"[" * 50000 + b"]" * 50000 + b"\n", "nested more"),
    "alias": (b"a: &x [1]\nb: *x\n", "aliases (*name) are not supported"),
}


@pytest.mark.parametrize("case", sorted(BAD_YAML))
def test_malformed_world_and_sweep_spec(here: Path, capsys, case: str) -> None:
    data, fragment = BAD_YAML[case]
    (here / "bad.yaml").write_bytes(data)
    argv = ["train", "--world", "bad.yaml", "--episodes", "1", "--qtable", "w.qtable"]
    expect_error(capsys, here, argv, "bad.yaml: ", fragment)
    expect_error(capsys, here, ["sweep", "bad.yaml"], "bad.yaml: ", fragment)


def test_exponent_without_a_dot_is_a_number_in_worlds_and_sweep_specs(here: Path) -> None:
    """YAML 1.1 (PyYAML) reads 1e-9 as text; every project file reads a number."""
    (here / "w.yaml").write_text("sensors: {noise: {scale: 5E-1}}\n")
    assert apply_world(Config(), "w.yaml").sensors.noise.scale == 0.5
    (here / "s.yaml").write_text("episodes: 10\ncompetence: 9e-1\n")
    assert load_spec("s.yaml").competence == 0.9


# -- arenas ----------------------------------------------------------------------------------
def _arena(**change: object) -> str:
    data = yaml.safe_load(ROOM)
    data.update(change)
    return yaml.safe_dump(data, sort_keys=False)


def test_names_that_look_like_numbers_survive_a_save(here: Path) -> None:
    """Arenas read YAML 1.2 numbers, so the writer quotes a goal named ``1e3`` (YAML 1.1
    would write it bare, and it would read back as the number 1000.0)."""
    from dataclasses import replace

    room = load_arena("room.yaml")
    names = ["1e3", "5E-1", ".5", "1_000", "0x1f", "+12", "-.inf", "317"]
    goals = tuple(
        replace(room.goals[0], name=n, at=(100.0 + i, 150.0)) for i, n in enumerate(names)
    )
    arena = replace(room, goals=goals, active_goal="1e3")
    (here / "named.yaml").write_text(arena_to_yaml(arena))
    assert load_arena("named.yaml").goal_names() == names


BAD_ARENAS: dict[str, tuple[Callable[[], str], str]] = {
    "400-digit float coordinate": (
        lambda: ROOM.replace("at: [48, 48]", "at: [" + "9" * 400 + ".5, 48]"),
        "start.at: not a finite number",
    ),
    "too many goals": (
        lambda: _arena(
            goals=[{"name": f"g{i}", "at": [100, 100]} for i in range(MAX_ENTRIES + 1)],
            active_goal="g0",
        ),
        f"goals: {MAX_ENTRIES + 1:,} entries (the limit is {MAX_ENTRIES:,})",
    ),
    "binary": (lambda: "name: x\n\x00\x01\x02", "line 2: control character U+0000: not a text"),
}


@pytest.mark.parametrize("case", sorted(BAD_ARENAS))
def test_malformed_arena(here: Path, capsys, case: str) -> None:
    make, fragment = BAD_ARENAS[case]
    (here / "bad.yaml").write_text(make(), encoding="utf-8")
    expect_error(capsys, here, ["check-arena", "bad.yaml"], "bad.yaml: ", fragment)


def test_points_in_all_are_bounded() -> None:
    """Each polygon within its limit, all of them together beyond theirs."""
    ring = [[i, 0] for i in range(MAX_POLYGON_POINTS)]
    data = {**yaml.safe_load(ROOM), "walls": ring, "obstacles": [ring, ring[:2]]}
    limit = f"the limit is {MAX_TOTAL_POINTS:,}"
    with pytest.raises(ArenaError, match=f"a.yaml: 20,006 points in walls, .*{limit}"):
        parse_arena(data, "a.yaml")


def test_a_huge_arena_is_refused_by_its_size_in_train(here: Path, capsys) -> None:
    with open(here / "big.yaml", "wb") as fh:  # sparse: 50 MB on paper, nothing on disk
        fh.truncate(50 * 1024 * 1024)
    argv = ["train", "--arena", "big.yaml", "--episodes", "1", "--qtable", "t.qtable"]
    expect_error(capsys, here, argv, "big.yaml: too large: 50 MiB")


def test_a_closed_room_checks_evaluates_and_opens_in_the_window(here: Path, capsys) -> None:
    """Zero markers (the paper: "any number"): check-arena, eval and the window."""
    data = yaml.safe_load(ROOM)
    del data["end_of_world"]
    (here / "closed.yaml").write_text(yaml.safe_dump(data, sort_keys=False))
    assert cli.main(["check-arena", "closed.yaml"]) == 0
    assert "0 end-of-world markers" in capsys.readouterr().out
    argv = ["--arena", "closed.yaml", "--qtable", "c.qtable", "--log", "c.csv"]
    assert cli.main(["view", *argv, "--steps", "30"]) == 0
    argv = ["eval", "--arena", "closed.yaml", "--qtable", "c.qtable", "--episodes", "1"]
    assert cli.main(argv) == 0 and (here / "c.csv").exists()


# -- value flags and argparse -------------------------------------------------------------------
#: Cases beyond test_attack.py's ``test_bad_flags_are_one_line_errors``.
BAD_FLAGS: dict[str, tuple[list[str], str]] = {
    "eval --seed -1": (["eval", "--seed", "-1", "--qtable", "good.qtable"], "--seed: must be"),
    "view --seed -1": (["view", "--seed", "-1", "--steps", "1"], "--seed: must be >= 0"),
    "--episodes missing": (["train", "--episodes"], "--episodes: expected one argument"),
    "view --size small": (["view", "--size", "10x10", "--steps", "1"], "smaller than"),
    "view --screenshot-every 0": (
        ["view", "--screenshot-every", "0", "frames", "--steps", "1"],
        "K must be >= 1",
    ),
    "view --screenshot-every x": (
        ["view", "--screenshot-every", "x", "frames", "--steps", "1"],
        "K must be an integer",
    ),
    "view --screenshot-every -1": (
        ["view", "--screenshot-every", "-1", "frames", "--steps", "1"],
        "K must be >= 1",
    ),
    "view --speed nan": (["view", "--speed", "nan", "--steps", "1"], "--speed"),
}


@pytest.mark.parametrize("case", sorted(BAD_FLAGS))
def test_bad_value_flag(here: Path, capsys, case: str) -> None:
    argv, fragment = BAD_FLAGS[case]
    expect_error(capsys, here, argv, fragment)
    assert not (here / "runs").exists()


def test_argparse_errors_name_the_subcommand(here: Path, capsys) -> None:
    line = expect_error(capsys, here, ["train", "--robots"], "--robots")
    assert line.endswith("(see koolio-pm train --help)")


def test_view_log_in_latin_1(here: Path, capsys) -> None:
    (here / "old.csv").write_bytes("é,1\n".encode("latin-1"))
    argv = ["view", "--log", "old.csv", "--qtable", "v.qtable", "--steps", "1"]
    expect_error(capsys, here, argv, "old.csv: not a UTF-8 training log")
