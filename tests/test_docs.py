"""Every command in the documentation runs: README.md and docs/*.md, with tiny budgets.

The commands are the lines of the shell code blocks (```` ```bash ````, ```` ```sh ```` or
no language) of each page, comments removed, ``A && B`` split into its parts. Each page
runs in a fresh working folder that holds copies of ``arenas/`` and ``examples/`` and
``docs/images/`` (so nothing in the checkout is written) and links to ``koolio_pymunk/``
and ``tools/``; a page's commands run in order, as a reader would type them, so a later
command finds the files an earlier one wrote. How each kind of command is run:

* ``koolio-pm ...`` (also ``.venv/bin/koolio-pm``, with ``VAR=value`` prefixes): the real
  ``koolio_pymunk.apps.cli.main`` with the budget cut: ``train`` 2 episodes (``--eval-every``
  1 with 1-episode checks), ``eval`` 1,
  ``transfer`` 2 training and 2 robot episodes with a 1-episode check after each,
  ``view`` 3 steps or 1 episode with screenshots every step, ``sweep`` on a copy of its
  spec cut to 1 configuration x 1 seed x 2 episodes (the documented spec itself is read
  by ``--dry-run``), each sweep into a fresh output folder so that none merely resumes;
  ``--ray`` and ``--ray auto`` use one Ray instance the test starts; ``edit`` and
  ``tools/arena_editor.py`` get ``--screenshot`` so the window closes; a synopsis's
  ``[--flag VALUE]`` runs with the flag;
* ``python tools/X.py``: the script itself (``view_bench.py``: 2 episodes, 1 repeat;
  ``learning_targets.py``: seed 0 and a budget of 5 episodes); a ``nice`` prefix is dropped;
  ``python examples/tabular_q.py``: the example with 2 training and 2 greedy episodes;
* ``koolio-pm edit``, ``tools/arena_editor.py`` and ``python .../robot_runtime.py``: a
  separate interpreter (``-I`` for the runtime: as on the robot); ``scp FILES
  robot:DIR/`` copies them into the folder ``robot/DIR`` where the robot's commands run;
* ``python3 -m venv``, ``pip install``: the set-up, run from nothing by ``.ci/run``;
  ``source .venv/bin/activate``: this test's interpreter is the venv's already;
  ``python -m pytest``: this test run itself.

Inputs that no documented command makes are supplied: the editor script the docs show
(``s.txt``, ``lab.txt``), and training logs in the format the robot runtime writes too
(``robot.csv``, ``a.csv``, ``b.csv``). A command the test does not know how to run fails
the test: a new documented command needs a rule here.

The ```` ```python ```` blocks of the pages in :data:`PYTHON_PAGES` are whole programs:
they run in order, in one namespace, in the page's fresh folder. Other pages' Python
blocks are fragments (the robot's loop, a learner's calls) and are not run.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import runpy
import shlex
import shutil
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import yaml

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

from koolio_pymunk.apps import cli

REPO = Path(__file__).resolve().parents[1]
PAGES = ["README.md", *sorted(f"docs/{p.name}" for p in (REPO / "docs").glob("*.md"))]
SHELL_LANGUAGES = ("bash", "sh", "")
#: Pages whose ```python blocks run (module doc).
PYTHON_PAGES = ("docs/envs.md",)
SETUP = "set-up (.ci/run runs it from nothing)"


def shell_blocks(text: str, languages: tuple[str, ...] = SHELL_LANGUAGES) -> list[str]:
    """The bodies of the ```` ```bash ````, ```` ```sh ```` and untagged code blocks (or of
    the blocks of ``languages``)."""
    blocks, body, language = [], [], None
    for line in text.splitlines():
        if line.startswith("```"):
            if language is None:
                language, body = line[3:].strip(), []
            else:
                if language in languages:
                    blocks.append("\n".join(body))
                language = None
        elif language is not None:
            body.append(line)
    return blocks


def documented_commands(page: str) -> list[list[str]]:
    """The commands of ``page``'s shell blocks: argument lists, ``&&`` chains split, lines
    ending in a backslash joined to the next (as the shell does)."""
    out = []
    for block in shell_blocks((REPO / page).read_text()):
        for line in block.replace("\\\n", " ").splitlines():
            words = shlex.split(line, comments=True)
            while words:
                part = words[: words.index("&&")] if "&&" in words else words
                out.append(part)
                words = words[len(part) + 1 :]
    return out


def _editor_script() -> str:
    """The scripted session docs/editor.md shows (``new lab`` ... ``screenshot lab.png``)."""
    text = (REPO / "docs" / "editor.md").read_text()
    start = text.index("new lab\n")
    return text[start : text.index("```", start)]


#: What ``tools/learning_targets.py`` gets in the docs test: a seed and a few episodes.
LEARNING_TARGETS_BUDGET = (
    ("--seeds", "0"),
    ("--workers", "1"),
    ("--every", "5"),
    ("--max-episodes", "5"),
    ("--paper-episodes", "5"),
    ("--paper-every", "5"),
    ("--random-episodes", "5"),
    ("--random-every", "5"),
    ("--random-check-episodes", "2"),
    ("--fresh-episodes", "2"),
)


def _set(args: list[str], flag: str, value: str) -> list[str]:
    """``args`` with ``flag value`` replaced, or appended."""
    if flag in args:
        i = args.index(flag)
        return [*args[: i + 1], value, *args[i + 2 :]]
    return [*args, flag, value]


def _fill_synopsis(args: list[str]) -> list[str]:
    """``[--window 50]`` -> ``--window 50``."""
    return [a.strip("[]") for a in args]


class Reader:
    """Runs one page's commands in ``folder``, in order."""

    def __init__(self, folder: Path, ray: Callable[[], None] = lambda: None) -> None:
        self.folder = folder
        self.robot: Path | None = None
        self.sweeps = 0
        self.start_ray = ray

    def run(self, words: list[str]) -> str:
        env = {}
        while words and re.fullmatch(r"[A-Z_]+=\S*", words[0]):
            key, _, value = words.pop(0).partition("=")
            env[key] = value
        assert env in ({}, {"SDL_VIDEODRIVER": "dummy"}), env
        if words[:1] == ["nice"]:
            words = words[1:]
        program, args = words[0], words[1:]
        if program.endswith("koolio-pm"):
            return self.koolio_pm(_fill_synopsis(args))
        if program.endswith(("python", "python3")):
            return self.python(args)
        if program.endswith("pip") and args[:1] == ["install"]:
            return SETUP
        if program in ("source", ".") and args == [".venv/bin/activate"]:
            return SETUP
        if program == "scp":
            *files, target = args
            self.robot = self.folder / "robot" / target.split(":", 1)[1]
            self.robot.mkdir(parents=True, exist_ok=True)
            for f in files:
                shutil.copy(self.folder / f, self.robot)
            return "copied"
        raise AssertionError(f"no rule to run {words!r}")

    def koolio_pm(self, args: list[str]) -> str:
        command = args[0]
        if command == "train":
            args = _set(args, "--episodes", "2")
            if "--eval-every" in args:  # a check after each episode, of one episode
                args = _set(_set(args, "--eval-every", "1"), "--eval-episodes", "1")
        elif command == "eval":
            args = _set(args, "--episodes", "1")
        elif command == "view":
            args = (
                _set(args, "--episodes", "1")
                if "--episodes" in args
                else _set(args, "--steps", "3")
            )
            if "--screenshot-every" in args:
                i = args.index("--screenshot-every")
                args[i + 1] = "1"
        elif command == "sweep":
            args = self.sweep_args(args)
        elif command == "edit":
            return self.subprocess(["-m", "koolio_pymunk", *self.editor_args(args)])
        elif command == "plot":
            self.supply_logs(args)
        elif command == "transfer":
            for flag, value in (("--episodes", "2"), ("--robot-episodes", "2")):
                args = _set(args, flag, value)
            args = _set(_set(args, "--eval-episodes", "1"), "--eval-every", "1")
        try:
            status = cli.main(args)
        except SystemExit as exc:  # argparse refused the command line
            status = exc.code
        assert status == 0, args
        return "ran"

    def sweep_args(self, args: list[str]) -> list[str]:
        if "--dry-run" in args:
            return args
        spec = yaml.safe_load((REPO / args[1]).read_text())
        spec.update(episodes=2, seeds=[0], eval_every=2, eval_episodes=1)
        spec["grid"] = {k: v[:1] for k, v in spec.get("grid", {}).items()}
        spec["runs"] = spec.get("runs", [])[:1]
        cut = self.folder / args[1]
        cut.write_text(yaml.safe_dump(spec))
        self.sweeps += 1
        if "--ray" in args:
            self.start_ray()
        return [*args, "--out", f"sweep{self.sweeps}"]

    def editor_args(self, args: list[str]) -> list[str]:
        if "--script" in args:
            name = args[args.index("--script") + 1]
            script = self.folder / name
            script.parent.mkdir(parents=True, exist_ok=True)
            shipped = REPO / name  # a script the repository ships runs as it is
            script.write_text(shipped.read_text() if shipped.exists() else _editor_script())
        if "--screenshot" not in args:
            args = [*args, "--screenshot", "editor.png"]
        return args

    def supply_logs(self, args: list[str]) -> None:
        """Logs that come from elsewhere (the robot, other runs): a 2-episode train log for
        each log named by ``--log`` or positionally that no earlier command wrote."""
        named = [args[i + 1] for i, a in enumerate(args[:-1]) if a == "--log"]
        named += [
            a for i, a in enumerate(args[1:], 1) if a.endswith(".csv") and args[i - 1] != "--out"
        ]
        for k, name in enumerate(dict.fromkeys(named)):
            log = self.folder / name
            if not log.exists():
                log.parent.mkdir(parents=True, exist_ok=True)
                table = f"supply{k}.qtable"
                with contextlib.redirect_stdout(io.StringIO()):
                    train = ["train", "--arena", "room", "--episodes", "2", "--quiet"]
                    assert cli.main([*train, "--qtable", table, "--log", str(log)]) == 0

    def python(self, args: list[str]) -> str:
        if args[:2] == ["-m", "venv"]:
            return SETUP
        if args[:2] == ["-m", "pytest"]:
            return "this test run"
        script = args[0]
        if script == "tools/arena_editor.py":
            return self.subprocess([script, *self.editor_args(["edit", *args[1:]])[1:]])
        if script == "tools/view_bench.py":
            args = _set(_set(args, "--episodes", "2"), "--repeat", "1")
            return self.script(REPO / script, args[1:])
        if script == "examples/tabular_q.py":  # a budget of a few episodes
            args = _set(_set(args, "--episodes", "2"), "--eval-episodes", "2")
            return self.script(REPO / script, args[1:])
        if script == "tools/learning_targets.py":  # one seed, a budget of a few episodes
            for flag, value in LEARNING_TARGETS_BUDGET:
                args = _set(args, flag, value)
            return self.script(REPO / script, args[1:])
        if script.endswith("robot_runtime.py"):
            where = self.robot if script == "robot_runtime.py" else self.folder
            assert where is not None, "robot_runtime.py runs where scp put it"
            return self.subprocess(["-I", script, *args[1:]], cwd=where)
        raise AssertionError(f"no rule to run python {args!r}")

    def subprocess(self, args: list[str], cwd: Path | None = None) -> str:
        """A separate interpreter (the editor quits pygame at its end, as a program
        should; the robot runtime needs nothing but the standard library)."""
        p = subprocess.run(
            [sys.executable, *args],
            cwd=cwd or self.folder,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert p.returncode == 0, (args, p.stderr)
        return "ran"

    def script(self, path: Path, args: list[str]) -> str:
        saved = sys.argv
        sys.argv = [str(path), *args]
        try:
            runpy.run_path(str(path), run_name="__main__")
        except SystemExit as exc:
            assert exc.code in (0, None), (path, args, exc.code)
        finally:
            sys.argv = saved
        return "ran"


@contextlib.contextmanager
def reader_in(folder: Path, ray: Callable[[], None] = lambda: None) -> Iterator[Reader]:
    for name in ("arenas", "examples"):
        shutil.copytree(REPO / name, folder / name)
    (folder / "docs" / "images").mkdir(parents=True)
    for name in ("koolio_pymunk", "tools"):
        (folder / name).symlink_to(REPO / name)
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        yield Reader(folder, ray)
    finally:
        os.chdir(cwd)


@pytest.fixture(scope="module")
def ray_instance() -> Iterator[Callable[[], None]]:
    """Starts one local Ray instance, on first use, for every page's ``--ray`` sweeps."""
    import ray

    def start() -> None:
        if not ray.is_initialized():
            ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)

    yield start
    ray.shutdown()


@pytest.mark.parametrize("page", [p for p in PAGES if documented_commands(p)])
def test_every_documented_command_runs(
    page: str, tmp_path: Path, ray_instance: Callable[[], None]
) -> None:
    commands = documented_commands(page)
    with reader_in(tmp_path, ray_instance) as reader, contextlib.redirect_stdout(io.StringIO()):
        done = [reader.run(list(words)) for words in commands]
    assert len(done) == len(commands)


def run_python_blocks(text: str, name: str, folder: Path) -> str:
    """Run the ```` ```python ```` blocks of ``text`` in order, in one namespace, in a fresh
    page folder under ``folder``; returns what they printed."""
    blocks = shell_blocks(text, ("python",))
    assert blocks, f"{name}: no python block"
    namespace: dict = {"__name__": "__main__"}
    with reader_in(folder), contextlib.redirect_stdout(io.StringIO()) as out:
        for block in blocks:
            exec(compile(block, f"{name} (python block)", "exec"), namespace)
    return out.getvalue()


@pytest.mark.parametrize("page", PYTHON_PAGES)
def test_every_python_block_of_a_program_page_runs(page: str, tmp_path: Path) -> None:
    assert run_python_blocks((REPO / page).read_text(), page, tmp_path)  # it printed


def test_a_python_block_that_fails_fails_the_page(tmp_path: Path) -> None:
    page = "text\n```python\nx = 1\n```\n```bash\nexit 1\n```\n```python\nassert x == 2\n```\n"
    with pytest.raises(AssertionError):
        run_python_blocks(page, "page", tmp_path / "a")
    assert run_python_blocks(page.replace("x == 2", "x == 1"), "page", tmp_path / "b") == ""
    with pytest.raises(AssertionError, match="no python block"):
        run_python_blocks("```bash\ntrue\n```\n", "page", tmp_path / "c")


def test_the_pages_have_commands_and_the_parser_finds_them() -> None:
    """The extraction itself: a page with commands yields them, split and uncommented."""
    handoff = documented_commands("docs/handoff.md")
    assert ["koolio-pm", "plot", "--log", "robot.csv", "--out", "robot.png"] in handoff
    readme = documented_commands("README.md")
    assert readme[:4] == [
        ["python3", "-m", "venv", ".venv"],
        [".venv/bin/pip", "install", "-e", "."],
        [".venv/bin/koolio-pm", "train"],
        [".venv/bin/koolio-pm", "eval"],
    ]
    assert sum(len(documented_commands(p)) for p in PAGES) >= 40


def test_an_unknown_command_fails(tmp_path: Path) -> None:
    with pytest.raises(AssertionError, match="no rule"):
        Reader(tmp_path).run(["make", "install"])
    quiet = contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO())
    with reader_in(tmp_path) as reader, quiet[0], quiet[1], pytest.raises(AssertionError):
        reader.run(["koolio-pm", "eval", "--qtable", "never-trained.qtable"])  # a broken line
