"""The exact swept volume, point by point: an independent reference for the meshed removal.

A point Q of the work frame is removed by a tooth passage if, at the instant the moving rake plane passes
through Q, Q lies inside the tooth's outline in that plane (every point crosses the rake plane in one
direction while the tooth is in the cut, :mod:`cutting.sweep`). That instant is found by bisection on the
signed distance of Q from the rake plane, to 2^-32 of the passage window, so the test has no chord error:
it answers what the kinematics and the edge really cut. Bisecting along a flank normal then gives the
exact surface the passes leave there, to compare with the mesh (sampling error) and with the nominal flank
(feed marks, the edge's own error).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cutting.edge import CuttingEdge
from cutting.removal import passage_range
from cutting.sweep import outline_points, simplify_outline
from cutting.trajectory import PassMotion


@dataclass
class Passages:
    """Every tooth passage of one pass: window [t0, t1], the cutter tooth's angle, a bounding ball."""

    motion: PassMotion
    t0: np.ndarray
    t1: np.ndarray
    tooth_angle: np.ndarray
    centre: np.ndarray  # (m, 3)
    radius: np.ndarray  # (m,)


def passages(motion: PassMotion, edge: CuttingEdge, probes: int = 65, chunk: int = 256) -> Passages:
    """The passages of ``motion`` as :func:`cutting.removal.cut` windows them, with bounding balls from
    ``probes`` poses each (evaluated ``chunk`` passages at a time to bound memory)."""
    z0 = motion.setup.cutter.teeth
    half, m_first, m_last = passage_range(motion, edge)
    m = np.arange(m_first, m_last + 1)
    pitch = 2 * math.pi / z0
    t0 = np.asarray(motion.time_at_angle(m * pitch - half), dtype=float)
    t1 = np.asarray(motion.time_at_angle(m * pitch + half), dtype=float)
    angle = 2 * np.pi * ((-m) % z0) / z0
    # a bounding ball per passage, from the outline simplified to 20 um (the margin covers that and the hull)
    coarse, _ = simplify_outline(edge.outline, 0.02)
    pts = outline_points(coarse)
    frac = np.linspace(0.0, 1.0, probes)
    centre = np.empty((len(m), 3))
    radius = np.empty(len(m))
    for a in range(0, len(m), chunk):
        b = min(a + chunk, len(m))
        rot, trans = motion.pose((t0[a:b, None] + frac[None, :] * (t1 - t0)[a:b, None]).ravel())
        c, s = np.cos(angle[a:b]), np.sin(angle[a:b])
        tooth = np.zeros((b - a, 3, 3))
        tooth[:, 0, 0], tooth[:, 0, 1], tooth[:, 1, 0], tooth[:, 1, 1], tooth[:, 2, 2] = c, -s, s, c, 1.0
        rot = np.einsum("mpij,mjk->mpik", rot.reshape(b - a, probes, 3, 3), tooth)
        w = np.einsum("mpij,nj->mpni", rot, pts) + trans.reshape(b - a, probes, 1, 3)
        lo, hi = w.min(axis=(1, 2)), w.max(axis=(1, 2))
        centre[a:b] = (lo + hi) / 2
        radius[a:b] = np.linalg.norm(hi - lo, axis=1) / 2 + 0.1  # 20 um outline + hull bulge between probes
    return Passages(motion, t0, t1, angle, centre, radius)


def _inside_polygon(xy: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Even-odd test of points (n, 2) against a closed polygon (k, 2)."""
    x, y = xy[:, :1], xy[:, 1:]
    a, b = poly[None, :, :], np.roll(poly, -1, axis=0)[None, :, :]
    crosses = (a[..., 1] > y) != (b[..., 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = a[..., 0] + (y - a[..., 1]) * (b[..., 0] - a[..., 0]) / (b[..., 1] - a[..., 1])
    return (crosses & (x < xc)).sum(axis=1) % 2 == 1


def removed(points: np.ndarray, sets: Sequence[Passages], edge: CuttingEdge, grid: int = 33) -> np.ndarray:
    """For points (n, 3) of the work frame: True where any passage of ``sets`` sweeps the point."""
    points = np.atleast_2d(points)
    out = np.zeros(len(points), dtype=bool)
    for ps in sets:
        d = np.linalg.norm(points[:, None, :] - ps.centre[None, :, :], axis=2)
        qi, mi = np.nonzero(d <= ps.radius[None, :])
        if qi.size == 0:
            continue
        q = points[qi]
        frac = np.linspace(0.0, 1.0, grid)
        ts = ps.t0[mi, None] + frac[None, :] * (ps.t1 - ps.t0)[mi, None]  # (p, grid)

        rot, trans = ps.motion.pose(ts.ravel())
        g = np.einsum("ni,ni->n", rot[:, :, 2], np.repeat(q, grid, axis=0) - trans).reshape(ts.shape)
        pair, k = np.nonzero(np.sign(g[:, :-1]) * np.sign(g[:, 1:]) <= 0)
        if pair.size == 0:
            continue
        lo, hi = ts[pair, k], ts[pair, k + 1]
        glo = g[pair, k]
        qq = q[pair]
        for _ in range(32):  # 2^-32 of the window: ~1e-7 mm of travel at 130 m/min
            mid = (lo + hi) / 2
            rot, trans = ps.motion.pose(mid)
            gm = np.einsum("ni,ni->n", rot[:, :, 2], qq - trans)
            left = np.sign(gm) == np.sign(glo)
            lo, hi = np.where(left, mid, lo), np.where(left, hi, mid)
            glo = np.where(left, gm, glo)
        rot, trans = ps.motion.pose((lo + hi) / 2)
        local = np.einsum("nji,nj->ni", rot, qq - trans)  # R^T (Q - p): cutter frame
        ang = ps.tooth_angle[mi[pair]]
        c, s = np.cos(ang), np.sin(ang)
        xy = np.column_stack([c * local[:, 0] + s * local[:, 1], -s * local[:, 0] + c * local[:, 1]])
        hit = _inside_polygon(xy, edge.outline)
        out[qi[pair[hit]]] = True
    return out


def surface_offset(
    points: np.ndarray,
    normals: np.ndarray,
    sets: Sequence[Passages],
    edge: CuttingEdge,
    span: float = 0.05,
    resolution: float = 1e-5,
) -> np.ndarray:
    """Where the exact cut surface crosses each line ``point + d * normal`` (normal pointing out of the
    material): d [mm], positive where material is left beyond the point. NaN if the line is not cut within
    +-``span`` or is cut everywhere on it."""
    lo = np.full(len(points), -span)
    hi = np.full(len(points), span)
    cut_lo = removed(points + lo[:, None] * normals, sets, edge)
    cut_hi = removed(points + hi[:, None] * normals, sets, edge)
    valid = ~cut_lo & cut_hi
    while (hi - lo).max() > resolution:
        mid = (lo + hi) / 2
        cut = removed(points + mid[:, None] * normals, sets, edge)
        lo, hi = np.where(cut, lo, mid), np.where(cut, mid, hi)
    return np.where(valid, (lo + hi) / 2, np.nan)
