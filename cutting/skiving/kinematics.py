"""The skiving kinematics: the crossed-axes pair of cutter and workpiece (its setup) and its ideal motion.

Machine frame (fixed): z along the work axis; the common perpendicular of the two axes along +x;
the cutter centre (the rake-face centre) at (a, 0, s), s being the carriage position along z.
The cutter axis is the work axis turned about x by ``tilt = -Sigma``, so that at the mesh point
(x = r_2, y = 0) the cutter's tooth direction lies along the gear's (domain.md section 1:
Sigma = beta2 + beta0 external, beta2 - beta0 internal; a rotation R_x(psi) turns a tooth direction
of helix angle gamma in the y-z plane into gamma - psi).

Ideal motion (domain.md section 1, "Kinematics"), with the signs of this frame:

    phi2 = ratio * phi0 - 2 pi s / p_z2

``ratio`` (signed, magnitude z0/z2) follows from equal velocity of both gears normal to the common
tooth direction at the mesh point (the common rack); the helix term turns the work back as the
cutter climbs so the same space stays under the cutter.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from cutting.errors import Problem
from cutting.flank import SIDES, flank_points
from cutting.gear import MIN_TIP_THICKNESS, Gear
from cutting.skiving.machine_geometry import MachineGeometry
from cutting.skiving.thermal_drift import ThermalDrift
from cutting.skiving.tooling import (
    Clamping,
    CutterErrors,
    RakeFace,
    blank_frame,
    chain,
    inverse,
    rake_frame,
    tooth_frames,
)

#: Below this shaft angle the sliding speed is under ~3.5 % of the cutter's peripheral speed:
#: the edge rubs instead of cutting. Modern practice is 10-30 deg (domain.md section 1).
MIN_SHAFT_ANGLE = math.radians(2.0)


def rot_x(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_z(angle: np.ndarray | float) -> np.ndarray:
    """Rotation matrices about z, shape (..., 3, 3)."""
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    out = np.zeros((*a.shape, 3, 3))  # filled in place: a run makes one per passage, np.stack cost 60 us
    out[..., 0, 0], out[..., 0, 1], out[..., 1, 0], out[..., 1, 1], out[..., 2, 2] = c, -s, s, c, 1.0
    return out


def default_cutter_tip_diameter(gear: Gear, cutter: Gear, centre_distance: float) -> float:
    """Tip diameter that makes the cutter cut the gear's root diameter at the finishing centre distance."""
    if gear.internal:
        return 2 * (gear.root_radius - centre_distance)
    return 2 * (centre_distance - gear.root_radius)


@dataclass(frozen=True)
class SkivingSetup:
    """Geometry and kinematics of skiving ``gear`` with ``cutter``.

    Parameters
    ----------
    gear: the workpiece (z2)
    cutter: the cutter as an external gear with the gear's normal basic rack (z0, beta0, x0);
        its ``tip_diameter`` None means "cut exactly the gear's root at the finishing centre distance"
    tool_speed: n0 [rpm]
    axial_feed: s [mm per workpiece revolution], always > 0; ``feed_direction`` sets the sign
    passes: radial infeed increments [mm] from first touch of the blank; the last is the finishing pass
    feed_direction: "down" (cutter moves towards -z) or "up"
    clearance: axial distance [mm] added before and after the engagement zone on every pass
    holder_diameter: the holder behind the cutter body [mm]; None means half the cutter's reference diameter
        (a typical arbor nut); the cutter body width behind the rake face is ``cutter.face_width``
    rake, cutter_errors, clamping: the rake face, the cutter's deviations and the blank's clamping
        (:mod:`cutting.skiving.tooling`); the edge is designed for the rake face of a cutter without deviations
    geometry: the machine's geometric errors (:mod:`cutting.skiving.machine_geometry`): the poses a machine makes
        (:meth:`machine_pose`) carry them; the kinematics it is set for (:meth:`cutter_pose`) do not
    thermal: the machine's thermal drift over the job (:mod:`cutting.skiving.thermal_drift`; None: none): each pass
        of the ideal kinematics takes its own share into its geometry (:func:`cutting.skiving.trajectory.ideal_passes`),
        the simulated machine its drift at each instant
    """

    gear: Gear
    cutter: Gear
    tool_speed: float
    axial_feed: float
    passes: tuple[float, ...]
    feed_direction: str = "down"
    clearance: float = 1.0
    holder_diameter: float | None = None
    rake: RakeFace = field(default_factory=RakeFace)
    cutter_errors: CutterErrors = field(default_factory=CutterErrors)
    clamping: Clamping = field(default_factory=Clamping)
    geometry: MachineGeometry = field(default_factory=MachineGeometry)
    thermal: ThermalDrift | None = None
    _cutter_tip: float | None = field(default=None, repr=False)

    @property
    def holder_diameter_value(self) -> float:
        return self.holder_diameter if self.holder_diameter is not None else self.cutter.reference_diameter / 2

    # ---- axes ---------------------------------------------------------------------------------
    @cached_property
    def shaft_angle(self) -> float:
        """Sigma = beta2 + beta0 (external) or beta2 - beta0 (internal) [rad], signed."""
        b2, b0 = self.gear.helix_angle, self.cutter.helix_angle
        return b2 - b0 if self.gear.internal else b2 + b0

    @cached_property
    def tilt(self) -> float:
        """Rotation of the cutter axis about the common perpendicular x [rad]."""
        return -self.shaft_angle

    @cached_property
    def cutter_axis(self) -> np.ndarray:
        return rot_x(self.tilt) @ np.array([0.0, 0.0, 1.0])

    @cached_property
    def final_centre_distance(self) -> float:
        """Centre distance of the finishing pass [mm], through the common rack of crossed gears:

        external a = r2 + r0 + (x2 + x0) mn;  internal a = r2 - r0 - (x2 + x0) mn.
        At this distance the cutter generates the gear's nominal tooth thickness.
        """
        g, c = self.gear, self.cutter
        shift = (g.x + c.x) * g.mn
        if g.internal:
            return g.reference_radius - c.reference_radius - shift
        return g.reference_radius + c.reference_radius + shift

    @cached_property
    def cutter_tip_diameter(self) -> float:
        """d_a0 [mm]: as given in the job, else the one that cuts the gear's root diameter."""
        if self.cutter.tip_diameter is not None:
            return float(self.cutter.tip_diameter)
        return default_cutter_tip_diameter(self.gear, self.cutter, self.final_centre_distance)

    @cached_property
    def generated_root_diameter(self) -> float:
        """Root diameter the cutter tip cuts at the finishing centre distance [mm].

        The closest (external) / farthest (internal) point of the tilted tip circle from the work
        axis lies on the common perpendicular, so it is a -/+ r_a0 exactly.
        """
        ra0 = self.cutter_tip_diameter / 2
        a = self.final_centre_distance
        return 2 * (a + ra0) if self.gear.internal else 2 * (a - ra0)

    @cached_property
    def touch_centre_distance(self) -> float:
        """Centre distance at which the cutter tip first touches the blank (tip diameter) [mm]."""
        ra0 = self.cutter_tip_diameter / 2
        return self.gear.tip_radius - ra0 if self.gear.internal else self.gear.tip_radius + ra0

    @cached_property
    def full_depth(self) -> float:
        """Radial infeed from first touch to the finishing centre distance [mm]."""
        return abs(self.touch_centre_distance - self.final_centre_distance)

    @cached_property
    def pass_depths(self) -> tuple[float, ...]:
        """Cumulative radial depth after each pass, measured from first touch [mm]."""
        return tuple(float(v) for v in np.cumsum(self.passes))

    @cached_property
    def pass_centre_distances(self) -> tuple[float, ...]:
        """Centre distance of every pass [mm]; the last equals the finishing one when the passes sum to the depth."""
        sign = 1.0 if self.gear.internal else -1.0
        return tuple(self.touch_centre_distance + sign * d for d in self.pass_depths)

    # ---- kinematics ---------------------------------------------------------------------------
    @cached_property
    def speed_ratio(self) -> float:
        """Signed omega2 / omega0 of the generating motion (magnitude z0/z2 for any profile shifts).

        Both bodies roll on their own reference cylinders against the common rack: their velocities at
        their pitch points agree along the direction that lies in the rack plane and is normal to the
        common tooth direction.
        """
        g = self.gear
        p2 = np.array([g.reference_radius, 0.0, 0.0])
        centre = np.array([self.final_centre_distance, 0.0, 0.0])
        r0 = self.cutter.reference_radius
        p0 = centre + np.array([r0 if g.internal else -r0, 0.0, 0.0])
        tooth_dir = np.array([0.0, math.sin(g.helix_angle), math.cos(g.helix_angle)])
        n = np.cross([1.0, 0.0, 0.0], tooth_dir)
        v_work = np.cross([0.0, 0.0, 1.0], p2) @ n
        v_tool = np.cross(self.cutter_axis, p0 - centre) @ n
        return float(v_tool / v_work)

    @cached_property
    def differential_rotation_per_mm(self) -> float:
        """Additional work rotation B4 per mm of carriage travel along +z: -2 pi / p_z2 [rad/mm] (0 spur)."""
        return 0.0 if self.gear.helix_angle == 0.0 else -2 * math.pi / self.gear.lead

    @cached_property
    def work_speed(self) -> float:
        """n2 = n0 z0 / z2 [rpm] (magnitude)."""
        return self.tool_speed * self.cutter.teeth / self.gear.teeth

    @cached_property
    def cutting_speed(self) -> float:
        """Cutting speed at the pitch point v = pi d0 n0 sin|Sigma| / cos(beta2) [m/min]."""
        d0 = self.cutter.reference_diameter
        return math.pi * d0 * self.tool_speed * math.sin(abs(self.shaft_angle)) / math.cos(self.gear.helix_angle) / 1000

    def engagement_half_length(self, centre_distance: float) -> float:
        """Axial half-extent [mm] of the part of the cutter tip circle inside the blank at ``centre_distance``.

        Tip circle point t: (a -/+ r_a0 cos t, r_a0 sin t cos(Sigma), r_a0 sin t sin(Sigma)) in the frame
        above; inside the blank where its distance to the work axis passes the blank's tip radius.
        """
        lo, hi = self.engagement_range(centre_distance)
        return (hi - lo) / 2

    def engagement_range(self, centre_distance: float) -> tuple[float, float]:
        """Axial extent [z_lo, z_hi] [mm], from the carriage position s, of the part of the rake face's tip circle
        inside the blank at ``centre_distance`` (symmetric about s unless the rake face is offset along the axis)."""
        ra0 = self.cutter_tip_diameter / 2
        h = self.face_height(ra0)
        sgn = 1.0 if self.gear.internal else -1.0
        if h == 0.0:  # the tip circle through the axes' common perpendicular: symmetric, half a turn is enough
            t = np.linspace(0.0, math.pi, 20001)
            x = centre_distance + sgn * ra0 * np.cos(t)
            y = ra0 * np.sin(t) * math.cos(self.shaft_angle)
            r = np.hypot(x, y)
            inside = r >= self.gear.tip_radius if self.gear.internal else r <= self.gear.tip_radius
            if not inside.any():
                return 0.0, 0.0
            half = float(ra0 * np.sin(t[inside]).max() * abs(math.sin(self.shaft_angle)))
            return -half, half
        t = np.linspace(-math.pi, math.pi, 40001)
        p = np.stack([-sgn * ra0 * np.cos(t), ra0 * np.sin(t), np.full_like(t, h)], -1) @ rot_x(self.tilt).T
        x, y, z = centre_distance + p[:, 0], p[:, 1], p[:, 2]
        r = np.hypot(x, y)
        inside = r >= self.gear.tip_radius if self.gear.internal else r <= self.gear.tip_radius
        if not inside.any():
            return 0.0, 0.0
        return float(z[inside].min()), float(z[inside].max())

    @cached_property
    def pass_travel(self) -> tuple[float, ...]:
        """Axial carriage travel of every pass: face width + engagement + 2 x clearance [mm]."""
        return tuple(
            self.gear.face_width + 2 * self.engagement_half_length(a) + 2 * self.clearance
            for a in self.pass_centre_distances
        )

    @cached_property
    def pass_middles(self) -> tuple[float, ...]:
        """The carriage position at the middle of every pass [mm]: 0 unless an offset rake face moves the
        engagement along the axis, then the position that centres the engagement on the face."""
        return tuple(-sum(self.engagement_range(a)) / 2 for a in self.pass_centre_distances)

    @cached_property
    def pass_times(self) -> tuple[float, ...]:
        """Machine time of every pass [s] at feed s per work revolution and work speed n2."""
        feed_rate = self.axial_feed * self.work_speed / 60.0  # mm/s
        return tuple(travel / feed_rate for travel in self.pass_travel)

    # ---- interference -------------------------------------------------------------------------
    def edge_points(self, samples: int = 40) -> np.ndarray:
        """Involute cutting edge of cutter tooth 0 in the cutter frame (rake plane z0 = 0), shape (n, 3).

        Both flanks from the depth that reaches the gear's root up to the tip, plus the tip land.
        """
        c = self.cutter
        ra0 = self.cutter_tip_diameter / 2
        r_low = max(c.base_radius * 1.0000001, ra0 - self.full_depth - 0.25 * c.mn)
        radii = np.linspace(r_low, ra0, samples)
        xi = np.sqrt(radii**2 - c.base_radius**2) / c.base_radius
        pts = [flank_points(c, side, xi, 0.0, 0) for side in SIDES]
        half = float(c.half_thickness_angle(ra0))
        ang = np.linspace(-half, half, max(3, samples // 4))
        pts.append(np.stack([ra0 * np.cos(ang), ra0 * np.sin(ang), np.zeros_like(ang)], -1))
        return np.concatenate(pts)

    @cached_property
    def cutter_phase(self) -> float:
        """Cutter angle offset that points cutter tooth 0 at the mesh point when phi0 = 0 [rad]."""
        return 0.0 if self.gear.internal else math.pi

    @cached_property
    def work_phase(self) -> float:
        """Work angle offset that puts the centre of space 0 (between teeth 0 and 1) on +x when phi2 = 0 [rad]."""
        return -math.pi / self.gear.teeth

    def cutter_pose(self, phi0: np.ndarray, s: np.ndarray | float = 0.0, centre_distance: float | None = None):
        """Ideal pose of the cutter frame in the rotating work frame.

        Returns ``(R, t)`` with shapes (n, 3, 3) and (n, 3) such that a cutter-frame point p maps to
        ``R @ p + t`` in the work frame, for cutter angles ``phi0`` [rad] and carriage positions ``s`` [mm].
        phi2 = speed_ratio * phi0 + differential_rotation_per_mm * s + work_phase.
        """
        return self._pose(phi0, s, centre_distance, None)

    def machine_pose(self, phi0: np.ndarray, s: np.ndarray | float = 0.0, centre_distance: float | None = None):
        """:meth:`cutter_pose` as the machine as built makes it from the same commanded axes: the shaft angle, the
        centre distance, the cutter's offset, the carriage's squareness, the screw's periodic error and the spindles'
        encoders of :attr:`geometry` (:mod:`cutting.skiving.machine_geometry`; the spindle's error motion is the
        blank's, in :attr:`blank_frame`). The nominal pose where the machine is exact."""
        return self._pose(phi0, s, centre_distance, None if self.geometry.exact else self.geometry)

    def _pose(self, phi0, s, centre_distance, g: MachineGeometry | None):
        """The poses of :meth:`cutter_pose` (``g`` None: the nominal chain, bit for bit) or :meth:`machine_pose`."""
        phi0 = np.atleast_1d(np.asarray(phi0, dtype=float))
        s_arr = np.broadcast_to(np.asarray(s, dtype=float), phi0.shape)
        a = self.final_centre_distance if centre_distance is None else centre_distance
        b2 = self.speed_ratio * phi0 + self.differential_rotation_per_mm * s_arr
        centre = np.stack([np.full_like(phi0, a), np.zeros_like(phi0), s_arr], -1)
        if g is None:
            back = rot_z(-(b2 + self.work_phase))
            rot = back @ rot_x(self.tilt) @ rot_z(phi0 + self.cutter_phase)
        else:
            e1, e2 = g.encoder_errors(phi0, b2)  # the spindles held at their encoders' readings stand behind by these
            back = rot_z(-(b2 - e2 + self.work_phase))
            rot = back @ rot_x(self.tilt + g.shaft_angle_error) @ rot_z(phi0 - e1 + self.cutter_phase)
            centre = centre + g.head_offset(s_arr)
        return rot, np.matmul(back, centre[:, :, None])[:, :, 0]

    def new_tool(self) -> SkivingSetup:
        """This setup with the tool as it was new (no regrind): the edge is designed for it. A regrind of depth d
        along the axis took d tan(alpha_a) off the tip radius and d tan(alpha_a) / mn off the profile shift (the
        relief of :class:`cutting.skiving.working_angles.Relief`)."""
        r = self.rake
        if not r.regrind:
            return self
        d = r.relief_depth(self.cutter.helix_angle) * math.tan(r.clearance_angle)
        cutter = replace(
            self.cutter, profile_shift=self.cutter.x + d / self.cutter.mn, tip_diameter=self.cutter_tip_diameter + 2 * d
        )
        return replace(self, cutter=cutter, rake=replace(r, regrind=0.0))

    @cached_property
    def rake_frame(self) -> np.ndarray:
        """Tooth 0's rake frame in the cutter's frame as designed (no deviations), (3, 4): what the edge is made in."""
        c = self.cutter
        return rake_frame(self.rake, c.helix_angle, c.reference_radius, *self._face_layout)

    @property
    def _face_layout(self) -> tuple[float, float]:
        """(body side, tooth 0's centre angle at the face) for :func:`cutting.skiving.tooling.rake_frame` (the end
        plane without a rake angle needs neither)."""
        r = self.rake
        if r.kind == "plane" and not r.rake_angle:
            return -1.0, 0.0
        c = self.cutter
        xi = math.sqrt(max(c.reference_radius**2 - c.base_radius**2, 0.0)) / c.base_radius
        centre = sum(float(np.arctan2(*flank_points(c, s, xi, r.offset, 0)[1::-1])) for s in ("left", "right")) / 2
        return (self.body_side if r.rake_angle else -1.0), centre

    def face_height(self, radius: float) -> float:
        """Where the rake face of tooth 0 crosses its radial line at ``radius`` along the cutter axis [mm] (the
        offset; a rake angle moves it by tan(gamma) per mm off the reference circle)."""
        return float(self.rake_frame[2, 3] + self.rake_frame[2, 0] * self.face_radius(radius))

    def face_radius(self, radius: float) -> float:
        """The rake frame's x on tooth 0's centre line (y = 0) that lies at ``radius`` from the cutter axis: the same
        unless a rake angle tilts the face about its tangential axis (then the reference circle's point stays)."""
        q = self.rake_frame
        if not self.rake.rake_angle:
            return radius
        x = float(radius)
        for _ in range(4):  # the radius is linear in x but for the stepped face's lean: Newton converges at once
            p, d = q[:, 0] * x + q[:, 3], q[:, 0]
            r = math.hypot(p[0], p[1])
            x -= (r - radius) / ((p[0] * d[0] + p[1] * d[1]) / r)
        return x

    def rake_pose(self, phi0: np.ndarray, s: np.ndarray | float = 0.0, centre_distance: float | None = None):
        """:meth:`cutter_pose` of tooth 0's designed rake frame (its edge's plane): ``(R, t)`` as there."""
        rot, t = self.cutter_pose(phi0, s, centre_distance)
        q = self.rake_frame
        return rot @ q[:, :3], t + rot @ q[:, 3]

    @cached_property
    def body_side(self) -> float:
        """+1 when the cutter body lies on the cutter frame's +z side of the rake face, -1 on its -z side: behind the
        face, which faces the cutting direction (the relative velocity of tooth 0's pitch point at the mesh; the
        feed, under 1 % of it, left out). External jobs cut along +z of the cutter frame, internal ones along -z."""
        p = np.array([self.cutter.reference_radius, 0.0, 0.0])
        h = 1e-7
        (r0, t0), (r1, t1) = self.cutter_pose(np.array([-h])), self.cutter_pose(np.array([h]))
        v = (r1[0] @ p + t1[0]) - (r0[0] @ p + t0[0])
        return -1.0 if float(v @ self.cutter_pose(np.array([0.0]))[0][0][:, 2]) > 0 else 1.0

    @cached_property
    def tooth_frames(self) -> np.ndarray:
        """Every cutter tooth's rake frame in the tool spindle's frame, (z0, 3, 4): its angle, pitch deviation, the
        rake face and the cutter's runout (:func:`cutting.skiving.tooling.tooth_frames`)."""
        c = self.cutter
        return tooth_frames(
            self.rake,
            self.cutter_errors,
            c.teeth,
            c.helix_angle,
            c.reference_radius,
            self.cutter_tip_diameter / 2,
            *self._face_layout,
        )

    @cached_property
    def blank_frame(self) -> np.ndarray:
        """The work spindle's frame in the blank's, (3, 4): the clamping's eccentricity and tilt undone, and the
        spindle's synchronous error motion (:meth:`MachineGeometry.spindle_placement`: the clamped blank turns with
        the rotor)."""
        clamped = blank_frame(self.clamping, self.gear.reference_radius)
        if not (self.geometry.work_spindle_radial_error or self.geometry.work_spindle_tilt_error):
            return clamped
        return chain(clamped, inverse(self.geometry.spindle_placement()))

    def passage_frames(self, m: np.ndarray) -> np.ndarray:
        """The rake frames of the teeth at the mesh at cutter pitches ``m`` (tooth (-m) mod z0), (n, 3, 4)."""
        return self.tooth_frames[(-np.asarray(m, dtype=np.int64)) % self.cutter.teeth]

    def edge_in_work_frame(self, edge: np.ndarray, phi0: np.ndarray, teeth: np.ndarray | None = None) -> np.ndarray:
        """Edge points of every cutter tooth (or of ``teeth``) for each cutter angle, in the work frame (s = 0), shape
        (n, m, 3): per angle the teeth's points one tooth after the other."""
        c = self.cutter
        teeth = np.arange(c.teeth) if teeth is None else np.asarray(teeth)
        per_tooth = np.einsum("kij,nj->kni", rot_z(2 * np.pi * teeth / c.teeth), edge).reshape(-1, 3)
        rot, t = self.cutter_pose(phi0)
        # rot[s] @ p for every pose s and point p, as one matrix product (einsum's loop took 4x as long)
        return (rot.reshape(-1, 3) @ per_tooth.T).reshape(len(rot), 3, -1).transpose(0, 2, 1) + t[:, None, :]

    def edge_intrusion(self, steps: int = 720) -> float:
        """Deepest intrusion [mm] of the ideal involute edge into the nominal gear material.

        Samples one cutter pitch of the ideal motion at the finishing centre distance (the motion is
        periodic with it). Material: the involute region between the gear's form limit and its tip,
        and everything beyond the root circle. Positive means the edge would cut the gear's teeth.

        Every tooth is first sampled at every INTRUSION_COARSE-th angle (and the last): a point moves at most D (the
        largest chord between those angles) to any angle between, so a tooth with no point within D of the involute
        band and its depth beyond the root more than 2 D below the deepest found cannot hold the deepest point at
        any angle (the depth beyond the root changes by at most the distance moved). Only the other teeth (those
        near the mesh) are sampled at every angle: the same maximum, at a fraction of the work.
        """
        phi0 = np.linspace(0.0, 2 * np.pi / self.cutter.teeth, steps, endpoint=False)
        edge = self.edge_points()
        coarse = np.unique(np.append(np.arange(0, steps, INTRUSION_COARSE), steps - 1))
        pts = self.edge_in_work_frame(edge, phi0[coarse])  # (angles, teeth x points, 3)
        moved = float(np.linalg.norm(np.diff(pts, axis=0), axis=-1).max()) if len(coarse) > 1 else np.inf
        depth, near_band = self._depth(pts.reshape(-1, 3), moved)
        per_tooth = depth.reshape(len(coarse), self.cutter.teeth, -1).max(axis=(0, 2))
        band_tooth = near_band.reshape(len(coarse), self.cutter.teeth, -1).any(axis=(0, 2))
        teeth = np.flatnonzero(band_tooth | (per_tooth >= per_tooth.max() - 2 * moved))
        fine, _ = self._depth(self.edge_in_work_frame(edge, phi0, teeth).reshape(-1, 3), 0.0)
        return float(max(fine.max(), per_tooth.max()))

    def _depth(self, pts: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
        """Per point (n, 3) of the work frame its depth into the nominal gear [mm] (> 0 inside material: beyond the
        root circle, or inside a tooth's involute band by the arc to its flank), and whether it lies within ``reach``
        [mm] of that band radially."""
        g = self.gear
        r = np.hypot(pts[:, 0], pts[:, 1])
        fillet = g.rack.rho_f * (1 - math.sin(g.alpha_n)) * g.mn
        if g.internal:
            lo, hi = max(g.tip_radius, g.base_radius), g.root_radius - fillet
            depth = r - g.root_radius
        else:
            lo, hi = max(g.rack_form_diameter / 2, g.base_radius), g.tip_radius
            depth = g.root_radius - r
        band = (r >= lo) & (r <= hi)
        if band.any():
            rb = r[band]
            theta = np.arctan2(pts[band, 1], pts[band, 0])
            centre = 2 * np.pi / g.lead * pts[band, 2] if g.helix_angle else 0.0
            d = theta - centre
            pitch = 2 * np.pi / g.teeth
            d = d - pitch * np.round(d / pitch)
            psi = np.asarray(g.half_thickness_angle(rb))
            depth[band] = np.maximum(depth[band], (psi - np.abs(d)) * rb)  # arc depth into the tooth
        return depth, (r >= lo - reach) & (r <= hi + reach)


#: edge_intrusion's first look at every tooth: every this many of its angles
INTRUSION_COARSE = 24

#: Intrusion of the ideal involute edge into the nominal teeth that counts as interference [mm].
#: The involute edge itself deviates from the exact (conjugate) edge by a few micrometres
#: (domain.md section 1), so the threshold sits well above that.
INTERFERENCE_TOLERANCE = 0.010

#: An internal gear's cutter must fit through the bore (tip diameter d_a2) with this radial clearance,
#: in multiples of mn, so it can be retracted radially to the axis and withdrawn axially after the cut.
INTERNAL_RETRACT_CLEARANCE = 1.0


def check_setup(setup: SkivingSetup) -> list[Problem]:
    """Every reason why ``setup.cutter`` cannot skive ``setup.gear`` with ``setup.passes``."""
    for fatal in (_shaft_angle_problem, _internal_cutter_size_problem, _base_circle_problem):
        problem = fatal(setup)
        if problem is not None:  # the other checks would be meaningless
            return [problem]
    checks = (_pointed_tip_problem, _root_diameter_problem, _passes_problem, _interference_problem)
    return [problem for problem in (check(setup) for check in checks) if problem is not None]


def _shaft_angle_problem(setup: SkivingSetup) -> Problem | None:
    """A shaft angle below MIN_SHAFT_ANGLE: no sliding, so no cutting speed."""
    g, c = setup.gear, setup.cutter
    if abs(setup.shaft_angle) < MIN_SHAFT_ANGLE:
        sigma = math.degrees(setup.shaft_angle)
        need = (
            "a helical cutter"
            if g.helix_angle == 0
            else f"a cutter helix other than {math.degrees(g.helix_angle):+.1f} deg"
        )
        return Problem(
            "cutter.helix_angle",
            round(math.degrees(c.helix_angle), 6),
            f"the shaft angle Sigma = {sigma:+.2f} deg leaves no cutting speed (skiving cuts by the sliding "
            f"of crossed axes, v ~ sin(Sigma))",
            f"choose {need} so that |Sigma| >= {math.degrees(MIN_SHAFT_ANGLE):.0f} deg (10-30 deg is usual)",
        )
    return None


def _internal_cutter_size_problem(setup: SkivingSetup) -> Problem | None:
    """An internal gear's cutter too large to be retracted through the bore after the cut."""
    g, c = setup.gear, setup.cutter
    if g.internal and (
        setup.final_centre_distance <= c.mn
        or setup.cutter_tip_diameter > g.tip_diameter_value - 2 * INTERNAL_RETRACT_CLEARANCE * g.mn
    ):
        return Problem(
            "cutter.teeth",
            c.teeth,
            f"the cutter (d0 = {c.reference_diameter:.3f} mm, tip {setup.cutter_tip_diameter:.3f} mm) is too large "
            f"for the internal gear: it must pass the bore d_a2 = {g.tip_diameter_value:.3f} mm with "
            f"{INTERNAL_RETRACT_CLEARANCE:g} mn clearance on the radius to be retracted after the cut",
            "use a cutter with clearly fewer teeth than the gear (z0 <= z2 - 10 is a safe start)",
        )
    return None


def _base_circle_problem(setup: SkivingSetup) -> Problem | None:
    """A cutter tip circle inside the cutter's base circle: no involute edge."""
    c = setup.cutter
    if setup.cutter_tip_diameter / 2 <= c.base_radius:
        return Problem(
            "cutter.tip_diameter",
            round(setup.cutter_tip_diameter, 6),
            f"the cutter tip circle lies inside its base circle d_b0 = {c.base_diameter:.3f} mm: no involute edge",
            f"use a tip diameter above {c.base_diameter:.3f} mm",
        )
    return None


def _pointed_tip_problem(setup: SkivingSetup) -> Problem | None:
    """Cutter teeth whose tip land is below MIN_TIP_THICKNESS modules."""
    c = setup.cutter
    tip_thickness = c.normal_thickness_at(setup.cutter_tip_diameter)
    if tip_thickness < MIN_TIP_THICKNESS * c.mn:
        return Problem(
            "cutter.tip_diameter",
            round(setup.cutter_tip_diameter, 6),
            f"the cutter teeth are pointed: tip land {tip_thickness:.3f} mm < {MIN_TIP_THICKNESS} mn "
            f"(cutter profile shift {c.x:+.3f})",
            "reduce the cutter tip diameter or its profile shift, or cut a shallower gear",
        )
    return None


def _root_diameter_problem(setup: SkivingSetup) -> Problem | None:
    """A given cutter tip diameter that does not cut the given gear root diameter (within 0.01 mm)."""
    g, c = setup.gear, setup.cutter
    if c.tip_diameter is None or g.root_diameter is None:
        return None
    gen = setup.generated_root_diameter
    if abs(gen - g.root_diameter_value) > 0.01:
        want = default_cutter_tip_diameter(g, c, setup.final_centre_distance)
        return Problem(
            "cutter.tip_diameter",
            c.tip_diameter,
            f"at the finishing centre distance {setup.final_centre_distance:.4f} mm this cutter cuts a root "
            f"diameter of {gen:.4f} mm, but gear.root_diameter = {g.root_diameter_value:.4f} mm",
            f"set cutter.tip_diameter = {want:.4f} or drop one of the two keys",
        )
    return None


def _passes_problem(setup: SkivingSetup) -> Problem | None:
    """Radial infeed increments that are not positive, or that reach deeper than the tooth."""
    if not setup.passes or setup.passes[0] <= 0 or any(p < 0 for p in setup.passes):
        return Problem(
            "process.passes",
            list(setup.passes),
            "the first radial infeed increment must be > 0 mm and none negative (a 0 after it is a spring pass)",
            "give increments like [2.0, 1.5, 0.8, 0.2] or, with a spring pass, [2.0, 1.5, 0.8, 0.2, 0.0]",
        )
    if sum(setup.passes) > setup.full_depth + 1e-6:
        return Problem(
            "process.passes",
            list(setup.passes),
            f"the increments sum to {sum(setup.passes):.4f} mm, deeper than the tooth: from first touch of the "
            f"blank to the finishing centre distance is {setup.full_depth:.4f} mm",
            f"make the increments sum to at most {setup.full_depth:.4f} mm",
        )
    return None


def _interference_problem(setup: SkivingSetup) -> Problem | None:
    """The ideal involute edge entering the nominal teeth by more than INTERFERENCE_TOLERANCE."""
    g, c = setup.gear, setup.cutter
    intrusion = setup.edge_intrusion()
    if intrusion > INTERFERENCE_TOLERANCE:
        sigma = math.degrees(setup.shaft_angle)
        where = (
            "tip interference with the internal gear's teeth"
            if g.internal
            else "the cutter edge undercuts or fouls the teeth"
        )
        return Problem(
            "cutter.teeth",
            c.teeth,
            f"{where}: the cutting edge enters the nominal teeth by {intrusion:.3f} mm under the ideal motion "
            f"(Sigma = {sigma:+.1f} deg)",
            "use fewer cutter teeth"
            + (" (internal gears need z2 - z0 well above 8)" if g.internal else "")
            + ", another cutter helix angle, or change the profile shifts",
        )
    return None


def reground(setup: SkivingSetup, regrind: float) -> SkivingSetup:
    """``setup`` (a new tool) with ``regrind`` [mm] ground off its rake face: the cutter is the relieved tooth's
    section that much deeper (its profile shift and tip smaller, :meth:`SkivingSetup.new_tool` undoes it); the
    finishing centre distance follows from it, as a shop sets the reground tool to the same tooth thickness."""
    if not regrind:
        return setup
    r = replace(setup.rake, regrind=regrind)
    d = r.relief_depth(setup.cutter.helix_angle) * math.tan(r.clearance_angle)
    c = setup.cutter
    cutter = replace(c, profile_shift=c.x - d / c.mn, tip_diameter=setup.cutter_tip_diameter - 2 * d)
    return replace(setup, cutter=cutter, rake=r)
