"""``koolio-pm plot``: reading training logs and drawing the learning curve."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from koolio_pymunk.apps.cli import main
from koolio_pymunk.apps.plotting import moving_average, outcome_rate, read_log
from koolio_pymunk.store.errors import KoolioError

HEADER = "episode,reward,steps,bumps,outcome,rescued,epsilon,goal\n"


def write_log(path, n: int = 60) -> None:
    rows = [HEADER]
    for e in range(n):
        outcome = "goal" if e % 3 == 0 else "end_of_world"
        rows.append(f"{e},{-100 + 2 * e},{200 - e},{e % 5},{outcome},0,0.1,311\n")
    rows.append(f"{n},-5,3,0,interrupted,0,0.1,311\n")
    path.write_text("".join(rows))


def test_read_log_skips_interrupted_rows(tmp_path) -> None:
    p = tmp_path / "train.csv"
    write_log(p, 10)
    log = read_log(p)
    assert len(log) == 10 and log.skipped == 1
    assert log.reward.tolist() == [-100 + 2 * e for e in range(10)]
    assert log.outcome[:3] == ["goal", "end_of_world", "end_of_world"]


def test_moving_average_and_outcome_rate() -> None:
    assert moving_average(np.array([1.0, 2.0, 3.0, 4.0, 5.0]), 3).tolist() == [
        1.0,
        1.5,
        2.0,
        3.0,
        4.0,
    ]
    rate = outcome_rate(["goal", "x", "goal", "goal"], "goal", 2)
    assert rate.tolist() == [1.0, 0.5, 0.5, 1.0]


def test_plot_writes_a_labelled_png(tmp_path, capsys) -> None:
    log = tmp_path / "train.csv"
    write_log(log)
    out = tmp_path / "curve.png"
    assert main(["plot", "--log", str(log), "--out", str(out), "--window", "10"]) == 0
    import matplotlib.image as mpimg

    img = mpimg.imread(out)
    assert img.shape[0] > 700 and img.shape[1] > 1000
    # Not a blank picture: the tab:blue moving-average line is drawn.
    blue = np.all(np.abs(img[:, :, :3] - np.array([31, 119, 180]) / 255) < 0.02, axis=2)
    assert blue.sum() > 500
    assert "60 episodes" in capsys.readouterr().out


def test_plot_overlays_several_logs(tmp_path) -> None:
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    write_log(a, 30)
    write_log(b, 40)
    out = tmp_path / "both.png"
    assert main(["plot", "--log", str(a), "--log", str(b), "--out", str(out)]) == 0
    assert out.stat().st_size > 10_000


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (None, "file not found"),
        ("a,b\n1,2\n", "missing columns"),
        (HEADER, "no finished episode"),
        (HEADER + "0,lots,5,0,goal,0,0.1,311\n", "line 2: reward: not a number"),
    ],
)
def test_bad_logs_are_one_line_errors(tmp_path, content, message) -> None:
    p = tmp_path / "log.csv"
    if content is not None:
        p.write_text(content)
    with pytest.raises(KoolioError, match=message):
        read_log(p)


def test_plot_cli_errors_exit_2(tmp_path, capsys) -> None:
    assert (
        main(["plot", "--log", str(tmp_path / "none.csv"), "--out", str(tmp_path / "c.png")]) == 2
    )
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "file not found" in err
    log = tmp_path / "t.csv"
    write_log(log, 5)
    assert main(["plot", "--log", str(log), "--out", str(tmp_path / "c.jpg")]) == 2
    assert main(["plot", "--log", str(log), "--out", str(tmp_path / "c.png"), "--window", "0"]) == 2


def test_several_logs_say_what_each_panel_shows(tmp_path) -> None:
    """Two runs: the middle panel says it is the share at the goal, the bottom panel draws
    bumps (dashed, right axis) as well as steps, one colour per run, named by folder."""
    import matplotlib.pyplot as plt

    from koolio_pymunk.apps.plotting import make_figure

    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    write_log(tmp_path / "a" / "train.csv", 30)
    write_log(tmp_path / "b" / "train.csv", 40)
    logs = [read_log(tmp_path / d / "train.csv") for d in ("a", "b")]
    fig = make_figure(logs, 10)
    _, ax_out, ax_steps, bumps = fig.axes
    assert "at the goal" in ax_out.get_ylabel() and ax_out.get_title(loc="right")
    assert [t.get_text() for t in ax_out.get_legend().get_texts()] == [
        "a/train.csv",
        "b/train.csv",
    ]
    assert "steps (solid) and bumps (dashed)" in ax_steps.get_title(loc="right")
    assert "bumps" in bumps.get_ylabel()
    steps_lines, bump_lines = ax_steps.get_lines(), bumps.get_lines()
    assert len(steps_lines) == len(bump_lines) == 2
    assert all(line.get_linestyle() == "--" for line in bump_lines)
    assert [line.get_color() for line in bump_lines] == [line.get_color() for line in steps_lines]
    expected = moving_average(logs[1].bumps, 10)
    assert np.allclose(bump_lines[1].get_ydata(), expected)
    plt.close(fig)


def test_single_log_draws_bumps_on_their_own_axis(tmp_path) -> None:
    import matplotlib.pyplot as plt

    from koolio_pymunk.apps.plotting import make_figure

    write_log(tmp_path / "t.csv", 30)
    log = read_log(tmp_path / "t.csv")
    fig = make_figure([log], 10)
    bumps = [ax for ax in fig.axes if "bumps" in ax.get_ylabel()]
    assert len(bumps) == 1 and len(bumps[0].get_lines()) == 1
    # The axis covers the whole average (not the default 0..1 it had before plotting).
    assert bumps[0].get_ylim()[1] >= moving_average(log.bumps, 10).max() > 1
    plt.close(fig)


def test_plot_takes_logs_positionally(tmp_path, capsys) -> None:
    a, b = tmp_path / "robot.csv", tmp_path / "sim.csv"
    write_log(a, 20)
    write_log(b, 25)
    out = tmp_path / "c.png"
    assert main(["plot", str(a), "--out", str(out)]) == 0
    assert "20 episodes from 1 log(s)" in capsys.readouterr().out
    assert main(["plot", str(a), "--log", str(b), "--out", str(out)]) == 0
    assert "45 episodes from 2 log(s)" in capsys.readouterr().out


EVALS = "episode,eval_episodes,seed,goal_rate,end_of_world_rate,wrong_door_rate,truncated_rate,"
EVALS += "mean_steps,mean_bumps,mean_return,best,seconds\n"


def write_evals(path, rates: list[float]) -> None:
    """A run's greedy checks every 10 episodes; ``best`` as train writes it."""
    rows, best = [EVALS], -1.0
    for i, g in enumerate(rates):
        flag = int(g > best)
        best = max(best, g)
        rows.append(f"{10 * (i + 1)},20,0,{g},{1 - g},0,0,50,1,{-100 + 100 * g},{flag},0.1\n")
    path.write_text("".join(rows))


def test_the_checks_beside_the_log_are_drawn(tmp_path, capsys) -> None:
    """``X.evals.csv`` beside ``X.csv``: diamonds on the goal and return panels, the kept
    best (the last best-so-far check: 0.8 at 30, not the equal 0.8 at 50) a gold star."""
    import matplotlib.pyplot as plt

    from koolio_pymunk.apps.plotting import evals_beside, make_figure

    log = tmp_path / "t.csv"
    write_log(log, 60)
    write_evals(evals_beside(log), [0.2, 0.5, 0.8, 0.4, 0.8, 0.6])
    out = tmp_path / "c.png"
    assert main(["plot", str(log), "--out", str(out)]) == 0
    assert "60 episodes and 6 greedy checks" in capsys.readouterr().out
    import matplotlib.image as mpimg

    img = mpimg.imread(out)[:, :, :3]
    gold = np.all(np.abs(img - np.array([1.0, 215 / 255, 0.0])) < 0.02, axis=2)
    assert gold.sum() > 100  # the star is drawn
    from koolio_pymunk.apps.plotting import attach_evals

    logs = [read_log(log)]
    attach_evals(logs, None)
    fig = make_figure(logs, 10)
    ax_ret, ax_out = fig.axes[0], fig.axes[1]
    labels = [t.get_text() for t in ax_out.get_legend().get_texts()]
    assert "greedy check, at the goal (20 episodes)" in labels
    assert "kept best: 80% at episode 30" in labels
    checks = [ln for ln in ax_out.get_lines() if ln.get_marker() == "D"]
    assert checks[0].get_xdata().tolist() == [10, 20, 30, 40, 50, 60]
    assert np.allclose(checks[0].get_ydata(), [20, 50, 80, 40, 80, 60])
    returns = [ln for ln in ax_ret.get_lines() if ln.get_marker() == "D"]
    assert np.allclose(returns[0].get_ydata(), [-80, -50, -20, -60, -20, -40])
    plt.close(fig)


def test_evals_flag_and_bad_evals_files(tmp_path, capsys) -> None:
    log = tmp_path / "t.csv"
    write_log(log, 20)
    other = tmp_path / "elsewhere.csv"
    write_evals(other, [0.5, 0.7])
    out = str(tmp_path / "c.png")
    assert main(["plot", str(log), "--evals", str(other), "--out", out]) == 0
    assert "2 greedy checks" in capsys.readouterr().out
    assert main(["plot", str(log), str(log), "--evals", str(other), "--out", out]) == 2
    assert "--evals: 1 file for 2 logs" in capsys.readouterr().err
    other.write_text("episode,reward\n1,2\n")
    assert main(["plot", str(log), "--evals", str(other), "--out", out]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not an evaluations file" in err
    other.write_text(EVALS + "10,20,0,lots,0,0,0,5,1,-3,1,0.1\n")
    assert main(["plot", str(log), "--evals", str(other), "--out", out]) == 2
    assert "line 2: goal_rate: not a number" in capsys.readouterr().err


def test_plot_without_out_writes_beside_the_log_and_says_where(tmp_path, capsys, monkeypatch):
    """The README's flow (``plot --log runs/hallway.csv``) leaves no ``curve.png`` in the
    current folder: the picture goes beside the log, and the command's line names it."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "runs").mkdir()
    write_log(tmp_path / "runs" / "hallway.csv", 12)
    write_log(tmp_path / "runs" / "other.csv", 12)
    assert main(["plot", "--log", "runs/hallway.csv"]) == 0
    assert capsys.readouterr().out.strip().endswith("-> runs/hallway.png")
    assert main(["plot", "runs/hallway.csv", "runs/other.csv"]) == 0
    assert capsys.readouterr().out.strip().endswith("-> runs/hallway.compared.png")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["runs"]
    assert (tmp_path / "runs" / "hallway.png").stat().st_size > 10_000
    assert (tmp_path / "runs" / "hallway.compared.png").stat().st_size > 10_000


def test_plot_never_draws_over_a_file_it_reads(tmp_path, capsys) -> None:
    log = tmp_path / "odd.png"  # a log by an odd name: its picture is odd.png.png
    write_log(log, 5)
    before = log.read_bytes()
    assert main(["plot", str(log), "--out", str(log)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "a file being plotted" in err
    assert main(["plot", str(log)]) == 0
    assert log.read_bytes() == before and (tmp_path / "odd.png.png").exists()


def test_x_steps_draws_against_the_steps_taken_interrupted_ones_included(tmp_path) -> None:
    """``--x steps``: each episode at the environment steps taken up to its end, counted
    from the log's first row; an ``interrupted`` row is not drawn but its steps were taken;
    the greedy checks sit at the steps of the episode they followed."""
    import matplotlib.pyplot as plt

    from koolio_pymunk.apps.plotting import attach_evals, evals_beside, make_figure

    log = tmp_path / "t.csv"
    log.write_text(
        HEADER
        + "0,-10,100,0,end_of_world,0,0.1,311\n"
        + "1,-3,7,0,interrupted,0,0.1,311\n"  # Ctrl-C: 7 steps, the episode run again
        + "1,-5,50,1,goal,0,0.1,311\n"
        + "2,-1,20,0,goal,0,0.1,311\n"
    )
    evals_beside(log).write_text(EVALS + "2,20,0,0.5,0.5,0,0,50,1,-3,1,0.1\n")
    logs = [read_log(log)]
    attach_evals(logs, None)
    for axis, xs, check in (("episodes", [1, 2, 3], [2]), ("steps", [100, 157, 177], [157])):
        fig = make_figure(logs, 2, x=axis)
        ax_ret, ax_out, ax_steps = fig.axes[:3]
        assert ax_ret.get_lines()[0].get_xdata().tolist() == xs
        diamonds = [ln for ln in ax_out.get_lines() if ln.get_marker() == "D"]
        assert diamonds[0].get_xdata().tolist() == check
        assert ax_steps.get_xlabel().startswith("episode" if axis == "episodes" else "environment")
        plt.close(fig)


def test_x_flag_on_the_command_line(tmp_path, capsys) -> None:
    log = tmp_path / "t.csv"
    write_log(log, 20)
    assert main(["plot", str(log), "--x", "steps", "--out", str(tmp_path / "s.png")]) == 0
    assert (tmp_path / "s.png").stat().st_size > 10_000
    capsys.readouterr()
    assert main(["plot", str(log), "--x", "time"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--x: invalid choice: 'time'" in err
