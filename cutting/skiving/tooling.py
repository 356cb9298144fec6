"""Where each cutter tooth's rake face and the workpiece really are: the cutter's rake face, its pitch deviations and
its runout on the tool spindle, and the blank's clamping on the work spindle, as rigid frames.

A tooth's rake frame carries the points of its edge (the planar outline of :mod:`cutting.skiving.edge`, x along the
tooth's radial line, the rake face in z = 0) into the cutter spindle's frame; the blank frame carries points of the
work spindle's frame into the blank's own (the gear is cut and measured about its own axis, as a gear measuring
machine centres it on its bore). Frames are (3, 4) arrays [R | t]: p -> R p + t. Angles in radians, lengths in mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

RAKE_FACES = ("plane", "stepped")
#: the teeth's tip clearance when a job gives none [rad]: 6 deg, a guess from shaper-cutter practice (docs/cutter.md)
DEFAULT_CLEARANCE_ANGLE = math.radians(6.0)


@dataclass(frozen=True)
class RakeFace:
    """The rake face as the tool designer specifies it.

    kind: "plane" (all teeth in one plane normal to the cutter axis, the end plane) or "stepped" (each tooth's
        face normal to its tooth direction on the reference cylinder: a step between neighbouring teeth)
    offset: the face's position along the cutter axis from the axes' common perpendicular [mm] (the face moves
        along +z of the cutter frame; the teeth are designed for it)
    clearance_angle: the tip clearance alpha_a of the teeth's conical relief behind the face [rad]
        (:class:`cutting.skiving.working_angles.Relief`)
    regrind: what has been ground off the face since the tool was new [mm, along the face's normal]: the face now
        cuts the relieved teeth that much deeper (:func:`relief_depth`); the tool is set again with its face at
        ``offset``
    rake_angle: the rake angle gamma [rad] of the face along each tooth's radial line: the face falls away behind
        the tip edge towards the body by tan(gamma) per mm inwards, through the reference circle at ``offset``.
        A conical face (the plane face) is ground as a cone; over one tooth it is its tangent plane along the
        tooth's centre line (:func:`rake_frame`; the cone departs from it by tan(gamma) y^2 / 2r, docs/cutter.md)
    """

    kind: str = "plane"
    offset: float = 0.0
    clearance_angle: float = DEFAULT_CLEARANCE_ANGLE
    regrind: float = 0.0
    rake_angle: float = 0.0

    def relief_depth(self, helix_angle: float) -> float:
        """The regrind's depth along the cutter axis [mm]: the face's normal leans by the rake angle (and a stepped
        face's by the helix angle)."""
        lean = math.cos(self.rake_angle) * (1.0 if self.kind == "plane" else math.cos(helix_angle))
        return self.regrind / lean


#: a profile deviation: the same on every tooth, or one value per tooth [mm]
Deviation = float | tuple[float, ...]


@dataclass(frozen=True)
class CutterErrors:
    """The cutter's deviations from its design (shaper-cutter tolerance classes AA, A, B).

    radial_runout: total indicator reading at the tip [mm]: the cutter's centre is radial_runout / 2 off the spindle
        axis, towards ``radial_runout_phase`` [rad] from tooth 0 (the tooth at that angle runs farthest out)
    axial_runout: total indicator reading of the rake face at the tip circle [mm]: the cutter's axis tilted by
        axial_runout / d_a0 against the spindle's, the face farthest along +z at ``axial_runout_phase`` [rad]
    pitch: single pitch deviations f_pt [mm], one per cutter pitch (pitch k lies between teeth k - 1 and k, counted
        along +phi of the cutter), summing to zero; () for a cutter without pitch deviations. The reference circle's
        arc: tooth k stands (f_pt,1 + ... + f_pt,k) / r0 ahead of its nominal angle.
    profile_slope, profile_form: each flank's (left, right) profile slope f_H and form f_f deviation [mm]
        (:mod:`cutting.skiving.cutter_profile`): a number, the same on every tooth, or a tuple of z0 numbers, one
        per tooth (tooth k at k pitches along +phi from tooth 0)
    """

    radial_runout: float = 0.0
    radial_runout_phase: float = 0.0
    axial_runout: float = 0.0
    axial_runout_phase: float = 0.0
    pitch: tuple[float, ...] = ()
    profile_slope: tuple[Deviation, Deviation] = (0.0, 0.0)
    profile_form: tuple[Deviation, Deviation] = (0.0, 0.0)

    @property
    def profile(self) -> bool:
        """Whether the edge carries profile deviations."""
        return any(np.any(np.asarray(v) != 0) for v in (*self.profile_slope, *self.profile_form))

    @property
    def profile_per_tooth(self) -> bool:
        """Whether the teeth's profile deviations differ (each tooth then cuts with its own edge)."""
        return any(np.ptp(np.atleast_1d(v)) > 0 for v in (*self.profile_slope, *self.profile_form))

    def tooth_profile(self, tooth: int | None = None) -> tuple[tuple[float, float], tuple[float, float]]:
        """((slope left, right), (form left, right)) [mm] of cutter tooth ``tooth``; None: the teeth's mean."""

        def of(v: Deviation) -> float:
            a = np.atleast_1d(np.asarray(v, dtype=float))
            return float(a.mean() if tooth is None or len(a) == 1 else a[tooth])

        slope, form = self.profile_slope, self.profile_form
        return (of(slope[0]), of(slope[1])), (of(form[0]), of(form[1]))


@dataclass(frozen=True)
class Clamping:
    """The blank on the work spindle.

    eccentricity: its axis this far [mm] off the spindle axis, towards ``eccentricity_phase`` [rad] (an angle of the
        blank's frame: 0 is the centre of space 0)
    tilt: axial runout of its face at the reference diameter [mm]: the axis tilted by tilt / d against the spindle's,
        about the mid-face point, the face farthest along +z at ``tilt_phase`` [rad]
    """

    eccentricity: float = 0.0
    eccentricity_phase: float = 0.0
    tilt: float = 0.0
    tilt_phase: float = 0.0


IDENTITY = np.hstack([np.eye(3), np.zeros((3, 1))])


def frame(rot: np.ndarray, origin: np.ndarray | tuple[float, float, float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """The (3, 4) frame [rot | origin]."""
    return np.hstack([np.asarray(rot, dtype=float), np.asarray(origin, dtype=float).reshape(3, 1)])


def chain(*frames: np.ndarray) -> np.ndarray:
    """The frames applied right to left: chain(A, B) p = A (B p). Broadcasts over leading axes."""
    out = frames[-1]
    for f in reversed(frames[:-1]):
        rot = f[..., :3] @ out[..., :3]
        org = (f[..., :3] @ out[..., 3:])[..., 0] + f[..., 3]
        out = np.concatenate([rot, org[..., None]], -1)
    return out


def inverse(f: np.ndarray) -> np.ndarray:
    rt = np.swapaxes(f[..., :3], -1, -2)
    return np.concatenate([rt, -(rt @ f[..., 3:])], -1)


def in_blank_frame(
    rot: np.ndarray, origin: np.ndarray, tooth: np.ndarray, blank: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Poses (rot (..., 3, 3), origin (..., 3)) of the cutter spindle in the work spindle's frame turned into poses
    of the rake frame ``tooth`` ((..., 3, 4)) in the blank's frame: blank o pose o tooth (contiguous arrays: the
    kernels read them)."""
    r = rot @ tooth[..., :3]
    o = (rot @ tooth[..., 3:])[..., 0] + origin
    r = np.ascontiguousarray(blank[:, :3] @ r)
    o = np.ascontiguousarray(o @ blank[:, :3].T + blank[:, 3])
    return r, o


def rotation(axis: np.ndarray | tuple[float, float, float], angle: float) -> np.ndarray:
    """Rodrigues' rotation about the unit ``axis`` by ``angle`` [rad]."""
    k = np.asarray(axis, dtype=float)
    k = k / np.linalg.norm(k)
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * (kx @ kx)


def turn_z(angle: float) -> np.ndarray:
    """The turn about z (cos and sin directly: a cutter without deviations keeps the poses bit for bit)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _tilt(amount: float, phase: float) -> np.ndarray:
    """The rotation that lifts a face point at angle ``phase`` along +z by ``amount`` * its radius (first order):
    about the in-plane axis (sin phase, -cos phase, 0)."""
    return rotation((math.sin(phase), -math.cos(phase), 0.0), amount)


def rake_frame(
    rake: RakeFace,
    helix_angle: float,
    reference_radius: float = 0.0,
    body_side: float = -1.0,
    centre_angle: float = 0.0,
) -> np.ndarray:
    """Tooth 0's rake frame in the cutter body's frame (tooth 0 about +x): the end plane moved to ``rake.offset``.

    Any other face is laid out about the tooth's centre line in it: turned about the axis by ``centre_angle`` (where
    the tooth's centre crosses the reference circle at the face's height: a helical cutter's teeth wind, so an offset
    face meets tooth 0 off +x), then a stepped face turned about that radial line (x) so that its normal is the tooth
    direction on the reference cylinder, (0, sin beta0, cos beta0) for a helix angle beta0 (right hand positive, the
    convention of :func:`cutting.flank.flank_points`), then a rake angle gamma turns the face about its tangential
    axis (y) through the reference circle's point (r0, 0) by body_side * gamma: inwards of r0 the face recedes towards
    the body (``body_side``: +1 on the cutter frame's +z, :attr:`SkivingSetup.body_side`), the wedge sharpens. The
    plane face without a rake angle keeps the end plane's own axes (bit for bit the cut it always made)."""
    if rake.kind == "plane" and not rake.rake_angle:
        return frame(np.eye(3), (0.0, 0.0, rake.offset))
    turn = turn_z(centre_angle)
    step = np.eye(3) if rake.kind == "plane" else rotation((1.0, 0.0, 0.0), -helix_angle)
    tilt = rotation((0.0, 1.0, 0.0), body_side * rake.rake_angle)
    pivot = np.array([reference_radius, 0.0, 0.0])
    rot = turn @ step
    return frame(rot @ tilt, rot @ (pivot - tilt @ pivot) + np.array([0.0, 0.0, rake.offset]))


def mount_frame(errors: CutterErrors, tip_radius: float) -> np.ndarray:
    """The cutter body's frame in the tool spindle's: its radial runout's offset and its axial runout's tilt."""
    e = errors.radial_runout / 2
    phase = errors.radial_runout_phase
    tilt = _tilt(errors.axial_runout / (2 * tip_radius), errors.axial_runout_phase)
    return frame(tilt, (e * math.cos(phase), e * math.sin(phase), 0.0))


def pitch_positions(pitch: tuple[float, ...], teeth: int) -> np.ndarray:
    """Each tooth's cumulative pitch deviation F_p,k [mm] (tooth 0: 0) from the single pitch deviations."""
    if not pitch:
        return np.zeros(teeth)
    f = np.asarray(pitch, dtype=float)
    return np.concatenate([[0.0], np.cumsum(f[1:])])


def tooth_frames(
    rake: RakeFace,
    errors: CutterErrors,
    teeth: int,
    helix_angle: float,
    reference_radius: float,
    tip_radius: float,
    body_side: float = -1.0,
    centre_angle: float = 0.0,
) -> np.ndarray:
    """Every tooth's rake frame in the tool spindle's frame, (z0, 3, 4): tooth k turned by 2 pi k / z0 plus its
    cumulative pitch deviation over r0, on a body mounted with its runout."""
    mount = mount_frame(errors, tip_radius)
    rake0 = rake_frame(rake, helix_angle, reference_radius, body_side, centre_angle)
    fp = pitch_positions(errors.pitch, teeth)
    return np.stack(
        [chain(mount, frame(turn_z(2 * math.pi * k / teeth + fp[k] / reference_radius)), rake0) for k in range(teeth)]
    )


def blank_frame(clamping: Clamping, reference_radius: float) -> np.ndarray:
    """The work spindle's frame in the blank's: the inverse of the blank's placement (tilted about its mid-face
    point, then moved off the axis by its eccentricity)."""
    phase = clamping.eccentricity_phase
    e = clamping.eccentricity
    tilt = _tilt(clamping.tilt / (2 * reference_radius), clamping.tilt_phase)
    placement = frame(tilt, (e * math.cos(phase), e * math.sin(phase), 0.0))
    return inverse(placement)


def random_pitch(tolerance: float, teeth: int, seed: int) -> tuple[float, ...]:
    """Single pitch deviations of a random cutter within ``tolerance`` [mm]: uniform in +-tolerance, the mean taken
    out (they close the circle), scaled back within the tolerance if that pushed one beyond it."""
    rng = np.random.default_rng(seed)
    f = rng.uniform(-tolerance, tolerance, teeth)
    f -= f.mean()
    peak = float(np.abs(f).max())
    if peak > tolerance:
        f *= tolerance / peak
    return tuple(float(v) for v in f)


def tooling_summary(rake: RakeFace, errors: CutterErrors, clamping: Clamping) -> dict:
    """The rake face, the cutter's deviations and the clamping a cut included (mm, deg), for measurement.json."""
    deg = math.degrees
    return {
        "rake_face": rake.kind,
        "rake_face_offset_mm": rake.offset,
        "clearance_angle_deg": math.degrees(rake.clearance_angle),
        "regrind_mm": rake.regrind,
        "rake_angle_deg": math.degrees(rake.rake_angle),
        "errors": {
            "radial_runout_mm": errors.radial_runout,
            "radial_runout_phase_deg": deg(errors.radial_runout_phase),
            "axial_runout_mm": errors.axial_runout,
            "axial_runout_phase_deg": deg(errors.axial_runout_phase),
            "pitch_mm": list(errors.pitch),
            "profile_slope_mm": _per_flank(errors.profile_slope),
            "profile_form_mm": _per_flank(errors.profile_form),
        },
        "clamping": {
            "eccentricity_mm": clamping.eccentricity,
            "eccentricity_phase_deg": deg(clamping.eccentricity_phase),
            "tilt_mm": clamping.tilt,
            "tilt_phase_deg": deg(clamping.tilt_phase),
        },
    }


def _per_flank(values: tuple[Deviation, Deviation]) -> dict[str, float | list[float]]:
    """A deviation per flank for JSON: a number, or a list of one per tooth."""
    return {side: list(v) if isinstance(v, tuple) else v for side, v in zip(("left", "right"), values, strict=True)}
