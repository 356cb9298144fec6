"""The dexel workpiece: the blank as material intervals along fixed lines, cut exactly, passage by passage.

The lines are :class:`cutting.skiving.dexel_lines.DexelLines` (fans across every tooth space, slice by slice); each
holds
the material it still has as intervals. A tooth passage, given as a row of a
:class:`cutting.skiving.exact_sweep.PassTable`
(its pose table over its window and the motion it came from, ideal or sampled), trims every line it can reach
(:func:`cutting.skiving.dexel_kernels.cut_lines`): the crossing of a line with the passage's swept region is solved
by the
exact measurement's kernels, so there is no facet and no chord error along a line. Passages are taken in the order
the machine made them, so each passage's chip is what it removed of the material the earlier ones left: volume,
centroid, chip thickness along the edge and contact length (:class:`DexelChip`), what the force model takes.

The solid (gear.stl, the recording's snapshots) is made from the lines' end points once per pass by
:mod:`cutting.skiving.dexel_solid`; the measurement probes the exact swept surface itself.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cutting.gear import Gear
from cutting.parallel import run_shared
from cutting.skiving.dexel_kernels import MAX_PIECES, OVERFLOW, STATS, cut_cells
from cutting.skiving.dexel_lines import DexelLines, DexelSpacing, LineSet
from cutting.skiving.edge import CuttingEdge
from cutting.skiving.exact_kernels import pack_table
from cutting.skiving.exact_solve import ItemSolver
from cutting.skiving.exact_sweep import CROSSING_TOLERANCE, SUBWINDOWS, PassTable, tooth_outlines_of

#: the rasters of the outline's signed distance for the march [mm]: a fine one (cell, band of exact distances) near
#: the edge, a coarse one (cell, pad: exact over all of it) beyond, so that steps far from the edge are long. An
#: estimate is within 0.71 cell + 0.25 um of the truth (bilinear lookup, the pose quadratic between table samples)
FINE_CELL, FINE_BAND = 0.002, 0.03
COARSE_CELL, COARSE_PAD = 0.016, 2.0
#: the coarse raster is exact this near the outline [mm], a lower bound within 1.42 cells farther off
COARSE_EXACT = 1.0
#: steps along a line that the estimate leaves unsure are solved exactly at this length [mm] (the measurement's)
FINE_STEP = 0.0025


@dataclass
class DexelChip:
    """What one tooth passage removed from the dexel workpiece.

    ``volume`` [mm^3]; ``centroid`` [mm] (work frame); ``thickness_max`` and ``thickness_mean`` [mm]: the uncut chip
    thickness normal to the space's nominal boundary, largest and mean over the chip's footprint along the edge;
    ``contact_length`` [mm]: the length of the space's profile (flank, root, flank) the chip covers in its widest
    slice; ``lines``: the dexel lines it cut."""

    pass_index: int
    passage: int
    volume: float
    centroid: np.ndarray
    thickness_max: float
    thickness_mean: float
    contact_length: float
    lines: int


class DexelWorkpiece:
    """A blank as dexel lines (a :class:`cutting.skiving.dexel_lines.LineSet`: a gear's fans, :meth:`for_gear`, or
    any other
       family), cut passage by passage by the motions of :class:`PassTable` rows.
    :meth:`cut` takes tables in time order and
       returns the chips; :attr:`removed` sums them; :meth:`surface` gives each line's material start (the cut
       surface seen from its fan's centre).
    """

    def __init__(self, lines: LineSet, edge: CuttingEdge):
        self.edge, self.lines = edge, lines
        origin, direction, length, entry, weight = lines.arrays
        self.p, self.u = np.ascontiguousarray(origin), np.ascontiguousarray(direction)
        self.length, self.weight, self.entry = length, np.ascontiguousarray(weight), entry
        n = len(length)
        self.mat_lo = np.zeros((n, MAX_PIECES))
        self.mat_hi = np.zeros((n, MAX_PIECES))
        self.mat_lo[:, 0], self.mat_hi[:, 0] = entry, length
        self.mat_n = (length > entry).astype(np.int64)
        self.flags = np.zeros(n, np.int64)
        #: the outlines the passages cut with; the rasters are the edge's (their deltas widen by the teeth's spread)
        self.outlines = tooth_outlines_of(edge)
        self.outline = self.outlines.edge
        fine, f_lo = self.outline.exact_raster(FINE_CELL, FINE_BAND, FINE_BAND)
        coarse, c_lo = self.outline.exact_raster(COARSE_CELL, COARSE_PAD, 2 * COARSE_PAD, COARSE_EXACT)
        w = [*f_lo, FINE_CELL, FINE_BAND, 0.71 * FINE_CELL + 0.00025]
        w += [*c_lo, COARSE_CELL, COARSE_PAD, 0.71 * COARSE_CELL + 0.00025]
        self._rasters = (fine, coarse, np.array(w, dtype=float))
        self.chips: list[DexelChip] = []
        #: raster estimates, table margins, exact margins, crossings and (line, passage) pairs tried so far
        self.work = np.zeros(5, np.int64)
        # per line of a cell: |cos| between the line and the nominal surface's normal, and its cell on it [mm]
        self._cos, self._arc_cell = lines.ray_cos, lines.ray_cell
        # a gear's fans: the rays' angles and their sense, for the kernel's choice of the rays a ball can reach
        fan = isinstance(lines, DexelLines)
        self._ray_alpha = np.ascontiguousarray(lines.alpha, dtype=float) if fan else np.zeros(0)
        self._alpha_sign = float(lines.inward) if fan else 0.0

    # ---- state -----------------------------------------------------------------------------------------------
    @classmethod
    def for_gear(
        cls, gear: Gear, edge: CuttingEdge, spacing: DexelSpacing, rim: float | None = None, phase: float = 0.0
    ):
        """The blank of ``gear`` as fans across its tooth spaces (:class:`cutting.skiving.dexel_lines.DexelLines`),
        turned by
        ``phase`` [rad] onto the spaces the motion cuts (:func:`cutting.skiving.dexel_lines.gear_phase`)."""
        return cls(DexelLines(gear, spacing, rim, phase), edge)

    @property
    def material_volume(self) -> float:
        """Material the lines hold [mm^3] (by the same quadrature as the chips)."""
        k = np.arange(MAX_PIECES)[None, :] < self.mat_n[:, None]
        lin = (self.mat_hi - self.mat_lo) * self.weight[:, :1]
        pol = (self.mat_hi**2 - self.mat_lo**2) / 2 * self.weight[:, 1:]
        return float(((lin + pol) * k).sum())

    def surface(self) -> np.ndarray:
        """Per line the distance from its fan's centre to the material holding the gear body (the start of its last
        material interval; its end if the cut took all of it) [mm]."""
        last = np.maximum(self.mat_n - 1, 0)
        rows = np.arange(len(self.mat_n))
        return np.where(self.mat_n > 0, self.mat_lo[rows, last], self.length)

    def pieces(self) -> np.ndarray:
        """Lines holding more than one material interval (a fin or pocket the cut left)."""
        return np.nonzero(self.mat_n > 1)[0]

    # ---- cutting --------------------------------------------------------------------------------------------
    def cut(self, tables: Sequence[PassTable], pass_index: Sequence[int] | None = None) -> list[DexelChip]:
        """Cut the passages of ``tables`` (in time order: table by table, passage by passage) from the lines; their
        chips, in the same order (also appended to :attr:`chips`). ``pass_index``: each table's pass (default the
        motion's ``index``)."""
        tables = [tb for tb in tables if len(tb.m)]
        if not tables:
            return []
        solver = ItemSolver.build(tables, np.zeros((0,)), self.outlines)
        if solver is None:
            raise ValueError("the dexel workpiece needs compiled poses: an ideal PassMotion or a SampledMotion")
        packed = np.ascontiguousarray(
            np.concatenate([pack_table(tb.normal, tb.offset, tb.rot, tb.origin) for tb in tables])
        )
        motion, (_, times, frames), outline = solver.motion, solver.tables, solver.outline
        ex_tables = (packed, times, frames)
        stack = [
            np.ascontiguousarray(np.concatenate([getattr(tb, name) for tb in tables]))
            for name in ("ball_centre", "ball_radius", "box_centre", "box_axes", "box_half")
        ]
        per = (tables[0].t.shape[1] - 1) // SUBWINDOWS
        # the cells (fans) each passage can reach, then per cell its passages in time order
        cell_of, g_of = [], []
        g = 0
        for tb in tables:
            for row in range(len(tb.m)):
                cells = self.lines.cells(tb.ball_centre[row], tb.ball_radius[row])
                cell_of.append(cells)
                g_of.append(np.full(len(cells), g, np.int64))
                g += 1
        cell = np.concatenate(cell_of).astype(np.int64)
        gg = np.concatenate(g_of)
        if g > 1:  # one passage (the co-simulation's usual call): cells() gives its cells sorted
            order = np.lexsort((gg, cell))
            cell, gg = cell[order], gg[order]
        first = np.ones(len(cell), bool)
        np.not_equal(cell[1:], cell[:-1], out=first[1:])
        cells = cell[first]
        cell_ptr = np.append(np.flatnonzero(first), len(cell)).astype(np.int64)
        out = np.zeros((len(cell), STATS))
        work = np.zeros((len(cells), 5), np.int64)
        tab = (packed, *self._rasters, self.outlines.passage_spread(np.concatenate([tb.m for tb in tables])))
        ln = self.lines
        run_shared(
            cut_cells,
            len(cells),
            cells,
            cell_ptr,
            gg,
            ln.rays,
            self.p,
            self.u,
            self.weight,
            self._cos,
            self._arc_cell,
            ln.dz[cells % ln.slices],
            ln.plane_normal,
            ln.plane_offset(cells),
            self._ray_alpha,
            self._alpha_sign,
            self.mat_lo,
            self.mat_hi,
            self.mat_n,
            (*stack, per),
            tab,
            motion,
            ex_tables,
            outline,
            FINE_STEP,
            CROSSING_TOLERANCE,
            out,
            self.flags,
            work,
        )
        self.work += work.sum(axis=0)
        pass_of = np.concatenate(
            [
                np.full(len(tb.m), tb.motion.index if pass_index is None else pass_index[k])
                for k, tb in enumerate(tables)
            ]
        )
        passage = np.concatenate([tb.m for tb in tables])
        chips = self._chips(cells % ln.slices, np.diff(cell_ptr), gg, out, g, pass_of, passage)
        self.chips += chips
        return chips

    def _chips(self, cell_slice, per_cell, g, out, count, pass_of, passage) -> list[DexelChip]:
        """Per passage: the sums and extremes of its (cell, passage) shares."""
        ln = self.lines
        s = np.repeat(cell_slice, per_cell)
        if count == 1:  # one passage (the co-simulation's usual call): its sums at once
            return [self._chip(out, s, pass_of[0], passage[0])]
        vol = np.bincount(g, out[:, 0], minlength=count)
        mom = np.stack([np.bincount(g, out[:, 1 + c], minlength=count) for c in range(3)], axis=1)
        t_max = np.zeros(count)
        np.maximum.at(t_max, g, out[:, 5])
        t_area = np.bincount(g, out[:, 7], minlength=count)
        t_mean = np.bincount(g, out[:, 6], minlength=count) / np.maximum(t_area, 1e-300)
        n_lines = np.bincount(g, out[:, 9], minlength=count)
        # contact length: the profile the chip covers in its widest slice (a slice's spaces summed)
        per_slice = np.bincount(g * ln.slices + s, out[:, 8], minlength=count * ln.slices)
        contact = per_slice.reshape(count, ln.slices).max(axis=1)
        chips = []
        for k in range(count):
            centroid = mom[k] / vol[k] if vol[k] > 0 else np.full(3, math.nan)
            chips.append(
                DexelChip(
                    int(pass_of[k]),
                    int(passage[k]),
                    float(vol[k]),
                    centroid,
                    float(t_max[k]),
                    float(t_mean[k]) if t_area[k] > 0 else 0.0,
                    float(contact[k]),
                    int(n_lines[k]),
                )
            )
        return chips

    def _chip(self, out: np.ndarray, s: np.ndarray, pass_index, passage) -> DexelChip:
        """The chip of one passage from its (cell, passage) shares ``out`` (cells of slices ``s``), as _chips."""
        total = out.sum(axis=0)
        vol, area = float(total[0]), float(total[7])
        return DexelChip(
            int(pass_index),
            int(passage),
            vol,
            total[1:4] / vol if vol > 0 else np.full(3, math.nan),
            float(out[:, 5].max()) if len(out) else 0.0,
            float(total[6] / area) if area > 0 else 0.0,
            float(np.bincount(s, out[:, 8]).max()) if len(out) else 0.0,
            int(total[9]),
        )

    @property
    def overflowed(self) -> int:
        """Lines that would have held more than MAX_PIECES material intervals (their smallest pieces dropped)."""
        return int((self.flags & OVERFLOW).astype(bool).sum())
