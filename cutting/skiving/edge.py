"""The cutting edge: the outline of one cutter tooth in its rake plane.

Rake frame (:mod:`cutting.skiving.tooling`): the rake face in z = 0, tooth 0 centred on +x; it is the cutter's end
plane (the ideal motion of :class:`cutting.skiving.kinematics.SkivingSetup` brings tooth 0 to the mesh point at
phi0 = 0) moved along the axis by the rake face's offset, or for a stepped face turned about the tooth's radial line
to be normal to the tooth direction. The outline is the
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
  dense time grid and refined by a bracketed search (golden section), so the edge is the exact envelope (no
  union of jagged sections to smooth). Both steps treat all radii of a flank at once (numpy arrays over
  radii x instants): done radius by radius, the Python overhead made the edge cost seconds per run.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from cutting.flank import SIDES, Side, base_tangent_deviation, flank_points, flank_polar_angle
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.tooling import RakeFace

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
    teeth: each cutter tooth's own ``theta`` when the teeth's profiles differ (tooth k at k pitches along +phi from
        tooth 0; ``outline`` and ``theta`` are then their mean); () when every tooth cuts with ``outline``
    """

    kind: str
    outline: np.ndarray
    radii: np.ndarray
    theta: dict[str, np.ndarray]
    r_low: float
    r_tip: float
    teeth: tuple[dict[str, np.ndarray], ...] = ()

    def tooth_outlines(self) -> tuple[np.ndarray, ...]:
        """Each tooth's outline (as ``outline``, vertex for vertex), or () when every tooth cuts with ``outline``."""
        return tuple(edge_polygon(self.radii, theta) for theta in self.teeth)


def edge_radii(setup: SkivingSetup, points: int) -> tuple[np.ndarray, float]:
    """Radii of the flank samples: from below the deepest reach of the workpiece's tip up to the cutter tip."""
    ra0 = setup.cutter_tip_diameter / 2
    g = setup.gear
    # the workpiece's tip circle seen from the cutter axis
    reach = g.tip_radius - setup.final_centre_distance if g.internal else setup.final_centre_distance - g.tip_radius
    r_low = max(0.3 * ra0, min(reach, ra0 - setup.full_depth) - 0.3 * g.mn)
    # the rake frame's radii: a rake angle tilts the face, so the tip circle lies a little farther out in it
    r_low, r_top = setup.face_radius(r_low), setup.face_radius(ra0)
    return np.linspace(r_low, r_top, points), r_low


def involute_edge(setup: SkivingSetup, points: int = 120) -> CuttingEdge:
    """The rake-plane section of the cutter's involute-helicoid flanks (radial below its base circle)."""
    c = setup.cutter
    radii, r_low = edge_radii(setup, points)
    r_eff = np.maximum(radii, c.base_radius)
    xi = np.sqrt(r_eff**2 - c.base_radius**2) / c.base_radius
    q = setup.rake_frame
    end_plane = bool(np.array_equal(q[:, :3], np.eye(3)))
    theta = {}
    for side in SIDES:
        p = flank_points(c, side, xi, float(q[2, 3]), 0)  # the end plane at the rake face's offset
        theta[side] = np.arctan2(p[:, 1], p[:, 0])
        if not end_plane:  # from the end plane's angles, turned into the face's own axes
            theta[side] = _section(setup, radii, theta[side] - math.atan2(q[1, 0], q[0, 0]), side)
    return assemble_edge("involute", radii, theta, r_low)


def _section(setup: SkivingSetup, radii: np.ndarray, start: np.ndarray, side: Side) -> np.ndarray:
    """The polar angles at ``radii`` of the rake plane's section of the cutter's own flank ``side`` (a stepped rake
    face: a plane through the tooth's radial line), by Newton's method from ``start``."""
    c, q = setup.cutter, setup.rake_frame

    def residual(th: np.ndarray) -> np.ndarray:
        p = np.stack([radii * np.cos(th), radii * np.sin(th), np.zeros_like(th)], -1) @ q[:, :3].T + q[:, 3]
        r = np.maximum(np.hypot(p[:, 0], p[:, 1]), c.base_radius)  # radial below the base circle
        d = np.arctan2(p[:, 1], p[:, 0]) - flank_polar_angle(c, r, p[:, 2], side, 0)
        return (d + np.pi) % (2 * np.pi) - np.pi

    th = np.array(start, dtype=float)
    for _ in range(NEWTON_ITERATIONS):
        f = residual(th)
        step = f / ((residual(th + NEWTON_H) - f) / NEWTON_H)
        th -= np.clip(step, -NEWTON_MAX_STEP, NEWTON_MAX_STEP)
        if np.max(np.abs(step)) < NEWTON_TOL:
            break
    return th


def edge_polygon(radii: np.ndarray, theta: dict[str, np.ndarray]) -> np.ndarray:
    """The outline of flanks ``theta`` at ``radii``: right flank up, a tip arc of 7 points, left flank down."""
    # the cutter is external: its left flank is on the +theta side of tooth 0
    right = np.stack([radii * np.cos(theta["right"]), radii * np.sin(theta["right"])], -1)
    left = np.stack([radii * np.cos(theta["left"]), radii * np.sin(theta["left"])], -1)[::-1]
    tip_a = np.linspace(theta["right"][-1], theta["left"][-1], 9)[1:-1]
    tip = radii[-1] * np.stack([np.cos(tip_a), np.sin(tip_a)], -1)
    return np.concatenate([right, tip, left])


def assemble_edge(
    kind: str,
    radii: np.ndarray,
    theta: dict[str, np.ndarray],
    r_low: float,
    teeth: tuple[dict[str, np.ndarray], ...] = (),
) -> CuttingEdge:
    return CuttingEdge(kind, edge_polygon(radii, theta), radii, theta, r_low, float(radii[-1]), teeth)


def mate_flank(setup: SkivingSetup, side: Side) -> Side:
    """The workpiece flank that the cutter flank ``side`` generates (checked at the mesh position)."""
    c = setup.cutter
    xi = math.sqrt(max(c.reference_radius**2 - c.base_radius**2, 0.0)) / c.base_radius
    p = flank_points(c, side, xi, 0.0, 0)
    rot, t = setup.cutter_pose(np.array([0.0]))
    w = rot[0] @ p + t[0]
    e = {s: abs(float(base_tangent_deviation(setup.gear, w[None, :], s)[0])) for s in SIDES}
    return min(e, key=e.get)


#: Newton on the flank condition: iteration cap, convergence threshold on the step [rad], largest step [rad] (keeps
#: a far start from jumping to another tooth), and the finite-difference increment of the derivative [rad].
NEWTON_ITERATIONS = 30
NEWTON_TOL = 1e-14
NEWTON_MAX_STEP = 0.05
NEWTON_H = 1e-7

#: The refinement of the most restrictive instant: golden-section search to this width in the cutter angle [rad].
REFINE_XATOL = 1e-12
_INV_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


def _on_flank(
    setup: SkivingSetup,
    rho: ArrayLike,
    th_start: ArrayLike,
    mate: Side,
    phi0: ArrayLike,
    band: tuple[float, float],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """theta_t for each (radius, cutter angle): the angle at which the rake-plane point at radius rho lies exactly on
    the workpiece's nominal ``mate`` flank (Newton from ``th_start``); with a validity mask and d(deviation)/d(theta)
    there.

    ``rho``, ``th_start`` and ``phi0`` broadcast together, so one call solves a whole grid (radii (m, 1) against angles
    (1, n)) or one angle per radius ((m,) each): the arithmetic is that of one point at a time, the Python overhead is
    paid once. Each point stops when its own step is below NEWTON_TOL (the others go on), as a call for that point
    alone would.

    Valid: the contact lies strictly inside the flank's radial band and within a quarter cutter pitch of ``th_start``.
    Work is saved where the outcome is already known, without changing it:

    - a point that cannot be valid is not solved, or dropped once it cannot come back (theta and the derivative are
      nan there): the work-frame radius moves by at most rho * |d theta| (a rotation keeps lengths, the projection on
      the transverse plane does not lengthen them) and one Newton step moves theta by at most NEWTON_MAX_STEP;
    - a point whose clipped steps bounce over a jump of the deviation (nearest tooth changing) until its state repeats
      exactly would do so to the last iteration: it ends on one of the two states, chosen by the iterations left.
    """
    g = setup.gear
    phi = np.asarray(phi0, dtype=float)
    shape = np.broadcast_shapes(np.shape(rho), np.shape(th_start), phi.shape)
    rot, t = setup.rake_pose(phi.ravel())  # the pose of the rake plane once per distinct angle
    # the rake-plane point (rho cos th, rho sin th, 0) is rho cos th * ex + rho sin th * ey + t in the work frame;
    # coordinate-major (3, angles) arrays keep each coordinate contiguous
    ex, ey, t = rot[:, :, 0].T.copy(), rot[:, :, 1].T.copy(), t.T.copy()
    window = 0.25 * 2 * np.pi / setup.cutter.teeth

    # whatever theta within the window, the radius stays within rho * window of the radius at the start (computed
    # by broadcasting: no copy of the poses per point)
    rho_b, start_b = np.asarray(rho, dtype=float), np.asarray(th_start, dtype=float)
    grid = (2, *phi.shape)
    x0, y0 = _work_point(
        rho_b * np.cos(start_b),
        rho_b * np.sin(start_b),
        ex[:2].reshape(grid),
        ey[:2].reshape(grid),
        t[:2].reshape(grid),
    )
    reach = rho_b * window
    r0 = np.broadcast_to(np.hypot(x0, y0), shape)
    todo = np.flatnonzero((r0 + reach > band[0]) & (r0 - reach < band[1]))
    # the candidates: the point is cos th * u + sin th * v + c in the work frame
    rho_all = np.broadcast_to(rho_b, shape).ravel()
    pose = np.broadcast_to(np.arange(phi.size).reshape(phi.shape), shape).ravel()[todo]
    start = np.broadcast_to(start_b, shape).ravel()[todo]
    rho_todo = rho_all[todo]
    u, v, c = rho_todo * np.take(ex, pose, axis=1), rho_todo * np.take(ey, pose, axis=1), np.take(t, pose, axis=1)

    th, de = start.copy(), np.full(todo.size, np.nan)
    live = np.arange(todo.size)
    th_prev, de_prev = np.full(todo.size, np.nan), np.full(todo.size, np.nan)  # the live points' previous state
    offsets = np.array([[0.0], [NEWTON_H]])
    for it in range(NEWTON_ITERATIONS):
        if live.size == 0:
            break
        pair = th[live] + offsets
        w = _work_point(np.cos(pair), np.sin(pair), *(np.take(a, live, axis=1) for a in (u, v, c)))
        e, e_h = base_tangent_deviation(g, np.stack(w, -1), mate)
        d = (e_h - e) / NEWTON_H
        step = np.clip(
            np.where(np.abs(d) > 1e-12, e / np.where(d == 0, 1.0, d), 0.0), -NEWTON_MAX_STEP, NEWTON_MAX_STEP
        )
        now, new = th[live], th[live] - step
        th[live], de[live] = new, d
        left = NEWTON_ITERATIONS - 1 - it  # iterations still to come
        converged = np.abs(step) < NEWTON_TOL
        cycle = ~converged & (new == th_prev[live])
        back = live[cycle & (left % 2 == 1)]  # an odd number left: the cycle ends on the state before this one
        th[back], de[back] = now[cycle & (left % 2 == 1)], de_prev[back]
        # a point more than a quarter pitch from its start is invalid: give up on those that cannot come back in time
        lost = np.abs(new - start[live]) >= window + NEWTON_MAX_STEP * left + 1e-9
        th[live[lost]] = np.nan
        keep = ~(converged | cycle | lost)
        th_prev[live], de_prev[live] = now, d
        live = live[keep]

    theta, deriv, valid = np.full(rho_all.size, np.nan), np.full(rho_all.size, np.nan), np.zeros(rho_all.size, bool)
    theta[todo], deriv[todo] = th, np.where(np.isnan(th), np.nan, de)
    x, y = _work_point(np.cos(th), np.sin(th), u[:2], v[:2], c[:2])
    # contact strictly inside the flank: at its ends the "envelope" is the tooth's corner, not the flank
    r = np.hypot(x, y)
    valid[todo] = (r > band[0] + 1e-6) & (r < band[1] - 1e-6) & (np.abs(th - start) < window)
    return theta.reshape(shape), valid.reshape(shape), deriv.reshape(shape)


def _work_point(
    cos: np.ndarray, sin: np.ndarray, u: np.ndarray, v: np.ndarray, c: np.ndarray
) -> tuple[np.ndarray, ...]:
    """The work-frame coordinates cos * u + sin * v + c, one array per row of u, v, c (coordinate-major: contiguous)."""
    return tuple(cos * uk + sin * vk + ck for uk, vk, ck in zip(u, v, c, strict=True))


def _golden_section_min(
    f: Callable[[np.ndarray], np.ndarray], lo: np.ndarray, hi: np.ndarray, xatol: float
) -> tuple[np.ndarray, np.ndarray]:
    """The least value of ``f`` found on each interval [lo, hi] by golden-section search, all intervals at once.

    ``f`` maps an array of abscissae (one per interval) to the values there, so each step is one vectorized call:
    this replaces a scalar bounded search per interval, whose cost was Python overhead. The search stops when every
    bracket is narrower than ``xatol``; it returns the best value evaluated (the interior points only, like a bounded
    scalar search) and where it was found. For a unimodal f it finds the minimum; where f jumps up (a contact leaving
    the flank) it closes on the jump from the low side.
    """
    a, b = np.array(lo, dtype=float), np.array(hi, dtype=float)
    c, d = b - _INV_GOLDEN * (b - a), a + _INV_GOLDEN * (b - a)
    fc, fd = f(c), f(d)
    best = np.minimum(fc, fd)
    at = np.where(fc <= fd, c, d)
    width = float(np.max(b - a, initial=0.0))
    steps = math.ceil(math.log(xatol / width) / math.log(_INV_GOLDEN)) if width > xatol else 0
    for _ in range(steps):
        left = fc < fd  # the minimum is in [a, d]: d becomes b, c the upper interior point
        a, b = np.where(left, a, c), np.where(left, d, b)
        kept_x, kept_f = np.where(left, c, d), np.where(left, fc, fd)
        new_x = np.where(left, b - _INV_GOLDEN * (b - a), a + _INV_GOLDEN * (b - a))
        new_f = f(new_x)
        c, fc = np.where(left, new_x, kept_x), np.where(left, new_f, kept_f)
        d, fd = np.where(left, kept_x, new_x), np.where(left, kept_f, new_f)
        at = np.where(new_f < best, new_x, at)
        best = np.minimum(best, new_f)
    return best, at


def envelope_bound(
    setup: SkivingSetup,
    radii: np.ndarray,
    th0: np.ndarray,
    mate: Side,
    sgn: float,
    phi_grid: np.ndarray,
    band: tuple[float, float],
    xatol: float = REFINE_XATOL,
) -> tuple[np.ndarray, np.ndarray]:
    """sgn * theta*(rho) for each radius: the most restrictive theta_t over the tooth passage (+inf where none bounds),
    and the cutter angle at which it binds (nan where none).

    ``th0``: the involute edge at ``radii`` (the Newton start); ``sgn``: the direction in which the cutter tooth grows
    thicker. The extreme is taken on ``phi_grid`` for all radii at once and refined between the grid's neighbours of
    each radius' most restrictive instant by one golden-section search over all radii.
    """
    th_t, valid, de = _on_flank(setup, radii[:, None], th0[:, None], mate, phi_grid[None, :], band)
    # the deviation is > 0 on the space side of the flank: where it falls as the cutter tooth thickens (theta moving
    # by +sgn), the point moves into the tooth: theta_t bounds the edge there
    active = valid & (sgn * de < 0)
    cand = np.where(active, sgn * th_t, np.inf)
    k = np.argmin(cand, axis=1)  # the most restrictive instant on the grid, refined in between
    grid_best = cand[np.arange(len(radii)), k]
    out, at = np.full(len(radii), np.inf), np.full(len(radii), np.nan)
    has = np.isfinite(grid_best)
    if not has.any():
        return out, at
    rho, start = radii[has], th0[has]

    def bound(phi: np.ndarray) -> np.ndarray:
        th, ok, d = _on_flank(setup, rho, start, mate, phi, band)
        return np.where(ok & (sgn * d < 0), sgn * th, 1e9)  # finite: keeps the comparisons ordered

    lo = phi_grid[np.maximum(k[has] - 1, 0)]
    hi = phi_grid[np.minimum(k[has] + 1, len(phi_grid) - 1)]
    refined, at_refined = _golden_section_min(bound, lo, hi, xatol)
    out[has] = np.minimum(grid_best[has], refined)  # 1e9 where none was found
    at[has] = np.where(refined <= grid_best[has], at_refined, phi_grid[k[has]])
    return out, at


#: A bound whose contact lies this close to the workpiece's tip circle [mm] comes from its tip corner, not its flank.
CORNER = 1e-4


def contact_radius(setup: SkivingSetup, radii: np.ndarray, theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """The work-frame radius of the rake-face points (radii, theta) at cutter angles phi (nan where phi is)."""
    out = np.full(len(radii), np.nan)
    ok = np.isfinite(phi) & np.isfinite(theta)
    if ok.any():
        rot, t = setup.rake_pose(phi[ok])
        p = np.stack([radii[ok] * np.cos(theta[ok]), radii[ok] * np.sin(theta[ok]), np.zeros(ok.sum())], -1)
        w = np.einsum("nij,nj->ni", rot, p) + t
        out[ok] = np.hypot(w[:, 0], w[:, 1])
    return out


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
        sgn = 1.0 if side == "left" else -1.0  # the direction in which the cutter tooth grows thicker
        th0 = inv_edge.theta[side]
        bound, at = envelope_bound(setup, radii, th0, mate_flank(setup, side), sgn, phi_grid, band)
        out = np.where(np.isfinite(bound), sgn * bound, th0)  # no instant bounds the edge: keep the involute
        # Below the generating zone the "envelope" comes from the workpiece's tip corner: keep the section there (it
        # never meets the flank). A plane rake face through the axes' crossing departs from the section by a few
        # micrometres where it generates; an offset or stepped face by tens all along: there the corner is found
        # by where the bound touches the workpiece.
        departure = np.abs(out - th0) * radii
        if setup.rake.kind == RakeFace.kind and setup.rake.offset == 0.0:
            corner = departure > CONJUGATE_MAX_DEPARTURE
        else:
            r = contact_radius(setup, radii, out, at)
            corner = np.abs(r - g.tip_radius) < CORNER
        out = np.where(corner, th0, out)
        # then make sure no point enters the whole nominal tooth (involute and tip circle)
        theta[side] = _clear_tip_corners(setup, radii, out, th0, phi_grid)
    return assemble_edge("conjugate", radii, theta, inv_edge.r_low)


def tooth_intrusion(setup: SkivingSetup, pts: np.ndarray, phi_grid: np.ndarray) -> np.ndarray:
    """Deepest intrusion [mm] of each rake-plane point (m, 2), or rake-frame point (m, 3), into the nominal teeth over
    the cutter angles.

    Material: inside a tooth's involute outline between the form circle and the tip circle.
    """
    g = setup.gear
    rot, t = setup.rake_pose(phi_grid)
    q = pts if pts.shape[1] == 3 else np.column_stack([pts, np.zeros(len(pts))])
    w = np.matmul(rot, q.T).transpose(0, 2, 1) + t[:, None, :]  # (angles, points, 3); a batched matmul: einsum is slow
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
    """The job's cutting edge (kept: the conjugate edge's envelope takes a fifth of a second, and a run needs it in
    several stages; the edge is immutable)."""
    if kind not in EDGE_KINDS:
        raise ValueError(f"cutter.edge = {kind!r}: unknown edge; use 'involute' or 'conjugate'")
    if setup.rake.regrind:  # the tool as reground: the relieved teeth cut deeper, as designed when new
        return reground_edge(setup, make_edge(setup.new_tool(), kind, points), points)
    edge = involute_edge(setup, points) if kind == "involute" else conjugate_edge(setup, points)
    if setup.cutter_errors.profile:  # the cutter as made: its profile deviations on the edge as designed
        from cutting.skiving.cutter_profile import deviated_edge

        edge = deviated_edge(setup, edge)
    return edge


def reground_edge(setup: SkivingSetup, new_edge: CuttingEdge, points: int = 120) -> CuttingEdge:
    """The edge of the reground tool of ``setup``: the rake face's section of its relieved teeth. The teeth were
    ground with the new tool's design: its edge's departure from its involute section (the envelope's correction,
    and any profile deviation), a base-tangent deviation along the cutter's roll length L0, is on the relieved flank
    at every depth; the reground section is the reground cutter's involute section plus that departure at the same
    L0 (docs/cutter.md, "Regrind")."""
    new = setup.new_tool()
    rb = setup.cutter.base_radius  # the relief changes the profile shift, not the base circle
    inv_new = involute_edge(new, points)
    inv = involute_edge(setup, points)

    def roll(radii: np.ndarray) -> np.ndarray:
        return np.sqrt(np.maximum(radii**2 - rb**2, 0.0))

    def reground(ground: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        theta = {}
        for side in SIDES:
            departure = (ground[side] - inv_new.theta[side]) * rb  # base-tangent, signed as the angle
            theta[side] = inv.theta[side] + np.interp(roll(inv.radii), roll(new_edge.radii), departure) / rb
        return theta

    teeth = tuple(reground(t) for t in new_edge.teeth)  # each tooth keeps its own ground departure
    return assemble_edge(new_edge.kind, inv.radii, reground(new_edge.theta), inv.r_low, teeth)
