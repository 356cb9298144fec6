"""The path of the profiled disc mill for spatially modified teeth (seed 003, fig. 1, its 15 steps).

The copying method cuts a tooth space with a mill whose edge is the space's section: what it cannot copy from its
edge (a profile that changes from section to section) it makes by its path. Each space is cut flank by flank: the
mill is narrower than the space by a clearance c, so the *left pass* (path point shifted -c/2) makes the left flank
with the mill's left edge and the *right pass* (+c/2) the right flank. Per pass the path carries the seed's two
corrections at the path points z_i = i b / (2n): the tangential k_t (x, along the thickness) and the radial k_r (y,
along the height), i.e. a level and a slope of that flank's profile per section. :func:`plan_copying` runs the steps
(listed there) into a :class:`CopyingPlan`. What the plans achieve: docs/form-milling.md, "The mill and its path".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
from scipy.interpolate import CubicSpline

from cutting.flank import SIDES, Side, flank_normals, flank_points
from cutting.form_milling import PATH_FORMS
from cutting.form_milling.helical import contact_profile, mill_axis, set_over
from cutting.form_milling.mill import (
    BezierChain,
    DiscMill,
    designed_section,
    from_space,
    section_normals,
    section_rolls,
    space_tooth,
    tip_index,
)
from cutting.form_milling.sweep import MilledGear, MillPassPoses
from cutting.gear import Gear, form_roll_length
from cutting.modification import Modification, roll

if TYPE_CHECKING:
    from cutting.form_milling.finger import FingerPlan

#: the geometric iteration (steps 11-14) stops when no path point moves more than this [mm]
PATH_TOLERANCE = 1e-7
#: the accuracy check (step 15) is met when every checked point is within this of the design [mm]
CHECK_TOLERANCE = 1e-4
#: ideal poses along a pass every this much feed [mm]
POSE_STEP = 0.05


class SingleBezier:
    """Seed 003's eq. 17 for one coordinate: one cubic Bezier curve over the whole path,
    c(tau) = c0 (1 - tau)^3 + 3 c1 tau (1 - tau)^2 + 3 c2 tau^2 (1 - tau) + c3 tau^3, with z's control points a third
    of the way apart, so that tau = (z - z0) / (z_n - z0). The four control values are the least-squares fit to the
    path points (through all of them when they lie on a cubic). Not pinned to the end points: the path's
    corrections (eq. 16) then move the curve until they are orthogonal to it, which a pinned fit would not
    reach. Called like a CubicSpline: ``curve(z, nu)`` is the value (nu = 0) or the first derivative (nu = 1)."""

    def __init__(self, z: np.ndarray, values: np.ndarray):
        self.z0, self.span = float(z[0]), float(z[-1] - z[0])
        tau = (np.asarray(z, dtype=float) - self.z0) / self.span
        if len(tau) < 4:
            raise ValueError(f"a single cubic Bezier is fitted to at least 4 path points, got {len(tau)}")
        basis = np.stack([(1 - tau) ** 3, 3 * tau * (1 - tau) ** 2, 3 * tau**2 * (1 - tau), tau**3], axis=-1)
        self.control = np.linalg.lstsq(basis, np.asarray(values, dtype=float), rcond=None)[0]

    def __call__(self, z, nu: int = 0) -> np.ndarray:
        t = (np.asarray(z, dtype=float) - self.z0) / self.span
        c0, c1, c2, c3 = self.control
        if nu == 0:
            return c0 * (1 - t) ** 3 + 3 * c1 * t * (1 - t) ** 2 + 3 * c2 * t**2 * (1 - t) + c3 * t**3
        if nu == 1:
            d = 3 * ((c1 - c0) * (1 - t) ** 2 + 2 * (c2 - c1) * t * (1 - t) + (c3 - c2) * t**2)
            return d / self.span
        raise ValueError("SingleBezier gives the value and the first derivative")


@dataclass(frozen=True, eq=False)
class FlankPath:
    """One pass's path: the path point (x_tr, y_tr) [mm] in the space frame at the path points ``z`` (increasing),
    as a C2 cubic spline of Bezier segments (``form`` "spline") or as the seed's single cubic Bezier fitted to the
    points ("bezier", eq. 17), continued along the end tangents beyond them."""

    side: Side
    z: np.ndarray
    x: np.ndarray
    y: np.ndarray
    form: str = "spline"

    def __post_init__(self) -> None:
        if self.form not in PATH_FORMS:
            raise ValueError(f"path form {self.form!r}: use one of {PATH_FORMS}")

    @cached_property
    def _splines(self) -> tuple:
        if self.form == "bezier":
            return SingleBezier(self.z, self.x), SingleBezier(self.z, self.y)
        return CubicSpline(self.z, self.x, bc_type="not-a-knot"), CubicSpline(self.z, self.y, bc_type="not-a-knot")

    def moved(self, dx: np.ndarray, dy: np.ndarray) -> tuple[FlankPath, float]:
        """The path whose points are this path's curve at the path points moved by (dx, dy) (eq. 16), and how far
        its curve moved at them [mm] (a fitted single Bezier does not pass through its points: the moves apply
        to the curve, else the points would drift from it without end)."""
        now = self.at(self.z)
        new = FlankPath(self.side, self.z, now[:, 0] + dx, now[:, 1] + dy, self.form)
        return new, float(np.max(np.abs(new.at(self.z) - now)))

    def at(self, z: np.ndarray) -> np.ndarray:
        """(n, 2) path point [x_tr, y_tr] at face positions ``z``; linear beyond the end points."""
        z = np.asarray(z, dtype=float)
        out = np.empty((*z.shape, 2))
        for k, sp in enumerate(self._splines):
            zc = np.clip(z, self.z[0], self.z[-1])
            out[..., k] = sp(zc) + sp(zc, 1) * (z - zc)
        return out

    def tangent(self, z: np.ndarray) -> np.ndarray:
        """(n, 3) unit path tangents (x, y, z)."""
        z = np.asarray(z, dtype=float)
        zc = np.clip(z, self.z[0], self.z[-1])
        d = np.stack([sp(zc, 1) for sp in self._splines] + [np.ones_like(zc)], axis=-1)
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    def bezier(self) -> list[dict[str, list[float]]]:
        """The path as cubic Bezier segments (what a CNC's spline interpolation takes): per segment its z span and
        the four control values of x and y [mm]; the spline's segments run between the path points, the single
        Bezier is one segment over the whole path."""
        knots = self.z[[0, -1]] if self.form == "bezier" else self.z
        out = []
        for i in range(len(knots) - 1):
            z0, z1 = float(knots[i]), float(knots[i + 1])
            h = z1 - z0
            seg: dict[str, list[float]] = {"z": [z0, z1]}
            for name, sp in zip(("x", "y"), self._splines, strict=True):
                y0, y1, d0, d1 = float(sp(z0)), float(sp(z1)), float(sp(z0, 1)), float(sp(z1, 1))
                seg[name] = [y0, y0 + h * d0 / 3, y1 - h * d1 / 3, y1]
            out.append(seg)
        return out


class ContactCurves:
    """A plan's contact curves: on a helical space, per side the roll lengths and the face positions (from the mill's
    reference plane: the disc's centre plane, the finger's axis) where the mill touches the flank (``contact``;
    empty on a spur gear: the profiling plane itself)."""

    contact: dict[str, tuple[np.ndarray, np.ndarray]]

    def contact_offset(self, side: Side, L: np.ndarray) -> np.ndarray:
        """Where, from the mill's reference plane, the mill cuts the ``side`` flank at roll lengths L [mm] (0: spur)."""
        if side not in self.contact:
            return np.zeros_like(np.asarray(L, dtype=float))
        grid, offset = self.contact[side]
        return np.interp(L, grid, offset)


@dataclass
class CopyingPlan(ContactCurves):
    """What the 15 steps give: the mill, the two passes' paths, the corrections and the iterations."""

    gear: Gear
    design: Modification | None
    mill: DiscMill
    paths: dict[str, FlankPath]
    clearance: float
    approach: float  # feed beyond each end face while the mill still reaches the blank [mm]
    k_r: dict[str, np.ndarray] = field(default_factory=dict)  # last radial corrections per path point [mm]
    k_t: dict[str, np.ndarray] = field(default_factory=dict)
    psi: dict[str, np.ndarray] = field(default_factory=dict)  # (n, 2) transfer angles psi_x, psi_y [rad]
    section_rms: dict[str, float] = field(default_factory=dict)  # eq. 8: sections' RMS from the mean [mm]
    iterations: list[dict] = field(default_factory=list)  # the geometric iterations and the accuracy checks
    turned: bool = True  # the mill's axis turned by the path's transfer angles (eq. 6), else fixed along x
    #: a helical space: per side the roll lengths and the face positions (from the mill's centre plane) where the
    #: set-over mill touches the flank (empty on a spur gear: the profiling plane itself)
    contact: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)

    def pass_poses(self, space: int, side: Side, step: float = POSE_STEP, turned: bool | None = None) -> MillPassPoses:
        """The ideal machine's poses of the ``side`` pass of ``space`` (the planned path, exactly); ``turned``: the
        mill's axis turned by the path's transfer angles (:func:`poses_on_path`), else fixed along x (default: the
        plan's)."""
        half = self.gear.face_width / 2 + self.approach
        return self.poses_at(space, side, np.arange(-half, half + step / 2, step), turned)

    def poses_at(self, space: int, side: Side, z: np.ndarray, turned: bool | None = None) -> MillPassPoses:
        """The poses of the ``side`` pass of ``space`` at path positions ``z`` [mm] (see :meth:`pass_poses`)."""
        turned = self.turned if turned is None else turned
        path = self.paths[side]
        z = np.asarray(z, dtype=float)
        psi = transfer_angles(path.tangent(z)) if turned else None
        return poses_on_path(self.gear, self.mill, space, side, z, path.at(z), psi)

    def all_passes(self, step: float = POSE_STEP) -> list[MillPassPoses]:
        return [self.pass_poses(k, s, step) for k in range(self.gear.teeth) for s in SIDES]

    def check_passes(self, space: int) -> list[MillPassPoses]:
        """The passes that shape the flanks of ``space``: its own and its neighbours'."""
        return [self.pass_poses(k % self.gear.teeth, s) for k in (space - 1, space, space + 1) for s in SIDES]

    def summary(self) -> dict:
        """The plan for measurement.json."""
        return {
            "method": "copying (seed 003): profiled disc mill, one pass per flank",
            "mill": self.mill.summary(),
            "clearance_mm": self.clearance,
            "approach_mm": round(self.approach, 3),
            "path_points_z_mm": np.round(self.paths["left"].z, 4).tolist(),
            "path_form": self.paths["left"].form,
            "k_r_um": {s: np.round(v * 1e3, 3).tolist() for s, v in self.k_r.items()},
            "k_t_um": {s: np.round(v * 1e3, 3).tolist() for s, v in self.k_t.items()},
            "psi_mrad": {s: np.round(v * 1e3, 4).tolist() for s, v in self.psi.items()},
            "section_rms_um": {s: round(v * 1e3, 3) for s, v in self.section_rms.items()},
            "path_bezier": {s: p.bezier() for s, p in self.paths.items()},
            "iterations": self.iterations,
        }


def mill_in_space(radius: float, z: np.ndarray, xy: np.ndarray, psi: np.ndarray | None = None):
    """The mill's centre and unit axis, (N, 3) each, in the space frame for path points ``xy`` (N, 2) at ``z``:
    the centre ``radius`` above the path point along the space's symmetry line, the axis along the space's x
    (tangential); with the transfer angles ``psi`` (N, 2) the mill turned with the path's tool frame instead
    (eq. 6, R = Rx(psi_x) Ry(psi_y), R e_z the path tangent): the axis R e_x, the centre ``radius`` along R e_y,
    so that the mill's axial section lies in the profiling plane, where its edge was fitted."""
    z = np.asarray(z, dtype=float)
    axis = np.broadcast_to([1.0, 0.0, 0.0], (len(z), 3))
    up = np.broadcast_to([0.0, 1.0, 0.0], (len(z), 3))
    if psi is not None:
        rot = tool_rotations(np.asarray(psi, dtype=float))
        axis, up = rot[:, :, 0], rot[:, :, 1]
    return np.stack([xy[:, 0], xy[:, 1], z], axis=-1) + radius * up, np.array(axis)


def poses_on_path(
    gear: Gear,
    mill: DiscMill,
    space: int,
    side: Side,
    z: np.ndarray,
    xy: np.ndarray,
    psi: np.ndarray | None = None,
) -> MillPassPoses:
    """Poses (gear frame) of the mill whose path point is ``xy`` (n, 2) in the space frame at ``z``, fixed or
    turned by ``psi`` (:func:`mill_in_space`); on a helical gear set over at the helix angle, each pose in the space
    frame of its face position (the space turns along the face: the poses make its screw motion)."""
    z = np.asarray(z, dtype=float)
    beta = set_over(gear)
    if beta != 0.0:
        psi = (np.zeros((len(z), 2)) if psi is None else np.asarray(psi, dtype=float)) + np.array([0.0, beta])
    centre, axis = mill_in_space(mill.radius, z, xy, psi)  # in the space frame at z (one frame on a spur gear)
    return MillPassPoses(space, side, z.copy(), from_space(gear, space, centre, z), from_space(gear, space, axis, z))


# ---- the steps ----------------------------------------------------------------------------------------------
def contact_curves(
    gear: Gear, L: np.ndarray, centres: dict[str, np.ndarray], axis: np.ndarray, mill: str, fix: str
) -> dict[str, np.ndarray]:
    """On a helical space, per side the face positions [mm] from a mill's reference point ``centres[side]`` (space
    frame, on its nominal pass) where the mill of revolution about ``axis`` touches the nominal helicoid at roll
    lengths ``L`` (:func:`cutting.form_milling.helical.contact_profile`); empty on a spur gear (the profiling plane
    itself). A profile point whose normal misses the axis is refused, naming the ``mill`` and the ``fix``."""
    contact: dict[str, np.ndarray] = {}
    if gear.helix_angle == 0.0:
        return contact
    for s in SIDES:
        contact[s] = contact_profile(gear, s, L, centres[s], axis)[2]
        if not np.all(np.isfinite(contact[s])):
            raise ValueError(
                f"{mill} cannot touch the {s} flank's whole profile (its normals miss the mill's axis): use {fix}"
            )
    return contact


def path_points(gear: Gear, n: int, reach: float = 0.0) -> np.ndarray:
    """z_i = i b / (2 n), i = -n..n (step 2) [mm]; with ``reach`` > 0 [mm] (a helical space: the set-over mill cuts
    up to that far from its centre plane) the same steps go on beyond each end face until they cover it, so that
    every flank point is cut by the path between two path points (else the flank near an end face is cut by the
    spline's extrapolation, which no correction reaches: measured -1.1 / +1.65 um of twist at beta = 20 deg)."""
    step = gear.face_width / (2 * n)
    extra = math.ceil(reach / step - 1e-9) if reach > 0 else 0
    return np.arange(-n - extra, n + extra + 1) * step


def nominal_path_point(gear: Gear, side: Side, clearance: float) -> tuple[float, float]:
    """(x^n, y^n): on the root circle, shifted -c/2 (left pass) or +c/2 (right pass) [mm]."""
    return (-clearance / 2 if side == "left" else clearance / 2), gear.root_radius


def pitch_point(gear: Gear, design: Modification | None, side: Side, z: np.ndarray) -> np.ndarray:
    """(n, 2) the designed ``side`` flank's point on the pitch (reference) cylinder in the sections ``z``, space
    frame [mm]: Newton on the roll length L until the section point's radius is the reference radius."""
    z = np.asarray(z, dtype=float)
    L = np.full(z.shape, roll(gear, gear.reference_diameter))
    r, h = gear.reference_radius, 1e-6
    for _ in range(20):
        rad = np.hypot(*np.moveaxis(designed_section(gear, design, side, L, z)[..., :2], -1, 0))
        slope = (np.hypot(*np.moveaxis(designed_section(gear, design, side, L + h, z)[..., :2], -1, 0)) - rad) / h
        step = (rad - r) / slope
        L = L - step
        if np.max(np.abs(step)) < 1e-13:
            break
    return designed_section(gear, design, side, L, z)[..., :2]


def initial_path(
    gear: Gear, design: Modification | None, side: Side, z: np.ndarray, clearance: float, form: str = "spline"
) -> FlankPath:
    """Step 2, eq. 1: x_i = x^n + Delta x_i, y_i = y^n + Delta y_i at z_i, where (Delta x_i, Delta y_i) is how far
    the design moves the flank's point on the pitch cylinder in section z_i, along the thickness and along the
    height (the seed takes the largest, at the end face, and spreads it over the points; here each point has its
    own, which is the same on the seed's linear case and closer on any other)."""
    xn, yn = nominal_path_point(gear, side, clearance)
    z = np.asarray(z, dtype=float)
    shift = np.zeros((len(z), 2))
    if design is not None:
        shift = pitch_point(gear, design, side, z) - pitch_point(gear, None, side, z)
    return FlankPath(side, z, xn + shift[:, 0], yn + shift[:, 1], form)


def transfer_angles(tangent: np.ndarray) -> np.ndarray:
    """Step 5, eqs. 4-5: psi_x = atan2(-T_y, T_z) about x, psi_y = asin(T_x) about y; (n, 2) [rad]."""
    return np.stack([np.arctan2(-tangent[:, 1], tangent[:, 2]), np.arcsin(np.clip(tangent[:, 0], -1, 1))], axis=-1)


def tool_rotation(psi_x: float, psi_y: float) -> np.ndarray:
    """Gear (space) frame -> tool frame rotation R with R e_z = T (eq. 6 uses R^T): R = Rx(psi_x) Ry(psi_y)."""
    return tool_rotations(np.array([[psi_x, psi_y]]))[0]


def tool_rotations(psi: np.ndarray) -> np.ndarray:
    """:func:`tool_rotation` for transfer angles (n, 2): (n, 3, 3), Rx(psi_x) Ry(psi_y) multiplied out."""
    cx, sx = np.cos(psi[:, 0]), np.sin(psi[:, 0])
    cy, sy = np.cos(psi[:, 1]), np.sin(psi[:, 1])
    zero = np.zeros_like(cx)
    rows = [[cy, zero, sy], [sx * sy, cx, -sx * cy], [-cx * sy, sx, cx * cy]]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def profiling_sections(
    gear: Gear, design: Modification | None, path: FlankPath, L: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Steps 3-6: per path point the designed flank's section in the profiling plane (normal to the path through
    the point), in tool coordinates relative to the path point (n, m, 2), and the transfer angles (n, 2)."""
    z = path.z
    pts = path.at(z)
    tangent = path.tangent(z)
    psi = transfer_angles(tangent)
    out = np.empty((len(z), len(L), 2))
    for i in range(len(z)):
        origin = np.array([pts[i, 0], pts[i, 1], z[i]])
        t = tangent[i]
        zz = np.full(len(L), z[i])
        for _ in range(4):  # eq. 2: the flank point of roll length L on the plane (p - origin) . T = 0
            p = designed_section(gear, design, path.side, L, zz)
            f = (p - origin) @ t
            zz = zz - f / t[2]
        p = designed_section(gear, design, path.side, L, zz)
        q = (p - origin) @ tool_rotation(*psi[i])  # eq. 6: R^T (p - origin), as rows
        out[i] = q[:, :2]
    return out, psi


def helical_sections(
    gear: Gear,
    design: Modification | None,
    path: FlankPath,
    L: np.ndarray,
    contact: np.ndarray,
    radius: float,
    turned: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """Steps 3-6 on a helical space: the set-over mill touches the flank along a space curve, not in a plane (the
    envelope, :mod:`cutting.form_milling.helical`), at face positions ``contact`` (per roll length, from the mill's
    centre plane) that the nominal helicoid fixes; the design moves the flank by micrometres, which moves the
    contact along the flank only to second order. Per path point: the designed flank at those points in the
    mill's axial coordinates (u along the axis, R - rho above the periphery) about its pose there, (n, m, 2), and
    the transfer angles (n, 2) (the set-over added to psi_y in the poses)."""
    z = path.z
    psi = transfer_angles(path.tangent(z)) if turned else np.zeros((len(z), 2))
    centre, axis = mill_in_space(radius, z, path.at(z), psi + np.array([0.0, set_over(gear)]))
    u, rho = axial_sections(gear, design, path.side, z, L, contact, centre, axis)
    return np.stack([u, radius - rho], axis=-1), psi


def axial_sections(
    gear: Gear,
    design: Modification | None,
    side: Side,
    z: np.ndarray,
    L: np.ndarray,
    contact: np.ndarray,
    centre: np.ndarray,
    axis: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The designed ``side`` flank where a mill of revolution touches it on a helical space, in the mill's axial
    coordinates: per path point z_i (n) the flank points at roll lengths ``L`` (m) and face positions z_i + contact
    (m), against the mill's reference point ``centre`` and unit ``axis`` (n, 3, each in the space frame of its z_i):
    the axial coordinate u and the distance rho from the axis, (n, m) each."""
    centre, axis = from_space(gear, 0, centre, z), from_space(gear, 0, axis, z)
    u = np.empty((len(z), len(L)))
    rho = np.empty((len(z), len(L)))
    for i in range(len(z)):
        zz = z[i] + contact
        p = from_space(gear, 0, designed_section(gear, design, side, L, zz), zz) - centre[i]
        u[i] = p @ axis[i]
        rho[i] = np.linalg.norm(p - u[i][:, None] * axis[i], axis=1)
    return u, rho


def mean_section(sections: np.ndarray) -> tuple[np.ndarray, float]:
    """Eqs. 7-8: the mean section (m, 2) over the path points and the sections' RMS thickness deviation from it."""
    mean = sections.mean(axis=0)
    rms = float(np.sqrt(np.mean((sections[..., 0] - mean[None, :, 0]) ** 2)))
    return mean, rms


def corrections(mill: DiscMill, side: Side, sections: np.ndarray, bottom: int, top: int) -> tuple[np.ndarray, ...]:
    """Steps 7-8, eqs. 10-15: per section the radial correction k_r (the edge moved by k_r along the height meets
    the section's bottom and top points with one thickness offset) and the tangential one k_t (that offset)."""

    def offsets(k_r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # eq. 12: thickness deviations dx_0, dx_n
        x0 = sections[:, bottom, 0] - mill.edge_x(side, sections[:, bottom, 1] - k_r)
        xn = sections[:, top, 0] - mill.edge_x(side, sections[:, top, 1] - k_r)
        return x0, xn

    k_r = np.zeros(len(sections))
    h = 1e-4
    for _ in range(8):  # Newton on eq. 10 (dx_0 = dx_n), derivative by central difference
        a0, an = offsets(k_r + h)
        b0, bn = offsets(k_r - h)
        f0, fn = offsets(k_r)
        f = f0 - fn
        df = ((a0 - an) - (b0 - bn)) / (2 * h)
        step = np.where(np.abs(df) > 1e-12, f / df, 0.0)
        k_r = k_r - step
        if np.max(np.abs(step)) < 1e-11:
            break
    x0, xn = offsets(k_r)
    return k_r, (x0 + xn) / 2  # eq. 11: k_t = (dx_00 + dx_0n) / 2


def plan_copying(
    gear: Gear,
    design: Modification | None,
    mill_diameter: float,
    clearance: float = 0.2,
    n: int = 10,
    mill_teeth: int = 12,
    max_iterations: int = 8,
    checks: int = 3,
    check_points: int = 11,
    path_form: str = "spline",
    turned: bool = True,
) -> CopyingPlan:
    """The seed's 15 steps for ``gear`` carrying ``design``: the mill, both passes' paths and the accuracy check
    (``checks`` rounds at most; 0: none). ``path_form``: "spline" (a C2 spline through the path points) or
    "bezier" (the seed's single cubic Bezier, eq. 17).

    The steps (seed fig. 1):

    1. initial data: the designed flank sections (:func:`cutting.form_milling.mill.designed_section`);
    2. initial path points (eq. 1): moved by how far the design moves the flank's point on the pitch cylinder at z_i,
       along the thickness and the height (the seed takes them between the symmetry plane and the end face; a
       design need not be symmetric, so both halves);
    3. the profiling plane through each path point, normal to the path (the seed puts it through each segment's
       middle; through the points with the adjacent segments' mean direction the corrections land on the points);
    4. its intersection with the designed flank (eq. 2, Newton on z per profile point);
    5. the transfer angles psi_x = atan2(-T_y, T_z), psi_y = asin(T_x) of the path tangent T (eqs. 4, 5);
    6. the section in tool coordinates, rotated by psi_x about x and psi_y about y (eq. 6);
    7./8. mean section over the path points (eq. 7) and the sections' RMS deviation from it (eq. 8); the mill edge
       fitted to the mean section as a Bezier chain (eq. 9); the radial correction k_r (eq. 10: the edge, moved by
       k_r along the height, meets the section's bottom and top points with one thickness offset) and the
       tangential correction k_t (eqs. 11-15: that offset, the thickness deviation of the bottom and top points);
    9. the refined path points x = x_pr + k_t, y = y_pr + k_r, z = z_pr (eq. 16);
    10. the path fitted with cubic Bezier segments (eq. 17; a C2 spline through the points, exact on a parabola,
        continued along its end tangents beyond the face so the mill runs in and out without a kink), or with the
        seed's single cubic Bezier over the face (``path_form="bezier"``);
    11.-14. the profiling planes of the Bezier path, their sections and corrections again, until the path stands;
    15. the accuracy check: the flank the mill really cuts on the path (its exact swept surface, no deflections)
        against the design at every path point; where it misses, the residual's level and slope over the profile
        (least squares) correct the path and the check is repeated.
    """
    radius = mill_diameter / 2
    L = section_rolls(gear)
    lf, la = form_roll_length(gear), roll(gear, gear.tip_diameter_value)
    bottom, top = 0, tip_index(gear, L)  # the profile's bottom and top points (eqs. 11-15)
    # a helical space's mill keeps its set-over: turned further by the path's transfer angles, a leaning mill's
    # envelope changes at first order with the turn, and step 15's corrections (which turn it) diverge (measured
    # 0.8 -> 1.8 -> 20 um at beta = 20 deg, where the set-over mill converges to 0.9 um)
    turned = turned and gear.helix_angle == 0.0
    centres = {s: np.array([nominal_path_point(gear, s, clearance)[0], gear.root_radius + radius, 0.0]) for s in SIDES}
    mill_name = f"the set-over mill of radius {radius} mm"
    contact = contact_curves(gear, L, centres, mill_axis(gear), mill_name, "a larger mill")
    reach = max((float(np.abs(c).max()) for c in contact.values()), default=0.0)
    z = path_points(gear, n, reach)
    paths = {s: initial_path(gear, design, s, z, clearance, path_form) for s in SIDES}
    log: list[dict] = []
    k_r: dict[str, np.ndarray] = {}
    k_t: dict[str, np.ndarray] = {}
    psi: dict[str, np.ndarray] = {}
    rms: dict[str, float] = {}
    mill = None
    for it in range(max_iterations):
        if contact:
            sections = {s: helical_sections(gear, design, paths[s], L, contact[s], radius, turned) for s in SIDES}
        else:
            sections = {s: profiling_sections(gear, design, paths[s], L) for s in SIDES}
        edges = {}
        for s in SIDES:
            mean, rms[s] = mean_section(sections[s][0])
            edges[s] = BezierChain.fit(mean, through=(top,))  # the edge meets the top point exactly
        mill = DiscMill(radius, edges["left"], edges["right"], mill_teeth)
        moved = 0.0
        for s in SIDES:
            secs, psi[s] = sections[s]
            k_r[s], k_t[s] = corrections(mill, s, secs, bottom, top)
            # the edge is the mean section relative to the path: a shift common to every path point moves path
            # and edge alike and changes no flank, so it is left out (else path and edge drift together)
            dr, dt = k_r[s] - k_r[s].mean(), k_t[s] - k_t[s].mean()
            paths[s], change = paths[s].moved(dt, dr)  # eq. 16
            moved = max(moved, change)
        log.append({"step": "path", "iteration": it + 1, "path_change_um": round(moved * 1e3, 5)})
        if moved < PATH_TOLERANCE:
            break
    approach = approach_length(gear, radius) + radius * abs(math.sin(set_over(gear)))  # a leaning mill reaches on
    plan = CopyingPlan(gear, design, mill, paths, clearance, approach, k_r, k_t, psi, rms, log, turned)
    plan.contact = {s: (L, c) for s, c in contact.items()}
    lc = np.linspace(lf, la, check_points)
    for c in range(checks):
        worst, res = accuracy_check(plan, lc)
        log.append({"step": "accuracy check", "round": c + 1, "max_residual_um": round(worst * 1e3, 4)})
        if worst < CHECK_TOLERANCE or c == checks - 1:
            break
        for s in SIDES:
            dx, dy = correction_from_residual(gear, s, lc, res[s])
            plan.paths[s] = plan.paths[s].moved(dx, dy)[0]
    return plan


def approach_length(gear: Gear, radius: float) -> float:
    """Feed beyond an end face while the mill's periphery still reaches the tip circle, plus 0.5 mm [mm]."""
    depth = gear.tip_radius - gear.root_radius
    return math.sqrt(max(radius**2 - (radius - depth) ** 2, 0.0)) + 0.5


def accuracy_check(
    plan: CopyingPlan | FingerPlan, L: np.ndarray, space: int = 0, passes: list[MillPassPoses] | None = None
) -> tuple[float, dict[str, np.ndarray]]:
    """Step 15: the flanks of ``space`` that the mill (disc or finger: ``plan`` a CopyingPlan or a FingerPlan) cuts
    on the planned path (its exact swept surface; no deflections), or by ``passes`` (e.g. what a machine made),
    against the design at every path point and roll length ``L``: residual [mm] per side (n, m), excess material
    positive, and the largest |residual|."""
    gear = plan.gear
    if passes is None:
        passes = plan.check_passes(space)
    cut = MilledGear(gear, plan.mill, passes, "accuracy check")
    res = {}
    worst = 0.0
    for s in SIDES:
        zz, LL = np.meshgrid(plan.paths[s].z, L, indexing="ij")
        zz = zz + plan.contact_offset(s, L)[None, :]  # what the mill cuts at each path point (helical: off its plane)
        # a helical contact beyond the face: that path point cuts no flank there (no residual to correct it by)
        beyond = np.abs(zz) > gear.face_width / 2 + 1e-9 if plan.contact else np.zeros(zz.shape, bool)
        zz = np.clip(zz, -gear.face_width / 2 + 1e-3, gear.face_width / 2 - 1e-3)
        tooth = space_tooth(gear, space, s)
        p = flank_points(gear, s, LL / gear.base_radius, zz, tooth)
        nrm = flank_normals(gear, s, LL / gear.base_radius, zz, tooth)
        d = cut.probe(p.reshape(-1, 3), nrm.reshape(-1, 3), 0.05).reshape(p.shape[:-1])
        design = 0.0 if plan.design is None else plan.design.deviation(gear, s, LL, zz)
        res[s] = np.where(beyond, np.nan, d - design)
        worst = max(worst, float(np.nanmax(np.abs(res[s]))))
    return worst, res


#: flank points a path point's residual needs for its (dx, dy) correction
LEAST_CHECK_POINTS = 4


def correction_from_residual(gear: Gear, side: Side, L: np.ndarray, res: np.ndarray) -> tuple[np.ndarray, ...]:
    """Path corrections (dx, dy) [mm] per path point that cancel the residual's level and slope over the profile
    (least squares; the seed's k_t, k_r match the bottom and top points only, which leaves a bow's whole height at
    mid profile): the surface moves by (dx, dy) . n, n the flank normal out of the material."""
    n = section_normals(gear, side, L)  # (m, 2)
    ok = np.isfinite(res)
    dx, dy = np.full(len(res), np.nan), np.full(len(res), np.nan)
    for i in range(len(res)):
        if ok[i].sum() >= LEAST_CHECK_POINTS:
            dx[i], dy[i] = np.linalg.lstsq(n[ok[i]], -res[i, ok[i]], rcond=None)[0]
    known = np.flatnonzero(np.isfinite(dx))
    if not len(known):
        return np.zeros(len(res)), np.zeros(len(res))
    # a path point whose contact curve meets the face in too few points (beyond an end face of a helical space)
    # takes its nearest determined neighbour's correction: fitted to one or two points it would run away
    nearest = known[np.abs(np.arange(len(res))[:, None] - known[None, :]).argmin(axis=1)]
    return dx[nearest], dy[nearest]
