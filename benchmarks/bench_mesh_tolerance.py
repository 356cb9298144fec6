"""Benchmark (run on demand): the manifold solid's sweep tolerance chosen from measurements.

    python benchmarks/bench_mesh_tolerance.py                       # spur_external, all four passes, 1/2/5/10/20 um
    python benchmarks/bench_mesh_tolerance.py --tols 1 2 3 5 10 20 50
    python benchmarks/bench_mesh_tolerance.py --passes 4            # the finishing pass alone, on the blank
    python benchmarks/bench_mesh_tolerance.py --roughing 10         # roughing held at 10 um, finishing varied
    options: --job JOB (a job of assets/jobs, or a path to a .toml), --workers N (default: one per core),
             --stl-tolerance UM (gear.stl's simplification),
             --keep DIR (keep each case's gear.stl in DIR instead of a temporary directory)

Every case cuts the job's passes with the ideal motion, every pass at the same tolerance (or the roughing passes
at ``--roughing``); the finest tolerance is the reference, cut first and kept in memory. Per case it prints wall
and CPU time and their ratio to the machine time, the solid's triangles, genus and loose pieces, the gear.stl it
writes as `skive cut` does (simplified within ``--stl-tolerance`` UM, default process.stl_tolerance; its triangles,
size, and whether it reads back watertight), the peak memory (resident, this process and its
workers, sampled) and, against the reference, per pass: the total chip volume's relative error, the 95th percentile
and maximum of the chips' relative errors (chips above 1 % of the pass's largest reference chip: the tiny chips at
the ends of the stroke carry no force) and the volume-weighted mean absolute relative error. Chips are matched by
(pass, cutter tooth, mesh time). At the end: which tolerances meet "every pass's total chip volume within 2 %, chip
p95 within 2 % and STL <= 50 MB", and the coarsest one that does, for the finishing and for the roughing passes.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import resource
import tempfile
import threading
import time
from dataclasses import dataclass, field

import numpy as np
import trimesh

from cutting.gear_file import write_gear_stl
from cutting.parallel import default_workers
from cutting.skiving.edge import make_edge
from cutting.skiving.engine import cut_passes
from cutting.skiving.passages import Chip, expected_genus
from cutting.skiving.trajectory import ideal_passes
from virtual_machine.job import PROCESS_KEYS, load_job
from virtual_machine.output.progress import Progress

#: the requirement: chip volumes within 2 % of a 1 um reference, a gear.stl a user can open
VOLUME_LIMIT = 2.0  # [%] every pass's total chip volume, and the 95th percentile of its chips
STL_LIMIT_MB = 50.0
SIGNIFICANT = 0.01  # chips above this fraction of the pass's largest reference chip enter p95 and max

ChipKey = tuple[int, int, float]


def peak_rss_mib() -> float:
    """Peak resident memory of this process or its largest finished child so far [MiB] (as bench_cut.py)."""
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    kids = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return max(own, kids) / 1024


def cpu_seconds() -> float:
    """User + system time of this process and its finished children [s]."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


class RssSampler:
    """The peak of the summed resident memory of this process and its descendants [MiB], sampled every
    ``period`` seconds while it runs (a case's workers are fresh processes, so this is that case's peak)."""

    def __init__(self, period: float = 0.5) -> None:
        self.period, self.peak = period, 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> RssSampler:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()

    def _run(self) -> None:
        try:
            import psutil
        except ImportError:  # not a dependency of skive: then only the getrusage peak is printed
            self.peak = math.nan
            return
        me = psutil.Process()
        while not self._stop.is_set():
            total = 0
            for p in [me, *me.children(recursive=True)]:
                with contextlib.suppress(psutil.Error):  # a worker that ended between the listing and the reading
                    total += p.memory_info().rss
            self.peak = max(self.peak, total / 2**20)
            self._stop.wait(self.period)


@dataclass
class Case:
    """One cut: its tolerances, timings, gear and chips."""

    tol_um: float  # the tolerance of the varied passes [um]
    tols: list[float]  # per cut pass [mm]
    wall: float
    cpu: float
    pass_seconds: list[float]
    triangles: int
    stl_mb: float  # the written gear.stl: the solid simplified within --stl-tolerance, welded in float32
    stl_triangles: int
    stl_watertight: bool
    collapsed: int  # vertices that float32 (the STL's precision) folds onto another one (welded in the file)
    genus: int
    loose_pieces: int
    loose_volume: float
    bound_um: dict[int, float]
    rss_sampled: float
    rss_peak: float
    chips: dict[ChipKey, float] = field(default_factory=dict)
    duplicates: int = 0


@dataclass
class PassStats:
    total_err: float  # [%] signed
    p95: float  # [%]
    worst: float  # [%]
    weighted: float  # [%]
    matched: int
    only_here: int  # chips of this case without a reference chip
    only_ref: int
    unmatched_volume: float  # [% of the pass's reference volume]


def chip_key(chip: Chip) -> ChipKey:
    return chip.pass_index, chip.cutter_tooth, round(chip.time, 9)


def cut_case(
    job_path: str,
    pass_numbers: list[int],
    tols: list[float],
    tol_um: float,
    workers: int,
    keep: str | None,
    stl_tol: float,
):
    """Cut the passes at ``tols`` [mm]; their timings, the gear's figures and the chips."""
    job = load_job(job_path)
    setup = job.skiving
    edge = make_edge(setup, job.cutter_options.edge)
    all_motions = ideal_passes(setup)
    motions = [all_motions[i - 1] for i in pass_numbers]
    bars: dict[int, Progress] = {}
    finished: set[int] = set()

    def progress(index: int, done: int, total: int) -> None:
        if done <= 0 or index in finished:
            return
        if index not in bars:
            tol = tols[[m.index for m in motions].index(index)]
            bars[index] = Progress(
                f"  {tol_um:g} um: pass {index + 1}/{len(all_motions)} at {tol * 1e3:g} um",
                total,
                "passages",
                step=0.25,
                interactive=False,
            )
        bars[index].update_to(done)
        if done >= total:
            bars[index].close()
            finished.add(index)

    cpu0 = cpu_seconds()
    t0 = time.perf_counter()
    with RssSampler() as sampler:
        run = cut_passes(setup.gear, edge, motions, tols, workers, progress=progress)
    wall = time.perf_counter() - t0
    cpu = cpu_seconds() - cpu0
    for bar in bars.values():
        bar.close()
    res = run.result
    triangles = res.gear.num_tri()
    genus = res.gear.genus()
    print(
        f"  {tol_um:g} um: cut in {wall:.1f} s (CPU {cpu:.1f} s); passes "
        + ", ".join(f"{s:.1f}" for s in run.pass_seconds)
        + " s; stages "
        + ", ".join(f"{k} {v:.1f}" for k, v in run.stage_seconds.items())
        + f" s; gear {triangles:,} triangles, genus {genus} (expected {expected_genus(setup.gear)}), "
        f"{res.loose_pieces} loose pieces ({res.loose_volume:.4f} mm^3)",
        flush=True,
    )
    with tempfile.TemporaryDirectory(prefix="skive-bench-tol-") as tmp:
        path = os.path.join(keep or tmp, f"gear_{tol_um:g}um.stl")
        t1 = time.perf_counter()
        written = write_gear_stl(res.gear, path, stl_tol)  # as skive cut / run write it
        t_write = time.perf_counter() - t1
        size = os.path.getsize(path)
        back = trimesh.load(path)  # what a user's viewer reads: float32 vertices, merged by position
        watertight = bool(back.is_watertight)
    print(
        f"  {tol_um:g} um: the solid {84 + 50 * triangles:,} bytes as STL; gear.stl simplified within "
        f"{stl_tol * 1e3:g} um: {len(written.mesh.faces):,} triangles, {size / 1e6:.1f} MB in {t_write:.1f} s, "
        f"read back watertight: {watertight} ({written.welded_vertices} vertices folded by float32, welded)",
        flush=True,
    )
    chips: dict[ChipKey, float] = {}
    duplicates = 0
    for chip in res.chips:
        key = chip_key(chip)
        duplicates += key in chips
        chips[key] = chips.get(key, 0.0) + chip.volume
    return Case(
        tol_um,
        tols,
        wall,
        cpu,
        list(run.pass_seconds),
        triangles,
        size / 1e6,
        len(written.mesh.faces),
        watertight,
        written.welded_vertices,
        genus,
        res.loose_pieces,
        res.loose_volume,
        {i: e * 1e3 for i, e in res.pass_sweep_error.items()},
        sampler.peak,
        peak_rss_mib(),
        chips,
        duplicates,
    )


def compare(case: Case, ref: Case, index: int) -> PassStats:
    """The chips of pass ``index`` of ``case`` against the reference's."""
    mine = {k: v for k, v in case.chips.items() if k[0] == index}
    theirs = {k: v for k, v in ref.chips.items() if k[0] == index}
    common = sorted(mine.keys() & theirs.keys())
    v = np.array([mine[k] for k in common])
    r = np.array([theirs[k] for k in common])
    ref_total = sum(theirs.values())
    total_err = 100 * (sum(mine.values()) - ref_total) / ref_total
    big = r > SIGNIFICANT * r.max()
    rel = 100 * np.abs(v[big] - r[big]) / r[big]
    unmatched = sum(mine[k] for k in mine.keys() - theirs.keys()) + sum(theirs[k] for k in theirs.keys() - mine.keys())
    return PassStats(
        total_err,
        float(np.percentile(rel, 95)),
        float(rel.max()),
        100 * float(np.abs(v - r).sum() / r.sum()),
        len(common),
        len(mine.keys() - theirs.keys()),
        len(theirs.keys() - mine.keys()),
        100 * unmatched / ref_total,
    )


def meets(stats: PassStats) -> bool:
    return abs(stats.total_err) <= VOLUME_LIMIT and stats.p95 <= VOLUME_LIMIT


def print_row(case: Case, ref: Case, indices: list[int], machine: float) -> None:
    tols = "/".join(sorted({f"{t * 1e3:g}" for t in case.tols}, key=float))
    bounds = ", ".join(f"{case.bound_um[i]:.2f}" for i in indices if i in case.bound_um)
    opens = "" if case.stl_watertight else " NOT watertight"
    print(
        f"{case.tol_um:6g} | {tols:>5s} um | wall {case.wall:7.1f} s x{case.wall / machine:5.1f} | "
        f"CPU {case.cpu:7.1f} s x{case.cpu / machine:5.1f} | {case.triangles:>10,} tris | "
        f"gear.stl {case.stl_triangles:>10,} tris {case.stl_mb:6.1f} MB{opens} | genus {case.genus} | "
        f"loose {case.loose_pieces} ({case.loose_volume:.4f} mm^3) | RSS {case.rss_sampled:6.0f} MiB "
        f"(peak so far {case.rss_peak:.0f}) | bound [um] {bounds}",
        flush=True,
    )
    for i in indices:
        s = compare(case, ref, i)
        extra = ""
        if s.only_here or s.only_ref:
            extra = f" | unmatched {s.only_here} here, {s.only_ref} in ref ({s.unmatched_volume:.3f} % of volume)"
        print(
            f"         pass {i + 1}: total {s.total_err:+7.3f} %  chips p95 {s.p95:7.3f} %  max {s.worst:8.3f} %  "
            f"weighted {s.weighted:7.3f} %  ({s.matched} chips){extra}{'' if meets(s) else '  FAILS'}",
            flush=True,
        )


def summary(cases: list[Case], ref: Case, indices: list[int], finishing: int) -> None:
    """Which tolerances meet the requirement, and the coarsest that does, per kind of pass."""
    groups = {"finishing": [i for i in indices if i == finishing], "roughing": [i for i in indices if i != finishing]}
    print("\nrequirement: every pass's total chip volume within 2 %, chip p95 within 2 %, STL <= 50 MB", flush=True)
    for case in cases:
        verdict = {name: all(meets(compare(case, ref, i)) for i in group) for name, group in groups.items() if group}
        stl = case.stl_mb <= STL_LIMIT_MB
        ok = all(verdict.values()) and stl
        parts = ", ".join(f"{name} {'ok' if v else 'fails'}" for name, v in verdict.items())
        print(f"  {case.tol_um:6g} um: {'MEETS' if ok else 'fails'} ({parts}, STL {'ok' if stl else 'too big'})")
    passing = [c.tol_um for c in cases if c.stl_mb <= STL_LIMIT_MB and all(meets(compare(c, ref, i)) for i in indices)]
    print(f"  coarsest meeting it for every pass: {max(passing):g} um" if passing else "  none meets it")
    for name, group in groups.items():
        if not group:
            continue
        # the STL is the finishing pass's surface: its size limits the finishing tolerance only
        ok = [
            c.tol_um
            for c in cases
            if all(meets(compare(c, ref, i)) for i in group) and (name != "finishing" or c.stl_mb <= STL_LIMIT_MB)
        ]
        print(f"  recommended {name} default: {max(ok):g} um" if ok else f"  {name}: no tolerance meets it")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--job", default="spur_external", help="a job of assets/jobs, or a path to a .toml")
    ap.add_argument(
        "--tols", type=float, nargs="+", default=[1.0, 2.0, 5.0, 10.0, 20.0], help="um; the finest is the reference"
    )
    ap.add_argument("--passes", type=int, nargs="+", help="pass numbers (1-based) to cut, in order; default all")
    ap.add_argument("--roughing", type=float, help="hold the roughing passes at this tolerance [um] in every case")
    ap.add_argument("--workers", type=int, default=default_workers())
    ap.add_argument("--keep", help="keep each case's gear.stl in this directory")
    ap.add_argument(
        "--stl-tolerance",
        type=float,
        default=PROCESS_KEYS["stl_tolerance"].default * 1e3,
        help="um: the simplification of gear.stl (default: the job schema's process.stl_tolerance)",
    )
    a = ap.parse_args()
    job_path = a.job if a.job.endswith(".toml") else f"assets/jobs/{a.job}.toml"
    setup = load_job(job_path).skiving
    finishing = len(setup.passes) - 1
    pass_numbers = a.passes or list(range(1, len(setup.passes) + 1))
    indices = [n - 1 for n in pass_numbers]
    machine = sum(setup.pass_times[i] for i in indices)
    tols_um = sorted(set(a.tols))
    order = [tols_um[0], *dict.fromkeys(t for t in a.tols if t != tols_um[0])]  # the reference, then as given
    print(
        f"{job_path}: passes {pass_numbers} (finishing: {finishing + 1}), machine time {machine:.2f} s, "
        f"tolerances {tols_um} um (reference {tols_um[0]:g} um)"
        + (f", roughing held at {a.roughing:g} um" if a.roughing else "")
        + f", {a.workers} workers, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}",
        flush=True,
    )

    def tolerances(um: float) -> list[float]:
        return [(a.roughing if a.roughing and i != finishing else um) * 1e-3 for i in indices]

    header = (
        "tol um | passes | wall, ratio to machine time | CPU | solid triangles | gear.stl (simplified) | genus | "
        "loose pieces | "
        "peak RSS of the case | chord bound per pass"
    )
    if a.keep:
        os.makedirs(a.keep, exist_ok=True)
    t_start = time.perf_counter()
    cases: list[Case] = []
    for um in order:  # the reference first: every later row is printed against it as soon as it is cut
        print(f"case {um:g} um (load {os.getloadavg()[0]:.2f}) ...", flush=True)
        case = cut_case(job_path, pass_numbers, tolerances(um), um, a.workers, a.keep, a.stl_tolerance * 1e-3)
        if case.duplicates:
            print(f"  note: {case.duplicates} chips share (pass, tooth, time) with another (volumes summed)")
        cases.append(case)
        print(header, flush=True)
        print_row(case, cases[0], indices, machine)
    cases.sort(key=lambda c: c.tol_um)
    print(f"\nall cases ({len(cases)}) in {time.perf_counter() - t_start:.0f} s\n{header}", flush=True)
    for case in cases:
        print_row(case, cases[0], indices, machine)
    summary(cases, cases[0], indices, finishing)


if __name__ == "__main__":
    main()
