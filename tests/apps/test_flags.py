"""Every number flag of every command has a range checked where argparse reads it: one
line naming the flag and its range, exit 2, nothing written (issue #21:
``koolio-pm transfer --seed -1`` was a ValueError traceback)."""

from __future__ import annotations

import argparse

import pytest
from inputs import expect_error

from koolio_pymunk.apps import cli
from koolio_pymunk.apps.flags import MAX_EPISODES, float_type, int_type, seed_type

BIG = str(2**63)
#: (argv, words) of a value just out of range (or not an ASCII integer) for every flag.
CASES = [
    (["train", "--seed", "-1"], "--seed: must be >= 0, got -1"),
    (["train", "--seed", BIG], "--seed: must be < 2**63"),
    (["train", "--seed", "١"], "--seed: not an integer"),
    (["train", "--seed", "1_0"], "--seed: not an integer"),
    (["train", "--episodes", "-1"], "--episodes: must be in 0..1,000,000,000, got -1"),
    (["train", "--episodes", str(MAX_EPISODES + 1)], "--episodes: must be in 0.."),
    (["train", "--episodes", "1e3"], "--episodes: not an integer: '1e3'"),
    (["train", "--robots", "0"], "--robots: must be in 1..1024, got 0"),
    (["train", "--robots", "1025"], "--robots: must be in 1..1024, got 1025"),
    (["eval", "--episodes", "-3"], "--episodes: must be in 1.."),
    (["eval", "--episodes", "0"], "--episodes: must be in 1..1,000,000,000, got 0"),
    (["eval", "--seed", BIG], "--seed: must be < 2**63"),
    (["view", "--seed", "-1"], "--seed: must be >= 0"),
    (["view", "--episodes", "-1"], "--episodes: must be in 0.."),
    (["view", "--steps", "-1"], "--steps: must be in 0..1,000,000,000,000, got -1"),
    (["view", "--steps", "9" * 20], "--steps: must be in 0.."),
    (["plot", "--window", "0"], "--window: must be in 1..1,000,000,000, got 0"),
    (["export", "--out", "p.json", "--episode", "-1"], "--episode: must be in 0.."),
    (["export", "--out", "p.json", "--episode", BIG], "--episode: must be in 0.."),
    (["sweep", "s.yaml", "--workers", "0"], "--workers: must be in 1..1024, got 0"),
    (["transfer", "--seed", "-1"], "--seed: must be >= 0, got -1"),
    (["transfer", "--seed", "0", BIG], "--seed: must be < 2**63"),
    (["transfer", "--episodes", "-1"], "--episodes: must be in 0.."),
    (["transfer", "--robot-episodes", "-1"], "--robot-episodes: must be in 0.."),
    (["transfer", "--eval-episodes", "0"], "--eval-episodes: must be in 1.."),
    (["transfer", "--eval-every", "0"], "--eval-every: must be in 1.."),
    (["transfer", "--target", "nan"], "--target: must be in [0, 1], got nan"),
    (["transfer", "--robot-alpha", "inf"], "--robot-alpha: must be in (0, 1], got inf"),
    (["transfer", "--robot-alpha", "0"], "--robot-alpha: must be in (0, 1], got 0"),
    (["train", "--eval-every", BIG], "--eval-every: must be in 1.."),
    (["train", "--eval-every", "2", "--eval-episodes", "0"], "--eval-episodes: must be in 1.."),
    (["eval", "--epsilon", "1.5"], "--epsilon: must be in [0, 1], got 1.5"),
    (["transfer", "--robot-epsilon", "1.5"], "--robot-epsilon: must be in [0, 1]"),
]


@pytest.mark.parametrize(("argv", "words"), CASES, ids=[" ".join(a) for a, _ in CASES])
def test_every_number_flag_is_one_line(tmp_path, monkeypatch, capsys, argv, words):
    monkeypatch.chdir(tmp_path)
    line = expect_error(capsys, tmp_path, argv, words)
    assert line.endswith(f"(see koolio-pm {argv[0]} --help)")


#: A range's refusal written in a command: ``"--robots: must be``, ``f"{flag}: must be``,
#: ``("--episodes", "must be``.
WORDS_OF_A_RANGE = (
    r"[\"'](?:--[a-z][a-z-]*|\{flag\}): must be|[\"']--[a-z][a-z-]*[\"'], [\"']must be"
)


def test_a_flag_s_range_is_checked_once_by_its_type():
    """No command checks a number flag's range again after argparse (``_positive(args.
    episodes)``, ``--robots: must be in ...`` were second checks that a run made after the
    flag's type had): the words ``--FLAG: must be`` are said by :mod:`~koolio_pymunk.apps.
    flags` alone. (``view --screenshot-every K DIR`` reads K itself: two words, one type.)"""
    import re
    from pathlib import Path

    apps = Path(cli.__file__).parent
    again = [
        f"{path.relative_to(apps)}: {m.group(0)}"
        for path in sorted(apps.rglob("*.py"))
        if path.name != "flags.py"
        for m in re.finditer(WORDS_OF_A_RANGE, path.read_text())
    ]
    assert again == [], again


def test_main_returns_the_status_of_argparse(capsys):
    assert cli.main(["train", "--seed", "-1"]) == 2
    assert cli.main(["--version"]) == 0
    assert "koolio-pm" in capsys.readouterr().out


def test_the_types_at_their_bounds():
    assert seed_type("0") == 0 and seed_type(str(2**63 - 1)) == 2**63 - 1
    assert int_type(1, 1024)("1024") == 1024 and int_type(0, 5)(" 3 ") == 3
    assert float_type(0, 1)("1") == 1.0 and float_type(0, 1)("0") == 0.0
    for parse, text in ((float_type(0, 1, low_open=True), "0"), (float_type(0, 1), "-inf")):
        with pytest.raises(argparse.ArgumentTypeError):
            parse(text)


@pytest.mark.parametrize(
    ("spec", "words"),
    [
        ("episodes: 10\nseeds: 1000000000000\n", "seeds: must be <= 10,000"),
        ("episodes: 10\nseeds: [-1]\n", "seeds[0]: must be >= 0"),
        (f"episodes: 10\nseeds: [{2**63}]\n", "seeds[0]: must be <= 9,223,372,036,854,775,807"),
        ("episodes: 10000000000\n", "episodes: must be <= 1,000,000,000"),
        ("episodes: 10\neval_episodes: 10000000000\n", "eval_episodes: must be <= 1,000,000,000"),
    ],
)
def test_sweep_spec_numbers_are_bounded(tmp_path, monkeypatch, capsys, spec, words):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.yaml").write_text(spec)
    expect_error(capsys, tmp_path, ["sweep", "s.yaml", "--dry-run"], f"s.yaml: {words}")
