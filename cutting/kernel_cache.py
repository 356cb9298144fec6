"""The numba kernels' on-disk caches kept in step with their sources.

numba keys a cached kernel on its own file's time stamp only. A kernel compiled with another module's kernel inside it
(the dexel removal's `cut_cells` holds the exact solve's pose, cutting/skiving/exact_solve.py) keeps that module's old
code after the module changes: a stale cache computes silently with the old code. So the caches carry a fingerprint
of every kernel module's source (each file of cutting/, metrology/ and virtual_machine/ that compiles with numba) and
numba's version; where it differs, every kernel cache of the three packages is removed before any kernel runs, and
the next call compiles (the install's warm-up does it, cutting/warmup.py). Checked once per process, when `cutting`
is imported.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("cutting", "metrology", "virtual_machine")
#: where the fingerprint of the sources the caches were compiled from is kept
STAMP = ROOT / "cutting" / "__pycache__" / "kernel_sources.sha256"


def _kernel_sources() -> list[Path]:
    """The modules that compile kernels with numba (their text names it)."""
    out = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            text = path.read_text(encoding="utf-8", errors="replace")
            if "from numba" in text or "import numba" in text:
                out.append(path)
    return out


def fingerprint() -> str:
    """The SHA-256 of the kernel modules' sources (path and text) and numba's version (read without importing it)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        numba_version = version("numba")
    except PackageNotFoundError:
        numba_version = "none"
    h = hashlib.sha256(numba_version.encode())
    for path in _kernel_sources():
        h.update(str(path.relative_to(ROOT)).encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def _cache_files() -> list[Path]:
    return [p for package in PACKAGES for p in (ROOT / package).rglob("*.nb[ic]") if p.parent.name == "__pycache__"]


def keep_in_step() -> bool:
    """Remove the kernel caches when their sources changed since they were written (module docstring); True if it
    removed them. A read-only installation, or a race with another process doing the same, is left to numba."""
    now = fingerprint()
    try:
        if STAMP.read_text().strip() == now:
            return False
    except OSError:
        pass
    removed = False
    for path in _cache_files():
        try:
            path.unlink()
            removed = True
        except OSError:
            pass
    try:
        STAMP.parent.mkdir(parents=True, exist_ok=True)
        tmp = STAMP.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(now + "\n")
        tmp.replace(STAMP)  # atomic: a process reading it sees the old stamp or the new one
    except OSError:
        pass
    return removed
