"""The kernels' caches kept in step with their sources (cutting/kernel_cache.py): numba keys a cache on its own file
only, so a kernel holding another module's kernel would keep that module's old code."""

from __future__ import annotations

from pathlib import Path

import pytest

import cutting.kernel_cache as kc


@pytest.fixture
def package(tmp_path, monkeypatch) -> Path:
    """A stand-in for the project: a kernel module, a plain module and their caches."""
    for name in kc.PACKAGES:
        (tmp_path / name / "__pycache__").mkdir(parents=True)
    (tmp_path / "cutting" / "solve.py").write_text("from numba import njit\n\n@njit\ndef f(x):\n    return x\n")
    (tmp_path / "cutting" / "plain.py").write_text("X = 1\n")
    monkeypatch.setattr(kc, "ROOT", tmp_path)
    monkeypatch.setattr(kc, "STAMP", tmp_path / "cutting" / "__pycache__" / "kernel_sources.sha256")
    return tmp_path


def _caches(root: Path) -> list[Path]:
    files = [root / "cutting" / "__pycache__" / "solve.f-4.py311.nbi", root / "metrology" / "__pycache__" / "m.nbc"]
    for f in files:
        f.write_bytes(b"cache")
    return files


def test_a_changed_kernel_source_removes_every_kernel_cache(package) -> None:
    files = _caches(package)
    assert kc.keep_in_step() is True  # no stamp yet: the caches' sources are unknown
    assert not any(f.exists() for f in files) and kc.STAMP.read_text().strip() == kc.fingerprint()
    files = _caches(package)
    assert kc.keep_in_step() is False and all(f.exists() for f in files)  # in step: kept
    (package / "cutting" / "plain.py").write_text("X = 2\n")  # not a kernel module: kept
    assert kc.keep_in_step() is False and all(f.exists() for f in files)
    (package / "cutting" / "solve.py").write_text("from numba import njit\n\n@njit\ndef f(x):\n    return 2 * x\n")
    assert kc.keep_in_step() is True and not any(f.exists() for f in files)


def test_the_fingerprint_covers_the_modules_whose_kernels_hold_each_other() -> None:
    """The stale cache that made this module: dexel_kernels.py compiles exact_solve.py's pose into its kernel; the
    loop's deflection kernel sits in virtual_machine. Each is among the fingerprinted sources; a module without
    numba is not."""
    names = {str(p.relative_to(kc.ROOT)) for p in kc._kernel_sources()}
    for module in (
        "cutting/skiving/exact_solve.py",
        "cutting/skiving/dexel_kernels.py",
        "metrology/mesh_bvh.py",
        "virtual_machine/runtime/machine_run.py",
    ):
        assert module in names, module
    assert "cutting/gear.py" not in names
