"""Swept volume of a cutter tooth's rake-face region between poses, as one closed manifold ("tube").

While a tooth is in the cut, every point of its rake face moves through the face's plane in one
direction (the relative velocity keeps a component along the rake-face normal of constant sign; checked
for both shipped jobs: v.n/|v| stays within 0.39..1 external, -1..-0.66 internal). The region swept by the
planar tooth outline is then bounded by the tube that its outline traces plus the outline at the first
and last pose. Between poses the tube is made of flat facets, so the error of the sweep is the sagitta of
the outline points' paths plus the twist of each facet, which :func:`sample_window` bounds.
"""

from __future__ import annotations

from collections.abc import Callable

import manifold3d as mf
import numpy as np

#: pose(t) -> (R (n, 3, 3), p (n, 3)): the cutter frame in the work frame at times t
PoseFunction = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def outline_points(outline: np.ndarray) -> np.ndarray:
    """(n, 3) rake-plane points (z = 0 in the cutter frame) of a 2D outline."""
    return np.column_stack([outline, np.zeros(len(outline))])


def place(points: np.ndarray, rot: np.ndarray, trans: np.ndarray) -> np.ndarray:
    """Points (n, 3) in every pose: shape (m, n, 3)."""
    return np.matmul(rot, points.T).transpose(0, 2, 1) + trans[:, None, :]  # batched BLAS: 10x an einsum


def sample_window(
    pose: PoseFunction,
    points: np.ndarray,
    t0: float,
    t1: float,
    tol: float,
    inside: Callable[[np.ndarray], np.ndarray] | None = None,
    start: int = 8,
    rounds: int = 16,
) -> tuple[np.ndarray, float]:
    """Times in [t0, t1] such that the tube through the closed polygon ``points`` deviates from the exact
    sweep of that polygon by at most ``tol`` [mm] wherever it can touch the workpiece.

    Two deviations are checked per interval and polygon side: the side's end point against its chord (the
    sagitta, quadratic in the interval), and the side's true midpoint at mid-interval against the facets,
    along their normal (the twist of the quad, linear in the interval and in the side's length). Only quads
    with a corner where ``inside`` (points (..., 3) -> bool) is true count: the hub chord of the outline, far
    outside the blank, may twist freely. An interval that fails is split into ceil(sqrt(dev / tol)) parts;
    repeated until all pass. Returns the times and the largest deviation left: the reported error bound.
    """
    side_mid = (points + np.roll(points, -1, axis=0)) / 2
    t = np.linspace(t0, t1, start)
    for _ in range(rounds):
        tm = (t[:-1] + t[1:]) / 2
        ends = place(points, *pose(t))
        rot_m, trans_m = pose(tm)
        chord = np.linalg.norm(place(points, rot_m, trans_m) - (ends[:-1] + ends[1:]) / 2, axis=2)
        # the facets of a quad a-b / c-d are split along a-d (see tube): how far the swept side's true midpoint
        # lies off them, along the quad's normal
        nxt = np.roll(ends, -1, axis=1)
        a, b, c, d = ends[:-1], nxt[:-1], ends[1:], nxt[1:]
        normal = np.cross(d - a, b - c)
        normal /= np.maximum(np.linalg.norm(normal, axis=2, keepdims=True), 1e-300)
        twist = np.abs(((place(side_mid, rot_m, trans_m) - (a + d) / 2) * normal).sum(axis=2))
        dev = np.maximum(chord, twist)
        if inside is not None:
            near = inside(ends)
            near_next = np.roll(near, -1, axis=1)
            dev = np.where(near[:-1] | near[1:] | near_next[:-1] | near_next[1:], dev, 0.0)
        dev = dev.max(axis=1)
        if (dev <= tol).all():
            return t, float(dev.max())
        parts = np.maximum(1, np.ceil(np.sqrt(dev / tol) * 1.05)).astype(int)
        pieces = [np.linspace(a, b, k + 1)[:-1] for a, b, k in zip(t[:-1], t[1:], parts, strict=True)]
        t = np.concatenate([*pieces, t[-1:]])
    raise RuntimeError(f"the trajectory could not be sampled to a sweep error of {tol * 1e3:.2f} um")


def tube(outline: np.ndarray, rot: np.ndarray, trans: np.ndarray) -> mf.Manifold:
    """The closed swept volume of the planar ``outline`` (CCW, star-shaped) through the poses (m >= 2)."""
    n = len(outline)
    m = len(rot)
    w = place(outline_points(outline), rot, trans)
    verts = np.vstack([w.reshape(-1, 3), w[0].mean(axis=0), w[-1].mean(axis=0)])
    idx = np.arange(m * n).reshape(m, n)
    nxt = np.r_[1:n, 0]
    a, b, c, d = idx[:-1, :], idx[:-1, nxt], idx[1:, :], idx[1:, nxt]
    c0, c1 = m * n, m * n + 1
    tris = np.concatenate(
        [
            np.stack([a, b, d], -1).reshape(-1, 3),
            np.stack([a, d, c], -1).reshape(-1, 3),
            np.stack([np.full(n, c0), idx[0, nxt], idx[0, :]], -1),  # start cap (fan from its centroid)
            np.stack([np.full(n, c1), idx[-1, :], idx[-1, nxt]], -1),  # end cap
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
    return outline[keep], worst


def split_sides(outline: np.ndarray, longest: float) -> np.ndarray:
    """The closed polygon with every side longer than ``longest`` [mm] cut into equal parts (same shape)."""
    nxt = np.roll(outline, -1, axis=0)
    parts = np.maximum(1, np.ceil(np.linalg.norm(nxt - outline, axis=1) / longest)).astype(int)
    return np.vstack([a + (b - a) * (np.arange(k)[:, None] / k) for a, b, k in zip(outline, nxt, parts, strict=True)])
