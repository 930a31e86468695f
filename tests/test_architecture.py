"""The floors of the package: the import contracts hold, and the map of them is complete."""

from __future__ import annotations

import re
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


def floor_row(text: str, floor: str) -> str:
    """The row of ``floor`` in docs/architecture.md's table of floors."""
    rows = [line for line in text.splitlines() if line.startswith(f"| `{floor}/` |")]
    assert len(rows) == 1, f"{floor}/ has {len(rows)} rows in the table of floors"
    return rows[0]


def test_every_module_is_on_the_map() -> None:
    """docs/architecture.md's table of floors names every module in its floor's row, those
    of the floor's folders too (``viewer/app.py``), and names no module that is not there;
    no floor is missing. (Once only each floor's top level was looked at, anywhere in the
    text: the 15 modules of the viewer and the editor were on no map.)"""
    text = (REPO / "docs" / "architecture.md").read_text()
    folders = sorted(p.name for p in PACKAGE.iterdir() if (p / "__init__.py").exists())
    assert folders == sorted(FLOORS)
    for floor in FLOORS:
        row = floor_row(text, floor)
        modules = {
            p.relative_to(PACKAGE / floor).as_posix()
            for p in (PACKAGE / floor).rglob("*.py")
            if p.name != "__init__.py"
        }
        assert len(modules) > 3
        unmapped = sorted(m for m in modules if f"`{m}`" not in row)
        assert unmapped == [], f"{floor}/: not in its row of the map: {unmapped}"
        named = set(re.findall(r"`([\w/]+\.py)`", row))
        gone = sorted(named - modules)
        assert gone == [], f"{floor}/: its row names modules that do not exist: {gone}"
    apart = sorted(p.name for p in PACKAGE.glob("*.py") if not p.name.startswith("__"))
    assert apart == ["_version.py", "robot_runtime.py"]
    assert "`robot_runtime.py` stands apart" in text and "`_version.py` holds" in text
