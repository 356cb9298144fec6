"""Form milling's removal with manifold3d: the mill's swept volume taken out of the blank, one tooth space after
another (the chips, the forces' volumes, gear.stl; the micrometre truth is :mod:`cutting.form_milling.sweep`).

The mill (a solid of revolution) is cut into frusta along its axis where its profile bends by more than the
tolerance; a frustum is convex, so what it sweeps between two poses that differ by a straight move is the
convex hull of its two placements. Each pass's poses are thinned to the fewest whose straight moves stay within
the tolerance of the path (and of the mill's turn, where its axis follows the path), and each circle of a frustum
is a polygon fine (chord within the tolerance) over the arc that can reach the blank and coarse elsewhere (a
disc's arc towards the gear axis; a finger mill's whole circle). The swept volume of a space is the union of those
hulls.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import manifold3d as mf
import numpy as np

from cutting.form_milling.mill import Mill
from cutting.form_milling.sweep import MillPassPoses
from cutting.gear import Gear
from cutting.skiving.solids import blank


def profile_slices(mill: Mill, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Axial positions u and edge heights h of the frusta's ends: the profile's polyline simplified so that no
    point of it is more than ``tol`` [mm] from a frustum (greedy: each frustum as long as it can be)."""
    u, h = mill.profile
    keep = [0]
    i = 0
    while i < len(u) - 1:
        lo, hi = i + 1, len(u) - 1
        while lo < hi:  # the farthest j whose chord i..j holds every point in between within tol
            mid = (lo + hi + 1) // 2
            if _chord_error(u, h, i, mid) <= tol:
                lo = mid
            else:
                hi = mid - 1
        i = lo
        keep.append(i)
    k = np.array(keep)
    return u[k], h[k]


def _chord_error(u: np.ndarray, h: np.ndarray, i: int, j: int) -> float:
    if j <= i + 1:
        return 0.0
    du, dh = u[j] - u[i], h[j] - h[i]
    norm = math.hypot(du, dh)
    return float(np.max(np.abs((u[i + 1 : j] - u[i]) * dh - (h[i + 1 : j] - h[i]) * du)) / norm)


def thin_poses(p: MillPassPoses, tol: float, reach: float = 0.0) -> np.ndarray:
    """Indices of the fewest poses whose straight moves keep every recorded centre within ``tol`` [mm], and every
    point of the mill within ``reach`` [mm] of its centre too where the axis turns between them (a mill turned by
    the path, :mod:`cutting.form_milling.copying_path`)."""
    c = p.centre
    a = p.axis / np.linalg.norm(p.axis, axis=1, keepdims=True)
    keep = [0]
    i, n = 0, len(c)
    while i < n - 1:
        j = i + 1
        step = 1
        while i + step < n:  # grow the run by doubling, then back off to the last one that holds
            if _run_error(c, a, i, min(i + step, n - 1), reach) > tol:
                break
            j = min(i + step, n - 1)
            if j == n - 1:
                break
            step *= 2
        lo, hi = j, min(i + step, n - 1)
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if _run_error(c, a, i, mid, reach) <= tol:
                lo = mid
            else:
                hi = mid - 1
        i = max(lo, i + 1)
        keep.append(i)
    return np.array(keep)


def _run_error(c: np.ndarray, a: np.ndarray, i: int, j: int, reach: float) -> float:
    """How far the straight move from pose i to pose j misses the poses between: the centres' distance from the
    chord, plus, where the axis turns, reach * theta_ik * theta_kj / 2 (a point at ``reach`` from the centre turns
    on an arc; the chord of its turn misses the arc by that much)."""
    if j <= i + 1:
        return 0.0
    d = c[j] - c[i]
    d = d / np.linalg.norm(d)
    v = c[i + 1 : j] - c[i]
    off = np.linalg.norm(v - np.outer(v @ d, d), axis=1)
    if reach > 0.0:
        inner = a[i + 1 : j]
        t_ik = np.arccos(np.clip(inner @ a[i], -1.0, 1.0))
        t_kj = np.arccos(np.clip(inner @ a[j], -1.0, 1.0))
        off = off + reach * t_ik * t_kj / 2
    return float(np.max(off))


def _circle(centre: np.ndarray, axis: np.ndarray, radius: float, down: np.ndarray, fine: float, reach: float):
    """Polygon of the circle (centre, axis, radius): chord ``fine`` [rad] within +-``reach`` of ``down`` (towards
    the gear axis), eight steps over the rest."""
    e1 = down - axis * (down @ axis)
    if np.linalg.norm(e1) < 1e-9 * np.linalg.norm(down):  # the axis points at the gear axis (a finger mill)
        e1 = np.cross(axis, [0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.cross(axis, [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    a_fine = np.linspace(-reach, reach, max(3, math.ceil(2 * reach / fine) + 1))
    a_rest = np.linspace(reach, 2 * math.pi - reach, 9)[1:-1] if reach < math.pi else np.empty(0)
    a = np.concatenate([a_fine, a_rest])
    return centre + radius * (np.outer(np.cos(a), e1) + np.outer(np.sin(a), e2))


@dataclass
class FormCutResult:
    """The cut: the gear solid and, per pass, the chip volume [mm^3] (space, side, volume)."""

    gear_solid: mf.Manifold
    chips: list[tuple[int, str, float]]
    hulls: int


def swept_hulls(gear: Gear, mill: Mill, p: MillPassPoses, tol: float) -> list[mf.Manifold]:
    """The convex pieces of the pass's swept volume (frustum x straight move) within ``tol`` [mm] of it: half of it
    for the profile's chords (outside the mill where its side is concave), half for the path's (either side); the
    circles' chords (inside) take half as well."""
    us, hs = profile_slices(mill, tol / 2)
    idx = thin_poses(p, tol / 2, math.hypot(mill.radius, mill.width / 2))
    depth = gear.tip_radius - gear.root_radius + 2 * tol
    reach = mill.reach_angle(depth)
    fine = 2 * math.acos(max(0.0, 1 - tol / 2 / mill.radius))
    out = []
    for a, b in itertools.pairwise(idx):
        rings = []
        for j in (a, b):
            c, ax = p.centre[j], p.axis[j] / np.linalg.norm(p.axis[j])
            down = -np.array([c[0], c[1], 0.0])
            rings.append(
                [_circle(c + u * ax, ax, mill.radius - h, down, fine, reach) for u, h in zip(us, hs, strict=True)]
            )
        for k in range(len(us) - 1):
            pts = np.vstack([rings[0][k], rings[0][k + 1], rings[1][k], rings[1][k + 1]])
            out.append(mf.Manifold.hull_points(pts))
    return out


def cut_gear(
    gear: Gear,
    mill: Mill,
    passes: Sequence[MillPassPoses],
    tol: float = 0.005,
    progress: Callable[[float], None] | None = None,
) -> FormCutResult:
    """The blank with every pass's swept volume removed, space after space; ``tol`` [mm] the sweep's chord error."""
    solid = blank(gear)
    chips = []
    hulls = 0
    spaces: dict[int, list[MillPassPoses]] = {}
    for p in passes:
        spaces.setdefault(p.space, []).append(p)
    for n, (_, group) in enumerate(sorted(spaces.items())):
        for p in group:
            pieces = swept_hulls(gear, mill, p, tol)
            hulls += len(pieces)
            tool = mf.Manifold.batch_boolean(pieces, mf.OpType.Add)
            before = solid.volume()
            solid = solid - tool
            chips.append((p.space, p.side, before - solid.volume()))
        if progress is not None:
            progress((n + 1) / len(spaces))
    return FormCutResult(solid, chips, hulls)
