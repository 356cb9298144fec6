"""Benchmark (run on demand): form milling's manifold removal (cutting/form_milling/removal.py) on a helical and a
spur gear, the set-over disc mill fed along each space's screw motion (z = 20, mn = 2, b = 10, mill R 25).

    python benchmarks/bench_form_removal.py              # one helical pass, the whole helical gear, the spur gear
    python benchmarks/bench_form_removal.py --pass-only  # one helical pass only

Prints per case the kept poses, hulls, the seconds of building the moves' solids and of subtracting them, and the
total; for the whole gear the chip volume against the nominal space's (section area x face width).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from cutting.form_milling.helical import envelope_mill, helical_pass
from cutting.form_milling.removal import PATH_SHARE, cut_gear, frusta_points, pose_frames, swept_moves, thin_moves
from cutting.gear import Gear
from cutting.skiving.solids import blank

FEED = np.arange(-21.0, 21.0 + 1e-9, 0.05)  # the pass's face positions [mm]: the mill clears both faces
TOL = 0.005


def one_pass(beta: float) -> None:
    gear = Gear(teeth=20, normal_module=2.0, helix_angle=math.radians(beta), face_width=10.0)
    mill = envelope_mill(gear, 25.0)
    p = helical_pass(gear, mill, 0, FEED)
    kept = thin_moves(p, pose_frames(p), np.vstack(frusta_points(gear, mill, TOL)), TOL * PATH_SHARE)
    t0 = time.perf_counter()
    moves, hulls = swept_moves(gear, mill, p, TOL)
    tris = sum(m.num_tri() for m in moves)
    t1 = time.perf_counter()
    solid = blank(gear)
    for m in moves:
        solid = solid - m
        solid.num_tri()
    t2 = time.perf_counter()
    print(
        f"beta {beta:4.1f} deg, one pass: {len(kept)} poses kept of {len(FEED)}, {hulls} hulls in {len(moves)} moves "
        f"({tris} triangles): build {t1 - t0:.2f} s, subtract {t2 - t1:.2f} s, total {t2 - t0:.2f} s",
        flush=True,
    )


def whole_gear(beta: float) -> None:
    gear = Gear(teeth=20, normal_module=2.0, helix_angle=math.radians(beta), face_width=10.0)
    mill = envelope_mill(gear, 25.0)
    passes = [helical_pass(gear, mill, k, FEED, x) for k in range(gear.teeth) for x in (-0.1, 0.1)]
    t0 = time.perf_counter()
    res = cut_gear(gear, mill, passes, TOL)
    tris = res.gear_solid.num_tri()
    took = time.perf_counter() - t0
    removed = sum(c[2] for c in res.chips)
    print(
        f"beta {beta:4.1f} deg, whole gear ({len(passes)} passes): cut_gear {took:.1f} s "
        f"({took / len(passes):.2f} s per pass), {res.hulls} hulls, {tris} triangles; removed {removed:.1f} mm^3",
        flush=True,
    )
    t0 = time.perf_counter()  # the moves' solids alone: the rest of cut_gear is the subtractions (local stocks)
    for p in passes:
        for m in swept_moves(gear, mill, p, TOL)[0]:
            m.num_tri()
    build = time.perf_counter() - t0
    print(f"    of which the moves' solids {build:.1f} s, the subtractions {took - build:.1f} s", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--pass-only", action="store_true")
    a = ap.parse_args()
    one_pass(20.0)
    one_pass(0.0)
    if not a.pass_only:
        whole_gear(20.0)
        whole_gear(0.0)


if __name__ == "__main__":
    main()
