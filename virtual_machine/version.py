"""Which skive made a result: its release and a fingerprint of its code and data.

The release number of an editable install does not change while the code does, so results that are kept (a study's
case store, a run's metadata) carry :func:`skive_version`: the release and the SHA-256 of every module and of the
material data the physics reads. A result made by other code is not taken for this code's.
"""

from __future__ import annotations

import functools
import hashlib
import platform
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: what a result depends on: the packages' modules and the data they read
SOURCES = ("machine_models", "virtual_machine", "cutting", "metrology")
DATA = ("assets/materials.toml",)


def release() -> str:
    try:
        return metadata.version("skive")
    except metadata.PackageNotFoundError:
        return "unreleased"


@functools.cache
def source_fingerprint(root: Path = ROOT) -> str:
    """SHA-256 (12 hex digits) of the packages' modules and the material data under ``root``, by path and content."""
    h = hashlib.sha256()
    files = sorted(p for package in SOURCES for p in (root / package).rglob("*.py"))
    files += [root / name for name in DATA if (root / name).is_file()]
    for path in files:
        h.update(str(path.relative_to(root)).encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()[:12]


def skive_version() -> str:
    """The release and the code's fingerprint, e.g. ``0.1.0+src.3f2a9c1e07bd``."""
    return f"{release()}+src.{source_fingerprint()}"


def versions() -> dict[str, str]:
    """skive's version and those of Python and the libraries a result depends on."""
    out = {"python": platform.python_version(), "skive": skive_version()}
    for dist in ("mujoco", "manifold3d", "numpy", "trimesh", "rerun-sdk"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = "not installed"
    return out
