"""Analytic gear meshes with imposed deviations: the known answers that prove the measurement.

Used only by tests and benchmarks, never as the result of a simulated run (that gear is what the
boolean removal leaves). The solid is the nominal transverse outline (involute flanks, tip arc, a radial
line from the involute start down to the root circle, root arc) extruded along z, then every vertex is
turned by the helix and by the imposed deviation:

    theta' = theta + 2 pi z / p_z + side_sign * e(side, tooth, L, z) / r_b

with e the deviation along the base tangent [mm], excess material positive, L the roll length and z
the axial position from the mid face. Between vertices the surface is linear, so the mesh represents
the intended flank to within the chordal error of its sampling (see :func:`chordal_error`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import manifold3d as mf
import numpy as np
import trimesh

from cutting.flank import SIDES, base_tangent_deviation, flank_polar_angle, side_sign, twist_rate
from cutting.gear import Gear

#: e(side, tooth, roll_length, z) -> deviation [mm]; tooth numbered 0..z-1 from the nominal tooth on +x.
Deviation = Callable[[str, np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def _flank_radii(gear: Gear, n: int) -> np.ndarray:
    """Radii from the involute start to the tip, uniform in roll length (uniform chordal error)."""
    r_lo, r_hi = sorted((gear.tip_radius, max(gear.base_radius * (1 + 1e-9), _involute_start(gear))))
    if gear.internal:
        r_lo, r_hi = gear.tip_radius, min(gear.root_radius, _involute_start(gear))
    L = np.linspace(math.sqrt(r_lo**2 - gear.base_radius**2), math.sqrt(r_hi**2 - gear.base_radius**2), n)
    return np.sqrt(gear.base_radius**2 + L**2)


def _involute_start(gear: Gear) -> float:
    """Where the outline leaves the root: the base circle (external) or just inside the root (internal)."""
    if gear.internal:
        return gear.root_radius - 0.15 * gear.mn
    return max(gear.base_radius * (1 + 1e-9), gear.root_radius)


def transverse_outline(gear: Gear, flank_points: int = 60, arc_points: int = 8) -> np.ndarray:
    """Counter-clockwise outline of the nominal transverse section at z = 0, shape (n, 2).

    For an internal gear this is the toothed inner boundary (the bore), still counter-clockwise.
    """
    radii = _flank_radii(gear, flank_points)  # increasing radius
    psi = np.asarray(gear.half_thickness_angle(radii))
    pitch = 2 * math.pi / gear.teeth
    pts = []
    for k in range(gear.teeth):
        c = k * pitch
        if not gear.internal:
            r_root = gear.root_radius
            up = np.stack([radii, c - psi], -1)  # right flank, root -> tip, theta increasing
            tip_a = np.linspace(c - psi[-1], c + psi[-1], arc_points)[1:-1]
            tip = np.stack([np.full_like(tip_a, radii[-1]), tip_a], -1)
            down = np.stack([radii[::-1], c + psi[::-1]], -1)  # left flank, tip -> root
            start, end = c + psi[0], c + pitch - psi[0]
            seg = [up, tip, down]
            if r_root < radii[0] - 1e-9:
                seg = [np.array([[r_root, c - psi[0]]]), *seg, np.array([[r_root, start]])]
            root_a = np.linspace(start, end, arc_points)[1:-1]
            seg.append(np.stack([np.full_like(root_a, r_root), root_a], -1))
        else:
            # internal: tooth k points inwards; CCW along the bore: left flank (theta_c - psi) from root to tip,
            # tip arc, right flank from tip to root, root arc to the next tooth
            r_root = gear.root_radius
            left = np.stack([radii[::-1], c - psi[::-1]], -1)  # root side (large r) -> tip (small r)
            tip_a = np.linspace(c - psi[0], c + psi[0], arc_points)[1:-1]
            tip = np.stack([np.full_like(tip_a, radii[0]), tip_a], -1)
            right = np.stack([radii, c + psi], -1)
            seg = [np.array([[r_root, c - psi[-1]]]), left, tip, right, np.array([[r_root, c + psi[-1]]])]
            root_a = np.linspace(c + psi[-1], c + pitch - psi[-1], arc_points)[1:-1]
            seg.append(np.stack([np.full_like(root_a, r_root), root_a], -1))
        pts.append(np.concatenate(seg))
    polar = np.concatenate(pts)
    return np.stack([polar[:, 0] * np.cos(polar[:, 1]), polar[:, 0] * np.sin(polar[:, 1])], -1)


def chordal_error(gear: Gear, flank_points: int) -> float:
    """Largest sagitta of the flank chords [mm]: ds^2 / (8 rho), rho = roll length (involute curvature radius)."""
    radii = _flank_radii(gear, flank_points)
    L = np.sqrt(radii**2 - gear.base_radius**2)
    ds = np.diff(L**2 / (2 * gear.base_radius))  # involute arc length s = L^2 / (2 r_b)
    return float(np.max(ds**2 / (8 * np.maximum(L[:-1], 1e-9))))


def reference_gear_mesh(
    gear: Gear,
    deviation: Deviation | None = None,
    *,
    flank_points: int = 60,
    arc_points: int = 8,
    z_divisions: int | None = None,
    rim: float | None = None,
    offset: tuple[float, float] = (0.0, 0.0),
    rotation: float = 0.0,
    helix_sagitta: float = 1e-4,
) -> trimesh.Trimesh:
    """Watertight mesh of ``gear`` (face from -b/2 to +b/2) with an imposed deviation.

    Parameters
    ----------
    deviation: e(side, tooth, L, z) [mm] along the base tangent, excess material positive; None = perfect gear
    flank_points: outline points per flank (sets the chordal error, :func:`chordal_error`)
    z_divisions: sections along the face; default enough for a helix chord below 0.02 um
    rim: radial rim thickness of an internal gear beyond the root [mm] (default 3 mn)
    offset: (x, y) translation applied last, e.g. an eccentricity [mm]
    rotation: rigid rotation about z applied before the offset [rad]
    helix_sagitta: largest radial chord error of the helix between sections [mm] (sets z_divisions)
    """
    outline = transverse_outline(gear, flank_points, arc_points)
    if gear.internal:
        rim_r = gear.root_radius + (3 * gear.mn if rim is None else rim)
        a = np.linspace(0, 2 * math.pi, 720, endpoint=False)
        outer = np.stack([rim_r * np.cos(a), rim_r * np.sin(a)], -1)
        cs = mf.CrossSection([outer, outline[::-1]], mf.FillRule.EvenOdd)
    else:
        cs = mf.CrossSection([outline], mf.FillRule.Positive)
    b = gear.face_width
    omega = twist_rate(gear)
    if z_divisions is None:
        # helix chord sagitta r (omega dz)^2 / 8 is radial: along the base tangent it counts ~ tan(alpha) of it
        z_divisions = 0 if omega == 0 else math.ceil(b * abs(omega) * math.sqrt(gear.tip_radius / 8 / helix_sagitta))
        if deviation is not None:
            z_divisions = max(z_divisions, 24)
    solid = mf.Manifold.extrude(cs, b, n_divisions=z_divisions).translate((0.0, 0.0, -b / 2))

    def warp(v: np.ndarray) -> np.ndarray:
        v = np.array(v, dtype=float)
        r = np.hypot(v[:, 0], v[:, 1])
        theta = np.arctan2(v[:, 1], v[:, 0])
        add = omega * v[:, 2]
        if deviation is not None:
            flat = np.column_stack([v[:, 0], v[:, 1], np.zeros(len(v))])
            on_flank = (r > gear.base_radius) & (r >= min(gear.tip_radius, gear.root_radius) - 1e-9)
            for side in SIDES:
                e0 = base_tangent_deviation(gear, flat, side)
                mask = on_flank & (np.abs(e0) < 1e-7)
                if not mask.any():
                    continue
                pitch = 2 * math.pi / gear.teeth
                nominal0 = flank_polar_angle(gear, r[mask], 0.0, side, 0)
                tooth = np.round((theta[mask] - nominal0) / pitch).astype(int) % gear.teeth
                L = np.sqrt(np.maximum(r[mask] ** 2 - gear.base_radius**2, 0.0))
                e = np.asarray(deviation(side, tooth, L, v[mask, 2]), dtype=float)
                add[mask] += side_sign(gear, side) * e / gear.base_radius
        theta = theta + add + rotation
        x = r * np.cos(theta) + offset[0]
        y = r * np.sin(theta) + offset[1]
        return np.column_stack([x, y, v[:, 2]])

    solid = solid.warp_batch(warp)
    if solid.status() != mf.Error.NoError or solid.is_empty():
        raise RuntimeError(f"reference gear mesh is not manifold: {solid.status()}")
    mesh = solid.to_mesh64()
    return trimesh.Trimesh(np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts), process=False)
