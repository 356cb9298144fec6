"""The working angles and the uncut chip thickness along the skiving cutter's engaged edge (ISO 3002-2: the tool-in-use
system referred to the resultant cutting direction), for one tooth passage of each pass: what a tool designer reads
before a cut, from the setup alone (the material the passage meets is the exact swept workpiece of the passages before
it). docs/cutter.md has the geometry, the definitions and the figures of the shipped jobs.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass

import numpy as np

from cutting.errors import InputError, Problem
from cutting.flank import flank_normals, flank_points
from cutting.gear import Gear
from cutting.skiving.edge import CuttingEdge, contact_radius, envelope_bound, mate_flank
from cutting.skiving.exact_sweep import PassTable, SweptVolumes, edge_key, tooth_spread
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.passages import in_blank_envelope, passage_range, tooth_pose
from cutting.skiving.trajectory import PassMotion, ideal_passes

#: instants sampled over a passage's window
INSTANTS = 41
#: the uncut chip thickness is sought this far [mn] past the deepest pass's radial stock, at every (instant, edge
#: point) of this stride (nan between)
CHIP_REACH = 0.1
THICKNESS_STRIDE = (2, 3)
#: the flank's generating contacts counted for the clearance: off the involute's ends by this share of the module
#: (at the tip corner and the form circle the flank's normal turns into the tip's and the fillet's)
CONTACT_MARGIN = 0.02
#: an edge point generates the pass's flank where its distance from that flank's envelope [mm] follows its
#: neighbours' within this (where the edge switches from its kept section to the envelope it jumps)
TOUCH = 2e-3


@dataclass(frozen=True)
class Relief:
    """The cutter's relieved teeth behind the rake face, as a shaper cutter's: each section normal to the cutter
    axis at depth d behind the rake face is the cutter gear with its profile shift smaller by d tan(alpha_a) / mn,
    so its tip circle shrinks by d tan(alpha_a) (``clearance_angle`` alpha_a, the tip clearance) and each flank
    recedes normal to itself by d tan(alpha_a) sin(alpha_n): the side clearance normal to the flank,
    tan(alpha_s) = tan(alpha_a) sin(alpha_n) (2.06 deg at alpha_a = 6 deg, alpha_n = 20 deg)."""

    clearance_angle: float  # rad
    pressure_angle: float  # rad, the cutter's normal pressure angle

    @classmethod
    def of(cls, setup: SkivingSetup) -> Relief:
        """The relief of the setup's cutter (its rake face's clearance angle)."""
        return cls(setup.rake.clearance_angle, setup.cutter.alpha_n)

    @property
    def side_clearance(self) -> float:
        return math.atan(math.tan(self.clearance_angle) * math.sin(self.pressure_angle))


@dataclass(frozen=True)
class EdgeFrames:
    """Per point of the cutting edge (the outline less its closing chord in the body), in the tooth's rake frame: the
    point (k, 3), the edge's unit tangent, the rake face's normal towards the chip, the relieved flank's (or tip
    cone's) outward normal, the position along the edge from the right flank's lowest point [mm] and the part."""

    points: np.ndarray
    tangent: np.ndarray
    rake: np.ndarray
    flank: np.ndarray
    position: np.ndarray
    part: np.ndarray


def edge_frames(setup: SkivingSetup, edge: CuttingEdge, relief: Relief) -> EdgeFrames:
    """The edge's frames (see :class:`EdgeFrames`); the body behind the rake face on :attr:`SkivingSetup.body_side`."""
    m = len(edge.radii)
    n = len(edge.outline)
    part = np.array(["right"] * m + ["tip"] * (n - 2 * m) + ["left"] * m)
    pts = np.column_stack([edge.outline, np.zeros(n)])
    tangent = np.gradient(pts, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    position = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    q = setup.rake_frame  # rake frame -> cutter frame
    into_body = body_direction(setup)
    rake = np.broadcast_to(rake_normal(setup), pts.shape)
    c = setup.cutter
    cut = pts @ q[:, :3].T + q[:, 3]  # the points in the cutter frame
    r = np.hypot(cut[:, 0], cut[:, 1])
    flank = np.empty_like(pts)
    k = math.tan(relief.clearance_angle)
    for s in ("right", "left"):
        sel = part == s
        xi = np.sqrt(np.maximum(r[sel] ** 2 - c.base_radius**2, 1e-12)) / c.base_radius
        normal = flank_normals(c, s, xi, cut[sel, 2], 0)
        # the helicoid's normal at the point's own polar angle (the conjugate edge is micrometres off the helicoid)
        nominal = flank_points(c, s, xi, cut[sel, 2], 0)
        turn = np.arctan2(cut[sel, 1], cut[sel, 0]) - np.arctan2(nominal[:, 1], nominal[:, 0])
        cs, sn = np.cos(turn), np.sin(turn)
        normal = np.column_stack(
            [cs * normal[:, 0] - sn * normal[:, 1], sn * normal[:, 0] + cs * normal[:, 1], normal[:, 2]]
        )
        flank[sel] = normal @ q[:, :3] + k * math.sin(relief.pressure_angle) * into_body
    tip = part == "tip"
    radial = np.column_stack([cut[tip, 0] / r[tip], cut[tip, 1] / r[tip], np.zeros(tip.sum())])
    flank[tip] = radial @ q[:, :3] + k * into_body
    flank /= np.linalg.norm(flank, axis=1, keepdims=True)
    return EdgeFrames(pts, tangent, np.ascontiguousarray(rake), flank, position, part)


def body_direction(setup: SkivingSetup) -> np.ndarray:
    """The direction from the rake face into the cutter's body, in the rake frame (along the cutter axis)."""
    return setup.body_side * (setup.rake_frame[:, :3].T @ np.array([0.0, 0.0, 1.0]))


def rake_normal(setup: SkivingSetup) -> np.ndarray:
    """The rake face's unit normal towards the chip, in the rake frame (+-z)."""
    return np.array([0.0, 0.0, 1.0 if rake_faces_chip(body_direction(setup)) else -1.0])


def rake_faces_chip(into_body: np.ndarray) -> bool:
    """Whether the rake frame's +z faces the chip: the body lies on its -z side."""
    return float(into_body[2]) < 0


@dataclass(frozen=True)
class PassageAngles:
    """One passage's working angles at every (instant, edge point) [rad], the cutting speed [m/min], whether the edge
    point cuts (it lies in the material the passages before left) and the uncut chip thickness there [mm] (nan
    where it does not cut)."""

    pass_index: int
    passage: int
    t: np.ndarray  # (n,) [s] of the pass's motion
    generating: np.ndarray  # (n,) the cutter's turn from the mesh [rad]
    position: np.ndarray  # (k,) along the edge [mm]
    part: np.ndarray  # (k,)
    rake: np.ndarray  # (n, k) working normal rake gamma_ne
    clearance: np.ndarray  # (n, k) working normal clearance alpha_ne
    wedge: np.ndarray  # (n, k) wedge angle in the working normal plane beta_ne
    inclination: np.ndarray  # (n, k) working cutting edge inclination lambda_se
    speed: np.ndarray  # (n, k) m/min
    cutting: np.ndarray  # (n, k) bool
    thickness: np.ndarray  # (n, k) mm
    #: (k,) the working normal clearance of each edge point where it generates the pass's flank (and the tip's
    #: middle where it generates the root): the clearance face passes against the generated surface there [rad];
    #: nan where the point generates none (:func:`contact_clearance`)
    generating_clearance: np.ndarray

    def summary(self) -> dict:
        """measurement.json's entry: the extremes over the cutting edge (deg, mm, m/min) and where the least
        clearance is."""
        on = self.cutting
        nan = float("nan")
        if not on.any():  # the passage meets no material: the same entry, no figures
            names = ("rake_min_deg", "rake_max_deg", "clearance_min_deg", "clearance_min_engaged_deg")
            names += ("inclination_max_deg", "chip_thickness_max_mm", "cutting_speed_max_m_min")
            return {"pass": self.pass_index + 1, **dict.fromkeys(names, nan), "clearance_min_at": None}
        deg = np.degrees
        clearance = np.where(on, self.clearance, np.inf)
        i, j = np.unravel_index(int(np.argmin(clearance)), clearance.shape)
        gen = self.generating_clearance
        g = int(np.nanargmin(gen)) if np.isfinite(gen).any() else -1
        return {
            "pass": self.pass_index + 1,
            "rake_min_deg": float(deg(self.rake[on].min())),
            "rake_max_deg": float(deg(self.rake[on].max())),
            "clearance_min_deg": float(deg(gen[g])) if g >= 0 else nan,
            "clearance_min_engaged_deg": float(deg(self.clearance[i, j])),
            "inclination_max_deg": float(deg(np.abs(self.inclination[on]).max())),
            "chip_thickness_max_mm": float(np.nanmax(np.where(on, self.thickness, nan))),
            "cutting_speed_max_m_min": float(self.speed[on].max()),
            "clearance_min_at": {"edge": str(self.part[g]), "edge_position_mm": float(self.position[g])}
            if g >= 0
            else None,
            "clearance_min_engaged_at": {
                "edge": str(self.part[j]),
                "edge_position_mm": float(self.position[j]),
                "generating_deg": float(deg(self.generating[i])),
            },
        }


def working_angles(frames: EdgeFrames, rot: np.ndarray, velocity: np.ndarray) -> tuple[np.ndarray, ...]:
    """The working angles at every (instant, edge point) from the rake frame's rotations (n, 3, 3) and the edge
    points' velocities relative to the work (n, k, 3) [mm/s].

    In the working normal plane P_ne (normal to the edge) at an edge point with resultant cutting velocity v: e1 is
    v's direction in P_ne, e2 the direction in P_ne normal to e1 on the side away from the flank. With the rake face's
    normal n_g and the flank's n_a projected into P_ne:

        gamma_ne = atan2(n_g . e2, n_g . e1)    (0: the rake face normal to v; positive: it leans back from the cut)
        alpha_ne = atan2(-n_a . e1, -n_a . e2)  (positive: the flank falls away from the surface it generates)
        beta_ne  = pi - angle(n_g, n_a)         (the wedge), so that gamma_ne + alpha_ne + beta_ne = 90 deg
        lambda_se = asin(t . v / |v|)           (t the edge's tangent)

    Returns (rake, clearance, wedge, inclination, speed [mm/s]) arrays (n, k).
    """
    t = np.einsum("nij,kj->nki", rot, frames.tangent)
    n_g = np.einsum("nij,kj->nki", rot, frames.rake)
    n_a = np.einsum("nij,kj->nki", rot, frames.flank)
    return angles_of(t, n_g, n_a, velocity)


def angles_of(t: np.ndarray, n_g: np.ndarray, n_a: np.ndarray, velocity: np.ndarray) -> tuple[np.ndarray, ...]:
    """:func:`working_angles` from the edge tangent, the rake face's and the flank's normals and the velocity in the
    work frame (arrays (..., 3) alike)."""
    speed = np.linalg.norm(velocity, axis=-1)
    v = velocity / speed[..., None]

    def in_plane(u: np.ndarray) -> np.ndarray:
        out = u - np.sum(u * t, axis=-1, keepdims=True) * t
        return out / np.linalg.norm(out, axis=-1, keepdims=True)

    e1 = in_plane(v)
    g, a = in_plane(n_g), in_plane(n_a)
    up = -a - np.sum(-a * e1, axis=-1, keepdims=True) * e1
    e2 = up / np.linalg.norm(up, axis=-1, keepdims=True)
    rake = np.arctan2(np.sum(g * e2, -1), np.sum(g * e1, -1))
    clearance = np.arctan2(np.sum(-a * e1, -1), np.sum(-a * e2, -1))
    wedge = np.pi - np.arccos(np.clip(np.sum(g * a, -1), -1.0, 1.0))
    inclination = np.arcsin(np.clip(np.sum(t * v, -1), -1.0, 1.0))
    return rake, clearance, wedge, inclination, speed


def chip_thickness(before, own: SweptVolumes, points: np.ndarray, directions: np.ndarray, reach: float) -> np.ndarray:
    """The uncut chip thickness [mm] at each edge point along its unit direction (into what the passage removes):
    the material the passages ``before`` left from the point on (inside the blank's envelope), as far as the passage's
    own sweep ``own`` goes on along the line (beyond, the material stays: the other side of the chip), exact on both
    (the removed intervals of the lines, :meth:`SweptVolumes.removed_intervals`); ``reach`` [mm] where both go on."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    u = np.asarray(directions, dtype=float).reshape(-1, 3)
    n = len(p)
    if not n:
        return np.zeros(0)
    material = _blank_reach(own.gear, p, u, reach)  # the blank's outside ends the material
    if isinstance(before, SweptVolumes):
        line, start, end = before.removed_intervals(p, u, reach)
        ahead = end > 0  # and the first removed part in front of the point
        np.minimum.at(material, line[ahead], np.maximum(start[ahead], 0.0))
    line, start, end = own.removed_intervals(p, u, reach)
    return np.minimum(material, _covered_from_zero(n, line, start, end))


def _covered_from_zero(n: int, line: np.ndarray, start: np.ndarray, end: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """For each of n lines, how far from d = 0 the union of its intervals [start, end] covers without a gap."""
    out = np.zeros(n)
    order = np.lexsort((start, line))
    line, start, end = line[order], start[order], end[order]
    for i, s, e in zip(line, start, end, strict=True):  # sorted by line, then start: one sweep
        if s <= out[i] + tol and e > out[i]:
            out[i] = e
    return out


def _blank_reach(gear: Gear, p: np.ndarray, u: np.ndarray, reach: float) -> np.ndarray:
    """How far along each unit line from its point (inside the blank's envelope) the envelope goes on, exactly: the
    first crossing of an end face (|z| = b / 2) or the tip cylinder (a ring gear: the bore), at most ``reach``."""
    half = gear.face_width / 2
    with np.errstate(divide="ignore", invalid="ignore"):
        face = np.where(
            u[:, 2] > 0, (half - p[:, 2]) / u[:, 2], np.where(u[:, 2] < 0, (-half - p[:, 2]) / u[:, 2], np.inf)
        )
        a = u[:, 0] ** 2 + u[:, 1] ** 2
        b = p[:, 0] * u[:, 0] + p[:, 1] * u[:, 1]
        c = p[:, 0] ** 2 + p[:, 1] ** 2 - gear.tip_radius**2
        disc = b * b - a * c
        root = np.sqrt(np.maximum(disc, 0.0))
        if gear.internal:  # outside the bore: it leaves where it enters the bore, if it heads into it
            radial = np.where((disc > 0) & (b < 0) & (a > 0), (-b - root) / a, np.inf)
        else:  # inside the tip cylinder: it leaves through it unless it runs along the axis
            radial = np.where(a > 0, (-b + root) / a, np.inf)
    return np.clip(np.minimum(face, radial), 0.0, reach)


class _Blank:
    """The material before the first passage of a job: the blank alone."""

    def __init__(self, gear: Gear):
        self.gear = gear

    def inside(self, q: np.ndarray) -> np.ndarray:
        return in_blank_envelope(self.gear, q)


def nearby_passages(
    setup: SkivingSetup, edge: CuttingEdge, motion: PassMotion, ms: np.ndarray, centre, radius: float, s_here: float
) -> PassTable | None:
    """The passages ``ms`` of ``motion`` whose sweep comes within ``radius`` [mm] of ``centre`` (first those whose
    carriage position is near ``s_here`` [mm], then by their bounding balls); None when none does."""
    pitch = 2 * math.pi / setup.cutter.teeth
    half, _, _ = passage_range(motion, edge)
    if not len(ms):
        return None
    s_at = np.asarray(motion.carriage(np.asarray(motion.time_at_angle(ms * pitch), dtype=float)))
    ms = ms[np.abs(s_at - s_here) <= radius + 2 * setup.engagement_half_length(motion.centre_distance)]
    if not len(ms):
        return None
    t0 = np.asarray(motion.time_at_angle(ms * pitch - half), dtype=float)
    t1 = np.asarray(motion.time_at_angle(ms * pitch + half), dtype=float)
    tb = PassTable.from_windows(
        motion, t0, t1, setup.passage_frames(ms), edge.outline, ms, setup.blank_frame, tooth_spread(edge)
    )
    gap = np.linalg.norm(tb.ball_centre - np.asarray(centre), axis=-1) - tb.ball_radius
    near = (gap <= radius).any(axis=1)
    return tb.take(np.flatnonzero(near)) if near.any() else None


def material_before(
    setup: SkivingSetup, edge: CuttingEdge, motions: list[PassMotion], pass_index: int, m: int, centre, radius
):
    """The workpiece that passage ``m`` of pass ``pass_index`` meets, as far as it lies within ``radius`` [mm] of
    ``centre``: the blank less the exact swept volumes of the passages before it that come that near (the earlier
    passes' and this pass's earlier visits to the same space: each a few feeds apart along the axis)."""
    motion = motions[pass_index]
    s_here = float(motion.carriage(motion.time_at_angle(m * 2 * math.pi / setup.cutter.teeth)))
    tables = []
    for i in range(pass_index + 1):
        _, first, last = passage_range(motions[i], edge)
        ms = np.arange(first, (last if i < pass_index else m - 1) + 1)
        tb = nearby_passages(setup, edge, motions[i], ms, centre, radius, s_here)
        if tb is not None:
            tables.append(tb)
    if not tables:
        return _Blank(setup.gear)
    return SweptVolumes(setup.gear, edge, [], tables=tables)


def own_sweep(setup: SkivingSetup, edge: CuttingEdge, motion: PassMotion, m: int) -> SweptVolumes:
    """The exact swept volume of passage ``m`` of ``motion`` alone."""
    pitch = 2 * math.pi / setup.cutter.teeth
    half, _, _ = passage_range(motion, edge)
    t0, t1 = (np.array([motion.time_at_angle(m * pitch + k * half)], dtype=float) for k in (-1, 1))
    ms = np.array([m])
    tb = PassTable.from_windows(
        motion, t0, t1, setup.passage_frames(ms), edge.outline, ms, setup.blank_frame, tooth_spread(edge)
    )
    return SweptVolumes(setup.gear, edge, [], tables=[tb])


def passage_angles(
    setup: SkivingSetup,
    edge: CuttingEdge,
    relief: Relief,
    pass_index: int,
    motions: list[PassMotion] | None = None,
    instants: int = INSTANTS,
    stride: tuple[int, int] = THICKNESS_STRIDE,
) -> PassageAngles:
    """The working angles and chip thickness of the passage at the middle of pass ``pass_index`` (the steady state of
    the ideal motion: every passage of the pass's middle meets the same material), over its window."""
    motions = motions if motions is not None else ideal_passes(setup)
    motion = motions[pass_index]
    pitch = 2 * math.pi / setup.cutter.teeth
    m = round(motion.omega0 * motion.duration / 2 / pitch)
    half, _, _ = passage_range(motion, edge)
    t = np.linspace(motion.time_at_angle(m * pitch - half), motion.time_at_angle(m * pitch + half), instants)
    pose = tooth_pose(motion, m)
    rot, origin = pose(t)
    frames = edge_frames(setup, edge, relief)
    h = 1e-6  # s: central differences of the pose (positions ~10 mm, speeds ~1 m/s)
    (r0, o0), (r1, o1) = pose(t - h), pose(t + h)
    place = lambda r, o: np.einsum("nij,kj->nki", r, frames.points) + o[:, None, :]  # noqa: E731
    w = place(rot, origin)
    velocity = (place(r1, o1) - place(r0, o0)) / (2 * h)
    rake, clearance, wedge, inclination, speed = working_angles(frames, rot, velocity)
    reach = max(setup.passes) + CHIP_REACH * setup.gear.mn  # past the deepest pass's stock
    candidates = _Blank(setup.gear).inside(w)
    thickness = np.full(w.shape[:2], np.nan)
    cutting = np.zeros(w.shape[:2], dtype=bool)
    if candidates.any():
        pts = w[candidates]
        centre = pts.mean(axis=0)
        radius = float(np.linalg.norm(pts - centre, axis=1).max()) + reach
        material = material_before(setup, edge, motions, pass_index, m, centre, radius)
        cutting[candidates] = material.inside(pts)
        if cutting.any():
            t_hat = np.einsum("nij,kj->nki", rot, frames.tangent)
            inward = np.einsum("nij,kj->nki", rot, np.cross([0.0, 0.0, 1.0], frames.tangent))
            v_hat = velocity / np.linalg.norm(velocity, axis=-1, keepdims=True)
            n_h = np.cross(v_hat, t_hat)
            n_h *= np.sign(np.sum(n_h * inward, axis=-1, keepdims=True))
            n_h /= np.linalg.norm(n_h, axis=-1, keepdims=True)
            own = own_sweep(setup, edge, motion, m)
            # the thickness on a coarser grid than the angles: each ray is an exact line probe of both sweeps
            probe = cutting.copy()
            probe[np.arange(probe.shape[0]) % stride[0] != 0] = False
            probe[:, np.arange(probe.shape[1]) % stride[1] != 0] = False
            thickness[probe] = chip_thickness(material, own, w[probe], n_h[probe], reach)
    generating = motion.omega0 * t - m * pitch
    return PassageAngles(
        pass_index,
        m,
        t,
        generating,
        frames.position,
        frames.part,
        rake,
        clearance,
        wedge,
        inclination,
        speed * 60e-3,
        cutting,
        thickness,
        contact_clearance(setup, edge, relief, frames, pass_index),
    )


def contact_clearance(
    setup: SkivingSetup, edge: CuttingEdge, relief: Relief, frames: EdgeFrames, pass_index: int
) -> np.ndarray:
    """The working normal clearance [rad] of each edge point where it generates pass ``pass_index``'s flank
    (:func:`contact_angles`)."""
    return contact_angles(setup, edge, relief, frames, pass_index)[1]


def contact_angles(
    setup: SkivingSetup, edge: CuttingEdge, relief: Relief, frames: EdgeFrames, pass_index: int
) -> tuple[np.ndarray, np.ndarray]:
    """The working normal rake and clearance [rad] of each edge point (k,) at the instant it generates the flank of pass
    ``pass_index``: the envelope method of :mod:`cutting.skiving.edge` run for the gear that pass leaves (the
    gear's profile shifted by the pass's centre distance) gives, per edge radius, the cutter angle at which it
    touches that flank; the tip's middle point generates the root at the mesh (cutter angle 0). Nan elsewhere. The
    feed's share of the velocity (under 1 %) is left out, as in the envelope. Kept for the last few setups, edges
    and passes (a run's clearance check, its working-angle maps and the tool's summaries ask for the same)."""
    key = (setup, edge.kind, edge_key(edge), relief, frames.points.tobytes(), pass_index)
    if key not in _CONTACTS:
        _kept(_CONTACTS, key, _contact_angles(setup, edge, frames, pass_index), 4 * MAPS_KEPT)
    rake, clearance = _CONTACTS[key]
    return rake.copy(), clearance.copy()


_CONTACTS: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}


def _contact_angles(
    setup: SkivingSetup, edge: CuttingEdge, frames: EdgeFrames, pass_index: int
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`contact_angles`, computed."""
    st = pass_setup(setup, pass_index)
    g = st.gear
    rake, out = np.full(len(frames.part), np.nan), np.full(len(frames.part), np.nan)
    phi_grid = np.linspace(-0.5 * math.pi, 0.5 * math.pi, 1500)
    band = (g.tip_radius, g.root_radius) if g.internal else (g.base_radius, g.tip_radius)
    m = len(edge.radii)
    n = len(frames.part)
    omega0 = setup.tool_speed * 2 * math.pi / 60
    for side in ("left", "right"):
        sgn = 1.0 if side == "left" else -1.0
        idx = np.arange(m) if side == "right" else n - 1 - np.arange(m)  # outline order: right up, left down
        theta = np.arctan2(frames.points[idx, 1], frames.points[idx, 0])
        bound, at = envelope_bound(st, edge.radii, theta, mate_flank(st, side), sgn, phi_grid, band)
        touches = _on_trend((sgn * bound - theta) * edge.radii)
        r = contact_radius(st, edge.radii, theta, at)
        # contacts strictly on the involute: off its ends (the tip corner, the form circle) by CONTACT_MARGIN mn
        fillet = g.rack.rho_f * (1 - math.sin(g.alpha_n)) * g.mn  # the root fillet's height on the rack
        lo, hi = (
            (g.tip_radius, g.root_radius - fillet) if g.internal else (max(band[0], g.rack_form_diameter / 2), band[1])
        )
        margin = CONTACT_MARGIN * g.mn
        # ... and off the cutter's tip corner, where the flank's normal turns into the tip's
        ok = np.isfinite(at) & touches & (r > lo + margin) & (r < hi - margin) & (edge.radii < edge.r_tip - 1e-9)
        ok[1:-1] &= ok[:-2] & ok[2:]  # and their neighbours too: the edge's tangent is taken across them
        ok[[0, -1]] = False
        rake[idx[ok]], out[idx[ok]] = _angles_at(st, frames, idx[ok], at[ok], omega0)
    tip = np.flatnonzero(frames.part == "tip")
    if len(tip):
        mid = tip[len(tip) // 2 : len(tip) // 2 + 1]
        rake[mid], out[mid] = _angles_at(st, frames, mid, np.zeros(1), omega0)
    return rake, out


def _angles_at(
    st: SkivingSetup, frames: EdgeFrames, idx: np.ndarray, phi: np.ndarray, omega0: float
) -> tuple[np.ndarray, np.ndarray]:
    """The working normal rake and clearance of edge points ``idx`` at cutter angles ``phi`` (one each) of the ideal
    motion."""
    h = 1e-7
    rot, _ = st.rake_pose(phi)
    (rm, tm), (rp, tp) = st.rake_pose(phi - h), st.rake_pose(phi + h)
    p = frames.points[idx]
    velocity = (np.einsum("nij,nj->ni", rp, p) + tp - np.einsum("nij,nj->ni", rm, p) - tm) / (2 * h) * omega0
    world = [np.einsum("nij,nj->ni", rot, v[idx]) for v in (frames.tangent, frames.rake, frames.flank)]
    return angles_of(*world, velocity)[:2]


def pass_setup(setup: SkivingSetup, pass_index: int) -> SkivingSetup:
    """The setup whose finishing centre distance is pass ``pass_index``'s: the gear that pass leaves, its profile
    shifted by the centre distance's difference (its tip as the blank's, its root as the pass cuts it)."""
    a = setup.pass_centre_distances[pass_index]
    g = setup.gear
    shift = (a - setup.final_centre_distance) / g.mn * (-1.0 if g.internal else 1.0)
    ra0 = setup.cutter_tip_diameter / 2
    root = 2 * (a + ra0) if g.internal else 2 * (a - ra0)
    gear = dataclasses.replace(g, profile_shift=g.x + shift, tip_diameter=g.tip_diameter_value, root_diameter=root)
    cutter = dataclasses.replace(setup.cutter, tip_diameter=setup.cutter_tip_diameter)
    return dataclasses.replace(setup, gear=gear, cutter=cutter)


def clearance_of_passes(setup: SkivingSetup, edge: CuttingEdge) -> list[dict]:
    """Every pass's least working clearance where the edge generates its flank (:func:`contact_clearance`), with
    where on the edge: [{"pass", "clearance_min_deg", "edge", "edge_position_mm"}] (from the setup alone)."""
    relief = Relief.of(setup)
    frames = edge_frames(setup, edge, relief)
    out = []
    for k in range(len(setup.passes)):
        c = contact_clearance(setup, edge, relief, frames, k)
        j = int(np.nanargmin(c))
        out.append(
            {
                "pass": k + 1,
                "clearance_min_deg": float(np.degrees(c[j])),
                "edge": str(frames.part[j]),
                "edge_position_mm": float(frames.position[j]),
            }
        )
    return out


def check_working_clearance(setup: SkivingSetup, edge: CuttingEdge, source: str = "job") -> list[dict]:
    """:func:`clearance_of_passes`, refused (InputError) where a working clearance is <= 0: the relieved flank would
    cut the flank the edge generates (rubbing)."""
    passes = clearance_of_passes(setup, edge)
    problems = [
        Problem(
            "cutter.clearance_angle",
            round(math.degrees(setup.rake.clearance_angle), 3),
            f"pass {p['pass']}: the working clearance is {p['clearance_min_deg']:.2f} deg where the {p['edge']} edge "
            f"({p['edge_position_mm']:.2f} mm along it) generates the flank: the clearance face rubs the cut flank",
            "raise cutter.clearance_angle (the side clearance is atan(tan(alpha_a) sin(alpha_n))), or change the shaft "
            "angle (cutter.helix_angle) or cutter.rake_face_offset",
        )
        for p in passes
        if not p["clearance_min_deg"] > 0
    ]
    if problems:
        raise InputError(problems, source)
    return passes


def working_angle_maps(
    setup: SkivingSetup, edge: CuttingEdge, stride: tuple[int, int] = THICKNESS_STRIDE
) -> list[PassageAngles]:
    """:func:`passage_angles` of every pass (the middle passage of the ideal motion), with the job's relief; the chip
    thickness on every ``stride`` = (instants, edge points) of the map. Kept for the last few setups and edges (a
    setting sheet per machine structure, a cut and its run ask for the same maps; the maps are not changed)."""
    key = _maps_key(setup, edge, stride)
    if key not in _MAPS:
        motions = ideal_passes(setup)
        relief = Relief.of(setup)
        maps = [passage_angles(setup, edge, relief, k, motions, stride=stride) for k in range(len(setup.passes))]
        _kept(_MAPS, key, maps, MAPS_KEPT)
    return list(_MAPS[key])


def keep_maps(
    setup: SkivingSetup, edge: CuttingEdge, maps: list[PassageAngles], stride: tuple[int, int] = THICKNESS_STRIDE
) -> None:
    """Keep ``maps``, made elsewhere (a worker process) for ``setup`` and ``edge``, as :func:`working_angle_maps`
    would make them: it returns them from then on."""
    _kept(_MAPS, _maps_key(setup, edge, stride), list(maps), MAPS_KEPT)


def _maps_key(setup: SkivingSetup, edge: CuttingEdge, stride: tuple[int, int]) -> tuple:
    """What tells the maps apart: the setup, the edge (each tooth's own flanks too: they cut the stock), the stride."""
    return (setup, edge.kind, edge_key(edge), tuple(stride))


def _kept(store: dict, key: tuple, value, limit: int) -> None:
    """``store[key] = value``, the oldest entries dropped beyond ``limit``."""
    store[key] = value
    while len(store) > limit:
        store.pop(next(iter(store)))


#: the working-angle maps kept (a few setups' worth: each pass's map holds ~10k points x 8 fields)
MAPS_KEPT = 4
_MAPS: dict[tuple, list[PassageAngles]] = {}


def working_angle_summaries(
    setup: SkivingSetup, edge: CuttingEdge, min_clearance_deg: float = 0.0, maps: list[PassageAngles] | None = None
) -> list[dict]:
    """measurement.json's ``working_angles``: per pass the extremes of its map (:func:`working_angle_maps`, or
    ``maps`` already made), with a ``warning`` where the generating clearance is under ``min_clearance_deg``."""
    out = []
    for pa in maps if maps is not None else working_angle_maps(setup, edge):
        entry = pa.summary()
        c = entry.get("clearance_min_deg", math.nan)
        if c < min_clearance_deg:
            entry["warning"] = (
                f"working clearance {c:.2f} deg under process.min_working_clearance = {min_clearance_deg:g} deg"
            )
        out.append(entry)
    return out


def _on_trend(offset: np.ndarray, window: int = 9) -> np.ndarray:
    """Where ``offset`` (nan allowed) lies within TOUCH of the running median of its ``window`` neighbours."""
    n = len(offset)
    half = window // 2
    padded = np.pad(offset, half, constant_values=np.nan)
    views = np.lib.stride_tricks.sliding_window_view(padded, window)
    with warnings.catch_warnings():  # a window of nan alone (no bound there) has no trend: nan, and no contact
        warnings.simplefilter("ignore", RuntimeWarning)
        trend = np.nanmedian(views, axis=1) if n else offset
    with np.errstate(invalid="ignore"):
        return np.isfinite(offset) & (np.abs(offset - trend) < TOUCH)
