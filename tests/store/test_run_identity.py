"""One run identity: every command checks a table through ``run_identity.check`` with its
purpose, by the rules docs/robustness.md shows; a table records its provenance once and
its log names its run; tables of the previous release load."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from koolio_pymunk.apps.cli import main
from koolio_pymunk.store import run_identity
from koolio_pymunk.store.config import Config, load_config
from koolio_pymunk.store.episode_log import RUN_LINE, log_rows
from koolio_pymunk.store.errors import QTableError
from koolio_pymunk.store.qtable import QTable, load_qtable
from koolio_pymunk.store.run_identity import PURPOSES, RULES, RunIdentity
from koolio_pymunk.task.env import KoolioEnv

ROOT = Path(__file__).resolve().parents[2]
RELEASE = Path(__file__).parent / "data" / "release-0.1.0"
SHORT = "episode: {max_steps: 40}\n"


@pytest.fixture
def here(tmp_path, monkeypatch) -> Path:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "c.yaml").write_text(SHORT)
    return tmp_path


def _train(*extra: str, qtable: str = "t.qtable", log: str = "t.csv") -> int:
    argv = ["train", "--arena", "room", "--config", "c.yaml", "--quiet", "--seed", "3"]
    return main([*argv, "--qtable", qtable, "--log", log, *extra])


# -- every command goes through one check ------------------------------------------------------

COMMANDS = {
    "train (resume)": (["train", "--episodes", "4"], {"resume"}),
    "train --init-qtable": (
        ["train", "--episodes", "4", "--init-qtable", "t.qtable", "--qtable", "n.qtable",
         "--log", "n.csv"],
        {"start", "resume"},  # the new table made from it, then trained
    ),
    "train --eval-every (a best table kept)": (
        ["train", "--episodes", "8", "--eval-every", "2", "--eval-episodes", "2"],
        {"resume", "keep"},
    ),
    "eval": (["eval", "--episodes", "2"], {"score"}),
    "view --greedy": (["view", "--greedy", "--episodes", "1"], {"watch"}),
    "view --learn": (["view", "--learn", "--episodes", "1"], {"resume"}),
    "export": (["export", "--out", "p.json"], {"export"}),
    "transfer --qtable": (
        ["transfer", "--dr-qtable", "t.qtable", "--robot-episodes", "1", "--eval-episodes",
         "1", "--eval-every", "1", "--no-plot", "--quiet", "--out", "tr"],
        {"transfer"},
    ),
    "info --qtable": (["info"], {"inspect"}),
}  # fmt: skip


@pytest.mark.parametrize("name", list(COMMANDS))
def test_every_command_checks_its_table_through_run_identity(here, monkeypatch, name) -> None:
    """Each command that reads a table calls :func:`run_identity.check` with its purpose
    (and no other checks exist to call: the old ones are gone from the package)."""
    assert _train("--episodes", "2") == 0
    if "eval-every" in name:  # a best table to keep beside it
        assert _train("--episodes", "4", "--eval-every", "2", "--eval-episodes", "2") == 0
    seen: list[tuple[str, str]] = []
    real = run_identity.check

    def recorded(table, run, purpose, source, *args, **kwargs):
        seen.append((purpose, Path(source).name))
        return real(table, run, purpose, source, *args, **kwargs)

    monkeypatch.setattr(run_identity, "check", recorded)
    argv, purposes = COMMANDS[name]
    command, rest = argv[0], argv[1:]
    common = ["--config", "c.yaml", "--qtable", "t.qtable"]
    if command in ("train", "view", "eval", "transfer"):
        common = ["--arena", "room", "--seed", "3", *common]
    if command in ("train", "view"):
        common += ["--log", "t.csv"]
    if command == "train":
        common.append("--quiet")
    if "--init-qtable" in rest:  # its own --qtable and --log come last and win
        common = [c for c in common if c not in ("--qtable", "t.qtable", "--log", "t.csv")]
    assert main([command, *common, *rest]) == 0
    assert {p for p, _ in seen} == purposes, seen
    assert all(p in PURPOSES for p, _ in seen)


def test_the_old_checks_are_gone() -> None:
    """The identity lives in one module: the functions it replaced are in no other."""
    gone = re.compile(
        r"^def (check_compatible|check_record|check_rule|check_algorithm|attach|adopt|"
        r"run_record|table_arena_goal|check_not_best|is_best_table|warn_table|sensor_signature"
        r"|algorithm_record|arena_goal|describe_goal|describe_world)\(",
        re.M,
    )
    for path in (ROOT / "koolio_pymunk").rglob("*.py"):
        if path.name == "run_identity.py":
            continue
        assert not gone.search(path.read_text()), path


def test_the_rules_table_is_the_one_docs_robustness_shows() -> None:
    """docs/robustness.md shows :data:`RULES` cell for cell."""
    text = (ROOT / "docs" / "robustness.md").read_text()
    header = re.search(r"^\| field \|(.+)\|$", text, re.M)
    assert header, "docs/robustness.md has no table of the identity's rules"
    purposes = [c.strip() for c in header.group(1).split("|")]
    assert purposes == list(PURPOSES)
    rows = {}
    for line in text[header.end() :].splitlines()[2:]:
        if not line.startswith("| "):
            break
        cells = [c.strip().strip("`") for c in line.strip("|").split("|")]
        rows[cells[0]] = dict(zip(purposes, cells[1:]))
    assert set(rows) == set(RULES)
    for field, row in rows.items():
        for purpose, cell in row.items():
            assert cell == RULES[field].get(purpose, "."), (field, purpose)


# -- the rules, field by field -------------------------------------------------------------------


def _outcome(table: QTable, run, purpose: str) -> str:
    said: list[str] = []
    try:
        run_identity.check(table, run, purpose, f"{purpose}-{id(table)}.qtable", said.append)
    except QTableError:
        return "refuse"
    return "warn" if said else "."


def _trained(env: KoolioEnv, **meta) -> QTable:
    table = run_identity.new_table(RunIdentity.of_run(env), seed=0)
    table.meta["episodes"] = 5
    table.row(7)[:] = [1.0, 2.0, 3.0, 4.0, 5.0]
    table.meta.update(meta)
    return table


DIFFERENT = {
    "goal": lambda env: _trained(env, goal="random"),
    "world": lambda env: _trained(env, world="koolio-real"),
    "algorithm": lambda env: _trained(env, algorithm={"name": "q", "no_undo": True}),
    "no_undo": lambda env: _trained(
        env, algorithm={"name": "qlambda", "trace_cutoff": 0.01, "trace_decay": 0.7}
    ),
    "sensors": lambda env: _trained(env, sensors={"sonar_arc_deg": 1.0}),
    "arena": lambda env: _trained(env, arena={"name": "elsewhere", "sha256": "0" * 16}),
    "empty": lambda env: run_identity.new_table(RunIdentity.of_run(env), seed=0),
}


@pytest.mark.parametrize("field", list(DIFFERENT))
@pytest.mark.parametrize("purpose", [p for p in PURPOSES if p != "inspect"])
def test_a_table_that_differs_in_one_field_is_refused_or_said_as_the_rules_say(
    field, purpose
) -> None:
    """A table made for this run but for one field is refused, warned about or taken, per
    purpose, as :data:`RULES` (and docs/robustness.md) say; the same table otherwise
    equal passes silently."""
    env = KoolioEnv("room", config=load_config(overrides={"episode": {"max_steps": 40}}))
    table = DIFFERENT[field](env)
    assert _outcome(table, env, purpose) == RULES[field].get(purpose, ".")
    assert _outcome(_trained(env), env, purpose) == "."


def test_keep_refuses_the_best_table_of_another_run() -> None:
    env = KoolioEnv("room")
    best = _trained(env)
    with pytest.raises(QTableError, match="the best table of another run"):
        run_identity.check(best, env, "keep", "t.best.qtable", run_id="0123456789abcdef")
    run_identity.check(best, env, "keep", "t.best.qtable", run_id=best.meta["run_id"])


def test_an_identity_without_an_arena_compares_no_goal() -> None:
    """``export`` and ``info`` know no arena: a table's goal is not compared."""
    env = KoolioEnv("room")
    table = _trained(env, goal="random")
    said: list[str] = []
    run_identity.check(table, RunIdentity.of_config(Config()), "export", "t.qtable", said.append)
    assert said == []


# -- provenance and the run id -------------------------------------------------------------------


def test_a_new_table_records_where_it_came_from_once(here) -> None:
    assert _train("--episodes", "3") == 0
    prov = load_qtable("t.qtable").meta["provenance"]
    assert prov["command"] == [
        *("train", "--arena", "room", "--config", "c.yaml", "--quiet", "--seed", "3"),
        *("--qtable", "t.qtable", "--log", "t.csv", "--episodes", "3"),
    ]
    assert prov["configuration"]["episode"]["max_steps"] == 40
    assert prov["koolio_pymunk"] and prov["numpy"] and prov["pymunk"] and prov["python"]
    git = prov.get("git")
    if (ROOT / ".git").exists() and shutil.which("git"):
        assert re.fullmatch(r"[0-9a-f]{40}", git["commit"]) and isinstance(git["changed"], bool)
    first = load_qtable("t.qtable").meta["run_id"]
    assert _train("--episodes", "6") == 0  # a resume: the record stays the creation's
    again = load_qtable("t.qtable").meta
    assert again["provenance"] == prov and again["run_id"] == first


def test_info_shows_the_provenance(here, capsys) -> None:
    assert _train("--episodes", "3") == 0
    capsys.readouterr()
    assert main(["info", "--qtable", "t.qtable", "--config", "c.yaml"]) == 0
    out = capsys.readouterr().out
    rid = load_qtable("t.qtable").meta["run_id"]
    assert f"run id {rid}, learned content " in out
    assert "command: koolio-pm train --arena room --config c.yaml" in out
    assert "configuration: the one given here, setting for setting" in out
    assert main(["info", "--qtable", "t.qtable"]) == 0  # the defaults: max_steps differs
    assert "configuration: differs from the one given here in episode.max_steps" in (
        capsys.readouterr().out
    )


def test_the_same_run_from_another_command_line_learns_the_same(here) -> None:
    """The learned digest and the run id leave out where a run came from: the same seeded
    run under other file names has them equal, and only its recorded command differs."""
    assert _train("--episodes", "3") == 0
    assert _train("--episodes", "3", qtable="u.qtable", log="u.csv") == 0
    a, b = load_qtable("t.qtable"), load_qtable("u.qtable")
    assert a.meta["provenance"]["command"] != b.meta["provenance"]["command"]
    assert a.meta["run_id"] == b.meta["run_id"]
    assert run_identity.learned_digest(a) == run_identity.learned_digest(b)
    assert Path("t.csv").read_bytes() == Path("u.csv").read_bytes()
    assert _train("--episodes", "3", "--seed", "4", qtable="v.qtable", log="v.csv") == 0
    c = load_qtable("v.qtable")
    assert c.meta["run_id"] != a.meta["run_id"]
    assert run_identity.learned_digest(c) != run_identity.learned_digest(a)


def test_a_log_names_its_run_and_another_runs_log_is_refused(here, capsys) -> None:
    assert _train("--episodes", "3") == 0
    rid = load_qtable("t.qtable").meta["run_id"]
    assert Path("t.csv").read_text().splitlines()[0] == RUN_LINE + rid
    assert len(log_rows("t.csv")) == 3
    assert _train("--episodes", "3", "--seed", "4", qtable="v.qtable", log="v.csv") == 0
    shutil.copy("v.csv", "w.csv")
    shutil.copy("t.qtable", "w.qtable")
    before = Path("w.csv").read_bytes()
    capsys.readouterr()
    assert _train("--episodes", "5", qtable="w.qtable", log="w.csv") == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("koolio-pm: error: w.csv: line 1: the log of run ") and (
        f"is run {rid}: a log of another run" in err
    )
    assert Path("w.csv").read_bytes() == before


# -- the previous release's tables -----------------------------------------------------------------


def test_tables_of_the_previous_release_load_with_their_identity(here, capsys) -> None:
    """Tables and logs written by 0.1.0 (no run id, no provenance, one-step Q the default
    learner) read with their identity from the old header: scored, inspected, resumed
    with the learner they record (their logs stay without a run line), and refused for
    another learner in one line that says what to do."""
    for name in ("plain.qtable", "plain.csv", "real309.qtable", "real309.csv"):
        shutil.copy(RELEASE / name, here / name)
    shutil.copy(RELEASE / "c.yaml", here / "c.yaml")
    plain = RunIdentity.of_table(load_qtable("plain.qtable"), "plain.qtable")
    assert (plain.algorithm_name, plain.no_undo, plain.goal, plain.world) == (
        "q",
        False,
        None,
        "ideal",
    )
    assert plain.run_id is None and plain.episodes == 6
    real = RunIdentity.of_table(load_qtable("real309.qtable"), "real309.qtable")
    assert (real.goal, real.world) == ("309", "koolio-real")
    capsys.readouterr()
    assert main(["info", "--qtable", "plain.qtable"]) == 0
    assert "provenance: not recorded" in capsys.readouterr().out
    room = ["--arena", "room", "--qtable", "plain.qtable"]
    assert main(["eval", *room, "--config", "c.yaml", "--episodes", "2"]) == 2
    err = capsys.readouterr().err
    assert "learner.no_undo: table learned choosing among all actions" in err
    assert "give eval the --config it was learned with" in err
    assert main(["eval", *room, "--config", "one-step-q", "--episodes", "2"]) == 0
    assert capsys.readouterr().err == ""
    resume = ["train", *room, "--config", "one-step-q", "--log", "plain.csv", "--quiet"]
    assert main([*resume, "--episodes", "8", "--seed", "1"]) == 0
    after = load_qtable("plain.qtable").meta
    assert after["episodes"] == 8 and "run_id" not in after and "provenance" not in after
    assert Path("plain.csv").read_text().startswith("episode,")  # no run line: none to name
    assert [r["episode"] for r in log_rows("plain.csv")] == [str(k) for k in range(8)]
    hall = ["eval", "--arena", "hallway", "--config", "one-step-q", "--world", "koolio-real"]
    hall += ["--qtable", "real309.qtable", "--episodes", "1"]
    assert main([*hall, "--goal", "309"]) == 0
    assert capsys.readouterr().err == ""
    assert main(hall) == 0
    assert "trained for goal 309, scored here for goal 311" in capsys.readouterr().err
