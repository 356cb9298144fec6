"""Run on demand: the working-angle maps of a job's passes (cutting.skiving.working_angles), each pass's time and
its extremes. Issue 41's bar: spur_external's four passes within 5 s (goal 1 s).

    python benchmarks/bench_working_angles.py [assets/jobs/spur_external.toml]
"""

from __future__ import annotations

import sys
import time

from cutting.skiving.edge import make_edge
from cutting.skiving.trajectory import ideal_passes
from cutting.skiving.working_angles import Relief, passage_angles
from virtual_machine.job import load_job


def main(path: str) -> None:
    st = load_job(path).skiving
    edge = make_edge(st, "conjugate")
    relief = Relief.of(st)
    motions = ideal_passes(st)
    total = time.perf_counter()
    for k in range(len(st.passes)):
        t0 = time.perf_counter()
        s = passage_angles(st, edge, relief, k, motions).summary()
        print(
            f"pass {k + 1}: {time.perf_counter() - t0:5.2f} s  rake {s['rake_min_deg']:6.1f}..{s['rake_max_deg']:5.1f} "
            f"clearance {s['clearance_min_deg']:5.2f} (engaged {s['clearance_min_engaged_deg']:6.1f}) deg  "
            f"chip <= {s['chip_thickness_max_mm'] * 1e3:5.0f} um"
        )
    print(f"all passes: {time.perf_counter() - total:.2f} s")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "assets/jobs/spur_external.toml")
