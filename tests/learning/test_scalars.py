"""train --tensorboard: the run's scalars in TensorBoard's event files, read back with
TensorBoard's own reader, continued by a resumed run."""

from __future__ import annotations

from koolio_pymunk.apps.cli import main
from koolio_pymunk.learning.training import train
from koolio_pymunk.store.config import load_config
from koolio_pymunk.store.episode_log import log_rows
from koolio_pymunk.store.qtable import QTableStore
from koolio_pymunk.task.env import KoolioEnv


def _accumulate(folder):
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    acc = EventAccumulator(str(folder))
    acc.Reload()
    return acc


def test_every_episode_and_check_is_a_scalar_at_its_environment_step(tmp_path) -> None:
    env = KoolioEnv("room", config=load_config(overrides={"episode": {"max_steps": 40}}))
    log, tb = tmp_path / "t.csv", tmp_path / "tb"
    train(env, QTableStore(tmp_path / "t.qtable"), 6, 0, log, report=None, eval_every=3,
          eval_episodes=2, tensorboard=tb)  # fmt: skip
    train(env, QTableStore(tmp_path / "t.qtable"), 2, 0, log, report=None, tensorboard=tb)
    acc = _accumulate(tb)
    rows = log_rows(log)
    steps = [sum(int(r["steps"]) for r in rows[: k + 1]) for k in range(len(rows))]
    returns = acc.Scalars("episode/return")
    assert [e.step for e in returns] == steps  # the second run continues the first's steps
    assert [e.value for e in returns] == [float(r["reward"]) for r in rows]
    assert [e.value for e in acc.Scalars("train/episodes")] == [1, 2, 3, 4, 5, 6, 7, 8]
    checks = acc.Scalars("check/goal_rate")
    assert [e.step for e in checks] == [steps[2], steps[5]]
    assert len(list(tb.iterdir())) == 2  # one event file per run


def test_a_tensorboard_path_that_is_a_file_is_refused_in_one_line(tmp_path, capsys) -> None:
    (tmp_path / "tb").write_text("a file")
    q = tmp_path / "q.qtable"
    argv = ["train", "--arena", "room", "--episodes", "1", "--qtable", str(q)]
    assert main([*argv, "--tensorboard", str(tmp_path / "tb")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--tensorboard: is a file, not a folder" in err
    assert not q.exists()
