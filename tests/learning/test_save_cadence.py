"""Saving off the step path: train --save-every K / --save-seconds T, always at the end,
on Ctrl-C and on SIGTERM; the files reconciled after a SIGKILL (issue #19)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from inputs import same_run

from koolio_pymunk.apps.cli import main
from koolio_pymunk.learning.training import train
from koolio_pymunk.store import qtable as qtable_module
from koolio_pymunk.store.config import load_config
from koolio_pymunk.store.episode_log import log_rows
from koolio_pymunk.store.qtable import QTableStore, load_qtable
from koolio_pymunk.task.env import KoolioEnv

CONFIG = "episode: {max_steps: 40}\n"
#: The pymunk reference sensors: the Python episode loop (on the step engine a 40-step
#: episode runs inside one compiled call, before a signal is looked at), so a signal lands
#: inside an episode.
PYTHON_LOOP = CONFIG + "sensors: {backend: pymunk}\n"


def env() -> KoolioEnv:
    return KoolioEnv("room", config=load_config(overrides={"episode": {"max_steps": 40}}))


def counted_saves(monkeypatch) -> list[int]:
    saves: list[int] = []
    real = qtable_module.QTableStore.save

    def save(self, table):
        saves.append(int(table.meta.get("episodes", 0)))
        return real(self, table)

    monkeypatch.setattr(qtable_module.QTableStore, "save", save)
    return saves


@pytest.mark.parametrize(("every", "seconds", "expected"), [
    (7, None, [7, 14, 20]),
    (1, 1e9, list(range(1, 21))),
    (100, 1e9, [20]),
    (100, 1e-12, list(range(1, 21))),
])  # fmt: skip
def test_the_cadence_changes_when_not_what(tmp_path, monkeypatch, every, seconds, expected):
    """Saving every K episodes or T seconds writes the same final bytes as saving after
    every episode; the saves happen when asked, and always at the end."""
    train(env(), QTableStore(tmp_path / "a.qtable"), 20, 3, tmp_path / "a.csv", report=None)
    saves = counted_saves(monkeypatch)
    b = tmp_path / "b.qtable"
    train(env(), QTableStore(b), 20, 3, tmp_path / "b.csv", report=None,
          save_every=every, save_seconds=seconds, fsync="episode")  # fmt: skip
    assert saves == expected
    assert b.read_bytes() == (tmp_path / "a.qtable").read_bytes()
    assert (tmp_path / "b.csv").read_bytes() == (tmp_path / "a.csv").read_bytes()


def _argv(folder: Path, name: str, *extra: str) -> list[str]:
    return [
        *("train", "--arena", "room", "--config", str(folder / "c.yaml"), "--quiet"),
        *("--episodes", "60", "--seed", "5", "--qtable", str(folder / f"{name}.qtable")),
        *extra,
    ]


def _wait_for_rows(log: Path, rows: int, proc: subprocess.Popen) -> None:
    deadline = time.monotonic() + 120
    while not (log.exists() and log.read_text().count("\n") > rows + 1):  # a run line, a header
        assert proc.poll() is None and time.monotonic() < deadline, "the run ended first"
        time.sleep(0.005)


def test_a_sigkill_between_saves_resumes_exactly(tmp_path) -> None:
    """Killed with rows logged beyond the last save: the same command moves those rows
    aside, runs their episodes again and ends byte-identical to an uninterrupted run."""
    (tmp_path / "c.yaml").write_text(CONFIG)
    assert main(_argv(tmp_path, "full", "--save-every", "8")) == 0
    cmd = [sys.executable, "-m", "koolio_pymunk", *_argv(tmp_path, "part", "--save-every", "8")]
    for _ in range(5):  # a kill between a save and its row leaves the row missing (by
        for f in tmp_path.glob("part.*"):  # design, a warning on resume): kill again
            f.unlink()
        proc = subprocess.Popen(cmd, stderr=subprocess.PIPE)
        _wait_for_rows(tmp_path / "part.csv", 12, proc)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        saved = int(load_qtable(tmp_path / "part.qtable").meta["episodes"])
        logged = len(log_rows(tmp_path / "part.csv"))
        if logged >= saved:
            break
    assert saved % 8 == 0 and saved < 60 and logged >= saved  # the premise
    assert main(_argv(tmp_path, "part", "--save-every", "8")) == 0
    for suffix in (".qtable", ".csv"):  # the same run from another command line
        full, part = tmp_path / f"full{suffix}", tmp_path / f"part{suffix}"
        assert same_run(part, full), suffix


def test_sigterm_saves_and_stops_like_ctrl_c(tmp_path) -> None:
    """SIGTERM (a scheduler's stop) with a long cadence: the unfinished episode folded in,
    the table saved, the row logged ``interrupted``, exit 143 (128 + SIGTERM), table and
    log in step."""
    (tmp_path / "c.yaml").write_text(PYTHON_LOOP)
    argv = _argv(tmp_path, "t", "--save-every", "1000")
    proc = subprocess.Popen([sys.executable, "-m", "koolio_pymunk", *argv], stderr=subprocess.PIPE)
    _wait_for_rows(tmp_path / "t.csv", 5, proc)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    rows = log_rows(tmp_path / "t.csv")
    table = load_qtable(tmp_path / "t.qtable")
    assert rows[-1]["outcome"] == "interrupted"
    assert int(table.meta["episodes"]) == len(rows) - 1  # every finished episode saved
    assert b"Traceback" not in err


def test_exit_without_save_writes_nothing_more(tmp_path, monkeypatch) -> None:
    """Ctrl-C with --discard-unfinished and a long cadence: nothing is written at the
    stop; the file keeps its last save (the log ahead of it, as after a SIGKILL)."""
    (tmp_path / "c.yaml").write_text(PYTHON_LOOP)
    from koolio_pymunk.task.env import KoolioEnv as Env

    calls = {"n": 0}
    real = Env.simulate

    def simulate(self, action):
        calls["n"] += 1
        if calls["n"] == 215:  # inside episode 6 (episodes here are at most 40 steps)
            os.kill(os.getpid(), signal.SIGINT)
        return real(self, action)

    monkeypatch.setattr(Env, "simulate", simulate)
    saves = counted_saves(monkeypatch)
    argv = _argv(tmp_path, "d", "--save-every", "3", "--discard-unfinished", "--fsync", "episode")
    assert main(argv) == 130
    assert saves and all(s % 3 == 0 for s in saves)  # no save at the stop
    table = load_qtable(tmp_path / "d.qtable")
    assert int(table.meta["episodes"]) == saves[-1]
    logged = (tmp_path / "d.csv").read_text().count("\n") - 1
    assert logged > saves[-1]  # the premise: finished episodes beyond the last save


@pytest.mark.parametrize(("flags", "message"), [
    (["--save-every", "0"], "--save-every: must be in 1.."),
    (["--save-seconds", "0"], "--save-seconds: must be in (0, "),
    (["--save-seconds", "nan"], "--save-seconds: must be in (0, "),
])  # fmt: skip
def test_bad_cadence_flags_are_one_line(tmp_path, capsys, flags, message) -> None:
    q = tmp_path / "q.qtable"
    assert main(["train", "--arena", "room", "--episodes", "1", "--qtable", str(q), *flags]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and not q.exists()
