"""The project's build backend: setuptools' own, and on an editable install the numba kernels compiled into the
package's ``__pycache__`` (cutting/warmup.py, metrology/mesh_bvh.py), so that the first ``skive run`` after
``pip install -e .`` does not spend a minute compiling them.

pip builds in an isolated environment: the warm-up needs the kernels' own dependencies there (the same version
ranges as the project's, so pip resolves the same numba the project then runs with; a numba of another version
ignores the cache and compiles on the first run, as without this step). A failed warm-up never fails the install.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path

from setuptools import build_meta as _setuptools
from setuptools.build_meta import *  # noqa: F403 (the PEP 517 hooks this backend does not change)

ROOT = Path(__file__).resolve().parents[1]
#: what cutting/warmup.py imports (keep in step with [project] dependencies)
WARMUP_REQUIRES = ["numpy>=1.26", "scipy>=1.11", "numba>=0.61", "manifold3d>=3.0"]


def warmup_env(environ: Mapping[str, str]) -> dict[str, str]:
    """The warm-up's environment: the project put before pip's own PYTHONPATH, not instead of it. pip's entry there
    makes the build environment's packages (WARMUP_REQUIRES) importable; without it a fresh machine, whose numpy and
    numba pip installs only after this build, failed the warm-up (ModuleNotFoundError: numpy) and its first run
    compiled for a minute."""
    path = environ.get("PYTHONPATH")
    return {**environ, "PYTHONPATH": os.pathsep.join([str(ROOT), path]) if path else str(ROOT)}


def get_requires_for_build_editable(config_settings=None):
    return [*_setuptools.get_requires_for_build_editable(config_settings), *WARMUP_REQUIRES]


def build_editable(wheel_directory, config_settings=None, metadata_directory=None):
    name = _setuptools.build_editable(wheel_directory, config_settings, metadata_directory)
    if not os.environ.get("SKIVE_NO_WARMUP"):
        print("skive: compiling the numba kernels into the package (about a minute, once)", file=sys.stderr)
        env = warmup_env(os.environ)
        # the cut's kernels, then the measuring machine's (metrology does not import cutting's warm-up)
        done = subprocess.run([sys.executable, "-m", "cutting.warmup"], cwd=ROOT, env=env, check=False)
        if done.returncode == 0:
            done = subprocess.run([sys.executable, "-m", "metrology.mesh_bvh"], cwd=ROOT, env=env, check=False)
        if done.returncode != 0:
            print("skive: the warm-up failed; the first run compiles the kernels instead", file=sys.stderr)
    return name
