"""A closed triangle mesh as a measuring machine's workpiece, probed along lines.

A gear measuring machine touches its workpiece along nominal directions; on a mesh that is where a line crosses
the triangles. Crossings are exact for the mesh as given (float64, no smoothing). The ray-triangle test is the
watertight one of Woop, Benthin and Wald (JCGT 2013): the line is sheared onto +z and every edge is judged by a
2-D edge function that depends only on the edge's two vertices, so the two triangles of an edge judge it with
exactly opposite signs. Where an edge function is exactly zero (the line through an edge or a vertex), the tie
is broken by simulation of simplicity: the line is taken as moved by (eps, eps^2) in the sheared plane, which
gives every edge a definite side. A line through an edge or vertex is thus seen by exactly one triangle of the
fan where the surface is crossed there, and by none or an entering/leaving pair where it only touches.

Meshes are large (50k to 16M triangles), mostly of small triangles, but end faces and uncut cylinders hold
long, skinny ones spanning millimetres (and an analytic gear's flanks are strips the face long). The search is a
bounding volume hierarchy of the triangles' boxes, compiled (:mod:`metrology.mesh_bvh`): a box judges a skinny
triangle by its own extent, and each line walks only the boxes its segment enters.
"""

from __future__ import annotations

import numpy as np

from metrology.mesh_bvh import MeshTree
from metrology.sections import MeshData

#: Crossings of one line closer than this [mm] with the same ``entering`` flag are reported as one.
MERGE_DISTANCE = 1e-9

# Ray direction of inside(): oblique to every axis and axis diagonal; its largest component goes along the
# shortest extent of the mesh (short rays).
_INSIDE_DIRECTION = np.array([0.8979, 0.3371, 0.2832])


class MeshWorkpiece:
    """A closed triangle mesh (outward-oriented, watertight) probed along lines.

    Parameters
    ----------
    mesh : MeshData
        Vertices [mm] and faces, counter-clockwise seen from outside (outward normal (b - a) x (c - a)).
    name : str
        Label for reports.

    Notes
    -----
    The search structure is built on first use and kept: the same workpiece is probed many times.
    """

    kind = "mesh"

    def __init__(self, mesh: MeshData, name: str = "mesh") -> None:
        self.mesh = mesh
        self.name = name
        self._tree: MeshTree | None = None
        v = mesh.vertices
        self._box_lo = v.min(axis=0) if len(v) else np.zeros(3)
        self._box_hi = v.max(axis=0) if len(v) else np.zeros(3)
        scale = float(np.abs(np.concatenate([self._box_lo, self._box_hi])).max()) if len(v) else 1.0
        # slack on every pruning distance: far above rounding, harmless (it only admits more candidates)
        self._slack = 1e-7 + 1e-12 * scale

    # ---- public API ---------------------------------------------------------------------------------
    def crossings(
        self, origins: np.ndarray, directions: np.ndarray, lo: float | np.ndarray, hi: float | np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every place where the segments ``origins[i] + d * directions[i]``, d in [lo_i, hi_i], cross the surface.

        Parameters
        ----------
        origins, directions : (n, 3)
            Lines; directions need not be unit (d is then in units of the direction's length).
        lo, hi : float or (n,)
            Finite range of d per line.

        Returns
        -------
        line : (m,) int64
            Index of the line, ascending.
        d : (m,) float64
            Where the line crosses, ascending within a line; exact for the mesh as given (to rounding, ~1e-14 mm).
        entering : (m,) bool
            True where moving towards +d enters material (outward normal . direction < 0). Crossings of a line
            with the same flag closer than ``MERGE_DISTANCE`` mm are reported once. A line that only touches the
            surface at an edge or vertex gives an entering and a leaving crossing at the same d, or none.
        """
        line, d, entering = self._crossings(origins, directions, lo, hi)
        return line, d, entering

    def probe(self, points: np.ndarray, directions: np.ndarray, reach: float | np.ndarray) -> np.ndarray:
        """Where a probe coming from the air side along each line first touches material.

        Parameters
        ----------
        points : (n, 3)
            Nominal surface points [mm].
        directions : (n, 3)
            Nominal outward directions (out of the material, into air); normalised here.
        reach : float or (n,)
            Half-length of the probed segment [mm].

        Returns
        -------
        (n,) float64
            Signed distance d [mm] along the direction: the largest crossing d in [-reach, reach] at which
            moving towards -d enters material (outward normal . direction > 0). NaN where the first crossing met
            from +reach is a leaving one (the +reach end is inside material) or where there is none. A line that
            touches an edge (entering and leaving at the same d) touches there.
        """
        points = np.atleast_2d(np.asarray(points, dtype=float))
        u = np.atleast_2d(np.asarray(directions, dtype=float))
        u = u / np.linalg.norm(u, axis=1, keepdims=True)
        n = len(points)
        reach = np.broadcast_to(np.asarray(reach, dtype=float), (n,))
        line, d, entering = self._crossings(points, u, -reach, reach)
        out = np.full(n, np.nan)
        if line.size == 0:
            return out
        top = np.full(n, -np.inf)
        last = np.append(line[1:] != line[:-1], True)  # sorted by line, then d: the largest d of each line
        top[line[last]] = d[last]
        touch = (d >= top[line] - MERGE_DISTANCE) & ~entering  # met first from +reach, and entering towards -d
        best = np.full(n, -np.inf)
        np.maximum.at(best, line[touch], d[touch])
        hit = np.isfinite(best)
        out[hit] = best[hit]
        return out

    def inside(self, points: np.ndarray) -> np.ndarray:
        """Whether each point is inside the material: parity of the crossings of a ray to outside the bounding box.

        The ray is oblique to every axis and axis diagonal (machined parts are full of axis-aligned edges) and
        goes mostly along the shortest extent of the mesh. A ray exactly through an edge or vertex needs no other
        direction: the tie rule of the crossing test counts it as a ray moved off it would be counted. Points on
        the surface (within rounding) may go either way.

        Parameters
        ----------
        points : (n, 3)

        Returns
        -------
        (n,) bool
        """
        points = np.atleast_2d(np.asarray(points, dtype=float))
        result = np.zeros(len(points), dtype=bool)
        margin = self._slack
        lo, hi = self._box_lo - margin, self._box_hi + margin
        todo = np.nonzero(np.all((points >= lo) & (points <= hi), axis=1))[0]
        if todo.size == 0 or len(self.mesh.faces) == 0:
            return result
        u = self.inside_direction()
        p = points[todo]
        line, _, _ = self._crossings(p, np.broadcast_to(u, p.shape), 0.0, _exit_distance(p, u, lo, hi), merge=False)
        result[todo] = np.bincount(line, minlength=len(todo)) % 2 == 1
        return result

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The bounding box (lo, hi) [mm] of the vertices: holds the whole workpiece."""
        return self._box_lo.copy(), self._box_hi.copy()

    def inside_direction(self) -> np.ndarray:
        """The unit ray direction of :meth:`inside` for this mesh."""
        u = np.zeros(3)
        u[np.argsort(self._box_hi - self._box_lo)] = _INSIDE_DIRECTION
        return u / np.linalg.norm(u)

    # ---- search structure ---------------------------------------------------------------------------
    @property
    def tree(self) -> MeshTree:
        """The triangles' hierarchy of boxes, built on first use."""
        if self._tree is None:
            self._tree = MeshTree(self.mesh.vertices, self.mesh.faces)
        return self._tree

    # ---- crossings ----------------------------------------------------------------------------------
    def _crossings(
        self,
        origins: np.ndarray,
        directions: np.ndarray,
        lo: float | np.ndarray,
        hi: float | np.ndarray,
        merge: bool = True,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`crossings`; ``merge=False`` keeps same-flag crossings closer than ``MERGE_DISTANCE`` (parity)."""
        o = np.ascontiguousarray(np.atleast_2d(origins), dtype=float)
        D = np.ascontiguousarray(np.atleast_2d(directions), dtype=float)
        n = len(o)
        if o.shape != (n, 3) or D.shape != (n, 3):
            raise ValueError(f"origins {o.shape} and directions {D.shape} must both be (n, 3)")
        lo = np.broadcast_to(np.asarray(lo, dtype=float), (n,))
        hi = np.broadcast_to(np.asarray(hi, dtype=float), (n,))
        if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
            raise ValueError("lo and hi must be finite")
        empty = (np.empty(0, np.int64), np.empty(0), np.empty(0, bool))
        if n == 0 or len(self.mesh.faces) == 0:
            return empty
        dn = np.linalg.norm(D, axis=1)
        # only the part of a segment inside the (slightly grown) bounding box can cross anything
        c_lo, c_hi = _clip_to_box(o, D, lo, hi, self._box_lo - self._slack, self._box_hi + self._slack)
        live = (c_lo <= c_hi) & (dn > 0)
        line, _, t, ent = self.tree.crossings(
            o, D, np.ascontiguousarray(lo), np.ascontiguousarray(hi), live, self._slack
        )
        if line.size == 0:
            return empty
        if merge:
            s = np.lexsort((t, ent, line))
            line, t, ent = line[s], t[s], ent[s]
            same = (line[1:] == line[:-1]) & (ent[1:] == ent[:-1]) & (t[1:] - t[:-1] <= MERGE_DISTANCE / dn[line[1:]])
            keep = np.append(True, ~same)
            line, t, ent = line[keep], t[keep], ent[keep]
        s = np.lexsort((t, line))
        return line[s], t[s], ent[s]


def _clip_to_box(
    o: np.ndarray, D: np.ndarray, lo: np.ndarray, hi: np.ndarray, box_lo: np.ndarray, box_hi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Range of d in [lo, hi] where o + d D lies in the box (empty where the first exceeds the second)."""
    a, b = lo.copy(), hi.copy()
    for k in range(3):
        dk = D[:, k]
        flat = dk == 0
        with np.errstate(divide="ignore", invalid="ignore"):
            t1 = (box_lo[k] - o[:, k]) / dk
            t2 = (box_hi[k] - o[:, k]) / dk
        a = np.maximum(a, np.where(flat, -np.inf, np.minimum(t1, t2)))
        b = np.minimum(b, np.where(flat, np.inf, np.maximum(t1, t2)))
        b = np.where(flat & ((o[:, k] < box_lo[k]) | (o[:, k] > box_hi[k])), -np.inf, b)
    return a, b


def _exit_distance(p: np.ndarray, u: np.ndarray, box_lo: np.ndarray, box_hi: np.ndarray) -> np.ndarray:
    """Distance along ``u`` from points inside the box to where the ray leaves it."""
    with np.errstate(divide="ignore", invalid="ignore"):
        far = np.where(u > 0, (box_hi - p) / u, np.where(u < 0, (box_lo - p) / u, np.inf))
    return np.maximum(far.min(axis=1), 0.0)
