"""A base install (no ``[view]`` extra): each drawing entry point names the extra to install.

The tests run the real commands in a subprocess whose import system cannot find
pygame, pygame-gui or matplotlib (a finder first in ``sys.meta_path`` raises
``ModuleNotFoundError`` for them, as an interpreter without them does), so no second
environment is needed. A regression (a raw ``ModuleNotFoundError``, a traceback, another
exit status, a sweep that fails after its runs) fails them.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from koolio_pymunk.store.extras import VIEW_INSTALL, missing_extra

#: Installed first in the subprocess: the [view] extra's modules are "not installed".
WITHOUT_VIEW = textwrap.dedent(
    """
    import importlib.abc, sys

    class _NotInstalled(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name.partition(".")[0] in ("pygame", "pygame_gui", "matplotlib"):
                raise ModuleNotFoundError(f"No module named {name!r}", name=name)
            return None

    sys.meta_path.insert(0, _NotInstalled())
    """
)


def without_view(code: str, cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    return subprocess.run(
        [sys.executable, "-c", WITHOUT_VIEW + textwrap.dedent(code)],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=env,
        timeout=300,
    )


def koolio_pm_without_view(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    return without_view(f"from koolio_pymunk.apps.cli import main; sys.exit(main({args!r}))", cwd)


def test_the_subprocess_really_lacks_the_extra(tmp_path: Path) -> None:
    p = without_view("import pygame", tmp_path)
    assert p.returncode == 1 and "ModuleNotFoundError: No module named 'pygame'" in p.stderr


@pytest.mark.parametrize(
    ("command", "needs"),
    [
        (["view", "--arena", "room", "--steps", "5", "--screenshot", "out.png"], "pygame-ce"),
        (["plot", "--log", "LOG", "--out", "out.png"], "matplotlib"),
        (["edit", "room", "--screenshot", "out.png"], "pygame-ce"),
    ],
)
def test_drawing_commands_name_the_extra_and_exit_2(
    command: list[str], needs: str, tiny_run: Path, tmp_path: Path
) -> None:
    args = [str(tiny_run / "log.csv") if a == "LOG" else a for a in command]
    p = koolio_pm_without_view(args, tmp_path)
    assert p.returncode == 2, p.stderr
    assert p.stderr == f"koolio-pm: error: {command[0]}: {needs} is not installed: {VIEW_INSTALL}\n"
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_sweep_runs_and_skips_its_plot_with_a_note(tmp_path: Path) -> None:
    spec = tmp_path / "tiny.yaml"
    spec.write_text(
        "name: tiny\nepisodes: 2\nseeds: [0]\nbase: {episode: {max_steps: 30}}\n"
        "arena: room\neval_every: 2\neval_episodes: 1\n"
    )
    out = tmp_path / "out"
    p = koolio_pm_without_view(["sweep", str(spec), "--workers", "1", "--out", str(out)], tmp_path)
    assert p.returncode == 0, p.stderr
    assert "Traceback" not in p.stderr
    note = (
        f"note: sweep: curves.png: matplotlib is not installed: {VIEW_INSTALL}; curves.png skipped"
    )
    assert note in p.stdout.splitlines()
    assert (out / "results.csv").exists() and not (out / "curves.png").exists()


def test_env_render_and_check_env_follow_gymnasiums_convention(tmp_path: Path) -> None:
    """``DependencyNotInstalled`` naming the extra, as Gymnasium's own envs do."""
    p = without_view(
        """
        import gymnasium as gym
        from gymnasium.error import DependencyNotInstalled
        from gymnasium.utils.env_checker import check_env
        import koolio_pymunk

        env = gym.make("koolio_pymunk/Hallway-v0", render_mode="rgb_array")
        env.reset(seed=0)
        try:
            env.render()
        except DependencyNotInstalled as exc:
            print("render:", exc)
        check_env(gym.make("koolio_pymunk/Hallway-v0").unwrapped, skip_render_check=True)
        print("check_env without rendering: ok")
        try:
            check_env(gym.make("koolio_pymunk/Hallway-v0").unwrapped)
        except DependencyNotInstalled as exc:
            print("check_env:", exc)
        """,
        tmp_path,
    )
    assert p.returncode == 0, p.stderr
    message = f"render: pygame-ce is not installed: {VIEW_INSTALL}"
    assert p.stdout.splitlines() == [
        f"render: {message}",
        "check_env without rendering: ok",
        f"check_env: {message}",
    ]


def test_only_the_extras_own_modules_count() -> None:
    def exc(name: str) -> ModuleNotFoundError:
        return ModuleNotFoundError(f"No module named {name!r}", name=name)

    assert str(missing_extra(exc("pygame_gui"), "view")) == (
        f"view: pygame-gui is not installed: {VIEW_INSTALL}"
    )
    assert missing_extra(exc("yaml"), "view") is None  # a core dependency: a real bug
    assert missing_extra(exc("matplotlib.backends.x"), "plot") is None  # broken install
    assert missing_extra(ImportError("cannot import name 'x'"), "plot") is None
