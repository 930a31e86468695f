"""koolio-pm transfer: the runtime driven on a simulated robot as the simulator itself
steps (rescues included), the command end to end with tiny budgets, reproducibility,
bad input."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
from inputs import same_run

from koolio_pymunk import robot_runtime as rt
from koolio_pymunk.apps.cli import main
from koolio_pymunk.apps.export import policy_document
from koolio_pymunk.apps.transfer import RobotAgent, drive_episode, plot_or_note
from koolio_pymunk.learning.episodes import ROBOT_STREAM, Episodes, episode_seeds
from koolio_pymunk.learning.training import train
from koolio_pymunk.store.config import Config
from koolio_pymunk.store.qtable import QTableStore, load_qtable
from koolio_pymunk.task.env import KoolioEnv

CONFIG = "sensors: {noise: {model: none}}\nepisode: {max_steps: 40}\n"


class Recorder(rt.RobotLearner):
    """A RobotLearner that records what the driving loop tells it."""

    def __init__(self, *args, **kw) -> None:
        super().__init__(*args, **kw)
        self.calls: list[tuple] = []

    def step(self, action, reward, next_codes, terminal, bump=False, rescued=False) -> None:
        key = self.policy.state_key(next_codes)
        self.calls.append(("step", action, reward, key, terminal))
        super().step(action, reward, next_codes, terminal, bump, rescued)

    def moved(self, codes) -> None:
        self.calls.append(("moved", self.policy.state_key(codes)))
        super().moved(codes)


def rescue_config() -> Config:
    cfg = Config()
    cfg.episode.max_steps = 120
    cfg.rescue.max_steps_before_rescue = 0
    cfg.rescue.rescue_chance = 0.5
    return cfg


def test_driven_runtime_sees_what_the_simulator_steps(tmp_path) -> None:
    """Random actions chosen by the runtime on a koolio-real robot, then replayed through
    the env's own ``transition`` (auto rescue on): the same states, rewards, ends and
    rescues, step by step; the runtime's judgement never differs."""
    cfg = rescue_config()
    env = KoolioEnv("room", config=cfg, world="koolio-real")
    store = QTableStore(tmp_path / "t.qtable")
    train(env, store, 1, seed=0, report=None)
    policy = rt.Policy(policy_document(load_qtable(store.path), cfg))
    robot = KoolioEnv("room", config=cfg, world="koolio-real")
    learner = Recorder(policy, epsilon=1.0, seed=3)
    loop = Episodes(robot, RobotAgent(robot, policy, learner), 11, ROBOT_STREAM)
    episode = drive_episode(loop, 0)
    assert episode.mismatches == 0
    moves = [c for c in learner.calls if c[0] == "moved"]
    assert moves and episode.rescued  # the test exercises rescues

    replay = KoolioEnv("room", config=cfg, world="koolio-real")
    assert replay.config.rescue.auto_rescue_toggle
    replay.reset(seed=episode_seeds(11, 0, ROBOT_STREAM)[0])
    calls = learner.calls
    for i, call in enumerate(calls):
        if call[0] == "moved":
            continue
        _, action, reward, key, terminal = call
        nxt, r, term, _ = replay.transition(action)
        assert (nxt, r, term) == (key, reward, terminal)
        after = calls[i + 1] if i + 1 < len(calls) else None
        if after is not None and after[0] == "moved":
            assert replay.rescued and replay.state_key == after[1]
        else:
            assert not replay.rescued
    assert (replay.steps, replay.bumps) == (episode.steps, episode.bumps)
    assert episode.outcome == (replay.judgement.event if term else "truncated")


def transfer(tmp_path: Path, out: str, *extra: str) -> int:
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text(CONFIG)
    args = ["transfer", "--arena", "room", "--config", str(cfg), "--out", str(tmp_path / out)]
    args += ["--episodes", "3", "--robot-episodes", "3", "--eval-episodes", "2"]
    return main(args + ["--eval-every", "2", *extra])


def without_timing(path: Path) -> dict:
    doc = json.loads(path.read_text())
    assert doc.pop("timing")["seconds"] >= 0
    return doc


def test_transfer_command_end_to_end_and_reproducible(tmp_path, capsys) -> None:
    assert transfer(tmp_path, "a", "--seed", "0", "1", "--target", "0") == 0
    out = capsys.readouterr().out
    assert "robot episode    3/3: greedy goal rate" in out
    assert "seed  trained in" in out and "trained in the ideal world: greedy" in out
    assert "trained in koolio-real-dr: greedy" in out
    doc = without_timing(tmp_path / "a" / "transfer.json")
    assert doc["format"] == "koolio-transfer" and doc["settings"]["seeds"] == [0, 1]
    assert [(r["seed"], r["source"]) for r in doc["runs"]] == [
        (0, "ideal"),
        (0, "dr"),
        (1, "ideal"),
        (1, "dr"),
    ]
    for r in doc["runs"]:
        robot = r["robot"]
        assert [c["episode"] for c in robot["checks"]] == [0, 2, 3]
        assert robot["recovered_at"] == 0  # target 0: recovered before learning
        assert robot["learning"]["episodes"] == 3 and robot["learning"]["judge_mismatches"] == 0
        assert robot["alpha"] == 0.1 and robot["epsilon"] == pytest.approx(0.15 - 0.14 * 3 / 150)
        assert r["table_episodes"] == 3 and set(r["greedy"]) == {"ideal", "real"}
        log = (tmp_path / "a" / robot["log"]).read_text().splitlines()
        assert [row.split(",")[0] for row in log[1:]] == ["3", "4", "5"]  # after training
        policy = rt.Policy.load(str(tmp_path / "a" / robot["policy"]))
        assert policy.episodes == 6 and policy.extra["world"] == "koolio-real"
    assert doc["summary"]["ideal"]["recovered"] == 2
    if "matplotlib" in sys.modules or _has_matplotlib():
        assert (tmp_path / "a" / "transfer.png").read_bytes()[:4] == b"\x89PNG"

    assert transfer(tmp_path, "b", "--seed", "0", "1", "--target", "0", "--quiet") == 0
    assert without_timing(tmp_path / "b" / "transfer.json") == doc
    for name in ("ideal.qtable", "dr.csv", "ideal-robot.csv", "dr-robot.policy.json"):
        for seed in (0, 1):
            a, b = (tmp_path / d / f"seed-{seed}" / name for d in "ab")
            assert same_run(a, b), name


def test_a_training_stage_stopped_by_ctrl_c_stops_the_experiment(tmp_path, monkeypatch) -> None:
    """Ctrl-C (or SIGTERM) taken by a training stage stops the whole experiment (exit 130,
    the stage's table kept) instead of going on with a half-trained table; later Ctrl-Cs
    are ignored by then, so nothing else could stop it."""
    import dataclasses

    from koolio_pymunk.apps import transfer as experiment

    real, calls = experiment.train, []

    def stopped(*args, **kwargs):
        calls.append(args[1].path.name)
        return dataclasses.replace(real(*args, **kwargs), interrupted=True)

    monkeypatch.setattr(experiment, "train", stopped)
    assert transfer(tmp_path, "a", "--seed", "0", "1") == 130
    assert calls == ["ideal.qtable"]  # no later stage or seed ran
    assert (tmp_path / "a" / "seed-0" / "ideal.qtable").exists()
    assert not (tmp_path / "a" / "transfer.json").exists()


def _has_matplotlib() -> bool:
    try:
        import matplotlib  # noqa: F401
    except ModuleNotFoundError:
        return False
    return True


def test_robot_settings_and_loaded_tables(tmp_path, capsys) -> None:
    """--robot-alpha / --robot-epsilon reach the runtime; --qtable / --dr-qtable are used
    as given, ``{seed}`` standing for the run seed (no training)."""
    assert transfer(tmp_path, "a", "--no-plot") == 0
    table = tmp_path / "a" / "seed-0" / "ideal.qtable"
    pattern = str(tmp_path / "a" / "seed-{seed}" / "ideal.qtable")
    args = ("--qtable", pattern, "--dr-qtable", str(table), "--no-plot")
    assert transfer(tmp_path, "b", *args, "--robot-alpha", "0.5", "--robot-epsilon", "0.1") == 0
    doc = without_timing(tmp_path / "b" / "transfer.json")
    assert {(r["robot"]["alpha"], r["robot"]["epsilon"]) for r in doc["runs"]} == {(0.5, 0.1)}
    assert {r["table"] for r in doc["runs"]} == {str(table)}
    assert not (tmp_path / "b" / "seed-0" / "ideal.qtable").exists()
    assert not (tmp_path / "b" / "transfer.png").exists()


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (("--eval-every", "0"), "--eval-every: must be in 1..1,000,000,000, got 0"),
        (("--seed", "-1"), "--seed: must be >= 0, got -1"),
        (("--robot-alpha", "nan"), "--robot-alpha: must be in (0, 1], got nan"),
        (("--robot-alpha", "0"), "--robot-alpha: must be in (0, 1], got 0"),
        (("--target", "1.5"), "--target: must be in [0, 1]"),
        (("--robot-epsilon", "-0.1"), "--robot-epsilon: must be in [0, 1], got -0.1"),
        (("--seed", "1", "1"), "--seed: repeated seed"),
        (("--world", "no-such-world"), "--world: no-such-world: no such world profile"),
        (("--dr-world", "no-such-world"), "--dr-world: no-such-world: no such world profile"),
        (("--dr-world", "paper"), "--dr-world: paper: a configuration profile, not a world"),
        (("--goal", "random"), "--goal: random"),
        (("--qtable", "missing.qtable"), "missing.qtable: cannot read"),
    ],
)
def test_bad_input_one_line_and_nothing_written(tmp_path, capsys, extra, message) -> None:
    assert transfer(tmp_path, "out", *extra) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("koolio-pm: error: ") and message in err
    assert not (tmp_path / "out").exists()


def test_an_earlier_run_is_never_overwritten(tmp_path, capsys) -> None:
    (tmp_path / "out").mkdir()
    keep = tmp_path / "out" / "transfer.json"
    keep.write_text("earlier")
    assert transfer(tmp_path, "out") == 2
    err = capsys.readouterr().err
    assert "--out: not a new or empty folder" in err and err.count("\n") == 1
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["transfer.json"]
    assert keep.read_text() == "earlier"


def test_no_matplotlib_skips_the_plot_with_a_note(tmp_path, monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    lines: list[str] = []
    plot_or_note({}, tmp_path / "transfer.png", lines.append)
    assert lines == [
        "note: transfer: matplotlib is not installed: pip install 'koolio-pymunk[view]'; "
        "transfer.png skipped"
    ]
    assert not (tmp_path / "transfer.png").exists()
