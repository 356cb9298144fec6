"""Benchmark (run on demand): the copying method (seed 003) on the form-milling job, stage by stage.

    python benchmarks/bench_form_milling.py                 # assets/jobs/form_milled_crowned.toml
    python benchmarks/bench_form_milling.py --job JOB --no-run
    python benchmarks/bench_form_milling.py --job assets/jobs/form_milled_helical.toml   # the set-over mill

Prints, for `skive cut` (ideal machine): the 15 steps' plan, the manifold removal (hulls, triangles) and the
measurement of the exact swept surface with gear.stl beside it; for `skive run`: each machine run (simulated
machine time per wall second), the removal and the measurement of the poses the machine made; and what they made
(largest residual of each accuracy check, largest topography against the design).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from virtual_machine.job import load_job
from virtual_machine.processes.form_milling.stages import cut_form_job, run_form_job

ASSET = Path(__file__).resolve().parent.parent / "assets" / "jobs" / "form_milled_crowned.toml"


def topography(doc: dict) -> float:
    return max(float(np.nanmax(np.abs(np.asarray(doc["topography"][s]["against_design_um"], float)))) for s in
               ("left", "right"))  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--job", type=Path, default=ASSET)
    ap.add_argument("--no-run", action="store_true")
    a = ap.parse_args()
    job = load_job(a.job)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        doc = cut_form_job(job, Path(tmp) / "cut")
        wall = time.perf_counter() - t0
        s = doc["cut"]["seconds"]
        print(f"skive cut (ideal machine) of {a.job.name}: {wall:.1f} s")
        print(f"  plan {s['plan']:.1f} s, removal {s['removal']:.1f} s ({doc['cut']['hulls']} hulls, "
              f"{doc['cut']['triangles']} triangles), measurement {s['measurement']:.1f} s")  # fmt: skip
        checks = [it["max_residual_um"] for it in doc["copying"]["iterations"] if it["step"] != "path"]
        mesh = doc["mesh"]
        print(
            f"  accuracy checks {checks} um; topography against the design <= {topography(doc):.2f} um; "
            f"gear.stl vs exact {mesh['trace_difference_um']:.2f} um (bound {mesh['trace_bound_um']:.1f})"
        )
        if a.no_run:
            return
        t0 = time.perf_counter()
        doc = run_form_job(job, a.job, Path(tmp) / "run")
        wall = time.perf_counter() - t0
    d = doc["run"]["durations_s"]
    print(f"skive run (simulated machine): {wall:.1f} s for {d['machine']:.1f} s of machine time")
    for k, v in d.items():
        if k.startswith("machine run"):
            print(f"  {k}: {v:.1f} s ({d['machine'] / v:.1f} x real time)")
    print(f"  removal {d['removal']:.1f} s, measurement {d['measurement']:.1f} s")
    runs = [r["max_residual_um"] for r in doc["copying"]["machine_checks"]]
    print(f"  machine accuracy checks {runs} um; topography against the design <= {topography(doc):.2f} um")
    for side in ("left", "right"):
        h, p = doc["helix"][side], doc["profile"][side]
        print(
            f"  {side}: C_beta {h['C_beta']:.2f} (design {h['C_beta_design']:.2f}), C_alpha {p['C_alpha']:.2f} "
            f"(design {p['C_alpha_design']:.2f}), F_alpha {p['F_alpha']:.2f}, F_beta {h['F_beta']:.2f} um"
        )


if __name__ == "__main__":
    main()
