"""Cutting passes with the dexel workpiece: the ideal motion (`skive cut`) or any sampled one, pass by pass.

Each pass's passages are the exact measurement's pass table (:class:`cutting.skiving.exact_sweep.PassTable`: the same
windows as :func:`cutting.skiving.passages.passage_range`), cut in time order in chunks (for the progress bar; the
chunks do
not change the cut: every line takes its passages in time order either way). The gear solid is made once, at the
end, from the lines' end points (:mod:`cutting.skiving.dexel_solid`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import manifold3d as mf
import numpy as np

from cutting.gear import Gear
from cutting.skiving.dexel import DexelChip, DexelWorkpiece
from cutting.skiving.dexel_lines import DexelSpacing, gear_phase
from cutting.skiving.dexel_solid import dexel_solid
from cutting.skiving.edge import CuttingEdge
from cutting.skiving.exact_sweep import PassTable, coarse_outline
from cutting.skiving.passages import Chip, CutResult, blank_window_of

#: passages cut per call (a progress step)
CHUNK = 256


@dataclass
class DexelCut:
    """A dexel cut: the result (solid and chips) and how the removal went."""

    result: CutResult
    workpiece: DexelWorkpiece
    pass_seconds: list[float] = field(default_factory=list)
    solid_seconds: float = 0.0
    land_touched: int = 0  # land rays the cut touched (cutting.skiving.dexel_solid.tube_ends)

    def summary(self) -> dict:
        """The removal's figures for measurement.json."""
        return {
            **removal_summary(self.workpiece, self.land_touched),
            "pass_seconds": [round(s, 3) for s in self.pass_seconds],
            "solid_seconds": round(self.solid_seconds, 3),
        }


def removal_summary(wp: DexelWorkpiece, land_touched: int = 0) -> dict:
    """A dexel workpiece's lines and the work its cut took; ``land_touched``: the land rays the cut touched, which the
    solid draws as uncut (cutting.skiving.dexel_solid.tube_ends)."""
    ln = wp.lines
    est, table, exact, crossings, pairs = (int(v) for v in wp.work)
    return {
        "kind": "dexel",
        "lines": ln.count,
        "rays_per_fan": ln.rays,
        "slices": ln.slices,
        "spacing_mm": {"profile": ln.spacing.profile, "face": ln.spacing.face, "fine": ln.spacing.fine},
        "line_passage_pairs": pairs,
        "estimates": est,
        "table_margins": table,
        "exact_margins": exact,
        "crossings": crossings,
        "lines_with_fins": len(wp.pieces()),
        "land_rays_touched": land_touched,
        "overflowed_lines": wp.overflowed,
    }


def chip_of(dexel: DexelChip, setup, motion, start: float = 0.0, end: float = 0.0) -> Chip:
    """The removal's :class:`Chip` of a dexel chip: cutter tooth and time at the mesh from the motion."""
    z0 = setup.cutter.teeth
    m = dexel.passage
    tm = float(motion.time_at_angle(m * 2 * math.pi / z0))
    c = dexel.centroid
    return Chip(
        dexel.pass_index,
        (-m) % z0,
        tm,
        dexel.volume,
        0,
        start,
        end,
        dexel.thickness_max,
        dexel.thickness_mean,
        dexel.contact_length,
        (float(c[0]), float(c[1]), float(c[2])),
    )


def cut_dexel(
    gear: Gear,
    edge: CuttingEdge,
    motions: Sequence,
    spacing: DexelSpacing,
    tolerance: float,
    progress: Callable[[int, int, int], None] | None = None,
) -> DexelCut:
    """Cut every pass of ``motions`` (ideal PassMotions or SampledMotions, in order) from a fresh dexel blank; the
    solid is the blank minus the spaces' tubes. ``tolerance`` [mm]: the solid's stated tolerance against the exact
    surface (reported as the cut's sweep error; the measurement checks it)."""
    wp = DexelWorkpiece.for_gear(gear, edge, spacing, phase=gear_phase(motions[0]))
    cut = DexelCut(CutResult(None), wp)
    result = cut.result
    for motion in motions:
        t0 = time.perf_counter()
        table = PassTable.build(motion, edge)
        total = len(table.m)
        points = coarse_outline(np.ascontiguousarray(edge.outline, dtype=float).tobytes(), len(edge.outline))
        for a in range(0, total, CHUNK):
            rows = table.rows(a, min(a + CHUNK, total))
            for k, dexel in enumerate(wp.cut([rows])):
                # the part of the window the tooth spends in the blank's envelope: its cutting path (tool load)
                found = blank_window_of(gear, points, rows.t[k], rows.rot[k], rows.origin[k]) if dexel.volume else None
                window = found[:2] if found is not None else (0.0, 0.0)
                result.chips.append(chip_of(dexel, motion.setup, motion, *window))
            if progress is not None:
                progress(motion.index, min(a + CHUNK, total), total)
        cut.pass_seconds.append(time.perf_counter() - t0)
        result.pass_sweep_error[motion.index] = tolerance
    result.sweep_error = tolerance
    t0 = time.perf_counter()
    result.gear, cut.land_touched = dexel_solid(wp)
    cut.solid_seconds = time.perf_counter() - t0
    if result.gear.status() != mf.Error.NoError:
        raise RuntimeError(f"the dexel solid is not valid ({result.gear.status()})")
    return cut
