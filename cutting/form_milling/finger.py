"""The finger mill of the copying method (seed 003: "a specially profiled disc or finger mill").

A finger mill is an end mill whose axis is normal to the gear axis, along the tooth space's radial symmetry line
y_s, its tip towards the root: an external gear's space is milled from outside (axis +y_s into the mill), an internal
gear's from inside the ring (axis -y_s), which no disc mill reaches. :class:`FingerMill` is the mill (fitted to the
space by :func:`fit_finger_mill`), :func:`finger_pass` a pass, :func:`plan_finger` the seed's steps for its path on a
design; the exact swept surface (:class:`cutting.form_milling.sweep.MilledGear`) and the manifold removal
(:func:`cutting.form_milling.removal.cut_gear`) take it as they take the disc mill. What it cuts:
docs/form-milling.md, "The finger mill".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import ClassVar

import numpy as np

from cutting.flank import SIDES, Side
from cutting.form_milling.copying_path import (
    PATH_TOLERANCE,
    ContactCurves,
    FlankPath,
    accuracy_check,
    axial_sections,
    contact_curves,
    correction_from_residual,
    corrections,
    mean_section,
    path_points,
    pitch_point,
)
from cutting.form_milling.helical import contact_profile
from cutting.form_milling.mill import (
    TIP_MARGIN,
    BezierChain,
    designed_section,
    flank_sign,
    from_space,
    section_rolls,
)
from cutting.form_milling.sweep import MillPassPoses
from cutting.gear import Gear, form_roll_length
from cutting.modification import Modification, roll

#: ideal poses along a straight pass every this much feed [mm] (the margin is refined between them)
POSE_STEP = 0.1
#: a mill wider than the space's section by more than this [mm] overcuts a flank: refused
THICK_TOLERANCE = 1e-4
#: the smallest tip radius [mm, in units of the module] a finger mill is given (a thinner tip would break)
MIN_TIP_RADIUS = 0.05


def finger_rolls(gear: Gear, points: int = 81) -> np.ndarray:
    """Roll lengths [mm] of the section the finger copies, from the root side to TIP_MARGIN mn beyond the tip circle
    (the tip circle's own among them). External: :func:`cutting.form_milling.mill.section_rolls` (from the form
    circle). Internal: from the root circle (an internal flank is involute down to it) inwards, to the tip circle
    less TIP_MARGIN mn (no nearer the base circle than 0.1 % of its radius)."""
    if not gear.internal:
        return section_rolls(gear, points)
    top = max(gear.tip_radius - TIP_MARGIN * gear.mn, 1.001 * gear.base_radius)
    L = np.geomspace(roll(gear, gear.root_diameter_value), roll(gear, 2 * top), points)
    tip = roll(gear, gear.tip_diameter_value)
    return np.insert(L, int(np.searchsorted(-L, -tip)), tip)


def tip_point(gear: Gear, L: np.ndarray) -> int:
    """Index of the tip circle's roll length in :func:`finger_rolls`."""
    return int(np.argmin(np.abs(L - roll(gear, gear.tip_diameter_value))))


def path_point(gear: Gear, side: Side, clearance: float) -> tuple[float, float]:
    """The nominal path point (x_tr, y_tr) [mm] of the ``side`` pass: the tip centre on the root circle, c/2 off the
    symmetry line towards that flank."""
    return flank_sign(gear, side) * clearance / 2, gear.root_radius


def axis_in_space(gear: Gear) -> np.ndarray:
    """The finger's axis (from its tip into it) in the space frame: +y_s external, -y_s internal."""
    return np.array([0.0, float(gear.sense), 0.0])


def finger_section(
    gear: Gear,
    design: Modification | None,
    side: Side,
    clearance: float,
    L: np.ndarray,
    z: float | np.ndarray = 0.0,
    space: int = 0,
) -> np.ndarray:
    """The designed ``side`` flank's section at roll lengths ``L`` and face position ``z`` in the finger's axial
    coordinates of the nominal ``side`` pass: (n, 2) of v (from the tip along the axis) and rho (from the axis) [mm]."""
    p = designed_section(gear, design, side, L, z, space)
    x0, y0 = path_point(gear, side, clearance)
    return np.stack([gear.sense * (p[..., 1] - y0), np.abs(p[..., 0] - x0)], axis=-1)


def finger_profile(
    gear: Gear,
    design: Modification | None,
    side: Side,
    clearance: float,
    L: np.ndarray,
    z: float = 0.0,
) -> np.ndarray:
    """(n, 2) (v, rho) [mm] of the ``side`` flank a finger on the nominal ``side`` pass must have to cut it: on a spur
    gear its (designed) section (:func:`finger_section`); on a helical gear the envelope of the nominal helicoid
    under the space's screw motion, where the flank's normal meets the finger's axis
    (:func:`cutting.form_milling.helical.contact_profile`, the contact up to rho tan(beta) off the mill's centre
    plane; NaN-free or refused)."""
    if gear.helix_angle == 0.0:
        return finger_section(gear, design, side, clearance, L, z)
    x0, y0 = path_point(gear, side, clearance)
    u, rho, zc = contact_profile(gear, side, L, np.array([x0, y0, 0.0]), axis_in_space(gear))
    if not np.all(np.isfinite(zc)):
        raise ValueError(
            f"the {side} flank has profile points whose normal never meets the finger's axis (roll lengths "
            f"{np.round(L[~np.isfinite(zc)], 3).tolist()} mm): no finger mill on the symmetry line cuts them"
        )
    return np.column_stack([u, rho])


@dataclass(frozen=True, eq=False)
class FingerMill:
    """The profiled finger mill: ``flank`` the chain (v, rho) [mm] of its radius along its axis from the lowest fitted
    point up (v from the tip), ``teeth`` its flutes; below the chain's first point the radius runs on along its
    end tangent down to the tip (v = 0).

    A solid of revolution: at the distance v from its tip along its axis its radius is rho(v), a chain of cubic
    Bezier segments (seed eq. 9, :meth:`cutting.form_milling.mill.BezierChain.fit`) fitted to the space's section,
    from the root (the tip, v = 0) to TIP_MARGIN mn beyond the tip circle; below the lowest section point (an
    external gear's form circle) the chain runs on to the tip, whose end is flat. It answers
    :class:`cutting.form_milling.mill.Mill` (its pose's centre is the tip centre, its axial table
    v -> rho(v) = R - h(v), R its largest radius). An internal gear's tooth space narrows towards its root (it is an
    external gear's tooth turned inside out): its finger mill is thinnest at its tip. On a helical gear its radius is
    the envelope of the helicoid (the flank's normal meets its axis, as the set-over disc's in
    :mod:`cutting.form_milling.helical`; :func:`finger_profile`)."""

    flank: BezierChain
    teeth: int = 4
    min_tip_radius: float = 0.0
    #: fed along a helix (a helical space's screw motion) it touches a point up to rho tan(beta) off its centre
    #: plane: the exact surface scans the pass that far (:class:`cutting.form_milling.mill.Mill`)
    scan_slope: ClassVar[float] = 1.0

    @cached_property
    def table(self) -> tuple[np.ndarray, np.ndarray]:
        """The radius as a dense table: v [mm] from the tip (increasing) and rho(v) [mm]."""
        pts = self.flank.dense()
        if np.any(np.diff(pts[:, 0]) <= 0):
            worst = float(pts[1:, 0][np.argmin(np.diff(pts[:, 0]))])
            raise ValueError(
                "the finger mill's profile is not single-valued along its axis (it turns back near "
                f"v = {worst:.3f} mm): a solid of revolution cannot copy that section; fit it to a space whose "
                "section rises monotonically from the root (no undercut), or use the disc mill"
            )
        if pts[0, 0] < -1e-9:
            raise ValueError(f"the finger mill's profile starts {-pts[0, 0]:.4f} mm below its tip: start it at v >= 0")
        if pts[0, 0] > 1e-12:  # along the end tangent down to the tip
            t = pts[1] - pts[0]
            pts = np.vstack([pts[0] - t * pts[0, 0] / t[0], pts])
        if not pts[0, 1] > self.min_tip_radius:
            raise ValueError(
                f"the finger mill cannot reach the root: its radius at the tip would be {pts[0, 1]:+.4f} mm (least "
                f"{self.min_tip_radius:.3f} mm; its flanks' tangents meet above the root): reduce the clearance, or "
                "move the root circle towards the tip (root_diameter)"
            )
        return pts[:, 0], pts[:, 1]

    @cached_property
    def radius(self) -> float:
        """Its largest radius [mm]."""
        return float(np.max(self.table[1]))

    @cached_property
    def profile(self) -> tuple[np.ndarray, np.ndarray]:
        """The axial table of :class:`cutting.form_milling.mill.Mill`: v [mm] and h = R - rho(v)."""
        v, rho = self.table
        return v, self.radius - rho

    @property
    def width(self) -> float:
        """Its cutting length along the axis [mm]."""
        return float(self.table[0][-1])

    @property
    def tip_radius(self) -> float:
        return float(self.table[1][0])

    @property
    def tangential_span(self) -> tuple[float, float]:
        """Its axis is along the space: it reaches +-R across it."""
        return -self.radius, self.radius

    def reach_angle(self, depth: float) -> float:
        """All of each circle reaches the blank (its axis points at the gear axis)."""
        return math.pi

    def rho(self, v: np.ndarray) -> np.ndarray:
        """Radius [mm] at ``v`` from the tip; NaN beyond its cutting length."""
        vv, rr = self.table
        v = np.asarray(v, dtype=float)
        return np.where((v >= vv[0]) & (v <= vv[-1]), np.interp(v, vv, rr), np.nan)

    def summary(self) -> dict:
        """The mill for measurement.json: tip and largest diameter, length and the radius's Bezier control points."""
        return {
            "type": "finger",
            "tip_diameter_mm": round(2 * self.tip_radius, 5),
            "diameter_mm": round(2 * self.radius, 5),
            "length_mm": round(self.width, 4),
            "teeth": self.teeth,
            "radius_bezier": np.round(self.flank.control, 6).tolist(),
        }


def fit_finger_mill(
    gear: Gear,
    clearance: float = 0.2,
    design: Modification | None = None,
    teeth: int = 4,
    points: int = 81,
    z: float = 0.0,
) -> FingerMill:
    """The finger mill whose radius copies the (designed) space's section at face position ``z``, c/2 in from each
    flank (eq. 9: the Bezier chain fitted to the mean of the two flanks' (v, rho), the tip circle's point a joint).
    On a helical gear the radius is the envelope of the helicoid instead (:func:`finger_profile`; the nominal space
    only). Refuses a negative clearance and a mill whose tip would be thinner than MIN_TIP_RADIUS mn."""
    if not clearance >= 0.0:
        raise ValueError(
            f"clearance {clearance} mm: a finger mill wider than the space overcuts the opposite flank; give c >= 0"
        )
    if gear.helix_angle != 0.0 and design is not None:
        raise ValueError(
            "a helical gear's finger mill is the envelope of its nominal helicoid: fit it without a design (the "
            "design is the path's: plan_finger)"
        )
    L = finger_rolls(gear, points)
    sec = np.mean([finger_profile(gear, design, s, clearance, L, z) for s in SIDES], axis=0)
    below = int(np.count_nonzero(sec[:, 0] < 0.0))  # an involute that starts below the root circle: from the root
    sec = sec[below:]
    mill = FingerMill(BezierChain.fit(sec, through=(tip_point(gear, L) - below,)), teeth, MIN_TIP_RADIUS * gear.mn)
    _ = mill.table  # its checks now
    return mill


def check_finger(gear: Gear, mill: FingerMill, clearance: float) -> None:
    """Raise ValueError when ``mill`` with passes c/2 off the symmetry line would overcut the nominal space (too thick
    for it: wider than the flank's section by more than THICK_TOLERANCE) or not reach from the root out beyond the
    tip circle."""
    L = finger_rolls(gear)
    top = tip_point(gear, L)
    for side in SIDES:
        v, rho = finger_profile(gear, None, side, clearance, L).T
        if mill.width < v[top]:
            raise ValueError(
                f"the finger mill's cutting length {mill.width:.3f} mm does not reach from the root to the tip circle "
                f"({v[top]:.3f} mm): it cannot cut the whole tooth depth; use a longer mill"
            )
        inside = v <= mill.width
        over = mill.rho(v[inside]) - rho[inside]
        k = int(np.argmax(over))
        if over[k] > THICK_TOLERANCE:
            raise ValueError(
                f"the finger mill is too thick for the space: {over[k] * 1e3:.1f} um wider than the {side} flank's "
                f"section {v[inside][k]:.3f} mm above its tip with a clearance of {clearance} mm; use a larger "
                "clearance or the mill fitted to this gear (fit_finger_mill)"
            )


def finger_pass(
    gear: Gear,
    mill: FingerMill,
    space: int,
    side: Side,
    z: np.ndarray,
    clearance: float = 0.2,
    xy: np.ndarray | None = None,
) -> MillPassPoses:
    """The poses (gear frame) of the ``side`` pass of tooth space ``space`` at face positions ``z`` [mm]: the tip
    centre on the path point (default the nominal one, :func:`path_point`; else ``xy`` (n, 2) in the space frame),
    the axis along the space's symmetry line into the mill; on a helical gear in the space frame of each face
    position (the space's screw motion: turned about the gear axis by 2 pi / p_z per mm of feed).

    Fed along the face (z) the mill's transverse silhouette is x = +-rho(v) about its axis, so a mill narrower than
    the space by a clearance c (rho(v) the flank section's distance from an axis c/2 off the symmetry line) cuts one
    flank exactly with each pass, like the disc mill: the pass of the ``side`` flank runs with the axis shifted c/2
    towards that flank. Its path point (x_tr, y_tr) is the tip centre in the space frame, nominally (+-c/2, r_f)."""
    z = np.asarray(z, dtype=float)
    if xy is None:
        xy = np.broadcast_to(path_point(gear, side, clearance), (len(z), 2))
    centre = np.column_stack([xy[:, 0], xy[:, 1], z])
    axis = np.broadcast_to(axis_in_space(gear), (len(z), 3))
    return MillPassPoses(space, side, z.copy(), from_space(gear, space, centre, z), from_space(gear, space, axis, z))


def pass_length(gear: Gear, mill: FingerMill) -> float:
    """Half the feed of a pass [mm]: the mill clears both end faces by 0.5 mm."""
    return gear.face_width / 2 + mill.radius + 0.5


def finger_passes(
    gear: Gear,
    mill: FingerMill,
    clearance: float = 0.2,
    spaces: list[int] | None = None,
    step: float = POSE_STEP,
) -> list[MillPassPoses]:
    """Both straight passes (nominal path points) of every space in ``spaces`` (default all), after
    :func:`check_finger`."""
    check_finger(gear, mill, clearance)
    half = pass_length(gear, mill)
    z = np.arange(-half, half + step / 2, step)
    spaces = list(range(gear.teeth)) if spaces is None else spaces
    return [finger_pass(gear, mill, k % gear.teeth, s, z, clearance) for k in spaces for s in SIDES]


# ---- the copying plan with the finger mill (seed 003's steps on its path) ---------------------------------------
@dataclass(frozen=True, eq=False)
class FingerEdge:
    """The finger's cutting edge in a transverse section, in tool coordinates relative to the path point (x
    tangential, y along the space's symmetry line): x = s rho(sense y), s the flank's side of the axis; what the
    seed's corrections (eqs. 10-15, :func:`cutting.form_milling.copying_path.corrections`) ask of a mill."""

    gear: Gear
    mill: FingerMill

    def edge_x(self, side: Side, y: np.ndarray) -> np.ndarray:
        v, rho = self.mill.table
        return flank_sign(self.gear, side) * np.interp(self.gear.sense * np.asarray(y, dtype=float), v, rho)


@dataclass
class FingerPlan(ContactCurves):
    """The finger mill's copying plan: the mill, both passes' paths (tip centre in the space frame), the last
    corrections and the log of the iterations and accuracy checks; on a helical space the contact curves (face
    positions from the finger's axis where it touches each flank)."""

    gear: Gear
    design: Modification | None
    mill: FingerMill
    paths: dict[str, FlankPath]
    clearance: float
    k_r: dict[str, np.ndarray] = field(default_factory=dict)  # last radial corrections per path point [mm]
    k_t: dict[str, np.ndarray] = field(default_factory=dict)
    iterations: list[dict] = field(default_factory=list)
    contact: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)

    def summary(self) -> dict:
        """The plan for measurement.json: the mill, the clearance, the path points and the corrections."""
        return {
            "method": "copying (seed 003): profiled finger mill, one pass per flank",
            "mill": self.mill.summary(),
            "clearance_mm": self.clearance,
            "path_points_z_mm": np.round(self.paths["left"].z, 4).tolist(),
            "path_form": self.paths["left"].form,
            "k_r_um": {s: np.round(v * 1e3, 3).tolist() for s, v in self.k_r.items()},
            "k_t_um": {s: np.round(v * 1e3, 3).tolist() for s, v in self.k_t.items()},
            "path_bezier": {s: p.bezier() for s, p in self.paths.items()},
            "iterations": self.iterations,
        }

    def pass_poses(self, space: int, side: Side, step: float = POSE_STEP) -> MillPassPoses:
        """The ``side`` pass of ``space`` on its planned path (the mill's axis along the symmetry line)."""
        half = pass_length(self.gear, self.mill)
        z = np.arange(-half, half + step / 2, step)
        return finger_pass(self.gear, self.mill, space, side, z, self.clearance, self.paths[side].at(z))

    def all_passes(self, step: float = POSE_STEP, spaces: list[int] | None = None) -> list[MillPassPoses]:
        spaces = list(range(self.gear.teeth)) if spaces is None else spaces
        return [self.pass_poses(k % self.gear.teeth, s, step) for k in spaces for s in SIDES]

    def check_passes(self, space: int) -> list[MillPassPoses]:
        """The passes that shape the flanks of ``space``: its own and its neighbours'."""
        return self.all_passes(spaces=[space - 1, space, space + 1])


def plan_finger(
    gear: Gear,
    design: Modification | None,
    clearance: float = 0.2,
    n: int = 10,
    teeth: int = 4,
    max_iterations: int = 8,
    checks: int = 3,
    check_points: int = 11,
    path_form: str = "spline",
) -> FingerPlan:
    """Seed 003's steps with the finger mill (external or internal, spur or helical). Its axis stays along the
    space's symmetry line (it is not turned with the path: a turn would move a silhouette that lies along the face),
    so on a spur gear the profiling plane is the transverse section at each path point z_i = i b / (2n) (steps 3-6).
    Step 2 (eq. 1) moves the nominal path point (+-c/2, r_f) by the design's shift of the pitch point; steps 7-8 fit
    the finger's radius to the mean section (eqs. 7, 9) and solve k_r, k_t per section (eqs. 10-15) with its edge
    (:class:`FingerEdge`); step 9 (eq. 16) moves the path, step 10 fits it (spline or the single Bezier, eq. 17),
    11-14 repeat until it stands, and step 15 checks the exact swept surface (:class:`MilledGear`) against the
    design at every path point, correcting the path by the residual's level and slope.

    On a helical space the finger follows the screw motion and touches each flank along a curve up to rho tan(beta)
    off its axis (:func:`finger_profile`): the sections are the designed flank at those points in the finger's
    axial coordinates (as the set-over disc's, :func:`cutting.form_milling.copying_path.helical_sections`), the path
    points go on past the end faces as far as that reach, and step 15 reads each path point along its contact
    curve."""
    fit_finger_mill(gear, clearance, None if gear.helix_angle else design, teeth)  # the mill's checks, nominal space
    L = finger_rolls(gear)
    top = tip_point(gear, L)
    centres = {s: np.array([*path_point(gear, s, clearance), 0.0]) for s in SIDES}  # where finger_profile looks
    contact = contact_curves(gear, L, centres, axis_in_space(gear), "the finger on the symmetry line", "the disc mill")
    z = path_points(gear, n, max((float(np.abs(c).max()) for c in contact.values()), default=0.0))
    paths = {}
    for s in SIDES:
        shift = np.zeros((len(z), 2))
        if design is not None:  # eq. 1: the design's move of the pitch point in each section
            shift = pitch_point(gear, design, s, z) - pitch_point(gear, None, s, z)
        x0, y0 = path_point(gear, s, clearance)
        paths[s] = FlankPath(s, z, x0 + shift[:, 0], y0 + shift[:, 1], path_form)
    sections: dict[str, np.ndarray] = {}
    k_r: dict[str, np.ndarray] = {}
    k_t: dict[str, np.ndarray] = {}
    log: list[dict] = []
    for it in range(max_iterations):
        for s in SIDES:  # steps 3-6: the sections relative to the path points (x across the space, y along it)
            sections[s] = finger_sections(gear, design, paths[s], L, contact.get(s))
        mean = [mean_section(sections[s])[0] for s in SIDES]  # eq. 7; the finger's radius from both flanks' mean
        sec = np.mean([np.column_stack([gear.sense * m[:, 1], np.abs(m[:, 0])]) for m in mean], axis=0)
        mill = FingerMill(BezierChain.fit(sec, through=(top,)), teeth, MIN_TIP_RADIUS * gear.mn)
        edge = FingerEdge(gear, mill)
        moved = 0.0
        for s in SIDES:  # eqs. 10-16
            k_r[s], k_t[s] = corrections(edge, s, sections[s], 0, top)  # type: ignore[arg-type]
            dr, dt = k_r[s] - k_r[s].mean(), k_t[s] - k_t[s].mean()  # a common shift moves path and mill alike
            paths[s], change = paths[s].moved(dt, dr)
            moved = max(moved, change)
        log.append({"step": "path", "iteration": it + 1, "path_change_um": round(moved * 1e3, 5)})
        if moved < PATH_TOLERANCE:
            break
    plan = FingerPlan(gear, design, mill, paths, clearance, k_r, k_t, log, {s: (L, c) for s, c in contact.items()})
    lc = np.linspace(form_roll_length(gear), roll(gear, gear.tip_diameter_value), check_points)
    for c in range(checks):  # step 15
        worst, res = finger_check(plan, lc)
        plan.iterations.append({"step": "accuracy check", "round": c + 1, "max_residual_um": round(worst * 1e3, 4)})
        if worst < 1e-4 or c == checks - 1:
            break
        for s in SIDES:
            dx, dy = correction_from_residual(gear, s, lc, res[s])
            plan.paths[s] = plan.paths[s].moved(dx, dy)[0]
    return plan


def finger_sections(
    gear: Gear, design: Modification | None, path: FlankPath, L: np.ndarray, contact: np.ndarray | None = None
) -> np.ndarray:
    """Steps 3-6 for the finger: per path point the designed ``path.side`` flank at roll lengths ``L`` relative to
    the path point, (n, m, 2): x across the space (the flank's side of the axis: +-rho) and y along the symmetry
    line (sense v). Spur: the transverse section at z_i. Helical: the flank points the finger touches (face
    positions z_i + ``contact``) in its axial coordinates (v along the axis, rho from it)."""
    z = path.z
    xy = path.at(z)
    if contact is None:
        p = designed_section(gear, design, path.side, L[None, :], z[:, None])[..., :2]
        return p - xy[:, None, :]
    tip = np.column_stack([xy, z])
    axis = np.broadcast_to(axis_in_space(gear), tip.shape)
    v, rho = axial_sections(gear, design, path.side, z, L, contact, tip, axis)
    return np.stack([flank_sign(gear, path.side) * rho, gear.sense * v], axis=-1)


def finger_check(
    plan: FingerPlan, L: np.ndarray, space: int = 0, passes: list[MillPassPoses] | None = None
) -> tuple[float, dict[str, np.ndarray]]:
    """Step 15 with the finger (:func:`cutting.form_milling.copying_path.accuracy_check`): the flanks of ``space``
    its passes and its neighbours' cut on the planned paths (or ``passes``, e.g. those a machine made) against the
    design at every path point (along its contact curve on a helical space) and roll length ``L``."""
    return accuracy_check(plan, L, space, passes)
