"""Compiled kernels of the dexel workpiece (numba): tooth passages cut the dexel lines, exactly, in time order.

Compiled so that the dexel removal cuts real gears at machine speed: :func:`cut_cells` cuts the lines cell by cell
in parallel (a nogil kernel on a thread pool) and sums each passage's chip (the scheme there); :func:`_march` marches
a line's material through one passage (estimate, crossing, exact polish there). A passage removes from a line the
points whose rake-plane image lies inside the edge outline at the instant the rake plane passes them
(:mod:`cutting.skiving.exact_sweep`). The dexel workpiece and its measured figures: docs/cutting.md, "The dexel
workpiece: real gears at machine speed".
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from cutting.borrowed import borrowed
from cutting.parallel import claim
from cutting.skiving.exact_kernels import in_plane
from cutting.skiving.exact_solve import margin_at, outline_margin

#: the in-plane track between two estimates may bow: its chord is lengthened by this factor (as the measurement's)
TRACK_BOW = 1.05
#: the outline margin at the table's in-plane point is this close to the exact one [mm] (quadratic pose between
#: table samples: some 0.01 um; ten times that kept as margin)
POSE_ERROR = 1e-4
#: the crossing on the table is found to this [mm] before the exact polish (the table is within ~1e-5 mm of it)
TABLE_TOL = 1e-6
#: after a Newton step from the table's crossing, a secant correction below this [mm] leaves an error of its square
NEWTON_SETTLED = 1e-7
#: a first Newton step no longer than this [mm] (the table's own error) is the crossing (see _crossing)
NEWTON_ONE_STEP = 2e-5
#: a march's end that the rake plane misses by rounding (a break of _crossing_breaks, where the plane meets the point at
#: the window's end sample) is estimated this far inside [mm], the estimate's error grown by the track over it (its
#: in-plane speed is far below 100); without it the march crept to the end in steps of a quarter of what was left
BREAK_NUDGE = 1e-9
BREAK_SLACK = 100 * BREAK_NUDGE
#: a track whose distance to the outline changes slower than this fraction of its in-plane speed grazes it
SHALLOW = 0.5
#: within this distance [mm] of the outline a march aims its step past it, to solve a clean crossing at once
NEAR = 0.05
#: material intervals a line can hold (a passage splitting one more time than this is reported)
MAX_PIECES = 8
#: flags per line
OVERFLOW = 1
#: per (cell, passage): volume, first moment (3), removed length, thickness max, thickness x area, area, contact
#: length, lines cut
STATS = 10


@njit(cache=True, inline="always", error_model="numpy")
def _bilinear(sdf, fx, fy):
    i, j = int(fx), int(fy)
    a, b = fx - i, fy - j
    return (1 - a) * ((1 - b) * sdf[i, j] + b * sdf[i, j + 1]) + a * ((1 - b) * sdf[i + 1, j] + b * sdf[i + 1, j + 1])


@njit(cache=True, inline="always", error_model="numpy")
def _distance(fine, coarse, w, x, y):
    """(e, delta): the outline's signed distance at (x, y) and how far it may be off. Two rasters: a fine one
    (exact node distances within its band of the outline) where the point is that near, else a coarse one over a
    wide box (exact node distances over all of it), and beyond that box a bound (the box holds the outline grown by
    its pad: the outline is at least pad plus the distance to the box away). The rasters are the edge's outline's;
    a passage's tooth may cut with its own: :func:`_estimate` adds how far that lies from it."""
    f0, f1, f_cell, f_band, f_delta = w[0], w[1], w[2], w[3], w[4]
    c0, c1, c_cell, c_pad, c_delta = w[5], w[6], w[7], w[8], w[9]
    fx, fy = (x - f0) / f_cell, (y - f1) / f_cell
    if 0 <= fx < fine.shape[0] - 1 and 0 <= fy < fine.shape[1] - 1:
        e = _bilinear(fine, fx, fy)
        if abs(e) < f_band - f_cell:  # within the band of exact nodes
            return e, f_delta
    fx, fy = (x - c0) / c_cell, (y - c1) / c_cell
    nx, ny = coarse.shape[0] - 1, coarse.shape[1] - 1
    if fx < 0 or fy < 0 or fx >= nx or fy >= ny:
        ox = max(0.0, max(-fx, fx - nx)) * c_cell
        oy = max(0.0, max(-fy, fy - ny)) * c_cell
        return -(c_pad + math.sqrt(ox * ox + oy * oy)), 0.0
    return _bilinear(coarse, fx, fy), c_delta


@njit(cache=True, inline="always", error_model="numpy")
def _estimate(tab, g, lo, hi, p, u, i, d):
    """(crossed, e, delta, x, y) at p_i + d u_i for passage g (table samples [lo, hi]): the rasters' signed distance e
    (within delta) at the table's in-plane point (x, y); e very negative where the rake plane does not cross the
    point there. ``tab`` = (packed table, fine raster, coarse raster, their corners, cells, bands and deltas, per
    passage how far its tooth's outline lies from the rasters')."""
    q0, q1, q2 = p[i, 0] + d * u[i, 0], p[i, 1] + d * u[i, 1], p[i, 2] + d * u[i, 2]
    ok, x, y = in_plane(tab[0], g, lo, hi, q0, q1, q2)
    if not ok:
        return False, -1e9, 0.0, 0.0, 0.0
    e, delta = _distance(tab[1], tab[2], tab[3], x, y)
    return True, e, delta + tab[4][g], x, y


@njit(cache=True, error_model="numpy")
def _table_margin(tab, outline, g, lo, hi, p, u, i, d):
    """The outline polygon's margin at the table's in-plane point (-1 where the plane does not cross)."""
    q0, q1, q2 = p[i, 0] + d * u[i, 0], p[i, 1] + d * u[i, 1], p[i, 2] + d * u[i, 2]
    ok, x, y = in_plane(tab[0], g, lo, hi, q0, q1, q2)
    return outline_margin(outline, g, x, y) if ok else -1.0


@njit(cache=True, error_model="numpy")
def _exact(motion, tables, outline, g, lo, hi, p, u, i, d):
    return margin_at(
        motion, tables, outline, g, lo, hi, p[i, 0] + d * u[i, 0], p[i, 1] + d * u[i, 1], p[i, 2] + d * u[i, 2]
    )


@njit(cache=True, error_model="numpy")
def _margin_sign(tab, motion, tables, outline, g, lo, hi, p, u, i, d, work):
    """The margin at d: the table's where it is clear of zero, else the exact one."""
    m = _table_margin(tab, outline, g, lo, hi, p, u, i, d)
    work[1] += 1
    if abs(m) <= POSE_ERROR:
        m = _exact(motion, tables, outline, g, lo, hi, p, u, i, d)
        work[2] += 1
    return m


@njit(cache=True, error_model="numpy")
def _crossing(tab, motion, tables, outline, g, lo, hi, p, u, i, a, b, ma, mb, tol, work, guess=math.nan):
    """The d in [a, b] where the margin changes sign (ma, mb of opposite signs at the ends): the Illinois method on
    the table's margin (from ``guess`` if it lies inside: where the estimated distances cross), then the exact
    margin's Newton and secant steps until the crossing moves less than ``tol``."""
    d_lo, d_hi, m_lo, m_hi = a, b, ma, mb
    d = (a + b) / 2
    slope = (mb - ma) / (b - a) if b != a else 0.0
    if min(a, b) < guess < max(a, b):
        mg = _table_margin(tab, outline, g, lo, hi, p, u, i, guess)
        work[1] += 1
        slope = (mg - ma) / (guess - a)
        if (mg > 0) == (ma > 0):  # the bracket [guess, b], the guess its newest end
            d_lo, m_lo, d_hi, m_hi = b, mb, guess, mg
        else:
            d_lo, m_lo, d_hi, m_hi = a, ma, guess, mg
    for _ in range(60):  # on the table (cheap): to about its own error
        den = m_hi - m_lo
        d = d_hi - m_hi * (d_hi - d_lo) / den if den != 0 else (d_lo + d_hi) / 2
        d = min(max(d, min(a, b)), max(a, b))
        m = _table_margin(tab, outline, g, lo, hi, p, u, i, d)
        work[1] += 1
        if d != d_hi:
            slope = (m - m_hi) / (d - d_hi)  # the margin's slope along the line, from the last two
        if (m > 0) == (m_hi > 0):
            m_lo = m_lo / 2
        else:
            m_lo, d_lo = m_hi, d_hi
        d_hi, m_hi = d, m
        # within the table's own error (its bracket that narrow, or its margin that small): the polish goes on
        if abs(d_hi - d_lo) <= max(tol, TABLE_TOL) or abs(m) <= TABLE_TOL:
            break
    # polish on the motion: the table's crossing differs from the exact one by the pose's interpolation (a smooth
    # offset of ~1e-5 mm), so a Newton step with the table's slope and a secant step land within ~1e-12 mm; more
    # secant steps only where they do not (then until the crossing moves less than tol)
    x0 = d
    f0 = _exact(motion, tables, outline, g, lo, hi, p, u, i, x0)
    work[2] += 1
    x1 = x0 - f0 / slope if slope != 0 and math.isfinite(slope) else x0 + max(1e-6, 1e3 * tol)
    x1 = min(max(x1, min(a, b)), max(a, b))
    if abs(x1 - x0) <= NEWTON_ONE_STEP:
        # the table's crossing was within its own error (~1e-5 mm) of the exact one and the two margins' slopes
        # differ by the interpolation's derivative (~1e-4 relative): one step leaves ~1e-9 mm
        work[3] += 1
        return x1
    f1 = _exact(motion, tables, outline, g, lo, hi, p, u, i, x1)
    work[2] += 1
    if f1 != f0:
        x2 = min(max(x1 - f1 * (x1 - x0) / (f1 - f0), min(a, b)), max(a, b))
        if abs(x2 - x1) <= NEWTON_SETTLED:  # the second step corrects the first by the error squared: done
            work[3] += 1
            return x2
    for _ in range(8):
        if f1 == f0 or abs(x1 - x0) <= tol:
            break
        x2 = x1 - f1 * (x1 - x0) / (f1 - f0)
        x2 = min(max(x2, min(a, b)), max(a, b))
        x0, f0 = x1, f1
        x1 = x2
        f1 = _exact(motion, tables, outline, g, lo, hi, p, u, i, x1)
        work[2] += 1
    work[3] += 1
    return x1


@njit(cache=True, error_model="numpy")
def _march(tab, motion, tables, outline, g, lo, hi, p, u, i, a, b, fine, tol, out_lo, out_hi, n_out, work):
    """The parts of [a, b] on line i that passage g removes, appended to out_lo/out_hi from n_out; returns the new
    count. ``work``: estimates, table margins, exact margins, crossings (added to).

    A step is taken when the estimates at its ends settle it: the state (removed or not) holds all along it, or it
    crosses the outline once (its ends surely on opposite sides, and the in-plane track no longer than the two
    distances add up to: no room for a second crossing deeper than the estimate's error), then found exactly.
    Near the outline the step aims past it; steps that settle nothing shrink to ``fine``, where the margin itself
    decides at the ends.

    - far from the edge, the pose table and a signed distance raster of the outline give the in-plane distance e(d)
      of the line's point to the outline within ``delta`` (as :func:`cutting.skiving.exact_kernels.in_plane` gives
      it to the measurement's estimate); e is 1-Lipschitz in the plane, so a step whose in-plane track is shorter
      than |e| - delta cannot cross the outline: far from the passage the steps are long, near it they shrink to
      ``fine``;
    - on a fine step the margin of the outline polygon itself is taken at the table's in-plane point (within
      ``POSE_ERROR`` of the truth: the pose is quadratic between table samples), its sign change found by the
      Illinois method, and the crossing polished with the margin solved exactly on the motion
      (:func:`cutting.skiving.exact_solve.margin_at`, the measurement's own solve) until it moves less than ``tol``;
      where the table's margin is within ``POSE_ERROR`` of zero the exact margin decides."""
    ok0, e0, dl0, x0, y0 = _estimate(tab, g, lo, hi, p, u, i, a)
    work[0] += 1
    if not ok0:  # a break (cut_cells): the rake plane meets a by the window's end sample, rounding put it outside
        ok0, e0, dl0, x0, y0 = _estimate(tab, g, lo, hi, p, u, i, a + BREAK_NUDGE)
        dl0 += BREAK_SLACK
        work[0] += 1
    m0 = 0.0
    have_m0 = False
    if not ok0 or abs(e0) <= dl0:
        m0 = _margin_sign(tab, motion, tables, outline, g, lo, hi, p, u, i, a, work)
        have_m0 = True
        inside = m0 > 0
    else:
        inside = e0 > 0
    start = a
    d = a
    speed = 1.0
    rate = math.nan  # de/dd over the last step that settled
    have_b, ok_b, e_b, dl_b, x_b, y_b = False, False, 0.0, 0.0, 0.0, 0.0
    while d < b:
        safe = max(fine, (abs(e0) - dl0) / speed)  # cannot reach the outline
        jump = 2.0 * abs(e0) / speed + fine if ok0 and abs(e0) < NEAR else 0.0  # aims past it: a clean crossing
        if math.isfinite(rate) and abs(rate) < SHALLOW * speed:
            jump = 0.0  # a track grazing the outline: no step across it can prove a single crossing
        # outside the outline, the rest of the range at once first: a track that leaves the outline settles it
        step = b - d if ok0 and not inside and abs(e0) > dl0 else max(safe, jump)
        unsure = False
        crossing = False
        while True:
            if step >= b - d:
                step = b - d
            d1 = d + step
            if d1 == b and have_b:  # the range's end, estimated before
                ok1, e1, dl1, x1, y1 = ok_b, e_b, dl_b, x_b, y_b
            else:
                ok1, e1, dl1, x1, y1 = _estimate(tab, g, lo, hi, p, u, i, d1)
                work[0] += 1
                if d1 == b and not ok1:  # b is a break, as a can be (above)
                    ok1, e1, dl1, x1, y1 = _estimate(tab, g, lo, hi, p, u, i, b - BREAK_NUDGE)
                    dl1 += BREAK_SLACK
                    work[0] += 1
                if d1 == b:
                    have_b, ok_b, e_b, dl_b, x_b, y_b = True, ok1, e1, dl1, x1, y1
            if ok0 and ok1:
                delta = max(dl0, dl1)
                chord = TRACK_BOW * math.sqrt((x1 - x0) ** 2 + (y1 - y0) ** 2)
                if inside and (e0 + e1 - chord) / 2 > delta:
                    break
                if not inside and (e0 + e1 + chord) / 2 < -delta:
                    break
                clean = abs(e0) > dl0 and abs(e1) > dl1 and (e0 > 0) == inside and (e1 > 0) != inside
                if clean and abs(e0) + abs(e1) + dl0 + dl1 >= chord - 2 * delta:
                    crossing = True
                    break
                if step > fine:
                    speed = max(speed, chord / step)
            if step <= fine:
                unsure = True
                break
            if step > max(safe, jump):  # the long attempt failed: the steps that can settle or cross
                step = max(safe, jump)
            elif step > safe and jump > 0:
                step = safe
            else:
                step = max(fine, step / 4)
        if crossing:
            ma = _table_margin(tab, outline, g, lo, hi, p, u, i, d)
            mb = _table_margin(tab, outline, g, lo, hi, p, u, i, d1)
            work[1] += 2
            if (ma > 0) == inside and (mb > 0) != inside:
                guess = d + (d1 - d) * e0 / (e0 - e1)  # where the estimated distances cross
                r = _crossing(tab, motion, tables, outline, g, lo, hi, p, u, i, d, d1, ma, mb, tol, work, guess)
                if inside and n_out < out_lo.shape[0]:
                    out_lo[n_out], out_hi[n_out] = start, r
                    n_out += 1
                else:
                    start = r
                inside = not inside
                have_m0 = False
                speed = max(0.5, TRACK_BOW * math.sqrt((x1 - x0) ** 2 + (y1 - y0) ** 2) / step)
                rate = math.nan
                d, ok0, e0, dl0, x0, y0 = d1, ok1, e1, dl1, x1, y1
                continue
            unsure = True  # the margins disagree with the estimates: take it as an unsure segment
        if unsure:
            if not have_m0:
                m0 = _margin_sign(tab, motion, tables, outline, g, lo, hi, p, u, i, d, work)
            m1 = _margin_sign(tab, motion, tables, outline, g, lo, hi, p, u, i, d1, work)
            now_in = m1 > 0
            if (m0 > 0) != now_in:
                r = _crossing(tab, motion, tables, outline, g, lo, hi, p, u, i, d, d1, m0, m1, tol, work)
            else:
                r = d  # the margin disagrees with the state carried in: trust it, at the segment's start
            if now_in != inside:
                if now_in:
                    start = r
                elif n_out < out_lo.shape[0]:
                    out_lo[n_out], out_hi[n_out] = start, r
                    n_out += 1
                inside = now_in
            m0, have_m0 = m1, True
            rate = math.nan
        else:
            have_m0 = False
            rate = math.nan
            if ok0 and ok1 and step > 0:
                speed = max(0.5, TRACK_BOW * math.sqrt((x1 - x0) ** 2 + (y1 - y0) ** 2) / step)
                rate = (e1 - e0) / step
        d, ok0, e0, dl0, x0, y0 = d1, ok1, e1, dl1, x1, y1
    if inside and n_out < out_lo.shape[0]:
        out_lo[n_out], out_hi[n_out] = start, b
        n_out += 1
    return n_out


@njit(cache=True, error_model="numpy")
def _crossing_breaks(table, g, lo, hi, p, u, i, a, b, breaks):
    """Where on [a, b] the rake plane's distance at samples lo and hi changes sign (each is linear in d): the
    pieces between these breaks either have a crossing within [lo, hi] everywhere or nowhere. Returns the count of
    break points written to ``breaks`` (a, the breaks inside, b)."""
    n = 0
    breaks[n] = a
    n += 1
    for j in (lo, hi):
        c0 = table[g, j, 0] * p[i, 0] + table[g, j, 1] * p[i, 1] + table[g, j, 2] * p[i, 2] - table[g, j, 3]
        c1 = table[g, j, 0] * u[i, 0] + table[g, j, 1] * u[i, 1] + table[g, j, 2] * u[i, 2]
        if c1 != 0.0:
            d = -c0 / c1
            if a < d < b:
                breaks[n] = d
                n += 1
    breaks[n] = b
    n += 1
    if n == 4 and breaks[1] > breaks[2]:
        breaks[1], breaks[2] = breaks[2], breaks[1]
    return n


@njit(cache=True, error_model="numpy")
def _crossed(table, g, lo, hi, q0, q1, q2):
    ga = table[g, lo, 0] * q0 + table[g, lo, 1] * q1 + table[g, lo, 2] * q2 - table[g, lo, 3]
    gb = table[g, hi, 0] * q0 + table[g, hi, 1] * q1 + table[g, hi, 2] * q2 - table[g, hi, 3]
    return not ((ga > 0 and gb > 0) or (ga < 0 and gb < 0))


@njit(cache=True, error_model="numpy")
def _ball_hit(p, u, i, d0, d1, c, r):
    """Whether the segment p_i + d u_i, d in [d0, d1], comes within r of c."""
    wx, wy, wz = c[0] - p[i, 0], c[1] - p[i, 1], c[2] - p[i, 2]
    t = min(d1, max(d0, wx * u[i, 0] + wy * u[i, 1] + wz * u[i, 2]))
    wx, wy, wz = wx - t * u[i, 0], wy - t * u[i, 1], wz - t * u[i, 2]
    return wx * wx + wy * wy + wz * wz <= r * r


@njit(cache=True, error_model="numpy")
def _box_meets_plane(c, axes, half, n, d):
    """Whether the box (centre, rows of axes, half extents) reaches the plane n . x = d."""
    reach = 0.0
    for a in range(3):
        reach += half[a] * abs(axes[a, 0] * n[0] + axes[a, 1] * n[1] + axes[a, 2] * n[2])
    return abs(c[0] * n[0] + c[1] * n[1] + c[2] * n[2] - d) <= reach


@njit(cache=True, error_model="numpy")
def _box_range(p, u, i, d0, d1, c, axes, half):
    """The part [lo, hi] of the segment p_i + d u_i, d in [d0, d1], inside the box (centre, rows of axes, half
    extents); lo > hi when it misses."""
    lo, hi = d0, d1
    for a in range(3):
        w = axes[a, 0] * (p[i, 0] - c[0]) + axes[a, 1] * (p[i, 1] - c[1]) + axes[a, 2] * (p[i, 2] - c[2])
        v = axes[a, 0] * u[i, 0] + axes[a, 1] * u[i, 1] + axes[a, 2] * u[i, 2]
        if v == 0.0:
            if abs(w) > half[a]:
                return 1.0, 0.0
            continue
        t0, t1 = (-half[a] - w) / v, (half[a] - w) / v
        lo, hi = max(lo, min(t0, t1)), min(hi, max(t0, t1))
        if lo > hi:
            return 1.0, 0.0
    return lo, hi


@njit(cache=True, error_model="numpy")
def _fan_rays(ray_alpha, alpha_sign, u0x, u0y, wx, wy, rs):
    """The rays [lo, hi] of a fan that can meet a circle of radius ``rs`` in its plane, at (wx, wy) from the fan's
    centre: the rays' angles ``ray_alpha`` increase; a ray's direction turns from ray 0's (u0x, u0y) by
    alpha_sign (alpha - alpha_0). A superset (the angular window is widened a little, and taken on both sides of
    the turn's +-pi seam); hi < lo when none can."""
    n = ray_alpha.shape[0]
    dist = math.sqrt(wx * wx + wy * wy)
    if dist <= rs:
        return 0, n - 1
    half = math.asin(rs / dist) + 1e-9
    turn = math.atan2(u0x * wy - u0y * wx, u0x * wx + u0y * wy)  # from ray 0 to the centre, about the plane normal
    lo, hi = n, -1
    for seam in (-2 * math.pi, 0.0, 2 * math.pi):
        aim = ray_alpha[0] + alpha_sign * (turn + seam)
        a = np.searchsorted(ray_alpha, aim - half)  # first ray at or after the window's start
        b = np.searchsorted(ray_alpha, aim + half, side="right") - 1  # last ray at or before its end
        if a <= b:
            lo, hi = min(lo, a), max(hi, b)
    return lo, hi


@njit(cache=True, nogil=True, error_model="numpy")
def cut_cells(
    counter,
    n_cells,
    cells,
    cell_ptr,
    cell_g,
    rays,
    p,
    u,
    weight,
    ray_cos,
    ray_arc,
    slice_dz,
    plane_n,
    plane_d,
    ray_alpha,
    alpha_sign,
    mat_lo,
    mat_hi,
    mat_n,
    boxes,
    tab,
    motion,
    tables,
    outline,
    fine,
    tol,
    out,
    flags,
    work,
):
    """Cut the lines of fan ``cells[k]`` (lines cells[k] * rays ... + rays - 1) by the passages
    ``cell_g[cell_ptr[k]:cell_ptr[k + 1]]`` (in time order), for every k < ``n_cells`` that this thread takes from
    ``counter`` (cutting.parallel.run_shared: the threads share the cells one by one).

    The lines are grouped in cells (one fan: a tooth space in one slice); a cell's lines share their candidate
    passages, and cells are cut in parallel. Per line, the passages that can reach it are taken in the order the
    machine made them; only the line's remaining material matters, so each material interval is marched through
    (:func:`_march`). What a passage removes of a line is subtracted from its material intervals, and the chip's
    share is summed per (cell, passage): volume (the polar quadrature of :mod:`cutting.skiving.dexel_lines`), first
    moment (centroid), removed length, chip thickness normal to the nominal boundary (largest, and summed over the
    footprint), the footprint on the boundary and the profile length it covers.

    ``p``, ``u``, ``weight``: every line's origin, direction and weights (n, 2): an interval [d1, d2] holds
    w0 (d2 - d1) + w1 (d2^2 - d1^2) / 2 of volume (parallel lines: w0, a fan's rays: w1); ``ray_cos``,
    ``ray_arc``: per ray of a fan, |cos| to the nominal boundary's normal and its arc cell [mm]; ``slice_dz`` per
    cell's slice [mm];
    ``plane_n``, ``plane_d``: the plane every cell's lines lie in (n . x = d_k: a slice); ``ray_alpha``,
    ``alpha_sign``: a fan's ray angles and their sense (:func:`_fan_rays`; an empty ``ray_alpha``: lines that are not
    fans, every line of a cell is tried); ``mat_lo``, ``mat_hi``,
    ``mat_n``: the material intervals (n, MAX_PIECES), updated; ``boxes`` = (ball centre
    (G, S, 3), ball radius (G, S), box centre (G, S, 3), axes (G, S, 3, 3), half (G, S, 3), samples per subwindow);
    ``tab`` = (packed table, the rasters of :func:`_distance`, per passage its outline's spread); ``motion``,
    ``tables``, ``outline``: the exact solve's (:class:`cutting.skiving.exact_solve.ItemSolver`). ``out[pair]``
    (STATS) per (cell, passage) pair; ``flags[line]`` |= OVERFLOW when a line would hold more than MAX_PIECES
    intervals; ``work[k]`` = estimates, table margins, exact margins, crossings, (line, passage) pairs of cell k."""
    # the kernel's arrays without reference counts (cutting.borrowed): the caller holds them for the whole call
    p, u, weight, ray_cos, ray_arc, slice_dz = borrowed((p, u, weight, ray_cos, ray_arc, slice_dz))
    plane_n, plane_d, ray_alpha, mat_lo, mat_hi, mat_n = borrowed((plane_n, plane_d, ray_alpha, mat_lo, mat_hi, mat_n))
    boxes, tab, motion, tables, outline = borrowed((boxes, tab, motion, tables, outline))
    out, flags, work, cells, cell_ptr, cell_g = borrowed((out, flags, work, cells, cell_ptr, cell_g))
    ball_c, ball_r, box_c, box_a, box_h, per = boxes
    nsub = box_c.shape[1]
    fans = ray_alpha.shape[0] == rays  # the lines of a cell are a fan from one centre (its plane's normal is z)
    table = tab[0]
    while True:
        k = claim(counter)  # the next cell not yet taken by a thread
        if k >= n_cells:
            break
        rem_lo = np.empty(MAX_PIECES)
        rem_hi = np.empty(MAX_PIECES)
        breaks = np.empty(4)
        wk = np.zeros(5, np.int64)
        dz = slice_dz[k]
        reach = np.empty(nsub, np.bool_)
        ray_lo = np.empty(nsub, np.int64)
        ray_hi = np.empty(nsub, np.int64)
        first_line = cells[k] * rays
        acc = np.empty(STATS)  # a pair's sums, kept here: out's rows of neighbouring cells share cache lines
        for pr in range(cell_ptr[k], cell_ptr[k + 1]):
            g = cell_g[pr]
            for c in range(STATS):
                out[pr, c] = 0.0
                acc[c] = 0.0
            # the subwindows whose boxes reach the fan's plane (the cell's lines share it, normal u_slice)
            any_reach = False
            ray_first, ray_last = rays, -1
            for s in range(nsub):
                reach[s] = _box_meets_plane(box_c[g, s], box_a[g, s], box_h[g, s], plane_n, plane_d[k])
                ray_lo[s], ray_hi[s] = 0, rays - 1
                if reach[s] and fans:
                    # a fan: only the rays whose direction meets the ball's section in the fan's plane can reach it
                    c = ball_c[g, s]
                    off = c[0] * plane_n[0] + c[1] * plane_n[1] + c[2] * plane_n[2] - plane_d[k]
                    rs2 = ball_r[g, s] ** 2 - off * off
                    if rs2 < 0:
                        reach[s] = False
                    else:
                        ray_lo[s], ray_hi[s] = _fan_rays(
                            ray_alpha,
                            alpha_sign,
                            u[first_line, 0],
                            u[first_line, 1],
                            c[0] - p[first_line, 0],
                            c[1] - p[first_line, 1],
                            math.sqrt(rs2),
                        )
                        reach[s] = ray_lo[s] <= ray_hi[s]
                if reach[s]:
                    ray_first, ray_last = min(ray_first, ray_lo[s]), max(ray_last, ray_hi[s])
                any_reach = any_reach or reach[s]
            if not any_reach:
                continue
            for ray in range(ray_first, ray_last + 1):
                i = first_line + ray
                n_mat = mat_n[i]
                if n_mat == 0:
                    continue
                wk[4] += 1
                # the subwindows whose balls and boxes the line enters: the table samples and the part of the line
                lo_j, hi_j = -1, -1
                d_lo, d_hi = math.inf, -math.inf
                m_first, m_last = mat_lo[i, 0], mat_hi[i, n_mat - 1]
                for s in range(nsub):
                    if not reach[s] or ray < ray_lo[s] or ray > ray_hi[s]:
                        continue
                    if not _ball_hit(p, u, i, m_first, m_last, ball_c[g, s], ball_r[g, s]):
                        continue
                    a, b = _box_range(p, u, i, m_first, m_last, box_c[g, s], box_a[g, s], box_h[g, s])
                    if a <= b:
                        lo_j = s * per if lo_j < 0 else min(lo_j, s * per)
                        hi_j = max(hi_j, (s + 1) * per)
                        d_lo, d_hi = min(d_lo, a), max(d_hi, b)
                if lo_j < 0:
                    continue
                n_rem = 0
                for piece in range(n_mat):
                    a, b = max(mat_lo[i, piece], d_lo), min(mat_hi[i, piece], d_hi)
                    if a >= b:
                        continue
                    nb = _crossing_breaks(table, g, lo_j, hi_j, p, u, i, a, b, breaks)
                    for c in range(nb - 1):
                        a2, b2 = breaks[c], breaks[c + 1]
                        if b2 <= a2:
                            continue
                        dm = (a2 + b2) / 2
                        if not _crossed(
                            table, g, lo_j, hi_j, p[i, 0] + dm * u[i, 0], p[i, 1] + dm * u[i, 1], p[i, 2] + dm * u[i, 2]
                        ):
                            continue
                        n_rem = _march(
                            tab,
                            motion,
                            tables,
                            outline,
                            g,
                            lo_j,
                            hi_j,
                            p,
                            u,
                            i,
                            a2,
                            b2,
                            fine,
                            tol,
                            rem_lo,
                            rem_hi,
                            n_rem,
                            wk,
                        )
                if n_rem == 0:
                    continue
                removed = 0.0
                for r in range(n_rem):
                    lo_r, hi_r = rem_lo[r], rem_hi[r]
                    if hi_r <= lo_r:
                        continue
                    removed += hi_r - lo_r
                    # the element (w_lin + w_pol d) dd (parallel lines / a fan's rays); its first moment
                    d1, d2, d3 = hi_r - lo_r, (hi_r * hi_r - lo_r * lo_r) / 2, (hi_r**3 - lo_r**3) / 3
                    v = weight[i, 0] * d1 + weight[i, 1] * d2
                    f = weight[i, 0] * d2 + weight[i, 1] * d3
                    acc[0] += v
                    acc[1] += p[i, 0] * v + u[i, 0] * f
                    acc[2] += p[i, 1] * v + u[i, 1] * f
                    acc[3] += p[i, 2] * v + u[i, 2] * f
                if removed <= 0:
                    continue
                thick = removed * ray_cos[ray]
                area = ray_arc[ray] * dz
                acc[4] += removed
                acc[5] = max(acc[5], thick)
                acc[6] += thick * area
                acc[7] += area
                acc[8] += ray_arc[ray]
                acc[9] += 1
                flags[i] |= _subtract(mat_lo, mat_hi, mat_n, i, rem_lo, rem_hi, n_rem)
            for c in range(STATS):
                out[pr, c] = acc[c]
        for c in range(5):
            work[k, c] = wk[c]


@njit(cache=True, error_model="numpy")
def _subtract(mat_lo, mat_hi, mat_n, i, rem_lo, rem_hi, n_rem):
    """Line i's material intervals minus the removed ones (each lies within one material interval); returns
    OVERFLOW if the result would not fit (the smallest pieces are then dropped)."""
    flag = 0
    for r in range(n_rem):
        a, b = rem_lo[r], rem_hi[r]
        if b <= a:
            continue
        n = mat_n[i]
        new_lo = np.empty(2 * MAX_PIECES)
        new_hi = np.empty(2 * MAX_PIECES)
        m = 0
        for piece in range(n):
            lo, hi = mat_lo[i, piece], mat_hi[i, piece]
            if b <= lo or a >= hi:
                new_lo[m], new_hi[m] = lo, hi
                m += 1
                continue
            if lo < a:
                new_lo[m], new_hi[m] = lo, a
                m += 1
            if b < hi:
                new_lo[m], new_hi[m] = b, hi
                m += 1
        while m > MAX_PIECES:  # drop the shortest piece (never the last: it holds the gear body)
            flag = OVERFLOW
            short = 0
            for piece in range(m - 1):
                if new_hi[piece] - new_lo[piece] < new_hi[short] - new_lo[short]:
                    short = piece
            for piece in range(short, m - 1):
                new_lo[piece], new_hi[piece] = new_lo[piece + 1], new_hi[piece + 1]
            m -= 1
        for piece in range(m):
            mat_lo[i, piece], mat_hi[i, piece] = new_lo[piece], new_hi[piece]
        mat_n[i] = m
    return flag
