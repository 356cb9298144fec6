"""Benchmark (run on demand): does the install's warm-up compile every kernel a run needs? (the first run
after install should not take twice the next)

    python benchmarks/bench_first_run.py                 # the default job
    python benchmarks/bench_first_run.py --job assets/jobs/spur_external.toml
    python benchmarks/bench_first_run.py --job assets/jobs/form_milled_helical.toml   # any kind of job

Runs what the editable install runs (``cutting.warmup`` then ``metrology.mesh_bvh``'s warm-up), notes every numba
kernel's compiled signatures in the project's packages, runs the job, and lists each kernel the run had to compile
again (a signature the warm-up did not make: a read-only or strided array, another dtype, a path it missed). Every
such kernel costs its compile time (a second to tens of seconds) on the first run after install.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from numba.core.registry import CPUDispatcher

import cutting.warmup
import metrology.mesh_bvh
from virtual_machine.api import run
from virtual_machine.job import default_job_path

PACKAGES = ("cutting", "metrology", "virtual_machine", "machine_models")


def kernels() -> dict[str, CPUDispatcher]:
    """Every numba dispatcher in the project's loaded modules, by qualified name."""
    out = {}
    for name, module in list(sys.modules.items()):
        if module is None or name.split(".")[0] not in PACKAGES:
            continue
        for attr, obj in vars(module).items():
            if isinstance(obj, CPUDispatcher) and obj.__module__ == name:
                out[f"{name}.{attr}"] = obj
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--job", type=Path, default=default_job_path())
    a = ap.parse_args()
    t0 = time.perf_counter()
    cutting.warmup.warm()
    metrology.mesh_bvh.warm()
    print(f"warm-up {time.perf_counter() - t0:.1f} s (loads the cache when the install compiled it)")
    before = {k: set(d.signatures) for k, d in kernels().items()}
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        run(a.job, Path(tmp), quiet=True)  # any kind of job: skiving, form milling, face contour, turning
        print(f"skive run {a.job}: {time.perf_counter() - t0:.1f} s")
    missed = []
    for k, d in sorted(kernels().items()):
        new = set(d.signatures) - before.get(k, set())
        if new:
            missed.append(k)
            kind = "not warmed at all" if k not in before or not before[k] else f"{len(new)} new signature(s)"
            print(f"  compiled by the run: {k} ({kind})")
    print("every kernel the run used was compiled by the warm-up" if not missed else f"{len(missed)} kernel(s) missed")


if __name__ == "__main__":
    main()
