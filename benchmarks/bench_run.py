"""Benchmark (run on demand): skive run end to end on a job, each stage's share, against the cut alone.

    python benchmarks/bench_run.py                      # the default job, with a recording
    python benchmarks/bench_run.py --job assets/jobs/spur_external.toml --no-rrd
    options: --workers N (default: one per core), --skip-cut (no cut-alone comparison)

Prints the wall time of each stage of the run (machine and cut, measurement, report, recording) and its share,
the split of the co-simulation (physics, controllers, removal or the wait for its workers), the machine time,
and then the cut alone of the same job (ideal motion, same workers, with its measurement, like `skive cut`):
the issue's bar is run <= 2x cut alone.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from cutting.gear_file import write_gear_stl
from cutting.ideal_cut import cut_ideal, default_workers
from cutting.trajectory import ideal_passes
from virtual_machine.job import default_job_path, load_job
from virtual_machine.run import measure_written_cut, run_job


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--job", type=Path, default=default_job_path())
    ap.add_argument("--workers", type=int, default=default_workers())
    ap.add_argument("--no-rrd", action="store_true")
    ap.add_argument("--skip-cut", action="store_true")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        t0 = time.perf_counter()
        doc = run_job(a.job, out, None if a.no_rrd else out / "run.rrd", workers=a.workers)
        wall = time.perf_counter() - t0
    run = doc["run"]
    d = run["durations_s"]
    print(f"skive run {a.job} ({a.workers} workers): {wall:.1f} s wall for {d['machine']:.2f} s of machine time")
    for stage, seconds in d.items():
        if stage != "machine":
            print(f"  {stage:18s} {seconds:8.1f} s  {seconds / wall:6.1%}")
    split = run["wall_split_s"]
    print(
        f"  co-simulation: physics {split['physics']:.1f} s, controllers {split['control']:.1f} s, removal (or the "
        f"wait for its workers) {split['cut']:.1f} s of {split['total']:.1f} s"
    )
    print(
        f"  class {doc['iso1328'].get('class', {}) and doc['iso1328']['class'].get('overall')}, sync error "
        f"{run['synchronisation']['sync_error_in_cut'].get('rms_um', 0):.2f} um RMS, peak force "
        f"{run['forces']['peak_force_N']:.0f} N"
    )
    if a.skip_cut:
        return
    job = load_job(a.job)
    t0 = time.perf_counter()
    report = cut_ideal(
        job.skiving,
        job.cutter_options["edge"],
        job.process["sweep_error"],
        job.process["roughing_sweep_error"],
        workers=a.workers,
    )
    with tempfile.TemporaryDirectory() as tmp:  # as `skive cut` does: gear.stl, the exact surface, the mesh beside
        stl = write_gear_stl(report.result.gear, Path(tmp) / "gear.stl", job.process["stl_tolerance"])
        measure_written_cut(job, report.edge, ideal_passes(job.skiving), report.result, stl, Path(tmp) / "gear.stl")
    alone = time.perf_counter() - t0
    print(
        f"cut alone (ideal motion, {a.workers} workers, with its measurement): {alone:.1f} s; "
        f"run / cut alone = {wall / alone:.2f} (bar <= 2)"
    )


if __name__ == "__main__":
    main()
