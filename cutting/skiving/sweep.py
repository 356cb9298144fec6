"""Swept volume of a cutter tooth's rake-face region between poses, as one closed manifold ("tube").

While a tooth is in the cut, every point of its rake face moves through the face's plane in one
direction (the relative velocity keeps a component along the rake-face normal of constant sign; checked
for both shipped jobs: v.n/|v| stays within 0.39..1 external, -1..-0.66 internal). The region swept by the
planar tooth outline is then bounded by the tube that its outline traces plus the outline at the first
and last pose. Between poses the tube is made of flat facets, so the error of the sweep is the sagitta of
the outline points' paths plus the twist of each facet, which :func:`sample_blocks` bounds per block of
neighbouring sides (each block at its own times); :class:`ZippedSweep` builds the tube from those times.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import manifold3d as mf
import numpy as np
from numba import njit

#: pose(t) -> (R (n, 3, 3), p (n, 3)): the cutter frame in the work frame at times t
PoseFunction = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def outline_points(outline: np.ndarray) -> np.ndarray:
    """(n, 3) rake-plane points (z = 0 in the cutter frame) of a 2D outline."""
    return np.column_stack([outline, np.zeros(len(outline))])


def place(points: np.ndarray, rot: np.ndarray, trans: np.ndarray) -> np.ndarray:
    """Points (n, 3) in every pose: shape (m, n, 3)."""
    return np.matmul(rot, points.T).transpose(0, 2, 1) + trans[:, None, :]  # batched BLAS: 10x an einsum


def place_few(points: np.ndarray, rot: np.ndarray, trans: np.ndarray) -> np.ndarray:
    """:func:`place` for a few poses and points (a passage's window, the engaged edge): compiled, where numpy's
    batched matmul costs ~100 us per call on such small operands. The same products, summed in another order (the
    values agree to rounding)."""
    return _place(
        np.ascontiguousarray(points, dtype=float),
        np.ascontiguousarray(rot, dtype=float),
        np.ascontiguousarray(trans, dtype=float),
    )


@njit(cache=True, error_model="numpy")
def _place(points, rot, trans):
    m, n = rot.shape[0], points.shape[0]
    out = np.empty((m, n, 3))
    for i in range(m):
        for j in range(n):
            x, y, z = points[j, 0], points[j, 1], points[j, 2]
            for c in range(3):
                out[i, j, c] = rot[i, c, 0] * x + rot[i, c, 1] * y + rot[i, c, 2] * z + trans[i, c]
    return out


def sample_window(
    pose: PoseFunction,
    points: np.ndarray,
    t0: float,
    t1: float,
    tol: float,
    inside: Callable[[np.ndarray], np.ndarray] | None = None,
) -> tuple[np.ndarray, float]:
    """One common grid of times in [t0, t1] for every side of the closed polygon ``points`` (the tube of
    :func:`tube`): :func:`sample_blocks` with all sides in one block. Returns the times and the bound."""
    s = sample_blocks(pose, points, t0, t1, tol, inside, block_of_side=np.zeros(len(points), dtype=int))
    return s.times[0], s.error


def tube(outline: np.ndarray, rot: np.ndarray, trans: np.ndarray) -> mf.Manifold:
    """The closed swept volume of the planar ``outline`` (CCW, star-shaped) through the poses (m >= 2): the plain
    sweep the zipped one (:class:`ZippedSweep`) is checked against."""
    n = len(outline)
    m = len(rot)
    w = place(outline_points(outline), rot, trans)
    idx = np.arange(m * n).reshape(m, n)
    nxt = np.r_[1:n, 0]
    a, b, c, d = idx[:-1, :], idx[:-1, nxt], idx[1:, :], idx[1:, nxt]
    sides = np.concatenate([np.stack([a, b, d], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])
    return _closed(w.reshape(-1, 3), sides, idx[0], idx[-1])


def _closed(verts: np.ndarray, sides: np.ndarray, first: np.ndarray, last: np.ndarray) -> mf.Manifold:
    """The solid bounded by the side triangles of a tube and two caps: fans from the centroids of the outline's
    ``first`` and ``last`` vertices (indices, in outline order)."""
    n = len(first)
    nxt = np.r_[1:n, 0]
    c0, c1 = len(verts), len(verts) + 1
    verts = np.vstack([verts, verts[first].mean(axis=0), verts[last].mean(axis=0)])
    tris = np.concatenate(
        [
            sides,
            np.stack([np.full(n, c0), first[nxt], first], -1),  # start cap
            np.stack([np.full(n, c1), last, last[nxt]], -1),  # end cap
        ]
    )
    tri = verts[tris]
    volume = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6
    if volume < 0:  # the outline moved against the cap orientation: flip to outward normals
        tris = tris[:, ::-1]
    # double precision: a float32 mesh sets manifold's tolerance to ~1e-7 of the part's size, and the booleans
    # may then move vertices by that much (enough to open slits where cells meet in a plane)
    mesh = mf.Mesh64(
        vert_properties=np.ascontiguousarray(verts, dtype=float),
        tri_verts=np.ascontiguousarray(tris, dtype=np.uint64),
    )
    solid = mf.Manifold(mesh)
    if solid.status() != mf.Error.NoError:
        raise RuntimeError(
            f"the swept volume is not a manifold ({solid.status()}): the rake face moved back "
            "through itself; sample the window more finely"
        )
    return solid


def simplify_outline(outline: np.ndarray, tol: float) -> tuple[np.ndarray, float]:
    """Fewest vertices of the closed polygon ``outline`` that keep every dropped vertex within ``tol`` [mm].

    Douglas-Peucker on each half (split at the vertex farthest from the first one), so the sweep costs
    triangles only where the edge bends. Returns the simplified outline and the largest deviation left.
    """
    keep, worst = simplify_keep(outline, tol)
    return outline[keep], worst


def simplify_keep(outline: np.ndarray, tol: float) -> tuple[np.ndarray, float]:
    """:func:`simplify_outline`'s kept vertices (a mask) and the largest deviation left."""
    n = len(outline)
    far = int(np.argmax(np.linalg.norm(outline - outline[0], axis=1)))
    keep = np.zeros(n, dtype=bool)
    keep[[0, far]] = True
    closed = np.vstack([outline, outline[:1]])
    stack = [(0, far), (far, n)]
    worst = 0.0
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        a, b = closed[i], closed[j]
        seg = b - a
        p = closed[i + 1 : j] - a
        cross = np.abs(seg[0] * p[:, 1] - seg[1] * p[:, 0]) / max(float(np.linalg.norm(seg)), 1e-300)
        k = int(np.argmax(cross))
        if cross[k] > tol:
            keep[i + 1 + k] = True
            stack += [(i, i + 1 + k), (i + 1 + k, j)]
        else:
            worst = max(worst, float(cross[k]))
    return keep, worst


def kept_deviation(outline: np.ndarray, keep: np.ndarray) -> float:
    """The largest distance [mm] of a vertex of the closed polygon ``outline`` that ``keep`` drops from the line
    through the kept vertices either side of it (as :func:`simplify_keep` measures it): the same simplification
    of another outline, vertex for vertex (a cutter tooth's own), and what it leaves."""
    kept = np.flatnonzero(keep)
    n = len(outline)
    before = kept[np.searchsorted(kept, np.arange(n), side="right") - 1]  # the kept vertex at or before each
    after = np.append(kept, kept[0] + n)[np.searchsorted(kept, np.arange(n), side="right")] % n
    a, b = outline[before], outline[after]
    seg, p = b - a, outline - a
    cross = np.abs(seg[:, 0] * p[:, 1] - seg[:, 1] * p[:, 0]) / np.maximum(np.linalg.norm(seg, axis=1), 1e-300)
    return float(cross[~keep].max()) if (~keep).any() else 0.0


def split_sides(outline: np.ndarray, longest: float) -> np.ndarray:
    """The closed polygon with every side longer than ``longest`` [mm] cut into equal parts (same shape)."""
    return split_into(outline, side_parts(outline, longest))


def side_parts(outline: np.ndarray, longest: float) -> np.ndarray:
    """Into how many equal parts :func:`split_sides` cuts each side (side i joins vertex i and i + 1)."""
    nxt = np.roll(outline, -1, axis=0)
    return np.maximum(1, np.ceil(np.linalg.norm(nxt - outline, axis=1) / longest)).astype(int)


def split_into(outline: np.ndarray, parts: np.ndarray) -> np.ndarray:
    """The closed polygon with side i cut into ``parts[i]`` equal parts."""
    nxt = np.roll(outline, -1, axis=0)
    return np.vstack([a + (b - a) * (np.arange(k)[:, None] / k) for a, b, k in zip(outline, nxt, parts, strict=True)])


#: outline sides per block: each block of neighbouring sides is sampled at its own times
BLOCK_SIDES = 8


def blocks_of(n: int, size: int = BLOCK_SIDES) -> np.ndarray:
    """Block index of each of ``n`` sides: contiguous runs of about ``size`` sides."""
    count = max(1, round(n / size))
    return np.minimum((np.arange(n) * count) // n, count - 1)


@dataclass
class BlockSampling:
    """Sample times of a tooth passage per block of outline sides (side i joins point i and point i + 1).

    The facets a side needs depend on how fast and how curved its points move where they can touch the
    workpiece: the sides in the blank need about 160 steps at 0.5 um, the hub chord inside the cutter 7 (measured
    on spur_external). Giving each block of neighbouring sides its own times halves the facets of one common
    grid. A vertex path (one outline point through the passage) carries the times of both sides it belongs to,
    so where two blocks meet the strips are zipped (:class:`ZippedSweep`).
    """

    block_of_side: np.ndarray  # (n,) block index of every side
    times: list[np.ndarray]  # per block: sorted sample times [s], all from t0 to t1
    error: float  # the largest deviation left where a facet can touch the workpiece [mm]

    @property
    def quads(self) -> int:
        """Side x step facets of the tube before zipping."""
        return int(sum((len(t) - 1) * int((self.block_of_side == b).sum()) for b, t in enumerate(self.times)))

    @property
    def steps(self) -> int:
        """Steps of the most finely sampled block."""
        return max(len(t) - 1 for t in self.times)

    def path_times(self) -> list[np.ndarray]:
        """Per outline point: the times of its two sides' blocks (their union where the blocks differ)."""
        own, prev = self.block_of_side, np.roll(self.block_of_side, 1)
        times = self.times
        return [times[a] if a == b else np.union1d(times[a], times[b]) for a, b in zip(own, prev, strict=True)]

    def relative(self, origin: float) -> list[np.ndarray]:
        """The block times relative to ``origin`` (a warm start for a similar passage)."""
        return [t - origin for t in self.times]


def sample_blocks(
    pose: PoseFunction,
    points: np.ndarray,
    t0: float,
    t1: float,
    tol: float,
    inside: Callable[[np.ndarray], np.ndarray] | None = None,
    start: list[np.ndarray] | None = None,
    block_of_side: np.ndarray | None = None,
    rounds: int = 16,
) -> BlockSampling:
    """Times in [t0, t1] per block of sides such that the tube through the closed polygon ``points`` deviates
    from the exact sweep of that polygon by at most ``tol`` [mm] wherever a facet can touch the workpiece.

    Per interval of each block and only where a facet has a corner ``inside``, two deviations are checked: each
    side's end points at mid-interval against their chords (the sagitta), and the side's true midpoint at
    mid-interval against the quad's two facets split along a-d, along their normal (the twist). A failing
    interval is split into ceil(sqrt(dev / tol)) parts. ``start`` gives initial times per block (a similar
    passage's, shifted: most intervals then pass in the first round); by default 8 even samples.
    """
    n = len(points)
    blk = blocks_of(n) if block_of_side is None else np.asarray(block_of_side)
    nb = int(blk.max()) + 1
    width = int(np.bincount(blk).max())
    # every block's sides, padded to ``width`` by repeating its last side (which changes no maximum)
    sides = np.zeros((nb, width), dtype=int)
    for b in range(nb):
        own = np.nonzero(blk == b)[0]
        sides[b] = np.r_[own, np.full(width - len(own), own[-1])]
    p0, p1 = points[sides], points[(sides + 1) % n]
    corners = np.concatenate([p0, p1, (p0 + p1) / 2], axis=1).transpose(0, 2, 1)  # (nb, 3, 3 width)
    if start is None:
        grids = [np.linspace(t0, t1, 8)] * nb
    else:
        grids = [np.unique(np.r_[t0, np.clip(s, t0, t1), t1]) for s in start]
    ib = np.concatenate([np.full(len(g) - 1, b) for b, g in enumerate(grids)])
    ta = np.concatenate([g[:-1] for g in grids])
    tb = np.concatenate([g[1:] for g in grids])
    done: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    worst = 0.0
    for _ in range(rounds):
        k = len(ta)
        u, inv = np.unique(np.concatenate([ta, tb, (ta + tb) / 2]), return_inverse=True)
        rot, trans = pose(u)

        def at(idx: np.ndarray) -> np.ndarray:
            # every interval's points placed at one of its times: (k, 3 width, 3)
            return (np.matmul(rot[idx], corners[ib]) + trans[idx][:, :, None]).transpose(0, 2, 1)  # noqa: B023

        wa, wb, wm = at(inv[:k]), at(inv[k : 2 * k]), at(inv[2 * k :])
        a, b = wa[:, :width], wa[:, width : 2 * width]
        c, d = wb[:, :width], wb[:, width : 2 * width]
        chord = np.maximum(
            np.linalg.norm(wm[:, :width] - (a + c) / 2, axis=2),
            np.linalg.norm(wm[:, width : 2 * width] - (b + d) / 2, axis=2),
        )
        normal = np.cross(d - a, b - c)
        normal /= np.maximum(np.linalg.norm(normal, axis=2, keepdims=True), 1e-300)
        twist = np.abs(((wm[:, 2 * width :] - (a + d) / 2) * normal).sum(axis=2))
        dev = np.maximum(chord, twist)
        if inside is not None:
            dev = np.where(inside(a) | inside(b) | inside(c) | inside(d), dev, 0.0)
        dev = dev.max(axis=1)
        ok = dev <= tol
        done.append((ib[ok], ta[ok], tb[ok]))
        if ok.any():
            worst = max(worst, float(dev[ok].max()))
        if ok.all():
            break
        bad = np.nonzero(~ok)[0]
        parts = np.ceil(np.sqrt(dev[bad] / tol) * 1.05).astype(int)
        owner = np.repeat(bad, parts)
        j = np.arange(parts.sum()) - np.repeat(np.cumsum(parts) - parts, parts)  # 0 .. parts - 1 in each
        p = np.repeat(parts, parts)
        lo, hi = ta[owner], tb[owner]
        # the same expression for the end of part j and the start of part j + 1: the parts tile exactly
        ta, tb = np.where(j == 0, lo, lo + (hi - lo) * j / p), np.where(j == p - 1, hi, lo + (hi - lo) * (j + 1) / p)
        ib = ib[owner]
    else:
        raise RuntimeError(f"the trajectory could not be sampled to a sweep error of {tol * 1e3:.2f} um")
    all_b, all_a, all_t = (np.concatenate(x) for x in zip(*done, strict=True))
    times = [np.unique(np.r_[all_a[all_b == b], all_t[all_b == b]]) for b in range(nb)]
    return BlockSampling(blk, times, worst)


class ZippedSweep:
    """The tube of one tooth passage from vertex paths sampled at their own times.

    The strip between two neighbouring paths is triangulated by merging their times (a zipper): where both paths
    share a time it is the quad split along a-d of :func:`tube`; where one path has extra samples they fan out
    from the other path's vertex. Within one block's interval the fan stays between the two quad triangles'
    bilinear patch, so the block's error bound holds. The poses are evaluated once for all paths.
    """

    def __init__(self, outline: np.ndarray, paths: list[np.ndarray], pose: PoseFunction):
        self.outline = outline
        self.points = outline_points(outline)
        self.grid = np.unique(np.concatenate(paths))
        self.rot, self.trans = pose(self.grid)
        # every path's samples as indices into the grid, all paths in one array
        self.counts = np.array([len(p) for p in paths])
        self.index = np.searchsorted(self.grid, np.concatenate(paths))

    def mesh(self, lo: int | None = None, hi: int | None = None):
        """Vertices (m, 3), side triangles (k, 3), the grid index of every vertex, and each path's first vertex and
        vertex count, of the tube between grid samples ``lo`` and ``hi`` (every path cut there, with a vertex
        inserted at both ends)."""
        n, counts, g = len(self.counts), self.counts, self.index
        offset = np.r_[0, np.cumsum(counts)[:-1]]
        if lo is not None:
            # each path keeps its samples strictly between lo and hi (a contiguous run: paths are sorted) and gets
            # lo and hi as its ends
            start = offset + np.add.reduceat((g <= lo).astype(int), offset)
            stop = offset + np.add.reduceat((g < hi).astype(int), offset)
            inner = stop - start
            counts = inner + 2
            offset = np.r_[0, np.cumsum(counts)[:-1]]
            k = np.arange(counts.sum()) - np.repeat(offset, counts)  # position within the new path
            src = np.repeat(start, counts) + k - 1
            g = np.where(k == 0, lo, np.where(k == np.repeat(counts, counts) - 1, hi, g[np.clip(src, 0, len(g) - 1)]))
        q = np.repeat(np.arange(n), counts)
        verts = np.matmul(self.rot[g], self.points[q][:, :, None])[:, :, 0] + self.trans[g]
        # zipper: per strip i (paths i and i + 1) the later samples of both paths in time order; on a tie the
        # B path (i + 1) first, which splits a common quad along a-d
        tail = np.ones(len(g), dtype=bool)
        tail[offset] = False  # every sample but a path's first is an event of two strips
        strip_a = q[tail]  # as path A (its own strip)
        strip_b = (q[tail] - 1) % n  # as path B (the strip before it)
        time = g[tail]
        strip = np.r_[strip_a, strip_b]
        is_a = np.r_[np.ones(len(strip_a), dtype=bool), np.zeros(len(strip_b), dtype=bool)]
        order = np.lexsort((is_a, np.r_[time, time], strip))
        strip, is_a = strip[order], is_a[order]
        first = np.searchsorted(strip, np.arange(n))  # each strip's first event
        cum_a = np.cumsum(is_a) - is_a  # A events before this one (all strips)
        cum_b = np.cumsum(~is_a) - ~is_a
        nxt = np.r_[1:n, 0]
        a_cur = offset[strip] + cum_a - cum_a[first][strip]
        b_cur = offset[nxt][strip] + cum_b - cum_b[first][strip]
        # a B event closes (A, B, B+1), an A event (A, B, A+1): on a common quad a-b-d and a-d-c as in tube()
        tris = np.stack([a_cur, b_cur, np.where(is_a, a_cur + 1, b_cur + 1)], -1)
        return verts, tris, g, offset, counts

    def solid(self, lo: int | None = None, hi: int | None = None) -> mf.Manifold:
        """The closed tube between grid samples ``lo`` and ``hi`` (all of it by default)."""
        verts, tris, _, first, counts = self.mesh(lo, hi)
        return _closed(verts, tris, first, first + counts - 1)
