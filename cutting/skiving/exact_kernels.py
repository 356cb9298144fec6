"""Compiled kernels of the exact swept surface (numba): which passages can change what a probe line meets.

The measurement probes some 10^5 lines, and each line passes near some 200 tooth passages; per (line, passage)
pair the work is a few dozen flops in an irregular pattern (a bisection over the pose table, a quadratic
interpolation, a raster lookup) that numpy can only vectorise through large temporaries. These kernels do it per
line, in parallel over clusters of nearby lines, and settle every pair the pose table can settle with a proven
bound; :mod:`cutting.skiving.exact_sweep` then solves only the rest exactly, with the motion itself.

A pair's state on a segment [d_c, d_c+1] of the line: NOT (the passage removes nothing of it), REMOVED (all of it),
UNSURE. The estimate of the signed distance e of the line's in-plane point to the edge outline is within
``delta`` of the truth (raster: 0.71 cell, bilinear on exact node distances; pose: quadratic in the table); the
signed distance is 1-Lipschitz in the plane, so along a segment whose in-plane track is ``step`` long it stays
above (e0 + e1 - step) / 2 - delta and below (e0 + e1 + step) / 2 + delta.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from cutting.borrowed import borrowed
from cutting.parallel import run_chunks

NOT, UNSURE, REMOVED = 0, 1, 2

#: the in-plane track between two samples may bow: its chord is lengthened by this factor
TRACK_BOW = 1.05
#: floats per packed table sample
PACKED = 16
#: fast-math flags for the estimate: reassociation and contraction only (no assumption about inf or NaN)
FAST = {"contract", "arcp", "reassoc", "nsz"}


@njit(cache=True)
def segment_distances(poly: np.ndarray, lo0: float, lo1: float, cell: float, out: np.ndarray, band: float) -> None:
    """Unsigned distance from each raster node to the closed polygon ``poly`` (m, 2), exact within ``band`` [mm]
    of it (``out`` keeps its value, e.g. inf, farther away)."""
    m = poly.shape[0]
    nx, ny = out.shape
    for k in range(m):
        ax, ay = poly[k, 0], poly[k, 1]
        bx, by = poly[(k + 1) % m, 0], poly[(k + 1) % m, 1]
        ex, ey = bx - ax, by - ay
        ll = ex * ex + ey * ey
        i0 = max(0, math.floor((min(ax, bx) - band - lo0) / cell))
        i1 = min(nx - 1, math.ceil((max(ax, bx) + band - lo0) / cell))
        j0 = max(0, math.floor((min(ay, by) - band - lo1) / cell))
        j1 = min(ny - 1, math.ceil((max(ay, by) + band - lo1) / cell))
        for i in range(i0, i1 + 1):
            x = lo0 + i * cell
            for j in range(j0, j1 + 1):
                y = lo1 + j * cell
                s = 0.0 if ll == 0.0 else ((x - ax) * ex + (y - ay) * ey) / ll
                s = min(1.0, max(0.0, s))
                dx, dy = x - ax - s * ex, y - ay - s * ey
                d = math.sqrt(dx * dx + dy * dy)
                if d < out[i, j]:
                    out[i, j] = d


@njit(cache=True, inline="always", error_model="numpy", fastmath=FAST)
def _sdf(sdf: np.ndarray, lo0: float, lo1: float, cell: float, far: float, x: float, y: float) -> float:
    fx, fy = (x - lo0) / cell, (y - lo1) / cell
    i, j = math.floor(fx), math.floor(fy)
    if i < 0 or j < 0 or i >= sdf.shape[0] - 1 or j >= sdf.shape[1] - 1:
        return far
    a, b = fx - i, fy - j
    return (1 - a) * ((1 - b) * sdf[i, j] + b * sdf[i, j + 1]) + a * ((1 - b) * sdf[i + 1, j] + b * sdf[i + 1, j + 1])


@njit(cache=True, inline="always", error_model="numpy", fastmath=FAST)
def _plane(table: np.ndarray, g: int, j: int, q0: float, q1: float, q2: float) -> float:
    return table[g, j, 0] * q0 + table[g, j, 1] * q1 + table[g, j, 2] * q2 - table[g, j, 3]


@njit(cache=True, inline="always", error_model="numpy", fastmath=FAST)
def in_plane(table, g, lo, hi, q0, q1, q2):
    """Where the rake plane of passage g crosses the point q within the table samples [lo, hi]: (ok, x, y) in the
    tooth frame; the crossing bracketed by bisection over the table, then the pose quadratic in time through
    three samples and the crossing solved on that quadratic (error ~ r dphi^3, some 0.01 um). ``table`` (m, P,
    PACKED) as :func:`pack_table` packs it."""
    npose = table.shape[1]
    ga = _plane(table, g, lo, q0, q1, q2)
    gb = _plane(table, g, hi, q0, q1, q2)
    if (ga > 0 and gb > 0) or (ga < 0 and gb < 0):
        return False, 0.0, 0.0
    a, b = lo, hi
    while b - a > 1:
        mid = (a + b) // 2
        gm = _plane(table, g, mid, q0, q1, q2)
        if (gm > 0) == (ga > 0) and (gm < 0) == (ga < 0):
            a, ga = mid, gm
        else:
            b, gb = mid, gm
    if b == a:  # lo == hi: the point lies in that sample's plane
        b = min(a + 1, npose - 1)
        a = b - 1
        ga = _plane(table, g, a, q0, q1, q2)
        gb = _plane(table, g, b, q0, q1, q2)
    # three nodes: a - 1, a, a + 1 (positions -1, 0, 1) or a, a + 1, a + 2 (0, 1, 2)
    n0 = a - 1 if a >= 1 else a
    gn0 = _plane(table, g, n0, q0, q1, q2) if n0 != a else ga
    gn1 = ga if n0 != a else gb
    gn2 = gb if n0 != a else _plane(table, g, min(a + 2, npose - 1), q0, q1, q2)
    shift = 1.0 if n0 != a else 0.0  # f (0..1 between a and a + 1) -> s = f + shift on nodes at s = 0, 1, 2
    f = ga / (ga - gb) if ga != gb else 0.5
    s = f + shift
    for _ in range(3):  # Newton on the quadratic through the three plane distances
        w0, w1, w2 = (s - 1) * (s - 2) / 2, -s * (s - 2), s * (s - 1) / 2
        d0, d1, d2 = s - 1.5, 2 - 2 * s, s - 0.5
        val = w0 * gn0 + w1 * gn1 + w2 * gn2
        der = d0 * gn0 + d1 * gn1 + d2 * gn2
        if der == 0.0:
            break
        s = min(max(s - val / der, shift - 0.25), shift + 1.25)
    w0, w1, w2 = (s - 1) * (s - 2) / 2, -s * (s - 2), s * (s - 1) / 2
    j0, j1, j2 = n0, n0 + 1, min(n0 + 2, npose - 1)
    x = 0.0
    y = 0.0
    for c in range(3):
        o = w0 * table[g, j0, 10 + c] + w1 * table[g, j1, 10 + c] + w2 * table[g, j2, 10 + c]
        qc = (q0 if c == 0 else (q1 if c == 1 else q2)) - o
        x += (w0 * table[g, j0, 4 + c] + w1 * table[g, j1, 4 + c] + w2 * table[g, j2, 4 + c]) * qc
        y += (w0 * table[g, j0, 7 + c] + w1 * table[g, j1, 7 + c] + w2 * table[g, j2, 7 + c]) * qc
    return True, x, y


def pack_table(normal: np.ndarray, offset: np.ndarray, rot: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """Per passage and sample, what :func:`in_plane` reads, side by side (PACKED floats: two cache lines): the
    rake plane's normal and offset, the tooth frame's x and y axes, its origin."""
    out = np.zeros((*offset.shape, PACKED))
    out[..., 0:3], out[..., 3] = normal, offset
    out[..., 4:7], out[..., 7:10], out[..., 10:13] = rot[..., :, 0], rot[..., :, 1], origin
    return out


@njit(cache=True, inline="always", error_model="numpy", fastmath=FAST)
def _classify(ok0, e0, x0, y0, ok1, e1, x1, y1, delta, lost_step):
    if not ok0 and not ok1:
        return NOT
    if not (ok0 and ok1):  # the plane leaves the balls' time range: assume the fastest track a tooth makes
        e = e0 if ok0 else e1
        return NOT if e + lost_step < -delta else UNSURE
    step = TRACK_BOW * math.sqrt((x1 - x0) ** 2 + (y1 - y0) ** 2)
    if (e0 + e1 - step) / 2 > delta:
        return REMOVED
    if (e0 + e1 + step) / 2 < -delta:
        return NOT
    return UNSURE


@njit(cache=True, inline="always", error_model="numpy", fastmath=FAST)
def _estimate(tab, g, lo, hi, p, u, i, d):
    """(crossed, e, x, y): the estimated signed distance e of the point p_i + d u_i to the outline in passage g's
    rake plane, and its in-plane position; ``tab`` = (packed table, sdf, sdf_lo0, sdf_lo1, cell, far)."""
    table, sdf, lo0, lo1, cell, far = tab
    q0, q1, q2 = p[i, 0] + d * u[i, 0], p[i, 1] + d * u[i, 1], p[i, 2] + d * u[i, 2]
    ok, x, y = in_plane(table, g, lo, hi, q0, q1, q2)
    e = _sdf(sdf, lo0, lo1, cell, far, x, y) if ok else far
    return ok, e, x, y


@njit(cache=True, error_model="numpy", fastmath=FAST)
def _cluster_balls(p, lines, reach, grid, balls):
    """The balls (sorted by index) that some segment of the cluster ``lines`` can enter, their boxes too: from the
    grid's cells around the cluster's bounding ball."""
    grid_lo, grid_cell, grid_dims, cell_ptr, cell_ball = grid
    centre_b, radius_b, box_centre, box_axes, box_half = balls
    centre = np.zeros(3)
    for i in lines:
        centre += p[i]
    centre /= len(lines)
    rc = 0.0
    for i in lines:
        rc = max(rc, math.sqrt(((p[i] - centre) ** 2).sum()))
    rc += reach
    rmax = radius_b.max()
    lo_i = np.empty(3, np.int64)
    hi_i = np.empty(3, np.int64)
    for a in range(3):
        lo_i[a] = max(0, math.floor((centre[a] - rc - rmax - grid_lo[a]) / grid_cell))
        hi_i[a] = min(grid_dims[a] - 1, math.floor((centre[a] + rc + rmax - grid_lo[a]) / grid_cell))
    if hi_i[0] < lo_i[0] or hi_i[1] < lo_i[1] or hi_i[2] < lo_i[2]:
        return np.zeros(0, np.int64)
    total = 0
    for ix in range(lo_i[0], hi_i[0] + 1):
        for iy in range(lo_i[1], hi_i[1] + 1):
            base = (ix * grid_dims[1] + iy) * grid_dims[2]
            total += cell_ptr[base + hi_i[2] + 1] - cell_ptr[base + lo_i[2]]
    cand = np.empty(total, np.int64)
    nc = 0
    for ix in range(lo_i[0], hi_i[0] + 1):
        for iy in range(lo_i[1], hi_i[1] + 1):
            base = (ix * grid_dims[1] + iy) * grid_dims[2]
            for k in range(cell_ptr[base + lo_i[2]], cell_ptr[base + hi_i[2] + 1]):
                b = cell_ball[k]
                lim = rc + radius_b[b]
                if ((centre_b[b] - centre) ** 2).sum() > lim * lim:
                    continue
                # the cluster's ball against the passage's box: the distance from the centre to the box
                out = 0.0
                for a in range(3):
                    w = 0.0
                    for k2 in range(3):
                        w += box_axes[b, a, k2] * (centre[k2] - box_centre[b, k2])
                    excess = abs(w) - box_half[b, a]
                    if excess > 0:
                        out += excess * excess
                if out <= rc * rc:
                    cand[nc] = b
                    nc += 1
    return np.sort(cand[:nc])


@njit(cache=True, inline="always", error_model="numpy", fastmath=FAST)
def _segment_enters(p, u, i, reach, c, r) -> bool:
    wx, wy, wz = c[0] - p[i, 0], c[1] - p[i, 1], c[2] - p[i, 2]
    t = min(reach, max(-reach, wx * u[i, 0] + wy * u[i, 1] + wz * u[i, 2]))
    wx, wy, wz = wx - t * u[i, 0], wy - t * u[i, 1], wz - t * u[i, 2]
    return wx * wx + wy * wy + wz * wz <= r * r


@njit(cache=True, inline="always", error_model="numpy", fastmath=FAST)
def _segment_enters_box(p, u, i, reach, c, axes, half) -> bool:
    """Slab test of the segment p_i + d u_i, |d| <= reach, against the box (centre, rows of axes, half extents)."""
    lo, hi = -reach, reach
    for a in range(3):
        w = axes[a, 0] * (p[i, 0] - c[0]) + axes[a, 1] * (p[i, 1] - c[1]) + axes[a, 2] * (p[i, 2] - c[2])
        v = axes[a, 0] * u[i, 0] + axes[a, 1] * u[i, 1] + axes[a, 2] * u[i, 2]
        if v == 0.0:
            if abs(w) > half[a]:
                return False
            continue
        t0, t1 = (-half[a] - w) / v, (half[a] - w) / v
        lo, hi = max(lo, min(t0, t1)), min(hi, max(t0, t1))
        if lo > hi:
            return False
    return True


@njit(cache=True, nogil=True, error_model="numpy", fastmath=FAST)
def settle_lines(
    lo_c,
    hi_c,
    p,
    u,
    ds,
    stride,
    clusters,
    grid,
    balls,
    tab,
    delta,
    air_cov,
    solid_blank,
    items,
    counts,
    covered,
    flag,
    work,
):
    """Per line (segments p + d u, d on the samples ``ds``): ``covered[i, c]``: segment c is removed for sure (by
    air or a passage); ``items[i, :counts[i]]``: (passage, lo_j, hi_j, segment) to solve exactly; ``flag[i]``: 0,
    1 when the line's items or near passages overflow (solve it another way), 2 when a passage removes all of it;
    ``work[i]``: the line's (passage, sample range) pairs, the near ones, and the fine estimates it took.

    ``clusters`` = (pointer, line index): nearby lines, handled passage by passage so that a passage's table is
    read once per cluster; clusters [lo_c, hi_c) are settled here (cutting.parallel runs them in parallel);
    ``grid`` = (lo, cell, dims, cell pointer, ball index) of the balls; ``balls`` = (centre, radius, passage g,
    subwindow, samples per subwindow, and each one's box: centre, axes, half extents);
    ``tab`` as :func:`_estimate` takes it."""
    # without reference counts below here (cutting.borrowed): the caller holds the arrays for the whole call
    p, u, ds, clusters, grid, balls, tab = borrowed((p, u, ds, clusters, grid, balls, tab))
    air_cov, items, counts, covered, flag, work = borrowed((air_cov, items, counts, covered, flag, work))
    cl_ptr, cl_line = clusters
    ball_centre, ball_radius, ball_g, ball_sub, per, box_centre, box_axes, box_half = balls
    nseg = ds.shape[0] - 1
    reach = max(-ds[0], ds[-1])
    cap = items.shape[1]
    near_cap = 4 * cap
    lost_step = 4 * (ds[-1] - ds[0]) / nseg * stride
    nco = nseg // stride
    for c in range(lo_c, hi_c):
        lines = cl_line[cl_ptr[c] : cl_ptr[c + 1]]
        nl = len(lines)
        cand = _cluster_balls(p, lines, reach, grid, (ball_centre, ball_radius, box_centre, box_axes, box_half))
        # coarse samples, passage by passage: which (line, passage) pairs can matter at all
        n_near = np.zeros(nl, np.int64)
        near = np.empty((nl, near_cap, 3), np.int64)  # passage, lo_j, hi_j
        co_state = np.empty((nl, near_cap, nco), np.int8)
        whole = np.zeros(nl, np.bool_)
        k = 0
        while k < len(cand):
            g = ball_g[cand[k]]
            k1 = k
            while k1 < len(cand) and ball_g[cand[k1]] == g:
                k1 += 1
            for li in range(nl):
                i = lines[li]
                if whole[li]:
                    continue
                lo, hi = -1, -1
                for kb in range(k, k1):
                    b = cand[kb]
                    if _segment_enters(p, u, i, reach, ball_centre[b], ball_radius[b]) and _segment_enters_box(
                        p, u, i, reach, box_centre[b], box_axes[b], box_half[b]
                    ):
                        s = ball_sub[b]
                        lo = s * per if lo < 0 else min(lo, s * per)
                        hi = max(hi, (s + 1) * per)
                if lo < 0:
                    continue
                work[i, 0] += 1
                ok0, e0, x0, y0 = _estimate(tab, g, lo, hi, p, u, i, ds[0])
                any_, all_removed = False, True
                slot = min(n_near[li], near_cap - 1)
                for cs in range(nco):
                    ok1, e1, x1, y1 = _estimate(tab, g, lo, hi, p, u, i, ds[(cs + 1) * stride])
                    st = _classify(ok0, e0, x0, y0, ok1, e1, x1, y1, delta, lost_step)
                    co_state[li, slot, cs] = st
                    any_ = any_ or st != NOT
                    all_removed = all_removed and st == REMOVED
                    ok0, e0, x0, y0 = ok1, e1, x1, y1
                if all_removed:
                    whole[li] = True
                elif any_:
                    near[li, slot, 0], near[li, slot, 1], near[li, slot, 2] = g, lo, hi
                    n_near[li] += 1
            k = k1
        for li in range(nl):
            i = lines[li]
            counts[i] = 0
            if whole[li]:
                flag[i] = 2
                continue
            if n_near[li] > near_cap:
                flag[i] = 1
                continue
            nnear = n_near[li]
            work[i, 1] = nnear
            # fine segments where the coarse ones are unsure
            state = np.zeros((nnear, nseg), np.int8)
            for kk in range(nnear):
                g, lo, hi = near[li, kk, 0], near[li, kk, 1], near[li, kk, 2]
                for cs in range(nco):
                    st = co_state[li, kk, cs]
                    if st != UNSURE or stride == 1:
                        for f in range(cs * stride, (cs + 1) * stride):
                            state[kk, f] = st
                        continue
                    ok0, e0, x0, y0 = _estimate(tab, g, lo, hi, p, u, i, ds[cs * stride])
                    work[i, 2] += stride + 1
                    for f in range(cs * stride, (cs + 1) * stride):
                        ok1, e1, x1, y1 = _estimate(tab, g, lo, hi, p, u, i, ds[f + 1])
                        state[kk, f] = _classify(ok0, e0, x0, y0, ok1, e1, x1, y1, delta, lost_step / stride)
                        ok0, e0, x0, y0 = ok1, e1, x1, y1
            # coverage, the highest segment surely material, and what stays to solve above it
            top = -1
            for f in range(nseg):
                cov = air_cov[i, f]
                solid = solid_blank[i, f]
                for kk in range(nnear):
                    cov = cov or state[kk, f] == REMOVED
                    solid = solid and state[kk, f] == NOT
                covered[i, f] = cov
                if solid:
                    top = f
            n_items = 0
            for f in range(top + 1, nseg):
                if covered[i, f]:
                    continue
                for kk in range(nnear):
                    if state[kk, f] == UNSURE:
                        if n_items < cap:
                            items[i, n_items, 0] = near[li, kk, 0]
                            items[i, n_items, 1] = near[li, kk, 1]
                            items[i, n_items, 2] = near[li, kk, 2]
                            items[i, n_items, 3] = f
                        n_items += 1
            counts[i] = min(n_items, cap)
            flag[i] = 1 if n_items > cap else 0
            for f in range(top + 1):  # below the material nothing counts
                covered[i, f] = False


@njit(cache=True, nogil=True)
def _sweep_bounds(lo_g, hi_g, rot, origin, points, subwindows, margin, centre, radius, box_centre, box_axes, box_half):
    """Per passage and subwindow of its pose table (rot (m, P, 3, 3), origin (m, P, 3)), what the outline
    ``points`` (k, 3, tooth frame) sweep: a ball (centre, radius) around their box in the work frame, and a box in
    the tooth frame of the subwindow's middle sample (centre, axes as rows, half extents); both grown by
    ``margin`` [mm] (the bulge between samples and the outline's simplification); passages [lo_g, hi_g)."""
    npose = rot.shape[1]
    per = (npose - 1) // subwindows
    for g in range(lo_g, hi_g):
        w = np.empty(3)
        for s in range(subwindows):
            mid = s * per + per // 2
            axes = rot[g, mid].T.copy()
            lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
            blo, bhi = np.full(3, np.inf), np.full(3, -np.inf)
            for j in range(s * per, (s + 1) * per + 1):
                for k in range(points.shape[0]):
                    for a in range(3):
                        w[a] = (
                            rot[g, j, a, 0] * points[k, 0]
                            + rot[g, j, a, 1] * points[k, 1]
                            + rot[g, j, a, 2] * points[k, 2]
                            + origin[g, j, a]
                        )
                        lo[a], hi[a] = min(lo[a], w[a]), max(hi[a], w[a])
                    for a in range(3):
                        v = axes[a, 0] * w[0] + axes[a, 1] * w[1] + axes[a, 2] * w[2]
                        blo[a], bhi[a] = min(blo[a], v), max(bhi[a], v)
            centre[g, s] = (lo + hi) / 2
            radius[g, s] = math.sqrt(((hi - lo) ** 2).sum()) / 2 + margin
            box_axes[g, s] = axes
            mid_local = (blo + bhi) / 2
            for a in range(3):
                box_centre[g, s, a] = axes[0, a] * mid_local[0] + axes[1, a] * mid_local[1] + axes[2, a] * mid_local[2]
            box_half[g, s] = (bhi - blo) / 2 + margin


def sweep_bounds(rot, origin, points, subwindows, margin):
    """:func:`_sweep_bounds` over every passage, on every core (cutting.parallel)."""
    m = rot.shape[0]
    out = (
        np.empty((m, subwindows, 3)),
        np.empty((m, subwindows)),
        np.empty((m, subwindows, 3)),
        np.empty((m, subwindows, 3, 3)),
        np.empty((m, subwindows, 3)),
    )
    run_chunks(_sweep_bounds, m, rot, origin, points, subwindows, margin, *out, smallest=16)
    return out
