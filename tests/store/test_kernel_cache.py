"""numba's cache is cleared when a kernel's source changes, and only then."""

from __future__ import annotations

from koolio_pymunk.store.kernel_cache import PACKAGE, STAMP, refresh, sources_hash


def _package(tmp_path):
    (tmp_path / "kernel.py").write_text("import numba\n")
    (tmp_path / "plain.py").write_text("x = 1\n")
    cache = tmp_path / "sub" / "__pycache__"
    cache.mkdir(parents=True)
    for name in ("kernel.f-3.py311.nbi", "kernel.f-3.py311.1.nbc", "plain.cpython-311.pyc"):
        (cache / name).write_bytes(b"compiled")
    return cache


def test_a_changed_kernel_clears_the_cached_kernels_only(tmp_path) -> None:
    cache = _package(tmp_path)
    assert refresh(tmp_path)  # no stamp yet
    assert sorted(p.name for p in cache.iterdir()) == ["plain.cpython-311.pyc"]
    (cache / "kernel.f-3.py311.nbi").write_bytes(b"compiled again")
    (tmp_path / "plain.py").write_text("x = 2\n")  # not a kernel: the cache stays
    assert not refresh(tmp_path)
    assert (cache / "kernel.f-3.py311.nbi").exists()
    (tmp_path / "kernel.py").write_text("import numba\n\n# changed\n")
    assert refresh(tmp_path)
    assert not (cache / "kernel.f-3.py311.nbi").exists()
    assert (tmp_path / STAMP).read_text() == sources_hash(tmp_path)


def test_a_package_it_cannot_stamp_is_left_alone(tmp_path) -> None:
    """No place for the stamp (as in a read-only package): nothing is deleted, or every
    process would compile the kernels again."""
    cache = _package(tmp_path)
    (tmp_path / "__pycache__").write_text("a file where the stamp's folder would be")
    assert not refresh(tmp_path)
    assert len(list(cache.iterdir())) == 3


def test_this_package_is_stamped_after_import() -> None:
    import koolio_pymunk.learning.engine  # noqa: F401  (a kernel module)

    assert (PACKAGE / STAMP).read_text() == sources_hash(PACKAGE)
