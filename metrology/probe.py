"""A ball probe on the mesh: exact point-to-triangle distances and the seat of a ball in a tooth space.

Used for runout (a ball in every space, touching both flanks) and for the dimension over/between balls.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from cutting.gear import Gear
from metrology.datum import Datum
from metrology.sections import MeshData


def point_triangle_distance(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Distance from point ``p`` (3,) to each triangle ``tri`` (n, 3, 3): closest point by Voronoi regions."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp = p - b
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    cp = p - c
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    # face region by default
    denom = va + vb + vc
    denom = np.where(np.abs(denom) < 1e-300, 1e-300, denom)
    v, w = vb / denom, vc / denom
    q = a + ab * v[:, None] + ac * w[:, None]

    def put(mask: np.ndarray, value: np.ndarray) -> None:
        q[mask] = value[mask]

    # edge regions (checked before vertices so vertex regions win)
    m_bc = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
    t_bc = (d4 - d3) / np.where((d4 - d3) + (d5 - d6) == 0, 1, (d4 - d3) + (d5 - d6))
    put(m_bc, b + (c - b) * t_bc[:, None])
    m_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    t_ac = d2 / np.where(d2 - d6 == 0, 1, d2 - d6)
    put(m_ac, a + ac * t_ac[:, None])
    m_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    t_ab = d1 / np.where(d1 - d3 == 0, 1, d1 - d3)
    put(m_ab, a + ab * t_ab[:, None])
    put((d6 >= 0) & (d5 <= d6), c)
    put((d3 >= 0) & (d4 <= d3), b)
    put((d1 <= 0) & (d2 <= 0), a)
    return np.linalg.norm(p - q, axis=1)


def ball_seats(mesh: MeshData, gear: Gear, datum: Datum, diameter: float, centre_radius: float) -> np.ndarray:
    """Centres (z, 3) of a ball of ``diameter`` seated in every space at mid face, touching both flanks.

    Row j is the space after nominal tooth j (between teeth j and j+1). ``centre_radius`` is the nominal
    radius of the ball centre, used as the start. The centre stays in the mid-face plane and moves in
    radius and angle until its distance to the mesh on each side of it is the ball radius.
    """
    pitch = 2 * math.pi / gear.teeth
    half = diameter / 2
    # only triangles the ball can touch: near the ball-centre circle, near the mid plane
    v = mesh.vertices
    vr = mesh.radius
    f = mesh.faces
    fr_lo, fr_hi = vr[f].min(axis=1), vr[f].max(axis=1)
    fz_lo, fz_hi = v[f, 2].min(axis=1), v[f, 2].max(axis=1)
    # a ball touches within half its diameter of its centre; the centre moves little from nominal
    reach = 0.5 * diameter + 0.5 * gear.mn
    zone = (fr_hi > centre_radius - reach) & (fr_lo < centre_radius + reach)
    zone &= (fz_lo < datum.z_mid + reach) & (fz_hi > datum.z_mid - reach)
    tri = v[f[zone]]
    cen = tri.mean(axis=1)
    thc = np.arctan2(cen[:, 1], cen[:, 0])
    out = np.zeros((gear.teeth, 3))
    radius = half
    for j in range(gear.teeth):
        phi0 = datum.rotation + (j + 0.5) * pitch
        dphi = (thc - phi0 + math.pi) % (2 * math.pi) - math.pi
        local = np.abs(dphi) < 0.75 * pitch + half / centre_radius
        t_loc, a_loc = tri[local], dphi[local]

        # Keep only triangles within reach of the ball around its nominal seat (one exact distance pass);
        # if the seat found touches anything left out, widen the reach and solve again.
        nominal_seat = np.array([centre_radius * math.cos(phi0), centre_radius * math.sin(phi0), datum.z_mid])
        d_nominal = point_triangle_distance(nominal_seat, t_loc)
        for margin in (0.05 * gear.mn, 0.3 * gear.mn, math.inf):
            reach = d_nominal < radius + margin
            try:
                seat, dist = _seat(
                    t_loc[(a_loc > 0) & reach],
                    t_loc[(a_loc <= 0) & reach],
                    radius,
                    centre_radius,
                    phi0,
                    pitch,
                    gear.mn,
                    datum.z_mid,
                    diameter,
                    j,
                )
            except RuntimeError:
                if math.isinf(margin):
                    raise
                continue
            # triangle inequality: only triangles this close to the nominal seat can be closer to the found one
            near = d_nominal < dist + np.linalg.norm(seat - nominal_seat) + 1e-9
            if point_triangle_distance(seat, t_loc[near]).min() >= dist - 1e-9:
                break
        out[j] = seat
    return out


def _seat(
    t_ccw: np.ndarray,
    t_cw: np.ndarray,
    radius: float,
    centre_radius: float,
    phi0: float,
    pitch: float,
    mn: float,
    z_mid: float,
    diameter: float,
    j: int,
) -> tuple[np.ndarray, float]:
    """Ball seat between the flank triangles on either side of the space centre line phi0."""

    def point(rho: float, phi: float) -> np.ndarray:
        return np.array([rho * math.cos(phi0 + phi), rho * math.sin(phi0 + phi), z_mid])

    def centred(rho: float) -> tuple[float, float]:
        """Angle at which the ball at radius rho is equidistant from both flanks, and that distance."""

        def gap(phi: float) -> float:
            c = point(rho, phi)
            return point_triangle_distance(c, t_ccw).min() - point_triangle_distance(c, t_cw).min()

        phi = brentq(gap, -0.45 * pitch, 0.45 * pitch, xtol=1e-13)
        return phi, point_triangle_distance(point(rho, phi), t_ccw).min()

    if len(t_ccw) == 0 or len(t_cw) == 0:
        raise RuntimeError(f"the ball of {diameter:.3f} mm finds no flank on one side of space {j}")
    lo, hi = centre_radius - 0.5 * mn, centre_radius + 0.5 * mn
    try:
        rho = brentq(lambda rr: centred(rr)[1] - radius, lo, hi, xtol=1e-10)
    except ValueError as exc:
        msg = f"the ball of {diameter:.3f} mm does not seat in space {j} near r = {centre_radius:.3f} mm"
        raise RuntimeError(msg) from exc
    phi, dist = centred(rho)
    return point(rho, phi), dist
