"""Attacks: bad files, faults and flags, as an attacker would try them.

Every case checks the promise of the README: one line ``koolio-pm: error: <file>: <item>:
<problem>``, exit status 2, no traceback, and the bytes of every file that existed before
are unchanged; no episode is lost or numbered twice, whatever stops a run. Faults the
machine cannot make on demand (a full disk, a folder without permission) are simulated by
patching the system call that would fail.
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from inputs import edit_header, expect_error, open_table

from koolio_pymunk import robot_runtime as rt
from koolio_pymunk.apps import cli
from koolio_pymunk.store import files as files_mod
from koolio_pymunk.store.episode_log import log_rows
from koolio_pymunk.store.errors import InUseError
from koolio_pymunk.store.locks import FileLock
from koolio_pymunk.store.qtable import QTableStore, load_qtable

TINY = "episode: {max_steps: 30}\n"
ROOT = Path(__file__).resolve().parents[1]


# -- helpers ------------------------------------------------------------------------------
def run_cli(capsys, *argv: str) -> tuple[int, str, str]:
    code = cli.main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def log_numbers(path: Path) -> tuple[list[int], list[int]]:
    """Episode numbers of the finished and of the interrupted rows of a log."""
    rows = log_rows(path)
    done = [int(r["episode"]) for r in rows if r["outcome"] != "interrupted"]
    cut = [int(r["episode"]) for r in rows if r["outcome"] == "interrupted"]
    return done, cut


def agree(table: Path, log: Path) -> None:
    """The log holds each of the table's episodes once, in order."""
    done, _ = log_numbers(log)
    assert done == list(range(load_qtable(table).meta["episodes"]))


@pytest.fixture(scope="module")
def base(tmp_path_factory) -> Path:
    """A tiny trained table, its log and its exported policy, in the room."""
    folder = tmp_path_factory.mktemp("base")
    (folder / "tiny.yaml").write_text(TINY)
    args = ["--arena", "room", "--config", str(folder / "tiny.yaml"), "--quiet"]
    q, log = str(folder / "q.qtable"), str(folder / "q.csv")
    # the paper's saving: the backup is the previous episode's table (the torn-table tests)
    train = ["train", *args, "--episodes", "3", "--qtable", q, "--log", log, "--fsync", "episode"]
    assert cli.main(train) == 0
    assert cli.main(["export", "--qtable", q, "--out", str(folder / "p.json")]) == 0
    return folder


@pytest.fixture
def work(base, tmp_path, monkeypatch) -> Path:
    """A copy of ``base`` as the current folder."""
    for p in base.iterdir():
        if p.is_file() and not p.name.endswith(".lock"):
            shutil.copy(p, tmp_path / p.name)
    shutil.copy(ROOT / "arenas" / "room.yaml", tmp_path / "room.yaml")
    monkeypatch.chdir(tmp_path)
    return tmp_path


TRAIN = ["train", "--arena", "room", "--config", "tiny.yaml", "--quiet"]


# == data loss ============================================================================
_HOLDER = textwrap.dedent(
    """
    import sys, time
    from koolio_pymunk.store.locks import FileLock
    lock = FileLock(sys.argv[1], "koolio-pm train").acquire()
    print("locked", flush=True)
    time.sleep(60)
    """
)


def _hold_lock(path: Path) -> subprocess.Popen:
    """Another process holding the lock of ``path`` (as a running trainer does)."""
    p = subprocess.Popen(
        [sys.executable, "-c", _HOLDER, str(path)], stdout=subprocess.PIPE, text=True
    )
    assert p.stdout is not None and p.stdout.readline().strip() == "locked"
    return p


def test_a_table_in_use_is_refused_and_freed_when_its_holder_is_killed(work, capsys):
    holder = _hold_lock(work / "q.qtable")
    try:
        line = expect_error(
            capsys, work, [*TRAIN, "--qtable", "q.qtable", "--log", "other.csv"], "q.qtable"
        )
        assert f"in use by process {holder.pid} (koolio-pm train)" in line
        assert not (work / "other.csv").exists()
        # --robots N, the window and a reader
        expect_error(capsys, work, [*TRAIN, "--qtable", "q.qtable", "--robots", "4"], "in use")
        from koolio_pymunk.apps.viewer.session import Session
        from koolio_pymunk.task.env import KoolioEnv

        with pytest.raises(InUseError, match="in use by process"):
            Session(KoolioEnv(arena="room", config="tiny.yaml"), "q.qtable", log="v.csv")
        code, _, _ = run_cli(capsys, "eval", "--arena", "room", "--qtable", "q.qtable",
                             "--config", "tiny.yaml", "--episodes", "1")  # fmt: skip
        assert code == 0  # readers take no lock
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait()
    # SIGKILL left no stale lock: training goes on
    code, _, err = run_cli(capsys, *TRAIN, "--qtable", "q.qtable", "--log", "q.csv",
                           "--episodes", "2")  # fmt: skip
    assert code == 0, err
    agree(work / "q.qtable", work / "q.csv")


def test_a_log_in_use_is_refused(work, capsys):
    holder = _hold_lock(work / "busy.csv")
    try:
        expect_error(capsys, work, [*TRAIN, "--qtable", "new.qtable", "--log", "busy.csv"],
                     "busy.csv: in use by process")  # fmt: skip
        assert not (work / "new.qtable").exists()
    finally:
        holder.kill()
        holder.wait()


def test_a_sweep_folder_in_use_is_refused(work):
    from koolio_pymunk.apps.sweep import parse_spec, run_sweep

    spec = parse_spec({"episodes": 1, "base": {"episode": {"max_steps": 5}}}, "s.yaml")
    lock = FileLock(work / "out", "koolio-pm sweep", path=work / "out" / ".sweep.lock")
    with lock, pytest.raises(InUseError, match="out: in use by process"):
        run_sweep(spec, work / "out", workers=1, plot=False, report=None)
    assert sorted(p.name for p in (work / "out").iterdir()) == [".sweep.lock"]


@pytest.mark.parametrize(
    ("log", "words"),
    [
        ("room.yaml", ["room.yaml: line 1: not a training log"]),
        ("p.json", ["p.json: line 1: not a training log"]),
        ("q.qtable", ["q.qtable: is the Q-table"]),
        ("q.qtable.bak", ["q.qtable.bak: is the Q-table's backup"]),
        ("q.qtable.lock", ["is the Q-table's lock file"]),
        ("other.qtable", ["other.qtable: not a UTF-8 training log"]),
        (".", ["is a folder, not a file"]),
    ],
)
def test_log_must_be_a_log_of_its_own(work, capsys, log, words):
    shutil.copy(work / "q.qtable", work / "other.qtable")
    expect_error(capsys, work, [*TRAIN, "--qtable", "q.qtable", "--log", log], *words)


def test_unreadable_table_is_refused_not_replaced_by_its_backup(work, capsys, monkeypatch):
    def read_only_others(path, *a, **k):  # as chmod 000 does when not root
        if Path(path).name == "q.qtable":
            raise PermissionError(errno.EACCES, "Permission denied", str(path))
        return open(path, *a, **k)

    monkeypatch.setattr(files_mod, "open", read_only_others, raising=False)
    expect_error(capsys, work, [*TRAIN, "--qtable", "q.qtable", "--log", "q.csv"],
                 "q.qtable: cannot read: permission denied", "backup is not used")  # fmt: skip


def test_a_new_table_with_an_old_log_is_refused(work, capsys):
    expect_error(capsys, work, [*TRAIN, "--qtable", "fresh.qtable", "--log", "q.csv"],
                 "q.csv: holds 3 rows of another run")  # fmt: skip
    assert not (work / "fresh.qtable").exists()


def test_resume_removes_rows_the_table_does_not_hold(work, capsys):
    """As after a SIGKILL with --robots N (rows logged, table saved every N) or a torn
    table replaced by its backup: the log is ahead of the table."""
    with open(work / "q.csv", "a") as fh:
        fh.write("3,-5,30,0,truncated,0,0.15,201\n4,-5,30,0,truncated,0,0.15,201\n4,-1")
    # --episodes is a total: 3 done, 2 more
    code, _, err = run_cli(capsys, *TRAIN, "--qtable", "q.qtable", "--log", "q.csv",
                           "--episodes", "5")  # fmt: skip
    assert code == 0
    assert "q.csv: moved 3 rows (episodes 3..4) to q.csv.removed" in err
    agree(work / "q.qtable", work / "q.csv")
    assert load_qtable(work / "q.qtable").meta["episodes"] == 5
    assert (work / "q.csv.removed").read_text().splitlines()[1:] == [
        "3,-5,30,0,truncated,0,0.15,201",
        "4,-5,30,0,truncated,0,0.15,201",
        "4,-1",
    ]  # nothing lost


def test_torn_table_falls_back_to_its_backup_without_repeating_numbers(work, capsys):
    data = (work / "q.qtable").read_bytes()
    (work / "q.qtable").write_bytes(data[: len(data) // 2])
    # --episodes is a total: the backup's 2, 2 more
    code, _, err = run_cli(capsys, *TRAIN, "--qtable", "q.qtable", "--log", "q.csv",
                           "--episodes", "4")  # fmt: skip
    assert code == 0
    assert "using the backup" in err and "q.csv: moved 1 row (episode 2)" in err
    agree(work / "q.qtable", work / "q.csv")
    assert load_qtable(work / "q.qtable").meta["episodes"] == 4


def _interrupt_after(monkeypatch, target, name: str, calls: int) -> None:
    """Ctrl-C after ``calls`` calls of ``target.name``."""
    real = getattr(target, name)
    count = [0]

    def wrapped(*a, **k):
        count[0] += 1
        if count[0] > calls:
            raise KeyboardInterrupt
        return real(*a, **k)

    monkeypatch.setattr(target, name, wrapped)


@pytest.mark.parametrize("discard", [False, True])
def test_ctrl_c_with_robots_keeps_every_finished_episode(work, capsys, monkeypatch, discard):
    from koolio_pymunk.learning import engine
    from koolio_pymunk.learning.engine import Engine

    advance = Engine.advance
    monkeypatch.setattr(engine, "CHUNK", 4)  # a tick of the four robots per compiled call
    _interrupt_after(monkeypatch, Engine, "advance", 40)  # 40 episodes finish
    flag = ["--discard-unfinished"] if discard else []
    code, _, _ = run_cli(capsys, *TRAIN, "--qtable", "m.qtable", "--log", "m.csv",
                         "--robots", "4", "--episodes", "100", *flag)  # fmt: skip
    assert code == 130
    done, cut = log_numbers(work / "m.csv")
    table = load_qtable(work / "m.qtable")
    assert done == list(range(table.meta["episodes"])) and len(done) >= 4
    n = len(done)
    assert cut == ([] if discard else [n, n + 1, n + 2, n + 3])  # four numbers, not one
    monkeypatch.setattr(Engine, "advance", advance)
    code, _, _ = run_cli(capsys, *TRAIN, "--qtable", "m.qtable", "--log", "m.csv",
                         "--robots", "4", "--episodes", "4")  # fmt: skip
    assert code == 0
    agree(work / "m.qtable", work / "m.csv")


def test_discard_takes_back_only_the_unfinished_writes():
    """The journal: a robot's writes are taken back newest first, unless another robot
    wrote over them since; rows only the discarded episodes created are dropped."""
    import numpy as np

    from koolio_pymunk.learning.table_kernel import SharedTable, new_journal, undo_writes, update
    from koolio_pymunk.store.keyword import KeywordLayout
    from koolio_pymunk.store.qtable import QTable

    table = QTable(KeywordLayout((("A", 8),)), q_init=-1.0)
    table.row(1)[:] = [0.0] * 5
    sh = SharedTable(table)
    journal = new_journal(2, 8)

    def write(robot, state, action, reward):
        update(sh.index, sh.args(), 0.5, 0.0, state, action, reward, 0, True, robot, journal)

    write(0, 1, 0, 10.0)  # robot 0 (kept): 5.0
    write(1, 1, 0, 20.0)  # robot 1 (discarded) over it: 12.5
    write(1, 1, 1, 4.0)  # robot 1 alone: 2.0
    write(1, 2, 0, 8.0)  # robot 1 creates row 2
    write(0, 1, 1, 6.0)  # robot 0 over robot 1's write: 4.0
    dropped = undo_writes(sh, journal, [1])
    assert np.array_equal(sh.q[0], [5.0, 4.0, 0.0, 0.0, 0.0]) and dropped == [2]


def test_sigkill_loses_at_most_the_row_of_one_episode(work, capsys):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    p = subprocess.Popen(
        [sys.executable, "-m", "koolio_pymunk.apps.cli", *TRAIN, "--qtable", "k.qtable",
         "--log", "k.csv", "--episodes", "100000"],
        env=env, cwd=work,
    )  # fmt: skip
    try:
        deadline = time.time() + 60
        while time.time() < deadline:
            if (work / "k.csv").exists() and len((work / "k.csv").read_text().splitlines()) > 20:
                break
            time.sleep(0.05)
    finally:
        p.send_signal(signal.SIGKILL)
        p.wait()
    table = load_qtable(work / "k.qtable").meta["episodes"]
    done, _ = log_numbers(work / "k.csv")
    # the table is saved before its row is written: at most that row is missing
    assert done == list(range(len(done))) and len(done) in (table - 1, table)
    # --episodes is a total: 2 more
    code, _, _ = run_cli(capsys, *TRAIN, "--qtable", "k.qtable", "--log", "k.csv",
                         "--episodes", str(table + 2))  # fmt: skip
    assert code == 0
    done, _ = log_numbers(work / "k.csv")
    assert len(done) == len(set(done)) and done[-1] == table + 1


def test_temporary_files_of_interrupted_writes_are_removed_on_start(work, capsys):
    stale = [".q.qtable.999999999.abcd_123.tmp", ".q.qtable.bak.999999999.zz99zz99.tmp",
             ".q.qtable.k3j4h5g6.tmp"]  # fmt: skip
    live = f".q.qtable.{os.getpid()}.abcdefgh.tmp"  # ours: a write in progress
    other = ".other.qtable.999999999.abcdefgh.tmp"
    for name in [*stale, live, other]:
        (work / name).write_bytes(b"half a table")
    # --episodes is a total: 1 more than the 3 done
    code, _, _ = run_cli(capsys, *TRAIN, "--qtable", "q.qtable", "--log", "q.csv",
                         "--episodes", "4")  # fmt: skip
    assert code == 0
    left = sorted(p.name for p in work.iterdir() if p.name.endswith(".tmp"))
    assert left == sorted([live, other])


def test_killed_sweep_worker_fails_only_its_run(tmp_path):
    from koolio_pymunk.apps.sweep import WorkerDied, run_pool

    results: dict[int, object] = {}
    tasks = [{"n": n} for n in range(5)]
    run_pool(tasks, 2, lambda t, r: results.__setitem__(t["n"], r), target=_die_on_two)
    assert {n: r for n, r in results.items() if n != 2} == {0: 0, 1: 10, 3: 30, 4: 40}
    assert isinstance(results[2], WorkerDied) and "SIGKILL" in str(results[2])


def _die_on_two(task: dict) -> int:
    if task["n"] == 2:
        os.kill(os.getpid(), signal.SIGKILL)
    return task["n"] * 10


def test_stale_sweep_run_folders_are_removed(tmp_path):
    from koolio_pymunk.apps.sweep import remove_stale_run_folders

    dead = tmp_path / "koolio-sweep-999999999-abc"
    alive = tmp_path / f"koolio-sweep-{os.getppid()}-abc"
    for d in (dead, alive):
        (d / "inner").mkdir(parents=True)
    assert remove_stale_run_folders(str(tmp_path)) == [dead.name]
    assert alive.exists() and not dead.exists()


# == faults of the operating system =========================================================
def _fail_call(monkeypatch, target, name: str, err: int, after: int = 0) -> None:
    """``target.name`` raises OSError(err) from its call number ``after + 1`` on."""
    real = getattr(target, name)
    count = [0]

    def failing(*a, **k):
        count[0] += 1
        if count[0] > after:
            raise OSError(err, os.strerror(err))
        return real(*a, **k)

    monkeypatch.setattr(target, name, failing)


@pytest.mark.parametrize("mode", ["episode", "second"])
def test_disk_full_during_training_stops_with_the_last_good_table(work, capsys, monkeypatch, mode):
    """Disk full at a save: with the paper's saving at a table's fsync (2 a save: the file
    and its folder), with the journal at an append (its write): one line, and the table
    (with its journal) holds every episode logged."""
    good = load_qtable(work / "q.qtable").meta["episodes"]
    call = "fsync" if mode == "episode" else "write"
    _fail_call(monkeypatch, files_mod.os, call, errno.ENOSPC, after=8)
    code, _, err = run_cli(capsys, *TRAIN, "--qtable", "q.qtable", "--log", "q.csv",
                           "--episodes", "50", "--fsync", mode)  # fmt: skip
    monkeypatch.undo()
    assert code == 2 and err.count("\n") == 1, err
    assert "cannot write: disk full (no space left on device)" in err
    table = load_qtable(work / "q.qtable")
    assert good < table.meta["episodes"] < good + 50
    if mode == "episode":
        assert load_qtable(work / "q.qtable.bak").meta["episodes"] == table.meta["episodes"] - 1
    else:  # the snapshot as it was, and the journal's records after it
        from koolio_pymunk.store.qtable import QTable

        snapshot = QTable.from_bytes((work / "q.qtable").read_bytes())
        assert snapshot.meta["episodes"] == good and (work / "q.qtable.journal").exists()
    agree(work / "q.qtable", work / "q.csv")
    assert not [p for p in work.iterdir() if p.name.endswith(".tmp")]


@pytest.mark.parametrize(
    ("argv", "what"),
    [
        ([*TRAIN, "--qtable", "new.qtable", "--log", "new.csv"], "new.qtable"),
        (["export", "--qtable", "q.qtable", "--out", "out.json"], "out.json"),
        (["export", "--qtable", "q.qtable", "--out", "out.qtable"], "out.qtable"),
        (["plot", "--log", "q.csv", "--out", "out.png"], "out.png"),
    ],
)
@pytest.mark.parametrize(
    ("err", "problem"),
    [
        (errno.ENOSPC, "disk full"),
        (errno.EROFS, "read-only file system"),
        (errno.EACCES, "permission denied"),
    ],
)
def test_every_writer_reports_a_failed_write_in_one_line(
    work, capsys, monkeypatch, argv, what, err, problem
):
    _fail_call(monkeypatch, files_mod.tempfile, "mkstemp", err)
    expect_error(capsys, work, argv, f"{what}: cannot write: {problem}")


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["check-arena", "room.yaml"], ["room.yaml: cannot read: permission denied"]),
        (["info", "--config", "tiny.yaml"], ["tiny.yaml: cannot read: permission denied"]),
        (["plot", "--log", "q.csv"], ["q.csv: cannot read: permission denied"]),
        (["sweep", "tiny.yaml"], ["tiny.yaml: cannot read: permission denied"]),
    ],
)
def test_a_folder_without_search_permission(work, capsys, monkeypatch, argv, words):
    def no_access(path, *a, **k):
        raise PermissionError(errno.EACCES, "Permission denied", str(path))

    monkeypatch.setattr(files_mod, "open", no_access, raising=False)
    expect_error(capsys, work, argv, *words)


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["export", "--qtable", "q.qtable", "--out", "."], [".: cannot write: is a folder"]),
        (["export", "--qtable", "q.qtable", "--out", "room.yaml/p.json"],
         ["cannot create the folder room.yaml: a file is in the way"]),
        ([*TRAIN, "--qtable", "room.yaml/q.qtable"],
         ["room.yaml/q.", "a file is in the way"]),
        ([*TRAIN, "--qtable", ""], ["--qtable: empty file name"]),
        (["export", "--qtable", "q.qtable", "--out", ""], ["--out: empty file name"]),
        (["export", "--qtable", "", "--out", "x.json"], ["--qtable: empty file name"]),
        (["check-arena", ""], ["empty file name"]),
        (["plot", "--log", "q.csv", "--out", "sub.png"], ["--out: sub.png: is a folder"]),
        (["view", "--steps", "2", "--screenshot", "sub.png"],
         ["--screenshot: sub.png: is a folder"]),
        (["view", "--steps", "2", "--screenshot-every", "2", "room.yaml"],
         ["--screenshot-every: room.yaml: is a file, not a folder"]),
        (["view", "--steps", "2", "--screenshot-every", "2", "frames"],
         ["frames: holds frames of an earlier run"]),
        (["view", "--steps", "2", "--arena", "room", "--qtable", "v.qtable", "--log", "bin.png"],
         ["bin.png: not a UTF-8 training log"]),
        (["eval", "--arena", "room", "--qtable", "."], [".: is a folder, not a file"]),
    ],
)  # fmt: skip
def test_paths_that_cannot_be_files(work, capsys, argv, words):
    (work / "sub.png").mkdir()
    (work / "frames").mkdir()
    (work / "frames" / "frame_00001.png").write_bytes(b"an earlier frame")
    (work / "bin.png").write_bytes(bytes(range(256)))
    expect_error(capsys, work, argv, *words)


# == malformed files ==========================================================================
@pytest.mark.parametrize(
    ("changes", "words"),
    [
        ({"q_init": "abc"}, ["header.q_init: must be a finite number"]),
        ({"episodes": -5}, ["header.episodes: must be an integer >= 0"]),
        ({"sensors": 7}, ["header.sensors: must be a mapping"]),
        ({"layout.n_actions": 10**400}, ["header.layout.n_actions: must be an integer 1..64"]),
        ({"layout.n_actions": 1e300}, ["header.layout.n_actions"]),
        ({"layout.fields": [["GoalCam0", 0]]}, ["header.layout.fields[0]: must be [name, levels"]),
        ({"layout.fields": [["A", 60000]] * 9}, ["does not fit 64 bits"]),
        ({"arena": "hallway"}, ["header.arena: must be {name, sha256}"]),
        ({"format": 2}, ["unsupported format version"]),
    ],
)
def test_table_headers_with_a_valid_checksum_are_checked(work, capsys, changes, words):
    (work / "h.qtable").write_bytes(edit_header((work / "q.qtable").read_bytes(), **changes))
    for argv in (
        ["eval", "--arena", "room", "--config", "tiny.yaml", "--qtable", "h.qtable"],
        ["info", "--qtable", "h.qtable"],
        ["export", "--qtable", "h.qtable", "--out", "h.json"],
        [*TRAIN, "--qtable", "h.qtable", "--log", "h.csv"],
    ):
        expect_error(capsys, work, argv, "h.qtable: ", *words)


def _policy(work: Path, name: str, change) -> None:
    doc = json.loads((work / "p.json").read_text())
    change(doc)
    (work / name).write_text(json.dumps(doc))


POLICY_CASES = [
    (lambda d: d["entries"][0].update(q=10**400), "entries[0]: needs an integer keyword"),
    (lambda d: d["entries"][0].update(keyword=10**400), "entries[0]: keyword 1000"),
    (lambda d: d["encoding"].update(n_sonar=10**400), "encoding.n_sonar: must be an integer"),
    (lambda d: d.update(actions=5), "actions: must be a list of 5 action names"),
    (lambda d: d.update(sensors="front"), "sensors: must be a mapping"),
    (lambda d: d.update(sensors=[0, 45]), "sensors: must be a mapping"),
    (lambda d: d["layout"]["fields"][0].update(levels=10**400), "layout.fields[0]: needs"),
    (lambda d: d.update(episodes=-1), "episodes: must be an integer >= 0"),
    (lambda d: d.update(rewards={"goal": 10**400}), "rewards: must map names to finite"),
]


def test_a_policy_without_its_sensor_signature(work, capsys):
    """The runtime needs only the encoding; the simulator needs the sensor signature."""
    _policy(work, "bad.json", lambda d: d["sensors"].pop("camera_sensors_deg"))
    for argv in (
        ["eval", "--arena", "room", "--config", "tiny.yaml", "--qtable", "bad.json"],
        ["export", "--qtable", "bad.json", "--out", "o.json"],
        [*TRAIN, "--init-qtable", "bad.json", "--qtable", "i.qtable", "--log", "i.csv"],
    ):
        expect_error(capsys, work, argv, "bad.json: sensors.camera_sensors_deg")


@pytest.mark.parametrize(("change", "words"), POLICY_CASES)
def test_bad_policies_in_every_command_and_the_runtime(work, capsys, change, words):
    _policy(work, "bad.json", change)
    for argv in (
        ["eval", "--arena", "room", "--config", "tiny.yaml", "--qtable", "bad.json"],
        ["export", "--qtable", "bad.json", "--out", "o.json"],
        [*TRAIN, "--init-qtable", "bad.json", "--qtable", "i.qtable", "--log", "i.csv"],
    ):
        expect_error(capsys, work, argv, "bad.json: ", words)
    assert rt.main(["bad.json"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and "Traceback" not in err


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ('{"format": "koolio-policy", "n_sonar": 1e999}', "version: unsupported version None"),
        ("[" * 5000 + "]" * 5000, "neither a .qtable file nor a koolio-policy"),
        ('{"format": "koolio-policy", "x": ' + "[" * 5000 + "]" * 5000 + "}", "nested too deeply"),
        ('{"format": "koolio-policy", "version": 1, "q": ' + "9" * 5000 + "}", "invalid JSON"),
    ],
)
def test_policy_json_attacks(work, capsys, text, words):
    (work / "bad.json").write_text(text)
    expect_error(capsys, work, ["export", "--qtable", "bad.json", "--out", "o.json"], words)
    with pytest.raises(rt.PolicyError):
        rt.Policy.load("bad.json")


@pytest.mark.parametrize(
    ("content", "words"),
    [
        (bytes(range(256)) * 4, ["c.yaml: not a UTF-8 configuration file"]),
        ("learner: {alpha: 0.5}\n".encode("utf-16"), ["not a UTF-8"]),
        (b"episode: {max_steps: " + b"9" * 400 + b"}\n", ["episode.max_steps: must be finite"]),
        (b"learner: {alpha: 0.1}\nlearner: {gamma: 0.5}\n", ["line 2", "duplicate key 'learner'"]),
        (b"sensors: {camera: {camera_sensors_deg: [" + b"0," * 30 + b"0]}}\n",
         ["sensors: the keyword would need", "it must fit 64"]),
        (b"rescue: {rescue_max_backup: 1000000, rescue_chance: 1}\n",
         ["rescue.rescue_max_backup: must be <= 100"]),
        (b"sensors: {sonar: {sub_arcs: 100000}}\n", ["sensors.sonar.sub_arcs: must be <= 360"]),
        (b"sensors: {sonar: {pings: 2}}\n", ["sensors.sonar.pings: must be odd, 1 to 9"]),
        (b"sensors: {sonar: {pings: 3.5}}\n", ["sensors.sonar.pings: expected an integer"]),
        (b"a: &x [1]\nb: *x\n", ["aliases (*name) are not supported"]),
        (b"x: " + b"[" * 100 + b"]" * 100, ["nested more than 64 levels"]),
    ],
)  # fmt: skip
def test_bad_configurations(work, capsys, content, words):
    (work / "c.yaml").write_bytes(content)
    expect_error(capsys, work, [*TRAIN[:3], "--config", "c.yaml", "--qtable", "c.qtable"], *words)


def test_yaml_1_2_numbers_are_numbers(work, capsys):
    from koolio_pymunk.store.config import load_config

    (work / "c.yaml").write_text(
        "learner: {alpha: 1e-1, q_init: -3E1}\nepisode: {max_steps: 3e1}\n"
    )
    cfg = load_config("c.yaml")
    assert (cfg.learner.alpha, cfg.learner.q_init, cfg.episode.max_steps) == (0.1, -30.0, 30)


ARENA = (ROOT / "arenas" / "room.yaml").read_text()


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("name: " + "[" * 50_000 + "]" * 50_000 + "\n", ["nested more than 64 levels"]),
        (ARENA.replace("[48, 48]", "[" + "4" * 5000 + ", 48]"),
         ["Exceeds the limit (4300 digits)"]),
        (ARENA.replace("[48, 48]", "[" + "4" * 400 + ", 48]"),
         ["start.at: not a finite number"]),
        (ARENA.replace("[48, 48]", "[4000000, 48]"), ["start.at: coordinate 4000000 beyond"]),
        (ARENA + "#" * (50 * 1024 * 1024),
         ["too large: 50 MiB", "the limit for arena files is 1 MiB"]),
        (ARENA.replace("name: room", "name: room\nname: hall"), ["duplicate key 'name'"]),
        (ARENA.replace("- name: '201'\n  at:", '- name: "20\\n1"\n  at:', 1),
         ["goals[0].name: control characters in the name"]),
        ("name: x\nwalls: [" + "[0, 0], " * 10_001 + "]\ngoals: []\nstart: {at: [0, 0]}\n",
         ["walls: 10,001 points (the limit is 10,000)"]),
    ],
)  # fmt: skip
def test_bad_arenas_in_bounded_time_and_memory(work, capsys, text, words):
    (work / "a.yaml").write_text(text)
    expect_error(capsys, work, ["check-arena", "a.yaml"], "a.yaml: ", *words)


def test_a_5000_point_polygon_is_checked(work, capsys):
    """The polygon checks sort and sweep (once minutes, a 5,000-point wall is now checked
    in about a second: tools/bench.py does not time it, this test proves it correct)."""
    import math

    n = 5000
    angles = [2 * math.pi * k / n for k in range(n)]
    ring = [[round(500 * math.cos(a), 6), round(500 * math.sin(a), 6)] for a in angles]
    arena = {"name": "round", "walls": ring, "goals": [{"name": "g", "at": [0, 100]}],
             "start": {"at": [0, 0]}}  # fmt: skip
    (work / "round.yaml").write_text(json.dumps(arena))  # JSON is YAML
    code, out, _ = run_cli(capsys, "check-arena", "round.yaml")
    assert code == 0 and "5000 wall points" in out
    ring[2500] = [600.0, 0.0]  # a spike across the ring: edges 2499 and 2500 cross edge 0
    (work / "round.yaml").write_text(json.dumps({**arena, "walls": ring}))
    expect_error(capsys, work, ["check-arena", "round.yaml"],
                 "walls[2499]: self-intersecting polygon: edge walls[2499]-walls[2500] meets "
                 "edge walls[0]-walls[1]")  # fmt: skip


# == flags ===================================================================================
@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["train", "--seed", "-1"], ["--seed: must be >= 0, got -1"]),
        (["eval", "--seed", "x"], ["--seed: not an integer: 'x'"]),
        (["train", "--episodes", "lots"], ["--episodes: not an integer"]),
        (["train", "--robots", "100000"], ["--robots: must be in 1..1024"]),
        (["train", "--bogus"], ["unrecognized arguments: --bogus"]),
        (["nonsense"], ["command: invalid choice: 'nonsense'"]),
        (["view", "--size", "100000x100000"], ["is larger than 7680x4320"]),
        (["view", "--size", "big"], ["expected WIDTHxHEIGHT"]),
        (["export"], ["the following arguments are required: --out"]),
    ],
)
def test_bad_flags_are_one_line_errors(work, capsys, argv, words):
    expect_error(capsys, work, argv, *words)


# == the rest of the promises ==================================================================
def test_defaults_follow_the_arena(work, capsys):
    code, _, _ = run_cli(capsys, "train", "--arena", "room.yaml", "--config", "tiny.yaml",
                         "--episodes", "1", "--quiet")  # fmt: skip
    assert code == 0
    assert (work / "runs" / "room.qtable").exists() and (work / "runs" / "room.csv").exists()
    assert cli.default_files("hallway") == ("runs/hallway.qtable", "runs/hallway.csv")


def test_a_table_records_its_arena_and_warns_once_elsewhere(work, capsys):
    meta = load_qtable(work / "q.qtable").meta
    assert meta["arena"]["name"] == "room" and len(meta["arena"]["sha256"]) == 16
    edited = ARENA.replace("[48, 48]", "[50, 48]")  # the start moved 2 in
    (work / "room2.yaml").write_text(edited)
    code, _, err = run_cli(capsys, "eval", "--arena", "room2.yaml", "--config", "tiny.yaml",
                           "--qtable", "q.qtable", "--episodes", "1", "--goal", "all")  # fmt: skip
    assert code == 0
    assert err.count("learned in arena 'room'") == 1 and "used in arena 'room'" in err
    code, _, err = run_cli(capsys, "eval", "--arena", "room", "--config", "tiny.yaml",
                           "--qtable", "q.qtable", "--episodes", "1")  # fmt: skip
    assert code == 0 and err == ""


def test_an_arena_without_end_of_world_markers_trains(work, capsys):
    lines = ARENA.splitlines()
    start = lines.index("end_of_world:")
    end = lines.index("start:")
    (work / "closed.yaml").write_text("\n".join(lines[:start] + lines[end:]) + "\n")
    for robots in ("1", "2"):
        argv = ["train", "--arena", "closed.yaml", "--config", "tiny.yaml", "--episodes", "2"]
        files = ["--qtable", f"c{robots}.qtable", "--log", f"c{robots}.csv"]
        code, _, err = run_cli(capsys, *argv, "--quiet", "--robots", robots, *files)
        assert code == 0, err
        assert log_numbers(work / f"c{robots}.csv")[0] == [0, 1]


def test_a_runtime_log_refuses_a_file_that_is_not_a_log(work):
    before = (work / "room.yaml").read_bytes()
    with pytest.raises(rt.PolicyError, match="not a training log"):
        rt.EpisodeLog("room.yaml")
    assert (work / "room.yaml").read_bytes() == before


def test_a_store_releases_its_lock_when_closed(tmp_path):
    from koolio_pymunk.store.keyword import KeywordLayout

    layout = KeywordLayout((("A", 3),))
    with QTableStore(tmp_path / "t.qtable") as store:
        open_table(store, layout, {}, 0.0)
        with pytest.raises(InUseError):
            open_table(QTableStore(tmp_path / "t.qtable"), layout, {}, 0.0)
    open_table(QTableStore(tmp_path / "t.qtable"), layout, {}, 0.0)
