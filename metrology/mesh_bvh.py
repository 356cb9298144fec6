"""Compiled line-mesh crossings (numba): a bounding volume hierarchy of the triangles' boxes and the watertight test.

:class:`metrology.mesh_probe.MeshWorkpiece` asks where lines cross a closed triangle mesh. The triangles' axis-aligned
boxes are kept in a binary tree (split at the middle of the longest extent of their centres, a few triangles per
leaf); each line walks the boxes its segment enters and tests the leaves' triangles exactly. A box judges a long
skinny triangle by its own extent, so the end faces' slivers and an analytic gear's face-long flank strips cost no
more than small triangles where the line is not near them.

The crossing test is the watertight one of Woop, Benthin and Wald (JCGT 2013), as mesh_probe documents: the line is
sheared onto its major axis kz, every edge judged by a 2-D edge function of its two vertices alone, exact zeros
broken by simulation of simplicity (the line moved by (eps, eps^2) in the sheared plane). Each operation is the
one the vectorised numpy test it replaced did, in the same order (no fast-math): the same crossings bit for bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from cutting.parallel import run_chunks

#: triangles per leaf of the tree: the box tests above a leaf cost about as much as its triangles' tests
LEAF = 4
#: crossings a line keeps in the first pass; lines with more are walked again with room for all of them
FIRST_CAP = 8


@njit(cache=True)
def build(tri_lo: np.ndarray, tri_hi: np.ndarray, leaf: int):
    """The tree over the boxes (n, 3) of n triangles: per node its box (lo, hi), first child (the second is the next
    node; -1 for a leaf), its range [start, start + count) of ``order`` (triangle indices); and the tree's depth.
    Nodes are split at the middle of their centres' longest extent (both sides keep a triangle, as the extent is
    positive); a node whose centres coincide stays a leaf whatever its count."""
    n = tri_lo.shape[0]
    cap = max(2 * n - 1, 1)
    node_lo = np.empty((cap, 3))
    node_hi = np.empty((cap, 3))
    child = np.full(cap, -1, np.int64)
    start = np.zeros(cap, np.int64)
    count = np.zeros(cap, np.int64)
    depth = np.zeros(cap, np.int64)
    order = np.arange(n)
    centre = (tri_lo + tri_hi) * 0.5
    count[0] = n
    nodes = 1
    k = 0
    deepest = 0
    while k < nodes:  # breadth first: children are appended behind the nodes still to split
        s, c = start[k], count[k]
        deepest = max(deepest, depth[k])
        c_lo = np.full(3, np.inf)
        c_hi = np.full(3, -np.inf)
        for a in range(3):
            node_lo[k, a] = np.inf
            node_hi[k, a] = -np.inf
        for j in range(s, s + c):
            f = order[j]
            for a in range(3):
                node_lo[k, a] = min(node_lo[k, a], tri_lo[f, a])
                node_hi[k, a] = max(node_hi[k, a], tri_hi[f, a])
                c_lo[a] = min(c_lo[a], centre[f, a])
                c_hi[a] = max(c_hi[a], centre[f, a])
        if c > leaf:
            axis = 0
            for a in range(1, 3):
                if c_hi[a] - c_lo[a] > c_hi[axis] - c_lo[axis]:
                    axis = a
            if c_hi[axis] > c_lo[axis]:
                mid = 0.5 * (c_lo[axis] + c_hi[axis])
                i, j = s, s + c - 1
                while i <= j:  # partition: centres below mid first
                    if centre[order[i], axis] < mid:
                        i += 1
                    else:
                        order[i], order[j] = order[j], order[i]
                        j -= 1
                child[k] = nodes
                for side in range(2):
                    start[nodes] = s if side == 0 else i
                    count[nodes] = i - s if side == 0 else s + c - i
                    depth[nodes] = depth[k] + 1
                    nodes += 1
        k += 1
    return (
        node_lo[:nodes].copy(),
        node_hi[:nodes].copy(),
        child[:nodes].copy(),
        start[:nodes].copy(),
        count[:nodes].copy(),
        order,
        deepest,
    )


@njit(cache=True, inline="always")
def _tie(e, dx, dy):
    """The edge function's sign with an exact zero broken by the perturbation (eps, eps^2)."""
    if e != 0:
        return e
    return dx if dx != 0 else dy


@njit(cache=True, nogil=True)
def cross_lines(
    lo_i,
    hi_i,
    lines,
    o,
    D,
    seg_lo,
    seg_hi,
    node_lo,
    node_hi,
    child,
    start,
    count,
    order,
    depth,
    vertices,
    faces,
    slack,
    out_face,
    out_t,
    out_ent,
    out_n,
):
    """Crossings of the lines ``lines[lo_i:hi_i]`` (rows of ``o``, ``D``; d in [seg_lo, seg_hi]) with the mesh:
    per row r of ``lines``, up to out_face.shape[1] of them in out_face[r], out_t[r] (d), out_ent[r] (entering
    towards +d), and their full count in out_n[r] (in no particular order)."""
    cap = out_face.shape[1]
    stack = np.empty(depth + 2, np.int64)
    for r in range(lo_i, hi_i):
        i = lines[r]
        kz = 0  # the major axis (the first of equal ones, as numpy's argmax)
        if abs(D[i, 1]) > abs(D[i, 0]):
            kz = 1
        if abs(D[i, 2]) > abs(D[i, kz]):
            kz = 2
        kx, ky = (kz + 1) % 3, (kz + 2) % 3
        dz = D[i, kz]
        sx, sy = D[i, kx] / dz, D[i, ky] / dz
        a_lo, a_hi = seg_lo[i], seg_hi[i]
        found = 0
        top = 0
        stack[0] = 0
        while top >= 0:
            node = stack[top]
            top -= 1
            # the segment against the node's box grown by the slack (slabs)
            t0, t1 = a_lo, a_hi
            for a in range(3):
                da = D[i, a]
                oa = o[i, a]
                lo_a, hi_a = node_lo[node, a] - slack, node_hi[node, a] + slack
                if da == 0.0:
                    if oa < lo_a or oa > hi_a:
                        t0, t1 = 1.0, 0.0
                        break
                else:
                    u0, u1 = (lo_a - oa) / da, (hi_a - oa) / da
                    if u0 > u1:
                        u0, u1 = u1, u0
                    t0, t1 = max(t0, u0), min(t1, u1)
                    if t0 > t1:
                        break
            if t0 > t1:
                continue
            if child[node] >= 0:
                top += 1
                stack[top] = child[node]
                top += 1
                stack[top] = child[node] + 1
                continue
            for j in range(start[node], start[node] + count[node]):
                f = order[j]
                ia, ib, ic = faces[f, 0], faces[f, 1], faces[f, 2]
                # sheared vertex coordinates (x, y, z): they depend on the vertex and the line only
                z = vertices[ia, kz] - o[i, kz]
                ax, ay, az = (vertices[ia, kx] - o[i, kx]) - sx * z, (vertices[ia, ky] - o[i, ky]) - sy * z, z
                z = vertices[ib, kz] - o[i, kz]
                bx, by, bz = (vertices[ib, kx] - o[i, kx]) - sx * z, (vertices[ib, ky] - o[i, ky]) - sy * z, z
                z = vertices[ic, kz] - o[i, kz]
                cx, cy, cz = (vertices[ic, kx] - o[i, kx]) - sx * z, (vertices[ic, ky] - o[i, ky]) - sy * z, z
                U = cx * by - cy * bx  # edge b -> c, the weight of a
                V = ax * cy - ay * cx  # edge c -> a
                W = bx * ay - by * ax  # edge a -> b
                su, sv, sw = _tie(U, cy - by, bx - cx), _tie(V, ay - cy, cx - ax), _tie(W, by - ay, ax - bx)
                if not ((su > 0 and sv > 0 and sw > 0) or (su < 0 and sv < 0 and sw < 0)):
                    continue
                det = U + V + W
                if det == 0:  # edge-on: the moved line misses it (its neighbours count the crossing)
                    continue
                t = (U * az + V * bz + W * cz) / (det * dz)
                if t < a_lo or t > a_hi:
                    continue
                if found < cap:
                    out_face[r, found] = f
                    out_t[r, found] = t
                    # det = -(n . D) / D[kz]: entering (n . D < 0) where det and D[kz] agree
                    out_ent[r, found] = (det > 0) == (dz > 0)
                found += 1
        out_n[r] = found


class MeshTree:
    """The tree of a mesh's triangles (built once per workpiece) and the crossings of lines with them."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray) -> None:
        self.vertices = np.ascontiguousarray(vertices, dtype=float)
        self.faces = np.ascontiguousarray(faces, dtype=np.int64)
        n = len(self.faces)
        lo, hi = np.empty((n, 3)), np.empty((n, 3))
        for s in range(0, n, 1 << 20):  # the triangles' boxes a block at a time (16M triangles: ~1 GB at once)
            tri = self.vertices[self.faces[s : s + (1 << 20)]]  # (block, 3 vertices, 3)
            lo[s : s + len(tri)], hi[s : s + len(tri)] = tri.min(axis=1), tri.max(axis=1)
        (self.node_lo, self.node_hi, self.child, self.start, self.count, self.order, self.depth) = build(lo, hi, LEAF)

    def crossings(
        self, o: np.ndarray, D: np.ndarray, lo: np.ndarray, hi: np.ndarray, live: np.ndarray, slack: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Every (line, face, d, entering) where a live segment o + d D, d in [lo, hi], crosses a triangle; lines
        ascending, each (line, face) once."""
        rows = np.nonzero(live)[0].astype(np.int64)
        # writable C copies: a read-only or strided operand is another signature, compiled on the first run
        o, D, lo, hi = (np.array(a, dtype=float, order="C") for a in (o, D, lo, hi))
        n = len(rows)
        face = np.empty((n, FIRST_CAP), np.int64)
        t = np.empty((n, FIRST_CAP))
        ent = np.empty((n, FIRST_CAP), bool)
        found = np.zeros(n, np.int64)
        self._walk(rows, o, D, lo, hi, slack, face, t, ent, found)
        keep = np.minimum(found, FIRST_CAP)
        mask = np.arange(FIRST_CAP)[None, :] < keep[:, None]
        line, f, d, e = np.repeat(rows, keep), face[mask], t[mask], ent[mask]
        more = np.nonzero(found > FIRST_CAP)[0]
        if more.size:  # lines through many triangles (an inside() ray across the part): again, with room for all
            cap = int(found[more].max())
            face = np.empty((more.size, cap), np.int64)
            t = np.empty((more.size, cap))
            ent = np.empty((more.size, cap), bool)
            again = np.zeros(more.size, np.int64)
            self._walk(rows[more], o, D, lo, hi, slack, face, t, ent, again)
            mask = np.arange(cap)[None, :] < again[:, None]
            drop = np.isin(line, rows[more])
            line = np.concatenate([line[~drop], np.repeat(rows[more], again)])
            f, d, e = (np.concatenate([x[~drop], y[mask]]) for x, y in ((f, face), (d, t), (e, ent)))
            s = np.argsort(line, kind="stable")
            line, f, d, e = line[s], f[s], d[s], e[s]
        return line, f, d, e

    def _walk(self, rows, o, D, lo, hi, slack, face, t, ent, found) -> None:
        run_chunks(
            cross_lines,
            len(rows),
            rows,
            o,
            D,
            lo,
            hi,
            self.node_lo,
            self.node_hi,
            self.child,
            self.start,
            self.count,
            self.order,
            int(self.depth),
            self.vertices,
            self.faces,
            float(slack),
            face,
            t,
            ent,
            found,
            smallest=256,
        )


def warm() -> None:
    """Compile the kernels on a tetrahedron (the editable install runs this module: build_backend/skive_build.py)."""
    v = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    MeshTree(v, f).crossings(
        np.array([[0.2, 0.2, -1.0]]),
        np.array([[0.0, 0.0, 1.0]]),
        np.array([-5.0]),
        np.array([5.0]),
        np.ones(1, bool),
        1e-7,
    )


if __name__ == "__main__":  # the editable install runs this after cutting.warmup (build_backend/skive_build.py)
    warm()
    print("skive: the mesh probe's kernels are compiled and cached")
