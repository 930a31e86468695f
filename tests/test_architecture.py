"""The floors of the package: the import contracts hold, and the map of them is complete."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PACKAGE = REPO / "koolio_pymunk"
FLOORS = ("store", "world", "sensing", "task", "learning", "apps")


def test_import_contracts_hold() -> None:
    """``lint-imports`` (the contracts in pyproject.toml) passes: floors only import
    downwards, no circles, ``robot_runtime.py`` imports nothing but the standard library."""
    exe = Path(sys.executable).with_name("lint-imports")
    assert exe.exists(), "import-linter is part of the [dev] extra: pip install -e '.[dev]'"
    done = subprocess.run([str(exe)], cwd=REPO, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert "3 kept, 0 broken" in done.stdout


def test_every_module_is_on_the_map() -> None:
    """docs/architecture.md names every module of every floor (and no floor is missing)."""
    text = (REPO / "docs" / "architecture.md").read_text()
    folders = sorted(p.name for p in PACKAGE.iterdir() if (p / "__init__.py").exists())
    assert folders == sorted(FLOORS)
    for floor in FLOORS:
        for module in sorted((PACKAGE / floor).glob("*.py")):
            if module.name != "__init__.py":
                assert f"`{module.name}`" in text, f"{floor}/{module.name} is not in the map"
