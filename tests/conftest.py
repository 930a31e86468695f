"""Fixtures shared by several test files."""

from __future__ import annotations

import signal
import sys
from pathlib import Path

import pytest

from koolio_pymunk.apps import cli

# The agreement modules of the compiled twins (``tools/sensing_agreement.py``,
# ``tools/move_agreement.py``) serve the tests and the tools, and live with the tools:
# the tests import them as the tools do, from ``tools/``.
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))

# Ctrl-C is part of what the tests check. A shell without job control starts a
# background job with SIGINT ignored, and an ignored signal stays ignored in every
# process it starts: give this one Python's own handler, which the commands the tests
# run inherit as the default (a handler, unlike an ignore, is reset by exec).
signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.fixture(scope="session")
def tiny_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder holding ``q.qtable`` and ``log.csv`` of a 2-episode training run in the
    room (30-step cap), for the commands that read a table or a log."""
    folder = tmp_path_factory.mktemp("tiny_run")
    (folder / "tiny.yaml").write_text("episode: {max_steps: 30}\n")
    args = ["train", "--arena", "room", "--episodes", "2", "--quiet", "--config"]
    args += [str(folder / "tiny.yaml"), "--qtable", str(folder / "q.qtable")]
    assert cli.main([*args, "--log", str(folder / "log.csv")]) == 0
    return folder


@pytest.fixture
def here(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty working folder with a tiny configuration (30-step episodes), the current
    folder (a test module may define its own ``here``)."""
    (tmp_path / "tiny.yaml").write_text("episode: {max_steps: 30}\n")
    monkeypatch.chdir(tmp_path)
    return tmp_path
