"""Swept-volume removal: the blank minus what the cutter teeth sweep along a pose trajectory.

The stock is kept as cells: one angular sector per tooth space (twisted with the helix) cut into axial
slabs, so each subtraction involves only a cell a tooth passage reaches and the cost follows what is cut,
not the whole blank. A tooth passage is the interval in which one cutter tooth crosses the mesh zone; it
is sampled to the allowed sweep error and swept as one sub-tube per cell it reaches (:mod:`cutting.skiving.sweep`).
Cells meet in real overlaps (sectors) or in exact planes (slabs, see :func:`sector_columns`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import manifold3d as mf
import numpy as np

from cutting.flank import twist_rate
from cutting.gear import Gear
from cutting.skiving.edge import CuttingEdge
from cutting.skiving.passages import (
    Chip,
    CutResult,
    blank_window,
    engagement_half_angle,
    in_blank_envelope,
    passage_range,
    tooth_pose,
)
from cutting.skiving.solids import blank
from cutting.skiving.sweep import (
    ZippedSweep,
    kept_deviation,
    outline_points,
    sample_blocks,
    side_parts,
    simplify_keep,
    split_into,
)
from cutting.skiving.trajectory import PassMotion

#: Slab height [mm]: thinner slabs carry fewer triangles per boolean, but a passage then needs more sub-tubes,
#: whose pose ranges overlap (benchmarks/bench_cut.py --slabs measures the trade-off).
DEFAULT_SLAB = 2.0

#: Angular overlap of neighbouring sectors, as a fraction of the pitch (a few micrometres of tooth centre).
SECTOR_OVERLAP = 2e-4


class Stock:
    """The workpiece as cells: angular sectors (one per tooth space, twisted with the helix, boundaries on the
    tooth centre lines) cut into axial slabs.

    A boolean costs about 1 us per triangle of both operands, so the cells keep each operand small: a tooth
    passage meets only the few cells its path crosses, and each cell carries only the feed marks of its own
    slab. ``slab`` is the target slab height [mm].
    """

    def __init__(
        self, gear: Gear, rim: float | None = None, slab: float = DEFAULT_SLAB, sectors: Sequence[int] | None = None
    ):
        """``sectors``: the tooth spaces this stock holds (all by default); a parallel cut gives each worker a share."""
        self.gear = gear
        self.n = gear.teeth
        self.owned = frozenset(range(self.n) if sectors is None else sectors)
        solid = blank(gear, rim)
        b = gear.face_width
        r_out = (gear.root_radius + 4 * gear.mn + (rim or 0)) * 1.5 if gear.internal else gear.tip_radius * 1.5
        pitch = 2 * math.pi / self.n
        twist = math.degrees(twist_rate(gear) * b)
        self.twist_rate = twist_rate(gear)
        slabs = max(1, round(b / slab))
        self.z_edges = np.linspace(-b / 2, b / 2, slabs + 1)
        divisions = 0 if twist == 0 else max(8, int(abs(twist) / 0.5))
        self.cells: dict[tuple[int, int], mf.Manifold] = {}
        for k in sorted(self.owned):
            # tooth centre k to tooth centre k+1 (space k in the middle), overlapping the neighbours by a sliver of
            # tooth that is never cut: the final union then meets real overlaps, not two nearly coincident walls
            a0, a1 = k * pitch - SECTOR_OVERLAP * pitch, (k + 1) * pitch + SECTOR_OVERLAP * pitch
            # the apex lies behind the axis, so near the axis the sectors overlap by a real width too; from half
            # the root radius outwards the sides are the exact radii a0, a1 (the ones reached_facets() assumes)
            back, inner, mid = -0.05 * gear.root_radius, 0.5 * gear.root_radius, (a0 + a1) / 2
            corners = [
                [back * math.cos(mid), back * math.sin(mid)],
                [inner * math.cos(a0), inner * math.sin(a0)],
                [r_out * math.cos(a0), r_out * math.sin(a0)],
                [r_out * math.cos(a1), r_out * math.sin(a1)],
                [inner * math.cos(a1), inner * math.sin(a1)],
            ]
            wedge = mf.CrossSection([np.array(corners)])
            # extrude twists counter-clockwise with +z for positive degrees, like a right-hand helix
            prism = mf.Manifold.extrude(wedge, b + 2, n_divisions=divisions, twist_degrees=twist)
            prism = prism.translate((0.0, 0.0, -b / 2 - 1)).rotate(
                (0.0, 0.0, math.degrees(-self.twist_rate * (b / 2 + 1)))
            )
            sector = solid ^ prism
            for s in range(slabs):
                cell = sector
                if s > 0:
                    cell = cell.trim_by_plane((0.0, 0.0, 1.0), float(self.z_edges[s]))
                if s < slabs - 1:
                    cell = cell.trim_by_plane((0.0, 0.0, -1.0), -float(self.z_edges[s + 1]))
                self.cells[k, s] = cell
        self.volumes = {key: cell.volume() for key, cell in self.cells.items()}

    def reached_facets(
        self, verts: np.ndarray, tris: np.ndarray, sample: np.ndarray, near: np.ndarray
    ) -> dict[tuple[int, int], tuple[int, int]]:
        """For a tube's side facets (``verts`` (m, 3), ``tris`` (k, 3), each vertex's ``sample`` index and whether it
        is ``near`` the blank): each cell that a facet with a near corner can enter, with the first and last sample
        of those facets (the sub-tube between them covers all of the tube that the cell sees).

        A facet lies within the z range of its corners and, being short, within their (untwisted) angle range
        plus a small margin; a facet whose corners all stay clear of the blank cannot reach it.
        """
        tris = tris[near[tris].any(axis=1)]
        out: dict[tuple[int, int], tuple[int, int]] = {}
        if len(tris) == 0:
            return out
        pitch = 2 * math.pi / self.n
        t, z, i = self._untwisted_angle(verts)[tris], verts[:, 2][tris], sample[tris]
        margin = 1e-3 * pitch  # a short facet bulges by far less than this in angle
        k_lo = np.floor((t.min(axis=1) - margin) / pitch).astype(int)
        k_hi = np.floor((t.max(axis=1) + margin) / pitch).astype(int)
        slabs = len(self.z_edges) - 1
        s_lo = np.maximum(np.searchsorted(self.z_edges, z.min(axis=1), side="right") - 1, 0)
        s_hi = np.minimum(np.searchsorted(self.z_edges, z.max(axis=1), side="left") - 1, slabs - 1)
        i_lo, i_hi = i.min(axis=1), i.max(axis=1)
        for s in range(int(s_lo.min()), int(s_hi.max()) + 1):
            in_slab = (s_lo <= s) & (s_hi >= s)
            if not in_slab.any():
                continue
            for k in range(int(k_lo[in_slab].min()), int(k_hi[in_slab].max()) + 1):
                if k % self.n not in self.owned:
                    continue
                hit = in_slab & (k_lo <= k) & (k_hi >= k)
                if hit.any():
                    out[k % self.n, s] = (int(i_lo[hit].min()), int(i_hi[hit].max()))
        return out

    def _untwisted_angle(self, p: np.ndarray) -> np.ndarray:
        """Polar angle of points (n, 3) with the helix twist taken out, continuous around their circular mean (a
        tube or a probe spans far less than a turn): the sector boundaries are then fixed angles."""
        theta = np.arctan2(p[:, 1], p[:, 0]) - self.twist_rate * p[:, 2]
        ref = float(np.angle(np.exp(1j * theta).mean()))
        return ref + np.angle(np.exp(1j * (theta - ref)))

    def may_reach_owned(self, w: np.ndarray, near: np.ndarray, pad: float) -> bool:
        """Whether the points ``w`` (m, n, 3) marked ``near`` can come within a sector this stock owns, when each
        point moves by at most ``pad`` [mm] between the samples ``w``: a worker skips the passages that only its
        neighbours' spaces see, without sampling them finely."""
        if len(self.owned) == self.n:
            return True
        p = w[near | np.roll(near, 1, axis=1) | np.roll(near, -1, axis=1)]  # with the other corners of their facets
        if p.size == 0:
            return False
        pitch = 2 * math.pi / self.n
        theta = self._untwisted_angle(p)
        margin = 1e-3 * pitch + pad / max(float(np.hypot(p[:, 0], p[:, 1]).min()), 1e-3)
        k_lo, k_hi = math.floor((theta.min() - margin) / pitch), math.floor((theta.max() + margin) / pitch)
        return any(k % self.n in self.owned for k in range(k_lo, k_hi + 1))

    def subtract(self, tool: mf.Manifold, key: tuple[int, int]) -> float:
        """Remove ``tool`` from one cell; returns the removed volume [mm^3]."""
        cut = self.cells[key] - tool
        v = cut.volume()  # evaluates the lazy boolean
        if cut.status() != mf.Error.NoError or cut.is_empty():
            raise RuntimeError(
                f"the subtraction left cell {key} {'empty' if cut.is_empty() else cut.status()}: a swept volume "
                "reached through the sector; check the trajectory (poses far off the job's kinematics?)"
            )
        removed = self.volumes[key] - v
        self.cells[key], self.volumes[key] = cut, v
        return removed

    def triangles(self) -> int:
        return sum(cell.num_tri() for cell in self.cells.values())

    def columns(self) -> dict[int, mf.Manifold]:
        """Per owned sector the union of its slabs (:func:`sector_columns`)."""
        return sector_columns(self.cells, self.z_edges)

    def solid(self) -> mf.Manifold:
        return union_cells(self.cells, self.z_edges)


def union_cells(cells: dict[tuple[int, int], mf.Manifold], z_edges: np.ndarray) -> mf.Manifold:
    """The union of the cells: per sector its slabs (:func:`sector_columns`), then the sectors."""
    return mf.Manifold.batch_boolean(list(sector_columns(cells, z_edges).values()), mf.OpType.Add)


def sector_columns(cells: dict[tuple[int, int], mf.Manifold], z_edges: np.ndarray) -> dict[int, mf.Manifold]:
    """Per sector the union of its slabs, each evaluated into a solid of its own.

    The slabs meet in exact planes z = const: vertices that the booleans left within manifold's tolerance of a
    slab plane are put back on it first, so the union merges the faces instead of leaving a sliver void (which a
    section exactly on the plane would see as walls). Two stages, each sector's column evaluated into a solid of
    its own: one batch union of every cell (planes and sector overlaps at once) left two tunnels near the tip on a
    slab plane of a small gear (genus 2, 2 um cut), and so do nested unions left lazy, which manifold flattens into
    that same batch; the evaluated columns unite cleanly (genus 0).
    """
    planes = np.asarray(z_edges)[1:-1]
    reach = 4 * max([1e-10, *(cell.get_tolerance() for cell in cells.values())])

    def snap(v: np.ndarray) -> np.ndarray:
        v = np.array(v, dtype=float)
        near = np.abs(v[:, 2:3] - planes[None, :]) < reach
        hit = near.any(axis=1)
        v[hit, 2] = planes[np.argmax(near[hit], axis=1)]
        return v

    sectors: dict[int, list[mf.Manifold]] = {}
    for (k, _), cell in sorted(cells.items()):
        sectors.setdefault(k, []).append(cell.warp_batch(snap) if planes.size else cell)
    columns = {}
    for k, parts in sectors.items():
        column = mf.Manifold.batch_boolean(parts, mf.OpType.Add)
        # evaluate now: a lazy node would be flattened into one batch with the rest
        columns[k] = from_arrays(*to_arrays(column))
    return columns


def to_arrays(solid: mf.Manifold) -> tuple[np.ndarray, np.ndarray, float]:
    """Vertices (float64), triangles (uint64) and tolerance of a solid: fresh, writable arrays, as Mesh64 needs."""
    mesh = solid.to_mesh64()
    return (
        np.array(mesh.vert_properties, dtype=float),
        np.array(mesh.tri_verts, dtype=np.uint64),
        solid.get_tolerance(),
    )


def from_arrays(verts: np.ndarray, tris: np.ndarray, tolerance: float) -> mf.Manifold:
    return mf.Manifold(mf.Mesh64(vert_properties=verts, tri_verts=tris, tolerance=tolerance))


class PassCutter:
    """Cuts one pass passage by passage, so the cutting can follow a machine that is still moving (co-simulation).

    ``plan`` is a motion of the pass used only to plan: the engagement half angle and the outline's split (the
    ideal motion will do). Each :meth:`cut_passage` takes the motion to cut along: it must cover the passage's
    window. ``tol`` bounds the whole sweep error: the simplified outline's deviation from the edge plus the chord
    error of the point paths between poses.
    """

    def __init__(self, stock: Stock, edge: CuttingEdge, plan: PassMotion, tol: float, result: CutResult):
        self.stock, self.result = stock, result
        self.index = plan.index
        self.gear = plan.setup.gear
        self.z0 = plan.setup.cutter.teeth
        self.pitch = 2 * math.pi / self.z0  # one tooth pitch of the cutter [rad]
        self.half = engagement_half_angle(plan, edge)
        _, m_first, m_last = passage_range(plan, edge)
        # the tolerance is shared: half for the outline's polygon, the rest for the facets (chords and twist); a
        # cutter whose teeth differ keeps the vertices any tooth's simplification keeps, so that each tooth's
        # outline is the same polygon, vertex for vertex, on its own points
        teeth = edge.tooth_outlines()
        keep = np.logical_or.reduce([simplify_keep(p, tol / 2)[0] for p in (edge.outline, *teeth)])
        errs = [kept_deviation(p, keep) for p in (edge.outline, *teeth)]
        self.outline_err = max(errs)
        self.sweep_tol = tol - self.outline_err
        m_mid = (m_first + m_last) // 2
        parts = _balanced_parts(plan, edge.outline[keep], self.sweep_tol, self.near_blank, m_mid, self.half)
        self.outline = split_into(edge.outline[keep], parts)
        self.points = outline_points(self.outline)
        #: per cutter tooth its outline as swept (the same split of its own vertices) and its simplification's error
        self._teeth = [(split_into(p[keep], parts), e) for p, e in zip(teeth, errs[1:], strict=True)]
        # every passage's sampling starts from the middle passage's, shifted to its own mesh time: most intervals
        # pass at once (the same start in every worker, so the cut does not depend on how the spaces are shared)
        tm = plan.time_at_angle(m_mid * self.pitch)
        lo, hi = plan.time_at_angle(m_mid * self.pitch - self.half), plan.time_at_angle(m_mid * self.pitch + self.half)
        template = sample_blocks(tooth_pose(plan, m_mid), self.points, lo, hi, self.sweep_tol, self.near_blank)
        self.start_times = template.relative(tm)

    def near_blank(self, w: np.ndarray) -> np.ndarray:
        """Points within 0.1 mm of the blank (a facet wholly farther away cannot reach it)."""
        return in_blank_envelope(self.gear, w, 0.1)

    def window(self, m: int, motion) -> tuple[float, float]:
        """Times [s] of the passage's engagement window: the cutter within the half angle of pitch ``m``."""
        t0 = max(motion.time_at_angle(m * self.pitch - self.half), 0.0)
        t1 = min(motion.time_at_angle(m * self.pitch + self.half), motion.duration)
        return float(t0), float(t1)

    def cut_passage(self, m: int, motion) -> Chip | None:
        """Sweep and subtract the passage of cutter pitch ``m`` along ``motion``; its chip, or None if the tooth
        stays clear of the blank."""
        result, stock, pts = self.result, self.stock, self.points
        tm = motion.time_at_angle(m * self.pitch)
        j = (-m) % self.z0  # the cutter tooth at the mesh at tm
        pose = tooth_pose(motion, m)
        t0, t1 = self.window(m, motion)
        if t1 <= t0:
            return None
        found = blank_window(self.gear, pose, pts, t0, t1)
        if found is None:
            return None
        t0, t1, w_probe = found
        chip = Chip(self.index, j, float(tm), 0.0, 0, float(t0), float(t1))
        outline, outline_err = self._teeth[j] if self._teeth else (self.outline, self.outline_err)
        # a worker owning a share of the spaces samples only the passages that can reach its cells; every point
        # moves by at most ``pad`` between probes (1.5 x the longest chord, for the arc)
        pad = 1.5 * float(np.linalg.norm(np.diff(w_probe, axis=0), axis=2).max()) if len(w_probe) > 1 else 0.0
        if not stock.may_reach_owned(w_probe, in_blank_envelope(self.gear, w_probe, 0.1 + pad), pad):
            result.chips.append(chip)
            return chip
        start = [t + tm for t in self.start_times]
        sampling = sample_blocks(pose, pts, t0, t1, self.sweep_tol, self.near_blank, start)
        sweep = ZippedSweep(outline, sampling.path_times(), pose)
        verts, tris, sample, _, _ = sweep.mesh()
        vol = 0.0
        for key, (i0, i1) in stock.reached_facets(verts, tris, sample, self.near_blank(verts)).items():
            vol += stock.subtract(sweep.solid(i0, i1), key)
            result.subtractions += 1
        result.sweeps += sampling.steps
        bound = sampling.error + outline_err
        result.sweep_error = max(result.sweep_error, bound)
        result.pass_sweep_error[self.index] = max(result.pass_sweep_error.get(self.index, 0.0), bound)
        chip.volume, chip.sweeps = vol, sampling.steps
        result.chips.append(chip)
        return chip


def cut(
    stock: Stock,
    edge: CuttingEdge,
    motion: PassMotion,
    tol: float,
    result: CutResult,
    progress: Callable[[int, int], None] | None = None,
) -> None:
    """Run one pass of ``motion`` on ``stock``: every tooth passage swept to ``tol`` [mm] and subtracted."""
    cutter = PassCutter(stock, edge, motion, tol, result)
    _, m_first, m_last = passage_range(motion, edge)
    total = m_last - m_first + 1
    for count, m in enumerate(range(m_first, m_last + 1)):
        if progress is not None and count:
            progress(count, total)  # the passage before this one is done (cut, or found clear of the blank)
        cutter.cut_passage(m, motion)
    if progress is not None:
        progress(total, total)


def _balanced_parts(motion: PassMotion, outline: np.ndarray, tol: float, near, m: int, half: float) -> np.ndarray:
    """Into how many parts to split each side of the outline (:func:`cutting.skiving.sweep.split_into`): its long
    sides where that makes the tube cheapest.

    A facet's twist grows with its side's length times the time step, the chord error with the time step
    squared: long sides force short steps. Tried on the middle passage of the pass, the split that gives the
    fewest facets (sides x samples per block) is kept; a few sample_blocks calls per pass.
    """
    pose = tooth_pose(motion, m)
    pitch = 2 * math.pi / motion.setup.cutter.teeth
    lo, hi = motion.time_at_angle(m * pitch - half), motion.time_at_angle(m * pitch + half)
    best, best_cost = np.ones(len(outline), int), math.inf
    for longest in (math.inf, 2.0, 1.0, 0.5, 0.3, 0.2, 0.1):
        parts = np.ones(len(outline), int) if longest == math.inf else side_parts(outline, longest)
        try:
            cost = sample_blocks(pose, outline_points(split_into(outline, parts)), lo, hi, tol, near).quads
        except RuntimeError:
            continue
        if cost < best_cost:
            best, best_cost = parts, cost
    return best
