"""Flank traces read off the mesh: deviation along the base tangent at chosen roll lengths or heights.

A profile trace is the section of the mesh by a transverse plane, cut by circles at the target roll
lengths; a helix trace is the section by the reference cylinder, read at the target heights. Each
trace value is taken on the mesh's own straight segments (no smoothing), then compared with the
nominal flank of the same tooth turned by the datum rotation:

    e = side_sign * r_b * (theta_measured - theta_nominal(r, z) - rotation)      [mm, excess material > 0]
"""

from __future__ import annotations

import math

import numpy as np

from cutting.flank import SIDES, Side, flank_polar_angle, side_sign
from cutting.gear import Gear
from metrology.datum import Datum
from metrology.sections import MeshData, level_segments


def _classify(gear: Gear, datum: Datum, pts: np.ndarray, z_rel: np.ndarray, side: Side, window: float):
    """Tooth index and deviation of section points lying near ``side`` flanks (|e| < window)."""
    r = np.hypot(pts[:, 0], pts[:, 1])
    theta = np.arctan2(pts[:, 1], pts[:, 0])
    pitch = 2 * math.pi / gear.teeth
    d = theta - flank_polar_angle(gear, r, z_rel, side, 0) - datum.rotation
    k = np.round(d / pitch)
    e = side_sign(gear, side) * gear.base_radius * (d - k * pitch)
    near = np.abs(e) < window
    return near, k.astype(int) % gear.teeth


def _nominal(gear: Gear, radius, z_rel, side: Side) -> np.ndarray:
    """Nominal flank angles, shape (teeth, samples), of every tooth in nominal index order."""
    teeth = 2 * math.pi * np.arange(gear.teeth)[:, None] / gear.teeth
    return flank_polar_angle(gear, radius, z_rel, side, 0)[None, :] + teeth


def _window(gear: Gear) -> float:
    """Half-width of the band around a nominal flank that belongs to it [mm]: a quarter of the space width."""
    return 0.25 * gear.mn * math.pi / 2


def profile_trace(mesh: MeshData, gear: Gear, datum: Datum, z_rel: float, radii: np.ndarray) -> dict[str, np.ndarray]:
    """Deviations e[side] of shape (z, len(radii)) [mm] in the transverse section at ``z_rel`` from mid face.

    Teeth in nominal index order; NaN where the mesh has no flank at that radius.
    """
    a, b = level_segments(mesh, "z", datum.z_mid + z_rel)
    mid = (a + b) / 2
    r_lo, r_hi = float(radii.min()), float(radii.max())
    ra, rb = np.hypot(a[:, 0], a[:, 1]), np.hypot(b[:, 0], b[:, 1])
    span = (np.maximum(ra, rb) >= r_lo - 1e-9) & (np.minimum(ra, rb) <= r_hi + 1e-9)
    out = {}
    for side in SIDES:
        near, tooth = _classify(gear, datum, mid, np.full(len(mid), z_rel), side, _window(gear))
        sel = near & span
        e = np.full((gear.teeth, radii.size), np.nan)
        _read_radii(a[sel], b[sel], tooth[sel], radii, e)
        d = e - _nominal(gear, radii, z_rel, side) - datum.rotation  # e holds measured theta here
        d = (d + math.pi) % (2 * math.pi) - math.pi
        out[side] = side_sign(gear, side) * gear.base_radius * d
    return out


def _read_radii(a: np.ndarray, b: np.ndarray, tooth: np.ndarray, radii: np.ndarray, out: np.ndarray) -> None:
    """Polar angle where each tooth's segments cross each target radius, written into ``out[tooth]``."""
    ra, rb = np.hypot(a[:, 0], a[:, 1]), np.hypot(b[:, 0], b[:, 1])
    lo, hi = np.minimum(ra, rb), np.maximum(ra, rb)
    order = np.argsort(lo)
    a, b, lo, hi, tooth = a[order], b[order], lo[order], hi[order], tooth[order]
    for j, r in enumerate(radii):
        hit = np.nonzero((lo <= r) & (hi > r))[0]
        if hit.size == 0:
            continue
        pa, pb = a[hit, :2], b[hit, :2]
        d = pb - pa
        qa = np.einsum("ij,ij->i", d, d)
        qb = 2 * np.einsum("ij,ij->i", pa, d)
        qc = np.einsum("ij,ij->i", pa, pa) - r * r
        disc = np.sqrt(np.maximum(qb * qb - 4 * qa * qc, 0.0))
        t1, t2 = (-qb + disc) / (2 * qa), (-qb - disc) / (2 * qa)
        t = np.where((t1 >= -1e-12) & (t1 <= 1 + 1e-12), t1, t2)
        p = pa + t[:, None] * d
        # one crossing per tooth and flank; if a flank crosses twice (a ripple), keep the one nearest nominal
        out[tooth[hit], j] = np.arctan2(p[:, 1], p[:, 0])


def helix_trace(mesh: MeshData, gear: Gear, datum: Datum, radius: float, z_rel: np.ndarray) -> dict[str, np.ndarray]:
    """Deviations e[side] of shape (z, len(z_rel)) [mm] on the cylinder ``radius`` at heights ``z_rel``."""
    a, b = level_segments(mesh, "r", radius)
    a = a - [0.0, 0.0, datum.z_mid]
    b = b - [0.0, 0.0, datum.z_mid]
    mid = (a + b) / 2
    out = {}
    for side in SIDES:
        near, tooth = _classify(gear, datum, mid, mid[:, 2], side, _window(gear))
        pa, pb, tk = a[near], b[near], tooth[near]
        theta = np.full((gear.teeth, z_rel.size), np.nan)
        za, zb = pa[:, 2], pb[:, 2]
        lo, hi = np.minimum(za, zb), np.maximum(za, zb)
        ta, tb = np.arctan2(pa[:, 1], pa[:, 0]), np.arctan2(pb[:, 1], pb[:, 0])
        dt = (tb - ta + math.pi) % (2 * math.pi) - math.pi
        for j, zz in enumerate(z_rel):
            hit = np.nonzero((lo <= zz) & (hi > zz) & (hi > lo))[0]
            if hit.size == 0:
                continue
            t = (zz - za[hit]) / (zb[hit] - za[hit])
            theta[tk[hit], j] = ta[hit] + t * dt[hit]
        d = (theta - _nominal(gear, radius, z_rel, side) - datum.rotation + math.pi) % (2 * math.pi) - math.pi
        out[side] = side_sign(gear, side) * gear.base_radius * d
    return out
