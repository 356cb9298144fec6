"""The exact measurement of a cut: its swept surface built and probed like a gear measuring machine probes a gear.

    python benchmarks/bench_exact_measure.py                    # spur_external, all four passes, ideal motion
    python benchmarks/bench_exact_measure.py default --edge involute

Prints the build of the passage tables, then each stage of the measurement (datum, profile, helix, pitch, balls,
span, tip and root) with its probes and seconds, and the total against the target of 10 s and against
the machine time of the passes.
"""

from __future__ import annotations

import argparse
import time
from collections import defaultdict

import metrology.measure as measure_module
from cutting.skiving.edge import make_edge
from cutting.skiving.exact_sweep import SweptVolumes
from cutting.skiving.trajectory import ideal_passes
from virtual_machine.job import load_job

STAGES = {
    "establish_datum": "datum",
    "profile_trace": "profile (and pitch)",
    "helix_trace": "helix",
    "ball_seats": "balls",
    "measure_span": "span",
    "_tip_root": "tip and root",
}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("job", nargs="?", default="spur_external", help="a job of assets/jobs, or a path to a .toml")
    ap.add_argument("--edge", default=None, choices=["conjugate", "involute"])
    a = ap.parse_args()
    job = load_job(a.job if a.job.endswith(".toml") else f"assets/jobs/{a.job}.toml")
    st = job.skiving
    edge = make_edge(st, a.edge or job.cutter_options.edge)
    motions = ideal_passes(st)
    t0 = time.perf_counter()
    sv = SweptVolumes(st.gear, edge, motions)
    build = time.perf_counter() - t0
    passages = sum(len(tb.m) for tb in sv.tables)
    print(f"{a.job}: {passages} passages in {len(motions)} passes, tables built in {build:.1f} s")

    seconds: dict[str, float] = defaultdict(float)
    probes: dict[str, int] = defaultdict(int)
    current = ["other"]
    probe = sv.probe

    def counted(points, directions, reach):
        probes[current[0]] += len(points)
        return probe(points, directions, reach)

    sv.probe = counted
    for name, label in STAGES.items():
        fn = getattr(measure_module, name)

        def timed(*args, fn=fn, label=label, **kw):
            current[0] = label
            t = time.perf_counter()
            try:
                return fn(*args, **kw)
            finally:
                seconds[label] += time.perf_counter() - t
                current[0] = "other"

        setattr(measure_module, name, timed)
    t0 = time.perf_counter()
    doc = measure_module.measure_gear(sv, job.gear)
    total = time.perf_counter() - t0
    for label in STAGES.values():
        print(f"  {label:22s} {probes[label]:8d} probes {seconds[label]:8.1f} s")
    machine = sum(st.pass_times)
    print(
        f"measurement {total:.1f} s (target 10 s), with the tables {total + build:.1f} s, for {machine:.1f} s of "
        f"machine time; class {doc['iso1328']['class']['overall'] if doc['iso1328'].get('class') else '-'}"
    )


if __name__ == "__main__":
    main()
