"""A researcher's first day (issue 33): the newcomer's surprises, each as it was met.

Nothing hangs without a display, no flag takes an empty file name, SDL's chatter about
``XDG_RUNTIME_DIR`` is not printed, a scripted editor run says what it wrote.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

from inputs import run

from koolio_pymunk.apps import cli
from koolio_pymunk.store.episode_log import log_rows

REPO = Path(__file__).resolve().parents[2]
XDG_LINE = "XDG_RUNTIME_DIR is invalid or not set"


def no_display_env() -> dict[str, str]:
    """The environment of a machine without a display: no SDL driver asked for, no X11 or
    Wayland display, no XDG_RUNTIME_DIR (a container, a CI runner)."""
    env = dict(os.environ)
    for name in ("SDL_VIDEODRIVER", "DISPLAY", "WAYLAND_DISPLAY", "XDG_RUNTIME_DIR"):
        env.pop(name, None)
    env["PYTHONPATH"] = str(REPO)
    return env


def koolio_pm(folder: Path, *argv: str, env: dict[str, str]) -> subprocess.CompletedProcess:
    """``python -m koolio_pymunk argv`` in ``folder``; a hang fails the test (timeout)."""
    return subprocess.run(
        [sys.executable, "-m", "koolio_pymunk", *argv],
        cwd=folder,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )


# -- edit refuses to wait for a person nobody can see ----------------------------------------
@pytest.mark.parametrize(
    ("argv", "how"),
    [
        (["edit", "room"], "give --script FILE (and --screenshot PNG to see the result)"),
        (
            ["edit", "--new", "lab.yaml"],
            "give --script FILE (and --screenshot PNG to see the result)",
        ),
        (["edit", "room", "--script", "s.txt", "--stay"], "leave out --stay"),
        (["edit", "room", "--screenshot", "x.png", "--stay"], "leave out --stay"),
    ],
)
def test_edit_without_a_display_refuses_in_one_line(here, capsys, argv, how) -> None:
    assert os.environ["SDL_VIDEODRIVER"] == "dummy"  # the premise: nothing is shown
    (here / "s.txt").write_text("view fit\n")
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    assert err == (
        "koolio-pm: error: edit: headless (SDL_VIDEODRIVER=dummy): the editor needs a "
        f"display; {how}\n"
    )
    assert sorted(p.name for p in here.iterdir()) == ["s.txt", "tiny.yaml"]


def test_edit_on_a_machine_without_a_display_refuses_and_says_nothing_of_sdl(here) -> None:
    """No SDL_VIDEODRIVER, no DISPLAY, no XDG_RUNTIME_DIR: SDL falls back to its offscreen
    driver, and the command refuses in one line (it used to wait until killed) without
    libwayland's line about XDG_RUNTIME_DIR; a screenshot run works and says so."""
    env = no_display_env()
    done = koolio_pm(here, "edit", "room", env=env)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr == (
        "koolio-pm: error: edit: headless (no display: DISPLAY and WAYLAND_DISPLAY are not "
        "set): the editor needs a display; give --script FILE (and --screenshot PNG to see "
        "the result)\n"
    )
    done = koolio_pm(here, "edit", "room", "--screenshot", "room.png", env=env)
    assert done.returncode == 0 and done.stderr == ""
    assert done.stdout.endswith("valid; screenshot room.png\n")
    assert (here / "room.png").stat().st_size > 1000


def test_view_without_a_display_prints_only_its_own_lines(here) -> None:
    """A headless ``view`` on a machine without XDG_RUNTIME_DIR: its two lines on stdout
    and nothing on stderr (no SDL message; the kernels compiled by earlier tests)."""
    args = ["view", "--arena", "room", "--config", "tiny.yaml", "--qtable", "v.qtable"]
    done = koolio_pm(here, *args, "--steps", "3", "--screenshot", "v.png", env=no_display_env())
    assert done.returncode == 0, done.stderr
    compiling = "compiling the simulator's kernels"  # a cold cache's own line, if any
    assert [ln for ln in done.stderr.splitlines() if not ln.startswith(compiling)] == []
    assert done.stdout.count("\n") == 2 and done.stdout.startswith("view: learning into")


def test_only_libwayland_s_line_is_dropped_from_the_display_start(capfd) -> None:
    """What C code writes to the standard error while the display starts is kept, but
    for libwayland's line (both its wordings)."""
    from koolio_pymunk.task.display import quiet_stderr

    with quiet_stderr():
        os.write(2, b"error: XDG_RUNTIME_DIR is invalid or not set in the environment.\n")
        os.write(2, b"ALSA lib pcm.c: a real problem\n")
        os.write(2, b"error: XDG_RUNTIME_DIR not set in the environment.\n")
    assert capfd.readouterr().err == "ALSA lib pcm.c: a real problem\n"


# -- no flag takes an empty file name ---------------------------------------------------------
#: Flags (by argparse dest) that name a file or a folder, positional ones included.
FILE_DESTS = {
    "arena", "config", "world", "dr_world", "qtable", "dr_qtable", "init_qtable", "log",
    "logs", "out", "evals", "script", "screenshot", "screenshot_every", "doors", "file", "spec",
}  # fmt: skip
#: What each command needs besides the flag under test to get that far.
NEEDS = {"export": ["--out", "p.json"], "view": ["--steps", "1"]}
#: ``--log ''`` is documented: no log.
NO_LOG = {("train", "log"), ("view", "log")}


def empty_name_cases() -> list[list[str]]:
    """``koolio-pm CMD FLAG ''`` for every file-name flag of every command, from the
    parsers themselves (a new flag is checked without a new line here)."""
    import argparse

    sub = next(a for a in cli.build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    cases = []
    for command, parser in sub.choices.items():
        for action in parser._actions:
            if action.dest not in FILE_DESTS or (command, action.dest) in NO_LOG:
                continue
            if not action.option_strings:
                cases.append([command, ""])
                continue
            flag = action.option_strings[0]
            needs = [w for w in NEEDS.get(command, []) if flag != "--out"]
            value = ["1", ""] if action.dest == "screenshot_every" else [""]
            cases.append([command, *needs, flag, *value])
    return cases


def test_the_empty_name_cases_cover_every_command_that_takes_files() -> None:
    commands = {case[0] for case in empty_name_cases()}
    assert commands == {
        "train", "eval", "check-arena", "info", "view", "plot", "export", "sweep", "transfer",
        "edit",
    }  # fmt: skip
    assert ["edit", "--script", ""] in empty_name_cases()
    assert ["transfer", "--out", ""] in empty_name_cases()


@pytest.mark.parametrize("argv", empty_name_cases(), ids=" ".join)
def test_no_flag_takes_an_empty_file_name(here, capsys, argv) -> None:
    """One line saying the name is empty, exit 2, nothing run or written (``transfer
    --out ''`` trained into the current folder, ``edit --script ''`` opened the editor,
    ``view --screenshot ''`` said ``: must end in .png``)."""
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "empty file name" in err, err
    assert sorted(p.name for p in here.iterdir()) == ["tiny.yaml"]


# -- edit says what it wrote -----------------------------------------------------------------
def test_a_scripted_edit_names_its_screenshot_and_the_arena_the_script_made(here, capsys):
    from koolio_pymunk.apps.editor.app import EditorApp
    from koolio_pymunk.apps.editor.model import EditorModel
    from koolio_pymunk.apps.editor.script import run_script

    script = REPO / "examples" / "editor-script.txt"
    code, out, err = run(capsys, "edit", "--script", str(script), "--screenshot", "e.png")
    assert code == 0 and err == ""
    assert out == (
        f"edit: script {script} run; arena 'office' (not saved yet): valid; screenshot e.png\n"
    )
    assert (here / "e.png").stat().st_size > 1000
    app = EditorApp(EditorModel.blank(), (1280, 720))
    run_script(app, script)
    assert app.model.describe() == "arena 'office' (not saved yet)"  # the status bar's words
    code, out, err = run(capsys, "edit", "room", "--screenshot", "r.png")
    assert code == 0 and out.startswith("edit: arena 'room' (")
    assert out.endswith("room.yaml): valid; screenshot r.png\n")


# -- one numbering of episodes --------------------------------------------------------------
def test_the_window_numbers_episodes_from_1_as_train_the_curve_and_the_log_do(here, capsys):
    """After 6 finished episodes the Stats say #6 while the 6th's end is shown and #7 once
    the next one runs (it said #6 for the 7th); ``train``'s progress counts the same
    6; the log's episode column is the number less one (its format is unchanged)."""
    import pygame

    from koolio_pymunk.apps.viewer import hud
    from koolio_pymunk.apps.viewer.session import Session
    from koolio_pymunk.task.env import KoolioEnv

    env = KoolioEnv(arena="room", config="tiny.yaml")
    session = Session(env, "w.qtable", log="w.csv")
    heading = hud.stats_rows(session, 0.0)[0][1]
    assert heading.startswith("This episode (#1,")
    while session.stats.episodes < 6:
        session.step()
    assert session.episode_over  # the 6th's end is on the screen
    assert hud.stats_rows(session, 0.0)[0][1].startswith("This episode (#6,")
    session.step()
    assert hud.stats_rows(session, 0.0)[0][1].startswith("This episode (#7,")
    session.exit(save=False)
    rows = log_rows(here / "w.csv")
    assert [r["episode"] for r in rows] == ["0", "1", "2", "3", "4", "5"]
    code, out, _ = run(capsys, "train", "--arena", "room", "--config", "tiny.yaml",
                       "--qtable", "t.qtable", "--episodes", "6")  # fmt: skip
    assert code == 0 and "episode      6/6 " in out
    surface = pygame.Surface((420, 320))
    drawn = hud.draw_curve(surface, pygame.Rect(0, 0, 420, 320), session.stats.returns)
    assert drawn["x_ticks"][-1] == 6.0  # the 6th return is drawn at "6"


@pytest.mark.parametrize("n", range(2, 40))
def test_the_live_curve_labels_whole_episodes_once_each(n) -> None:
    """Early on the x axis read ``1 1 1 2 2 2`` (ticks 1.0, 1.2, ... rounded)."""
    import pygame

    from koolio_pymunk.apps.viewer import hud

    surface = pygame.Surface((420, 320))
    drawn = hud.draw_curve(surface, pygame.Rect(0, 0, 420, 320), [0.0] * n)
    ticks = drawn["x_ticks"]
    assert ticks and all(t == int(t) and 1 <= t <= n for t in ticks)
    assert len({f"{t:,.0f}" for t in ticks}) == len(ticks)


# -- configuration dumps: resolved values, and only when asked ---------------------------------
def test_train_verbose_shows_every_setting_resolved(here, capsys) -> None:
    """``goal: None``, ``config: None``, ``world: None`` were listed before the values
    they stand for; now every line says what the run uses."""
    code, out, _ = run(capsys, "train", "--arena", "room", "--episodes", "1", "--verbose")
    assert code == 0
    settings = out.split("koolio-pm train\n", 1)[1].split("configuration:\n", 1)
    lines = settings[0].splitlines()
    assert "  goal: 201 at (102.0, 191.0) (the arena's active goal)" in lines
    assert "  config: the built-in defaults (no --config)" in lines
    assert "  world: ideal (nothing laid over the configuration)" in lines
    assert not [ln for ln in out.splitlines() if "None" in ln or "null" in ln]
    assert "robot_radius: 10.0" in settings[1]  # the profile's radius, not null
    more = ["--config", "tiny.yaml", "--world", "koolio-real", "--qtable", "r.qtable"]
    code, out, _ = run(capsys, "train", "--arena", "room", "--episodes", "1", "--verbose", *more)
    assert code == 0 and "  config: file tiny.yaml\n" in out
    assert "  world: world profile koolio-real\n" in out
    assert not [ln for ln in out.splitlines() if "None" in ln or "null" in ln]


TRANSFER = ["transfer", "--arena", "room", "--config", "tiny.yaml", "--episodes", "1",
            "--robot-episodes", "1", "--eval-episodes", "1", "--eval-every", "1",
            "--no-plot"]  # fmt: skip


def test_transfer_dumps_its_settings_only_with_verbose(here, capsys) -> None:
    code, out, _ = run(capsys, *TRANSFER, "--out", "a")
    assert code == 0
    first, second = out.splitlines()[:2]
    assert first.startswith("transfer: seed 0: tables from the ideal world and koolio-real-dr")
    assert second.startswith("[seed 0, ideal table]")  # no dump of 18 lines
    code, out, _ = run(capsys, *TRANSFER, "--out", "b", "--verbose")
    assert code == 0
    dump = [ln for ln in out.splitlines() if ln.startswith("  ")][:14]
    assert dump[0] == f"  arena: room ({REPO / 'arenas' / 'room.yaml'})"
    assert "  config: file tiny.yaml" in dump
    assert "  robot alpha: 0.1 (config's)" in dump
    assert not [ln for ln in dump if "None" in ln or "(default)" in ln]
    code, out, _ = run(capsys, *TRANSFER, "--out", "c", "--quiet", "--verbose")
    assert code == 0 and not out.startswith("transfer:")  # --quiet: the results only


# -- warnings about the user's data: always, on stderr --------------------------------------------
TRAIN_T = ["train", "--arena", "room", "--config", "tiny.yaml", "--qtable", "t.qtable"]


@pytest.mark.parametrize("damage", ["torn", "missing"])
@pytest.mark.parametrize("quiet", [[], ["--quiet"]])
def test_nothing_to_train_from_a_backup_warns_and_says_the_backup_holds_them(
    here, capsys, damage, quiet
) -> None:
    """The table's file torn or missing, its backup holding the episodes asked for: it
    said ``t.qtable already holds 3 episodes`` (only the backup did), never warned, and
    said nothing at all with --quiet."""
    assert run(capsys, *TRAIN_T, "--episodes", "3", "--quiet")[0] == 0
    assert run(capsys, *TRAIN_T, "--episodes", "4", "--quiet")[0] == 0  # backup: 3 episodes
    table = here / "t.qtable"
    if damage == "torn":
        table.write_bytes(table.read_bytes()[:100])
    else:
        table.unlink()
    before = {p.name: p.read_bytes() for p in here.iterdir() if p.is_file()}
    code, out, err = run(capsys, *TRAIN_T, "--episodes", "3", *quiet)
    assert code == 0
    problem = "corrupt or truncated" if damage == "torn" else "missing"
    assert err.count("\n") == 1 and err.startswith(f"warning: t.qtable: {problem}")
    assert err.endswith("; using the backup t.qtable.bak\n")
    if quiet:
        assert out == ""
    else:
        assert out.startswith("t.qtable is damaged or missing (see the warning); its backup "
                              "t.qtable.bak already holds 3 episodes")  # fmt: skip
    assert {p.name: p.read_bytes() for p in here.iterdir() if p.is_file()} == before


def test_a_run_that_trains_from_the_backup_warns_once_and_says_so_first(here, capsys) -> None:
    assert run(capsys, *TRAIN_T, "--episodes", "2", "--quiet")[0] == 0
    assert run(capsys, *TRAIN_T, "--episodes", "3", "--quiet")[0] == 0
    (here / "t.qtable").write_bytes(b"torn")
    code, out, err = run(capsys, *TRAIN_T, "--episodes", "4", "--log", "")
    assert code == 0 and out.startswith("resuming t.qtable from its backup t.qtable.bak: 2 ")
    assert err.count("using the backup t.qtable.bak") == 1  # the locked load does not repeat it
    code, out, err = run(capsys, *TRAIN_T, "--episodes", "5", "--log", "", "--quiet")
    assert code == 0 and out == "" and err == ""  # saved again: nothing to warn of


def test_a_table_whose_dyna_model_is_bad_is_handled_like_a_torn_one(here, capsys) -> None:
    """docs/robustness.md: ``eval`` (like ``train`` and ``view``) falls back to the backup
    with a warning; ``export`` and ``--init-qtable`` read the file given and refuse it."""
    from koolio_pymunk.store.qtable import load_qtable

    (here / "dyna.yaml").write_text(
        "learner: {algorithm: dyna, planning_steps: 3}\nepisode: {max_steps: 30}\n"
    )
    dyna = ["--arena", "room", "--config", "dyna.yaml"]
    train = ["train", *dyna, "--qtable", "d.qtable", "--episodes", "2", "--fsync", "episode"]
    assert run(capsys, *train)[0] == 0  # the backup: the table of episode 1
    table = load_qtable(here / "d.qtable")
    assert "dyna_model" in table.sections
    table.sections["dyna_model"] = b"not a model"
    (here / "d.qtable").write_bytes(table.to_bytes())  # a whole file, its model bad
    code, out, err = run(capsys, "eval", *dyna, "--qtable", "d.qtable", "--episodes", "1")
    assert code == 0 and out.startswith("greedy evaluation of d.qtable (1 episode,")
    assert err == (
        "warning: d.qtable: dyna_model: malformed Dyna-Q model; using the backup d.qtable.bak\n"
    )
    for argv in (
        ["export", "--qtable", "d.qtable", "--config", "dyna.yaml", "--out", "p.json"],
        ["train", *dyna, "--init-qtable", "d.qtable", "--qtable", "n.qtable", "--log", "n.csv"],
    ):
        code, out, err = run(capsys, *argv)
        assert code == 2 and err == (
            "koolio-pm: error: d.qtable: dyna_model: malformed Dyna-Q model\n"
        )
    text = (REPO / "docs" / "robustness.md").read_text()
    assert "`train`, `eval` and `view` use its backup" in " ".join(text.split())
