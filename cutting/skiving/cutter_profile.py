"""The cutter's profile deviations: a slope and a form deviation of each flank of its edge, the same on every tooth,
as a cutter measuring machine reports them (transverse, along the base tangent, in the rake face), over the active
flank: the part of the edge that generates the gear's flank from its form circle to its tip.

With u the position along that part of the cutter's flank by its roll length L0 (-1/2 where it generates the gear's
tip, +1/2 where it generates the gear's form circle: towards the cutter's tip), a flank's deviation is

    e(u) = f_H u + f_f (4 u^2 - 1/3)      [mm, + more tool material]

a slope f_H across the active flank and a parabola of range f_f about its mean line; beyond the active flank (the
radii that never generate the gear's flank) e keeps its value at the nearer end. The edge's polar angle moves by
e / r_b0 (a transverse base-tangent deviation on an involute is a turn of the flank by e / r_b0).
"""

from __future__ import annotations

import math

import numpy as np

from cutting.flank import flank_normals, flank_points
from cutting.skiving.edge import CuttingEdge, assemble_edge, contact_radius, envelope_bound, mate_flank
from cutting.skiving.kinematics import SkivingSetup

#: an edge radius generates the flank where it lies this close [mm] to the envelope (the involute edge is a few
#: micrometres off it, the radii below the generating zone tens)
TOUCHING = 0.005


def roll_map(setup: SkivingSetup, edge: CuttingEdge, side: str) -> tuple[np.ndarray, np.ndarray]:
    """Where flank ``side`` of the edge generates the gear's flank: the gear's roll lengths L2 [mm] (increasing) and
    the cutter's L0 [mm] of the edge radii that generate them (the envelope's contacts, :mod:`cutting.skiving.edge`)."""
    l2, l0, _ = generating_map(setup, edge, side)
    return l2, l0


def generating_map(setup: SkivingSetup, edge: CuttingEdge, side: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`roll_map` and, per contact, the transfer k: the gear flank's normal deviation per unit of the edge's
    transverse base-tangent deviation m (a turn of the edge point by m / r_b0 in the rake face moves it r m / r_b0
    along the face's e_theta; the gear flank moves by that times |e_theta . n| with n the gear flank's normal at the
    contact). On the end plane through the axes' crossing k = cos(beta_b0) (n is the cutter helicoid's normal
    there); an offset face meets the gear where the helicoids are not tangent, and k departs from it."""
    g, c = setup.gear, setup.cutter
    sgn = 1.0 if side == "left" else -1.0
    band = (g.tip_radius, g.root_radius) if g.internal else (g.base_radius, g.tip_radius)
    grid = np.linspace(-0.5 * math.pi, 0.5 * math.pi, 1500)
    theta = edge.theta[side]
    bound, at = envelope_bound(setup, edge.radii, theta, mate_flank(setup, side), sgn, grid, band)
    r = contact_radius(setup, edge.radii, theta, at)
    touching = np.isfinite(r) & (np.abs(sgn * bound - theta) * edge.radii < TOUCHING)
    if touching.sum() < 3:
        raise ValueError(f"the {side} edge generates no flank: no profile deviation can be placed on it")
    l0 = np.sqrt(np.maximum(edge.radii[touching] ** 2 - c.base_radius**2, 0.0))
    l2 = np.sqrt(np.maximum(r[touching] ** 2 - g.base_radius**2, 0.0))
    rho, th = edge.radii[touching], theta[touching]
    rot, t = setup.rake_pose(at[touching])
    w = np.einsum("nij,nj->ni", rot, np.stack([rho * np.cos(th), rho * np.sin(th), 0 * th], -1)) + t
    e_theta = np.einsum("nij,nj->ni", rot, np.stack([-np.sin(th), np.cos(th), 0 * th], -1))
    mate = mate_flank(setup, side)
    xi = l2 / g.base_radius
    normal = flank_normals(g, mate, xi, w[:, 2], 0)
    nominal = flank_points(g, mate, xi, w[:, 2], 0)
    turn = np.arctan2(w[:, 1], w[:, 0]) - np.arctan2(nominal[:, 1], nominal[:, 0])  # the normal at w's own angle
    cs, sn = np.cos(turn), np.sin(turn)
    n_xy = np.stack([cs * normal[:, 0] - sn * normal[:, 1], sn * normal[:, 0] + cs * normal[:, 1]], -1)
    dot = np.abs(e_theta[:, 0] * n_xy[:, 0] + e_theta[:, 1] * n_xy[:, 1] + e_theta[:, 2] * normal[:, 2])
    k = dot * rho / c.base_radius
    order = np.argsort(l2)
    return l2[order], l0[order], k[order]


def active_flank(setup: SkivingSetup, edge: CuttingEdge, side: str) -> tuple[float, float]:
    """The cutter roll lengths L0 [mm] of the edge radii that generate the gear's tip and its form circle on flank
    ``side`` (:func:`roll_map`, interpolated)."""
    g = setup.gear
    l2, l0 = roll_map(setup, edge, side)
    form = max(g.base_radius, g.rack_form_diameter / 2) if not g.internal else g.root_radius
    ends = [math.sqrt(max(x**2 - g.base_radius**2, 0.0)) for x in (g.tip_radius, form)]
    at_tip, at_form = (float(np.interp(e, l2, l0)) for e in ends)
    return at_tip, at_form


def deviated_edge(setup: SkivingSetup, edge: CuttingEdge) -> CuttingEdge:
    """``edge`` with the setup's cutter profile deviations (:attr:`CutterErrors.profile_slope`, ``profile_form``,
    each (left, right) [mm], the same on every tooth or one per tooth): the teeth's mean on the edge itself and,
    where the teeth differ, each tooth's own flanks in :attr:`CuttingEdge.teeth`."""
    err = setup.cutter_errors
    c = setup.cutter
    l0 = np.sqrt(np.maximum(edge.radii**2 - c.base_radius**2, 0.0))
    u = {}
    for side in ("left", "right"):
        at_tip, at_form = active_flank(setup, edge, side)  # the envelope: once per flank, not per tooth
        # beyond the active flank the profile is not measured: the deviation holds its end value there (the parabola
        # carried on would grow without bound towards the cutter's root and tip: 47 um at u = -2 for f_f = 3 um)
        u[side] = np.clip((l0 - (at_tip + at_form) / 2) / (at_form - at_tip), -0.5, 0.5)

    def flanks(tooth: int | None) -> dict[str, np.ndarray]:
        slope, form = err.tooth_profile(tooth)
        theta = dict(edge.theta)
        for k, side in enumerate(("left", "right")):
            e = slope[k] * u[side] + form[k] * (4 * u[side] ** 2 - 1 / 3)
            # more tool material: the left flank (on +theta of the tooth) turns to +theta, the right one to -theta
            theta[side] = theta[side] + (1.0 if side == "left" else -1.0) * e / c.base_radius
        return theta

    teeth = tuple(flanks(k) for k in range(c.teeth)) if err.profile_per_tooth else ()
    return assemble_edge(edge.kind, edge.radii, flanks(None), edge.r_low, teeth)
