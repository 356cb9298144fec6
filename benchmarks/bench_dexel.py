"""Benchmark (run on demand): the dexel workpiece's spacing chosen from measurements, and its speed on a real gear.

    python benchmarks/bench_dexel.py                     # the default job: dexel spacings against a 2 um manifold cut
    python benchmarks/bench_dexel.py --job spur_external --reference 0   # spacings only (no manifold reference)
    python benchmarks/bench_dexel.py --finishing         # spur_external's finishing pass from the blank + its exact
                                                         # measurement, stage by stage (bar 20 s, goal 6.3 s)
    options: --job JOB (a job of assets/jobs or a .toml), --spacings P,F ... (profile and face spacing in mn),
             --reference UM (the manifold reference's sweep error; 0: none), --workers N (the manifold reference's)

Spacings: every case cuts the job's passes with the ideal motion on a fresh dexel blank; against the reference
(the manifold cut at ``--reference`` um, or the finest spacing without one) it prints, per pass, the total chip
volume's error and the 95th percentile and maximum of the chips' errors (chips above 1 % of the pass's largest,
matched by (pass, cutter tooth, mesh time)), the lines, the wall time against the machine time, and the dexel
solid written as gear.stl and measured beside the exact swept surface: the largest difference of the traces (the
solid's tolerance) and its class against the exact surface's.
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time
from pathlib import Path

import numpy as np

from cutting.gear_file import write_gear_stl
from cutting.parallel import default_workers
from cutting.skiving.dexel_lines import DexelSpacing
from cutting.skiving.edge import make_edge
from cutting.skiving.exact_sweep import SweptVolumes
from cutting.skiving.ideal_cut import cut_ideal
from cutting.skiving.trajectory import ideal_passes
from metrology.cut_measurement import measure_cut
from metrology.datum import check_mesh
from metrology.measure import MeasureOptions, measure_gear
from virtual_machine.job import load_job

SIGNIFICANT = 0.01  # chips above this fraction of the pass's largest reference chip enter p95 and max
JOBS = Path(__file__).resolve().parents[1] / "assets" / "jobs"


def job_path(name: str) -> Path:
    p = Path(name)
    return p if p.suffix == ".toml" else JOBS / f"{name}.toml"


def peak_rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def chip_table(report) -> dict[tuple[int, int, float], float]:
    return {(c.pass_index, c.cutter_tooth, round(c.time, 7)): c.volume for c in report.result.chips}


def compare(chips: dict, ref: dict, passes: int) -> list[tuple[float, float, float]]:
    """Per pass: total error, p95 and max of the chips' errors [%] against the reference."""
    out = []
    for p in range(passes):
        keys = [k for k in ref if k[0] == p and k in chips]
        r = np.array([ref[k] for k in keys])
        d = np.array([chips[k] for k in keys])
        big = r > SIGNIFICANT * r.max()
        rel = np.abs(d[big] - r[big]) / r[big] * 100
        out.append(((d.sum() - r.sum()) / r.sum() * 100, float(np.percentile(rel, 95)), float(rel.max())))
    return out


def spacings(a) -> None:
    job = load_job(job_path(a.job))
    st = job.skiving
    machine = sum(st.pass_times)
    ref = None
    if a.reference > 0:
        t0 = time.perf_counter()
        tol = a.reference * 1e-3
        rep = cut_ideal(st, "conjugate", tol, tol, workers=a.workers, removal="manifold")
        ref = chip_table(rep)
        print(f"reference: manifold at {a.reference:g} um, {time.perf_counter() - t0:.1f} s ({a.workers} workers)")
    opts = MeasureOptions.from_job(job.measurement, job.modification)
    rows = []
    for spec in a.spacings:
        fp, ff = (float(v) for v in spec.split(","))
        spacing = DexelSpacing.for_gear(st.gear, st.axial_feed, fp * st.gear.mn, ff * st.gear.mn)
        t0 = time.perf_counter()
        rep = cut_ideal(st, "conjugate", 0.01, 0.01, removal="dexel", spacing=spacing)
        wall = time.perf_counter() - t0
        with tempfile.TemporaryDirectory() as tmp:
            stl = write_gear_stl(rep.result.gear, Path(tmp) / "gear.stl", 0.0)
            mesh = check_mesh(stl.mesh, "gear.stl")
            doc, _ = measure_cut(st.gear, SweptVolumes(st.gear, rep.edge, ideal_passes(st)), mesh, opts, 0.01)
        rows.append((spec, rep, wall, doc, stl))
        ref = ref if ref is not None else chip_table(rep)
    print(f"\n{a.job}: {len(st.passes)} passes, {machine:.2f} s of machine time, feed {st.axial_feed} mm/rev")
    print(
        "spacing (mn)  lines      wall  x machine  solid tris  solid vs exact  class (exact)  "
        "per pass: total / p95 / max chip error [%]"
    )
    for spec, rep, wall, doc, stl in rows:
        errs = compare(chip_table(rep), ref, len(st.passes))
        m = doc["mesh"]
        passes = "  ".join(f"{t:+.2f} / {p:.2f} / {x:.1f}" for t, p, x in errs)
        print(
            f"{spec:12s}  {rep.removal['lines']:8,d}  {wall:6.1f} s  {wall / machine:7.1f}  "
            f"{stl.solid_triangles:10,d}  "
            f"{m['trace_difference_um']:9.2f} um  {m['class']} ({doc['iso1328']['class']['overall']})  {passes}"
        )


def finishing(a) -> None:
    """The finishing pass of spur_external from the blank, then the exact measurement of it."""
    job = load_job(job_path("spur_external"))
    st = job.skiving
    motion = ideal_passes(st)[-1]
    edge = make_edge(st, "conjugate")
    t0 = time.perf_counter()
    rep = cut_ideal(st, "conjugate", 0.01, 0.01, motions=[motion], removal="dexel")
    t_cut = time.perf_counter() - t0
    t0 = time.perf_counter()
    exact = SweptVolumes(st.gear, edge, [motion])
    t_tables = time.perf_counter() - t0
    t0 = time.perf_counter()
    doc = measure_gear(exact, st.gear, MeasureOptions.from_job(job.measurement, job.modification), exact.name)
    t_measure = time.perf_counter() - t0
    r = rep.removal
    total = t_cut + t_tables + t_measure
    print(f"spur_external finishing pass from the blank: {motion.duration:.2f} s of machine time")
    print(
        f"  dexel cut  {t_cut:6.1f} s ({r['lines']:,} lines, {len(rep.result.chips)} passages, "
        f"{r['crossings']:,} crossings; passes {r['pass_seconds']} s, solid {r['solid_seconds']:.1f} s)"
    )
    print(f"  exact tables {t_tables:6.1f} s, exact measurement {t_measure:6.1f} s")
    print(f"  total {total:.1f} s = {total / motion.duration:.2f}x the machine time (bar 20 s, goal 6.3 s)")
    print(f"  peak memory {peak_rss_mib():.0f} MiB; class {doc['iso1328']['class']['overall']}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--job", default="default")
    ap.add_argument("--spacings", nargs="+", default=["0.05,0.1", "0.1,0.2", "0.15,0.3", "0.2,0.4"])
    ap.add_argument("--reference", type=float, default=2.0)
    ap.add_argument("--workers", type=int, default=default_workers())
    ap.add_argument("--finishing", action="store_true")
    a = ap.parse_args()
    if a.finishing:
        finishing(a)
    else:
        spacings(a)


if __name__ == "__main__":
    main()
