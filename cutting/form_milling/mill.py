"""The profiled disc mill of the copying method (seed 003) and the tooth-space sections it copies.

Tool coordinates are the seed's: x along the tooth thickness (tangential; the disc mill's axis), y along the
tooth height (radial, along the tooth space's symmetry line), z along the face. A tooth space k of a spur gear
(between tooth k and tooth k+1, centred at the polar angle 2 pi (k + 1/2) / z) is described in its *space frame*:
x_s tangential (+theta), y_s along the symmetry line outwards, z. The left flank of the space is tooth k's left
flank (x_s < 0), the right one tooth k+1's right flank (x_s > 0).

The mill's *path point* (x_tr, y_tr) is its lowest periphery point in the space frame; the nominal one is on the
symmetry line at the root circle. Its cutting edge is given relative to the path point: the left and the right
edge each a chain of cubic Bezier segments (seed eq. 9) fitted to a flank section, a straight run along the
edge's end tangent down to the periphery, and the periphery itself (y = 0). The mill is a solid of revolution
about its axis (the tool x axis through the centre at y = R): at axial position u its radius is R - h(u), h the
edge height at x = u.

What the exact swept surface (:mod:`cutting.form_milling.sweep`) and the removal (:mod:`cutting.form_milling.removal`)
ask of a mill is :class:`Mill`: a solid of revolution about the axis of its poses, given by the axial table u -> R -
h(u) from its reference point (the pose's centre); the disc mill here and the finger mill
(:mod:`cutting.form_milling.finger`) both answer it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar, Protocol

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.spatial import cKDTree

from cutting.flank import Side, flank_normals, flank_points, twist_rate
from cutting.gear import Gear, form_roll_length
from cutting.modification import Modification, bernstein, bernstein_derivative, roll

#: the edge's Bezier chain is fitted to this [mm] (0.05 um: far below what a mill grinder holds)
EDGE_FIT_TOLERANCE = 5e-5
#: the edge reaches this far [mm, in units of the module] above the tip circle, so the mill clears the tip
TIP_MARGIN = 0.25
#: dense samples per Bezier segment of the mill's profile table (linear interpolation between them: < 1 nm)
TABLE_SAMPLES = 4000


def space_angle(gear: Gear, space: int) -> float:
    """Polar angle of the symmetry line of tooth space ``space`` (between tooth k and k+1) [rad]."""
    return 2 * math.pi * (space + 0.5) / gear.teeth


def to_space(gear: Gear, space: int, points: np.ndarray, frame_z=0.0) -> np.ndarray:
    """Gear-frame points (..., 3) in the frame of space ``space``: (x_s tangential, y_s radial, z). On a helical gear
    the space turns along the face: ``frame_z`` [mm] (broadcast with the points) is the face position whose frame
    is meant (default mid face: one rigid frame); a point's own z gives the frame it lies in."""
    a = space_angle(gear, space) + twist_rate(gear) * np.asarray(frame_z, dtype=float)
    c, s = np.cos(a), np.sin(a)
    p = np.asarray(points, dtype=float)
    return np.stack([-s * p[..., 0] + c * p[..., 1], c * p[..., 0] + s * p[..., 1], p[..., 2]], axis=-1)


def from_space(gear: Gear, space: int, points: np.ndarray, frame_z=0.0) -> np.ndarray:
    """Space-frame points (..., 3) back in the gear frame (``frame_z`` as :func:`to_space`)."""
    a = space_angle(gear, space) + twist_rate(gear) * np.asarray(frame_z, dtype=float)
    c, s = np.cos(a), np.sin(a)
    p = np.asarray(points, dtype=float)
    return np.stack([-s * p[..., 0] + c * p[..., 1], c * p[..., 0] + s * p[..., 1], p[..., 2]], axis=-1)


def check_copying_gear(gear: Gear, mill: str = "disc") -> list[str]:
    """Why the copying method here cannot make ``gear`` with a ``mill`` ("disc" or "finger") mill (empty if it can)."""
    if mill not in ("disc", "finger"):
        raise ValueError(f"mill {mill!r}: use 'disc' or 'finger'")
    out = []
    if gear.internal and mill == "disc":
        out.append(
            "an internal gear: a disc mill reaches no internal tooth space (cut it with the finger mill, "
            "cutting.form_milling.finger, or by skiving)"
        )
    return out


def space_tooth(gear: Gear, space: int, side: Side) -> int:
    """The tooth whose ``side`` flank bounds tooth space ``space`` (between tooth k and k+1): on an external gear the
    left flank is tooth k's, on an internal one (its left flank on a tooth's clockwise side) tooth k+1's."""
    first = side == "left"
    if gear.internal:
        first = not first
    return space if first else space + 1


def flank_sign(gear: Gear, side: Side) -> int:
    """The sign of x_s (space frame) of the ``side`` flank of a tooth space: -1 left / +1 right on an external gear,
    reversed on an internal one."""
    return -1 if space_tooth(gear, 0, side) == 0 else 1


def section_rolls(gear: Gear, points: int = 81) -> np.ndarray:
    """Roll lengths [mm] of a flank section from the form circle to TIP_MARGIN mn above the tip, spaced
    geometrically (the involute's curvature 1/L changes alike between neighbours), with the tip circle's own
    roll length among them (:func:`tip_index`): the profile's top point."""
    lf = max(form_roll_length(gear), 1e-3 * gear.mn)
    la = roll(gear, 2 * (gear.tip_radius + TIP_MARGIN * gear.mn))
    L = np.geomspace(lf, la, points)
    tip = roll(gear, gear.tip_diameter_value)
    return np.insert(L, int(np.searchsorted(L, tip)), tip)


def tip_index(gear: Gear, L: np.ndarray) -> int:
    """Index of the tip circle's roll length in a section's roll lengths (:func:`section_rolls`)."""
    return int(np.argmin(np.abs(L - roll(gear, gear.tip_diameter_value))))


def designed_section(
    gear: Gear, design: Modification | None, side: Side, L: np.ndarray, z: np.ndarray, space: int = 0
) -> np.ndarray:
    """Points (..., 3) of the designed ``side`` flank of tooth space ``space`` at roll lengths ``L`` and face
    positions ``z`` (broadcast), in the space frame at their own z (a helical space's section is then the same
    at every z): the involute moved along its normal by the design's deviation (excess material positive; beyond
    the tip the design's own formula continues)."""
    L, z = np.broadcast_arrays(np.asarray(L, dtype=float), np.asarray(z, dtype=float))
    tooth = space_tooth(gear, space, side)
    xi = L / gear.base_radius
    p = flank_points(gear, side, xi, z, tooth)
    if design is not None:
        e = design.deviation(gear, side, L, z) * math.cos(gear.base_helix_angle)
        p = p + e[..., None] * flank_normals(gear, side, xi, z, tooth)
    return to_space(gear, space, p, z)


def section_normals(gear: Gear, side: Side, L: np.ndarray, space: int = 0) -> np.ndarray:
    """Unit normals (..., 2) (x_s, y_s) of the nominal ``side`` flank of the space, out of the material."""
    tooth = space_tooth(gear, space, side)
    n = flank_normals(gear, side, np.asarray(L, dtype=float) / gear.base_radius, 0.0, tooth)
    return to_space(gear, space, n)[..., :2]


@dataclass(frozen=True, eq=False)
class BezierChain:
    """A planar curve as a chain of cubic Bezier segments, control points (k, 4, 2), tangent-continuous."""

    control: np.ndarray

    @property
    def segments(self) -> int:
        return len(self.control)

    def at(self, tau: np.ndarray) -> np.ndarray:
        """Points at the chain parameter tau in [0, k] (segment i spans [i, i+1])."""
        tau = np.clip(np.asarray(tau, dtype=float), 0.0, self.segments)
        i = np.minimum(tau.astype(int), self.segments - 1)
        return np.einsum("...k,...kd->...d", bernstein(tau - i), self.control[i])

    def dense(self, per_segment: int = TABLE_SAMPLES) -> np.ndarray:
        return self.at(np.linspace(0.0, self.segments, self.segments * per_segment + 1))

    def distance(self, points: np.ndarray) -> np.ndarray:
        """Distance of ``points`` (n, 2) from the curve [mm]: nearest table point, then Newton on the parameter."""
        per = 400
        tau_table = np.linspace(0.0, self.segments, self.segments * per + 1)
        _, idx = cKDTree(self.at(tau_table)).query(points)
        tau = tau_table[idx]
        for _ in range(8):
            i = np.minimum(tau.astype(int), self.segments - 1)
            f = tau - i
            c = np.einsum("nk,nkd->nd", bernstein(f), self.control[i])
            d1 = np.einsum("nk,nkd->nd", bernstein_derivative(f), self.control[i])
            d2 = np.einsum("nk,nkd->nd", _bernstein_second(f), self.control[i])
            r = c - points
            den = np.einsum("nd,nd->n", d1, d1) + np.einsum("nd,nd->n", r, d2)
            step = np.einsum("nd,nd->n", r, d1) / np.where(np.abs(den) > 1e-15, den, 1e-15)
            tau = np.clip(tau - step, 0.0, self.segments)
        return np.linalg.norm(self.at(tau) - points, axis=1)

    @classmethod
    def fit(
        cls,
        points: np.ndarray,
        tolerance: float = EDGE_FIT_TOLERANCE,
        max_segments: int = 12,
        through: tuple[int, ...] = (),
    ) -> BezierChain:
        """A chain whose distance from every point is within ``tolerance`` [mm] (seed eq. 9 fitted to a flank
        section): ends and joints on the points (the points ``through`` are joints: the chain passes through them
        exactly), tangents the section's own; the segment that misses most is split at its worst point until the
        chain fits or has ``max_segments``."""
        p = np.asarray(points, dtype=float)
        joints = sorted({0, len(p) - 1, *(int(i) for i in through if 3 <= i <= len(p) - 4)})
        while True:
            chain = cls(_fit_chain(p, joints))
            err = chain.distance(p)
            worst = int(np.argmax(err))
            if err[worst] <= tolerance or len(joints) - 1 >= max_segments:
                return chain
            k = int(np.searchsorted(joints, worst))  # the segment joints[k-1]..joints[k] holds it
            a, b = joints[k - 1], joints[k]
            split = worst if a + 3 <= worst <= b - 3 else (a + b) // 2
            if split - a < 3 or b - split < 3:
                return chain
            joints.insert(k, split)


def _fit_chain(p: np.ndarray, joints: list[int]) -> np.ndarray:
    """Control points (k, 4, 2) of cubic segments between the points at ``joints`` (indices, increasing)."""
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
    tangents = CubicSpline(s, p, axis=0)(s, 1)  # the section's own tangents (a spline through its points)
    tangents /= np.linalg.norm(tangents, axis=1, keepdims=True)
    k = len(joints) - 1
    control = np.empty((k, 4, 2))
    for i in range(k):
        a, b = joints[i], joints[i + 1]
        q = p[a : b + 1]
        p0, p3, t0, t3 = q[0], q[-1], tangents[a], tangents[b]
        tau = (s[a : b + 1] - s[a]) / (s[b] - s[a])
        for _ in range(30):  # least squares of the two tangent lengths, then Newton-project the parameters
            w = bernstein(tau)
            base = np.outer(w[:, 0] + w[:, 1], p0) + np.outer(w[:, 2] + w[:, 3], p3)
            A = np.stack([(w[:, 1, None] * t0).ravel(), (-w[:, 2, None] * t3).ravel()], axis=1)
            lengths = np.linalg.lstsq(A, (q - base).ravel(), rcond=None)[0]
            ctrl = np.array([p0, p0 + lengths[0] * t0, p3 - lengths[1] * t3, p3])
            c = bernstein(tau) @ ctrl
            d1 = bernstein_derivative(tau) @ ctrl
            d2 = _bernstein_second(tau) @ ctrl
            r = c - q
            num = np.einsum("ij,ij->i", r, d1)
            den = np.einsum("ij,ij->i", d1, d1) + np.einsum("ij,ij->i", r, d2)
            tau = np.clip(tau - num / np.where(np.abs(den) > 1e-15, den, 1e-15), 0.0, 1.0)
            tau[0], tau[-1] = 0.0, 1.0
        control[i] = ctrl
    return control


def _bernstein_second(t: np.ndarray) -> np.ndarray:
    t = np.asarray(t, dtype=float)
    return np.stack([6 * (1 - t), -12 * (1 - t) + 6 * t, 6 * (1 - t) - 12 * t, 6 * t], -1)


class Mill(Protocol):
    """A mill as the exact swept surface and the removal see it: a solid of revolution about the axis of its pose,
    whose radius at u [mm] along the axis from the pose's centre is ``radius - h(u)`` (``profile``: the table u
    increasing, h) over u's span, nothing beyond it."""

    radius: float  # its largest radius [mm] (the scale of how far along the feed it touches a point)
    teeth: int
    #: the exact surface scans a pass for a point's least margin up to radius x min(path slope, scan_slope) along the
    #: feed from the point (plus the axis's lean): how far off its centre plane a sloped path makes it touch
    scan_slope: float

    @property
    def profile(self) -> tuple[np.ndarray, np.ndarray]: ...

    @property
    def width(self) -> float: ...

    @property
    def tangential_span(self) -> tuple[float, float]:
        """How far [mm] across the tooth space (x_s, from the path point) the mill reaches."""
        ...

    def reach_angle(self, depth: float) -> float:
        """Half the angle [rad] of its circles, about the side towards the gear axis, that can reach material a
        tooth depth ``depth`` [mm] deep (pi: all round)."""
        ...

    def summary(self) -> dict: ...


@dataclass(frozen=True, eq=False)
class DiscMill:
    """The profiled disc mill: outer radius ``radius`` [mm] and its left and right cutting edges (Bezier chains in
    tool coordinates relative to the path point, from the bottom upwards)."""

    radius: float
    left: BezierChain
    right: BezierChain
    teeth: int = 12
    #: a disc's contact stays in its axial plane, turned with the path (set over: its lean): a recorded path's
    #: slope counts up to 0.05 (its vibration is no slope)
    scan_slope: ClassVar[float] = 0.05

    @cached_property
    def profile(self) -> tuple[np.ndarray, np.ndarray]:
        """The axial profile as a dense table: u [mm] along the axis (increasing) and the edge height h(u) [mm]
        above the periphery; the mill's radius at u is R - h(u)."""
        sides = []
        for chain in (self.left, self.right):
            pts = chain.dense()
            t = pts[1] - pts[0]
            if abs(t[1]) < 1e-12:
                raise ValueError("the mill edge starts horizontally: it cannot run down to the periphery")
            foot = pts[0] - t * pts[0][1] / t[1]  # along the end tangent down to y = 0
            sides.append(np.vstack([foot, pts]))
        left, right = sides
        if not left[0, 0] < right[0, 0]:
            raise ValueError(
                f"the mill's periphery has no width (edges meet at the root: {left[0, 0]:.3f} >= {right[0, 0]:.3f} "
                "mm): reduce the mill's clearance or the root form"
            )
        u = np.concatenate([left[::-1, 0], right[:, 0]])
        h = np.concatenate([left[::-1, 1], right[:, 1]])
        if np.any(np.diff(u) <= 0):
            raise ValueError("the mill edge is not single-valued along the axis (a flank section that undercuts)")
        return u, h

    @property
    def width(self) -> float:
        u, _ = self.profile
        return float(u[-1] - u[0])

    @property
    def tangential_span(self) -> tuple[float, float]:
        """The disc's axis is tangential: its axial span [mm]."""
        u, _ = self.profile
        return u[0], u[-1]

    def reach_angle(self, depth: float) -> float:
        """Half the angle of its circles within ``depth`` [mm] of the periphery, and 0.05 rad more."""
        return math.acos(max(-1.0, (self.radius - depth) / self.radius)) + 0.05

    @property
    def periphery(self) -> tuple[float, float]:
        """Axial span [mm] of the periphery (h = 0)."""
        u, h = self.profile
        flat = u[h <= 1e-12]
        return float(flat[0]), float(flat[-1])

    def height(self, u: np.ndarray) -> np.ndarray:
        """Edge height h(u) [mm]; NaN outside the mill's axial span."""
        uu, hh = self.profile
        u = np.asarray(u, dtype=float)
        return np.where((u >= uu[0]) & (u <= uu[-1]), np.interp(u, uu, hh), np.nan)

    def edge_x(self, side: Side, y: np.ndarray) -> np.ndarray:
        """x [mm] of the ``side`` edge at heights ``y`` above the periphery (the edge as x(y))."""
        u, h = self.profile
        i0 = int(np.argmin(h))
        if side == "left":
            hh, uu = h[: i0 + 1][::-1], u[: i0 + 1][::-1]
        else:
            last = np.nonzero(h <= 1e-12)[0][-1]
            hh, uu = h[last:], u[last:]
        return np.interp(y, hh, uu)

    def summary(self) -> dict:
        """The mill for measurement.json: radius, width, periphery and the edges' Bezier control points."""
        a, b = self.periphery
        return {
            "diameter_mm": 2 * self.radius,
            "teeth": self.teeth,
            "width_mm": round(self.width, 4),
            "periphery_mm": [round(a, 5), round(b, 5)],
            "edge_bezier": {
                "left": np.round(self.left.control, 6).tolist(),
                "right": np.round(self.right.control, 6).tolist(),
            },
        }
