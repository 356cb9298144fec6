"""Compiled kernels of the form-milled gear's exact swept surface (numba): the least mill margin of points.

:meth:`cutting.form_milling.sweep.MilledGear.margin` asks, for every point, the passes of its own tooth space and of
the nearer neighbouring one; per (point, pass) pair the work is a bisection over the pass's pose table, a scan of a
few dozen samples around it and a parabola-vertex refinement, which numpy can only vectorise through many small
temporaries. :func:`_margins` does it per point, on every core (:func:`cutting.parallel.run_chunks`), with the
arithmetic of the numpy reference (``MilledGear._margin_numpy``) step for step: the same samples, the same
clipping, the same order of the sums (numpy's einsum of three terms adds the first and the last first), so that
the two agree to rounding.

The passes are packed (:meth:`MilledGear._packed`) as flat arrays: ``centre`` and ``axis`` (N, 3) of all passes'
poses, sorted along the feed, pass i's rows ``ptr[i]:ptr[i + 1]``; ``scan`` (passes, 2) their (k, stride) scan
parameters; the passes of space s ``space_pass[space_ptr[s]:space_ptr[s + 1]]``. The mill's profile table (some
10^4 points, unevenly spaced) is looked up through a guide of equal buckets (:func:`interp_guide`), which finds the
same interval as np.interp's bisection.

The per-sample helpers are inlined by numba (``inline="always"``): called as functions with array arguments they
cost reference counting per sample, three times the arithmetic; each has as few call sites as may be (compile time).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from cutting.parallel import run_chunks

#: the margin of a point beyond the mill's axial span [mm]
FAR = 1e3
#: points below which a call runs inline on this thread
SMALLEST = 256


def interp_guide(xp: np.ndarray) -> tuple[np.ndarray, float]:
    """A guide to the table ``xp`` (increasing) for :func:`_interp`: split [xp[0], xp[-1]] into len(xp) equal
    buckets, ``guide[b]`` the last table index at or below bucket b's start; and the buckets per unit of x."""
    n = len(xp)
    span = float(xp[-1] - xp[0])
    if n < 2 or not span > 0:
        return np.zeros(2, np.int64), 0.0
    edges = xp[0] + span * np.arange(n + 1) / n
    guide = np.clip(np.searchsorted(xp, edges, side="right") - 1, 0, n - 2).astype(np.int64)
    return guide, n / span


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _interp(x: float, xp: np.ndarray, fp: np.ndarray, guide: np.ndarray, scale: float) -> float:
    """np.interp(x, xp, fp) of one value (clamped at the ends); the interval found by bisection within the
    guide's bucket of x (the same interval as a bisection of the whole table: the one with xp[j] <= x < xp[j+1])."""
    n = xp.shape[0]
    if x >= xp[n - 1]:
        return fp[n - 1]
    if x < xp[0]:
        return fp[0]
    m = guide.shape[0] - 1
    b = min(max(int((x - xp[0]) * scale), 0), m - 1)
    lo, hi = guide[b], min(guide[b + 1] + 1, n - 1)
    if not xp[lo] <= x:  # the bucket's rounding: fall back on the whole table
        lo = 0
    if not x < xp[hi]:
        hi = n - 1
    while hi - lo > 1:  # xp[lo] <= x < xp[hi]
        mid = (lo + hi) >> 1
        if xp[mid] <= x:
            lo = mid
        else:
            hi = mid
    slope = (fp[lo + 1] - fp[lo]) / (xp[lo + 1] - xp[lo])
    out = slope * (x - xp[lo]) + fp[lo]
    if math.isnan(out):
        out = slope * (x - xp[lo + 1]) + fp[lo + 1]
        if math.isnan(out) and fp[lo] == fp[lo + 1]:
            out = fp[lo]
    return out


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _minimum(a: float, b: float) -> float:
    """np.minimum of two values (NaN if either is)."""
    return a if (a <= b or a != a) else b


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _margin_at(q0, q1, q2, c0, c1, c2, a0, a1, a2, mill) -> float:
    """w - R(u) of the point q for the mill at centre c with unit axis a (FAR beyond its axial span); ``mill`` =
    (u table, h table, its interp_guide, its scale, radius R)."""
    u_tab, h_tab, guide, scale, radius = mill
    v0, v1, v2 = q0 - c0, q1 - c1, q2 - c2
    u = (v0 * a0 + v2 * a2) + v1 * a1  # the sums in the order of numpy's einsum of three terms
    if not (u >= u_tab[0] and u <= u_tab[u_tab.shape[0] - 1]):
        return FAR
    r0, r1, r2 = v0 - u * a0, v1 - u * a1, v2 - u * a2
    w = math.sqrt((r0 * r0 + r2 * r2) + r1 * r1)
    return w - (radius - _interp(u, u_tab, h_tab, guide, scale))


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _at_sample(q0, q1, q2, centre, axis, b, s, mill) -> float:
    """The margin of q at pose sample b + s (no interpolation)."""
    i = b + s
    return _margin_at(q0, q1, q2, centre[i, 0], centre[i, 1], centre[i, 2], axis[i, 0], axis[i, 1], axis[i, 2], mill)


@njit(cache=True, nogil=True, error_model="numpy")
def _least(q0, q1, q2, centre, axis, b, n, j, k, stride, mill):
    """(least margin, its sample) over the samples j + stride * (-k..k) of the pass at rows b..b + n, clipped."""
    best = np.inf
    arg = min(max(j, 1), n - 2)
    for off in range(-k, k + 1):
        s = min(max(j + off * stride, 0), n - 1)
        g = _at_sample(q0, q1, q2, centre, axis, b, s, mill)
        if g < best:
            best, arg = g, s
    return best, arg


@njit(cache=True, nogil=True, error_model="numpy")
def _pass_margin(q0, q1, q2, centre, axis, b, n, k, stride, mill) -> float:
    """min over one pass (rows b..b + n, sorted along the feed) of w - R(u) at q: the coarse scan around q's face
    position, the fine scan around its least sample, the parabola vertex through the least sample and its neighbours
    (``MilledGear.pass_margin``)."""
    if n < 3:
        return FAR
    lo, hi = 0, n  # searchsorted(centre z, q2, side="left")
    while lo < hi:
        mid = (lo + hi) >> 1
        if centre[b + mid, 2] < q2:
            lo = mid + 1
        else:
            hi = mid
    best, arg = _least(q0, q1, q2, centre, axis, b, n, lo, k, stride, mill)
    if stride > 1:
        best, arg = _least(q0, q1, q2, centre, axis, b, n, arg, stride, 1, mill)
    mid = min(max(arg, 1), n - 2)
    g0 = g1 = g2 = 0.0
    for d in range(3):  # one call site of the inlined helper (compile time)
        g = _at_sample(q0, q1, q2, centre, axis, b, mid - 1 + d, mill)
        if d == 0:
            g0 = g
        elif d == 1:
            g1 = g
        else:
            g2 = g
    curv = g0 - 2 * g1 + g2
    vertex = float(mid)
    if curv > 1e-15 and g0 < FAR / 2 and g2 < FAR / 2:
        vertex = mid + 0.5 * (g0 - g2) / curv
    s = min(max(vertex, mid - 1.0), mid + 1.0)
    # the pose at the continuous sample index s, linear between samples, its axis made unit
    i = min(max(math.floor(s), 0), n - 2)
    f = min(max(s - i, 0.0), 1.0)
    e, h = b + i, b + i + 1
    c0 = centre[e, 0] * (1 - f) + centre[h, 0] * f
    c1 = centre[e, 1] * (1 - f) + centre[h, 1] * f
    c2 = centre[e, 2] * (1 - f) + centre[h, 2] * f
    a0 = axis[e, 0] * (1 - f) + axis[h, 0] * f
    a1 = axis[e, 1] * (1 - f) + axis[h, 1] * f
    a2 = axis[e, 2] * (1 - f) + axis[h, 2] * f
    norm = math.sqrt((a0 * a0 + a1 * a1) + a2 * a2)
    refined = _margin_at(q0, q1, q2, c0, c1, c2, a0 / norm, a1 / norm, a2 / norm, mill)
    return _minimum(refined, _minimum(best, g1))


@njit(cache=True, nogil=True, error_model="numpy")
def _margins(
    lo: int,
    hi: int,
    q: np.ndarray,
    sign_only: bool,
    teeth: int,
    rate: float,
    reach_lo: float,
    reach_hi: float,
    centre: np.ndarray,
    axis: np.ndarray,
    ptr: np.ndarray,
    scan: np.ndarray,
    space_ptr: np.ndarray,
    space_pass: np.ndarray,
    u_tab: np.ndarray,
    h_tab: np.ndarray,
    guide: np.ndarray,
    scale: float,
    radius: float,
    out: np.ndarray,
) -> None:
    """``out[p]`` for the points p in [lo, hi): the least margin over the passes of the point's tooth space and then
    of the nearer neighbouring one (``rate`` the twist rate [rad/mm]), each space's passes asked where the point's
    distance across its symmetry line is in [reach_lo, reach_hi]; ``sign_only``: a pass is asked only where the
    passes before it left the point (value > 0)."""
    mill = (u_tab, h_tab, guide, scale, radius)
    for p in range(lo, hi):
        q0, q1, q2 = q[p, 0], q[p, 1], q[p, 2]
        twist = rate * q2
        pos = (math.atan2(q1, q0) - twist) / (2 * math.pi) * teeth
        fl = math.floor(pos)
        own = int(fl) % teeth
        near = (own - 1 if pos - fl < 0.5 else own + 1) % teeth
        val = FAR
        for which in range(2):
            k = own if which == 0 else near
            a = 2 * math.pi * (k + 0.5) / teeth + twist
            x_s = -math.sin(a) * q0 + math.cos(a) * q1
            if not (x_s >= reach_lo and x_s <= reach_hi):
                continue
            for e in range(space_ptr[k], space_ptr[k + 1]):
                if sign_only and not val > 0:
                    break
                i = space_pass[e]
                m = _pass_margin(q0, q1, q2, centre, axis, ptr[i], ptr[i + 1] - ptr[i], scan[i, 0], scan[i, 1], mill)
                val = _minimum(val, m)
        out[p] = val


def milled_margins(
    q: np.ndarray, sign_only: bool, teeth: int, rate: float, reach: tuple[float, float], packed: tuple
) -> np.ndarray:
    """:func:`_margins` of the points ``q`` (n, 3) on every core; ``packed`` = (centre, axis, ptr, scan, space_ptr,
    space_pass, u_tab, h_tab, guide, scale, radius) as ``MilledGear._packed`` makes it."""
    q = np.ascontiguousarray(q, dtype=np.float64).reshape(-1, 3)
    out = np.empty(len(q))
    run_chunks(
        _margins,
        len(q),
        q,
        bool(sign_only),
        int(teeth),
        float(rate),
        float(reach[0]),
        float(reach[1]),
        *packed,
        out,
        smallest=SMALLEST,
    )
    return out
