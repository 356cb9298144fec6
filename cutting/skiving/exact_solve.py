"""The exact solve of a probe line's unsettled (passage, segment) items, compiled (numba).

:meth:`cutting.skiving.exact_sweep.SweptVolumes.settled_intervals` leaves some items the pose table cannot settle; each
needs the removal margin at both ends of its segment (the rake-plane crossing bracketed over the table, the crossing
instant solved on the motion itself to 1e-10 mm, the outline's margin there) and, where the sign changes, the
root in d. In numpy that is a few dozen flops per item spread over hundreds of small-array calls (the vectorised
pose above all), so Python overhead dominates; here it is one loop per item, in parallel.

The kernels reproduce :meth:`SweptVolumes._margin_exact` and :meth:`SweptVolumes._root` step for step (the same
bisection, the same Illinois iterations and stopping rules, the same arithmetic order): the surface they give
is the Python path's within rounding. They need the pose as a compiled function: :func:`compiled_pose` gives it
for the ideal motion (:class:`cutting.skiving.trajectory.PassMotion`) and the sampled one
(:class:`cutting.skiving.sampled_motion.SampledMotion`); any other motion keeps the Python path.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numba import njit

from cutting.borrowed import borrowed
from cutting.parallel import run_chunks
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.sampled_motion import SampledMotion
from cutting.skiving.trajectory import PassMotion

#: the kinds of compiled pose
IDEAL, SAMPLED = 0, 1
#: floats per interval of a sampled motion: the log of the next sample, the rotation and translation tangents
#: (each still to be scaled by the interval's length)
_PER_INTERVAL = 15


def compiled_pose(motion) -> tuple[int, np.ndarray] | None:
    """(kind, float parameters) that the kernels evaluate the pose of ``motion`` from, exactly as its ``pose``
    does; None for a motion they do not know (or a subclass that changes its pose). Kept on the motion (motions are
    not changed once made)."""
    cached = motion.__dict__.get("_compiled_pose", False) if hasattr(motion, "__dict__") else False
    if cached is not False:
        return cached
    out = _compiled_pose(motion)
    if hasattr(motion, "__dict__"):
        object.__setattr__(motion, "_compiled_pose", out)
    return out


def _compiled_pose(motion) -> tuple[int, np.ndarray] | None:
    if isinstance(motion, PassMotion) and type(motion).pose is PassMotion.pose:
        st = motion.setup
        own = type(st).cutter_pose, type(st).machine_pose
        if own != (SkivingSetup.cutter_pose, SkivingSetup.machine_pose):
            return None
        g = st.geometry
        a = st.final_centre_distance if motion.centre_distance is None else motion.centre_distance
        params = [motion.omega0, motion.s_start, motion.v_s, a + g.centre_distance_offset, st.speed_ratio]
        tilt = st.tilt + g.shaft_angle_error
        params += [st.differential_rotation_per_mm, st.work_phase, math.cos(tilt), math.sin(tilt), st.cutter_phase]
        return IDEAL, np.array(params + g.compiled(), dtype=float)
    if isinstance(motion, SampledMotion) and type(motion).pose is SampledMotion.pose:
        return SAMPLED, _sampled_parameters(motion)
    return None


def _sampled_parameters(motion: SampledMotion) -> np.ndarray:
    """[n, t (n), rot (n, 9), trans (n, 3), per interval i (n - 1, 15)]: what SampledMotion.pose derives from the
    samples around interval i (the logs of R_i^T R_neighbours, the finite-difference tangents), so that the kernel
    only evaluates the Hermite curves and Rodrigues' formula. The same expressions (compiled: a co-simulation makes
    one per passage), so the same values to rounding."""
    t = np.ascontiguousarray(motion.t, dtype=float)
    rot = np.ascontiguousarray(motion.rot, dtype=float).reshape(-1, 9)
    p = np.ascontiguousarray(motion.trans, dtype=float)
    return _sampled_parameters_of(t, rot, p)


@njit(cache=True, error_model="numpy")
def _log9(r):
    """sampled_motion._log of one rotation (a row-major 9-tuple)."""
    cos = min(max((r[0] + r[4] + r[8] - 1) / 2, -1.0), 1.0)
    angle = math.acos(cos)
    scale = angle / (2 * math.sin(max(angle, 1e-12))) if angle > 1e-12 else 0.5
    return (r[7] - r[5]) * scale, (r[2] - r[6]) * scale, (r[3] - r[1]) * scale


@njit(cache=True, error_model="numpy")
def _sampled_parameters_of(t, rot, p):
    n = t.shape[0]
    out = np.empty(1 + 13 * n + _PER_INTERVAL * (n - 1))
    out[0] = n
    out[1 : 1 + n] = t
    out[1 + n : 1 + 10 * n] = rot.ravel()
    out[1 + 10 * n : 1 + 13 * n] = p.ravel()
    for i in range(n - 1):
        i0, i2, i3 = max(i - 1, 0), i + 1, min(i + 2, n - 1)
        ri = rot[i]
        logs = []
        ri_t = (ri[0], ri[3], ri[6], ri[1], ri[4], ri[7], ri[2], ri[5], ri[8])  # R_i^T, row-major
        for k in (i0, i2, i3):
            logs.append(_log9(_mm(ri_t, rot[k])))  # R_i^T R_k
        v0, v2, v3 = logs[0], logs[1], logs[2]
        e = 1 + 13 * n + _PER_INTERVAL * i
        d02, d13 = t[i2] - t[i0], t[i3] - t[i]
        for c in range(3):
            out[e + c] = v2[c]
            out[e + 3 + c] = (v2[c] - v0[c]) / d02
            out[e + 6 + c] = (v3[c] - 0.0) / d13
            out[e + 9 + c] = (p[i2, c] - p[i0, c]) / d02
            out[e + 12 + c] = (p[i3, c] - p[i, c]) / d13
    return out


def pose_table(motion, t: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """``motion.pose(t)`` evaluated compiled: rotations (n, 3, 3) and origins (n, 3), the same values to rounding
    (the pass tables take 65 poses per passage: 1.5M on spur_external); None for a motion without a compiled
    pose."""
    q = compiled_pose(motion)
    if q is None:
        return None
    t = np.ascontiguousarray(np.atleast_1d(t), dtype=float)
    rot, org = np.empty((len(t), 9)), np.empty((len(t), 3))
    run_chunks(_poses, len(t), q[0], q[1], t, rot, org, smallest=4096)
    return rot.reshape(-1, 3, 3), org


class ItemSolver:
    """The compiled item solve of a set of pass tables: every table's pose parameters side by side (passage g over
    all tables, in order, as :class:`cutting.skiving.exact_sweep._CompiledTables` numbers them)."""

    def __init__(self, motion: tuple, tables: tuple, outline: tuple):
        self.motion, self.tables, self.outline = motion, tables, outline
        #: margins evaluated and roots found so far (tests check that this path ran)
        self.points = 0
        self.roots_found = 0

    @classmethod
    def build(cls, tables: Sequence, packed: np.ndarray, outline) -> ItemSolver | None:
        """From the pass tables (``motion``, ``t`` (m, P), ``tooth`` (m, 3, 4), ``blank`` (3, 4)), their packed pose
        table and the
        :class:`cutting.skiving.exact_sweep.ToothOutlines` the passages cut with; None unless every table's motion
        has a compiled pose."""
        poses = [compiled_pose(tb.motion) for tb in tables]
        if not poses or any(q is None for q in poses):
            return None
        kind = np.array([q[0] for q in poses], np.int64)
        ptr = np.concatenate([[0], np.cumsum([len(q[1]) for q in poses])]).astype(np.int64)
        params = np.concatenate([q[1] for q in poses])
        owner = np.concatenate([np.full(len(tb.m), k, np.int64) for k, tb in enumerate(tables)])
        times = np.ascontiguousarray(np.concatenate([tb.t for tb in tables]), dtype=float)
        frames = np.concatenate([passage_frames(tb.tooth, tb.blank) for tb in tables])
        m = np.concatenate([tb.m for tb in tables])
        return cls(
            (owner, kind, ptr, params),
            (np.ascontiguousarray(packed), times, frames),
            outline.compiled(m),
        )

    def margins(self, p, u, ds, line, g, sample, lo_j, hi_j) -> np.ndarray:
        """The removal margin of passage g at the points p[line] + ds[sample] u[line] (SweptVolumes._margin_exact)."""
        out = np.empty(len(line))
        p, u, ds = (np.ascontiguousarray(a, dtype=float) for a in (p, u, ds))
        ints = [np.ascontiguousarray(a, dtype=np.int64) for a in (line, g, sample, lo_j, hi_j)]
        run_chunks(exact_margins, len(line), p, u, ds, *ints, self.motion, self.tables, self.outline, out, smallest=64)
        self.points += len(line)
        return out

    def roots(self, p, u, ds, line, g, lo_j, hi_j, f, m0, m1, tol: float) -> np.ndarray:
        """Where passage g's margin changes sign on segment f of the line, to ``tol`` [mm] (SweptVolumes._root)."""
        out = np.empty(len(line))
        p, u, ds, m0, m1 = (np.ascontiguousarray(a, dtype=float) for a in (p, u, ds, m0, m1))
        ints = [np.ascontiguousarray(a, dtype=np.int64) for a in (line, g, lo_j, hi_j, f)]
        run_chunks(
            exact_roots,
            len(line),
            p,
            u,
            ds,
            *ints,
            m0,
            m1,
            tol,
            self.motion,
            self.tables,
            self.outline,
            out,
            smallest=16,
        )
        self.roots_found += len(line)
        return out


# ---- the pose ----------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always", error_model="numpy")
def _mm(a, b):
    """3x3 product of row-major 9-tuples (the sums in matmul's order)."""
    return (
        a[0] * b[0] + a[1] * b[3] + a[2] * b[6],
        a[0] * b[1] + a[1] * b[4] + a[2] * b[7],
        a[0] * b[2] + a[1] * b[5] + a[2] * b[8],
        a[3] * b[0] + a[4] * b[3] + a[5] * b[6],
        a[3] * b[1] + a[4] * b[4] + a[5] * b[7],
        a[3] * b[2] + a[4] * b[5] + a[5] * b[8],
        a[6] * b[0] + a[7] * b[3] + a[8] * b[6],
        a[6] * b[1] + a[7] * b[4] + a[8] * b[7],
        a[6] * b[2] + a[7] * b[5] + a[8] * b[8],
    )


@njit(cache=True, inline="always", error_model="numpy")
def _rz(c, s):
    return (c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)


@njit(cache=True, error_model="numpy")
def _ideal(w, o, t, full):
    """SkivingSetup.machine_pose at phi0 = omega0 t, s = s_start + v_s t: (rotation 9-tuple, origin). Unless
    ``full``, only the rotation's third column (the rake plane's normal) is right: the turn about the cutter axis
    leaves it as it is (bit for bit: it adds products with zero), so it is skipped. The machine's geometry
    (cutting.skiving.machine_geometry): its centre distance and shaft angle in w[o + 3], w[o + 7:9], the cutter
    centre's offset from w[o + 10:16] (y offset, squareness x and y, the screw's periodic error, 2 pi / pitch,
    phase), the encoders' readings from w[o + 16:20] (tool, its phase, work, its phase), the axial drift from
    w[o + 20:22] (offset, rate: cutting.skiving.thermal_drift)."""
    phi0 = w[o] * t
    s = w[o + 1] + w[o + 2] * t
    b2 = w[o + 4] * phi0 + w[o + 5] * s
    phi2 = b2 - w[o + 18] * math.sin(b2 + w[o + 19]) + w[o + 6]  # the work encoder's reading held
    c, sn = math.cos(-phi2), math.sin(-phi2)
    tilt = (1.0, 0.0, 0.0, 0.0, w[o + 7], -w[o + 8], 0.0, w[o + 8], w[o + 7])
    rot = _mm(_rz(c, sn), tilt)
    if full:
        phi = phi0 - w[o + 16] * math.sin(phi0 + w[o + 17]) + w[o + 9]  # and the tool encoder's
        rot = _mm(rot, _rz(math.cos(phi), math.sin(phi)))
    x = w[o + 3] + w[o + 11] * s
    y = w[o + 10] + w[o + 12] * s
    z = s + w[o + 20] + w[o + 21] * s + w[o + 13] * math.sin(w[o + 14] * s + w[o + 15])
    return rot, (c * x - sn * y, sn * x + c * y, z)


@njit(cache=True, error_model="numpy")
def _sampled(w, o, t):
    """SampledMotion.pose: cubic Hermite with Catmull-Rom tangents, the rotation in the tangent space of the
    interval's first sample (R_i exp(v)); t clipped to the samples."""
    n = int(w[o])
    ts, rs, ps = o + 1, o + 1 + n, o + 1 + 10 * n
    t = min(max(t, w[ts]), w[ts + n - 1])
    lo, hi = 0, n  # searchsorted(side="right"): the first sample after t
    while lo < hi:
        mid = (lo + hi) // 2
        if w[ts + mid] <= t:
            lo = mid + 1
        else:
            hi = mid
    i = min(max(lo - 1, 0), n - 2)
    h = w[ts + i + 1] - w[ts + i]
    x = (t - w[ts + i]) / h
    x2 = x * x
    x3 = x * x * x
    h00, h10, h01, h11 = 2 * x3 - 3 * x2 + 1, x3 - 2 * x2 + x, -2 * x3 + 3 * x2, x3 - x2
    e = o + 1 + 13 * n + _PER_INTERVAL * i
    pi, pn = ps + 3 * i, ps + 3 * i + 3
    org = (
        h00 * w[pi] + h10 * (w[e + 9] * h) + h01 * w[pn] + h11 * (w[e + 12] * h),
        h00 * w[pi + 1] + h10 * (w[e + 10] * h) + h01 * w[pn + 1] + h11 * (w[e + 13] * h),
        h00 * w[pi + 2] + h10 * (w[e + 11] * h) + h01 * w[pn + 2] + h11 * (w[e + 14] * h),
    )
    v0 = h10 * (w[e + 3] * h) + h01 * w[e] + h11 * (w[e + 6] * h)
    v1 = h10 * (w[e + 4] * h) + h01 * w[e + 1] + h11 * (w[e + 7] * h)
    v2 = h10 * (w[e + 5] * h) + h01 * w[e + 2] + h11 * (w[e + 8] * h)
    # Rodrigues, as sampled_motion.exp_rotations
    angle = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    den = max(angle, 1e-300)
    k0, k1, k2 = v0 / den, v1 / den, v2 / den
    kx = (0.0, -k2, k1, k2, 0.0, -k0, -k1, k0, 0.0)
    kk = _mm(kx, kx)
    s, c1 = math.sin(angle), 1 - math.cos(angle)
    ex = (
        1.0 + s * kx[0] + c1 * kk[0],
        0.0 + s * kx[1] + c1 * kk[1],
        0.0 + s * kx[2] + c1 * kk[2],
        0.0 + s * kx[3] + c1 * kk[3],
        1.0 + s * kx[4] + c1 * kk[4],
        0.0 + s * kx[5] + c1 * kk[5],
        0.0 + s * kx[6] + c1 * kk[6],
        0.0 + s * kx[7] + c1 * kk[7],
        1.0 + s * kx[8] + c1 * kk[8],
    )
    r = rs + 9 * i
    ri = (w[r], w[r + 1], w[r + 2], w[r + 3], w[r + 4], w[r + 5], w[r + 6], w[r + 7], w[r + 8])
    return _mm(ri, ex), org


#: floats per passage of :func:`passage_frames`: the tooth frame (9 + 3), the blank frame (9 + 3), and 1.0 where the
#: tooth frame keeps the spindle's z axis (a turn about it and a shift along it: the plane needs only the third column)
FRAME_FLOATS = 25


def passage_frames(tooth: np.ndarray, blank: np.ndarray) -> np.ndarray:
    """Each passage's frames as the kernels read them, (n, FRAME_FLOATS): tooth frames (n, 3, 4) [R | q] and the
    blank frame (3, 4) [L | l], row-major."""
    tooth = np.asarray(tooth, dtype=float)
    n = len(tooth)
    out = np.empty((n, FRAME_FLOATS))
    out[:, 0:9] = tooth[:, :, :3].reshape(n, 9)
    out[:, 9:12] = tooth[:, :, 3]
    out[:, 12:21] = np.asarray(blank, dtype=float)[:, :3].ravel()
    out[:, 21:24] = np.asarray(blank, dtype=float)[:, 3]
    axial = (tooth[:, 0, 2] == 0) & (tooth[:, 1, 2] == 0) & (tooth[:, 2, 2] == 1) & (tooth[:, 0, 3] == 0)
    out[:, 24] = axial & (tooth[:, 1, 3] == 0)
    return np.ascontiguousarray(out)


@njit(cache=True, error_model="numpy")
def _tooth_pose(motion, tables, g, t, full=True):
    """PassTable.exact_pose: the motion's frame at t carrying passage g's tooth frame, in the blank's frame (rotation
    9-tuple, origin); unless ``full``, only the rotation's third column and the origin are right (enough for the rake
    plane: a tooth frame that keeps the spindle's z axis needs only that column of the spindle's rotation)."""
    owner, kind, ptr, params = motion
    f = tables[2][g]
    k = owner[g]
    whole = full or f[24] == 0.0
    if kind[k] == IDEAL:
        rot, org = _ideal(params, ptr[k], t, whole)
    else:
        rot, org = _sampled(params, ptr[k], t)
    q = (f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7], f[8])
    if whole:
        o0 = rot[0] * f[9] + rot[1] * f[10] + rot[2] * f[11] + org[0]
        o1 = rot[3] * f[9] + rot[4] * f[10] + rot[5] * f[11] + org[1]
        o2 = rot[6] * f[9] + rot[7] * f[10] + rot[8] * f[11] + org[2]
        rot = _mm(rot, q)
    else:  # q turns about z and shifts along it: the third column stays, the origin moves along it
        o0, o1, o2 = rot[2] * f[11] + org[0], rot[5] * f[11] + org[1], rot[8] * f[11] + org[2]
    ll = (f[12], f[13], f[14], f[15], f[16], f[17], f[18], f[19], f[20])
    org = (
        ll[0] * o0 + ll[1] * o1 + ll[2] * o2 + f[21],
        ll[3] * o0 + ll[4] * o1 + ll[5] * o2 + f[22],
        ll[6] * o0 + ll[7] * o1 + ll[8] * o2 + f[23],
    )
    return _mm(ll, rot), org


# ---- the margin ----------------------------------------------------------------------------------------------
@njit(cache=True, inline="always", error_model="numpy")
def _sign(x):
    return 1.0 if x > 0 else (-1.0 if x < 0 else (0.0 if x == 0 else math.nan))


@njit(cache=True, inline="always", error_model="numpy")
def _plane(table, g, j, q0, q1, q2):
    return table[g, j, 0] * q0 + table[g, j, 1] * q1 + table[g, j, 2] * q2 - table[g, j, 3]


#: buckets per chain of the compiled outline: where a chain's search starts for an x (a chain has ~125 points)
OUTLINE_BUCKETS = 512


def with_rows(stacked: tuple, rows: np.ndarray | None) -> tuple:
    """:func:`stacked_outlines` with each passage's row (None: every passage reads row 0)."""
    rows = np.zeros(1, np.int64) if rows is None else np.ascontiguousarray(rows, dtype=np.int64)
    return (*stacked, rows)


def stacked_outlines(outlines: Sequence) -> tuple:
    """Per outline its lower and upper chains (x, y) as rows of a stacked array (a shorter chain padded with its
    last point: the lookup clamps there anyway), x0, x1, and per chain the index of its last point at or before each
    of OUTLINE_BUCKETS even steps over its x range (so that a lookup starts next to its point instead of bisecting
    the chain)."""
    parts: list[list] = [[] for _ in range(10)]
    for o in outlines:
        for c, chain in enumerate((o.lower, o.upper)):
            xs, ys = (np.ascontiguousarray(chain[:, k], dtype=float) for k in (0, 1))
            lo, hi = float(xs[0]), float(xs[-1])
            scale = OUTLINE_BUCKETS / (hi - lo) if hi > lo else 0.0
            edges = lo + np.arange(OUTLINE_BUCKETS + 1) / scale if scale > 0 else np.full(OUTLINE_BUCKETS + 1, lo)
            start = np.maximum(np.searchsorted(xs, edges, side="right") - 1, 0).astype(np.int64)
            for k, v in enumerate((xs, ys, start, lo, scale)):
                parts[5 * c + k].append(v)

    def stacked(arrays: list) -> np.ndarray:
        n = max(len(a) for a in arrays)
        return np.ascontiguousarray([np.concatenate([a, np.full(n - len(a), a[-1])]) for a in arrays])

    lx, ly, lb, l0, ls, ux, uy, ub, u0, us = (
        stacked(p) if isinstance(p[0], np.ndarray) else np.array(p, dtype=float) for p in parts
    )
    x0 = np.array([o.x0 for o in outlines], dtype=float)
    x1 = np.array([o.x1 for o in outlines], dtype=float)
    return (lx, ly, ux, uy, x0, x1, lb, l0, ls, ub, u0, us)


@njit(cache=True, inline="always", error_model="numpy")
def _interp_from(x, xp, fp, start, lo, scale):
    """np.interp(x, xp, fp) for one x: clamped at the ends, the last xp[j] <= x found from the bucket of x (a walk
    of a step or two instead of bisecting the chain), its value where x hits it; NaN in, NaN out."""
    n = len(xp)
    if x != x:
        return x
    if x < xp[0]:
        return fp[0]
    if x > xp[n - 1]:
        return fp[n - 1]
    b = min(max(int((x - lo) * scale), 0), start.shape[0] - 1)
    j = start[b]
    while j > 0 and xp[j] > x:
        j -= 1
    while j + 1 < n and xp[j + 1] <= x:
        j += 1
    if j == n - 1 or xp[j] == x:
        return fp[j]
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    out = slope * (x - xp[j]) + fp[j]
    if out != out:
        out = slope * (x - xp[j + 1]) + fp[j + 1]
        if out != out and fp[j] == fp[j + 1]:
            out = fp[j]
    return out


@njit(cache=True, error_model="numpy")
def outline_margin(outline, g, x, y):
    """Outline.margin of passage g's outline: min(above the lower chain, below the upper, x - x0, x1 - x)."""
    lx, ly, ux, uy, x0, x1, lb, l0, ls, ub, u0, us, rows = outline
    r = rows[g] if g < rows.shape[0] else 0
    below = y - _interp_from(x, lx[r], ly[r], lb[r], l0[r], ls[r])
    above = _interp_from(x, ux[r], uy[r], ub[r], u0[r], us[r]) - y
    return min(min(below, above), min(x - x0[r], x1[r] - x))


@njit(cache=True, error_model="numpy")
def margin_at(motion, tables, outline, g, lo, hi, q0, q1, q2):
    """SweptVolumes._margin_exact at one point: the crossing bracketed over the table samples [lo, hi]
    (_events), the instant solved by the Illinois method to 1e-10 mm (_solve_time), the outline's margin there
    (at least -1); -1 where the plane does not cross the point."""
    table, times = tables[0], tables[1]
    ga, gb = _plane(table, g, lo, q0, q1, q2), _plane(table, g, hi, q0, q1, q2)
    if not _sign(ga) * _sign(gb) <= 0:
        return -1.0
    a, b = lo, hi
    while b - a > 1:
        mid = (a + b) // 2
        gm = _plane(table, g, mid, q0, q1, q2)
        if _sign(gm) == _sign(ga):
            a, ga = mid, gm
        else:
            b, gb = mid, gm
    ta, tb = times[g, a], times[g, a + 1]
    tk = ta
    for _ in range(40):
        denom = gb - ga
        tk = tb - gb * (tb - ta) / denom if denom != 0 else (ta + tb) / 2
        tk = min(max(tk, min(ta, tb)), max(ta, tb))
        rot, org = _tooth_pose(motion, tables, g, tk, False)  # the plane only
        w0, w1, w2 = q0 - org[0], q1 - org[1], q2 - org[2]
        gk = rot[2] * w0 + rot[5] * w1 + rot[8] * w2
        if _sign(gk) == _sign(gb):  # Illinois: halve the stale end's value when the same end moves twice
            ga = ga / 2
        else:
            ga, ta = gb, tb
        tb, gb = tk, gk
        if abs(gk) < 1e-10 or abs(tb - ta) <= 1e-15 * max(1.0, abs(tk)):
            break
    rot, org = _tooth_pose(motion, tables, g, tk, True)
    w0, w1, w2 = q0 - org[0], q1 - org[1], q2 - org[2]
    x = rot[0] * w0 + rot[3] * w1 + rot[6] * w2
    y = rot[1] * w0 + rot[4] * w1 + rot[7] * w2
    m = outline_margin(outline, g, x, y)
    return -1.0 if m < -1.0 else m


@njit(cache=True, nogil=True, error_model="numpy")
def exact_margins(lo_k, hi_k, p, u, ds, line, g, sample, lo_j, hi_j, motion, tables, outline, out):
    """``out[k]``: the margin of passage g[k] (table samples [lo_j, hi_j]) at p[line] + ds[sample] u[line], for k in
    [lo_k, hi_k)."""
    p, u, ds, line, g, sample, lo_j, hi_j = borrowed((p, u, ds, line, g, sample, lo_j, hi_j))
    motion, tables, outline, out = borrowed((motion, tables, outline, out))  # (cutting.borrowed)
    for k in range(lo_k, hi_k):
        i, d = line[k], ds[sample[k]]
        q0, q1, q2 = p[i, 0] + d * u[i, 0], p[i, 1] + d * u[i, 1], p[i, 2] + d * u[i, 2]
        out[k] = margin_at(motion, tables, outline, g[k], lo_j[k], hi_j[k], q0, q1, q2)


@njit(cache=True, error_model="numpy")
def line_root(motion, tables, outline, g, lo, hi, p, u, i, d_lo, d_hi, m_lo, m_hi, tol):
    """The d in [d_lo, d_hi] where passage g's margin (table samples [lo, hi]) along the line p[i] + d u[i] changes
    sign, from the margins m_lo, m_hi at the ends: the Illinois method to ``tol`` [mm] (SweptVolumes._root). The
    measurement's roots and the dexel workpiece's cuts are both found here."""
    d = (d_lo + d_hi) / 2
    for _ in range(80):
        denom = m_hi - m_lo
        dk = d_hi - m_hi * (d_hi - d_lo) / denom if denom != 0 else (d_lo + d_hi) / 2
        dk = min(max(dk, min(d_lo, d_hi)), max(d_lo, d_hi))
        q0, q1, q2 = p[i, 0] + dk * u[i, 0], p[i, 1] + dk * u[i, 1], p[i, 2] + dk * u[i, 2]
        mk = margin_at(motion, tables, outline, g, lo, hi, q0, q1, q2)
        d = dk
        if (mk > 0) == (m_hi > 0):  # Illinois: halve the stale end
            m_lo = m_lo / 2
        else:
            m_lo, d_lo = m_hi, d_hi
        d_hi, m_hi = dk, mk
        if abs(d_hi - d_lo) <= tol or abs(mk) <= 1e-12:
            break
    return d


@njit(cache=True, nogil=True, error_model="numpy")
def exact_roots(lo_k, hi_k, p, u, ds, line, g, lo_j, hi_j, f, m0, m1, tol, motion, tables, outline, out):
    """``out[k]``: the d in [ds[f], ds[f + 1]] where passage g[k]'s margin along the line changes sign, from the
    margins m0, m1 at the ends (:func:`line_root`), for k in [lo_k, hi_k)."""
    p, u, ds, line, g, lo_j, hi_j, f, m0, m1 = borrowed((p, u, ds, line, g, lo_j, hi_j, f, m0, m1))
    motion, tables, outline, out = borrowed((motion, tables, outline, out))  # (cutting.borrowed)
    for k in range(lo_k, hi_k):
        d_lo, d_hi = ds[f[k]], ds[f[k] + 1]
        out[k] = line_root(
            motion, tables, outline, g[k], lo_j[k], hi_j[k], p, u, line[k], d_lo, d_hi, m0[k], m1[k], tol
        )


@njit(cache=True, nogil=True, error_model="numpy")
def _poses(lo_k, hi_k, kind, w, t, rot, org):
    """The motion's frame at the times t[lo_k:hi_k]: rows of the rotation (9 per pose) and the origin."""
    for k in range(lo_k, hi_k):
        if kind == IDEAL:
            r, o = _ideal(w, 0, t[k], True)
        else:
            r, o = _sampled(w, 0, t[k])
        for c in range(9):
            rot[k, c] = r[c]
        for c in range(3):
            org[k, c] = o[c]
