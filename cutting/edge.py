"""The cutting edge: the outline of one cutter tooth in its rake plane (the cutter's end plane, z0 = 0).

Cutter frame: z along the cutter axis, the rake face in z = 0, tooth 0 centred on +x (the ideal motion of
:class:`cutting.skiving.SkivingSetup` brings tooth 0 to the mesh point at phi0 = 0). The outline is the
closed, counter-clockwise polygon of the tooth section from the depth that can meet the workpiece up to
the tip; the removed volume is what this planar region sweeps.

Two edges (domain.md section 1):

- ``involute``: the end-plane section of involute-helicoid flanks with the gear's normal basic rack (a
  shaper-type cutter). With crossed axes it touches the workpiece flank only at a point, so it leaves a
  small theoretical profile error.
- ``conjugate``: designed by the envelope method. For each radius rho of the rake plane the edge point is
  pushed as far towards the workpiece flank as the ideal motion allows without ever entering it:
  theta*(rho) = the extreme over the tooth passage of theta_t(rho), the angle at which the point at
  (rho, theta) lies exactly on the workpiece's nominal flank at instant t. The extreme is found on a
  dense time grid and refined by a bounded scalar search, so the edge is the exact envelope (no union of
  jagged sections to smooth).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from cutting.flank import SIDES, base_tangent_deviation, flank_points
from cutting.skiving import SkivingSetup

EDGE_KINDS = ("involute", "conjugate")

#: The conjugate edge departs from the involute edge by a few micrometres (domain.md section 1); a larger
#: departure marks radii that never generate the flank [mm].
CONJUGATE_MAX_DEPARTURE = 0.010


@dataclass(frozen=True)
class CuttingEdge:
    """One cutter tooth's edge in the rake plane.

    outline: (n, 2) counter-clockwise polygon [mm]: right flank up, tip, left flank down, closed by a chord
        at ``r_low`` inside the cutter body
    radii: the flank radii sampled [mm] (increasing)
    theta: {"left": (m,), "right": (m,)} polar angle of each flank at ``radii`` [rad]
    """

    kind: str
    outline: np.ndarray
    radii: np.ndarray
    theta: dict[str, np.ndarray]
    r_low: float
    r_tip: float


def edge_radii(setup: SkivingSetup, points: int) -> tuple[np.ndarray, float]:
    """Radii of the flank samples: from below the deepest reach of the workpiece's tip up to the cutter tip."""
    ra0 = setup.cutter_tip_diameter / 2
    g = setup.gear
    # the workpiece's tip circle seen from the cutter axis
    reach = g.tip_radius - setup.final_centre_distance if g.internal else setup.final_centre_distance - g.tip_radius
    r_low = max(0.3 * ra0, min(reach, ra0 - setup.full_depth) - 0.3 * g.mn)
    # uniform in roll length above the base circle keeps the chord error of the outline even
    return np.linspace(r_low, ra0, points), r_low


def involute_edge(setup: SkivingSetup, points: int = 120) -> CuttingEdge:
    """The rake-plane section of the cutter's involute-helicoid flanks (radial below its base circle)."""
    c = setup.cutter
    radii, r_low = edge_radii(setup, points)
    r_eff = np.maximum(radii, c.base_radius)
    xi = np.sqrt(r_eff**2 - c.base_radius**2) / c.base_radius
    theta = {}
    for side in SIDES:
        p = flank_points(c, side, xi, 0.0, 0)
        theta[side] = np.arctan2(p[:, 1], p[:, 0])
    return _assemble("involute", radii, theta, r_low)


def _assemble(kind: str, radii: np.ndarray, theta: dict[str, np.ndarray], r_low: float) -> CuttingEdge:
    # the cutter is external: its left flank is on the +theta side of tooth 0
    right = np.stack([radii * np.cos(theta["right"]), radii * np.sin(theta["right"])], -1)
    left = np.stack([radii * np.cos(theta["left"]), radii * np.sin(theta["left"])], -1)[::-1]
    tip_a = np.linspace(theta["right"][-1], theta["left"][-1], 9)[1:-1]
    tip = radii[-1] * np.stack([np.cos(tip_a), np.sin(tip_a)], -1)
    outline = np.concatenate([right, tip, left])
    return CuttingEdge(kind, outline, radii, theta, r_low, float(radii[-1]))


def _mate(setup: SkivingSetup, side: str) -> str:
    """The workpiece flank that the cutter flank ``side`` generates (checked at the mesh position)."""
    c = setup.cutter
    xi = math.sqrt(max(c.reference_radius**2 - c.base_radius**2, 0.0)) / c.base_radius
    p = flank_points(c, side, xi, 0.0, 0)
    rot, t = setup.cutter_pose(np.array([0.0]))
    w = rot[0] @ p + t[0]
    e = {s: abs(float(base_tangent_deviation(setup.gear, w[None, :], s)[0])) for s in SIDES}
    return min(e, key=e.get)


def _on_flank(setup: SkivingSetup, rho: float, th_start: float, mate: str, phi0: np.ndarray, band: tuple[float, float]):
    """theta_t for each cutter angle: the angle at which the rake-plane point at radius rho lies exactly on the
    workpiece's nominal ``mate`` flank; with a validity mask and d(deviation)/d(theta) there (Newton)."""
    g = setup.gear
    rot, t = setup.cutter_pose(np.atleast_1d(phi0))

    def deviation(th: np.ndarray) -> np.ndarray:
        q = np.stack([rho * np.cos(th), rho * np.sin(th), np.zeros_like(th)], -1)
        return base_tangent_deviation(g, np.einsum("nij,nj->ni", rot, q) + t, mate)

    th = np.full(rot.shape[0], th_start)
    h = 1e-7
    for _ in range(30):
        e = deviation(th)
        de = (deviation(th + h) - e) / h
        step = np.clip(np.where(np.abs(de) > 1e-12, e / np.where(de == 0, 1.0, de), 0.0), -0.05, 0.05)
        th = th - step
        if np.all(np.abs(step) < 1e-14):
            break
    q = np.stack([rho * np.cos(th), rho * np.sin(th), np.zeros_like(th)], -1)
    w = np.einsum("nij,nj->ni", rot, q) + t
    r = np.hypot(w[:, 0], w[:, 1])
    # contact strictly inside the flank: at its ends the "envelope" is the tooth's corner, not the flank
    valid = (
        (r > band[0] + 1e-6) & (r < band[1] - 1e-6) & (np.abs(th - th_start) < 0.25 * 2 * np.pi / setup.cutter.teeth)
    )
    return th, valid, de


def conjugate_edge(setup: SkivingSetup, points: int = 120, steps: int = 1500) -> CuttingEdge:
    """The edge by the envelope method (see the module docstring); exact to the root-finding tolerance."""
    g = setup.gear
    inv_edge = involute_edge(setup, points)
    radii = inv_edge.radii
    phi_grid = np.linspace(-0.5 * math.pi, 0.5 * math.pi, steps)  # one tooth passage around the mesh
    # the workpiece's involute: from the base circle (external) or the tip (internal) to the other end
    band = (g.tip_radius, g.root_radius) if g.internal else (g.base_radius, g.tip_radius)
    theta: dict[str, np.ndarray] = {}
    for side in SIDES:
        mate = _mate(setup, side)
        sgn = 1.0 if side == "left" else -1.0  # the direction in which the cutter tooth grows thicker
        th0 = inv_edge.theta[side]
        out = th0.copy()
        for i, rho in enumerate(radii):
            th_t, valid, de = _on_flank(setup, rho, th0[i], mate, phi_grid, band)
            # the deviation is > 0 on the space side of the flank: where it falls as the cutter tooth
            # thickens (theta moving by +sgn), the point moves into the tooth: theta_t bounds the edge there
            active = valid & (sgn * de < 0)
            if not active.any():
                continue
            cand = np.where(active, sgn * th_t, np.inf)
            k = int(np.argmin(cand))  # the most restrictive instant on the grid, refined in between

            def bound(phi: float, rho: float = rho, start: float = th0[i], mate: str = mate, sgn: float = sgn) -> float:
                th, ok, d = _on_flank(setup, rho, start, mate, np.array([phi]), band)
                return float(sgn * th[0]) if ok[0] and sgn * d[0] < 0 else 1e9  # finite: keeps Brent stable

            lo, hi = phi_grid[max(k - 1, 0)], phi_grid[min(k + 1, steps - 1)]
            best = minimize_scalar(bound, bounds=(lo, hi), method="bounded", options={"xatol": 1e-12})
            out[i] = sgn * min(cand[k], best.fun)  # best.fun = 1e9 where no bound was found
        # Below the generating zone the "envelope" comes from the workpiece's tip corner and departs from the
        # involute by far more than the crossing error: keep the involute there (it never meets the flank).
        out = np.where(np.abs(out - th0) * radii > CONJUGATE_MAX_DEPARTURE, th0, out)
        # then make sure no point enters the whole nominal tooth (involute and tip circle)
        theta[side] = _clear_tip_corners(setup, radii, out, th0, phi_grid)
    return _assemble("conjugate", radii, theta, inv_edge.r_low)


def tooth_intrusion(setup: SkivingSetup, pts: np.ndarray, phi_grid: np.ndarray) -> np.ndarray:
    """Deepest intrusion [mm] of each rake-plane point (m, 2) into the nominal teeth over the cutter angles.

    Material: inside a tooth's involute outline between the form circle and the tip circle.
    """
    g = setup.gear
    rot, t = setup.cutter_pose(phi_grid)
    q = np.column_stack([pts, np.zeros(len(pts))])
    w = np.einsum("sij,nj->sni", rot, q) + t[:, None, :]
    r = np.hypot(w[..., 0], w[..., 1])
    pitch = 2 * math.pi / g.teeth
    centre = 2 * math.pi / g.lead * w[..., 2] if g.helix_angle else 0.0
    d = np.arctan2(w[..., 1], w[..., 0]) - centre
    d = d - pitch * np.round(d / pitch)
    lo = max(g.base_radius, g.rack_form_diameter / 2) if not g.internal else g.tip_radius
    hi = g.tip_radius if not g.internal else g.root_radius - g.rack.rho_f * (1 - math.sin(g.alpha_n)) * g.mn
    band = (r >= lo) & (r <= hi)
    psi = np.asarray(g.half_thickness_angle(np.clip(r, g.base_radius, None)))
    depth = np.where(band, (psi - np.abs(d)) * r, -np.inf)
    return depth.max(axis=0)


def _clear_tip_corners(
    setup: SkivingSetup, radii: np.ndarray, theta: np.ndarray, safe: np.ndarray, phi_grid: np.ndarray, tol: float = 1e-7
) -> np.ndarray:
    """Move each edge point from ``theta`` towards ``safe`` (the involute edge) until it enters no tooth."""

    def pts(th: np.ndarray) -> np.ndarray:
        return np.column_stack([radii * np.cos(th), radii * np.sin(th)])

    bad = tooth_intrusion(setup, pts(theta), phi_grid) > tol
    if not bad.any():
        return theta
    lo, hi = np.zeros(len(radii)), np.ones(len(radii))  # fraction of the way from safe to theta
    for _ in range(40):
        mid = (lo + hi) / 2
        trial = safe + mid * (theta - safe)
        ok = tooth_intrusion(setup, pts(trial), phi_grid) <= tol
        lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
    return np.where(bad, safe + lo * (theta - safe), theta)


@functools.lru_cache(maxsize=8)
def make_edge(setup: SkivingSetup, kind: str, points: int = 120) -> CuttingEdge:
    """The job's cutting edge (kept: the conjugate edge's envelope takes seconds, and a run needs it in several
    stages; the edge is immutable)."""
    if kind not in EDGE_KINDS:
        raise ValueError(f"cutter.edge = {kind!r}: unknown edge; use 'involute' or 'conjugate'")
    return involute_edge(setup, points) if kind == "involute" else conjugate_edge(setup, points)
