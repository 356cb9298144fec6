"""Form milling's removal with manifold3d: the mill's swept volume taken out of the blank, one tooth space after
another (the chips, the forces' volumes, gear.stl; the micrometre truth is :mod:`cutting.form_milling.sweep`).

The mill, a solid of revolution, is cut into frusta (:func:`frusta_points`); each straight move between thinned poses
(:func:`thin_moves`) sweeps the convex hulls of their two placements (:func:`swept_moves`), and :func:`cut_gear`
subtracts the moves space by space. The tolerance ``tol`` is shared between the profile, the circles and the path
(PROFILE_SHARE, CIRCLE_SHARE, PATH_SHARE), argued against :class:`cutting.form_milling.sweep.MilledGear` in
:func:`swept_moves`; why the moves are subtracted one by one: :func:`cut_gear`. The figures that set the design:
docs/form-milling.md, "The removal's figures".
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

#: the shares of the sweep's tolerance (module docstring): the profile's chords (outside the mill where its side
#: is concave), the path's chords (either side), the circles' chords (inside); the rest of the outside is the
#: margin for a turning frustum's hull
PROFILE_SHARE = 0.3
PATH_SHARE = 0.4
CIRCLE_SHARE = 0.5
#: a disc's arc away from the move's contact: one polygon point every this [rad] (:func:`contact_band`)
COARSE_STEP = 0.1


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
    the path, :mod:`cutting.form_milling.copying_path`). :func:`cut_gear` thins with :func:`thin_moves`, which
    checks the cutting part's own points instead."""
    c = p.centre
    a = p.axis / np.linalg.norm(p.axis, axis=1, keepdims=True)
    return _greedy_runs(len(c), lambda i, j: _run_error(c, a, i, j, reach), tol)


def _greedy_runs(n: int, error: Callable[[int, int], float], tol: float) -> np.ndarray:
    """Indices 0 = k_0 < k_1 < ... = n - 1, each run k_i..k_{i+1} the longest whose ``error`` holds ``tol`` (grown
    by doubling, then bisected back to the last one that holds)."""
    keep = [0]
    i = 0
    while i < n - 1:
        j = i + 1
        step = 1
        while i + step < n:
            if error(i, min(i + step, n - 1)) > tol:
                break
            j = min(i + step, n - 1)
            if j == n - 1:
                break
            step *= 2
        lo, hi = j, min(i + step, n - 1)
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if error(i, mid) <= tol:
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


def pose_frames(p: MillPassPoses) -> np.ndarray:
    """Per pose the mill's frame (n, 3, 3), rows e1, e2, a: a its unit axis, e1 the direction towards the gear axis
    made normal to it (the disc's cutting side; for a finger mill, whose axis points at the gear axis, any normal),
    e2 = a x e1. A body point q is at centre + q @ frame in the gear frame."""
    c = p.centre
    a = p.axis / np.linalg.norm(p.axis, axis=1, keepdims=True)
    down = np.column_stack([-c[:, 0], -c[:, 1], np.zeros(len(c))])
    e1 = down - a * np.einsum("ij,ij->i", down, a)[:, None]
    size = np.linalg.norm(e1, axis=1)
    along = size < 1e-9 * np.maximum(np.linalg.norm(down, axis=1), 1e-300)
    if np.any(along):  # the axis points at the gear axis (a finger mill)
        ref = np.where(np.abs(a[along, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
        e1[along] = np.cross(a[along], ref)
        size[along] = np.linalg.norm(e1[along], axis=1)
    e1 /= size[:, None]
    return np.stack([e1, np.cross(a, e1), a], axis=1)


def frusta_points(gear: Gear, mill: Mill, tol: float) -> list[np.ndarray]:
    """Per frustum that can reach the blank, the points of its two circles' polygons in the mill's frame (e1, e2,
    a): chords within ``tol/2``; a disc's over the arc of each circle that comes within the tooth depth + 2 ``tol``
    of its lowest point's circle (and 0.05 rad more), a finger mill's all round.

    The mill is cut into frusta along its axis where its profile bends by more than its share of the tolerance
    (:func:`profile_slices`); a frustum is convex, so what it sweeps between two poses that differ by a straight move
    is (close to) the convex hull of its two placements. Each circle of a frustum is a polygon whose chords stay
    within its share, and only where that circle can reach the blank: a disc's circles only over the arc towards the
    gear axis that comes within the tooth depth (+ 2 tol, + 0.05 rad) of the tip circle, per circle from its own
    radius (a circle higher up the edge reaches less; a frustum that stays above the tip circle is dropped). The part
    of a disc beyond that arc's chord never comes inside the tip cylinder, so leaving it out changes nothing inside
    the blank."""
    us, hs = profile_slices(mill, tol * PROFILE_SHARE)
    depth = gear.tip_radius - gear.root_radius + 2 * tol
    mill_reach = mill.reach_angle(depth)
    fine = 2 * math.acos(max(0.0, 1 - tol * CIRCLE_SHARE / mill.radius))
    out = []
    for k in range(len(us) - 1):
        radii = (mill.radius - hs[k], mill.radius - hs[k + 1])
        if mill_reach >= math.pi:
            # an even count: vertices at +-e1, where a finger fed along the face touches the flanks
            angles = np.linspace(0.0, 2 * math.pi, max(8, 2 * math.ceil(math.pi / fine)), endpoint=False)
        else:
            if min(hs[k], hs[k + 1]) > depth:  # its lowest points stay outside the tip circle
                continue
            # a circle of radius r reaches the depth where r cos(phi) >= R - depth
            reach = min(mill_reach, math.acos(min(1.0, (mill.radius - depth) / max(radii))) + 0.05)
            angles = np.linspace(-reach, reach, max(3, math.ceil(2 * reach / fine) + 1))
        cos, sin = np.cos(angles), np.sin(angles)
        out.append(np.vstack([np.column_stack([r * cos, r * sin, np.full(len(angles), u)])
                              for u, r in zip(us[k : k + 2], radii, strict=True)]))  # fmt: skip
    return out


def thin_moves(p: MillPassPoses, frames: np.ndarray, points: np.ndarray, tol: float) -> np.ndarray:
    """Indices of the fewest poses whose straight moves keep each of the body ``points`` (m, 3) (mill frame), at
    every recorded pose between, within ``tol`` [mm] of the chord of its own path (at the fraction of the move the
    centre has made). The miss is affine in the point, so checking the corners of the points' box (mill frame)
    bounds it over all of them: 8 points a pose, whatever the pass's length (a recorded pass has 10^5 poses)."""
    c = p.centre
    lo, hi = points.min(axis=0), points.max(axis=0)  # the largest miss is at a corner of their box (a few poses
    points = np.array(list(itertools.product(*zip(lo, hi, strict=True))))  # more than their hull: 8 points per pose)
    world = c[:, None, :] + np.einsum("mj,nji->nmi", points, frames)

    def error(i: int, j: int) -> float:
        if j <= i + 1:
            return 0.0
        d = c[j] - c[i]
        length = float(d @ d)
        if length > 0.0:
            s = np.clip((c[i + 1 : j] - c[i]) @ d / length, 0.0, 1.0)
        else:  # the centre stands (a turn only): the recorded instants
            s = (p.t[i + 1 : j] - p.t[i]) / (p.t[j] - p.t[i])
        chord = world[i][None] + s[:, None, None] * (world[j] - world[i])[None]
        return float(np.sqrt(np.max(np.sum((world[i + 1 : j] - chord) ** 2, axis=2))))

    return _greedy_runs(len(c), error, tol)


def _misses_blank(gear: Gear, w: np.ndarray, pad: float) -> bool:
    """Whether the convex hull of gear-frame points ``w`` lies beyond a plane that bounds the blank: an end face, or
    (an external gear) the tip cylinder's tangent plane towards the points' mean."""
    half = gear.face_width / 2 + pad
    if w[:, 2].min() > half or w[:, 2].max() < -half:
        return True
    if gear.internal:
        return False
    m = w[:, :2].mean(axis=0)
    size = float(np.linalg.norm(m))
    return size > 0.0 and float((w[:, :2] @ (m / size)).min()) > gear.tip_radius + pad


def contact_band(q: np.ndarray, turn: np.ndarray, shift: np.ndarray, coarse: float = COARSE_STEP) -> np.ndarray:
    """Which points of a disc frustum's arc polygons ``q`` (two rings of equal angles, mill frame) to keep for the move
    to pose ``q @ turn.T + shift``: all of them within two polygon steps of where the frustum's surface turns from
    the move's back to its front (n . m changes sign: the contact, whose sweep is the sweep's boundary), one every
    ``coarse`` [rad] elsewhere and the arc's ends (a point there is swept through by the polygon's inside, which
    the move carries over it: leaving it out of the hull leaves nothing behind). All if the sign never changes.
    The removed volume is the same with about half the hulls' facets (docs/form-milling.md, "The removal's
    figures")."""
    n = len(q) // 2
    rings = (q[:n], q[n:])
    r = [float(np.hypot(*ring[0, :2])) for ring in rings]
    du = rings[1][0, 2] - rings[0][0, 2]
    slope = (r[1] - r[0]) / du if abs(du) > 1e-12 else 0.0
    changes = []
    for ring, radius in zip(rings, r, strict=True):
        normal = np.column_stack([ring[:, 0] / radius, ring[:, 1] / radius, np.full(n, -slope)])
        g = np.einsum("ij,ij->i", normal, ring @ turn.T + shift - ring)
        changes.extend(np.flatnonzero(np.sign(g[:-1]) != np.sign(g[1:])))
    if not changes:
        return np.arange(len(q))
    lo, hi = max(0, min(changes) - 2), min(n - 1, max(changes) + 3)
    step = np.arctan2(q[1, 1], q[1, 0]) - np.arctan2(q[0, 1], q[0, 0])
    every = max(1, int(coarse / max(abs(step), 1e-12)))
    keep = np.unique(np.concatenate([np.arange(0, n, every), np.arange(lo, hi + 1), [n - 1]]))
    return np.concatenate([keep, keep + n])


def swept_moves(gear: Gear, mill: Mill, p: MillPassPoses, tol: float) -> tuple[list[mf.Manifold], int]:
    """The pass's swept volume within ``tol`` [mm] as one solid per straight move (the union of its frusta's hulls,
    built in the move's frame and moved back), moves that cannot meet the blank left out; and the number of hulls.

    Why it holds the tolerance ``tol`` against :class:`cutting.form_milling.sweep.MilledGear` (the exact surface):

    - the profile (PROFILE_SHARE = 0.3 tol): each frustum's generator is a chord of the profile within it (outside
      the mill where its side is concave, as on both flanks of a space, inside where it is convex);
    - the circles (CIRCLE_SHARE = 0.5 tol): polygon chords within it, inside;
    - the path (PATH_SHARE = 0.4 tol): the poses are thinned (:func:`thin_moves`) to the fewest whose straight moves
      keep every point of the cutting part, at every recorded pose between, within it of where the straight move
      puts it. The mill is rigid, so a point's miss of its chord is affine in the point and its length convex: the
      largest is at a corner of the box (mill frame) of the rings' polygon points, and those 8 are checked. No screw
      and no straight feed is assumed: recorded (simulated machine) passes are thinned alike (their wobble keeps more
      poses);
    - the rest (0.3 tol on the outside) is the margin for the hull of a turning frustum, which exceeds its sweep by
      a term of first order in the move's turn times the length of its facets between polygon points (a
      translation's hull is its sweep exactly); docs/form-milling.md gives the figures measured on a helical pass
      that set the split.

    Hulls and their union are what cost: manifold's booleans cost with the operands' facets whose boxes overlap, and
    thin stacked slabs with large tilted facets overlap each other's boxes everywhere. So each move's hulls are built
    and unioned in the move's own frame (the mill's axis along z: the slabs stack along z and their facets' boxes
    stay thin), only those that can meet the blank (beyond an end face or the tip cylinder's tangent plane they
    cannot), and moved back by the pose's rigid transform. The union of a move is the same set in either frame, so
    the tolerance argument is unchanged by it."""
    pieces = frusta_points(gear, mill, tol)
    arcs = mill.reach_angle(gear.tip_radius - gear.root_radius + 2 * tol) < math.pi  # a disc's
    frames = pose_frames(p)
    kept = thin_moves(p, frames, np.vstack(pieces), tol * PATH_SHARE)
    moves, hulls = [], 0
    for a, b in itertools.pairwise(kept):
        ea, eb, ca = frames[a], frames[b], p.centre[a]
        turn, shift = ea @ eb.T, ea @ (p.centre[b] - ca)  # pose b in the frame of pose a
        local = []
        for q in pieces:
            if arcs:
                q = q[contact_band(q, turn, shift)]
            pts = np.vstack([q, q @ turn.T + shift])
            if not _misses_blank(gear, ca + pts @ ea, tol):
                local.append(mf.Manifold.hull_points(pts))
        if local:
            hulls += len(local)
            move = local[0] if len(local) == 1 else mf.Manifold.batch_boolean(local, mf.OpType.Add)
            moves.append(move.transform(np.hstack([ea.T, ca[:, None]])).as_original())
    return moves, hulls


@dataclass
class FormCutResult:
    """The cut: the gear solid and, per pass, the chip volume [mm^3] (space, side, volume)."""

    gear_solid: mf.Manifold
    chips: list[tuple[int, str, float]]
    hulls: int


def cut_gear(
    gear: Gear,
    mill: Mill,
    passes: Sequence[MillPassPoses],
    tol: float = 0.005,
    progress: Callable[[float], None] | None = None,
) -> FormCutResult:
    """The blank with every pass's swept volume removed, space after space, move after move; ``tol`` [mm] the
    sweep's error (:func:`swept_moves`). The moves are subtracted one after another (their union first costs more),
    each space from a local stock: the solid's part inside the box of its moves, put back after (a boolean's cost
    grows with the solid it cuts)."""
    solid = blank(gear)
    chips = []
    hulls = 0
    spaces: dict[int, list[MillPassPoses]] = {}
    for p in passes:
        spaces.setdefault(p.space, []).append(p)
    for n, (_, group) in enumerate(sorted(spaces.items())):
        cut = []
        for p in group:
            moves, count = swept_moves(gear, mill, p, tol)
            hulls += count
            cut.append((p, moves))
        boxes = np.array([m.bounding_box() for _, moves in cut for m in moves]).reshape(-1, 6)
        if len(boxes):
            lo, hi = boxes[:, :3].min(axis=0) - 1.0, boxes[:, 3:].max(axis=0) + 1.0
            box = mf.Manifold.cube(hi - lo).translate(lo)
            local, rest = solid ^ box, solid - box
            rest.num_tri()
        else:
            local, rest = solid, None
        volume = local.volume()
        for p, moves in cut:
            for move in moves:  # one boolean each: cheaper than their union (module docstring)
                local = local - move
                local.num_tri()
            after = local.volume()
            chips.append((p.space, p.side, volume - after))
            volume = after
        # as an original: manifold keeps every operand's triangle relation, and the booleans slowed down with the
        # thousands of hulls behind them (2 s per space at the 9th space, 10 s without)
        solid = (local if rest is None else rest + local).as_original()
        if progress is not None:
            progress((n + 1) / len(spaces))
    return FormCutResult(solid, chips, hulls)
