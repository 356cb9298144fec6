"""Benchmark (run on demand): skive run end to end on a job, each stage's share, against the cut alone.

    python benchmarks/bench_run.py                      # the default job, with a recording
    python benchmarks/bench_run.py --job assets/jobs/spur_external.toml --no-rrd --skip-cut
    options: --workers N (the manifold removal's processes; default: one per core), --removal dexel|manifold,
             --skip-cut (no cut-alone comparison)

Prints the wall time of each stage of the run (machine and cut, measurement, report, recording), its share and
its ratio to the machine time, the split of the co-simulation (physics, controllers, removal), the peak memory of
this process (the dexel removal cuts here; the manifold reference's workers are not counted), the issue's bar for
the job (the bars: default job <= 10 s after the first run, spur_external <= 2 min and <= 4 GiB, helical_internal
<= 4 min), and then the cut alone of the same job (ideal motion, with its measurement, like `skive cut`).
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time
from pathlib import Path

from cutting.gear_file import write_gear_stl
from cutting.parallel import default_workers
from cutting.skiving.ideal_cut import cut_ideal
from cutting.skiving.trajectory import ideal_passes
from virtual_machine.job import default_job_path, dexel_spacing, load_job
from virtual_machine.processes.skiving.run import measure_written_cut, run_job

#: the bars per job file name (docs/performance.md): wall seconds (after the first run), peak memory [GiB]
BARS = {"default.toml": (10.0, None), "spur_external.toml": (120.0, 4.0), "helical_internal.toml": (240.0, None)}


def peak_rss_gib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--job", type=Path, default=default_job_path())
    ap.add_argument("--workers", type=int, default=default_workers())
    ap.add_argument("--no-rrd", action="store_true")
    ap.add_argument("--skip-cut", action="store_true")
    ap.add_argument("--removal", choices=("dexel", "manifold"), default="dexel")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        t0 = time.perf_counter()
        doc = run_job(a.job, out, None if a.no_rrd else out / "run.rrd", workers=a.workers, removal=a.removal)
        wall = time.perf_counter() - t0
    run = doc["run"]
    d = run["durations_s"]
    machine = d["machine"]
    print(
        f"skive run {a.job} ({a.removal} removal): {wall:.1f} s wall for {machine:.2f} s of machine time "
        f"({wall / machine:.1f}x); peak memory {peak_rss_gib():.2f} GiB"
    )
    for stage, seconds in d.items():
        if stage != "machine":
            print(f"  {stage:18s} {seconds:8.1f} s  {seconds / wall:6.1%}  {seconds / machine:6.2f}x machine time")
    bar, memory = BARS.get(Path(a.job).name, (None, None))
    if bar is not None:
        verdict = "met" if wall <= bar else "NOT met"
        print(f"  bar: {bar:.0f} s ({verdict})" + (f", {memory:.0f} GiB" if memory else ""))
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
        job.cutter_options.edge,
        job.process.sweep_error,
        job.process.roughing_sweep_error,
        workers=a.workers,
        removal=a.removal,
        spacing=dexel_spacing(job),
    )
    with tempfile.TemporaryDirectory() as tmp:  # as `skive cut` does: gear.stl, the exact surface, the mesh beside
        stl = write_gear_stl(report.result.gear, Path(tmp) / "gear.stl", job.process.stl_tolerance)
        measure_written_cut(job, report.edge, ideal_passes(job.skiving), report.result, stl, Path(tmp) / "gear.stl")
    alone = time.perf_counter() - t0
    print(
        f"cut alone (ideal motion, {a.workers} workers, with its measurement): {alone:.1f} s; "
        f"run / cut alone = {wall / alone:.2f} (bar <= 2)"
    )


if __name__ == "__main__":
    main()
