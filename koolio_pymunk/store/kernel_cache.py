"""numba's on-disk cache of the compiled kernels, kept in step with their sources.

numba stores a compiled ``cache=True`` function in the ``__pycache__`` folder beside its
module and reuses it while that module's file keeps its time stamp and size. It does not
look at the functions the kernel inlines or calls from other files: the step engine
compiles the ray, encoding and realism kernels into itself (``sensing/inline_twins.py``),
so after a change to ``realism_kernel.py`` alone (a ``git pull``, an edit) it would load
its old machine code and compute the old readings.

:func:`refresh` guards against that: it hashes the source of every module of the package
that uses numba and, when the hash is not the one stored beside the cache
(``__pycache__/kernels.sha256`` at the package's top), deletes the package's cached
kernels (``*.nbi``, ``*.nbc``), so numba compiles them again (about a minute on 2 cores, once).
Every kernel module calls it at import, before any kernel runs; it does its work once
per process. A package folder it cannot write (an installed, read-only package: its
files change only by a reinstall, which gives every file a new stamp) is left alone.

>>> import tempfile, pathlib
>>> root = pathlib.Path(tempfile.mkdtemp())
>>> _ = (root / "k.py").write_text("import numba\\n")
>>> (root / "__pycache__").mkdir()
>>> _ = (root / "__pycache__" / "k.f-1.py311.nbi").write_bytes(b"old")
>>> refresh(root), refresh(root)     # stale (no hash yet): cleared; then up to date
(True, False)
>>> _ = (root / "k.py").write_text("import numba  # changed\\n")
>>> refresh(root)
True
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

#: The package's top folder.
PACKAGE = Path(__file__).resolve().parent.parent
#: Where the hash of the kernels' sources is kept, under the package's top.
STAMP = Path("__pycache__") / "kernels.sha256"
#: The cached kernels' file suffixes (numba's index and data files).
CACHED = ("*.nbi", "*.nbc")

_done = False


def sources_hash(root: Path) -> str:
    """SHA-256 over the path and text of every ``.py`` file under ``root`` that mentions
    numba (the kernels and the modules they inline), in path order."""
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        text = path.read_bytes()
        if b"numba" in text:
            digest.update(path.relative_to(root).as_posix().encode() + b"\0" + text + b"\0")
    return digest.hexdigest()


def refresh(root: Path) -> bool:
    """Delete the cached kernels under ``root`` when its kernel sources changed since the
    last call (see the module doc); True when it deleted them."""
    stamp = root / STAMP
    now = sources_hash(root)
    try:
        if stamp.read_text() == now:
            return False
    except OSError:
        pass  # no stamp yet: caches of an older version may be there
    temporary = stamp.with_name(f"{stamp.name}.{os.getpid()}.tmp")
    try:
        stamp.parent.mkdir(exist_ok=True)
        temporary.write_text(now)
    except OSError:
        return False  # a read-only package: numba keeps its cache elsewhere
    try:
        for pattern in CACHED:
            for path in root.rglob(f"__pycache__/{pattern}"):
                path.unlink(missing_ok=True)
        os.replace(temporary, stamp)
    finally:
        temporary.unlink(missing_ok=True)
    return True


def ensure_fresh() -> None:
    """:func:`refresh` of this package, once per process (the kernel modules call it)."""
    global _done
    if not _done:
        _done = True
        refresh(PACKAGE)
