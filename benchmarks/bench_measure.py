"""Benchmark (run on demand): measuring a ~1M-triangle gear, all teeth, both flanks. Target < 5 s.

python benchmarks/bench_measure.py
"""

from __future__ import annotations

import cProfile
import math
import pstats
import sys
import time

from cutting.gear import Gear
from metrology.datum import check_mesh
from metrology.measure import measure_gear
from metrology.reference_gear import reference_gear_mesh


def main() -> None:
    gear = Gear(60, 2.0, math.radians(20), math.radians(20), 20.0, internal=True)  # helical_internal.toml
    t0 = time.perf_counter()
    mesh = reference_gear_mesh(gear, flank_points=100, helix_sagitta=2e-5)
    t_build = time.perf_counter() - t0
    t0 = time.perf_counter()
    data = check_mesh(mesh)
    t_check = time.perf_counter() - t0
    t0 = time.perf_counter()
    res = measure_gear(data, gear)
    t_measure = time.perf_counter() - t0
    print(f"gear z = {gear.teeth} internal helical, {len(mesh.faces):,} triangles (built in {t_build:.1f} s)")
    print(f"mesh check (watertight): {t_check:.2f} s")
    print(f"measure, all {gear.teeth} teeth, both flanks: {t_measure:.2f} s  (target < 5 s)")
    print(
        f"  F_alpha {res['profile']['left']['F_alpha']:.3f} um, F_beta {res['helix']['left']['F_beta']:.3f} um, "
        f"F_p {res['pitch']['left']['F_p']:.3f} um, F_r {res['runout']['F_r']:.3f} um"
    )
    if "--profile" in sys.argv:
        cProfile.runctx("measure_gear(data, gear)", globals(), locals(), "/tmp/measure.prof")
        pstats.Stats("/tmp/measure.prof").sort_stats("cumtime").print_stats(15)


if __name__ == "__main__":
    main()
