"""Benchmark (run on demand): `skive stability` of a job, against issue 42's bar.

    python benchmarks/bench_stability.py                                   # spur_external, four passes
    python benchmarks/bench_stability.py --job assets/jobs/default.toml

Prints the time of the passes' lobes (the oriented coefficients at every trial infeed and the lobes over 300 tool
speeds) after one warm-up, and each pass's margin. Bar: spur_external's four passes <= 10 s (goal 2 s).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from virtual_machine.job import load_job
from virtual_machine.processes.skiving.stability import pass_stability
from virtual_machine.setting.machine_layout import machine_params

JOBS = Path(__file__).resolve().parent.parent / "assets" / "jobs"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--job", type=Path, default=JOBS / "spur_external.toml")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    job = load_job(a.job)
    params = machine_params(job)
    pass_stability(job.skiving, params, job.process.material, job.cutter_options.edge_radius)  # compiled kernels
    times = []
    for _ in range(a.repeat):
        t0 = time.perf_counter()
        res = pass_stability(job.skiving, params, job.process.material, job.cutter_options.edge_radius)
        times.append(time.perf_counter() - t0)
    print(f"{a.job.name}: {len(res)} passes, lobes in {min(times):.2f} s (best of {a.repeat}; bar 10 s, goal 2 s)")
    for r in res:
        crit = f"{r.critical_infeed:.3g} mm"
        print(f"  pass {r.index + 1}: infeed {r.infeed:.3f} mm, margin {r.margin:.3g}, critical {crit}")


if __name__ == "__main__":
    main()
