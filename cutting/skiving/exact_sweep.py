"""The exact swept surface of a cut: the workpiece the measurement probes for micrometre truth.

A point Q of the work frame is removed by a tooth passage if, at the instant t* at which the moving rake plane
passes through Q, Q lies inside the tooth's outline in that plane (while a tooth cuts, every point crosses its
rake plane once, in one direction: :mod:`cutting.skiving.sweep`). The workpiece is the blank minus what every passage of
every pass sweeps. Along a probe line Q(d) = P + d u, one passage removes the part where the rake-plane image
xy(d) of Q(d) lies inside the outline; the ends of that part are the roots in d of the outline's margin at
xy(d), with t*(d) solved exactly for each d. Both roots are found to 1e-9 mm, so the surface has no chord error:
it is what the kinematics (the pose function, sampled or ideal) and the edge polygon really cut.

Cost follows what can reach a line: each passage keeps a table of its poses (65 per window) and one bounding
ball per eighth of its window; a line meets only the passages whose balls it enters, the table gives every
crossing instant to within a sample and the in-plane position to ~1 um, and only the passages whose edge comes
near the line on that estimate are solved exactly.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from cutting.gear import Gear
from cutting.parallel import run_chunks
from cutting.skiving.edge import CuttingEdge
from cutting.skiving.exact_kernels import PACKED, pack_table, segment_distances, settle_lines, sweep_bounds
from cutting.skiving.exact_solve import ItemSolver, pose_table, stacked_outlines, with_rows
from cutting.skiving.passages import passage_range
from cutting.skiving.sweep import outline_points, simplify_outline
from cutting.skiving.tooling import IDENTITY, in_blank_frame
from cutting.skiving.trajectory import PassMotion

#: a line's crossing is solved to this [mm] (and the rake-plane instant to 1e-10 mm of the plane's distance)
CROSSING_TOLERANCE = 1e-9

#: samples of the pose table per passage window, and bounding balls per window (SAMPLES - 1 divisible by it)
SAMPLES = 65
SUBWINDOWS = 8

#: the compiled estimate's raster of the outline: cell, pad beyond the outline's box, band of exact distances [mm]
RASTER_CELL = 0.002
RASTER_PAD = 0.1
RASTER_BAND = 0.05
#: its error bound [mm]: bilinear lookup 0.71 cell, the pose quadratic in the table (~0.01 um) and rounding
ESTIMATE_ERROR = 0.71 * RASTER_CELL + 0.00025
#: probe-line samples: fine ones this far apart [mm] at most 129 on a line, coarse ones (every stride-th) ~25 um
FINE_STEP = 0.0025
COARSE_STEP = 0.025
#: the balls' grid cell [mm], lines per cluster and its cell [mm], and the exact items a line may leave before it
#: takes the table-wide path
GRID_CELL = 2.0
CLUSTER = 32
CLUSTER_CELL = 0.5
ITEMS_PER_LINE = 64

#: a passage whose estimated in-plane track stays this far [mm] from the outline (plus its own length) is settled
#: without solving: the estimate's error (pose between table samples ~1 um, distance field 6 um) is far below it
SETTLE_MARGIN = 0.012


@functools.lru_cache(maxsize=16)
def _outline(shape: tuple[int, ...], data: bytes) -> Outline:
    return Outline(np.frombuffer(data, dtype=float).reshape(shape))


def outline_of(points: np.ndarray) -> Outline:
    """The :class:`Outline` of an edge polygon, one per polygon: its distance raster and compiled form are made once
    for every swept volume of the same edge (the working angles make several per pass, a scipy distance transform
    each: 1.3 s of spur_external's 7.7 s before)."""
    p = np.ascontiguousarray(points, dtype=float)
    return _outline(p.shape, p.tobytes())


class Outline:
    """The edge polygon in its rake plane, as two chains monotone in x (the tooth of :mod:`cutting.skiving.edge` is
    centred on +x: the right flank and half the tip below, the left flank and the other half above), so that
    the inside test and the margin are exact for the polygon and cost a binary search.

    ``margin(x, y)`` is positive inside, negative outside and zero on the polygon, continuous (a root finder
    needs no more); :meth:`distance` is a signed distance from a raster, for estimates only.
    """

    def __init__(self, outline: np.ndarray, cell: float = 0.004, pad: float = 0.5):
        p = np.asarray(outline, dtype=float)
        i0, i1 = int(np.argmin(p[:, 0])), int(np.argmax(p[:, 0]))
        n = len(p)
        lower = p[[(i0 + k) % n for k in range((i1 - i0) % n + 1)]]  # counter-clockwise: along the bottom
        upper = p[[(i1 + k) % n for k in range((i0 - i1) % n + 1)]][::-1]
        for name, chain in (("lower", lower), ("upper", upper)):
            if np.any(np.diff(chain[:, 0]) < 0):
                raise ValueError(f"the edge outline's {name} chain is not monotone in x: not a tooth centred on +x")
        self.lower, self.upper = lower, upper
        self.x0, self.x1 = float(p[i0, 0]), float(p[i1, 0])
        self._points, self._cell, self._pad = p, cell, pad

    @cached_property
    def _raster(self) -> tuple[np.ndarray, np.ndarray]:
        """The signed distance raster of :meth:`distance` and its lower corner (built when first needed: only the
        numpy estimate reads it)."""
        p, cell, pad = self._points, self._cell, self._pad
        lo, hi = p.min(axis=0) - pad, p.max(axis=0) + pad
        nx, ny = (np.ceil((hi - lo) / cell).astype(int) + 1).tolist()
        gx, gy = np.meshgrid(lo[0] + cell * np.arange(nx), lo[1] + cell * np.arange(ny), indexing="ij")
        inside = self.margin(gx, gy) > 0
        return (ndimage.distance_transform_edt(inside) - ndimage.distance_transform_edt(~inside)) * cell, lo

    @cached_property
    def default_raster(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`exact_raster` with its defaults, made once per outline (every swept volume's compiled tables read
        it)."""
        return self.exact_raster()

    def exact_raster(
        self,
        cell: float = RASTER_CELL,
        pad: float = RASTER_PAD,
        band: float = RASTER_BAND,
        exact_within: float | None = None,
    ):
        """The signed distance [mm] on a raster of ``cell`` over the outline's box grown by ``pad``: exact at every
        node within ``band`` of the polygon, clamped to +-band beyond (a bound that keeps its side). Bilinear
        lookups are then within 0.71 cell of the truth wherever it matters. Returns (raster, lower corner).

        ``exact_within`` (< band): exact only that near; a node farther off holds a lower bound of its distance
        within 1.42 cell of the truth. The segment from a point to its nearest outline point crosses the level
        ``exact_within`` + 0.29 cell at a point whose nearest node (0.71 cell away at most) is within
        ``exact_within`` + cell, where the raster is exact: the distance is at least the Euclidean distance
        transform of those nodes plus ``exact_within`` - 0.42 cell. A lower bound keeps every certificate (steps
        and sides); a wide band costs a fraction of the exact one."""
        p = np.concatenate([self.lower, self.upper[::-1][1:-1]])  # the polygon, counter-clockwise
        lo = p.min(axis=0) - pad
        nx, ny = (np.ceil((p.max(axis=0) + pad - lo) / cell).astype(int) + 1).tolist()
        near = band if exact_within is None or exact_within >= band else exact_within
        dist = np.full((nx, ny), np.inf if near < band else float(band))  # float: a band given as int
        segment_distances(p, float(lo[0]), float(lo[1]), cell, dist, near + cell)
        if near < band:
            known = dist <= near + cell  # exact (a node that near lies in its nearest segment's box)
            half = math.sqrt(0.5) * cell  # a point's distance to its nearest node, at most
            bound = np.maximum(ndimage.distance_transform_edt(~known) * cell + near + cell - 2 * half, near + cell)
            dist = np.minimum(np.where(known, dist, bound), band)
        gy = lo[1] + cell * np.arange(ny)
        for i in range(0, nx, 256):  # the sign, row block by row block (memory)
            gx = lo[0] + cell * np.arange(i, min(i + 256, nx))
            inside = self.margin(gx[:, None], gy[None, :]) > 0
            dist[i : i + 256] = np.where(inside, dist[i : i + 256], -dist[i : i + 256])
        return dist.astype(np.float32), lo

    def margin(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        below = y - np.interp(x, self.lower[:, 0], self.lower[:, 1])
        above = np.interp(x, self.upper[:, 0], self.upper[:, 1]) - y
        return np.minimum(np.minimum(below, above), np.minimum(x - self.x0, self.x1 - x))

    def distance(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Signed distance to the polygon [mm] (+ inside) to within a raster cell; -pad beyond the raster."""
        sdf, lo = self._raster
        i = np.rint((np.asarray(x) - lo[0]) / self._cell).astype(np.int64)
        j = np.rint((np.asarray(y) - lo[1]) / self._cell).astype(np.int64)
        ok = (i >= 0) & (j >= 0) & (i < sdf.shape[0]) & (j < sdf.shape[1])
        out = np.full(np.shape(i), -self._pad)
        out[ok] = sdf[i[ok], j[ok]]
        return out


def tooth_spread(edge: CuttingEdge) -> float:
    """How far [mm] any tooth's own outline lies from the edge's (0 when every tooth cuts with it)."""
    return tooth_outlines_of(edge).spread if edge.teeth else 0.0


class ToothOutlines:
    """The outlines a cut's passages cut with: the edge's own and, when the cutter's teeth carry profile deviations
    of their own (:attr:`cutting.skiving.edge.CuttingEdge.teeth`), one per tooth: the passage of cutter pitch m is
    cut by tooth (-m) mod z0 (:meth:`cutting.skiving.kinematics.SkivingSetup.passage_frames`).

    The estimates' rasters are the edge's outline's; a tooth's polygon lies within :attr:`spread` [mm] of it (its
    vertices correspond one to one, and no point of a side lies farther from the other polygon than the farther of
    its ends), so every signed distance the rasters give is within that of the tooth's: the certificates widen by
    it.
    """

    def __init__(self, edge: CuttingEdge):
        self.edge = outline_of(edge.outline)
        teeth = edge.tooth_outlines()
        self.teeth = [outline_of(p) for p in teeth]
        #: per outline of :meth:`compiled` how far it lies from the edge's [mm], and the largest
        self.spreads = np.array([0.0, *(float(np.linalg.norm(p - edge.outline, axis=1).max()) for p in teeth)])
        self.spread = float(self.spreads.max())
        self._stacked = [self.edge, *self.teeth]

    def rows(self, m: np.ndarray) -> np.ndarray:
        """Per passage of cutter pitch ``m``, the index of its outline in :meth:`compiled`: 0 the edge's, 1 + k
        tooth k's."""
        m = np.asarray(m, dtype=np.int64)
        return 1 + (-m) % len(self.teeth) if self.teeth else np.zeros(len(m), np.int64)

    @cached_property
    def _compiled(self) -> tuple:
        return stacked_outlines(self._stacked)  # made once: the co-simulation builds a solver per passage

    def passage_spread(self, m: np.ndarray) -> np.ndarray:
        """Per passage of cutter pitch ``m``, how far its tooth's outline lies from the edge's [mm]."""
        return np.ascontiguousarray(self.spreads[self.rows(m)])

    def compiled(self, m: np.ndarray) -> tuple:
        """What the compiled margin reads for passages of cutter pitches ``m`` (in the solver's order)."""
        return with_rows(self._compiled, self.rows(m) if self.teeth else None)

    def margin(self, m: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Outline.margin of each point's passage's outline (passage of cutter pitch ``m``, broadcast with x, y)."""
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        if not self.teeth:
            return self.edge.margin(x, y)
        rows, x, y = np.broadcast_arrays(self.rows(np.atleast_1d(m)).reshape(np.shape(m)), x, y)
        out = np.empty(x.shape)
        for r in np.unique(rows):
            at = rows == r
            out[at] = self._stacked[r].margin(x[at], y[at])
        return out


#: the ToothOutlines of the last few edges (working angles make swept volumes of the same edge over and over)
_TOOTH_OUTLINES: dict[bytes, ToothOutlines] = {}


def edge_key(edge: CuttingEdge) -> bytes:
    """What tells an edge's polygons apart: its outline and each tooth's own flanks (a cache's key)."""
    teeth = (t[side].tobytes() for t in edge.teeth for side in ("left", "right"))
    return b"".join([np.ascontiguousarray(edge.outline, dtype=float).tobytes(), *teeth])


def tooth_outlines_of(edge: CuttingEdge) -> ToothOutlines:
    """The :class:`ToothOutlines` of ``edge``, one per edge's polygons (kept)."""
    key = edge_key(edge)
    if key not in _TOOTH_OUTLINES:
        if len(_TOOTH_OUTLINES) >= 8:
            _TOOTH_OUTLINES.pop(next(iter(_TOOTH_OUTLINES)))
        _TOOTH_OUTLINES[key] = ToothOutlines(edge)
    return _TOOTH_OUTLINES[key]


def tooth_frames_of(angle_or_frames: np.ndarray) -> np.ndarray:
    """Tooth frames (n, 3, 4) from themselves or from tooth angles about the cutter axis (n,) [rad]."""
    a = np.asarray(angle_or_frames, dtype=float)
    if a.ndim == 3:
        return a
    a = np.atleast_1d(a)
    out = np.zeros((len(a), 3, 4))
    c, s = np.cos(a), np.sin(a)
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1], out[:, 2, 2] = c, -s, s, c, 1.0
    return out


@dataclass
class PassTable:
    """Every tooth passage of one pass with its pose table: times (m, P), the tooth's rake frame in the blank's frame
    (rotation (m, P, 3, 3), origin (m, P, 3)) and one bounding ball per subwindow. ``tooth`` (m, 3, 4): each
    passage's rake frame in the motion's (cutter spindle) frame; ``blank`` (3, 4): the motion's (work spindle)
    frame in the blank's (:mod:`cutting.skiving.tooling`)."""

    motion: PassMotion
    m: np.ndarray
    t: np.ndarray
    rot: np.ndarray
    origin: np.ndarray
    tooth: np.ndarray
    blank: np.ndarray
    ball_centre: np.ndarray  # (m, S, 3)
    ball_radius: np.ndarray  # (m, S)
    box_centre: np.ndarray  # (m, S, 3): a box per subwindow, in the tooth frame of its middle sample
    box_axes: np.ndarray  # (m, S, 3, 3): rows are the box's axes
    box_half: np.ndarray  # (m, S, 3): half extents along them

    def __post_init__(self) -> None:
        self.normal = np.ascontiguousarray(self.rot[..., :, 2])  # the rake plane's normal (m, P, 3)
        self.offset = np.einsum("mpc,mpc->mp", self.normal, self.origin)  # its distance from the work axis origin

    @classmethod
    def build(cls, motion: PassMotion, edge: CuttingEdge) -> PassTable:
        """The passages of a skiving pass, windowed as :func:`cutting.skiving.removal.cut` windows them."""
        st = motion.setup
        z0 = st.cutter.teeth
        half, m_first, m_last = passage_range(motion, edge)
        m = np.arange(m_first, m_last + 1)
        pitch = 2 * math.pi / z0
        t0 = np.asarray(motion.time_at_angle(m * pitch - half), dtype=float)
        t1 = np.asarray(motion.time_at_angle(m * pitch + half), dtype=float)
        frames = st.passage_frames(m)
        return cls.from_windows(motion, t0, t1, frames, edge.outline, m, st.blank_frame, tooth_spread(edge))

    @classmethod
    def from_windows(
        cls,
        motion,
        t0: np.ndarray,
        t1: np.ndarray,
        tooth: np.ndarray,
        outline: np.ndarray,
        m: np.ndarray | None = None,
        blank: np.ndarray | None = None,
        spread: float = 0.0,
    ) -> PassTable:
        """Passages of any motion with ``pose(t)``: windows [t0, t1] [s], each passage's tooth frame in the motion's
        frame ((n, 3, 4), or the tooth's angle about the cutter axis (n,) [rad]) and the motion's frame in the
        blank's ((3, 4), default the same frame). ``spread``: how far the teeth's own outlines lie from ``outline``
        [mm] (:func:`tooth_spread`: the bounds grow by it)."""
        t0, t1 = np.atleast_1d(t0).astype(float), np.atleast_1d(t1).astype(float)
        tooth = tooth_frames_of(tooth)
        blank = IDENTITY if blank is None else np.asarray(blank, dtype=float)
        n = len(t0)
        t = t0[:, None] + np.linspace(0.0, 1.0, SAMPLES)[None, :] * (t1 - t0)[:, None]
        rot, origin = pose_table(motion, t.ravel()) or motion.pose(t.ravel())
        rot, origin = rot.reshape(n, SAMPLES, 3, 3), origin.reshape(n, SAMPLES, 3)
        rot, origin = in_blank_frame(rot, origin, tooth[:, None], blank)
        # balls and boxes from the outline simplified to 20 um; the margin covers that and the bulge between samples
        coarse = coarse_outline(np.ascontiguousarray(outline, dtype=float).tobytes(), len(outline))
        bounds = sweep_bounds(rot, origin, np.ascontiguousarray(coarse, dtype=float), SUBWINDOWS, 0.1 + spread)
        m = np.arange(n) if m is None else m
        return cls(motion, m, t, rot, origin, tooth, blank, *bounds)

    def rows(self, a: int, b: int) -> PassTable:
        """The passages a .. b - 1 of this table (same motion)."""
        sl = slice(a, b)
        return PassTable(
            self.motion,
            self.m[sl],
            self.t[sl],
            self.rot[sl],
            self.origin[sl],
            self.tooth[sl],
            self.blank,
            self.ball_centre[sl],
            self.ball_radius[sl],
            self.box_centre[sl],
            self.box_axes[sl],
            self.box_half[sl],
        )

    def take(self, index: np.ndarray) -> PassTable:
        """The passages ``index`` (an index array or mask) of this table (same motion)."""
        i = np.asarray(index)
        parts = (self.t, self.rot, self.origin, self.tooth)
        bounds = (self.ball_centre, self.ball_radius, self.box_centre, self.box_axes, self.box_half)
        return PassTable(self.motion, self.m[i], *(a[i] for a in parts), self.blank, *(a[i] for a in bounds))

    def exact_pose(self, passage: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The tooth frame of the passages at times t, from the motion itself."""
        rot, origin = self.motion.pose(t)
        return in_blank_frame(rot, origin, self.tooth[passage], self.blank)


@functools.lru_cache(maxsize=16)
def coarse_outline(outline: bytes, n: int) -> np.ndarray:
    """The outline simplified to 20 um, as the balls and boxes bound it (kept: a run asks for it per passage)."""
    return outline_points(simplify_outline(np.frombuffer(outline).reshape(n, 2), 0.02)[0])


class SweptVolumes:
    """The workpiece a cut leaves: the blank minus the exact swept volumes of every passage of ``motions``.

    Probed like a gear measuring machine probes a gear (:meth:`probe`, :meth:`inside`); the measurement uses it
    through the same interface as a mesh (:mod:`metrology.workpiece`).
    """

    kind = "exact swept surface"

    def __init__(
        self,
        gear: Gear,
        edge: CuttingEdge,
        motions: Sequence[PassMotion],
        rim: float | None = None,
        tables: Sequence[PassTable] | None = None,
    ):
        """``motions``: the passes as cut (ideal or sampled); or ``tables`` of passages of any motion (tests)."""
        self.gear, self.edge = gear, edge
        self.name = "exact swept surface"
        #: the outlines the passages cut with; the estimates' rasters are the edge's (certificates widen by spread)
        self.outlines = tooth_outlines_of(edge)
        self.outline = self.outlines.edge
        self._settle_margin = SETTLE_MARGIN + self.outlines.spread
        self.tables = list(tables) if tables is not None else [PassTable.build(m, edge) for m in motions]
        self.rim_radius = gear.root_radius + (3 * gear.mn if rim is None else rim)
        centres = np.concatenate([tb.ball_centre.reshape(-1, 3) for tb in self.tables])
        self._radius = np.concatenate([tb.ball_radius.ravel() for tb in self.tables])
        self._owner = np.concatenate([np.full(tb.ball_radius.size, k) for k, tb in enumerate(self.tables)])
        self._offset = np.concatenate([[0], np.cumsum([tb.ball_radius.size for tb in self.tables])])
        #: each table's first passage in the tables' numbering (the compiled solver's g)
        self._first_passage = np.concatenate([[0], np.cumsum([len(tb.m) for tb in self.tables])])
        self._tree = cKDTree(centres)
        self._compiled = _CompiledTables(self.tables, centres, self._radius, self.outline)
        #: the compiled item solve when every motion has a compiled pose (else None: the numpy path)
        self._solver = ItemSolver.build(self.tables, self._compiled.table, self.outlines)
        #: what the probes took so far: lines, (line, passage) pairs, near pairs, fine estimates, exact items,
        #: lines that took the table-wide path
        self.work = np.zeros(6, np.int64)

    # ---- the blank -------------------------------------------------------------------------------------------
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The blank's box [mm]: nothing outside it is material."""
        r = self.rim_radius if self.gear.internal else self.gear.tip_radius
        half = self.gear.face_width / 2
        return np.array([-r, -r, -half]), np.array([r, r, half])

    def in_blank(self, q: np.ndarray) -> np.ndarray:
        g = self.gear
        r = np.hypot(q[..., 0], q[..., 1])
        radial = (r >= g.tip_radius) & (r <= self.rim_radius) if g.internal else r <= g.tip_radius
        return radial & (np.abs(q[..., 2]) <= g.face_width / 2)

    def _blank_pieces(self, p: np.ndarray, u: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """The blank along each line as disjoint d intervals [lo, hi], in order (lo > hi: empty)."""
        g = self.gear
        a = u[:, 0] ** 2 + u[:, 1] ** 2
        b = 2 * (p[:, 0] * u[:, 0] + p[:, 1] * u[:, 1])
        c0 = p[:, 0] ** 2 + p[:, 1] ** 2
        axial = a < 1e-24

        def cylinder(radius: float) -> tuple[np.ndarray, np.ndarray]:
            disc = b * b - 4 * a * (c0 - radius * radius)
            root = np.sqrt(np.maximum(disc, 0.0))
            safe = np.where(axial, 1.0, a)
            lo, hi = (-b - root) / (2 * safe), (-b + root) / (2 * safe)
            lo = np.where(axial, np.where(c0 <= radius * radius, -np.inf, 1.0), np.where(disc < 0, 1.0, lo))
            hi = np.where(axial, np.where(c0 <= radius * radius, np.inf, -1.0), np.where(disc < 0, -1.0, hi))
            return lo, hi

        half = g.face_width / 2
        flat = np.abs(u[:, 2]) < 1e-12
        uz = np.where(flat, 1.0, u[:, 2])
        z1, z2 = (-half - p[:, 2]) / uz, (half - p[:, 2]) / uz
        in_faces = np.abs(p[:, 2]) <= half
        f_lo = np.where(flat, np.where(in_faces, -np.inf, 1.0), np.minimum(z1, z2))
        f_hi = np.where(flat, np.where(in_faces, np.inf, -1.0), np.maximum(z1, z2))
        if not g.internal:
            c_lo, c_hi = cylinder(g.tip_radius)
            return [(np.maximum(c_lo, f_lo), np.minimum(c_hi, f_hi))]
        o_lo, o_hi = cylinder(self.rim_radius)
        lo, hi = np.maximum(o_lo, f_lo), np.minimum(o_hi, f_hi)
        b_lo, b_hi = cylinder(g.tip_radius)  # the bore
        bore = b_lo < b_hi
        return [
            (lo, np.where(bore, np.minimum(hi, b_lo), hi)),
            (np.where(bore, np.maximum(lo, b_hi), 1.0), np.where(bore, hi, -1.0)),
        ]

    def _air_intervals(self, p: np.ndarray, u: np.ndarray, reach: float) -> tuple[np.ndarray, ...]:
        """The parts of each segment |d| <= reach outside the blank: (line, start, end)."""
        idx = np.arange(len(p))
        lines, starts, ends = [], [], []
        cursor = np.full(len(p), -reach)
        for lo, hi in self._blank_pieces(p, u):
            solid = lo < hi
            gap_end = np.where(solid, np.minimum(lo, reach), reach)
            keep = solid & (gap_end > cursor)
            lines.append(idx[keep]), starts.append(cursor[keep]), ends.append(gap_end[keep])
            cursor = np.where(solid, np.maximum(cursor, np.minimum(hi, reach)), cursor)
        keep = cursor < reach
        lines.append(idx[keep]), starts.append(cursor[keep]), ends.append(np.full(keep.sum(), reach))
        return np.concatenate(lines), np.concatenate(starts), np.concatenate(ends)

    # ---- candidates ------------------------------------------------------------------------------------------
    def _candidates(self, p: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
        """(line, ball) pairs whose ball the segment can enter (the ball index runs over every pass's balls)."""
        lines = cKDTree(p)
        pairs = lines.sparse_distance_matrix(self._tree, reach + float(self._radius.max()), output_type="ndarray")
        keep = pairs["v"] <= reach + self._radius[pairs["j"]]
        return pairs["i"][keep].astype(np.int64), pairs["j"][keep].astype(np.int64)

    # ---- one passage along many lines ------------------------------------------------------------------------
    def _events(self, tb: PassTable, passage, lo_j, hi_j, q):
        """The rake-plane crossing of the points ``q`` (k, 3) by ``passage`` (k,) within the samples [lo_j, hi_j],
        bracketed between two neighbouring samples by bisection over the table (near the tooth the plane sweeps
        a point once, in one direction): rows (point) with a crossing, the sample j before it and the exact
        plane distances g at j and j + 1."""

        def g(rows: np.ndarray, j: np.ndarray) -> np.ndarray:
            pa = passage[rows]
            return np.einsum("kc,kc->k", tb.normal[pa, j], q[rows]) - tb.offset[pa, j]

        every = np.arange(len(q))
        g_lo, g_hi = g(every, lo_j), g(every, hi_j)
        row = np.nonzero(np.sign(g_lo) * np.sign(g_hi) <= 0)[0]
        a, b, ga, gb = lo_j[row], hi_j[row], g_lo[row], g_hi[row]
        while True:
            open_ = np.nonzero(b - a > 1)[0]
            if open_.size == 0:
                break
            mid = (a[open_] + b[open_]) // 2
            gm = g(row[open_], mid)
            left = np.sign(gm) == np.sign(ga[open_])  # the crossing lies after mid
            a[open_] = np.where(left, mid, a[open_])
            ga[open_] = np.where(left, gm, ga[open_])
            b[open_] = np.where(left, b[open_], mid)
            gb[open_] = np.where(left, gb[open_], gm)
        return row, a, ga, gb

    def _solve_time(self, tb: PassTable, passage, q, j, ga, gb, iterations: int = 40):
        """t* (exact to 1e-10 mm of plane distance) by the Illinois method in [t_j, t_j+1], and the in-plane xy."""
        ta, tb_ = tb.t[passage, j].copy(), tb.t[passage, j + 1].copy()
        ga, gb = ga.copy(), gb.copy()
        t = ta.copy()
        active = np.ones(len(q), dtype=bool)
        for _ in range(iterations):
            if not active.any():
                break
            k = np.nonzero(active)[0]
            denom = gb[k] - ga[k]
            with np.errstate(divide="ignore", invalid="ignore"):
                tk = np.where(denom != 0, tb_[k] - gb[k] * (tb_[k] - ta[k]) / denom, (ta[k] + tb_[k]) / 2)
            tk = np.clip(tk, np.minimum(ta[k], tb_[k]), np.maximum(ta[k], tb_[k]))
            rot, org = tb.exact_pose(passage[k], tk)
            gk = np.einsum("kc,kc->k", rot[:, :, 2], q[k] - org)
            t[k] = tk
            same = np.sign(gk) == np.sign(gb[k])
            # Illinois: halve the stale end's value when the same end moves twice
            ga[k] = np.where(same, ga[k] / 2, gb[k])
            ta[k] = np.where(same, ta[k], tb_[k])
            tb_[k], gb[k] = tk, gk
            done = (np.abs(gk) < 1e-10) | (np.abs(tb_[k] - ta[k]) <= 1e-15 * np.maximum(1.0, np.abs(tk)))
            active[k[done]] = False
        rot, org = tb.exact_pose(passage, t)
        local = np.einsum("kji,kj->ki", rot, q - org)
        return t, local[:, 0], local[:, 1]

    def _margin_exact(self, tb: PassTable, passage, lo_j, hi_j, q) -> np.ndarray:
        """The passage's removal margin at the points q: the largest outline margin over its plane crossings in
        the samples [lo_j, hi_j] (> 0: removed); -1 where the plane does not cross a point there."""
        row, j, ga, gb = self._events(tb, passage, lo_j, hi_j, q)
        out = np.full(len(q), -1.0)
        if row.size:
            _, x, y = self._solve_time(tb, passage[row], q[row], j, ga, gb)
            np.maximum.at(out, row, self.outlines.margin(tb.m[passage[row]], x, y))
        return out

    def _estimate(self, tb: PassTable, passage, lo_j, hi_j, p, u, ds):
        """From the table alone, for segments p + d u (one per passage): the signed distance to the outline
        [mm] (raster; -pad where the plane does not cross) and the in-plane point at each d of ``ds``.

        The plane distance is linear in d at every sample, so one bisection (at the middle d that has a crossing)
        brackets the crossing for every d; the pose is taken linear between the two samples."""
        k = len(ds)
        n_lo, n_hi = tb.normal[passage, lo_j], tb.normal[passage, hi_j]
        g_lo = np.einsum("kc,kc->k", n_lo, p) - tb.offset[passage, lo_j]
        g_hi = np.einsum("kc,kc->k", n_hi, p) - tb.offset[passage, hi_j]
        lo_d = g_lo[:, None] + ds[None, :] * np.einsum("kc,kc->k", n_lo, u)[:, None]
        hi_d = g_hi[:, None] + ds[None, :] * np.einsum("kc,kc->k", n_hi, u)[:, None]
        crossing = np.sign(lo_d) * np.sign(hi_d) <= 0
        has = crossing.any(axis=1)
        # the sample of d to bisect at: the middle one if it has a crossing, else the nearest that does
        pref = np.argsort(np.abs(np.arange(k) - (k - 1) / 2), kind="stable")
        pick = pref[np.argmax(crossing[:, pref], axis=1)]
        dist = np.full((len(p), k), -self.outline._pad)
        xy = np.full((len(p), k, 2), np.nan)
        rows = np.nonzero(has)[0]
        if rows.size == 0:
            return dist, xy
        row, j, _, _ = self._events(tb, passage[rows], lo_j[rows], hi_j[rows], p[rows] + ds[pick[rows], None] * u[rows])
        rows = rows[row]
        pa = passage[rows]
        n0, n1 = tb.normal[pa, j], tb.normal[pa, j + 1]
        ga = (np.einsum("kc,kc->k", n0, p[rows]) - tb.offset[pa, j])[:, None] + ds * np.einsum("kc,kc->k", n0, u[rows])[
            :, None
        ]
        gb = (np.einsum("kc,kc->k", n1, p[rows]) - tb.offset[pa, j + 1])[:, None] + ds * np.einsum(
            "kc,kc->k", n1, u[rows]
        )[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            f = np.clip(np.where(ga != gb, ga / (ga - gb), 0.5), -1.0, 2.0)  # (rows, k)
        r0, r1 = tb.rot[pa, j], tb.rot[pa, j + 1]
        o0, o1 = tb.origin[pa, j], tb.origin[pa, j + 1]
        for c in range(k):
            fc = f[:, c]
            rot = r0 + (r1 - r0) * fc[:, None, None]
            org = o0 + (o1 - o0) * fc[:, None]
            local = np.einsum("kji,kj->ki", rot, p[rows] + ds[c] * u[rows] - org)
            cross = crossing[rows, c]  # where the plane misses the point in the balls' time range, nothing is cut
            dist[rows[cross], c] = self.outline.distance(local[cross, 0], local[cross, 1])
            xy[rows[cross], c] = local[cross, :2]
        return dist, xy

    # ---- probing -----------------------------------------------------------------------------------------------
    def _pairs(self, p: np.ndarray, reach: float):
        """Per pass table: the (line, passage) pairs whose balls a segment enters, with the range of table samples
        [lo_j, hi_j] their balls cover."""
        line_of, ball = self._candidates(p, reach)
        per = (SAMPLES - 1) // SUBWINDOWS
        for k, tb in enumerate(self.tables):
            sel = self._owner[ball] == k
            if not sel.any():
                continue
            local = ball[sel] - self._offset[k]
            key = line_of[sel] * len(tb.m) + local // SUBWINDOWS
            sub = local % SUBWINDOWS
            order = np.argsort(key, kind="stable")
            key, sub = key[order], sub[order]
            first = np.nonzero(np.r_[True, key[1:] != key[:-1]])[0]
            ukey = key[first]
            lo_j = np.minimum.reduceat(sub, first) * per
            hi_j = (np.maximum.reduceat(sub, first) + 1) * per
            yield tb, ukey // len(tb.m), ukey % len(tb.m), lo_j, hi_j

    def removed_intervals(
        self, points: np.ndarray, directions: np.ndarray, reach: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The removed parts of the segments points + d directions, |d| <= reach: (line, start, end) arrays
        (overlapping, unsorted), from every passage and from the outside of the blank."""
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        u = np.asarray(directions, dtype=float).reshape(-1, 3)
        u = u / np.linalg.norm(u, axis=1, keepdims=True)
        # samples of d: 25 um apart on a flank probe, at most 32 intervals on a long one (an axial probe through
        # the gear body, where the passages stay far from it and the estimate settles them)
        ds = np.linspace(-reach, reach, min(32, max(2, math.ceil(2 * reach / 0.025))) + 1)
        out = [[a] for a in self._air_intervals(p, u, reach)]
        for tb, li, pa, lo_j, hi_j in self._pairs(p, reach):
            for a in range(0, len(li), PAIR_CHUNK):
                s = slice(a, a + PAIR_CHUNK)
                found = self._pair_intervals(tb, li[s], pa[s], lo_j[s], hi_j[s], p, u, ds)
                for part, new in zip(out, found, strict=True):
                    part.append(new)
        return tuple(np.concatenate(part) for part in out)

    def _pair_intervals(self, tb: PassTable, li, pa, lo_j, hi_j, p, u, ds) -> tuple[np.ndarray, ...]:
        """What each passage pa removes of its line li: (line, start, end)."""
        n, k = len(li), len(ds)
        rep = np.repeat
        est, xy = self._estimate(tb, pa, lo_j, hi_j, p[li], u[li], ds)
        # the estimate's in-plane track between samples; where the plane misses a sample (the point is outside
        # the balls' time range there, so not removed) assume the fastest track a cutting tooth makes
        step = np.linalg.norm(np.diff(xy, axis=1), axis=2)
        longest = np.where(np.isfinite(step), step, 4 * (ds[1] - ds[0])).max(axis=1)
        inside = est > 0
        settled = (np.abs(est) > self._settle_margin + longest[:, None]).all(axis=1)
        settled &= (inside == inside[:, :1]).all(axis=1)
        full = np.nonzero(settled & inside[:, 0])[0]
        lines, starts, ends = [li[full]], [np.full(len(full), ds[0])], [np.full(len(full), ds[-1])]
        todo = np.nonzero(~settled)[0]
        if todo.size:
            li, pa, lo_j, hi_j = li[todo], pa[todo], lo_j[todo], hi_j[todo]
            n = len(li)
            solver = self._solver
            if solver is not None:  # compiled: the same margins and roots to rounding
                g = pa + self._first_passage[self.tables.index(tb)]
                lines_k, samples = rep(np.arange(n), k), np.tile(np.arange(k), n)
                pl, ul = p[li], u[li]
                m = solver.margins(pl, ul, ds, lines_k, rep(g, k), samples, rep(lo_j, k), rep(hi_j, k)).reshape(n, k)
            else:
                q = (p[li][:, None, :] + ds[None, :, None] * u[li][:, None, :]).reshape(-1, 3)
                m = self._margin_exact(tb, rep(pa, k), rep(lo_j, k), rep(hi_j, k), q).reshape(n, k)
            state = m > 0
            row, c = np.nonzero(state[:, :-1] != state[:, 1:])
            if solver is not None:
                root = solver.roots(
                    pl, ul, ds, row, g[row], lo_j[row], hi_j[row], c, m[row, c], m[row, c + 1], CROSSING_TOLERANCE
                )
            else:
                root = self._root(
                    tb,
                    pa[row],
                    lo_j[row],
                    hi_j[row],
                    p[li[row]],
                    u[li[row]],
                    ds[c],
                    ds[c + 1],
                    m[row, c],
                    m[row, c + 1],
                )
            # breakpoints: a removal starts at ds[0] if removed there, at each rising root; ends at each falling
            # root and at ds[-1] if removed there; per pair they alternate in d
            rising = state[row, c + 1]
            first, last = np.nonzero(state[:, 0])[0], np.nonzero(state[:, -1])[0]
            s_row = np.concatenate([first, row[rising]])
            s_d = np.concatenate([np.full(len(first), ds[0]), root[rising]])
            e_row = np.concatenate([row[~rising], last])
            e_d = np.concatenate([root[~rising], np.full(len(last), ds[-1])])
            so, eo = np.lexsort((s_d, s_row)), np.lexsort((e_d, e_row))
            lines.append(li[s_row[so]]), starts.append(s_d[so]), ends.append(e_d[eo])
        return np.concatenate(lines), np.concatenate(starts), np.concatenate(ends)

    def _root(self, tb, pa, lo_j, hi_j, p, u, d_lo, d_hi, m_lo, m_hi, iterations: int = 80) -> np.ndarray:
        """The d in [d_lo, d_hi] where the passage's margin along the line changes sign (Illinois method)."""
        d_lo, d_hi, m_lo, m_hi = d_lo.copy(), d_hi.copy(), m_lo.copy(), m_hi.copy()
        d = (d_lo + d_hi) / 2
        active = np.arange(len(pa))
        for _ in range(iterations):
            if active.size == 0:
                break
            k = active
            denom = m_hi[k] - m_lo[k]
            safe = np.where(denom != 0, denom, 1.0)
            dk = np.where(denom != 0, d_hi[k] - m_hi[k] * (d_hi[k] - d_lo[k]) / safe, (d_lo[k] + d_hi[k]) / 2)
            dk = np.clip(dk, np.minimum(d_lo[k], d_hi[k]), np.maximum(d_lo[k], d_hi[k]))
            mk = self._margin_exact(tb, pa[k], lo_j[k], hi_j[k], p[k] + dk[:, None] * u[k])
            d[k] = dk
            same = (mk > 0) == (m_hi[k] > 0)
            m_lo[k] = np.where(same, m_lo[k] / 2, m_hi[k])  # Illinois: halve the stale end
            d_lo[k] = np.where(same, d_lo[k], d_hi[k])
            d_hi[k], m_hi[k] = dk, mk
            done = (np.abs(d_hi[k] - d_lo[k]) <= CROSSING_TOLERANCE) | (np.abs(mk) <= 1e-12)
            active = k[~done]
        return d

    def probe(self, points: np.ndarray, directions: np.ndarray, reach: float) -> np.ndarray:
        """(n,) signed distance d [mm] along the unit ``directions`` (out of the material, into air) at which a
        probe coming from ``points + reach * directions`` (air) first touches material; NaN where that end is
        not in air or the segment holds no material within ``reach``."""
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        u = np.asarray(directions, dtype=float).reshape(-1, 3)
        u = u / np.linalg.norm(u, axis=1, keepdims=True)
        out = np.full(len(p), np.nan)
        for a in range(0, len(p), LINE_CHUNK):
            s = slice(a, a + LINE_CHUNK)
            line, start, end = self.settled_intervals(p[s], u[s], reach)
            out[s] = surface_from_intervals(len(p[s]), line, start, end, reach)
        return out

    def settled_intervals(self, p: np.ndarray, u: np.ndarray, reach: float) -> tuple[np.ndarray, ...]:
        """What :meth:`removed_intervals` gives where it decides the surface, from the compiled estimate (every
        pair the pose table settles within its bound) and the exact solution of the pairs it leaves."""
        n = len(p)
        ds, stride = line_samples(reach)
        air = self._air_intervals(p, u, reach)
        air_cov, solid = _segment_cover(n, ds, *air)
        items, counts, covered, flag = self._settle(p, u, ds, stride, air_cov, solid)
        i, f = np.nonzero(covered)
        whole = np.nonzero(flag == 2)[0]
        parts = [air, (i, ds[f], ds[f + 1]), (whole, np.full(len(whole), ds[0]), np.full(len(whole), ds[-1]))]
        over = np.nonzero(flag == 1)[0]
        if over.size:  # too many unsettled passages: the table-wide path for these lines
            li, s0, e0 = self.removed_intervals(p[over], u[over], reach)
            parts.append((over[li], s0, e0))
        keep = np.arange(ITEMS_PER_LINE)[None, :] < counts[:, None]
        li = np.broadcast_to(np.arange(n)[:, None], keep.shape)[keep]
        if li.size:
            parts.append(self._solve_items(p, u, ds, li, items[keep]))
        return tuple(np.concatenate([q[k] for q in parts]) for k in range(3))

    def _settle(self, p, u, ds, stride, air_cov, solid):
        """:func:`cutting.skiving.exact_kernels.settle_lines` on these lines: (items, counts, covered, flag)."""
        n, ct = len(p), self._compiled
        items = np.zeros((n, ITEMS_PER_LINE, 4), np.int64)
        counts = np.zeros(n, np.int64)
        covered = np.zeros((n, len(ds) - 1), bool)
        flag = np.zeros(n, np.int8)
        work = np.zeros((n, 3), np.int64)
        grid = (ct.grid_lo, GRID_CELL, ct.grid_dims, ct.cell_ptr, ct.cell_ball)
        per = (SAMPLES - 1) // SUBWINDOWS
        balls = (ct.centre, ct.radius, ct.ball_g, ct.ball_sub, per, ct.box_centre, ct.box_axes, ct.box_half)
        tab = (ct.table, ct.sdf, *map(float, ct.sdf_lo), RASTER_CELL, -RASTER_PAD)
        clusters = _clusters(p)
        out = (items, counts, covered, flag, work)
        n_clusters = len(clusters[0]) - 1
        delta = ESTIMATE_ERROR + self.outlines.spread
        run_chunks(settle_lines, n_clusters, p, u, ds, stride, clusters, grid, balls, tab, delta, air_cov, solid, *out)
        self.work += [n, *work.sum(axis=0), counts.sum(), (flag == 1).sum()]
        return items, counts, covered, flag

    def _solve_items(self, p, u, ds, li, items) -> tuple[np.ndarray, ...]:
        """The exact removal of each (line, passage, segment) item: the margin at both ends, the root between;
        compiled (:mod:`cutting.skiving.exact_solve`) when every motion has a compiled pose, else in numpy."""
        g, lo_j, hi_j, f = items.T
        ends = np.concatenate([f, f + 1])
        key_line, key_g, key_s = np.tile(li, 2), np.tile(g, 2), ends
        key = (key_line * (int(g.max()) + 1) + key_g) * (len(ds) + 1) + key_s  # one integer per (line, g, sample)
        _, first_of, back = np.unique(key, return_index=True, return_inverse=True)
        keys = np.stack([key_line[first_of], key_g[first_of], key_s[first_of]])
        lo2, hi2 = np.tile(lo_j, 2), np.tile(hi_j, 2)
        first = np.zeros(keys.shape[1], np.int64)
        first[back] = np.arange(len(back))
        ul, ug, us = keys
        solver = self._solver
        if solver is not None:
            margin = solver.margins(p, u, ds, ul, ug, us, lo2[first], hi2[first])
        else:
            margin = np.empty(keys.shape[1])
            table = np.searchsorted(self._compiled.first_g, ug, side="right") - 1
            for k, tb in enumerate(self.tables):
                sel = np.nonzero(table == k)[0]
                if sel.size:
                    q = p[ul[sel]] + ds[us[sel], None] * u[ul[sel]]
                    pa = ug[sel] - self._compiled.first_g[k]
                    margin[sel] = self._margin_exact(tb, pa, lo2[first[sel]], hi2[first[sel]], q)
        m = margin[back]
        m0, m1 = m[: len(li)], m[len(li) :]
        lines, starts, ends_ = [], [], []
        both = (m0 > 0) & (m1 > 0)
        lines.append(li[both]), starts.append(ds[f[both]]), ends_.append(ds[f[both] + 1])
        change = np.nonzero((m0 > 0) != (m1 > 0))[0]
        if solver is not None:
            c = change
            root = solver.roots(p, u, ds, li[c], g[c], lo_j[c], hi_j[c], f[c], m0[c], m1[c], CROSSING_TOLERANCE)
            rising = m1[c] > 0
            lines.append(li[c])
            starts.append(np.where(rising, root, ds[f[c]]))
            ends_.append(np.where(rising, ds[f[c] + 1], root))
            return np.concatenate(lines), np.concatenate(starts), np.concatenate(ends_)
        table = np.searchsorted(self._compiled.first_g, g[change], side="right") - 1
        for k, tb in enumerate(self.tables):
            sel = change[table == k]
            if sel.size == 0:
                continue
            pa = g[sel] - self._compiled.first_g[k]
            root = self._root(
                tb, pa, lo_j[sel], hi_j[sel], p[li[sel]], u[li[sel]], ds[f[sel]], ds[f[sel] + 1], m0[sel], m1[sel]
            )
            rising = m1[sel] > 0
            lines.append(li[sel])
            starts.append(np.where(rising, root, ds[f[sel]]))
            ends_.append(np.where(rising, ds[f[sel] + 1], root))
        return np.concatenate(lines), np.concatenate(starts), np.concatenate(ends_)

    def removed(self, points: np.ndarray) -> np.ndarray:
        """True where some passage sweeps the point (the blank aside): the table's estimate settles the passages
        far from the point's in-plane position; only those near the edge are solved exactly."""
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        out = np.zeros(len(p), dtype=bool)
        zero, at = np.zeros((1, 3)), np.zeros(1)
        for tb, li, pa, lo_j, hi_j in self._pairs(p, 0.0):
            for a in range(0, len(li), PAIR_CHUNK):
                s = slice(a, a + PAIR_CHUNK)
                keep = ~out[li[s]]  # a point already removed needs no more passages
                l_, pa_, lo_, hi_ = li[s][keep], pa[s][keep], lo_j[s][keep], hi_j[s][keep]
                est, _ = self._estimate(tb, pa_, lo_, hi_, p[l_], np.repeat(zero, len(l_), axis=0), at)
                est = est[:, 0]
                out[l_[est > self._settle_margin]] = True
                near = np.abs(est) <= self._settle_margin
                if near.any():
                    q, solver = p[l_[near]], self._solver
                    if solver is not None:  # compiled: the same margins to rounding
                        n = len(q)
                        g = pa_[near] + self._first_passage[self.tables.index(tb)]
                        idx = np.arange(n)
                        m = solver.margins(q, np.zeros((n, 3)), at, idx, g, np.zeros(n, np.int64), lo_[near], hi_[near])
                    else:
                        m = self._margin_exact(tb, pa_[near], lo_[near], hi_[near], q)
                    out[l_[near][m > 0]] = True
        return out

    def inside(self, points: np.ndarray) -> np.ndarray:
        """True where the point is material: in the blank and swept by no passage."""
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        out = self.in_blank(p)
        if out.any():
            out[out] = ~self.removed(p[out])
        return out


#: (line, passage) pairs handled at once: bounds the memory of the table gathers
PAIR_CHUNK = 20000
#: probe lines settled at once: bounds the memory of the items and segment flags
LINE_CHUNK = 20000


def line_samples(reach: float) -> tuple[np.ndarray, int]:
    """The samples d of a probe line |d| <= reach: fine ones FINE_STEP apart (at most 129), every stride-th of
    them a coarse one about COARSE_STEP apart."""
    coarse = max(2, math.ceil(2 * reach / COARSE_STEP))
    stride = max(1, min(math.ceil(2 * reach / coarse / FINE_STEP), 128 // coarse))
    return np.linspace(-reach, reach, coarse * stride + 1), stride


def _segment_cover(n: int, ds: np.ndarray, line: np.ndarray, start: np.ndarray, end: np.ndarray):
    """Per line and segment [d_c, d_c+1]: whether an air interval holds all of it, and whether none touches it."""
    lo, hi = ds[:-1][None, :], ds[1:][None, :]
    inside = (start[:, None] <= lo) & (end[:, None] >= hi)
    touch = (start[:, None] < hi) & (end[:, None] > lo)
    air = np.zeros((n, len(ds) - 1), bool)
    hit = np.zeros((n, len(ds) - 1), bool)
    np.logical_or.at(air, line, inside)
    np.logical_or.at(hit, line, touch)
    return air, ~hit


def _clusters(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lines in Morton order of their points' CLUSTER_CELL cells, at most CLUSTER at a time from one cell (a
    cluster stays compact: its candidates are few): (pointer, line index)."""
    q = np.minimum(np.floor((p - p.min(axis=0)) / CLUSTER_CELL), 2**21 - 1).astype(np.uint64)
    code = np.zeros(len(p), np.uint64)
    for axis in range(3):
        x = q[:, axis]
        for shift, mask in (
            (32, 0x1F00000000FFFF),
            (16, 0x1F0000FF0000FF),
            (8, 0x100F00F00F00F00F),
            (4, 0x10C30C30C30C30C3),
            (2, 0x1249249249249249),
        ):
            x = (x | (x << np.uint64(shift))) & np.uint64(mask)
        code |= x << np.uint64(axis)
    order = np.argsort(code, kind="stable")
    code = code[order]
    new_cell = np.r_[True, code[1:] != code[:-1]]
    rank = np.arange(len(p)) - np.maximum.accumulate(np.where(new_cell, np.arange(len(p)), 0))  # index in its cell
    start = np.nonzero(new_cell | (rank % CLUSTER == 0))[0]
    return np.r_[start, len(p)].astype(np.int64), order.astype(np.int64)


class _CompiledTables:
    """Every pass table's poses as one array per quantity (passage g over all passes, in order), the balls on a
    grid, and the outline's exact raster: what :func:`cutting.skiving.exact_kernels.settle_lines` reads."""

    def __init__(self, tables: Sequence[PassTable], centres: np.ndarray, radius: np.ndarray, outline: Outline):
        sizes = [len(tb.m) for tb in tables]
        self.first_g = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
        self.table = np.concatenate(
            [pack_table(tb.normal, tb.offset, tb.rot, tb.origin) for tb in tables] or [np.zeros((0, SAMPLES, PACKED))]
        )
        # the balls: passage g and subwindow of each (balls are ordered pass, passage, subwindow)
        per_table = [np.arange(tb.ball_radius.size) for tb in tables]
        self.ball_g = np.concatenate(
            [self.first_g[k] + b // SUBWINDOWS for k, b in enumerate(per_table)] or [np.zeros(0, np.int64)]
        ).astype(np.int64)
        self.ball_sub = np.concatenate([b % SUBWINDOWS for b in per_table] or [np.zeros(0, np.int64)]).astype(np.int64)
        boxes = [
            (tb.box_centre.reshape(-1, 3), tb.box_axes.reshape(-1, 3, 3), tb.box_half.reshape(-1, 3)) for tb in tables
        ]
        self.box_centre, self.box_axes, self.box_half = (
            np.ascontiguousarray(np.concatenate([b[k] for b in boxes])) if boxes else np.zeros((0, *shape))
            for k, shape in enumerate([(3,), (3, 3), (3,)])
        )
        self.centre = np.ascontiguousarray(centres if len(centres) else np.zeros((1, 3)))
        self.radius = np.ascontiguousarray(radius if len(radius) else np.zeros(1))
        lo = self.centre.min(axis=0) - GRID_CELL
        dims = np.floor((self.centre.max(axis=0) + GRID_CELL - lo) / GRID_CELL).astype(np.int64) + 1
        ijk = np.floor((self.centre - lo) / GRID_CELL).astype(np.int64)
        cell = (ijk[:, 0] * dims[1] + ijk[:, 1]) * dims[2] + ijk[:, 2]
        self.cell_ball = np.argsort(cell, kind="stable").astype(np.int64)
        self.cell_ptr = np.r_[0, np.cumsum(np.bincount(cell, minlength=int(np.prod(dims))))].astype(np.int64)
        if not len(radius):  # no passage: an empty grid
            self.cell_ball = np.zeros(0, np.int64)
            self.cell_ptr = np.zeros(int(np.prod(dims)) + 1, np.int64)
        self.grid_lo, self.grid_dims = lo, dims
        self.sdf, self.sdf_lo = outline.default_raster


def surface_from_intervals(
    n: int, line: np.ndarray, start: np.ndarray, end: np.ndarray, reach: float, gap: float = 1e-8
) -> np.ndarray:
    """The lower end of the removed (air) component that holds d = +reach of each line, from its removed
    intervals; NaN where +reach is not removed or the component reaches -reach. Intervals closer than ``gap``
    [mm] join (a material sliver thinner than that is a rounding artefact, not a burr)."""
    out = np.full(n, np.nan)
    if len(line) == 0:
        return out
    order = np.lexsort((-end, line))  # per line, by end descending
    line, start, end = line[order], start[order], end[order]
    big = 4 * reach + 1.0
    low = np.minimum.accumulate(start - line * big) + line * big  # running lowest start per line
    first = np.r_[True, line[1:] != line[:-1]]
    prev_low = np.where(first, reach, np.r_[reach, low[:-1]])
    joined = end >= prev_low - gap
    # a line's component ends at its first interval that does not join
    broken = ~joined
    seg = np.cumsum(first) - 1
    count_broken = np.cumsum(broken)
    base = np.r_[0, count_broken][np.nonzero(first)[0]][seg]
    ok = (count_broken - base) == 0
    res = np.full(n, np.inf)
    np.minimum.at(res, line[ok], start[ok])
    res[~np.isfinite(res)] = np.nan
    res[res <= -reach + gap] = np.nan
    return res
