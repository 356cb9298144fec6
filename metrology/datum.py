"""Reading a mesh and setting up the measuring datum: gear axis, face, angular position, tooth numbers.

Datum (issue 3): the mesh's z axis is the gear axis, the face spans the mesh's z extent, tooth 1 is the
first tooth counter-clockwise from +x. Like a measuring machine, the angular position of the gear is
found from the flanks themselves: the mean of left and right flank positions on a circle near mid
depth, so a uniform change of tooth thickness splits equally onto both flanks.
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


def circle_crossings(a: np.ndarray, b: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Polar angles where section segments (a, b) cross the circle ``radius``, and the sign of d(theta)/dr.

    On a left flank theta falls as r grows (external and internal gears alike): sign -1; right flank +1.
    """
    ra, rb = np.hypot(a[:, 0], a[:, 1]), np.hypot(b[:, 0], b[:, 1])
    hit = (ra - radius) * (rb - radius) < 0
    a, b, ra, rb = a[hit, :2], b[hit, :2], ra[hit], rb[hit]
    d = b - a
    # |a + t d| = radius
    qa = np.einsum("ij,ij->i", d, d)
    qb = 2 * np.einsum("ij,ij->i", a, d)
    qc = ra**2 - radius**2
    disc = np.sqrt(np.maximum(qb**2 - 4 * qa * qc, 0.0))
    t1, t2 = (-qb + disc) / (2 * qa), (-qb - disc) / (2 * qa)
    t = np.where((t1 >= 0) & (t1 <= 1), t1, t2)
    p = a + t[:, None] * d
    theta = np.arctan2(p[:, 1], p[:, 0])
    ta, tb = np.arctan2(a[:, 1], a[:, 0]), np.arctan2(b[:, 1], b[:, 0])
    dtheta = (tb - ta + math.pi) % (2 * math.pi) - math.pi
    return theta, np.sign(dtheta / (rb - ra))


def establish_datum(mesh: MeshData, gear: Gear, name: str = "mesh") -> Datum:
    """Check that the mesh is the job's gear with its axis on z; find face, rotation and tooth 1."""
    z = mesh.vertices[:, 2]
    z_lo, z_hi = float(z.min()), float(z.max())
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
    _check_axis(mesh, z_lo, z_hi, name, problems)
    if problems:
        raise InputError(problems)
    z_mid = (z_lo + z_hi) / 2
    radius = measuring_radius(gear)
    a, bb = level_segments(mesh, "z", z_mid)
    theta, slope = circle_crossings(a, bb, radius)
    n_left, n_right = int((slope < 0).sum()), int((slope > 0).sum())
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
    for side, sgn in (("left", -1), ("right", 1)):
        d = theta[slope == sgn] - flank_polar_angle(gear, radius, 0.0, side, 0)
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
