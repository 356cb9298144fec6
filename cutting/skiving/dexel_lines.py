"""The dexel lines of a gear blank: fans of rays across every tooth space, slice by slice along the face.

A dexel is a line through the blank along which the workpiece is kept as material intervals. skive's lines are
fans in transverse planes: in each slice z_j and for each tooth space k, rays start at a point C above the space
(outside the blank: beyond the tip circle of an external gear, inside the bore of an internal one) and run into
it, spread so that they meet the nominal space boundary (tooth land, flank, root, flank, land; from one tooth's
centre line to the next one's) at even steps of arc length. Seen from C a tooth space is star-shaped: each ray
meets the cut surface once, so the rays' end points are the surface and the fan between them is the space's
removed region (:mod:`cutting.skiving.dexel_solid`). Along a ray the volume element is rho d(rho) d(alpha) dz, so a
removed interval [rho_1, rho_2] of ray i in slice j stands for (rho_2^2 - rho_1^2) / 2 * dalpha_i * dz_j of
material: the chips are exact quadratures of what the passages remove.

Slices follow the helix (each is the space-centred frame turned by the twist at z_j), so a ray keeps its place
on the flank from slice to slice.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Protocol

import numpy as np
from numba import njit

from cutting.flank import twist_rate
from cutting.gear import Gear

#: C lies this far [mn] outside the blank above the space's centre: the lands are then seen at a usable angle
CENTRE_OFFSET = 0.5
#: rays end this far [mn] beyond the root (in the gear body), unless a tooth's centre plane comes first
ROOT_REACH = 1.0


@dataclass(frozen=True)
class DexelSpacing:
    """Spacing of the dexel lines [mm]: ``profile`` along the nominal space boundary, ``face`` between slices; both
    refine towards ``fine`` where the chips are narrow: at the tip corners (a chip's layer meets the tip circle)
    and at the end faces (a passage entering or leaving the blank takes a chip only a feed or two long), the
    spacing growing by GROWTH from one line to the next."""

    profile: float
    face: float
    fine: float

    @classmethod
    def for_gear(cls, gear: Gear, feed: float, profile: float | None = None, face: float | None = None) -> DexelSpacing:
        """The default spacing of a gear cut at ``feed`` [mm per work revolution]: 0.1 mn along the profile,
        0.2 mn along the face, refined to an eighth of the feed (and of the profile spacing) at the faces and the
        tip corners; or the given values (docs/cutting.md, "Spacing": chips against the manifold reference)."""
        profile = 0.1 * gear.mn if profile is None else profile
        face = 0.2 * gear.mn if face is None else face
        return cls(profile, face, min(feed / 8, profile / 8, face / 8))

    def check(self) -> None:
        for name, v in (("profile", self.profile), ("face", self.face), ("fine", self.fine)):
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"dexel spacing {name} = {v}: must be a positive length [mm]")


#: the spacing grows by this factor from line to line away from where it is refined
GROWTH = 1.15


def graded(a: float, b: float, step: float, fine: float, at_a: bool, at_b: bool) -> np.ndarray:
    """Points from a to b (both included), ``step`` apart, refined to ``fine`` at a (``at_a``) and b (``at_b``) and
    growing by GROWTH from there."""
    length = b - a
    if length <= 0:
        return np.array([a])

    def spacing(x: np.ndarray) -> np.ndarray:
        d = np.full(np.shape(x), np.inf)
        if at_a:
            d = np.minimum(d, x)
        if at_b:
            d = np.minimum(d, length - x)
        return np.minimum(step, fine + (GROWTH - 1) * d)

    xs = [0.0]
    while xs[-1] < length:
        xs.append(xs[-1] + float(spacing(np.array(xs[-1]))))
    x = np.array(xs)
    x = x * (length / x[-1]) if len(x) > 2 else np.array([0.0, length])  # the last step stretched onto b
    return a + x


def space_boundary(gear: Gear, samples: int = 400) -> tuple[np.ndarray, tuple[int, int]]:
    """The nominal boundary of tooth space 0 in a transverse section, in the space frame (the space centred on
    +x): from tooth 0's centre on the tip circle along its land, down its flank, along the root circle, up tooth
    1's flank and its land to tooth 1's centre: (m, 2) [mm], and the indices of the two tip corners. The root
    fillet is left out (the rays only need their spread from it)."""
    pitch = 2 * math.pi / gear.teeth
    r_tip, r_root, r_base = gear.tip_radius, gear.root_radius, gear.base_radius
    # the flank's involute reaches from the tip down (external) / out (internal) to the root or the base circle
    r_low = max(r_root, r_base) if not gear.internal else r_root
    r_flank = np.linspace(r_tip, r_low, samples)
    psi = np.asarray(gear.half_thickness_angle(np.maximum(r_flank, r_base)), dtype=float)
    psi_tip = float(psi[0])
    land = np.linspace(0.0, psi_tip, max(4, samples // 8))
    parts = [np.column_stack([np.full(len(land), r_tip), land])]
    parts.append(np.column_stack([r_flank, psi]))
    if not gear.internal and r_root < r_base:  # radial below the base circle down to the root
        r_rad = np.linspace(r_base, r_root, max(4, samples // 8))
        parts.append(np.column_stack([r_rad, np.full(len(r_rad), psi[-1])]))
    root = np.linspace(psi[-1], pitch - psi[-1], samples)
    parts.append(np.column_stack([np.full(len(root), r_root), root]))
    first = np.concatenate(parts)
    second = first[::-1].copy()
    second[:, 1] = pitch - second[:, 1]
    polar = np.concatenate([first, second[len(parts[-1]) :]])  # the root arc once
    theta = polar[:, 1] - pitch / 2
    pts = np.column_stack([polar[:, 0] * np.cos(theta), polar[:, 0] * np.sin(theta)])
    corner = len(land) - 1
    corners = (corner, len(pts) - 1 - corner)
    keep = np.r_[True, np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-12]
    keep[list(corners)] = True
    index = np.cumsum(keep) - 1
    return pts[keep], (int(index[corners[0]]), int(index[corners[1]]))


class LineSet(Protocol):
    """What a dexel workpiece needs of its lines: ``count`` lines in cells of ``rays`` lines (a cell's lines share
    their candidate passages), cell c in slice c % ``slices`` of thickness ``dz``; ``arrays`` = (origin (n, 3),
    unit direction (n, 3), end (n,), entry into the blank (n,), weights (n, 2): an interval [d1, d2] holds
    w0 (d2 - d1) + w1 (d2^2 - d1^2) / 2 of volume); per line of a cell its ``ray_cos`` to the surface's normal and
    ``ray_cell`` (its share of the surface across the cell [mm]); a cell's lines lie in the plane
    ``plane_normal`` . x = ``plane_offset(cell)``; ``cells(centres, radii)``: the cells balls can reach."""

    count: int
    rays: int
    slices: int
    dz: np.ndarray
    ray_cos: np.ndarray
    ray_cell: np.ndarray
    plane_normal: np.ndarray

    def plane_offset(self, cells: np.ndarray) -> np.ndarray: ...

    @property
    def arrays(self) -> tuple[np.ndarray, ...]: ...

    def cells(self, centres: np.ndarray, radii: np.ndarray) -> np.ndarray: ...


class GridLines:
    """Parallel lines along ``axis`` through a rectangular grid: ``across`` x ``slices`` of them, ``spacing`` apart
    (the rectangle from ``corner`` along unit ``u_across`` and ``u_slice``), each from d = 0 at the grid to
    ``length``, material from ``entry``. Cell j is the row of lines at slice j. A slab blank (tests, planing)."""

    def __init__(
        self,
        corner,
        axis,
        u_across,
        u_slice,
        across: int,
        slices: int,
        spacing: tuple[float, float],
        length: float,
        entry: float = 0.0,
    ):
        self.corner, self.axis = np.asarray(corner, float), np.asarray(axis, float)
        self.u_across, self.u_slice = np.asarray(u_across, float), np.asarray(u_slice, float)
        self.rays, self.slices, self.spaces = across, slices, 1
        self.count = across * slices
        self.spacing, self.length, self.entry = spacing, length, entry
        self.dz = np.full(slices, spacing[1])
        self.ray_cos = np.ones(across)
        self.ray_cell = np.full(across, spacing[0])

    @cached_property
    def arrays(self) -> tuple[np.ndarray, ...]:
        j, i = np.meshgrid(np.arange(self.slices), np.arange(self.rays), indexing="ij")
        h0, h1 = self.spacing
        origin = self.corner + ((i.ravel() + 0.5) * h0)[:, None] * self.u_across
        origin = origin + ((j.ravel() + 0.5) * h1)[:, None] * self.u_slice
        n = self.count
        weight = np.column_stack([np.full(n, h0 * h1), np.zeros(n)])
        return origin, np.tile(self.axis, (n, 1)), np.full(n, self.length), np.full(n, self.entry), weight

    @property
    def plane_normal(self) -> np.ndarray:
        """A cell's lines lie in a plane of this normal (the rows across ``u_slice``)."""
        return self.u_slice

    def plane_offset(self, cells: np.ndarray) -> np.ndarray:
        return self.corner @ self.u_slice + (np.asarray(cells) % self.slices + 0.5) * self.spacing[1]

    def cells(self, centres: np.ndarray, radii: np.ndarray) -> np.ndarray:
        """Every row a ball can reach (by its extent along ``u_slice``)."""
        c, r = np.asarray(centres, float).reshape(-1, 3), np.asarray(radii, float).ravel()
        s = (c - self.corner) @ self.u_slice / self.spacing[1] - 0.5
        lo = np.clip(np.floor(s - r / self.spacing[1]), 0, self.slices - 1).astype(int)
        hi = np.clip(np.ceil(s + r / self.spacing[1]), 0, self.slices - 1).astype(int)
        keep = (s + r / self.spacing[1] >= -1) & (s - r / self.spacing[1] <= self.slices)
        return np.unique(
            np.concatenate([np.arange(a, b + 1) for a, b in zip(lo[keep], hi[keep], strict=True)] or [np.zeros(0, int)])
        ).astype(np.int64)


class DexelLines:
    """Every dexel line of a gear blank: ``spaces`` x ``slices`` fans of ``rays`` rays, numbered
    ``(space * slices + slice) * rays + ray``.

    Per line: ``origin`` (n, 3) C of its fan and unit ``direction`` (n, 3) in the work frame [mm]; ``length`` (n,)
    where it ends (a tooth's centre plane or ROOT_REACH beyond the root); ``entry`` (n,) where it enters the blank;
    ``weight`` (n, 2): (0, dalpha * dz [rad mm]), so that a removed interval [d1, d2] is
    dalpha dz (d2^2 - d1^2) / 2 of volume. Per ray of a fan: ``alpha`` (the angle from the inward direction [rad]),
    ``arc`` (its place on the nominal boundary [mm]), ``normal`` (the nominal boundary's outward normal there, space
    frame, 2D), ``land`` (it meets a tooth's land, beyond the tip corners).
    """

    def __init__(self, gear: Gear, spacing: DexelSpacing, rim: float | None = None, phase: float = 0.0):
        """``phase`` [rad]: where the motion puts the gear's teeth, turned about the work axis from the nominal
        (:func:`gear_phase`): the fans follow the spaces the cut really makes."""
        spacing.check()
        self.gear, self.spacing, self.phase = gear, spacing, phase
        self.spaces = gear.teeth
        self.pitch = 2 * math.pi / gear.teeth
        self.twist_rate = twist_rate(gear)
        offset = CENTRE_OFFSET * gear.mn
        self.inward = -1.0 if not gear.internal else 1.0  # along the space frame's x
        self.centre_radius = gear.tip_radius + offset if not gear.internal else gear.tip_radius - offset
        if gear.internal and self.centre_radius <= 0:
            raise ValueError(f"internal gear: the bore (d = {2 * gear.tip_radius:.3f} mm) is too small for dexel fans")
        self.rim_radius = gear.root_radius + (3 * gear.mn if rim is None else rim)
        self._rays(spacing)
        b = gear.face_width
        self.z = graded(-b / 2, b / 2, spacing.face, spacing.fine, True, True)
        self.dz = _trapezoid(self.z)
        self.slices = len(self.z)
        self.count = self.spaces * self.slices * self.rays

    # ---- one fan, in the space frame ----------------------------------------------------------------------
    def _rays(self, spacing: DexelSpacing) -> None:
        """Ray angles at even arc length on the nominal boundary, refined at the tip corners (which, like the tooth
        centres, get a ray of their own)."""
        g = self.gear
        pts, corners = space_boundary(g)
        seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        arc = np.r_[0.0, np.cumsum(seg)]
        c1, c2 = (float(arc[c]) for c in corners)
        step, fine = spacing.profile, spacing.fine
        s = np.unique(
            np.concatenate(
                [
                    graded(0.0, c1, step, fine, False, True),
                    graded(c1, c2, step, fine, True, True),
                    graded(c2, float(arc[-1]), step, fine, True, False),
                ]
            )
        )
        #: the rays that meet the tooth lands (beyond the tip corners): the blank's uncut tip cylinder
        self.land = (s < c1 - 1e-12) | (s > c2 + 1e-12)
        bx, by = np.interp(s, arc, pts[:, 0]), np.interp(s, arc, pts[:, 1])
        vx, vy = bx - self.centre_radius, by
        alpha = np.arctan2(vy, self.inward * vx)
        if np.any(np.diff(alpha) <= 0):
            raise ValueError(
                "the tooth space is not star-shaped from its dexel centre (an undercut or very short space): "
                "the dexel removal cannot cut this gear; use --removal manifold"
            )
        tangent = np.column_stack([np.gradient(bx, s), np.gradient(by, s)])
        tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
        # the boundary runs from tooth 0 to tooth 1 with the space on its left: the outward normal (into the space)
        normal = np.column_stack([-tangent[:, 1], tangent[:, 0]])
        if g.internal:
            normal = -normal
        self.alpha, self.arc, self.normal = alpha, s, normal
        self.nominal_distance = np.hypot(vx, vy)
        self.dalpha = _trapezoid(alpha)
        self.rays = len(alpha)
        self.ray_u = np.column_stack([self.inward * np.cos(alpha), np.sin(alpha)])  # space frame
        self.ray_length, self.ray_entry = self._reach()

    def _reach(self) -> tuple[np.ndarray, np.ndarray]:
        """Where each ray of the fan ends (the nearer tooth centre plane, or ROOT_REACH beyond the root) and where it
        enters the blank, in the space frame."""
        g = self.gear
        c = np.array([self.centre_radius, 0.0])
        u = self.ray_u
        big = 10 * (g.tooth_depth + 2 * g.mn) + 1.0
        ends = np.full(len(u), big)
        for sign in (1.0, -1.0):  # the tooth centre planes at +-pitch/2 from the space centre
            a = sign * self.pitch / 2
            nrm = np.array([-math.sin(a), math.cos(a)])  # normal of the plane through the axis at angle a
            den = u @ nrm
            with np.errstate(divide="ignore", invalid="ignore"):
                t = -(c @ nrm) / den
            hit = (den != 0) & (t > 0)
            ends = np.where(hit, np.minimum(ends, t), ends)
        r_cap = g.root_radius - ROOT_REACH * g.mn if not g.internal else g.root_radius + ROOT_REACH * g.mn
        ends = np.minimum(ends, _circle_exit(c, u, r_cap, not g.internal))
        entry = _circle_exit(c, u, g.tip_radius, not g.internal)  # the tip circle / the bore
        if np.any(entry[1:-1] >= ends[1:-1]):
            raise ValueError("a dexel ray meets no blank before its end: the fan does not fit this gear")
        return ends, np.minimum(entry, ends)  # the outermost rays meet the land on the tooth centre plane

    # ---- the lines in the work frame ---------------------------------------------------------------------------
    def frame_angle(self, space: np.ndarray, z: np.ndarray) -> np.ndarray:
        """Polar angle of the space frame's +x for space k at height z [rad]."""
        return (np.asarray(space) + 0.5) * self.pitch + self.twist_rate * np.asarray(z) + self.phase

    @cached_property
    def arrays(self) -> tuple[np.ndarray, ...]:
        """(origin, direction, length, entry, weight) of every line, in line order."""
        k, j, i = np.meshgrid(np.arange(self.spaces), np.arange(self.slices), np.arange(self.rays), indexing="ij")
        k, j, i = k.ravel(), j.ravel(), i.ravel()
        ang = self.frame_angle(k, self.z[j])
        c, s = np.cos(ang), np.sin(ang)
        origin = np.column_stack([self.centre_radius * c, self.centre_radius * s, self.z[j]])
        ux, uy = self.ray_u[i, 0], self.ray_u[i, 1]
        direction = np.column_stack([c * ux - s * uy, s * ux + c * uy, np.zeros(len(i))])
        weight = np.column_stack([np.zeros(len(i)), self.dalpha[i] * self.dz[j]])  # polar: rho drho dalpha dz
        return origin, direction, self.ray_length[i].copy(), self.ray_entry[i].copy(), weight

    @cached_property
    def ray_cos(self) -> np.ndarray:
        """Per ray of a fan: |cos| between it and the nominal boundary's normal (a removed length times it is the
        layer's thickness normal to the surface)."""
        return np.abs(np.einsum("ij,ij->i", self.ray_u, self.normal))

    @cached_property
    def ray_cell(self) -> np.ndarray:
        """Per ray of a fan: the arc of the nominal boundary it stands for [mm]."""
        return _trapezoid(self.arc)

    #: a fan's rays lie in its slice's transverse plane z = z_j
    plane_normal = np.array([0.0, 0.0, 1.0])

    def plane_offset(self, cells: np.ndarray) -> np.ndarray:
        return self.z[np.asarray(cells) % self.slices]

    def index(self, space: int, slice_: int, ray: int = 0) -> int:
        return (space * self.slices + slice_) * self.rays + ray

    def cells(self, centres: np.ndarray, radii: np.ndarray) -> np.ndarray:
        """The fans (cell = space * slices + slice) that the balls (centres (m, 3), radii (m,)) [mm] can reach: per
        ball and slice its section's angular reach against each space's sector (a superset; the kernel tests
        each line against the passage's balls and boxes). Compiled: a run asks once per passage."""
        c = np.ascontiguousarray(np.asarray(centres, float).reshape(-1, 3))
        r = np.ascontiguousarray(np.asarray(radii, float).ravel())
        return _fan_cells(c, r, self.z, self.twist_rate, self.pitch, self.phase, self.spaces)


@njit(cache=True, error_model="numpy")
def _fan_cells(c, r, z, twist, pitch, phase, spaces):
    """DexelLines.cells: the sorted cells whose sectors the balls' sections reach (widened by 1e-9 rad)."""
    slices = z.shape[0]
    hit = np.zeros(spaces * slices, np.bool_)
    for b in range(c.shape[0]):
        rho = math.hypot(c[b, 0], c[b, 1])
        for j in range(slices):
            dz = c[b, 2] - z[j]
            if abs(dz) > r[b]:
                continue
            rs = math.sqrt(max(r[b] * r[b] - dz * dz, 0.0))  # the ball's radius in the slice's plane
            # the ball centre's angle in the slice's untwisted frame (space k centred at k pitch)
            theta = math.atan2(c[b, 1], c[b, 0]) - twist * z[j] - pitch / 2 - phase
            width = math.asin(min(max(rs / max(rho, 1e-12), 0.0), 1.0)) + 1e-9 if rs < rho else math.pi
            # a fan spreads half a pitch either side of its space's centre (its rays end on the tooth centre planes)
            k_lo = math.ceil((theta - width) / pitch - 0.5)
            k_hi = math.floor((theta + width) / pitch + 0.5)
            for k in range(k_lo, k_lo + min(k_hi - k_lo + 1, spaces)):
                hit[(k % spaces) * slices + j] = True
    return np.nonzero(hit)[0].astype(np.int64)


def gear_phase(motion) -> float:
    """The turn about the work axis [rad] of the gear a motion cuts, against the ideal kinematics: the ideal pose
    at the motion's own first cutter angle, carriage and centre distance, against its pose there. A machine's work
    phase (where its helix term starts, its servo offset) turns the whole gear: invisible on the gear, but the
    dexel fans must sit on the spaces it cuts. 0 for the ideal motion."""
    t0 = float(np.atleast_1d(getattr(motion, "t", [0.0]))[0])
    _, trans = motion.pose(np.array([t0]))
    phi0 = float(motion.cutter_angle(np.array([t0]))[0])
    s0 = float(motion.carriage(np.array([t0]))[0])
    _, ideal = motion.setup.cutter_pose(np.array([phi0]), s0, motion.centre_distance)
    d = math.atan2(trans[0][1], trans[0][0]) - math.atan2(ideal[0][1], ideal[0][0])
    return float((d + math.pi) % (2 * math.pi) - math.pi)


def _trapezoid(x: np.ndarray) -> np.ndarray:
    """The trapezoid rule's weights of the points x (each stands for half the steps either side)."""
    if len(x) < 2:
        return np.ones(len(x))
    mid = (x[1:] + x[:-1]) / 2
    return np.diff(np.r_[x[0], mid, x[-1]])


def _circle_exit(c: np.ndarray, u: np.ndarray, radius: float, outside_first: bool) -> np.ndarray:
    """Distance along rays from ``c`` (2,) in directions ``u`` (n, 2) to the circle |x| = radius: the first crossing
    if ``outside_first`` (the ray starts outside the circle and enters it), else the exit from inside (inf where
    the ray misses)."""
    b = u @ c
    disc = b * b - (c @ c - radius * radius)
    root = np.sqrt(np.maximum(disc, 0.0))
    if outside_first:
        t = -b - root
        return np.where((disc >= 0) & (t > 0), t, np.inf)
    return np.where(disc >= 0, -b + root, np.inf)
