"""Log rows read back: ASCII numbers only, bounded lines; a torn last row, however hostile,
is moved to ``<log>.removed`` by a writer and left out by a reader; a complete malformed
row is one line naming it, in ``train``, ``view`` and ``plot`` alike (issue #21)."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest
from inputs import expect_error

from koolio_pymunk.apps import cli
from koolio_pymunk.store.config import EpsilonSchedule
from koolio_pymunk.store.episode_log import (
    RUN_LINE,
    LogWriter,
    RowRules,
    ascii_float,
    ascii_int,
    log_rows,
    schedule_gives,
)
from koolio_pymunk.store.errors import KoolioError
from koolio_pymunk.store.qtable import load_qtable

ENV = ["--arena", "room", "--config", "tiny.yaml"]
FILES = ["--qtable", "q.qtable", "--log", "q.csv"]
TRAIN = ["train", *ENV, "--episodes", "3", "--quiet", *FILES]  # a total: one more episode
VIEW = ["view", *ENV, "--learn", "--steps", "2", *FILES]
PLOT = ["plot", "--log", "q.csv", "--out", "c.png"]
HUGE = "x" * 200_000


@pytest.fixture
def work(tiny_run, tmp_path, monkeypatch) -> Path:
    shutil.copy(tiny_run / "q.qtable", tmp_path / "q.qtable")
    shutil.copy(tiny_run / "log.csv", tmp_path / "q.csv")
    shutil.copy(tiny_run / "tiny.yaml", tmp_path / "tiny.yaml")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    return tmp_path


def _append(work: Path, text: str) -> str:
    with open(work / "q.csv", "a", encoding="utf-8") as fh:
        fh.write(text)
    return (work / "q.csv").read_text(encoding="utf-8")


@pytest.mark.parametrize("torn", ["²,-5", "2" + HUGE, f"2,{HUGE}", '2,"-5', "\x00\x01"])
@pytest.mark.parametrize("argv", [TRAIN, VIEW], ids=["train", "view"])
def test_a_hostile_torn_row_is_moved_like_any_torn_row(work, capsys, argv, torn):
    before = (work / "q.csv").read_text(encoding="utf-8")
    _append(work, torn)
    assert cli.main(argv) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("warning: q.csv: moved 1 row"), err
    assert (work / "q.csv").read_text(encoding="utf-8").startswith(before)
    removed = (work / "q.csv.removed").read_text(encoding="utf-8").split("\n")
    assert removed[1] == torn  # nothing lost


@pytest.mark.parametrize("torn", ["²,-5", f"2,{HUGE}"])
def test_plot_leaves_a_torn_row_out(work, capsys, torn):
    _append(work, torn)
    assert cli.main(PLOT) == 0
    assert "plot: 2 episodes" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("row", "words"),
    [
        ("²,-5,3,0,goal,0,0.1,201", "line 5: episode: not an integer >= 0 in digits 0-9: '²'"),
        ("١٢,-5,3,0,goal,0,0.1,201", "episode: not an integer"),
        ("2,-5,3,0,goal,0,0.1,201" + HUGE, "line 5: 200,023 characters (a log line has at most"),
        (f"2,-5,3,0,goal,0,0.1,{HUGE}", "line 5: 200,020 characters"),
        ("2,nan,3,0,goal,0,0.1,201", "line 5: reward: not a finite decimal number: 'nan'"),
        ("2,1e999,3,0,goal,0,0.1,201", "reward: not a finite decimal number"),
        ("2,-5, 3,0,goal,0,0.1,201", "steps: not an integer >= 0"),
        ("2,-5,3,1_0,goal,0,0.1,201", "bumps: not an integer >= 0"),
        ("2,-5,3,0,goal,yes,0.1,201", "rescued: not 0 or 1"),
    ],
)
@pytest.mark.parametrize("argv", [TRAIN, VIEW], ids=["train", "view"])
def test_a_complete_malformed_row_is_one_line(work, capsys, argv, row, words):
    _append(work, row + "\n")
    expect_error(capsys, work, argv, "q.csv: ", words)


@pytest.mark.parametrize(
    ("row", "words"),
    [
        ("²,-5,3,0,goal,0,0.1,201", "line 5: episode: not a number: '²'"),
        ("2,٣,3,0,goal,0,0.1,201", "reward: not a number"),
        (f"2,-5,3,0,goal,0,0.1,{HUGE}", "line 5: 200,020 characters"),
    ],
)
def test_plot_refuses_a_complete_malformed_row(work, capsys, row, words):
    _append(work, row + "\n")
    expect_error(capsys, work, PLOT, "q.csv: ", words)


def test_log_rows_checks_every_complete_row(work):
    _append(work, "2,-5,3,0,goal,0,0.1,201\n3,-1")
    rows = log_rows(work / "q.csv")
    assert [r["episode"] for r in rows] == ["0", "1", "2"]  # the torn row left out
    _append(work, ",3,0,goal,0,0.1²,201\n")
    with pytest.raises(KoolioError, match=r"q\.csv: line 6: epsilon: not a finite decimal"):
        log_rows(work / "q.csv")


def test_a_writer_refuses_before_it_writes(work):
    text = _append(work, "2,-5,3,0,goal,0,0.1,201\n³,-5,3,0,goal,0,0.1,201\n")
    with pytest.raises(KoolioError, match=r"q\.csv: line 6: episode"):
        LogWriter(work / "q.csv", episodes=9, table=work / "q.qtable")
    assert (work / "q.csv").read_text(encoding="utf-8") == text
    assert not (work / "q.csv.removed").exists()


def test_ascii_numbers():
    assert [ascii_int(t) for t in ("0", "17", "9" * 18)] == [0, 17, 10**18 - 1]
    assert [ascii_int(t) for t in ("9" * 19, "", "+1", "1.0", "٣", "1 ")] == [None] * 6
    assert [ascii_float(t) for t in ("-0.5", "1e-05", ".5", "3.", "+2")] == [
        -0.5,
        1e-05,
        0.5,
        3.0,
        2.0,
    ]
    bad = ("inf", "-inf", "NaN", "1e400", "1_000.5", "٣.٥", " 1", "0x10", "1e", "")
    assert [ascii_float(t) for t in bad] == [None] * len(bad)


def test_a_goal_name_is_bounded_as_log_fields_are(tmp_path):
    """A goal's name goes into every row: a name longer than a log line could hold is
    refused where the arena is read."""
    from koolio_pymunk.world.arena import MAX_NAME_CHARS, ArenaError, load_arena

    root = Path(__file__).resolve().parents[2]
    text = (root / "arenas" / "room.yaml").read_text(encoding="utf-8")
    name = load_arena("room").goals[0].name
    long = tmp_path / "long.yaml"
    long.write_text(text.replace(f"name: '{name}'", f"name: '{'g' * (MAX_NAME_CHARS + 1)}'"))
    assert long.read_text() != text
    with pytest.raises(ArenaError, match=r"name: 201 characters \(a name has at most 200\)"):
        load_arena(long)


def test_a_malformed_row_is_refused_before_the_table_is_read(work, capsys):
    """One line, not a warning about the table's backup and then the line: the writer's
    rows are checked with its header, before the table is read."""
    data = (work / "q.qtable").read_bytes()
    (work / "q.qtable").write_bytes(data[: len(data) // 2])  # torn: its backup would be used
    _append(work, "2,-5,3,0,goal,0,0.1,201\n²,-5,3,0,goal,0,0.1,201\n")
    expect_error(capsys, work, TRAIN, "q.csv: line 6: episode: not an integer")


def test_a_log_that_cannot_take_its_first_row_is_refused_before_anything(work, capsys):
    """Found by the fuzzer: a log that is a link to a missing file (or in a folder that
    cannot be made) failed at its first row, after the table was saved: out of step."""
    (work / "n.csv").symlink_to("nowhere/at/all")
    argv = [*TRAIN[:-4], "--qtable", "q.qtable", "--log", "n.csv"]
    expect_error(capsys, work, argv, "n.csv: is a link to a missing file (nowhere/at/all)")
    argv[-1] = "tiny.yaml/n.csv"
    expect_error(capsys, work, argv, "cannot create the folder tiny.yaml: a file is in the way")


@pytest.mark.skipif(not hasattr(os, "statvfs"), reason="POSIX statvfs")
def test_a_read_only_file_system_is_named_as_such(tmp_path, monkeypatch):
    """A new log in a folder that cannot be written: "read-only file system" when the
    folder's file system is mounted read-only (as ``export`` says it), "permission
    denied" otherwise (both read "permission denied" before: newcomer audit)."""
    from koolio_pymunk.store.episode_log import check_log_path
    from koolio_pymunk.store.errors import FileError

    monkeypatch.setattr(os, "access", lambda *a, **k: False)
    with pytest.raises(FileError, match=r"new\.csv: cannot write: permission denied \("):
        check_log_path(tmp_path / "new.csv", extra_fields=())
    real = os.statvfs(tmp_path)

    class ReadOnly:
        f_flag = real.f_flag | os.ST_RDONLY

    monkeypatch.setattr(os, "statvfs", lambda p: ReadOnly())
    with pytest.raises(FileError, match=r"new\.csv: cannot write: read-only file system \("):
        check_log_path(tmp_path / "new.csv", extra_fields=())


# -- another run's log, a torn row of an episode the table holds, a log with no rows --------
OTHER = "episode: {max_steps: 30}\nlearner: {epsilon: {start: 0.01, decay_episodes: 0}}\n"


def test_the_log_of_another_table_ahead_of_it_is_refused(work, capsys):
    """Audit: ``--log`` naming another table's log, ahead of this table: its rows moved
    aside as if this table's, the rest appended after them (two runs in one log). Their
    epsilons are no value of this run's schedule: refused, nothing written."""
    (work / "m.yaml").write_text(OTHER)
    mine = ["train", "--arena", "room", "--config", "m.yaml", "--quiet", "--qtable", "m.qtable"]
    assert cli.main([*mine, "--episodes", "1"]) == 0  # m.qtable: 1 episode, log m.csv
    capsys.readouterr()
    line = expect_error(capsys, work, [*mine, "--log", "q.csv", "--episodes", "3"])
    theirs = (work / "q.csv").read_text().split("\n")[0].removeprefix(RUN_LINE)
    assert line == (
        f"koolio-pm: error: q.csv: line 1: the log of run {theirs}, and the Q-table m.qtable "
        f"is run {load_qtable(work / 'm.qtable').meta['run_id']}: a log of another run; give "
        "another --log"
    )
    # a log and a table made before run ids: told apart by the log's epsilons
    shutil.copy(work / "q.csv", work / "old.csv")
    shutil.copy(work / "m.qtable", work / "old.qtable")
    _forget_run_ids(work / "old.csv", work / "old.qtable")
    old = [*mine[:-1], "old.qtable", "--log", "old.csv", "--episodes", "3"]
    line = expect_error(capsys, work, old)
    assert line == (
        "koolio-pm: error: old.csv: line 3: episode 1 has epsilon 0.149067, which this run's "
        "learner.epsilon never gives: a row of another run, ahead of the Q-table old.qtable "
        "(1 episode); give another --log, or resume with the configuration that wrote it"
    )
    # the same table's own log ahead of it (a stop between two saves) moves as before
    shutil.copy(work / "m.qtable", work / "m1.qtable")
    assert cli.main([*mine, "--episodes", "3"]) == 0
    shutil.copy(work / "m1.qtable", work / "m.qtable")
    assert cli.main([*mine, "--episodes", "4"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "warning: m.csv: moved 2 rows (episodes 1..2) to m.csv.removed: the Q-table m.qtable "
        "holds 1 episode (it was saved before them); they run again"
    ]
    assert [r["episode"] for r in log_rows(work / "m.csv")] == ["0", "1", "2", "3"]


def _forget_run_ids(log: Path, table: Path | None = None) -> None:
    """Make ``log`` (and ``table``) as a version before run ids wrote them."""
    text = log.read_text(encoding="utf-8")
    if text.startswith(RUN_LINE):
        log.write_text(text.split("\n", 1)[1], encoding="utf-8")
    if table is not None:
        t = load_qtable(table)
        for key in ("run_id", "provenance"):
            t.meta.pop(key, None)
        table.write_bytes(t.to_bytes())
        table.with_name(table.name + ".bak").unlink(missing_ok=True)


def _writer(episodes: int, rules: RowRules) -> list[str]:
    """Bring q.csv (in the working folder) in step with a table of ``episodes`` episodes
    under ``rules``; the warnings."""
    said: list[str] = []
    LogWriter("q.csv", episodes, table="q.qtable", warn=said.append, rules=rules).close()
    return said


def test_rows_ahead_take_any_value_of_the_schedule(work):
    """Many robots log an episode with the epsilon of its start's number, not its own:
    a row ahead passes with any value the schedule gives (here episode 2 with episode
    1's), and fails with one it never gives (half way between two episodes' values)."""
    schedule = EpsilonSchedule(start=0.15, end=0.01, decay_episodes=600)
    _forget_run_ids(work / "q.csv")  # the schedule tells only logs without a run line
    _append(work, "2,-5,30,0,truncated,0,0.149767,201\n3,-5,30,0,truncated,0,0.01,201\n")
    text = (work / "q.csv").read_text(encoding="utf-8")
    mid = "3,-5,30,0,truncated,0,0.14965,201\n"
    _append(work, mid)
    with pytest.raises(KoolioError, match=r"^q\.csv: line 6: episode 3 has epsilon 0\.14965,"):
        _writer(2, RowRules(epsilon=schedule))
    (work / "q.csv").write_text(text, encoding="utf-8")
    assert _writer(2, RowRules(epsilon=schedule)) == [
        "q.csv: moved 2 rows (episodes 2..3) to q.csv.removed: the Q-table q.qtable holds "
        "2 episodes (it was saved before them); they run again"
    ]
    assert schedule_gives(EpsilonSchedule(0.3, 0.0, 10**9), "0.299999")  # 1e-10 a step
    assert not schedule_gives(EpsilonSchedule(0.3, 0.0, 10**9), "0.31")


def test_a_table_with_a_goal_refuses_rows_of_another_goal(work):
    """A table that records a goal keeps it for life (run_identity's rules): every row of
    its log names it, kept rows too."""
    rid = load_qtable(work / "q.qtable").meta["run_id"]
    before = (work / "q.csv").read_text(encoding="utf-8")
    with pytest.raises(KoolioError) as info:
        _writer(2, RowRules(goal="302", run_id=rid))
    assert str(info.value) == (
        "q.csv: line 3: episode 0 was logged for goal 201, and the Q-table q.qtable is "
        "trained for goal 302: a row of another run; give another --log"
    )
    assert (work / "q.csv").read_text(encoding="utf-8") == before
    assert _writer(2, RowRules(goal="201", run_id=rid)) == []


@pytest.mark.parametrize(
    ("torn", "warning"),
    [
        (None, "q.csv: its last row was cut short (episode 1, a write interrupted): moved to "
         "q.csv.removed; the Q-table q.qtable holds episode 1, whose row is lost"),
        ("2,-5,3", "q.csv: moved 1 row (episode 2) to q.csv.removed: the Q-table q.qtable "
         "holds 2 episodes (it was saved before them); they run again"),
        ("1", "q.csv: moved 1 row (a torn row) to q.csv.removed: the Q-table q.qtable "
         "holds 2 episodes (it was saved before them); they run again"),
    ],
    ids=["held", "ahead", "no-number"],
)  # fmt: skip
def test_a_torn_row_says_whether_its_episode_runs_again(work, capsys, torn, warning):
    """Audit: ``truncate -s -5`` on the log cut the row of an episode the table holds;
    the warning said it runs again (it does not: its row is lost). The episode number
    before the first comma decides; a row cut before it is unknown, as before."""
    text = (work / "q.csv").read_text(encoding="utf-8")
    if torn is None:
        (work / "q.csv").write_text(text[:-5], encoding="utf-8")
        torn = text[:-5].split("\n")[-1]
    else:
        _append(work, torn)
    assert cli.main(TRAIN) == 0
    assert capsys.readouterr().err.strip().splitlines() == [f"warning: {warning}"]
    want = ["0", "2"] if torn.startswith("1,") else ["0", "1", "2"]
    assert [r["episode"] for r in log_rows(work / "q.csv")] == want
    assert (work / "q.csv.removed").read_text(encoding="utf-8").split("\n")[1] == torn


@pytest.mark.parametrize(
    ("state", "why"),
    [("missing", "it is missing"), ("empty", "it is empty"), ("header", "it holds no rows")],
)
def test_a_log_without_rows_beside_a_trained_table_warns(work, capsys, state, why):
    """Audit: a deleted or emptied log resumed silently at the table's count, while a log
    lacking only its last rows warned. The same warning now, one line; training goes on.
    A table the run makes itself (``--init-qtable``) starts its new log quietly."""
    header = "\n".join((work / "q.csv").read_text(encoding="utf-8").split("\n")[:2])
    content = {"missing": None, "empty": "", "header": header + "\n"}[state]
    if content is None:
        (work / "q.csv").unlink()
    else:
        (work / "q.csv").write_text(content, encoding="utf-8")
    assert cli.main(TRAIN) == 0
    assert capsys.readouterr().err.strip().splitlines() == [
        f"warning: q.csv: lacks the rows of episodes 0..1 ({why}; the Q-table q.qtable holds "
        "2 episodes); new rows start at episode 2"
    ]
    assert [r["episode"] for r in log_rows(work / "q.csv")] == ["2"]
    seeded = ["train", *ENV, "--episodes", "4", "--quiet", "--init-qtable", "q.qtable"]
    assert cli.main([*seeded, "--qtable", "n.qtable", "--log", "n.csv"]) == 0
    assert capsys.readouterr().err == ""
    assert [r["episode"] for r in log_rows(work / "n.csv")] == ["3"]


def test_a_log_lacking_its_last_row_names_it(work, capsys):
    """The kill between a save and its row: one row missing, named as one."""
    lines = (work / "q.csv").read_text(encoding="utf-8").split("\n")
    (work / "q.csv").write_text("\n".join(lines[:3]) + "\n", encoding="utf-8")
    assert cli.main(TRAIN) == 0
    assert capsys.readouterr().err.strip().splitlines() == [
        "warning: q.csv: lacks the row of episode 1 (the run stopped after saving the table "
        "and before writing it)"
    ]


def test_a_store_trained_in_chunks_resumes_its_own_log(tmp_path) -> None:
    """``train`` called again with the same store object (a sweep's or the targets
    tool's chunks between checks): the table the first call created is resumed with its
    log, quietly, and the files equal one uninterrupted run's."""
    from koolio_pymunk.learning.training import train
    from koolio_pymunk.store.config import load_config
    from koolio_pymunk.store.qtable import QTableStore
    from koolio_pymunk.task.env import KoolioEnv

    warnings: list[str] = []
    files = {}
    for name, chunks in (("one", [6]), ("chunks", [2, 2, 2])):
        env = KoolioEnv("room", config=load_config(overrides={"episode": {"max_steps": 40}}))
        store = QTableStore(tmp_path / f"{name}.qtable", warn=warnings.append)
        done = 0
        for n in chunks:
            train(env, store, n, 1, tmp_path / f"{name}.csv", report=None)
            done += n
        files[name] = [(tmp_path / f"{name}{s}").read_bytes() for s in (".qtable", ".csv")]
    assert files["chunks"] == files["one"] and warnings == []
