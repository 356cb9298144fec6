"""The build backend's warm-up (build_backend/skive_build.py, cutting/warmup.py): the editable install compiles every
kernel a run needs, so that the first ``skive run`` after ``pip install -e .`` does not compile for a minute."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "build_backend"))

from skive_build import warmup_env  # noqa: E402


def test_the_warm_up_keeps_pips_path_to_the_build_environment(tmp_path: Path) -> None:
    # pip's isolated build puts its environment's packages on PYTHONPATH; a fresh machine has numpy and numba only
    # there while the package is built (the warm-up failed with ModuleNotFoundError: numpy when this was replaced)
    assert warmup_env({"PYTHONPATH": "/pip/overlay", "X": "1"}) == {
        "PYTHONPATH": os.pathsep.join([str(ROOT), "/pip/overlay"]),
        "X": "1",
    }
    assert warmup_env({})["PYTHONPATH"] == str(ROOT)
    (tmp_path / "only_in_the_build_env.py").write_text("VALUE = 7\n")
    env = warmup_env({**os.environ, "PYTHONPATH": str(tmp_path)})
    code = "import only_in_the_build_env, cutting.warmup; print(only_in_the_build_env.VALUE)"
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "7"


def test_the_warm_up_compiles_what_a_run_then_needs() -> None:
    # a fresh process (kernels of earlier tests would hide a gap): after the two warm-ups, the measurement's item
    # solve is compiled, and the mesh probe takes read-only operands (as a run hands it) without a new signature
    code = textwrap.dedent(
        """
        import numpy as np
        import cutting.warmup, metrology.mesh_bvh as mb
        from cutting.skiving.exact_solve import exact_margins, exact_roots
        cutting.warmup.warm()
        mb.warm()
        assert exact_margins.signatures and exact_roots.signatures, "the warm-up never solved a probe line's items"
        known = len(mb.cross_lines.signatures)
        v = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
        f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
        lo = np.broadcast_to(np.array([-5.0]), (1,))  # read-only, as np.broadcast_to makes them
        hi = np.broadcast_to(np.array([5.0]), (1,))
        o, d = np.array([[0.2, 0.2, -1.0]]), np.array([[0.0, 0.0, 1.0]])
        o.flags.writeable = False
        mb.MeshTree(v, f).crossings(o, d, lo, hi, np.ones(1, bool), 1e-7)
        assert len(mb.cross_lines.signatures) == known, mb.cross_lines.signatures
        print("ok")
        """
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip() == "ok"
