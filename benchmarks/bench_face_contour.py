"""Benchmark (run on demand): the face coupling's manifold cut of three slots, fixed and eccentric setting.

    python benchmarks/bench_face_contour.py

Prints the cut's wall time per control, its chord error against the sweep tolerance and the solid's triangles
(tests/test_face_contour.py checks the same cut against the exact slot; the time is kept here, not asserted there).
"""

from __future__ import annotations

import time
from dataclasses import replace

from cutting.face_contour.slots import SWEEP_TOLERANCE, FaceCoupling, cut_slots


def main() -> None:
    coupling = FaceCoupling()
    flat = replace(coupling, control="eccentric", e=coupling.flat_bottom_eccentricity())
    cut_slots(coupling, (0,))  # compile and warm the caches: the figures below are steady
    for name, c in (("fixed", coupling), ("eccentric", flat)):
        t0 = time.perf_counter()
        cut = cut_slots(c, (0, 1, 2))
        wall = time.perf_counter() - t0
        triangles = len(cut.solid.to_mesh().tri_verts)
        print(
            f"{name:10s} three slots: {wall:5.2f} s wall ({cut.seconds:.2f} s in the cut), chord error "
            f"{cut.chord_error * 1e3:.2f} um of {SWEEP_TOLERANCE * 1e3:.1f}, {triangles} triangles"
        )


if __name__ == "__main__":
    main()
