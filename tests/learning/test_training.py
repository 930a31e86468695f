"""Training loop: reproducibility, resume, Exit / Exit Without Save, evaluation."""

from __future__ import annotations

import pytest

from koolio_pymunk.learning.evaluation import evaluate
from koolio_pymunk.learning.qlearning import QLearner
from koolio_pymunk.learning.training import train
from koolio_pymunk.store.config import Config
from koolio_pymunk.store.episode_log import LOG_FIELDS, log_rows
from koolio_pymunk.store.qtable import QTableStore, load_qtable
from koolio_pymunk.task.action_rules import allowed
from koolio_pymunk.task.env import KoolioEnv


def small_env() -> KoolioEnv:
    cfg = Config()
    cfg.episode.max_steps = 60
    return KoolioEnv("room", config=cfg)


def run(tmp_path, name: str, episodes: int, seed: int = 0, **kw):
    q = tmp_path / f"{name}.qtable"
    log = tmp_path / f"{name}.csv"
    res = train(small_env(), QTableStore(q), episodes, seed, log, report=None, **kw)
    return q, log, res


def test_same_seed_same_bytes(tmp_path) -> None:
    qa, la, _ = run(tmp_path, "a", 6)
    qb, lb, _ = run(tmp_path, "b", 6)
    qc, _, _ = run(tmp_path, "c", 6, seed=1)
    assert qa.read_bytes() == qb.read_bytes()
    assert la.read_bytes() == lb.read_bytes()
    assert qa.read_bytes() != qc.read_bytes()


def test_resume_continues_exactly(tmp_path) -> None:
    q_full, log_full, _ = run(tmp_path, "full", 7)
    q_part, log_part, _ = run(tmp_path, "part", 4)
    run(tmp_path, "part", 3)  # resumes from part.qtable: episodes 4..6
    assert q_part.read_bytes() == q_full.read_bytes()
    assert log_part.read_bytes() == log_full.read_bytes()


def test_log_format(tmp_path) -> None:
    _, log, res = run(tmp_path, "a", 3)
    rows = log_rows(log)
    assert tuple(rows[0].keys()) == LOG_FIELDS
    assert [int(r["episode"]) for r in rows] == [0, 1, 2]
    assert all(r["outcome"] in ("goal", "end_of_world", "truncated") for r in rows)
    assert [int(r["steps"]) for r in rows] == [r.steps for r in res.results]
    assert load_qtable(tmp_path / "a.qtable").meta["episodes"] == 3


def _interrupt_after(monkeypatch, n: int) -> None:
    calls = {"n": 0}
    original = KoolioEnv.simulate

    def transition(self, action):
        calls["n"] += 1
        if calls["n"] > n:
            raise KeyboardInterrupt
        return original(self, action)

    monkeypatch.setattr(KoolioEnv, "simulate", transition)


def test_ctrl_c_folds_unfinished_episode(tmp_path, monkeypatch) -> None:
    """The Python loop (the interrupt is raised inside ``simulate``)."""
    q, log, _ = run(tmp_path, "x", 2)
    after_two = load_qtable(q)
    _interrupt_after(monkeypatch, 25)
    _, _, res = run(tmp_path, "x", 5, compiled=False)
    assert res.interrupted
    folded = load_qtable(q)
    assert folded.rows != after_two.rows  # the partial episode's updates were saved
    assert folded.meta["episodes"] == 2  # ...but it is not counted as finished
    last = log_rows(log)[-1]
    assert last["outcome"] == "interrupted" and last["episode"] == "2"


def test_discard_unfinished_leaves_file_byte_identical(tmp_path, monkeypatch) -> None:
    q, log, _ = run(tmp_path, "y", 2)
    before = q.read_bytes()
    log_before = log.read_bytes()
    _interrupt_after(monkeypatch, 25)
    _, _, res = run(tmp_path, "y", 5, discard_unfinished=True, compiled=False)
    assert res.interrupted
    assert q.read_bytes() == before
    assert log.read_bytes() == log_before


def test_evaluate_is_greedy_and_does_not_learn(tmp_path, monkeypatch) -> None:
    """Every action of an evaluation is one of highest Q in the table's row of its state
    (of those the no-undo rule allows; any action in a state never visited, whose row is
    all ``q_init``), recorded step by step; the table is left as it was, the same seed
    gives the same figures, and the outcomes' rates (wrong door included) sum to 1."""
    q, _, _ = run(tmp_path, "e", 8)
    table = load_qtable(q)
    rows = {k: list(v) for k, v in table.rows.items()}
    steps: list[tuple[int, int, list[int], float]] = []
    choose = QLearner.act

    def recorded(agent: QLearner, state: int) -> int:
        row = agent.table.peek(state)
        choices = allowed(agent.n_actions, agent.bar)
        best = (
            choices
            if row is None
            else [a for a in choices if row[a] == max(row[c] for c in choices)]
        )
        action = choose(agent, state)
        steps.append((state, action, best, agent.epsilon))
        return action

    monkeypatch.setattr(QLearner, "act", recorded)
    env = small_env()
    a = evaluate(env, table, 4, seed=0, compiled=False)  # the reference: its act is patched
    assert [(s, action) for s, action, best, _ in steps if action not in best] == []
    assert {eps for *_, eps in steps} == {0.0}
    told = sum(len(best) == 1 for _, _, best, _ in steps)  # a step where exploring would show
    assert told >= 20, f"only {told} steps in states with one best action: a weak premise"
    assert len(steps) == round(a.mean_steps * a.episodes)  # every step chose through act
    assert evaluate(env, table, 4, seed=0) == a
    assert table.rows == rows
    rates = (a.goal_rate, a.end_of_world_rate, a.wrong_door_rate, a.truncated_rate)
    assert sum(rates) == pytest.approx(1.0)


def test_the_run_identity_takes_the_arena_its_env_loaded(tmp_path) -> None:
    """A run's identity is made from the arena its env loaded, not from the file read
    again: that arena's active goal is what a table recording no goal was learned for
    (an edit of the file after the env loaded it changes neither the run nor its
    identity), another goal made active (``goal``) is recorded, and a sibling (the
    periodic check's robot) has the same identity."""
    from koolio_pymunk.store.run_identity import RunIdentity
    from koolio_pymunk.world.arena import arena_path

    text = arena_path("hallway").read_text()
    arena = tmp_path / "h.yaml"
    arena.write_text(text)
    env = KoolioEnv(str(arena))
    first = env.arena.active_goal
    other = next(g for g in env.arena.goal_names() if g != first)
    arena.write_text(text.replace(f"active_goal: '{first}'", f"active_goal: '{other}'"))
    assert arena.read_text() != text  # the premise: the file names another goal now
    run = RunIdentity.of_run(env)
    assert (run.goal, run.home_goal) == (None, first)
    chosen = KoolioEnv(str(arena), goal=first)  # the file's active goal is `other` now
    mine = RunIdentity.of_run(chosen)
    assert (mine.goal, mine.home_goal) == (first, other)
    assert RunIdentity.of_run(chosen.sibling()) == mine
    assert RunIdentity.of_run(env.sibling()) == run


def test_a_run_that_fails_before_its_first_episode_releases_its_files(tmp_path, monkeypatch):
    """A failure between opening the run's files and its first episode (a Ctrl-C during
    the first compile, say) closes the table, the log and the checks' files: their locks
    are released, even while the traceback is kept (as an interactive session keeps the
    last one), whose frames would otherwise hold them."""
    from koolio_pymunk.learning import engine
    from koolio_pymunk.store import locks

    def stopped(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(engine, "robots", stopped)
    q, log = tmp_path / "q.qtable", tmp_path / "q.csv"
    with pytest.raises(KeyboardInterrupt) as kept:
        train(KoolioEnv("room"), QTableStore(q), 2, 0, log, report=None, eval_every=1)
    for f in (q, log, tmp_path / "q.evals.csv", tmp_path / "q.best.qtable"):
        assert locks._held(locks.lock_path(f)) is None, f
    assert kept.traceback  # the frames were alive while the locks were looked at
