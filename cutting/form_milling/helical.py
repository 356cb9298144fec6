"""A helical tooth space by the copying method: the disc mill set over at the helix angle, its profile the envelope
of the helicoid (seed 003 says "a specially profiled disc or finger mill" and gives the profile only as the space's
section, which holds for a spur gear).

The mill sits over tooth space 0 at mid face (space frame: x tangential, y radial, z axial), its centre ``radius``
above the path point and its axis turned from the tangential direction by the reference helix angle beta about the
radial line, a = (cos beta, 0, -sin beta) (the mill's plane along the space at the reference cylinder). Relative
to the work it makes the space's screw motion: turning about the gear axis by 2 pi / p_z per mm of feed along it.
A surface of revolution and a helicoid touch along a fixed curve of the mill, where the flank's normal meets the
mill's axis: (P - C) . (a x n) = 0. Per profile point (roll length L) that fixes the face position z of the
contact; the mill's axial profile there is u = (P - C) . a along the axis and rho = |P - C - u a| from it. On a
spur gear (beta = 0) the contact is the section z = 0 and the profile is the section itself.
"""

from __future__ import annotations

import math

import numpy as np

from cutting.flank import Side, flank_normals, flank_points, twist_rate
from cutting.form_milling.mill import BezierChain, DiscMill, from_space, section_rolls, space_tooth, tip_index, to_space
from cutting.form_milling.sweep import MillPassPoses
from cutting.gear import Gear

#: the contact's face position is searched within this many module either side of the mill's centre plane
CONTACT_REACH = 6.0


def set_over(gear: Gear) -> float:
    """The mill's set-over angle about the radial line [rad]: the reference helix angle, signed with the hand (0 on a
    spur gear); the copying method's poses add it to psi_y."""
    return math.atan(gear.reference_radius * twist_rate(gear))


def mill_axis(gear: Gear) -> np.ndarray:
    """The set-over mill's axis in the space frame: the tangential direction turned by the set-over angle about the
    radial line (its plane along the space at the reference cylinder)."""
    beta = set_over(gear)
    return np.array([math.cos(beta), 0.0, -math.sin(beta)])


def contact_profile(gear: Gear, side: Side, L: np.ndarray, centre: np.ndarray, axis: np.ndarray):
    """Per roll length L (n,): the contact point of the ``side`` flank of space 0 with a surface of revolution about
    (``centre``, ``axis``) (space frame), as the mill's axial coordinate u and radius rho [mm], and the contact's
    face position z [mm] (NaN where the normal never meets the axis within CONTACT_REACH mn)."""
    tooth = space_tooth(gear, 0, side)
    xi = np.asarray(L, dtype=float) / gear.base_radius
    reach = CONTACT_REACH * gear.mn
    zs = np.linspace(-reach, reach, 241)

    def gap(x: np.ndarray, z: np.ndarray) -> np.ndarray:
        p = to_space(gear, 0, flank_points(gear, side, x, z, tooth)) - centre
        n = to_space(gear, 0, flank_normals(gear, side, x, z, tooth))
        return np.einsum("...i,...i->...", p, np.cross(axis, n))

    g = gap(xi[:, None], zs[None, :])
    z = np.full(len(xi), np.nan)
    for i in range(len(xi)):
        change = np.flatnonzero(np.sign(g[i, :-1]) != np.sign(g[i, 1:]))
        if not len(change):
            continue
        k = change[np.argmin(np.abs(zs[change]))]  # the crossing nearest the centre plane
        lo, hi, glo = zs[k], zs[k + 1], g[i, k]
        for _ in range(60):  # bisection to ~1e-16 of the grid step
            mid = 0.5 * (lo + hi)
            gm = float(gap(xi[i], np.array(mid)))
            if (gm > 0) == (glo > 0):
                lo, glo = mid, gm
            else:
                hi = mid
        z[i] = 0.5 * (lo + hi)
    ok = np.isfinite(z)
    p = np.full((len(xi), 3), np.nan)
    p[ok] = to_space(gear, 0, flank_points(gear, side, xi[ok], z[ok], tooth)) - centre
    u = p @ axis
    rho = np.linalg.norm(p - u[:, None] * axis, axis=1)
    return u, rho, z


def envelope_mill(gear: Gear, radius: float, teeth: int = 12, x_path: float = 0.0, points: int = 81) -> DiscMill:
    """The disc mill (outer radius ``radius`` [mm]) whose edges are the envelope profile of both flanks of the
    helical space, its path point at ``x_path`` [mm] (tangential) on the root circle at mid face: edges in tool
    coordinates (x along the axis, y above the periphery) fitted by Bezier chains (eq. 9), the tip point a joint."""
    centre = np.array([x_path, gear.root_radius + radius, 0.0])
    axis = mill_axis(gear)
    L = section_rolls(gear, points)
    top = tip_index(gear, L)
    edges = []
    for side in ("left", "right"):
        u, rho, z = contact_profile(gear, side, L, centre, axis)
        if not np.all(np.isfinite(z)):
            raise ValueError(
                f"the {side} flank has profile points whose normal never meets the set-over mill's axis (roll "
                f"lengths {np.round(L[~np.isfinite(z)], 3).tolist()} mm): the mill of radius {radius} mm cannot "
                "touch them; use a larger mill"
            )
        edges.append(BezierChain.fit(np.column_stack([u, radius - rho]), through=(top,)))
    return DiscMill(radius, edges[0], edges[1], teeth)


def helical_pass(gear: Gear, mill: DiscMill, space: int, z: np.ndarray, x_path: float = 0.0) -> MillPassPoses:
    """The poses (gear frame) of the set-over mill fed along tooth space ``space`` at face positions ``z`` [mm]: the
    mid-face setting carried by the space's screw motion (turned about the gear axis by 2 pi / p_z per mm)."""
    z = np.asarray(z, dtype=float)
    centre0 = from_space(gear, space, np.array([x_path, gear.root_radius + mill.radius, 0.0]))
    axis0 = from_space(gear, space, mill_axis(gear))
    turn = twist_rate(gear) * z
    c, s = np.cos(turn), np.sin(turn)

    def screw(v: np.ndarray, shift: np.ndarray) -> np.ndarray:
        return np.column_stack([c * v[0] - s * v[1], s * v[0] + c * v[1], v[2] + shift])

    return MillPassPoses(space, "both", z.copy(), screw(centre0, z), screw(axis0, 0 * z))
