"""Reading a mesh and setting up the measuring datum: gear axis, face, angular position, tooth numbers.

Datum: the workpiece's z axis is the gear axis, the face spans its end faces (probed along the axis in
the gear body), tooth 1 is the first tooth counter-clockwise from +x. Like a measuring machine, the teeth are
found by scanning the circle near mid depth in the mid section, and the angular position of the gear from the
flanks themselves: the mean of left and right flank positions on that circle, so a uniform change of tooth
thickness splits equally onto both flanks. A mesh is also checked for being a closed solid with its axis on z.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from cutting.errors import InputError, Problem
from cutting.flank import flank_polar_angle
from cutting.gear import Gear
from metrology.sections import MeshData, level_segments
from metrology.workpiece import Workpiece

#: An axis tilted by more than this from z is not "on z" (a gross error, not a deviation to measure).
MAX_AXIS_TILT_DEG = 0.5


def load_mesh(path: str | Path) -> MeshData:
    """Read a mesh file (STL, PLY, OBJ, 3MF, GLB ...) and check it is a closed solid."""
    p = Path(path)
    if not p.is_file():
        raise InputError(Problem("mesh", str(p), "no such file", "give a gear mesh file (STL, PLY, OBJ, 3MF, GLB)"))
    try:
        loaded = trimesh.load(str(p), force="mesh", process=True)
    except Exception as exc:  # trimesh raises many types for unreadable files
        why = f"cannot be read as a mesh: {exc}"
        raise InputError(Problem("mesh", str(p), why, "export it as STL, PLY, OBJ, 3MF or GLB")) from exc
    return check_mesh(loaded, str(p))


def check_mesh(mesh: trimesh.Trimesh, name: str = "mesh") -> MeshData:
    """A watertight, outward-oriented solid, or an InputError saying what is wrong."""
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise InputError(Problem("mesh", name, "holds no triangles", "export the gear as a closed triangle mesh"))
    # files are loaded with process=True, which already merges duplicate vertices (STL triangle soup)
    if not mesh.is_watertight:
        raise InputError(
            Problem(
                "mesh",
                name,
                f"is not watertight ({len(mesh.faces)} triangles; some edges do not have exactly two faces)",
                "measure a closed solid: repair holes and non-manifold edges before measuring",
            )
        )
    tri = np.asarray(mesh.vertices)[np.asarray(mesh.faces)]
    volume = float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6)
    if volume <= 0:
        why = f"has volume {volume:.3f} mm^3 (inside out)"
        raise InputError(Problem("mesh", name, why, "fix the triangle winding"))
    return MeshData(np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces))


@dataclass(frozen=True)
class Datum:
    """Where the gear sits in the mesh frame.

    z_mid: mid face [mm]; face_width: z extent [mm]; rotation: angle of the measured gear relative to the
    nominal gear (tooth 0 on +x) [rad]; first_tooth: nominal index of the tooth reported as tooth 1.
    """

    z_mid: float
    face_width: float
    rotation: float
    first_tooth: int
    teeth: int

    def number(self, k: np.ndarray | int) -> np.ndarray:
        """Reported tooth number (1..z) of nominal tooth index k."""
        return (np.asarray(k) - self.first_tooth) % self.teeth + 1


def measuring_radius(gear: Gear) -> float:
    """Radius of the circle near mid tooth depth used for pitch and the datum [mm]."""
    return (gear.tip_radius + gear.root_radius) / 2


def face_positions(wp: Workpiece, gear: Gear) -> tuple[float, float]:
    """The end faces [mm]: probed along the axis from inside the gear body (inside the root circle of an external
    gear, in the rim of an internal one) at 16 angles; the median of the touches."""
    lo, hi = wp.bounds()
    r_body = gear.root_radius + (0.5 if gear.internal else -0.5) * gear.mn
    z_c = (lo[2] + hi[2]) / 2
    reach = (hi[2] - lo[2]) / 2 + 1.0
    a = np.linspace(0.0, 2 * math.pi, 16, endpoint=False) + 0.1
    p = np.column_stack([r_body * np.cos(a), r_body * np.sin(a), np.full(len(a), z_c)])
    up = np.tile([0.0, 0.0, 1.0], (len(a), 1))
    top, bottom = wp.probe(p, up, reach), wp.probe(p, -up, reach)
    if not (np.isfinite(top).any() and np.isfinite(bottom).any()):
        return float(lo[2]), float(hi[2])  # no body where a gear has one: its extent, for the checks to report
    return z_c - float(np.nanmedian(bottom)), z_c + float(np.nanmedian(top))


def circle_flanks(wp: Workpiece, gear: Gear, radius: float, z: float, per_pitch: int = 8) -> tuple[np.ndarray, ...]:
    """The flanks met going counter-clockwise round the circle ``radius`` at height ``z``: polar angles [rad] of
    the crossings and +1 where material ends there (the counter-clockwise flank of a tooth), -1 where it begins.

    The circle is scanned with :meth:`Workpiece.inside` (``per_pitch`` points a pitch: a tooth and a space each
    hold several), each change bisected to 1e-4 of a pitch, then the probe touches the flank along the circle's
    tangent from the air side (the tangent leaves the circle by r (1e-4 pitch)^2 / 2, under 1e-6 um)."""
    n = per_pitch * gear.teeth
    a = np.linspace(0.0, 2 * math.pi, n, endpoint=False)

    def on_circle(angle: np.ndarray) -> np.ndarray:
        return np.column_stack([radius * np.cos(angle), radius * np.sin(angle), np.full(len(angle), z)])

    state = wp.inside(on_circle(a))
    i = np.nonzero(state != np.roll(state, -1))[0]
    lo, hi = a[i], a[i] + 2 * math.pi / n
    leaving = state[i]  # material before the crossing, air after
    if i.size == 0:
        return np.empty(0), np.empty(0, dtype=int)
    while (hi - lo).max() > 1e-4 * 2 * math.pi / gear.teeth:
        mid = (lo + hi) / 2
        before = wp.inside(on_circle(mid)) == leaving
        lo, hi = np.where(before, mid, lo), np.where(before, hi, mid)
    mid = (lo + hi) / 2
    for _ in range(2):  # the touch, and once more from the circle point at its angle
        tangent = np.column_stack([-np.sin(mid), np.cos(mid), np.zeros(len(mid))])
        air = np.where(leaving, 1.0, -1.0)[:, None] * tangent  # the side of the crossing that is air
        d = wp.probe(on_circle(mid), air, radius * (hi - lo).max() + 1e-6)
        hit = on_circle(mid) + np.where(np.isfinite(d), d, 0.0)[:, None] * air
        mid = np.arctan2(hit[:, 1], hit[:, 0])
    return mid % (2 * math.pi), np.where(leaving, 1, -1)


def establish_datum(wp: Workpiece, gear: Gear, name: str | None = None) -> Datum:
    """Check that the workpiece is the job's gear with its axis on z; find face, rotation and tooth 1."""
    name = name or wp.name
    z_lo, z_hi = face_positions(wp, gear)
    b = z_hi - z_lo
    problems: list[Problem] = []
    if abs(b - gear.face_width) > 0.01 * gear.face_width + 0.01:
        problems.append(
            Problem(
                "mesh",
                name,
                f"its z extent is {b:.3f} mm but the job's face width is {gear.face_width:.3f} mm",
                "put the gear axis on the mesh's z axis (is it lying on its side?) or use the right job",
            )
        )
    mesh = getattr(wp, "mesh", None)
    if mesh is not None:  # a mesh may come in any orientation; a cut's swept volumes are on the axis by making
        _check_axis(mesh, z_lo, z_hi, name, problems)
    if problems:
        raise InputError(problems)
    z_mid = (z_lo + z_hi) / 2
    radius = measuring_radius(gear)
    theta, ccw = circle_flanks(wp, gear, radius, z_mid)
    # the counter-clockwise flank of a tooth is its left flank on an external gear, its right on an internal one
    left = ccw < 0 if gear.internal else ccw > 0
    n_left, n_right = int(left.sum()), int((~left).sum())
    if n_left != gear.teeth or n_right != gear.teeth:
        raise InputError(
            Problem(
                "mesh",
                name,
                f"on the circle d = {2 * radius:.3f} mm in the mid section it shows {n_left} left and {n_right} right "
                f"flanks, but the job's gear has z = {gear.teeth} teeth (mn = {gear.mn:g} mm)",
                "measure the mesh with the job that made it (tooth count, module, internal/external), axis on z",
            )
        )
    pitch = 2 * math.pi / gear.teeth
    offsets = {}
    for side, sel in (("left", left), ("right", ~left)):
        d = theta[sel] - flank_polar_angle(gear, radius, 0.0, side, 0)
        offsets[side] = np.angle(np.mean(np.exp(1j * gear.teeth * d))) / gear.teeth
    # left and right offsets may sit on either side of a pitch wrap: bring right next to left
    dr = offsets["right"] - offsets["left"]
    dr -= pitch * round(dr / pitch)
    rotation = offsets["left"] + dr / 2
    thickness_error = -dr * radius  # arc; left moves + and right moves - for a thicker external tooth
    if abs(thickness_error) > 0.4 * gear.mn * math.pi / 2:
        raise InputError(
            Problem(
                "mesh",
                name,
                f"its teeth are {thickness_error:+.3f} mm off the nominal thickness at d = {2 * radius:.3f} mm: "
                f"not a gear of module {gear.mn:g} mm with these data",
                "check the job's module, pressure angle, profile shift and helix angle",
            )
        )
    centres = (rotation + pitch * np.arange(gear.teeth)) % (2 * math.pi)
    first = int(np.argmin(np.where(centres <= 1e-12, centres + 2 * math.pi, centres)))
    return Datum(z_mid, b, float(rotation), first, gear.teeth)


def _check_axis(mesh: MeshData, z_lo: float, z_hi: float, name: str, problems: list[Problem]) -> None:
    """The sections near both faces must have their area centroids on one vertical line.

    The area centroid does not depend on how densely the mesh is tessellated (a cut gear has dense feed marks
    on some flanks and none on others), and a thin burr left at a face edge (a fin of a few um, which the
    outline's length would weigh like a flank) barely moves it.
    """
    b = z_hi - z_lo
    centres = []
    for f in (0.2, 0.8):
        centre = _section_centroid(mesh, z_lo + f * b)
        if centre is None:
            return
        centres.append(centre)
    drift = float(np.linalg.norm(centres[1] - centres[0]))
    tilt = math.degrees(math.atan2(drift, 0.6 * b))
    if tilt > MAX_AXIS_TILT_DEG:
        problems.append(
            Problem(
                "mesh",
                name,
                f"its axis is not on z: the centre moves {drift:.3f} mm over the face (tilt about {tilt:.2f} deg)",
                "align the gear axis with the mesh's z axis before measuring",
            )
        )


def _section_centroid(mesh: MeshData, z: float) -> np.ndarray | None:
    """Area centroid (x, y) of the plane section at ``z`` (None if the plane misses the mesh).

    Each segment is oriented so the material lies on its left (its triangle's outward normal on the right);
    the shoelace sums then hold for any order of the segments and any number of loops (a bore counts negative).
    """
    a, bb, faces = level_segments(mesh, "z", z, with_faces=True)
    if len(a) == 0:
        return None
    tri = mesh.vertices[mesh.faces[faces]]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    d = bb - a
    flip = d[:, 0] * normal[:, 1] - d[:, 1] * normal[:, 0] > 0
    a, bb = np.where(flip[:, None], bb, a), np.where(flip[:, None], a, bb)
    cross = a[:, 0] * bb[:, 1] - bb[:, 0] * a[:, 1]
    area = cross.sum() / 2
    if abs(area) <= 1e-12:
        return None
    return ((a[:, :2] + bb[:, :2]) * cross[:, None]).sum(axis=0) / (6 * area)
