"""Packaging: entry points, version, typing marker, licence, and light imports (numba only
where a compiled kernel is needed)."""

from __future__ import annotations

import importlib.metadata
import subprocess
import sys
from pathlib import Path

import pytest

import koolio_pymunk

REPO = Path(__file__).resolve().parents[1]


def run_python(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, *args], capture_output=True, text=True, cwd=cwd, timeout=300
    )


def test_python_dash_m_and_version() -> None:
    p = run_python("-m", "koolio_pymunk", "--version")
    assert p.returncode == 0, p.stderr
    assert p.stdout == f"koolio-pm {koolio_pymunk.__version__}\n"
    assert importlib.metadata.version("koolio-pymunk") == koolio_pymunk.__version__
    p = run_python("-m", "koolio_pymunk", "--help")
    assert p.returncode == 0 and "usage: koolio-pm" in p.stdout
    for command in ("train", "eval", "view", "plot", "export", "sweep", "edit"):
        assert command in p.stdout


def test_package_metadata_files() -> None:
    meta = importlib.metadata.metadata("koolio-pymunk")
    assert meta["License-Expression"] == "MIT"
    assert "Typing :: Typed" in meta.get_all("Classifier")
    assert (REPO / "LICENSE").read_text().startswith("MIT License\n")
    assert (REPO / "koolio_pymunk" / "py.typed").exists()
    scripts = importlib.metadata.entry_points(group="console_scripts", name="koolio-pm")
    assert [e.value for e in scripts] == ["koolio_pymunk.apps.cli:main"]


LOADS_NUMBA = "import sys; print('numba' in sys.modules, 'pygame' in sys.modules)"


@pytest.mark.parametrize(
    "command",
    [
        ["--help"],
        ["info", "--qtable", "q.qtable"],
        ["check-arena", "hallway"],
        ["export", "--qtable", "q.qtable", "--out", "policy.json"],
        ["plot", "--log", "log.csv", "--out", "curve.png"],
    ],
)
def test_commands_without_sensing_do_not_load_numba(command: list[str], tiny_run: Path) -> None:
    code = (
        "import contextlib, io\nfrom koolio_pymunk.apps.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n"
        f"        rc = main({command!r})\n"
        "    except SystemExit as exc:\n"
        "        rc = exc.code\n"
        f"print(rc)\n{LOADS_NUMBA}"
    )
    p = run_python("-c", code, cwd=tiny_run)
    assert p.stdout.split() == ["0", "False", "False"], p.stderr


def test_import_is_light_and_the_env_loads_the_kernels() -> None:
    p = run_python("-c", f"import koolio_pymunk\n{LOADS_NUMBA}")
    assert p.stdout.split() == ["False", "False"], p.stderr
    code = "import koolio_pymunk\nkoolio_pymunk.KoolioEnv('room').reset(seed=0)\n" + LOADS_NUMBA
    p = run_python("-c", code)
    assert p.stdout.split() == ["True", "False"], p.stderr  # the check above can fail
