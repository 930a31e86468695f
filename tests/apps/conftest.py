"""Fixtures of the command tests."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture
def here(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty working folder with a tiny configuration (30-step episodes)."""
    (tmp_path / "tiny.yaml").write_text("episode: {max_steps: 30}\n")
    monkeypatch.chdir(tmp_path)
    return tmp_path
