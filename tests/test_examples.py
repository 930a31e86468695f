"""examples/tabular_q.py, the outside tabular learner of docs/envs.md: with Gymnasium's
API and the env's info alone it learns what ``koolio-pm train --config one-step-q``
learns, with and without the no-undo rule."""

from __future__ import annotations

import contextlib
import importlib.util
import io
import json
from pathlib import Path
from types import ModuleType

import pytest

from koolio_pymunk.apps import cli

REPO = Path(__file__).resolve().parents[1]
#: The comparison's budget: the room with a 300-step cap, 100 training episodes, 100
#: greedy ones, seeds 0-7 (about 25 s on two cores). The rule's gain is large there
#: (greedy 0.70 -> 0.88), so a learner that ignored the mask would fail under the rule.
EPISODES, EVALS, CAP, SEEDS = 100, 100, 300, range(8)
#: Largest difference of the mean greedy goal rates over the seeds. Measured (room, seeds
#: 0-9, example against train, without / with the rule): 300-step cap, after 100
#: episodes, 0.683 / 0.674 and 0.875 / 0.892; the default 1500-step cap, after 100,
#: 200 and 300 episodes, 0.727 / 0.743 and 0.906 / 0.914, 0.828 / 0.909 and 0.964 /
#: 0.985, 0.964 / 0.914 and 0.978 / 0.994. One seed's rate spreads by about 0.15 (sd).
TOLERANCE = 0.10


def load_example() -> ModuleType:
    spec = importlib.util.spec_from_file_location("tabular_q", REPO / "examples/tabular_q.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def train_rate(folder: Path, seed: int, no_undo: bool) -> float:
    """``koolio-pm train`` then ``koolio-pm eval --json``: the greedy goal rate."""
    config = folder / "rule.yaml"  # the one-step-q profile, with or without the rule
    rule = str(no_undo).lower()
    learner = "{algorithm: q, alpha: 0.2, epsilon: {start: 0.15, end: 0.01, decay_episodes: 600}"
    config.write_text(f"learner: {learner}, no_undo: {rule}}}\nepisode: {{max_steps: {CAP}}}\n")
    table = str(folder / f"s{seed}-{no_undo}.qtable")
    common = ["--arena", "room", "--seed", str(seed), "--config", str(config), "--qtable", table]
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert (
            cli.main(["train", *common, "--episodes", str(EPISODES), "--log", "", "--quiet"]) == 0
        )
        out.truncate(0)
        out.seek(0)
        assert cli.main(["eval", *common, "--episodes", str(EVALS), "--json"]) == 0
    figures = json.loads(out.getvalue())
    assert figures["episodes"] == EVALS and figures["goal"] == "201"
    return figures["goal_rate"]


@pytest.fixture(scope="module")
def rates(tmp_path_factory: pytest.TempPathFactory) -> dict[tuple[str, bool], float]:
    """Mean greedy goal rates over :data:`SEEDS`, by learner and rule."""
    folder = tmp_path_factory.mktemp("tabular_q")
    example = load_example()
    out = {}
    for no_undo in (False, True):
        ours = [
            example.run("koolio_pymunk/Room-v0", EPISODES, EVALS, s, no_undo, max_steps=CAP)
            for s in SEEDS
        ]
        theirs = [train_rate(folder, s, no_undo) for s in SEEDS]
        out["example", no_undo] = sum(ours) / len(ours)
        out["train", no_undo] = sum(theirs) / len(theirs)
    return out


@pytest.mark.parametrize("no_undo", [False, True], ids=["without the rule", "with the rule"])
def test_the_outside_learner_reaches_trains_greedy_goal_rate(rates, no_undo: bool) -> None:
    assert abs(rates["example", no_undo] - rates["train", no_undo]) <= TOLERANCE, rates


def test_both_learners_gain_from_the_rule_more_than_the_tolerance(rates) -> None:
    """The premise of the comparison: at this budget the rule matters, so the example's
    use of ``info["action_mask"]`` is what the first test checks."""
    for learner in ("example", "train"):
        assert rates[learner, True] - rates[learner, False] > TOLERANCE, rates
