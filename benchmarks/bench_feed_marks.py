"""What the kinematics and the edge cut, without any meshing: the exact profile left by the finishing pass.

    python benchmarks/bench_feed_marks.py                          # spur_external, conjugate, feed 0.2/0.1/0.05
    python benchmarks/bench_feed_marks.py helical_internal --edge involute --feeds 0.2 0.05

For each feed the finishing pass's exact swept volume (cutting.skiving.exact_sweep: no chord
error) is probed along the flank normals of one tooth over the measurement's profile evaluation range,
in two transverse sections (z = 0 and z = 0.07 mm, between generating lines). The deviation (transverse,
excess material positive) is evaluated like a measuring machine does: f_Halpha, f_falpha. Deviations
that shrink with the feed squared are feed marks; what stays at a small feed belongs to the edge.
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace

import numpy as np

from cutting.flank import SIDES, flank_normals, flank_points
from cutting.skiving.edge import make_edge
from cutting.skiving.exact_sweep import SweptVolumes
from cutting.skiving.trajectory import ideal_passes
from metrology.flank_lines import evaluate
from metrology.measure import MeasureOptions, profile_range
from virtual_machine.job import load_job


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("job", nargs="?", default="spur_external", help="a job of assets/jobs, or a path to a .toml")
    ap.add_argument("--edge", default="conjugate", choices=["conjugate", "involute"])
    ap.add_argument("--feeds", type=float, nargs="+", default=[0.2, 0.1, 0.05])
    ap.add_argument("--points", type=int, default=61)
    a = ap.parse_args()
    job = load_job(a.job if a.job.endswith(".toml") else f"assets/jobs/{a.job}.toml")
    g = job.gear
    l0, l1 = profile_range(g, MeasureOptions())
    roll = np.linspace(l0, l1, a.points)
    to_transverse = 1e3 / math.cos(g.base_helix_angle)  # normal offset [mm] -> base-tangent deviation [um]
    print(f"{a.job}, {a.edge} edge, finishing pass, profile roll length {l0:.3f}..{l1:.3f} mm")
    for feed in a.feeds:
        st = replace(job.skiving, axial_feed=feed)
        edge = make_edge(st, a.edge)
        t0 = time.perf_counter()
        sv = SweptVolumes(g, edge, ideal_passes(st)[-1:])
        rows = []
        for z in (0.0, 0.07):
            for side in SIDES:
                p = flank_points(g, side, roll / g.base_radius, z, 0)
                n = flank_normals(g, side, roll / g.base_radius, z, 0)
                e = sv.probe(p, n, 0.03) * to_transverse
                ev = evaluate(roll, e)
                rows.append((z, side, ev["f_H"], ev["f_f"], np.nanmin(e), np.nanmax(e)))
        for z, side, fh, ff, lo, hi in rows:
            print(
                f"  feed {feed:5.3f} mm/rev  z {z:4.2f}  {side:5s}  f_Halpha {fh:+5.2f}  f_falpha {ff:5.2f}  "
                f"excess {lo:5.2f}..{hi:5.2f} um"
            )
        print(f"  ({time.perf_counter() - t0:.0f} s)", flush=True)


if __name__ == "__main__":
    main()
