"""A fuzzer per surface of issue #21: realism configurations, Dyna-Q model sections,
policies in the robot runtime, training logs, lock and special files, command flags.

Each case must end either well (the file loads, the command exits 0) *and behave
correctly* (what was loaded learns and saves a file that loads again; the table and the
log stay in step), or in the project's one-line error (exit 2, one line, every file that
existed before byte-identical), and within a time limit (:func:`limit`: an alarm in the
process, a timeout for a real one). Anything else fails with the case's label.

Small by default (seeded, a few hundred cases in all, well under a minute);
``KOOLIO_FUZZ_CASES=N`` runs N cases per surface (the default is 40) and
``KOOLIO_FUZZ_SEED`` other cases than the usual ones; a failure names its label, and the
same two settings replay it (CONTRIBUTING.md).
"""

from __future__ import annotations

import copy
import itertools
import json
import math
import os
import random
import shutil
import signal
import socket
import struct
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from inputs import small_table, snapshot
from test_fuzz import mutate_structure, says_what_it_holds

from koolio_pymunk import robot_runtime as rt
from koolio_pymunk.apps import cli
from koolio_pymunk.apps.export import policy_document
from koolio_pymunk.learning.dyna import DynaQ
from koolio_pymunk.store.config import Config, LearnerConfig, apply_world
from koolio_pymunk.store.dyna_model import SECTION, Model
from koolio_pymunk.store.episode_log import log_rows
from koolio_pymunk.store.errors import KoolioError
from koolio_pymunk.store.qtable import QTable, load_qtable

ROOT = Path(__file__).resolve().parent.parent
CASES = int(os.environ.get("KOOLIO_FUZZ_CASES", "40"))
SEED = os.environ.get("KOOLIO_FUZZ_SEED", "")
#: Seconds one case may take (an env step, a short training run, a plot).
TIME_LIMIT = 60
pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals and FIFOs")


def rng_for(surface: str) -> random.Random:
    return random.Random(f"{surface}{SEED}")


@contextmanager
def limit(label: str, seconds: int = TIME_LIMIT) -> Iterator[None]:
    """Fail the case, not the suite, when it runs longer than ``seconds``."""

    def ring(signum, frame):
        raise TimeoutError(f"{label}: still running after {seconds} s")

    old = signal.signal(signal.SIGALRM, ring)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def one_line(exc: BaseException, label: str, source: str = "") -> None:
    message = str(exc)
    assert message and "\n" not in message, f"{label}: not one line: {message!r}"
    assert message.startswith(source), f"{label}: does not name {source!r}: {message!r}"


def run_cli(capsys, argv: list[str], folder: Path, label: str) -> int:
    """``koolio-pm argv`` in ``folder`` within the time limit: exit 0, or exit 2 with one
    line and no file changed. Returns the exit status."""
    before = snapshot(folder)
    with limit(label):
        try:
            code = cli.main(argv)
        except Exception as exc:  # anything but the promise
            pytest.fail(f"{label}: {type(exc).__name__}: {exc}")
    _, err = capsys.readouterr()
    assert "Traceback" not in err, f"{label}: {err}"
    assert code in (0, 2), f"{label}: exit {code}: {err}"
    if code == 2:
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("koolio-pm: error: "), f"{label}: {err}"
        assert snapshot(folder) == before, f"{label}: a refusal changed files"
    return code


def in_step(folder: Path, table: str, log: str, label: str) -> None:
    """The table and the log agree: finished rows numbered strictly upwards, none beyond
    the table, the last one the table's last episode (a row may be missing: a torn row
    of an episode the table holds is moved away, and a planted empty log starts anew)."""
    rows = log_rows(folder / log)
    done = [int(r["episode"]) for r in rows if r["outcome"] != "interrupted"]
    episodes = load_qtable(folder / table).meta["episodes"]
    assert all(a < b for a, b in itertools.pairwise(done)), f"{label}: numbers {done}"
    assert done and done[-1] == episodes - 1, f"{label}: log {done} vs table {episodes}"


# == realism configurations =====================================================================
#: Values a realism parameter may get (every magnitude, the type's edges, the bad kinds).
NUMBERS = [0, 1, -1, 0.5, 2, 1e-9, 1e-6, 0.02, 30, 31, 90, 120, 1e3, 1e6, 1e15, 1e16, -1e6]
AWKWARD = ["x", None, True, [], {}, ".nan", ".inf", "-.inf", "1e999", [1, 2], 9 * 10**400]


def _realism_doc(rng: random.Random) -> dict:
    base = copy.deepcopy(Config().to_dict()["realism"])
    base.pop("randomize")
    doc: dict[str, Any] = {}
    for _ in range(rng.randint(1, 4)):
        section = rng.choice(sorted(base))
        key = rng.choice(sorted(base[section]))
        value = rng.choice(NUMBERS) * rng.choice([1, 1, -1]) if rng.random() < 0.8 else None
        if value is None:
            value = rng.choice(AWKWARD)
        doc.setdefault(section, {})[key] = value
    if rng.random() < 0.4:
        key = rng.choice(
            ["sonar.sigma_hit", "sonar.z_rand", "motion.slip_sigma", "motion.drift_deg", "x.y"]
        )
        span = sorted(rng.choice(NUMBERS) for _ in range(2))
        doc["randomize"] = {key: span if rng.random() < 0.8 else rng.choice(AWKWARD)}
    return {"realism": doc}


def test_fuzz_realism_configuration(tmp_path):
    """Accepted worlds drive the robot: a few hundred steps of the room never hang or
    crash (``slip_sigma: 1e6`` once made one move a million inches)."""
    from koolio_pymunk.task.env import KoolioEnv

    rng = rng_for("realism")
    path = tmp_path / "w.yaml"
    driven = 0
    for case in range(CASES):
        label = f"realism case {case}"
        text = yaml.safe_dump(_realism_doc(rng), sort_keys=False)
        text = text.replace("'.nan'", ".nan").replace("'.inf'", ".inf").replace("'-.inf'", "-.inf")
        path.write_text(text)
        try:
            cfg = apply_world(Config(), path)
        except KoolioError as exc:
            one_line(exc, label, str(path))
            continue
        except Exception as exc:
            pytest.fail(f"{label}: {type(exc).__name__}: {exc}\n{text}")
        if driven >= max(4, CASES // 8):
            continue
        driven += 1
        cfg.episode.max_steps = 200
        with limit(label):
            env = KoolioEnv(arena="room", config=cfg)
            env.reset(seed=case)
            for _ in range(200):
                _, _, done, truncated, _ = env.step(int(rng.randrange(5)))
                if done or truncated:
                    env.reset(seed=case)
    assert driven >= 1  # the premise: some worlds were accepted and driven


# == Dyna-Q model sections =======================================================================
TABLE = small_table()
LAYOUT = TABLE.layout
STATES = sorted(TABLE.rows)


def _good_model(rng: random.Random) -> Model:
    model = Model()
    for _ in range(rng.randint(1, 12)):
        model.record(
            rng.choice(STATES),
            rng.randrange(5),
            rng.choice([-0.5, -1.0, -5.0, 100.0, -100.0]),
            rng.choice(STATES),
            rng.random() < 0.2,
        )
    return model


def _mutate_section(data: bytes, rng: random.Random) -> bytes:
    """The section with one or two of its 8-byte words replaced or its length changed."""
    words = bytearray(data)
    for _ in range(rng.randint(1, 2)):
        action = rng.random()
        if action < 0.75 and len(words) >= 8:
            at = 8 * rng.randrange(len(words) // 8)
            value = rng.choice(
                [
                    struct.pack("<Q", rng.choice([0, 1, 2, 5, 7, 2**24, 2**53 + 1, 2**63])),
                    struct.pack("<Q", 2**64 - 1),
                    struct.pack("<d", rng.choice([math.nan, math.inf, 1e308, -1e16, 1e15])),
                    struct.pack("<Q", rng.choice(STATES) + rng.choice([0, 1, 1 << 20])),
                ]
            )
            words[at : at + 8] = value
        elif action < 0.9:
            del words[rng.randrange(len(words) + 1) :]
        else:
            words += bytes(rng.randrange(256) for _ in range(rng.choice([1, 8, 40])))
    return bytes(words)


def _section_as_json(data: bytes) -> dict | None:
    """The model of a section as the robot's JSON form, values as they are (None when the
    section's lengths do not even hold together)."""
    if len(data) < 16:
        return None
    n, m = struct.unpack_from("<QQ", data)
    if len(data) != 16 + 8 * (3 * n + 4 * m):
        return None
    arrays, pos = [], 16
    for count, dtype in ((n, "<u8"),) * 3 + ((m, "<u8"), (m, "<f8"), (m, "<u8"), (m, "<u8")):
        arrays.append(np.frombuffer(data, dtype, count, pos).tolist())
        pos += 8 * count
    states, actions, sizes, nexts, rewards, terminals, counts = arrays
    if sum(sizes) != m or any(s < 1 for s in sizes):
        return None
    pairs, k = [], 0
    for s, a, size in zip(states, actions, sizes):
        outs = []
        for j in range(k, k + size):
            flag = bool(terminals[j]) if terminals[j] in (0, 1) else terminals[j]
            outs.append([nexts[j], rewards[j], flag, counts[j]])
        pairs.append([s, a, outs])
        k += size
    return {"pairs": pairs}


def _learn_and_reload(table: QTable, rng: random.Random, label: str) -> None:
    """A loaded model learns and saves a table that loads again (it never poisons it)."""
    cfg = LearnerConfig(algorithm="dyna", planning_steps=5)
    agent = DynaQ(table, cfg, np.random.default_rng(rng.randrange(1000)))
    agent.begin_episode(0, np.random.default_rng(1))
    for _ in range(20):
        s, s2 = rng.choice(STATES), rng.choice(STATES)
        agent.observe(s, rng.randrange(5), rng.choice([-0.5, 100.0, -1e15]), s2, False)
    QTable.from_bytes(table.to_bytes(), f"{label} (saved again)")


def test_fuzz_dyna_model_sections():
    """Both readers agree on every mutated model, and what they accept learns safely."""
    rng = rng_for("dyna")
    lay = LAYOUT
    accepted = 0
    for case in range(CASES):
        label = f"dyna case {case}"
        section = _mutate_section(bytes(_good_model(rng)), rng) if case else b""
        table = small_table()
        table.meta["algorithm"] = {"name": "dyna", "planning_steps": 5}
        table.sections[SECTION] = section
        data = table.to_bytes()
        ours: bool
        try:
            with limit(label):
                loaded = QTable.from_bytes(data, "t.qtable")
            ours = True
        except KoolioError as exc:
            one_line(exc, label, "t.qtable: ")
            ours = False
        except Exception as exc:
            pytest.fail(f"{label}: {type(exc).__name__}: {exc}")
        doc = _section_as_json(section) if section else None
        if doc is not None:  # the same content, as the robot keeps it
            try:
                rt.Model.from_json(doc, lay)
                theirs = True
            except rt.PolicyError:
                theirs = False
            assert theirs == ours, f"{label}: package {ours}, robot {theirs}: {doc}"
        if ours:
            accepted += 1
            _learn_and_reload(loaded, rng, label)
    assert accepted >= 1


# == policies in the robot runtime =============================================================
def _dyna_policy_doc(rng: random.Random) -> dict:
    doc = policy_document(small_table())
    doc["learner"].update(algorithm="dyna", planning_steps=3)
    model = rt.Model()
    for _ in range(4):
        model.record(rng.choice(STATES), rng.randrange(5), -0.5, rng.choice(STATES), False)
    doc["model"] = model.to_json()
    return json.loads(json.dumps(doc))


def test_fuzz_robot_runtime_policies(tmp_path):
    """A mutated policy loads or is one PolicyError; a loaded one learns, saves and loads
    again on the robot (no value it accepts poisons its next save)."""
    rng = rng_for("policy")
    base = _dyna_policy_doc(rng)
    path = tmp_path / "p.json"
    learned = 0
    for case in range(CASES):
        label = f"policy case {case}"
        doc = mutate_structure(base, rng) if case else base
        try:
            with limit(label):
                policy = rt.Policy(doc, str(path))
        except rt.PolicyError as exc:
            one_line(exc, label, f"{path}: ")
            continue
        except Exception as exc:
            pytest.fail(f"{label}: {type(exc).__name__}: {exc}")
        learned += 1
        says_what_it_holds(doc, policy, label)
        with limit(label):
            learner = rt.RobotLearner(policy, save_path=str(path), seed=case, goal="201")
            fields = policy.layout.levels
            learner.begin([rng.randrange(lv) for lv in fields])
            try:
                for _ in range(10):
                    action = learner.choose()
                    reward = rng.choice(list(policy.rewards.values()) or [0.0])
                    learner.step(action, reward, [rng.randrange(lv) for lv in fields], False)
            except rt.PolicyError as exc:  # e.g. no learner.gamma in the file: pass it
                one_line(exc, label)
                continue
            learner.end("goal")
            rt.Policy.load(str(path))  # the save loads again
    assert learned >= 1


# == training logs ================================================================================
TINY = "episode: {max_steps: 30}\n"
TRAIN = ["train", "--arena", "room", "--config", "tiny.yaml", "--quiet", "--episodes", "4"]
LOG_TOKENS = ["²", "١٢", "1_0", " 7", "nan", "inf", "-1", "\x00", '"', ",", "\n", "x" * 70_000]


@pytest.fixture(scope="module")
def trained(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("trained")
    (folder / "tiny.yaml").write_text(TINY)
    argv = [*TRAIN[:-1], "3", "--qtable", str(folder / "q.qtable"), "--log", str(folder / "q.csv")]
    argv[4] = str(folder / "tiny.yaml")
    assert cli.main(argv) == 0
    return folder


def _copy(trained: Path, folder: Path) -> None:
    for name in ("q.qtable", "q.qtable.bak", "q.csv", "tiny.yaml"):
        shutil.copy(trained / name, folder / name)


def _mutate_log(text: str, rng: random.Random) -> str:
    lines = text.split("\n")
    k = rng.randrange(1, len(lines))
    line = lines[k]
    i = rng.randrange(len(line) + 1)
    lines[k] = line[:i] + rng.choice(LOG_TOKENS) + line[i + rng.choice([0, 0, 1, 3]) :]
    out = "\n".join(lines)
    return out.rstrip("\n") if rng.random() < 0.4 else out  # torn last row, or not


def test_fuzz_training_logs(trained, tmp_path, monkeypatch, capsys):
    """train (which reconciles the log) and plot (which reads it) on a mutated log: exit 0
    with the table and the log in step and no row lost, or exit 2 with one line and
    nothing changed."""
    monkeypatch.chdir(tmp_path)
    rng = rng_for("logs")
    text = (trained / "q.csv").read_text()
    for case in range(max(4, CASES // 2)):
        label = f"log case {case}"
        _copy(trained, tmp_path)
        for p in tmp_path.glob("q.csv.*"):
            p.unlink()
        bad = _mutate_log(text, rng)
        (tmp_path / "q.csv").write_text(bad, encoding="utf-8")
        if case % 2:
            code = run_cli(capsys, ["plot", "--log", "q.csv", "--out", "c.png"], tmp_path, label)
            assert code == 2 or (tmp_path / "c.png").stat().st_size > 1000, label
            (tmp_path / "c.png").unlink(missing_ok=True)
            continue
        argv = [*TRAIN, "--qtable", "q.qtable", "--log", "q.csv"]
        if run_cli(capsys, argv, tmp_path, label) == 0:
            in_step(tmp_path, "q.qtable", "q.csv", label)
            kept = (tmp_path / "q.csv").read_text(encoding="utf-8").split("\n")
            removed = tmp_path / "q.csv.removed"
            moved = removed.read_text(encoding="utf-8").split("\n")[1:] if removed.exists() else []
            for line in bad.split("\n")[1:]:  # nothing lost
                assert not line or line in kept or line in moved, f"{label}: lost {line!r}"


# == lock and special files ======================================================================
def _plant(folder: Path, name: str, kind: str) -> None:
    """Put a ``kind`` of thing at ``folder / name`` (replacing what was there)."""
    p = folder / name
    if p.is_symlink() or p.exists():
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p)
        else:
            p.unlink()
    if kind == "fifo":
        os.mkfifo(p)
    elif kind == "folder":
        p.mkdir()
    elif kind == "link to table":
        p.symlink_to("q.qtable")
    elif kind == "dangling link":
        p.symlink_to("nowhere/at/all")
    elif kind == "link to /dev/zero":
        p.symlink_to("/dev/zero")
    elif kind == "hard link of table":
        table = folder / "q.qtable"
        if table.is_file() and not table.is_symlink():  # a planted table may be no file
            os.link(table, p)
    elif kind == "random bytes":
        p.write_bytes(bytes(random.Random(name).randrange(256) for _ in range(300)))
    elif kind == "empty":
        p.write_bytes(b"")
    elif kind == "note":
        p.write_text("#process 1 (koolio-pm train)\n")
    elif kind == "socket":
        sock = socket.socket(socket.AF_UNIX)
        with suppress(OSError):
            sock.bind(str(p.relative_to(Path.cwd())))
        sock.close()


PLACES = ["q.qtable.lock", "q.best.qtable", "q.qtable", "q.qtable.bak", "q.csv", "tiny.yaml"]
KINDS = [
    "fifo",
    "folder",
    "link to table",
    "dangling link",
    "link to /dev/zero",
    "hard link of table",
    "random bytes",
    "empty",
    "note",
    "socket",
]


def test_fuzz_lock_and_special_files(trained, tmp_path, monkeypatch, capsys):
    """Something odd at a lock file's or an input's name: train ends at once, in step, or
    with one line and nothing changed (a FIFO never blocks, a link is never written
    through)."""
    monkeypatch.chdir(tmp_path)
    rng = rng_for("special")
    for case in range(max(4, CASES // 2)):
        for p in list(tmp_path.iterdir()):
            if p.is_dir() and not p.is_symlink():
                shutil.rmtree(p)
            else:
                p.unlink()
        _copy(trained, tmp_path)
        planted = [(rng.choice(PLACES), rng.choice(KINDS)) for _ in range(rng.randint(1, 2))]
        for name, kind in planted:
            if name == "q.qtable" and kind in ("link to table", "hard link of table"):
                kind = "fifo"
            _plant(tmp_path, name, kind)
        label = f"special case {case}: {planted}"
        table = (tmp_path / "q.qtable").read_bytes() if (tmp_path / "q.qtable").is_file() else None
        argv = [*TRAIN, "--qtable", "q.qtable", "--log", "q.csv"]
        code = run_cli(capsys, argv, tmp_path, label)
        if code == 0:
            in_step(tmp_path, "q.qtable", "q.csv", label)
        elif table is not None and (tmp_path / "q.qtable").is_file():
            assert (tmp_path / "q.qtable").read_bytes() == table, label


# == command flags ================================================================================
COUNT_TOKENS = ["-1", "0", "1", "2", "1e3", "nan", "١", "1_0", "", "abc", "0x10", "+1", " 2"]
COUNT_TOKENS += [str(10**9 + 1), "9" * 25, "9" * 5000]
SEED_TOKENS = ["-1", "0", "7", str(2**63 - 1), str(2**63), "9" * 400, "١", "1.5", "", "-0"]
FLOAT_TOKENS = ["nan", "inf", "-inf", "-0.1", "0", "0.5", "1", "1.0000001", "1e-320", "x"]
#: command -> (base argv, {flag: tokens}); every base runs in a second or two, and a
#: valid token keeps it short.
FLAGS: dict[str, tuple[list[str], dict[str, list[str]]]] = {
    "train": (
        [*TRAIN[:-1], "0", "--qtable", "n.qtable", "--log", "n.csv"],
        {"--seed": SEED_TOKENS, "--episodes": COUNT_TOKENS, "--robots": COUNT_TOKENS},
    ),
    "eval": (
        ["eval", "--arena", "room", "--config", "tiny.yaml", "--qtable", "q.qtable"],
        {"--seed": SEED_TOKENS, "--episodes": COUNT_TOKENS},
    ),
    "plot": (["plot", "--log", "q.csv", "--out", "c.png"], {"--window": COUNT_TOKENS}),
    "export": (
        ["export", "--qtable", "q.qtable", "--out", "p.json"],
        {"--episode": SEED_TOKENS + COUNT_TOKENS},
    ),
    "sweep": (["sweep", "s.yaml", "--dry-run"], {"--workers": COUNT_TOKENS}),
    "transfer": (  # --out is not empty: every valid value ends in that one line
        ["transfer", "--arena", "room", "--out", "full"],
        {
            "--seed": SEED_TOKENS,
            "--episodes": COUNT_TOKENS,
            "--robot-episodes": COUNT_TOKENS,
            "--eval-episodes": COUNT_TOKENS,
            "--eval-every": COUNT_TOKENS,
            "--target": FLOAT_TOKENS,
            "--robot-alpha": FLOAT_TOKENS,
            "--robot-epsilon": FLOAT_TOKENS,
        },
    ),
    "view": (
        ["view", "--arena", "room", "--config", "tiny.yaml", "--greedy", "--qtable", "q.qtable"],
        {"--seed": SEED_TOKENS, "--steps": COUNT_TOKENS, "--episodes": COUNT_TOKENS},
    ),
}


def _flag_case(rng: random.Random) -> list[str]:
    command = rng.choice(sorted(FLAGS))
    base, flags = FLAGS[command]
    argv = list(base)
    for flag in rng.sample(sorted(flags), k=min(len(flags), rng.randint(1, 2))):
        argv += [flag, rng.choice(flags[flag])]
    if command == "view" and "--steps" not in argv:
        argv += ["--steps", "3"]
    return argv


def test_fuzz_command_flags(trained, tmp_path, monkeypatch, capsys):
    """Random values for every number flag of every command, in this process."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    _copy(trained, tmp_path)
    (tmp_path / "s.yaml").write_text("episodes: 5\n")
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "keep.txt").write_text("an earlier experiment\n")
    rng = rng_for("flags")
    for case in range(CASES):
        argv = _flag_case(rng)
        label = f"flags case {case}: {argv}"
        code = run_cli(capsys, argv, tmp_path, label)
        if code == 0:
            for p in ("n.qtable", "n.qtable.bak", "n.csv", "c.png", "p.json"):
                (tmp_path / p).unlink(missing_ok=True)


def test_fuzz_command_flags_in_real_processes(trained, tmp_path):
    """A few of the same cases as real processes, with a timeout: exit 0 or 2, one line,
    no traceback."""
    _copy(trained, tmp_path)
    (tmp_path / "s.yaml").write_text("episodes: 5\n")
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "keep.txt").write_text("an earlier experiment\n")
    rng = rng_for("flags-process")
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "PYTHONPATH": str(ROOT)}
    for case in range(max(2, CASES // 20)):
        argv = _flag_case(rng)
        if argv[0] == "view" and "--episodes" not in argv:  # a valid --steps 1000000001
            argv += ["--episodes", "1"]  # watches for hours: one episode (or the case's own)
        label = f"process case {case}: {argv}"
        p = subprocess.run(
            [sys.executable, "-m", "koolio_pymunk", *argv],
            cwd=tmp_path,
            env=env,
            capture_output=True,
            text=True,
            timeout=TIME_LIMIT * 2,
        )
        assert p.returncode in (0, 2) and "Traceback" not in p.stderr, f"{label}: {p.stderr}"
        if p.returncode == 2:
            assert len(p.stderr.strip().splitlines()) == 1, f"{label}: {p.stderr}"


def test_the_fuzzers_are_seeded():
    a, b = (_flag_case(random.Random("x")) for _ in range(2))
    assert a == b
    assert _mutate_log("a,b\n1,2\n", random.Random(3)) == _mutate_log(
        "a,b\n1,2\n", random.Random(3)
    )
