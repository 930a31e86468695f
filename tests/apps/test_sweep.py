"""koolio-pm sweep: spec parsing, local processes vs Ray (same results), resume, outputs."""

from __future__ import annotations

import csv
import shutil
import sys
from pathlib import Path

import pytest
from inputs import same_run

from koolio_pymunk.apps import cli
from koolio_pymunk.apps.sweep import load_spec, parse_spec, plan, run_sweep
from koolio_pymunk.store.errors import ConfigError

#: Result columns that depend on the machine's speed (left out of comparisons).
TIMING_COLUMNS = ("competence_seconds", "train_seconds")
SPEC = """
name: tiny
episodes: 3
seeds: [0, 1]
base: {episode: {max_steps: 40}}
grid:
  learner.alpha: [0.1, 0.5]
eval_every: 2
eval_episodes: 1
"""


@pytest.fixture
def spec_file(tmp_path) -> Path:
    path = tmp_path / "tiny.yaml"
    path.write_text(SPEC)
    return path


def _rows(out: Path) -> list[dict[str, str]]:
    with open(out / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    return [{k: v for k, v in r.items() if k not in TIMING_COLUMNS} for r in rows]


def _tables(out: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(out)): p.read_bytes() for p in sorted(out.glob("runs/*/*/qtable.qtable"))
    }


def test_local_processes_and_ray_give_identical_results(spec_file, tmp_path):
    ray = pytest.importorskip("ray")
    spec = load_spec(spec_file)
    local = run_sweep(spec, tmp_path / "local", workers=2, plot=False, report=None)
    assert (local.ran, local.skipped, local.failed) == (4, 0, [])
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        remote = run_sweep(spec, tmp_path / "ray", ray_address="", plot=False, report=None)
        assert ray.is_initialized()  # the sweep used the test's instance and left it running
    finally:
        ray.shutdown()
    assert (remote.ran, remote.failed) == (4, [])
    rows = _rows(tmp_path / "local")
    assert rows == _rows(tmp_path / "ray")
    assert [r["run_id"] for r in rows] == [t["run_id"] for t in plan(spec)]
    assert {r["learner.alpha"] for r in rows} == {"0.1", "0.5"}
    assert len({r["table_sha256"] for r in rows}) == 4
    assert _tables(tmp_path / "local") == _tables(tmp_path / "ray")
    for name in ("train.csv", "evals.csv"):
        a = [_untimed(p) for p in sorted((tmp_path / "local").glob(f"runs/*/*/{name}"))]
        b = [_untimed(p) for p in sorted((tmp_path / "ray").glob(f"runs/*/*/{name}"))]
        assert len(a) == 4
        assert a == b


def _untimed(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as fh:
        return [{k: v for k, v in r.items() if k != "train_seconds"} for r in csv.DictReader(fh)]


def test_resume_skips_finished_runs_and_matches(spec_file, tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["sweep", str(spec_file), "--out", str(out), "--workers", "1"]
    assert cli.main(argv) == 0
    first = _rows(out)
    assert len(first) == 4
    evals = (out / "runs" / first[0]["run_id"] / "evals.csv").read_text().splitlines()
    assert evals[0].startswith("episode,goal_rate,mean_steps,mean_bumps")
    assert [line.split(",")[0] for line in evals[1:]] == ["2", "3"]
    train_log = (out / "runs" / first[0]["run_id"] / "train.csv").read_text().splitlines()
    assert train_log[0].startswith("# koolio-pymunk run ")  # the table's run
    assert train_log[1] == "episode,reward,steps,bumps,outcome,rescued,epsilon,goal"
    assert len(train_log) == 5
    assert (out / "curves.png").read_bytes()[:4] == b"\x89PNG"
    # lose one run entirely and another's results.csv row only (its result.json remains)
    lines = (out / "results.csv").read_text().splitlines()
    (out / "results.csv").write_text("\n".join(lines[:3]) + "\n")
    shutil.rmtree(out / "runs" / first[2]["run_id"])
    capsys.readouterr()
    outcome = run_sweep(load_spec(spec_file), out, workers=1, plot=False, report=print)
    said = capsys.readouterr().out
    assert "4 runs (3 already done, 1 to run)" in said
    assert (outcome.ran, outcome.skipped) == (1, 3)
    assert _rows(out) == first


def test_a_run_s_checkpoints_are_train_eval_every_s_checks(tmp_path):
    """A run checks its table as ``koolio-pm train --eval-every`` does, with the run's
    seed: the same table bytes and the same check figures (a sweep once evaluated with
    seed 1,000,000 + s, so one run had other checkpoints in a sweep than in ``train``);
    a last stretch shorter than ``eval_every`` ends with that evaluation of the final
    table."""
    from koolio_pymunk.learning.evaluation import evaluate
    from koolio_pymunk.store.qtable import load_qtable
    from koolio_pymunk.task.env import KoolioEnv

    text = "name: one\nepisodes: 5\nseeds: [3]\narena: room\n"
    text += "base: {episode: {max_steps: 40}}\neval_every: 2\neval_episodes: 4\n"
    run_sweep(load_spec_text(tmp_path, text), tmp_path / "out", workers=1, plot=False, report=None)
    (run,) = (tmp_path / "out").glob("runs/*/seed3")
    swept = list(csv.DictReader((run / "evals.csv").open()))
    (tmp_path / "cfg.yaml").write_text("episode: {max_steps: 40}\n")
    table = tmp_path / "t.qtable"
    argv = ["train", "--arena", "room", "--config", str(tmp_path / "cfg.yaml"), "--seed", "3",
            "--episodes", "5", "--eval-every", "2", "--eval-episodes", "4", "--qtable",
            str(table), "--quiet"]  # fmt: skip
    assert cli.main(argv) == 0
    assert same_run(run / "qtable.qtable", table)
    assert (run / "train.csv").read_bytes() == (tmp_path / "t.csv").read_bytes()
    checks = list(csv.DictReader((tmp_path / "t.evals.csv").open()))
    assert [r["episode"] for r in swept] == ["2", "4", "5"]
    assert [c["episode"] for c in checks] == ["2", "4"]
    figures = ("goal_rate", "mean_steps", "mean_bumps", "mean_return")
    for row, check in zip(swept, checks):  # the check file keeps 6 significant digits
        assert [f"{float(row[k]):.6g}" for k in figures] == [check[k] for k in figures]
    env = KoolioEnv("room", config=str(tmp_path / "cfg.yaml"))
    last, before = (
        evaluate(env, load_qtable(table), 4, 3),
        evaluate(env, load_qtable(table), 4, 3 + 1_000_000),
    )
    assert [float(swept[-1][k]) for k in figures] == [
        last.goal_rate,
        last.mean_steps,
        last.mean_bumps,
        last.mean_reward,
    ]
    assert (last.mean_steps, last.mean_reward) != (before.mean_steps, before.mean_reward)


def test_a_run_in_another_world_records_it_in_its_table(tmp_path):
    """As ``train --world`` does: resuming or continuing the table elsewhere is refused."""
    from koolio_pymunk.store.qtable import load_qtable

    spec = load_spec_text(
        tmp_path, SPEC.replace("seeds: [0, 1]", "seeds: [0]") + "world: koolio-real\n"
    )
    run_sweep(spec, tmp_path / "out", workers=1, plot=False, report=None)
    tables = sorted((tmp_path / "out").glob("runs/*/*/qtable.qtable"))
    assert len(tables) == 2
    assert {load_qtable(t).meta.get("world") for t in tables} == {"koolio-real"}


def test_a_run_whose_configuration_turns_realism_on_records_its_world(tmp_path):
    """``config: koolio-real`` is the world koolio-real, as ``--world`` is; realism swept
    in the grid is named by its content, one world per value."""
    from koolio_pymunk.store.qtable import load_qtable

    text = SPEC.replace("seeds: [0, 1]", "seeds: [0]").replace(
        "learner.alpha: [0.1, 0.5]", "realism.motion.drift_deg: [0.0, 1.0]"
    )
    spec = load_spec_text(tmp_path, text + "config: koolio-real\n")
    run_sweep(spec, tmp_path / "out", workers=1, plot=False, report=None)
    worlds = {t.parent.parent.name.split("-")[0]: load_qtable(t).meta.get("world")
              for t in (tmp_path / "out").glob("runs/*/*/qtable.qtable")}  # fmt: skip
    assert worlds["drift_deg=0.0"].startswith("realism-")  # koolio-real without its drift
    assert worlds["drift_deg=1.0"].startswith("realism-")
    assert len(set(worlds.values())) == 2
    spec = load_spec_text(
        tmp_path, SPEC.replace("seeds: [0, 1]", "seeds: [0]") + "config: koolio-real\n"
    )
    run_sweep(spec, tmp_path / "real", workers=1, plot=False, report=None)
    tables = sorted((tmp_path / "real").glob("runs/*/*/qtable.qtable"))
    assert {load_qtable(t).meta.get("world") for t in tables} == {"koolio-real"}


def test_an_output_folder_of_another_spec_or_command_is_refused(tmp_path, capsys):
    """A sweep into a folder holding another spec's results would mix them in
    results.csv (and replace spec.yaml and configs.csv): refused, as a folder that is not
    a sweep's is; the same spec, or one that only adds runs, resumes."""
    from tests.inputs import expect_error

    one = SPEC.replace("seeds: [0, 1]", "seeds: [0]").replace("0.1, 0.5", "0.1")
    (tmp_path / "a.yaml").write_text(one)
    (tmp_path / "b.yaml").write_text(one.replace("[0.1]", "[0.5]"))
    (tmp_path / "more.yaml").write_text(one.replace("seeds: [0]", "seeds: [0, 1]"))
    out = tmp_path / "out"
    sweep = ["sweep", "--out", str(out), "--workers", "1", "--no-plot"]
    assert cli.main([*sweep, str(tmp_path / "a.yaml")]) == 0
    capsys.readouterr()
    expect_error(capsys, out, [*sweep, str(tmp_path / "b.yaml")],
                 f"{out}: --out: holds 1 finished run of another spec ('alpha=0.1-",
                 "spec.yaml line 7 was 'learner.alpha: [0.1]', now 'learner.alpha: [0.5]'",
                 "give a new --out")  # fmt: skip
    expect_error(capsys, out, [*sweep, str(tmp_path / "a.yaml"), "--world", "koolio-real"],
                 "the same spec.yaml: its runs had another --world")  # fmt: skip
    assert cli.main([*sweep, str(tmp_path / "more.yaml")]) == 0
    assert "2 runs (1 already done, 1 to run)" in capsys.readouterr().out
    assert len(_rows(out)) == 2
    transfer = tmp_path / "transfer"
    transfer.mkdir()
    (transfer / "transfer.json").write_text("{}")
    expect_error(capsys, transfer, [*sweep[:1], str(tmp_path / "a.yaml"), "--out", str(transfer)],
                 f"{transfer}: --out: not a sweep's folder (it holds 'transfer.json'")  # fmt: skip
    assert sorted(p.name for p in transfer.iterdir()) == ["transfer.json"]  # no lock file


def load_spec_text(folder: Path, text: str):
    path = folder / "spec.yaml"
    path.write_text(text)
    return load_spec(path)


def test_spec_grid_and_runs_make_configurations(tmp_path):
    spec = parse_spec(
        {
            "episodes": 5,
            "seeds": 2,
            "goal": 302,
            "base": {"actions": {"move_action_distance": 6}},
            "grid": {"learner.gamma": [0.9, 0.99], "robot.profile": ["koolio", "tjpro"]},
            "runs": [{"name": "a"}, {"name": "b", "rewards": {"bump": -3}, "goal": "random"}],
        },
        "s.yaml",
    )
    tasks = plan(spec)
    assert len(tasks) == 2 * 2 * 2 * 2
    assert len({t["config_id"] for t in tasks}) == 8
    assert tasks[0]["label"] == "a gamma=0.9 profile=koolio"
    assert {t["goal"] for t in tasks} == {"302", "random"}
    b = [t for t in tasks if t["label"].startswith("b ")]
    assert {t["config"]["rewards"]["bump"] for t in b} == {-3.0}
    assert {t["config"]["robot"]["profile"] for t in tasks} == {"koolio", "tjpro"}
    assert [t["seed"] for t in tasks[:4]] == [0, 1, 0, 1]


def test_rotate_deg_sweeps_the_arena_rotation_without_a_copy_of_the_file():
    runs = [{"name": "file"}, {"name": "r", "rotate_deg": 5}]
    spec = parse_spec({"episodes": 2, "rotate_deg": 2, "runs": runs}, "s.yaml")
    tasks = plan(spec)
    assert [t["arena_obj"].rotate_deg for t in tasks] == [2.0, 5.0]
    assert [t["rotate_deg"] for t in tasks] == [2.0, 5.0]
    assert {t["arena"] for t in tasks} == {"hallway"}
    assert len({t["config_id"] for t in tasks}) == 2  # the rotation is part of the hash
    plain = plan(parse_spec({"episodes": 2}, "s.yaml"))[0]
    zero = plan(parse_spec({"episodes": 2, "grid": {"rotate_deg": [0]}}, "s.yaml"))[0]
    assert plain["arena_obj"].rotate_deg == zero["arena_obj"].rotate_deg == 0.0
    assert plain["config_id"].split("-")[-1] == zero["config_id"].split("-")[-1]
    with pytest.raises(ConfigError, match=r"s.yaml: grid: rotate_deg: expected a finite num"):
        plan(parse_spec({"episodes": 2, "grid": {"rotate_deg": ["five"]}}, "s.yaml"))
    with pytest.raises(ConfigError, match=r"s.yaml: rotate_deg: expected a finite number"):
        parse_spec({"episodes": 2, "rotate_deg": float("nan")}, "s.yaml")


def test_summary_reports_spread_and_table_size(spec_file, tmp_path, capsys):
    out = tmp_path / "out"
    assert cli.main(["sweep", str(spec_file), "--out", str(out), "--workers", "1"]) == 0
    said = capsys.readouterr().out
    assert "min-max" in said and "states" in said
    with open(out / "configs.csv", newline="") as fh:
        configs = list(csv.DictReader(fh))
    rows = _rows(out)
    for c in configs:
        mine = [r for r in rows if r["config_id"] == c["config_id"]]
        rates = [float(r["final_goal_rate"]) for r in mine]
        states = [int(r["states"]) for r in mine]
        assert float(c["final_goal_rate_min"]) == min(rates)
        assert float(c["final_goal_rate_max"]) == max(rates)
        assert float(c["states_mean"]) == sum(states) / len(states)
        assert int(c["state_space"]) == 3**6 * 4**6  # the paper's 2,985,984 states


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({}, "s.yaml: episodes: missing"),
        ({"episodes": 3, "sedes": 2}, "s.yaml: sedes: unknown key (did you mean 'seeds'?)"),
        ({"episodes": 3, "grid": {"learner.alpha": 0.1}}, "grid.learner.alpha: must be a non"),
        ({"episodes": 3, "seeds": [1, 1]}, "s.yaml: seeds: a seed is listed twice"),
        ({"episodes": 0}, "s.yaml: episodes: must be >= 1, got 0"),
        ({"episodes": 3, "competence": 2}, "s.yaml: competence: must be in (0, 1]"),
    ],
)
def test_bad_specs_fail_in_one_line(data, message):
    with pytest.raises(ConfigError) as info:
        parse_spec(data, "s.yaml")
    assert message in str(info.value)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (
            {"episodes": 3, "grid": {"learner.alfa": [0.1]}},
            "s.yaml: grid: learner.alfa: unknown key",
        ),
        ({"episodes": 3, "grid": {"learner.alpha": [2.0]}}, "learner.alpha: must be in (0, 1]"),
        ({"episodes": 3, "goal": "999"}, "s.yaml: goal: no goal named '999'"),
        ({"episodes": 3, "grid": {"goal": ["999"]}}, "s.yaml: grid: goal: no goal named '999'"),
        ({"episodes": 3, "arena": "nosuch"}, "s.yaml: arena: nosuch: no such arena file"),
        ({"episodes": 3, "world": "koolio-rea"}, "s.yaml: world: koolio-rea: no such world"),
        ({"episodes": 3, "grid": {"world": ["nope"]}}, "s.yaml: grid: world: nope: no such w"),
        ({"episodes": 3, "runs": [{"name": "x"}, {"name": "x"}]}, "'x' repeats the config"),
    ],
)
def test_bad_parameters_fail_before_running(data, message):
    with pytest.raises(ConfigError) as info:
        plan(parse_spec(data, "s.yaml"))
    assert message in str(info.value)
    assert "\n" not in str(info.value)


def test_cli_dry_run_and_missing_ray(spec_file, tmp_path, capsys, monkeypatch):
    assert cli.main(["sweep", str(spec_file), "--dry-run"]) == 0
    out = capsys.readouterr().out
    assert "2 configurations x 2 seeds" in out and "alpha=0.1-" in out
    assert cli.main(["sweep", str(spec_file.with_name("nope.yaml"))]) == 2
    assert "nope.yaml: file not found" in capsys.readouterr().err
    monkeypatch.setitem(sys.modules, "ray", None)  # as if Ray were not installed
    assert cli.main(["sweep", str(spec_file), "--ray", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err == (
        "koolio-pm: error: --ray: Ray is not installed (pip install 'koolio-pymunk[ray]')\n"
    )


LONG_SPEC = """
name: long
episodes: 1000
seeds: [0, 1, 2, 3]
base: {episode: {max_steps: 200}, learner: {algorithm: dyna}}
"""


@pytest.mark.parametrize("sig", ["SIGTERM", "SIGKILL"])
def test_a_stopped_sweep_ends_without_tracebacks(tmp_path, sig):
    """SIGTERM stops a sweep as Ctrl-C does (finished runs kept, workers stopped, exit
    143 = 128 + SIGTERM, one line); after a SIGKILL of the sweep its workers end quietly (nobody to
    tell), without a traceback."""
    import signal
    import subprocess
    import time

    spec = tmp_path / "long.yaml"
    spec.write_text(LONG_SPEC)
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "koolio_pymunk", "sweep", str(spec), "--workers", "2",
           "--out", str(out), "--no-plot"]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)  # fmt: skip
    deadline = time.monotonic() + 60
    while not (out / "spec.yaml").exists() and time.monotonic() < deadline:
        time.sleep(0.1)
    time.sleep(2.0)  # the workers are inside their first runs
    proc.send_signal(getattr(signal, sig))
    stdout, err = proc.communicate(timeout=120)
    if sig == "SIGTERM":
        assert proc.returncode == 143, err
        assert "interrupted: finished runs are saved" in stdout + err
    else:  # the workers, orphaned, finish their run and find the pipe closed
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            ps = subprocess.run(["pgrep", "-s", str(proc.pid)], capture_output=True, text=True)
            if not ps.stdout.strip():
                break
            time.sleep(0.5)
        assert not ps.stdout.strip(), "the workers did not end"
    assert "Traceback" not in err
