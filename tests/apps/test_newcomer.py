"""A newcomer's first hour (issue 20): no silent surprises, numbers that explain themselves.

Each test is a trap a new user fell into, checked as that user meets it: the README's
screenshot recipes must not train the quick start's table, a resumed ``train`` says what
it resumes and ``--episodes`` is a total, a table trained for another goal or world is
not quietly continued, ``eval`` shows every outcome and where it scores, errors come
first and leave nothing behind, a mistyped flag gets a did-you-mean.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

from inputs import learned, open_table, run

from koolio_pymunk.apps import cli
from koolio_pymunk.store.config import PROFILE_DIR, load_config
from koolio_pymunk.store.qtable import QTableStore, load_qtable
from koolio_pymunk.store.run_identity import sensor_signature
from koolio_pymunk.task.env import KoolioEnv
from koolio_pymunk.world.arena import arena_record
from tests.inputs import expect_error, header_of

REPO = Path(__file__).resolve().parents[2]
ROOM = ["--arena", "room", "--config", "tiny.yaml"]


def files_of(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


# -- 1. the window learns into a table only when asked ----------------------------------------
def readme_view_recipes() -> list[list[str]]:
    """The README's headless ``view`` commands (screenshots, frame sequences) of the quick
    start's table (a recipe that names its own ``--qtable``, such as the shared arena's, is
    run after the command that makes that table by ``tests/test_docs.py``)."""
    from tests.test_docs import documented_commands

    out = []
    for words in documented_commands("README.md"):
        own_table = "--qtable" in words
        if "view" in words and any(w.startswith("--screenshot") for w in words) and not own_table:
            out.append(words[words.index("view") :])
    return out


def _cut(words: list[str]) -> list[str]:
    """A README view command with a few steps (and a frame every step)."""
    words = list(words)
    words[words.index("--steps") + 1] = "40"
    if "--screenshot-every" in words:
        words[words.index("--screenshot-every") + 1] = "20"
    return words


def test_readme_screenshot_recipes_leave_the_quick_start_table_as_it_was(here, capsys) -> None:
    recipes = readme_view_recipes()
    assert len(recipes) >= 2, recipes  # --screenshot and --screenshot-every
    assert run(capsys, "train", "--episodes", "2", "--quiet")[0] == 0  # the quick start
    runs = here / "runs"
    before = files_of(runs)
    for words in recipes:
        code, out, _ = run(capsys, *_cut(words))
        assert code == 0, words
        first, last = out.strip().splitlines()[0], out.strip().splitlines()[-1]
        assert first.startswith("view: watching runs/hallway.qtable (2 episodes")
        assert "--learn trains it further" in first
        assert "greedy: runs/hallway.qtable unchanged" in last
    after = files_of(runs)
    assert {k: v for k, v in after.items() if not k.endswith(".lock")} == {
        k: v for k, v in before.items() if not k.endswith(".lock")
    }


def test_view_learns_into_an_existing_table_only_with_learn_and_says_so(here, capsys) -> None:
    q = ["--qtable", "w.qtable", "--log", "w.csv"]
    code, out, _ = run(capsys, "view", *ROOM, *q, "--episodes", "1", "--clockless")
    assert code == 0
    assert out.splitlines()[0] == "view: learning into w.qtable, a new table (log w.csv)"
    assert out.splitlines()[-1].endswith("w.qtable: 1 episode added (1 in all)")
    code, out, _ = run(capsys, "view", *ROOM, *q, "--episodes", "2", "--learn", "--clockless")
    assert code == 0
    assert out.splitlines()[0] == "view: learning into w.qtable, which holds 1 episode (log w.csv)"
    assert out.splitlines()[-1].endswith("w.qtable: 2 episodes added (3 in all)")
    assert load_qtable("w.qtable").meta["episodes"] == 3
    expect_error(capsys, here, ["view", *ROOM, *q, "--steps", "2", "--learn", "--greedy"],
                 "--greedy, --learn: choose one")  # fmt: skip


# -- 2. resumes are said, --episodes is a total, another goal or world is refused -------------
def test_train_says_what_it_resumes_and_episodes_is_the_total(here, capsys) -> None:
    argv = ["train", *ROOM, "--qtable", "c.qtable"]
    code, out, _ = run(capsys, *argv, "--episodes", "2")
    assert code == 0 and out.splitlines()[0].startswith("new table c.qtable: 2 episodes; ")
    code, out, _ = run(capsys, *argv, "--episodes", "5")  # as after Ctrl-C at 2 of 5
    assert code == 0
    assert out.splitlines()[0].startswith(
        "resuming c.qtable: 2 episodes done, 3 more to reach --episodes 5; arena room, goal 201"
    )
    assert load_qtable("c.qtable").meta["episodes"] == 5
    before = files_of(here)
    code, out, _ = run(capsys, *argv, "--episodes", "5")  # the same command again
    assert code == 0 and "nothing to train" in out and files_of(here) == before


def test_another_goal_or_world_does_not_quietly_continue_a_table(here, capsys) -> None:
    assert run(capsys, "train", *ROOM, "--episodes", "2", "--quiet")[0] == 0
    expect_error(capsys, here, ["train", *ROOM, "--goal", "random", "--episodes", "20"],
                 "runs/room.qtable: goal: trained for goal 201, this run asks for a random goal",
                 "run with no --goal to continue it", "--init-qtable runs/room.qtable")  # fmt: skip
    expect_error(capsys, here, ["train", *ROOM, "--world", "koolio-real", "--episodes", "20"],
                 "runs/room.qtable: world: trained for the ideal world, this run asks for "
                 "world koolio-real")  # fmt: skip
    expect_error(capsys, here, ["view", *ROOM, "--goal", "random", "--steps", "3", "--learn"],
                 "runs/room.qtable: goal:")  # fmt: skip
    # a new table started from it learns for the new goal, and resumes with it
    new = ["--qtable", "any.qtable", "--goal", "random"]
    argv = ["train", *ROOM, *new, "--init-qtable", "runs/room.qtable", "--quiet"]
    assert run(capsys, *argv, "--episodes", "3")[0] == 0
    assert run(capsys, "train", *ROOM, *new, "--episodes", "4", "--quiet")[0] == 0
    assert load_qtable("any.qtable").meta["goal"] == "random"


def test_the_header_records_goal_and_world_only_when_not_the_defaults(here, capsys) -> None:
    for flags, name in (
        ([], "d"),
        (["--goal", "201"], "g201"),  # the arena's active goal, named: the same bytes
        (["--goal", "random"], "r"),
        (["--world", "koolio-real"], "w"),
    ):
        argv = ["train", *ROOM, *flags, "--episodes", "1", "--quiet", "--qtable", f"{name}.qtable"]
        assert run(capsys, *argv)[0] == 0
    header = {n: header_of((here / f"{n}.qtable").read_bytes()) for n in ("d", "g201", "r", "w")}
    assert "goal" not in header["d"] and "world" not in header["d"]
    assert learned(here / "d.qtable") == learned(here / "g201.qtable")  # the same run
    assert header["r"]["goal"] == "random" and "world" not in header["r"]
    assert header["w"]["world"] == "koolio-real" and "goal" not in header["w"]


def test_a_configuration_with_realism_records_the_world_it_ran_in(here, capsys) -> None:
    """``--config koolio-real`` (the profile says it is a valid way to use it) runs the
    realistic world: its table records it as ``--world koolio-real``'s does, ``eval`` there
    does not warn of a transfer, and neither table resumes quietly in the other world."""
    real = (PROFILE_DIR / "koolio-real.yaml").read_text() + "episode: {max_steps: 30}\n"
    (here / "real.yaml").write_text(real)  # koolio-real's realism, tiny.yaml's episodes
    quiet = ["--arena", "room", "--episodes", "2", "--log", ""]
    code, out, _ = run(capsys, "train", *quiet, "--config", "real.yaml", "--qtable", "c.qtable")
    assert code == 0 and out.splitlines()[0].startswith(
        "new table c.qtable: 2 episodes; arena room, goal 201, world koolio-real, seed 0"
    )
    argv = ["train", *ROOM, "--world", "koolio-real", "--qtable", "w.qtable", "--log", ""]
    assert run(capsys, *argv, "--episodes", "2", "--quiet")[0] == 0
    assert header_of((here / "c.qtable").read_bytes())["world"] == "koolio-real"
    assert learned(here / "c.qtable") == learned(here / "w.qtable")
    code, out, err = run(capsys, "eval", *ROOM, "--world", "koolio-real", "--qtable", "c.qtable",
                         "--episodes", "1")  # fmt: skip
    assert code == 0 and err == ""
    assert "(2 episodes, trained for goal 201 in world koolio-real)" in out.splitlines()[0]
    expect_error(capsys, here, ["train", *ROOM, "--qtable", "c.qtable", "--episodes", "3"],
                 "c.qtable: world: trained for world koolio-real, this run asks for the ideal "
                 "world: run with --world koolio-real (or --config koolio-real)")  # fmt: skip
    assert run(capsys, "train", *ROOM, "--qtable", "i.qtable", *quiet[2:], "--quiet")[0] == 0
    expect_error(capsys, here, ["train", *quiet, "--config", "real.yaml", "--qtable", "i.qtable"],
                 "i.qtable: world: trained for the ideal world, this run asks for world "
                 "koolio-real: run with no --world and no realism in --config")  # fmt: skip
    # realism that is no shipped world's: named by its content
    (here / "drifty.yaml").write_text(real.replace("drift_deg: 0.43", "drift_deg: 1.0"))
    argv = ["train", *quiet, "--config", "drifty.yaml", "--qtable", "d.qtable", "--quiet"]
    assert run(capsys, *argv)[0] == 0
    drifty = header_of((here / "d.qtable").read_bytes())["world"]
    assert re.fullmatch(r"realism-[0-9a-f]{8}", drifty)
    expect_error(capsys, here, ["train", *quiet, "--config", "real.yaml", "--qtable", "d.qtable"],
                 f"d.qtable: world: trained for world {drifty}, this run asks for world "
                 "koolio-real: run with a --config (and --world) with the same")  # fmt: skip


# -- 3. eval shows every outcome, where it scores, and what it scores -------------------------
def test_eval_prints_every_outcome_the_world_and_the_goal(here, capsys) -> None:
    assert (
        run(capsys, "train", *ROOM, "--episodes", "2", "--quiet", "--world", "koolio-real")[0] == 0
    )
    code, out, err = run(capsys, "eval", *ROOM, "--episodes", "2")
    assert code == 0
    head, scored, columns, row = out.splitlines()[:4]
    assert head == (
        "greedy evaluation of runs/room.qtable (2 episodes, trained for goal 201 in world "
        "koolio-real)"
    )
    assert scored.startswith("  scored in arena room, goal 201, the ideal world: 2 episodes")
    assert re.split(r"\s{2,}", columns.strip()) == [
        "goal greedy goal rate",
        "end of world",
        "wrong door",
        "step cap",
        "mean steps",
        "mean bumps",
        "mean return",
    ]
    assert len(row.split()) == 8
    assert err.splitlines() == [
        "warning: runs/room.qtable: trained in world koolio-real, scored here in the ideal world"
    ]


def test_eval_in_another_arena_does_not_name_this_arenas_goal(here, capsys) -> None:
    """A table of the room (goal 201, not recorded: the room's active goal) scored in the
    hallway was said to be trained for goal 311, the hallway's; resuming it there for
    another goal named 311 too."""
    assert run(capsys, "train", *ROOM, "--episodes", "1", "--quiet", "--log", "")[0] == 0
    hallway = ["--arena", "hallway", "--config", "tiny.yaml", "--qtable", "runs/room.qtable"]
    code, out, err = run(capsys, "eval", *hallway, "--episodes", "1")
    assert code == 0 and "learned in arena 'room'" in err
    assert out.splitlines()[0] == (
        "greedy evaluation of runs/room.qtable (1 episode, trained in arena room for its "
        "active goal, in the ideal world)"
    )
    expect_error(capsys, here, ["train", *hallway, "--goal", "random", "--episodes", "3"],
                 "runs/room.qtable: goal: trained for the arena's active goal, this run asks "
                 "for a random goal per episode")  # fmt: skip
    code, out, _ = run(capsys, "eval", *ROOM, "--episodes", "1")  # at home: the number
    assert "(1 episode, trained for goal 201 in the ideal world)" in out.splitlines()[0]


def test_eval_of_a_policy_file_reads_its_goal_and_world(here, capsys) -> None:
    """A policy records the table's arena, goal and world (export keeps them): eval names
    them and says when it scores another goal, as for the table."""
    argv = ["--qtable", "g.qtable", "--log", ""]
    assert run(capsys, "train", *ROOM, *argv, "--goal", "random", "--episodes", "1")[0] == 0
    assert run(capsys, "export", "--qtable", "g.qtable", "--out", "g.json")[0] == 0
    code, out, err = run(capsys, "eval", *ROOM, "--qtable", "g.json", "--episodes", "1")
    assert code == 0 and err.strip().splitlines() == [
        "warning: g.json: trained for a random goal per episode, scored here for goal 201"
    ]
    assert out.splitlines()[0] == (
        "greedy evaluation of g.json (1 episode, trained for a random goal per episode in "
        "the ideal world)"
    )


def test_eval_warns_on_an_empty_table(here, capsys) -> None:
    env = KoolioEnv("room", config="tiny.yaml")
    with QTableStore("empty.qtable") as store:
        open_table(store, env.layout, sensor_signature(env.config), -30.0, arena_record(env.arena))
    code, _, err = run(capsys, "eval", *ROOM, "--qtable", "empty.qtable", "--episodes", "1")
    assert code == 0
    assert "warning: empty.qtable: holds 0 episodes (an empty table" in err


def test_eval_falls_back_to_the_backup_as_train_does(here, capsys) -> None:
    argv = ["--qtable", "q.qtable", "--log", "q.csv", "--fsync", "episode"]
    assert run(capsys, "train", *ROOM, *argv, "--episodes", "2", "--quiet")[0] == 0
    data = (here / "q.qtable").read_bytes()
    (here / "q.qtable").write_bytes(data[: len(data) // 2])  # torn
    code, out, err = run(capsys, "eval", *ROOM, "--qtable", "q.qtable", "--episodes", "1")
    assert code == 0 and "(1 episode," in out  # the backup: one episode behind
    lines = [ln for ln in err.splitlines() if not ln.startswith("compiling")]
    assert len(lines) == 1 and re.match(
        r"warning: q.qtable: corrupt .*; using the backup q.qtable.bak$", lines[0]
    )


# -- 4. errors first, nothing left behind; the compile announced; rates labelled -------------
def test_an_early_error_is_the_only_line_and_leaves_no_file(here, capsys) -> None:
    expect_error(capsys, here, ["train", "--init-qtable", "nothere.json", "--qtable", "y.qtable"],
                 "nothere.json: cannot read")  # fmt: skip
    assert not list(here.glob("y.*"))  # no y.qtable.lock either
    (here / "old.csv").write_text(
        "episode,reward,steps,bumps,outcome,rescued,epsilon,goal\n0,-5,30,0,truncated,0,0.15,201\n"
    )
    expect_error(capsys, here, ["train", *ROOM, "--qtable", "n.qtable", "--log", "old.csv"],
                 "old.csv: holds 1 rows of another run")  # fmt: skip
    expect_error(capsys, here, ["view", *ROOM, "--qtable", "n.qtable", "--log", "old.csv",
                                "--steps", "2"], "old.csv: holds 1 rows")  # fmt: skip
    assert not list(here.glob("n.*")) and not (here / "old.csv.lock").exists()


def test_configuration_only_with_verbose_and_rates_named(here, capsys) -> None:
    argv = ["train", *ROOM, "--episodes", "2"]
    code, out, _ = run(capsys, *argv)
    assert code == 0 and "configuration:" not in out and len(out.splitlines()) <= 6
    assert "training goal rate (exploring; last 2)" in out
    assert "score the greedy policy (no exploration): koolio-pm eval --arena room" in out
    code, out, _ = run(capsys, *argv[:-1], "4", "--verbose")
    assert code == 0 and "configuration:" in out and "rotate_action_arc_deg" in out


def test_the_compile_is_announced_before_it_happens_when_the_cache_is_cold(
    here, capsys, monkeypatch
) -> None:
    monkeypatch.setattr(cli, "_cached", lambda dispatcher: False)  # a cold cache
    code, _, err = run(capsys, "train", *ROOM, "--episodes", "1")
    assert code == 0
    assert err.splitlines() == [
        "compiling the simulator's kernels (first run only, about a minute on 2 cores); "
        "later runs load them from the cache"
    ]
    monkeypatch.setattr(cli, "_cached", lambda dispatcher: True)  # warm
    assert run(capsys, "train", *ROOM, "--episodes", "2")[2] == ""


def test_a_cold_cache_is_told_from_numba_s_own_index() -> None:
    from koolio_pymunk.sensing import ray_kernel

    env = KoolioEnv("room")
    env.reset(seed=0)  # compiled (or loaded) now: the index is there
    assert cli._cached(ray_kernel.sense_one) and not cli.kernels_to_compile(env)


def test_the_step_engine_counts_where_it_runs(monkeypatch) -> None:
    """``train`` and ``eval`` step on the engine: its cache is asked, unless the run steps
    in Python (the pymunk reference compiles nothing)."""
    from koolio_pymunk.learning import engine

    env = KoolioEnv("room")
    env.reset(seed=0)
    cold = {engine.run}
    monkeypatch.setattr(cli, "_cached", lambda dispatcher: dispatcher not in cold)
    assert cli.kernels_to_compile(env, training=True) and cli.kernels_to_compile(env)
    reference = KoolioEnv("room", config=load_config(overrides={"sensors": {"backend": "pymunk"}}))
    assert not cli.kernels_to_compile(reference, training=True)


# -- 5. flags: whole words only, and a did-you-mean ------------------------------------------
@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["train", "--epsiodes", "400"], ["unrecognized arguments: --epsiodes 400",
                                          "did you mean --episodes?", "koolio-pm train --help"]),
        (["train", "--episode", "0"], ["unrecognized arguments: --episode 0",
                                       "did you mean --episodes?"]),
        (["eval", "--qtabel=x.qtable"], ["did you mean --qtable?"]),
        (["train", "--epi", "8"], ["did you mean --episodes?"]),  # cut short: the one it starts
        (["view", "--screnshot", "a.png"], ["did you mean --screenshot?"]),
        (["trian"], ["invalid choice: 'trian'", "did you mean 'train'?"]),
    ],
)  # fmt: skip
def test_no_abbreviations_and_a_did_you_mean(here, capsys, argv, words) -> None:
    expect_error(capsys, here, argv, *words)


def test_every_parser_refuses_abbreviations() -> None:
    parser = cli.build_parser()
    subs = [a for a in parser._actions if isinstance(a, cli.argparse._SubParsersAction)]
    assert not parser.allow_abbrev
    assert subs and all(not p.allow_abbrev for p in subs[0].choices.values())


# -- 6. smaller ones -------------------------------------------------------------------------
def test_eval_before_train_says_to_train_first(here, capsys) -> None:
    expect_error(capsys, here, ["eval"], "runs/hallway.qtable: no such Q-table yet",
                 "run koolio-pm train first")  # fmt: skip


def test_a_paper_table_without_config_paper_names_the_profile(here, capsys) -> None:
    argv = ["--arena", "room", "--qtable", "p.qtable", "--episodes", "1"]
    assert run(capsys, "train", *argv, "--config", "paper", "--quiet", "--log", "")[0] == 0
    expect_error(capsys, here, ["eval", *argv], "sensors.camera_sensors_deg",
                 "shipped profile 'paper': add --config paper")  # fmt: skip
    assert run(capsys, "train", "--arena", "room", "--qtable", "d.qtable", "--log", "",
               "--episodes", "1", "--quiet")[0] == 0  # fmt: skip
    expect_error(capsys, here, ["eval", "--arena", "room", "--qtable", "d.qtable", "--config",
                                "paper"], "default configuration: leave out --config")  # fmt: skip


def test_a_one_episode_learning_curve_has_whole_episodes_and_axes_from_zero(here) -> None:
    from koolio_pymunk.apps.plotting import make_figure, read_log

    (here / "one.csv").write_text(
        "episode,reward,steps,bumps,outcome,rescued,epsilon,goal\n0,46,46,0,goal,0,0.15,201\n"
    )
    fig = make_figure([read_log(here / "one.csv")])
    ax_ret, _, ax_steps = fig.axes[:3]
    lo, hi = ax_steps.get_xlim()
    assert (lo, hi) == (0.0, 2.0)
    assert ax_steps.get_ylim()[0] == 0.0 and ax_ret.get_ylim()[0] == 0.0
    assert [line.get_marker() for line in ax_steps.get_lines()][-1] == "o"  # a visible dot


# -- 7. the README's newcomer path -----------------------------------------------------------
def test_readme_scratch_outputs_go_to_an_ignored_folder() -> None:
    """Every file a README example writes for a look (a PNG, frames, a policy) goes under
    ``scratch/``, which git ignores: a newcomer's checkout stays clean."""
    from tests.test_docs import documented_commands

    ignored = (REPO / ".gitignore").read_text().split()
    assert "scratch/" in ignored
    for words in documented_commands("README.md"):
        if "edit" in words:  # the editor's scripted example is the editor's own (docs/editor.md)
            continue
        for flag in ("--out", "--screenshot"):
            if flag in words:
                target = words[words.index(flag) + 1]
                assert target.startswith(("scratch/", "docs/images/", "bench")), words
        if "--screenshot-every" in words:
            assert words[words.index("--screenshot-every") + 2].startswith("scratch/"), words


def test_readme_says_to_activate_the_venv_once() -> None:
    text = (REPO / "README.md").read_text()
    assert "source .venv/bin/activate" in text
    commands = [w for w in _readme_commands() if w and w[0].endswith("koolio-pm")]
    setup = [w for w in commands if w[0].startswith(".venv/")]
    # only the one-line set-ups spell the venv's path; everything else assumes it active
    assert setup == [[".venv/bin/koolio-pm", "train"], [".venv/bin/koolio-pm", "eval"]]


def _readme_commands() -> list[list[str]]:
    from tests.test_docs import documented_commands

    return documented_commands("README.md")


# -- 7. the second audit ---------------------------------------------------------------------
def test_world_ideal_is_the_default_world(here, capsys) -> None:
    """``--world ideal`` names the default (nothing laid over): the same table, bit for
    bit, and it is listed among the worlds of a bad name's error."""
    assert run(capsys, "train", *ROOM, "--episodes", "2", "--qtable", "a.qtable")[0] == 0
    argv = ["train", *ROOM, "--episodes", "2", "--qtable", "b.qtable", "--world", "ideal"]
    assert run(capsys, *argv)[0] == 0
    assert learned(here / "a.qtable") == learned(here / "b.qtable")
    code, out, err = run(capsys, "eval", *ROOM, "--qtable", "a.qtable", "--episodes", "1",
                         "--world", "ideal")  # fmt: skip
    assert code == 0 and "the ideal world" in out and "warning" not in err
    expect_error(capsys, here, ["eval", "--world", "ideel"], "did you mean 'ideal'?",
                 "(worlds: ideal, koolio-real")  # fmt: skip


def test_a_configuration_file_without_yaml_suffix_is_read(here, capsys) -> None:
    (here / "tiny").write_text("episode: {max_steps: 30}\n")
    argv = ["train", "--arena", "room", "--config", "tiny", "--episodes", "1", "--qtable"]
    argv += ["t.qtable"]
    assert run(capsys, *argv)[0] == 0
    assert (
        run(
            capsys,
            "eval",
            "--arena",
            "room",
            "--config",
            "tiny.yaml",
            "--qtable",
            "t.qtable",
            "--episodes",
            "1",
        )[0]
        == 0
    )  # fmt: skip  (the same configuration)


def test_eval_of_random_goals_is_labelled_random(here, capsys) -> None:
    assert run(capsys, "train", *ROOM, "--episodes", "2", "--qtable", "t.qtable")[0] == 0
    argv = ["eval", *ROOM, "--qtable", "t.qtable", "--episodes", "3", "--goal", "random"]
    code, out, _ = run(capsys, *argv)
    rows = [ln.split() for ln in out.splitlines() if ln.strip().endswith(tuple("0123456789"))]
    assert code == 0 and rows and rows[-1][0] == "random", out
    code, out, _ = run(capsys, *argv, "--json")
    assert code == 0 and '"goal": "random"' in out
    code, out, _ = run(capsys, *argv, "--epsilon", "0.5")
    assert code == 0 and "greedy goal rate" not in out and "goal rate" in out


def test_view_says_when_it_watches_a_table_of_another_world(here, capsys) -> None:
    assert run(capsys, "train", *ROOM, "--episodes", "2", "--qtable", "t.qtable")[0] == 0
    argv = ["view", *ROOM, "--greedy", "--qtable", "t.qtable", "--steps", "2"]
    code, _, err = run(capsys, *argv, "--world", "koolio-real")
    assert code == 0
    assert "warning: t.qtable: trained in the ideal world, watched here in world koolio-real" in err
    assert "warning" not in run(capsys, *argv)[2]


def test_sweep_names_its_world_flag(here, capsys) -> None:
    (here / "s.yaml").write_text("name: s\nepisodes: 2\nseeds: [0]\n")
    expect_error(capsys, here, ["sweep", "s.yaml", "--world", "nope", "--dry-run"],
                 "koolio-pm: error: --world: nope: no such world profile")  # fmt: skip
