"""The best policy kept (``train --eval-every``): checks that leave training alone, the
evaluations file, the best table, stops and resumes, refusals; ``eval --epsilon``."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from inputs import expect_error, same_run

from koolio_pymunk.apps.cli import main
from koolio_pymunk.learning import evaluation
from koolio_pymunk.learning.evaluation import PeriodicCheck, evaluate
from koolio_pymunk.learning.training import train
from koolio_pymunk.store.check_files import EVALS_FIELDS, CheckFiles, best_path, evals_path
from koolio_pymunk.store.config import Config
from koolio_pymunk.store.errors import KoolioError, QTableError
from koolio_pymunk.store.qtable import QTableStore, load_qtable
from koolio_pymunk.store.run_identity import RunIdentity
from koolio_pymunk.task.env import KoolioEnv

EVERY, CHECK = 2, 4  # a check every 2 episodes, 4 greedy episodes each


def config(algorithm: str = "q") -> Config:
    cfg = Config()
    cfg.episode.max_steps = 60
    cfg.learner.algorithm = algorithm
    return cfg


def run(tmp_path: Path, name: str, episodes: int, env=None, checks: bool = True, **kw):
    """Train ``episodes`` more episodes into ``name.qtable`` / ``name.csv``."""
    q, log = tmp_path / f"{name}.qtable", tmp_path / f"{name}.csv"
    env = env or KoolioEnv("room", config=config())
    more = {"eval_every": EVERY, "eval_episodes": CHECK} if checks else {}
    res = train(env, QTableStore(q), episodes, 0, log, report=None, **more, **kw)
    return q, log, res


def rows(path: Path) -> list[dict[str, str]]:
    """The evaluations file's rows without the ``seconds`` column (wall time)."""
    out = list(csv.DictReader(path.open()))
    for r in out:
        assert float(r.pop("seconds")) >= 0
    return out


def files(tmp_path: Path, name: str) -> dict[str, bytes | list]:
    """Everything a run with checks leaves that must match another run's."""
    q = tmp_path / f"{name}.qtable"
    return {
        "table": q.read_bytes(),
        "log": (tmp_path / f"{name}.csv").read_bytes(),
        "best": best_path(q).read_bytes(),
        "evals": rows(tmp_path / f"{name}.evals.csv"),
    }


@pytest.mark.parametrize(
    ("algorithm", "world"),
    [("q", None), ("qlambda", None), ("dyna", None), ("q", "koolio-real-dr")],
)
def test_checks_leave_the_training_stream_alone(tmp_path, algorithm, world) -> None:
    """The same table and log bytes with and without checks, for every learner and with
    domain randomization (the checks reset the same env with seeds of their own)."""

    def env() -> KoolioEnv:
        return KoolioEnv("room", config=config(algorithm), world=world)

    qa, la, res = run(tmp_path, "with", 6, env())
    qb, lb, _ = run(tmp_path, "without", 6, env(), checks=False)
    assert [c.episode for c in res.checks] == [2, 4, 6]  # the premise: checks ran
    assert qa.read_bytes() == qb.read_bytes()
    assert la.read_bytes() == lb.read_bytes()


def test_evals_file_and_best_table(tmp_path) -> None:
    q, _, res = run(tmp_path, "a", 7)
    got = rows(tmp_path / "a.evals.csv")
    assert list(got[0]) == [f for f in EVALS_FIELDS if f != "seconds"]
    assert [int(r["episode"]) for r in got] == [2, 4, 6]  # not 7: not a multiple of 2
    assert {(r["eval_episodes"], r["seed"]) for r in got} == {("4", "0")}
    for r, c in zip(got, res.checks):
        assert float(r["goal_rate"]) == c.result.goal_rate
        assert float(r["mean_return"]) == pytest.approx(c.result.mean_reward, rel=1e-5)
    # the best: highest goal rate, then highest mean return, the earlier on a tie; a
    # row's best is 1 when its check is the best so far
    best, flags = res.checks[0], ["1"]
    for c in res.checks[1:]:
        if c.score > best.score:
            best = c
        flags.append("1" if best is c else "0")
    assert [r["best"] for r in got] == flags
    table = load_qtable(best_path(q))
    assert table.meta["best"] == best.record()
    assert table.meta["episodes"] == best.episode
    # it is the table as saved after that many episodes, and scores what the check said
    run(tmp_path, "b", best.episode, checks=False)
    plain = load_qtable(tmp_path / "b.qtable")
    assert table.rows == plain.rows
    assert {k: v for k, v in table.meta.items() if k != "best"} == plain.meta
    again = evaluate(KoolioEnv("room", config=config()), table, CHECK, 0)
    assert again == best.result


def test_best_table_is_kept_when_later_checks_are_worse(tmp_path) -> None:
    """A session never replaces a better best of an earlier session; the best flag
    of the evaluations file follows the kept table."""
    q, _, _ = run(tmp_path, "a", 2)
    bp = best_path(q)
    table = load_qtable(bp)
    table.meta["best"] = dict(table.meta["best"], goal_rate=1.0)
    bp.write_bytes(table.to_bytes())
    before = bp.read_bytes()
    _, _, res = run(tmp_path, "a", 4)
    assert [c.best for c in res.checks] == [False, False] and res.checks[0].result.goal_rate < 1
    assert bp.read_bytes() == before


def test_an_exact_tie_keeps_the_earlier_best(tmp_path) -> None:
    """Goal rate, then mean return; an exact tie of both keeps the earlier table."""
    _, _, full = run(tmp_path, "full", 4)
    later = full.checks[1].record()

    def resumed_against(name: str, mean_return: float) -> int:
        q, _, _ = run(tmp_path, name, 2)
        bp = best_path(q)
        table = load_qtable(bp)
        table.meta["best"] = dict(
            table.meta["best"], goal_rate=later["goal_rate"], mean_return=mean_return
        )
        bp.write_bytes(table.to_bytes())
        _, _, res = run(tmp_path, name, 2)
        assert res.checks[0].record() == later  # the premise: the same check at 4
        return load_qtable(bp).meta["best"]["episode"]

    assert resumed_against("tie", later["mean_return"]) == 2
    assert resumed_against("lower", later["mean_return"] - 1.0) == 4


@pytest.mark.parametrize("split", [3, 4])
def test_resumed_run_continues_exactly(tmp_path, split) -> None:
    """Stopped between episodes at a check (4) or between checks (3), then resumed."""
    run(tmp_path, "full", 8)
    run(tmp_path, "part", split)
    run(tmp_path, "part", 8 - split)
    assert files(tmp_path, "part") == files(tmp_path, "full")


class Killed(BaseException):
    """Stands for SIGKILL: nothing after it runs (the files stay as they are)."""


@pytest.mark.parametrize("where", ["before the check", "in the check", "before the row"])
def test_killed_anywhere_around_a_check_resumes_exactly(tmp_path, monkeypatch, where) -> None:
    run(tmp_path, "full", 6)
    calls = {"n": 0}

    def kill_on_second(original):
        def wrapper(*args, **kw):
            calls["n"] += 1
            if calls["n"] == 2:
                raise Killed
            return original(*args, **kw)

        return wrapper

    target = {
        "before the check": (PeriodicCheck, "check"),
        "in the check": (evaluation, "evaluate"),
        "before the row": (CheckFiles, "append"),
    }[where]
    with monkeypatch.context() as m:
        m.setattr(*target, kill_on_second(getattr(*target)))
        with pytest.raises(Killed):
            run(tmp_path, "part", 6)
    assert load_qtable(tmp_path / "part.qtable").meta["episodes"] == 4
    assert len(rows(tmp_path / "part.evals.csv")) == 1  # the check at 4 never written
    run(tmp_path, "part", 2)
    assert files(tmp_path, "part") == files(tmp_path, "full")


def test_ctrl_c_in_a_check_drops_it_and_resume_runs_it(tmp_path, monkeypatch) -> None:
    run(tmp_path, "full", 6)
    original = evaluation.evaluate
    calls = {"n": 0}

    def evaluate_then_ctrl_c(*args, **kw):
        calls["n"] += 1
        if calls["n"] == 2:
            signal.raise_signal(signal.SIGINT)  # SafeInterrupt: pending, the check stops
        return original(*args, **kw)

    with monkeypatch.context() as m:
        m.setattr(evaluation, "evaluate", evaluate_then_ctrl_c)
        _, _, res = run(tmp_path, "part", 6)
    assert res.interrupted and [c.episode for c in res.checks] == [2]
    assert load_qtable(tmp_path / "part.qtable").meta["episodes"] == 4
    run(tmp_path, "part", 2)
    assert files(tmp_path, "part") == files(tmp_path, "full")


def test_rows_beyond_the_table_move_out(tmp_path, capsys) -> None:
    """A table that fell back to its backup: the checks beyond it run again."""
    run(tmp_path, "full", 6)
    q, _, _ = run(tmp_path, "part", 4, fsync="episode")  # the backup: the previous table
    q.write_bytes((tmp_path / "part.qtable.bak").read_bytes())  # 3 episodes
    text = (tmp_path / "part.evals.csv").read_text()
    (tmp_path / "part.evals.csv").write_text(text + "6,4,0,0.5")  # and a torn row
    run(tmp_path, "part", 3)
    assert "moved 2 checks to" in capsys.readouterr().err
    moved = (tmp_path / "part.evals.csv.removed").read_text().splitlines()
    assert [r.split(",")[0] for r in moved[1:]] == ["4", "6"]
    assert files(tmp_path, "part")["evals"] == files(tmp_path, "full")["evals"]
    assert files(tmp_path, "part")["best"] == files(tmp_path, "full")["best"]


def test_a_real_sigkill_resumes_exactly(tmp_path) -> None:
    """``koolio-pm train --eval-every`` killed (SIGKILL) mid-run, then resumed: the
    table, the best table and the checks of an uninterrupted run."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text("episode: {max_steps: 60}\n")

    def argv(name: str, episodes: int) -> list[str]:
        return [
            *("train", "--arena", "room", "--config", str(cfg), "--quiet"),
            *("--episodes", str(episodes), "--eval-every", "3", "--eval-episodes", "4"),
            *("--qtable", str(tmp_path / f"{name}.qtable")),
        ]

    assert main(argv("full", 24)) == 0
    cmd = [sys.executable, "-m", "koolio_pymunk", *argv("part", 24)]
    proc = subprocess.Popen(cmd, env=os.environ | {"SDL_VIDEODRIVER": "dummy"})
    evals = tmp_path / "part.evals.csv"
    deadline = time.monotonic() + 120
    while not (evals.exists() and evals.read_text().count("\n") >= 2):
        assert proc.poll() is None and time.monotonic() < deadline
        time.sleep(0.01)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    done = load_qtable(tmp_path / "part.qtable").meta["episodes"]
    assert 3 <= done < 24  # the premise: killed mid-run
    assert main(argv("part", 24)) == 0  # --episodes is the total to reach
    for name in ("qtable", "best.qtable"):  # the same run from another command line
        assert same_run(tmp_path / f"part.{name}", tmp_path / f"full.{name}")
    assert rows(evals) == rows(tmp_path / "full.evals.csv")


def test_the_commands_read_the_best_table(tmp_path, capsys) -> None:
    """eval, export, transfer --qtable and view --greedy take X.best.qtable as it is."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text("sensors: {noise: {model: none}}\nepisode: {max_steps: 40}\n")
    env = ["--arena", "room", "--config", str(cfg)]
    q = tmp_path / "t.qtable"
    best = tmp_path / "t.best.qtable"
    assert main(["train", *env, "--episodes", "4", "--eval-every", "2", "--eval-episodes", "5",
                 "--qtable", str(q), "--quiet"]) == 0  # fmt: skip
    record = load_qtable(best).meta["best"]
    capsys.readouterr()
    assert main(["eval", *env, "--qtable", str(best), "--episodes", "5", "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert (figures["goal_rate"], figures["mean_reward"]) == (
        record["goal_rate"],
        record["mean_return"],
    )
    policy = tmp_path / "best.policy.json"
    assert main(["export", "--qtable", str(best), "--config", str(cfg), "--out", str(policy)]) == 0
    assert json.loads(policy.read_text())["format"] == "koolio-policy"
    out = tmp_path / "transfer"
    assert main(["transfer", *env, "--qtable", str(best), "--dr-qtable", str(best),
                 "--robot-episodes", "2", "--eval-episodes", "2", "--eval-every", "2",
                 "--out", str(out), "--no-plot", "--quiet"]) == 0  # fmt: skip
    assert {r["table"] for r in json.loads((out / "transfer.json").read_text())["runs"]} == {
        str(best)
    }
    before = best.read_bytes()
    assert main(["view", *env, "--qtable", str(best), "--greedy", "--steps", "5"]) == 0
    assert best.read_bytes() == before


def test_training_on_from_a_best_table_drops_its_record(tmp_path) -> None:
    q, _, _ = run(tmp_path, "a", 2)
    (tmp_path / "b.qtable").write_bytes(best_path(q).read_bytes())
    run(tmp_path, "b", 1, checks=False)
    table = load_qtable(tmp_path / "b.qtable")
    assert table.meta["episodes"] == 3 and "best" not in table.meta


def test_training_a_best_table_in_place_is_refused(tmp_path, capsys, monkeypatch) -> None:
    """Audit: ``train --qtable X.best.qtable`` trained the kept best table in place (its
    backup rotated: the best snapshot lost) and started ``X.best.csv``. Refused in one
    line naming the way, by train (one robot or many) and view --learn alike; a new table
    started from it trains, and so does a table merely named like one (no record)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    (tmp_path / "c.yaml").write_text("episode: {max_steps: 40}\n")
    env = ["--arena", "room", "--config", "c.yaml"]
    assert main(["train", *env, "--episodes", "4", "--eval-every", "2", "--eval-episodes", "2",
                 "--qtable", "t.qtable", "--quiet"]) == 0  # fmt: skip
    episode = load_qtable(tmp_path / "t.best.qtable").meta["best"]["episode"]
    assert episode in (2, 4)
    line = (
        f"koolio-pm: error: t.best.qtable: the best table kept by train --eval-every (its "
        f"check at episode {episode}): training it would change it in place; start a new "
        "table from it: koolio-pm train --init-qtable t.best.qtable --qtable NEW.qtable"
    )
    best = ["--qtable", "t.best.qtable"]
    for argv in (
        ["train", *env, *best, "--episodes", "6"],
        ["train", *env, *best, "--episodes", "6", "--robots", "2"],
        ["view", *env, *best, "--learn", "--steps", "2"],
    ):
        assert expect_error(capsys, tmp_path, argv) == line
    assert not (tmp_path / "t.best.csv").exists()
    more = str(episode + 1)
    assert main(["train", *env, "--init-qtable", "t.best.qtable", "--qtable", "n.qtable",
                 "--episodes", more, "--quiet"]) == 0  # fmt: skip
    assert load_qtable(tmp_path / "n.qtable").meta["episodes"] == episode + 1
    (tmp_path / "u.best.qtable").write_bytes((tmp_path / "t.qtable").read_bytes())
    assert main(["train", *env, "--qtable", "u.best.qtable", "--episodes", "5", "--quiet"]) == 0


def test_file_names() -> None:
    assert best_path("runs/x.qtable") == Path("runs/x.best.qtable")
    assert evals_path("runs/x.csv", "t.qtable") == Path("runs/x.evals.csv")
    assert evals_path(None, "runs/t.qtable") == Path("runs/t.evals.csv")


def test_another_runs_files_are_refused_before_anything_is_written(tmp_path) -> None:
    run(tmp_path, "a", 2)
    for name in ("a.evals.csv", "a.best.qtable"):
        (tmp_path / name).rename(tmp_path / f"new.{name.split('.', 1)[1]}")
        with pytest.raises(KoolioError, match="another run"):
            run(tmp_path, "new", 2)
        assert not (tmp_path / "new.qtable").exists() and not (tmp_path / "new.csv").exists()
        (tmp_path / f"new.{name.split('.', 1)[1]}").unlink()
    (tmp_path / "new.evals.csv").write_text("episode,reward\n")
    with pytest.raises(KoolioError, match="not an evaluations file"):
        run(tmp_path, "new", 2)
    assert not (tmp_path / "new.qtable").exists()


def test_a_bad_evaluations_file_is_refused_before_anything_is_written(tmp_path) -> None:
    q, log, _ = run(tmp_path, "a", 2)
    evals = tmp_path / "a.evals.csv"
    good = evals.read_text()
    for bad, message in (
        (good + "x,y\n", "line 3: not a row of an evaluations file"),
        (good + good.splitlines()[1] + "\n", "line 3: episode 2 after 2"),
    ):
        evals.write_text(bad)
        before = q.read_bytes(), log.read_bytes()
        with pytest.raises(KoolioError, match=message):
            run(tmp_path, "a", 2)
        assert (q.read_bytes(), log.read_bytes()) == before and evals.read_text() == bad


def test_a_best_table_of_another_layout_is_refused(tmp_path) -> None:
    run(tmp_path, "a", 2)
    cfg = config()
    cfg.sensors.camera.camera_sensors_deg = [0.0, -90.0, 90.0]
    with pytest.raises(QTableError, match=r"a\.best\.qtable: sensors\.camera_sensors_deg"):
        CheckFiles.open(
            RunIdentity.of_run(KoolioEnv("room", config=cfg)),
            QTableStore(tmp_path / "a.qtable"),
            None,
        )


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (["--eval-every", "0"], "--eval-every: must be in 1..1,000,000,000, got 0"),
        (["--eval-every", "9" * 23], "--eval-every: must be in 1..1,000,000,000, got 9"),
        (["--eval-every", "2", "--eval-episodes", "0"], "--eval-episodes: must be in 1..1,"),
        (["--eval-episodes", "5"], "--eval-episodes: only with --eval-every N"),
    ],
)
def test_bad_flags_one_line_exit_2(tmp_path, capsys, flags, message) -> None:
    q = tmp_path / "q.qtable"
    assert main(["train", "--arena", "room", "--episodes", "1", "--qtable", str(q), *flags]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"koolio-pm: error: {message}") and err.count("\n") == 1
    assert not q.exists()


def test_eval_epsilon(tiny_run, capsys) -> None:
    """``eval --epsilon E``: the acting policy, its own seeded draws, E in the JSON."""
    base = ["eval", "--arena", "room", "--config", str(tiny_run / "tiny.yaml")]
    base += ["--qtable", str(tiny_run / "q.qtable"), "--episodes", "6", "--json"]

    def figures(*flags: str) -> str:
        assert main([*base, *flags]) == 0
        return capsys.readouterr().out

    greedy = figures()
    assert '"epsilon": 0.0' in greedy  # without the flag: greedy, and the JSON says so
    assert figures("--epsilon", "0") == greedy
    half = figures("--epsilon", "0.5")
    assert '"epsilon": 0.5' in half and half == figures("--epsilon", "0.5")
    assert half.replace('"epsilon": 0.5', '"epsilon": 0.0') != greedy
    for bad in ("-0.1", "1.5", "nan"):
        assert main([*base, "--epsilon", bad]) == 2
        assert "--epsilon: must be in [0, 1]" in capsys.readouterr().err
