"""First-order signatures of the machine's geometry on the gear: the envelope theorem at the generating points.

A small displacement of the tool moves the surface its edge generates along the surface's normal by the normal part
of the tool's displacement at the point that generates it. So the deviation a machine error leaves at a flank point
Q is n(Q) . (x_as_built - x_nominal), the tool's material point at Q moved from the nominal pose to the one the
machine as built makes from the same axes (:meth:`SkivingSetup.machine_pose`), at Q's generating instant, over
cos(beta_b) along the transverse base tangent (as a gear measuring machine reads it; docs/machine_geometry.md).

Q's generating instant, on the nominal machine: the cutter angle phi0 and the carriage s (both taken continuous: the
feed's scallops left out) at which Q lies in a tooth's rake plane with the edge's outline margin there at its
largest (zero on the nominal flank: the envelope touches it). For each s the rake plane crosses Q at one cutter angle
(a root); the margin along s is then maximised. This is independent of the cut (no swept volume, no measurement):
the tests hold the cut and measured gear against it (tests/test_machine_geometry.py).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from cutting.flank import flank_normals, flank_points
from cutting.skiving.edge import make_edge
from cutting.skiving.exact_sweep import Outline
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.tooling import chain, frame, turn_z

#: how far along the face from Q the generating carriage position is searched [mm] (the contact runs a few mm up
#: and down the rake face: L tan(Sigma) at most)
SEARCH = 6.0


def _tooth_coordinates(st: SkivingSetup, q: np.ndarray, phi0, s: float, a: float, k: int) -> np.ndarray:
    """Q in the rake frame of the nominal tooth ``k`` at cutter angles ``phi0`` (n,) and carriage ``s``: (n, 3)."""
    rot, trans = st.cutter_pose(np.atleast_1d(phi0), s, a)
    tooth = chain(frame(turn_z(2 * math.pi * k / st.cutter.teeth)), st.rake_frame)
    in_cutter = np.einsum("nji,nj->ni", rot, q - trans)
    return (in_cutter - tooth[:, 3]) @ tooth[:, :3]


def _nearest_tooth(phi0: float, teeth: int) -> int:
    """The tooth at the mesh at cutter angle ``phi0`` (tooth 0 is there at 0)."""
    return round(-phi0 * teeth / (2 * math.pi))


def generating_instant(st: SkivingSetup, q: np.ndarray, a: float, edge=None) -> tuple[float, float, float]:
    """(phi0, s, margin) at which the nominal machine generates the blank-frame point ``q`` (module docstring) at
    centre distance ``a``; the margin [mm] is ~0 for a point on the nominal flank."""
    outline = Outline((edge or make_edge(st, "conjugate")).outline)
    theta = math.atan2(q[1], q[0])
    z0 = st.cutter.teeth
    turn = 2 * math.pi / abs(st.speed_ratio)  # the cutter's turn over one work revolution

    def crossing(s: float, k: int) -> float:
        # the rake plane of tooth k crossing q, at the root next to the cutter angle that brings q to the mesh
        # (machine azimuth 0), searched over a quarter of a work revolution either side
        guess = (-theta - st.differential_rotation_per_mm * s - st.work_phase) / st.speed_ratio
        guess -= round(guess / turn) * turn
        grid = guess + np.linspace(-turn / 4, turn / 4, 65)
        f = lambda p: float(_tooth_coordinates(st, q, p, s, a, k)[0, 2])  # noqa: E731
        v = _tooth_coordinates(st, q, grid, s, a, k)[:, 2]
        change = np.nonzero(np.sign(v[:-1]) != np.sign(v[1:]))[0]
        if not len(change):
            raise ValueError("the rake plane does not cross the point near the mesh")
        j = change[np.argmin(np.abs(grid[change] - guess))]
        return brentq(f, grid[j], grid[j + 1], xtol=1e-14)

    def teeth(s: float) -> list[int]:
        guess = (-theta - st.differential_rotation_per_mm * s - st.work_phase) / st.speed_ratio
        k = _nearest_tooth(guess - round(guess / turn) * turn, z0)
        return [k - 1, k, k + 1]  # the tooth at the mesh and its neighbours: the one that reaches q cuts it

    def margin(s: float) -> tuple[float, float]:
        """(margin, cutter angle) of the tooth that reaches q deepest at carriage s."""
        best = (-1e3, math.nan)
        for k in teeth(s):
            try:
                phi0 = crossing(s, k)
            except ValueError:  # the rake plane does not reach q's height at this carriage position
                continue
            p = _tooth_coordinates(st, q, phi0, s, a, k)[0]
            best = max(best, (float(outline.margin(p[0], p[1])), phi0))
        return best

    def minus_margin(s: float) -> float:
        return -margin(s)[0]

    zq = float(q[2])
    grid = np.linspace(zq - SEARCH, zq + SEARCH, 25)
    values = [minus_margin(s) for s in grid]
    i = int(np.argmin(values))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
    best = minimize_scalar(minus_margin, bounds=(lo, hi), method="bounded", options={"xatol": 1e-9})
    s = float(best.x)
    m, phi0 = margin(s)
    return phi0, s, m


def flank_deviation_first_order(
    nominal: SkivingSetup, built: SkivingSetup, side: str, roll: np.ndarray, z: float, a: float | None = None
) -> np.ndarray:
    """The deviation [mm] (along the transverse base tangent, material added positive) that the machine as built
    (``built``: the nominal setup with its :attr:`SkivingSetup.geometry`) leaves on the ``side`` flank of tooth 0 at
    roll lengths ``roll`` [mm] and height ``z`` [mm], to first order (module docstring); ``a`` the centre distance
    (default the finishing one)."""
    g = nominal.gear
    a = nominal.final_centre_distance if a is None else a
    edge = make_edge(nominal, "conjugate")
    xi = np.asarray(roll, dtype=float) / g.base_radius
    points = flank_points(g, side, xi, z, 0)
    normals = flank_normals(g, side, xi, z, 0)
    cos_beta_b = math.cos(math.atan(math.tan(g.beta) * g.base_radius / g.reference_radius))
    out = np.empty(len(xi))
    for i, (q, n) in enumerate(zip(points, normals, strict=True)):
        phi0, s, _ = generating_instant(nominal, q, a, edge)
        rot, trans = nominal.cutter_pose(np.array([phi0]), s, a)
        tool_point = rot[0].T @ (q - trans[0])
        rot_b, trans_b = built.machine_pose(np.array([phi0]), s, a)
        moved = rot_b[0] @ tool_point + trans_b[0]
        out[i] = float(n @ (moved - q)) / cos_beta_b
    return out
