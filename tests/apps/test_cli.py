"""koolio-pm: tiny-budget smoke tests of every core command and its bad-input errors."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from koolio_pymunk.apps.cli import main


def cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "koolio_pymunk.apps.cli", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=120,
    )


def one_line_error(p: subprocess.CompletedProcess, *words: str) -> None:
    assert p.returncode == 2, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1, p.stderr
    assert "Traceback" not in p.stderr
    for w in words:
        assert w in lines[0], lines[0]


def tiny_config(tmp_path: Path) -> Path:
    cfg = tmp_path / "tiny.yaml"
    cfg.write_text("episode: {max_steps: 40}\n")
    return cfg


def test_train_then_eval_then_info(tmp_path) -> None:
    cfg = tiny_config(tmp_path)
    q, log = tmp_path / "q.qtable", tmp_path / "log.csv"
    p = cli(
        "train",
        "--arena",
        "room",
        "--episodes",
        "3",
        "--seed",
        "1",
        "--qtable",
        str(q),
        "--log",
        str(log),
        "--config",
        str(cfg),
    )
    assert p.returncode == 0, p.stderr
    assert "configuration:" not in p.stdout  # behind --verbose
    assert "training goal rate" in p.stdout and "steps/s" in p.stdout
    assert q.exists() and Path(str(q) + ".bak").exists()
    assert log.read_text().startswith("# koolio-pymunk run ")
    assert len(log.read_text().splitlines()) == 5  # the run line, the header, 3 rows
    p = cli(
        "eval",
        "--arena",
        "room",
        "--qtable",
        str(q),
        "--episodes",
        "2",
        "--json",
        "--config",
        str(cfg),
    )
    assert p.returncode == 0, p.stderr
    figures = json.loads(p.stdout)
    assert figures["episodes"] == 2 and 0 <= figures["goal_rate"] <= 1
    p = cli("info", "--qtable", str(q))
    assert p.returncode == 0
    assert "238.4 GiB" in p.stdout and "113.9 MiB" in p.stdout and "2,985,984" in p.stdout
    assert "GoalCam0<<25" in p.stdout and "Sonar7<<3" in p.stdout


def test_eval_goal_all_prints_every_door(tmp_path, capsys) -> None:
    cfg = tiny_config(tmp_path)
    q = tmp_path / "q.qtable"
    assert (
        main(
            [
                "train",
                "--arena",
                "hallway",
                "--episodes",
                "1",
                "--qtable",
                str(q),
                "--log",
                str(tmp_path / "l.csv"),
                "--config",
                str(cfg),
                "--quiet",
            ]
        )
        == 0
    )
    assert (
        main(["eval", "--qtable", str(q), "--episodes", "1", "--goal", "all", "--config", str(cfg)])
        == 0
    )
    out = capsys.readouterr().out
    for room in ("301", "302", "311", "318"):
        assert f" {room} " in out
    assert " all " in out


@pytest.mark.parametrize(("trained_for", "warned"), [("random", False), ("311", True)])
def test_eval_goal_all_warns_only_for_a_table_of_one_goal(tmp_path, capsys, trained_for, warned):
    """``eval --goal all`` asks what a random-goal run asks: a table trained for a random
    goal is scored without a warning, a table of one door with one."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text("episode: {max_steps: 20}\n")
    q, log = str(tmp_path / "q.qtable"), str(tmp_path / "l.csv")
    train = ["train", "--episodes", "1", "--qtable", q, "--log", log, "--config", str(cfg)]
    assert main([*train, "--goal", trained_for, "--quiet"]) == 0
    capsys.readouterr()
    score = ["eval", "--qtable", q, "--episodes", "1", "--goal", "all", "--config", str(cfg)]
    assert main(score) == 0
    err = capsys.readouterr().err
    assert ("scored here for" in err) == warned, err


def test_check_arena_ok_and_bad(tmp_path) -> None:
    p = cli("check-arena", "hallway")
    assert p.returncode == 0 and "ok" in p.stdout and "1728 x 184 in" in p.stdout
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nwals: [[0, 0], [1, 0], [1, 1]]\n")
    one_line_error(cli("check-arena", str(bad)), "bad.yaml", "wals", "did you mean 'walls'")
    one_line_error(cli("check-arena", str(tmp_path / "missing.yaml")), "missing.yaml")


def test_bad_flags_and_bad_files_are_one_line_exit_2(tmp_path) -> None:
    one_line_error(cli("train", "--episodes", "many"), "--episodes", "not an integer")
    one_line_error(cli("train", "--frobnicate"), "unrecognized arguments")
    one_line_error(cli("train", "--episodes", "-1", "--qtable", str(tmp_path / "q")), "--episodes")
    corrupt = tmp_path / "c.qtable"
    corrupt.write_bytes(b"KOOLIOQT" + b"\x00" * 40)
    one_line_error(cli("eval", "--qtable", str(corrupt)), "c.qtable")
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text("learner: {alpah: 0.1}\n")
    one_line_error(
        cli("train", "--config", str(cfg), "--qtable", str(tmp_path / "q")),
        "cfg.yaml",
        "learner.alpah",
        "did you mean 'alpha'",
    )
    cfg.write_text("actions: {move_action_distance: 50}\n")
    one_line_error(
        cli("train", "--config", str(cfg), "--qtable", str(tmp_path / "q")),
        "actions.move_action_distance",
    )
    one_line_error(
        cli("train", "--goal", "999", "--qtable", str(tmp_path / "q")), "no goal named '999'"
    )


def test_mismatched_table_is_refused_and_untouched(tmp_path) -> None:
    cfg = tiny_config(tmp_path)
    q = tmp_path / "q.qtable"
    assert (
        cli(
            "train",
            "--arena",
            "room",
            "--episodes",
            "1",
            "--qtable",
            str(q),
            "--log",
            str(tmp_path / "l.csv"),
            "--config",
            str(cfg),
            "--quiet",
        ).returncode
        == 0
    )
    before = q.read_bytes()
    other = tmp_path / "other.yaml"
    other.write_text("episode: {max_steps: 40}\nsensors: {sonar: {sonar_arc_deg: 40}}\n")
    p = cli(
        "train",
        "--arena",
        "room",
        "--episodes",
        "1",
        "--qtable",
        str(q),
        "--config",
        str(other),
        "--log",
        str(tmp_path / "l.csv"),
    )
    one_line_error(p, "q.qtable", "sensors.sonar_arc_deg")
    assert q.read_bytes() == before


@pytest.mark.parametrize(
    "command", ["train", "eval", "check-arena", "info", "view", "plot", "export", "sweep"]
)
def test_every_command_has_help(command: str) -> None:
    p = cli(command, "--help")
    assert p.returncode == 0 and "usage:" in p.stdout


def test_eval_reads_an_exported_policy(tmp_path) -> None:
    cfg = tiny_config(tmp_path)
    q, pol = tmp_path / "q.qtable", tmp_path / "policy.json"
    assert (
        main(
            [
                "train",
                "--arena",
                "room",
                "--episodes",
                "2",
                "--qtable",
                str(q),
                "--log",
                str(tmp_path / "l.csv"),
                "--config",
                str(cfg),
                "--quiet",
            ]
        )
        == 0
    )
    assert main(["export", "--qtable", str(q), "--out", str(pol)]) == 0
    a = cli(
        "eval",
        "--arena",
        "room",
        "--qtable",
        str(q),
        "--episodes",
        "2",
        "--json",
        "--config",
        str(cfg),
    )
    b = cli(
        "eval",
        "--arena",
        "room",
        "--qtable",
        str(pol),
        "--episodes",
        "2",
        "--json",
        "--config",
        str(cfg),
    )
    assert a.returncode == b.returncode == 0
    assert json.loads(a.stdout) == json.loads(b.stdout)


def test_closed_output_pipe_is_not_an_error() -> None:
    p = subprocess.run(
        f"{sys.executable} -m koolio_pymunk.apps.cli info | head -c 10",
        shell=True,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert p.stdout == "State spac" and p.stderr == ""


def test_a_table_in_use_is_the_only_line_train_prints(tmp_path, capsys):
    """A second ``train`` on a table another run holds says so and nothing else (it
    printed ``resuming ...`` first: newcomer audit)."""
    from koolio_pymunk.store.locks import FileLock

    table = tmp_path / "t.qtable"
    argv = ["train", "--arena", "room", "--episodes", "2", "--qtable", str(table)]
    assert main([*argv, "--quiet"]) == 0
    capsys.readouterr()
    with FileLock(table, "koolio-pm train"):
        assert main([*argv[:-3], "4", "--qtable", str(table)]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.count("\n") == 1 and "t.qtable: in use by process" in err


def test_info_of_a_bad_table_says_only_that(tmp_path, capsys):
    """``info --qtable BAD``: the one error line, not the state-space block first
    (newcomer audit)."""
    bad = tmp_path / "bad.qtable"
    bad.write_bytes(b"garbage")
    assert main(["info", "--qtable", str(bad)]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    want = "neither a .qtable file nor a koolio-policy (JSON) file"
    assert err == f"koolio-pm: error: {bad}: {want}\n"


def test_info_describes_the_tables_own_layout(tmp_path, capsys) -> None:
    """``info --qtable`` describes the layout the table records, not the defaults', and
    says when the configuration is not the table's (audit: a 35-bit table was printed
    under the default 27-bit keyword, its share of the dense table computed against the
    35-bit one); "in the file" is the file's size (it was the rows' bytes: 16.5 KiB for
    files of 17,643 and 89,019 bytes)."""
    from inputs import table_file

    from koolio_pymunk.apps.export import policy_document, write_policy
    from koolio_pymunk.store.config import load_config
    from koolio_pymunk.store.qtable import load_qtable

    qlambda = {"name": "qlambda", "trace_cutoff": 0.01, "trace_decay": 0.9}
    mem = table_file(tmp_path / "mem.qtable", load_config("paper-memory-qlambda"), qlambda)
    plain = table_file(tmp_path / "plain.qtable", load_config())
    pol = tmp_path / "plain.json"
    write_policy(policy_document(load_qtable(plain)), pol)

    def in_file(path: Path) -> str:
        size = path.stat().st_size
        return f"{size:,} bytes" + (f" ({size / 1024:.1f} KiB)" if size >= 1024 else "")

    def info(*argv: str) -> list[str]:
        assert main(["info", *argv]) == 0
        out, err = capsys.readouterr()
        assert err == ""
        return out.splitlines()

    lines = info("--qtable", str(mem))
    assert lines[5:9] == [
        f"  this table ({mem}: the layout in its header):",
        f"    states  {358_318_080:>16,}",
        f"    entries {1_791_590_400:>16,}  (x 5 actions)",
        "    dense           13.3 GiB",
    ]
    assert lines[9] == "Keyword (35 bits, Table 12):"
    assert lines[10].endswith("GoalMemory<<9 | LastAction<<6 | GoalBearing<<3 | Action")
    assert lines[11] == (
        f"Q-table {mem}: 3 states visited, 15 entries (0.000% of its dense table), "
        f"{in_file(mem)} in the file, 3 episodes"
    )
    assert lines[12] == "  learned with qlambda (trace_cutoff 0.01, trace_decay 0.9)"
    assert lines[13].startswith(
        "  not a table of the default configuration (no --config): layout: table made for "
        "35-bit keyword"
    )
    assert lines[13].endswith("add --config paper-memory-qlambda)")
    assert lines[14].startswith("  learned content ") and lines[15] == (
        "  provenance: not recorded (a table made before tables recorded it)"
    )
    assert len(lines) == 16
    lines = info("--qtable", str(mem), "--config", "paper-memory-qlambda")
    assert lines[5] == "  this configuration:" and len(lines) == 15  # its own: no remark
    lines = info("--qtable", str(plain), "--config", "paper-memory")
    assert lines[5:7] == ["  this configuration:", f"    states  {71_663_616:>16,}"]
    assert lines[9] == "Keyword (32 bits, Table 12):"
    assert lines[12].startswith("  its keyword (27 bits): GoalCam0<<25 | ")
    assert lines[13].startswith("  not a table of --config paper-memory: layout: table made")
    assert lines[13].endswith("(it was made with the default configuration: leave out --config)")
    for path in (plain, pol):  # the file's own size, whichever format
        assert f", {in_file(path)} in the file, 3 episodes" in info("--qtable", str(path))[11]
    assert pol.stat().st_size > 2 * plain.stat().st_size  # the premise: the sizes differ
