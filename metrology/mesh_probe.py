"""A closed triangle mesh as a measuring machine's workpiece, probed along lines.

A gear measuring machine touches its workpiece along nominal directions; on a mesh that is where a line crosses
the triangles. Crossings are exact for the mesh as given (float64, no smoothing). The ray-triangle test is the
watertight one of Woop, Benthin and Wald (JCGT 2013): the line is sheared onto +z and every edge is judged by a
2-D edge function that depends only on the edge's two vertices, so the two triangles of an edge judge it with
exactly opposite signs. Where an edge function is exactly zero (the line through an edge or a vertex), the tie
is broken by simulation of simplicity: the line is taken as moved by (eps, eps^2) in the sheared plane, which
gives every edge a definite side. A line through an edge or vertex is thus seen by exactly one triangle of the
fan where the surface is crossed there, and by none or an entering/leaving pair where it only touches.

Meshes are large (50k to 16M triangles) and most triangles are small, but end faces and uncut cylinders hold
long, skinny ones spanning millimetres. Triangles are bounded by spheres, kept in tiers of similar radius
(factors of 1.5), one k-d tree of sphere centres per tier, built on first use and reused. A triangle much larger
than most is covered by the spheres of its pieces under longest-edge bisection (its own sphere would be near
every line). A call cuts each line, per tier, into pieces about as long as the tier's spheres are wide: the
spheres a piece must consider then fill a ball of some twice their radius, and fewer, longer pieces would each
consider many more. Long lines are first halved only where some sphere is near, so rays through air or
material cost little. Each piece asks for the sphere centres within reach (k nearest with a distance bound:
fixed-width arrays, no Python lists, threaded); the spheres that really reach the piece give the (line,
triangle) pairs for the exact test, handled in chunks of bounded size.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from metrology.sections import MeshData

#: Crossings of one line closer than this [mm] with the same ``entering`` flag are reported as one.
MERGE_DISTANCE = 1e-9

_TIER_FACTOR = 1.5  # sphere radii within a tier span this factor: the search radius fits most of them
_MAX_TIERS = 16
_MIN_TIER_SIZE = 256  # smaller tiers join the next coarser one: a tree for a handful of spheres costs more
_COVER_SHARE = 8  # large triangles are cut until their pieces number at most (faces / this), see _build
_COVER_MIN = 250_000  # ... or this many (a few MB), whichever is more
_PAIRS_PER_CHUNK = 1_000_000  # (line, triangle) pairs handled at once: some 100-200 MB of temporaries
_MAX_K = 256  # most centres asked per piece at first (more come by asking again)
_DIRECT = 32.0  # pieces longer than this many tier radii are halved where a sphere is near, shorter ones cut
_WORKERS = -1  # threads of the k-d tree queries
#: queries of fewer points run on one thread: scipy starts and joins its threads on every call (~1-2 ms of a
#: measurement's ~1600 queries on spur_external's gear.stl, 2.5 of its 6 s), more than a small query takes
_PARALLEL_QUERY = 4096
# Ray direction of inside(): oblique to every axis and axis diagonal; its largest component goes along the
# shortest extent of the mesh (short rays).
_INSIDE_DIRECTION = np.array([0.8979, 0.3371, 0.2832])


@dataclass
class _Tier:
    """Spheres no larger than ``radius``, each around a triangle or a piece of one."""

    radius: float
    faces: np.ndarray  # (k,) face index of each sphere (a large triangle has several), in the tree's order
    centres: np.ndarray  # (k, 3) sphere centres: the tree's data
    radii: np.ndarray  # (k,) sphere radii
    tree: cKDTree
    k: int = 16  # centres asked per piece at first: learnt from the counts found, see _candidates


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
        self._tiers: list[_Tier] | None = None
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
    def tiers(self) -> list[_Tier]:
        """The sphere tiers, built on first use."""
        if self._tiers is None:
            self._tiers = self._build()
        return self._tiers

    def _build(self) -> list[_Tier]:
        """Tiers of bounding spheres by radius, one k-d tree over the sphere centres per tier.

        A triangle much larger than most (end faces, uncut cylinders: often slivers across the part) would be a
        candidate for every line near its sphere, so it is covered by the spheres of its pieces under
        longest-edge bisection, each no wider than ``cap``; all of them stand for the one triangle.
        """
        v, f = self.mesh.vertices, self.mesh.faces
        n = len(f)
        if n == 0:
            return []
        centres = np.empty((n, 3))
        radii = np.empty(n)
        area = np.empty(n)
        step = 1 << 20
        for s in range(0, n, step):
            a, b, c = (v[f[s : s + step, k]] for k in range(3))
            centres[s : s + step], radii[s : s + step] = _bounding_spheres(a, b, c)
            area[s : s + step] = 0.5 * np.sqrt(_sq(np.cross(b - a, c - a)))
        # cap: above nearly every triangle, raised until the covering pieces are few (memory), lowered while they
        # stay few (a mesh of long triangles, e.g. an analytic spur gear, would otherwise see every sphere from
        # every line). Bisection leaves pieces of some cap^2 / 4 in area, slivers some 2 cap in length.
        budget = max(n / _COVER_SHARE, _COVER_MIN)
        cap = max(2.0 * float(np.quantile(radii, 0.9)), 1e-9)
        floor = 2.0 * float(np.quantile(radii, 0.1))
        while cap / 2 > floor and _cover_pieces(radii, area, cap / 2) <= budget:
            cap /= 2
        while _cover_pieces(radii, area, cap) > budget:
            cap *= 2
        big = np.nonzero(radii > cap)[0]
        del area
        index = np.int32 if n < 2**31 else np.int64
        face = np.arange(n, dtype=index)
        if big.size:
            sub_f, sub_c, sub_r = _cover(v, f, big, cap)
            keep = np.ones(n, dtype=bool)
            keep[big] = False
            face = np.concatenate([face[keep], sub_f.astype(index)])
            centres = np.concatenate([np.compress(keep, centres, axis=0), sub_c])
            radii = np.concatenate([radii[keep], sub_r])
            del sub_f, sub_c, sub_r, keep
        rmax = max(float(radii.max()), 1e-300)
        level = np.floor(np.log(rmax / np.maximum(radii, 1e-300)) / np.log(_TIER_FACTOR))
        level = np.clip(level, 0, _MAX_TIERS - 1).astype(np.int8)
        counts = np.bincount(level, minlength=_MAX_TIERS)
        for k in range(_MAX_TIERS - 1, 0, -1):  # small tiers join the next coarser one (a safe radius bound)
            if 0 < counts[k] < _MIN_TIER_SIZE:
                counts[k - 1] += counts[k]
                counts[k] = 0
                level[level == k] = k - 1
        # float32 radii, raised past their rounding (1e-6 relative > 6e-8): a fifth less memory per sphere
        radii = (radii * (1 + 1e-6)).astype(np.float32)
        parts = []
        for k in np.nonzero(counts)[0]:
            member = level == k
            parts.append((np.compress(member, centres, axis=0), face[member], radii[member]))
        del centres, face, radii, level  # the tiers' copies replace them before the trees take their memory
        tiers = []
        for c, fk, rk in parts:
            tree = cKDTree(c, leafsize=16, balanced_tree=False, compact_nodes=False)
            tiers.append(_Tier(float(rk.max()), fk, c, rk, tree))
        return tiers

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
        ray = _Shear(D)
        parts = []
        for tier in self.tiers:
            for L, faces in self._candidates(tier, o, D, dn, c_lo, c_hi, live):
                hit = _intersect(self.mesh.vertices, self.mesh.faces, o, ray, L, faces)
                ok = (hit[2] >= lo[hit[0]]) & (hit[2] <= hi[hit[0]])
                parts.append(tuple(x[ok] for x in hit))
        if not parts:
            return empty
        line, face, t, ent = (np.concatenate(x) for x in zip(*parts, strict=True))
        if line.size == 0:
            return empty
        # one crossing per (line, triangle): a triangle may be found by two pieces of a line in different chunks
        _, first = np.unique(line * len(self.mesh.faces) + face, return_index=True)
        line, t, ent = line[first], t[first], ent[first]
        if merge:
            s = np.lexsort((t, ent, line))
            line, t, ent = line[s], t[s], ent[s]
            same = (line[1:] == line[:-1]) & (ent[1:] == ent[:-1]) & (t[1:] - t[:-1] <= MERGE_DISTANCE / dn[line[1:]])
            keep = np.append(True, ~same)
            line, t, ent = line[keep], t[keep], ent[keep]
        s = np.lexsort((t, line))
        return line[s], t[s], ent[s]

    def _candidates(
        self,
        tier: _Tier,
        o: np.ndarray,
        D: np.ndarray,
        dn: np.ndarray,
        lo: np.ndarray,
        hi: np.ndarray,
        live: np.ndarray,
    ) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """(line, face) pairs of ``tier`` whose sphere a segment's piece reaches, unique within each chunk.

        A piece of half-length h around m reaches a sphere (c, r) only if |c - m| <= h + r: every point of the
        piece is within h of m, and a crossing lies on the triangle, inside its sphere.
        """
        R = tier.radius
        target = max(R, 1e-9)  # half-length of the pieces asked for sphere centres (near-optimal, see above)
        slack = self._slack
        n_faces = len(self.mesh.faces)
        size = len(tier.faces)
        pl = np.nonzero(live)[0]
        p0, p1 = lo[pl], hi[pl]
        done_l, done_0, done_1 = [], [], []
        while pl.size:
            hl = 0.5 * (p1 - p0) * dn[pl]
            # short enough: cut at once into equal pieces no longer than the target
            short = hl <= _DIRECT * target
            m = np.maximum(np.ceil(hl[short] / target), 1).astype(np.int64)
            k = np.arange(m.sum()) - np.repeat(np.cumsum(m) - m, m)  # piece number within its line
            a, w = np.repeat(p0[short], m), np.repeat((p1 - p0)[short], m)
            done_l.append(np.repeat(pl[short], m))
            m = np.repeat(m, m)
            done_0.append(a + w * k / m)
            done_1.append(a + w * (k + 1) / m)
            pl, p0, p1, hl = pl[~short], p0[~short], p1[~short], hl[~short]
            if pl.size == 0:
                break
            # long (rays through the part): halve, keeping the halves of pieces that have a sphere within reach
            mid = 0.5 * (p0 + p1)
            reach = hl + R + slack
            at = o[pl] + mid[:, None] * D[pl]
            dist, _ = tier.tree.query(at, distance_upper_bound=reach.max(), workers=_workers(len(at)))
            near = dist <= reach
            pl, a, b, mid = pl[near], p0[near], p1[near], mid[near]
            pl = np.concatenate([pl, pl])
            p0, p1 = np.concatenate([a, mid]), np.concatenate([mid, b])
        pl, p0, p1 = np.concatenate(done_l), np.concatenate(done_0), np.concatenate(done_1)
        if pl.size == 0:
            return
        mids = o[pl] + (0.5 * (p0 + p1))[:, None] * D[pl]
        hl = 0.5 * (p1 - p0) * dn[pl]
        # neighbouring pieces together (Z order): the searches walk the same part of the tree, and the pieces of
        # a line mostly share a chunk, where their common pairs are merged
        s = np.argsort(_morton(mids, self._box_lo, self._box_hi), kind="stable")
        pl, mids, hl = pl[s], mids[s], hl[s]
        unit = D[pl] / dn[pl, None]
        bound = float(hl.max()) + R + slack
        start = 0
        while start < pl.size:
            # k: the tier's learnt guess of the centres within reach (kept across calls), so that few rows come
            # back full and need asking again with a larger k
            k = min(tier.k, size)
            todo = np.arange(start, min(start + max(_PAIRS_PER_CHUNK // k, 1000), pl.size))
            start += todo.size
            first = True
            while todo.size:
                k = min(k, size)
                dist, j = tier.tree.query(mids[todo], k=k, distance_upper_bound=bound, workers=_workers(len(todo)))
                dist, j = dist.reshape(len(todo), k), j.reshape(len(todo), k)
                full = np.isfinite(dist[:, -1]) & (k < size)  # maybe more within reach: ask again, k x 4
                if first:
                    count = np.isfinite(dist).sum(axis=1)
                    if full.mean() > 0.05:
                        tier.k = min(4 * k, _MAX_K)
                    elif np.quantile(count, 0.95) < k / 3:
                        tier.k = max(k // 2, 4)
                    first = False
                dist, j, rows = dist[~full], j[~full], todo[~full]
                todo = todo[full]
                k *= 4
                found = dist <= hl[rows, None] + slack + tier.radii[np.minimum(j, size - 1)]
                i, j, dist = np.broadcast_to(rows[:, None], found.shape)[found], j[found], dist[found]
                # the sphere must reach the piece itself, not only the ball around it: along the line within
                # the half-length, across it within the radius (the distance |c - m| is small: no cancellation)
                r = tier.radii[j] + slack
                along = np.einsum("ij,ij->i", tier.centres[j] - mids[i], unit[i])
                keep = (np.abs(along) <= hl[i] + r) & (dist * dist - along * along <= r * r)
                if not keep.any():
                    continue
                key = np.sort(pl[i[keep]] * n_faces + tier.faces[j[keep]])
                key = key[np.append(True, key[1:] != key[:-1])]
                for s0 in range(0, key.size, _PAIRS_PER_CHUNK):
                    part = key[s0 : s0 + _PAIRS_PER_CHUNK]
                    yield part // n_faces, part % n_faces


def _workers(points: int) -> int:
    """Threads for a k-d tree query of ``points`` points (the results do not depend on it)."""
    return _WORKERS if points >= _PARALLEL_QUERY else 1


class _Shear:
    """Per line: the shear of the watertight test that maps the direction onto the major axis kz."""

    def __init__(self, D: np.ndarray) -> None:
        rows = np.arange(len(D))
        self.kz = np.argmax(np.abs(D), axis=1)
        dz = D[rows, self.kz]
        self.dz = np.where(dz == 0, 1.0, dz)  # zero directions are never tested (see live)
        self.Sx = D[rows, (self.kz + 1) % 3] / self.dz
        self.Sy = D[rows, (self.kz + 2) % 3] / self.dz


def _intersect(
    vertices: np.ndarray, faces: np.ndarray, o: np.ndarray, ray: _Shear, L: np.ndarray, f: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Watertight test of the pairs (line L[i], face f[i]): (line, face, d, entering) of those that cross.

    The sheared vertex coordinates depend only on (vertex, line), so an edge shared by two triangles has
    exactly opposite edge functions in both; an exactly zero one takes the sign of its derivative along the
    perturbation (eps, eps^2), which is exactly opposite too. x and y are not swapped for a negative major
    component (Woop et al. do, to keep the orientation): the orientation is recovered from its sign instead.
    """
    out = []
    for kz in range(3):
        sel = np.nonzero(ray.kz[L] == kz)[0]
        if sel.size == 0:
            continue
        kx, ky = (kz + 1) % 3, (kz + 2) % 3
        Lg, fg = L[sel], f[sel]
        tri = faces[fg]
        og, sx, sy = o[Lg], ray.Sx[Lg], ray.Sy[Lg]
        P = []
        for col in range(3):
            X = vertices[tri[:, col]] - og
            z = X[:, kz]
            P.append((X[:, kx] - sx * z, X[:, ky] - sy * z, z))
        (ax, ay, az), (bx, by, bz), (cx, cy, cz) = P
        U = _tie(cx * by - cy * bx, cy - by, bx - cx)  # edge b -> c, the weight of a
        V = _tie(ax * cy - ay * cx, ay - cy, cx - ax)  # edge c -> a
        W = _tie(bx * ay - by * ax, by - ay, ax - bx)  # edge a -> b
        hit = ((U[1] > 0) & (V[1] > 0) & (W[1] > 0)) | ((U[1] < 0) & (V[1] < 0) & (W[1] < 0))
        det = U[0] + V[0] + W[0]
        hit &= det != 0  # edge-on: the moved line misses it (its neighbours count the crossing)
        h = np.nonzero(hit)[0]
        if h.size == 0:
            continue
        U, V, W, det, Lh = U[0][h], V[0][h], W[0][h], det[h], Lg[h]
        t = (U * az[h] + V * bz[h] + W * cz[h]) / (det * ray.dz[Lh])
        # det = -(n . D) / D[kz] with n = (b - a) x (c - a): entering (n . D < 0) where det and D[kz] agree
        entering = (det > 0) == (ray.dz[Lh] > 0)
        out.append((Lh, fg[h], t, entering))
    if not out:
        return np.empty(0, np.int64), np.empty(0, np.int64), np.empty(0), np.empty(0, bool)
    return tuple(np.concatenate(x) for x in zip(*out, strict=True))


def _tie(e: np.ndarray, dx: np.ndarray, dy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Edge function ``e`` and its sign with exact zeros broken by the perturbation (eps, eps^2): (e, signed)."""
    zero = e == 0
    if not zero.any():
        return e, e
    return e, np.where(zero, np.where(dx != 0, dx, dy), e)


def _bounding_spheres(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centre and radius of a small sphere around each triangle (a, b, c), each (k, 3).

    The midpoint of the longest edge when the third vertex lies within (right, obtuse and skinny triangles:
    the smallest sphere), else the centroid; skinny triangles are common on end faces, where this sphere is a
    quarter smaller than the centroid's.
    """
    l_ab, l_bc, l_ca = _sq(b - a), _sq(c - b), _sq(a - c)
    ab = (l_ab >= l_bc) & (l_ab >= l_ca)
    bc = ~ab & (l_bc >= l_ca)
    ca = ~ab & ~bc
    centre = 0.5 * (a + b)
    centre[bc] = 0.5 * (b[bc] + c[bc])
    centre[ca] = 0.5 * (c[ca] + a[ca])
    third = c.copy()
    third[bc] = a[bc]
    third[ca] = b[ca]
    r2 = 0.25 * np.maximum(np.maximum(l_ab, l_bc), l_ca)
    far = np.nonzero(_sq(third - centre) > r2)[0]  # acute: the third vertex sticks out, take the centroid
    if far.size:
        g = (a[far] + b[far] + c[far]) / 3
        centre[far] = g
        r2[far] = np.maximum(np.maximum(_sq(a[far] - g), _sq(b[far] - g)), _sq(c[far] - g))
    return centre, np.sqrt(r2) * (1 + 1e-12)


def _sq(x: np.ndarray) -> np.ndarray:
    """Squared norms of the rows of x (k, 3)."""
    return np.einsum("ij,ij->i", x, x)


def _cover(
    vertices: np.ndarray, faces: np.ndarray, big: np.ndarray, cap: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Spheres no wider than ``cap`` covering the triangles ``big``: (face, centre, radius) per sphere.

    Longest-edge bisection: a sliver of length l gives some l / cap pieces, not (l / cap)^2 as a uniform
    subdivision would.
    """
    out_f, out_c, out_r = [], [], []
    for s in range(0, len(big), 1 << 14):  # bounded temporaries: the pieces of one batch
        face = big[s : s + (1 << 14)]
        a, b, c = (vertices[faces[face, j]] for j in range(3))
        while len(face):
            centre, r = _bounding_spheres(a, b, c)
            ok = r <= cap
            out_f.append(face[ok])
            out_c.append(centre[ok])
            out_r.append(r[ok])
            face, a, b, c = face[~ok], a[~ok], b[~ok], c[~ok]
            # bisect the longest edge: (p, q) with third vertex w -> (p, m, w) and (m, q, w), same orientation
            l_ab, l_bc, l_ca = _sq(b - a), _sq(c - b), _sq(a - c)
            ab = (l_ab >= l_bc) & (l_ab >= l_ca)
            bc = ~ab & (l_bc >= l_ca)
            p = np.where(ab[:, None], a, np.where(bc[:, None], b, c))
            q = np.where(ab[:, None], b, np.where(bc[:, None], c, a))
            w = np.where(ab[:, None], c, np.where(bc[:, None], a, b))
            m = 0.5 * (p + q)
            face = np.concatenate([face, face])
            a, b, c = np.concatenate([p, m]), np.concatenate([m, q]), np.concatenate([w, w])
    return np.concatenate(out_f), np.concatenate(out_c), np.concatenate(out_r)


def _morton(x: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Z-order key of points in the box (10 bits per axis): sorting by it keeps neighbours together."""
    q = np.clip((x - lo) / np.maximum(hi - lo, 1e-300) * 1023, 0, 1023).astype(np.int64)
    key = np.zeros(len(x), dtype=np.int64)
    for bit in range(10):
        for axis in range(3):
            key |= ((q[:, axis] >> bit) & 1) << (3 * bit + axis)
    return key


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


def _cover_pieces(radii: np.ndarray, area: np.ndarray, cap: float) -> float:
    """About how many pieces longest-edge bisection leaves of the triangles wider than ``cap``."""
    big = radii > cap
    return float((4 * area[big] / cap**2 + radii[big] / cap).sum())


def _exit_distance(p: np.ndarray, u: np.ndarray, box_lo: np.ndarray, box_hi: np.ndarray) -> np.ndarray:
    """Distance along ``u`` from points inside the box to where the ray leaves it."""
    with np.errstate(divide="ignore", invalid="ignore"):
        far = np.where(u > 0, (box_hi - p) / u, np.where(u < 0, (box_lo - p) / u, np.inf))
    return np.maximum(far.min(axis=1), 0.0)
