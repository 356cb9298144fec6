"""The workpiece a gear measuring machine probes, and the probing moves the measurement makes on it.

A workpiece answers two questions: along a line, where does material begin (:meth:`Workpiece.probe`), and is a
point material (:meth:`Workpiece.inside`). Two workpieces answer them: a mesh
(:class:`metrology.mesh_probe.MeshWorkpiece`, any file ``skive measure`` is given) and the exact swept volumes of
a cut (:class:`cutting.skiving.exact_sweep.SweptVolumes`). The measurement uses only these answers and the nominal gear,
so one evaluation serves both.

Probing a flank: the probe is placed on the nominal flank (turned by the datum) and moved along the flank normal;
the distance d at which it touches is the normal deviation, excess material positive (ISO 1328-1 sign), and
d / cos(beta_b) the deviation along the base tangent in the transverse plane.
"""

from __future__ import annotations

import math
from typing import Protocol, runtime_checkable

import numpy as np

from cutting.flank import Side, flank_normals, flank_points
from cutting.gear import Gear


@runtime_checkable
class Workpiece(Protocol):
    """What the measuring machine probes."""

    kind: str  # "mesh" or "exact swept surface"
    name: str

    def probe(self, points: np.ndarray, directions: np.ndarray, reach: float) -> np.ndarray:
        """Signed distance d [mm] along the unit ``directions`` (from material into air) from ``points`` at which
        a probe coming from ``points + reach * directions`` first touches material; NaN where that end is not in
        air or no material lies within ``reach``."""
        ...

    def inside(self, points: np.ndarray) -> np.ndarray:
        """True where a point is material."""
        ...

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """A box (lo, hi) [mm] that holds the whole workpiece."""
        ...


def as_workpiece(obj, name: str | None = None) -> Workpiece:
    """A workpiece from a workpiece or a mesh (:class:`metrology.sections.MeshData`)."""
    from metrology.mesh_probe import MeshWorkpiece
    from metrology.sections import MeshData

    if isinstance(obj, MeshData):
        return MeshWorkpiece(obj, name or "mesh")
    if not isinstance(obj, Workpiece):
        raise TypeError(f"cannot measure a {type(obj).__name__}: give a mesh or a workpiece that can be probed")
    return obj


def reaches(gear: Gear) -> tuple[float, ...]:
    """Probe reaches [mm], tried in turn where a shorter one finds no surface: most flanks lie within a few
    micrometres of nominal; the last is a quarter of the space width (what still belongs to the flank)."""
    quarter = 0.25 * gear.mn * math.pi / 2
    return (*(r for r in (0.02, 0.1, 0.3) if r < quarter), quarter)


def probe_growing(wp: Workpiece, points: np.ndarray, directions: np.ndarray, steps: tuple[float, ...]) -> np.ndarray:
    """:meth:`Workpiece.probe` with the shortest reach first and longer ones where it found nothing."""
    shape = points.shape[:-1]
    p, u = points.reshape(-1, 3), directions.reshape(-1, 3)
    d = np.full(len(p), np.nan)
    todo = np.arange(len(p))
    for reach in steps:
        if todo.size == 0:
            break
        d[todo] = wp.probe(p[todo], u[todo], reach)
        todo = todo[np.isnan(d[todo])]
    return d.reshape(shape)


def turn(points: np.ndarray, angle: float, z_shift: float = 0.0) -> np.ndarray:
    """Points (..., 3) turned about the z axis by ``angle`` [rad] and moved by ``z_shift`` [mm] along it."""
    c, s = math.cos(angle), math.sin(angle)
    out = np.empty_like(points)
    out[..., 0] = c * points[..., 0] - s * points[..., 1]
    out[..., 1] = s * points[..., 0] + c * points[..., 1]
    out[..., 2] = points[..., 2] + z_shift
    return out


def nominal_flank(gear: Gear, datum, side: Side, roll_angle, z_rel, teeth) -> tuple[np.ndarray, np.ndarray]:
    """Points and outward unit normals of the nominal ``side`` flanks placed by the datum (its rotation and mid
    face), broadcast over roll angle xi, height from mid face [mm] and nominal tooth index."""
    p = flank_points(gear, side, roll_angle, z_rel, teeth)
    n = flank_normals(gear, side, roll_angle, z_rel, teeth)
    return turn(p, datum.rotation, datum.z_mid), turn(n, datum.rotation)


def flank_deviation(wp: Workpiece, gear: Gear, datum, side: Side, roll_angle, z_rel, teeth) -> np.ndarray:
    """Deviation along the base tangent in the transverse plane [mm] (excess material positive) of the ``side``
    flanks at the broadcast (roll angle, height from mid face, nominal tooth): probed along the flank normals."""
    p, n = nominal_flank(gear, datum, side, roll_angle, z_rel, teeth)
    return probe_growing(wp, p, n, reaches(gear)) / math.cos(gear.base_helix_angle)


def flank_surface(wp: Workpiece, gear: Gear, datum, side: Side, roll_angle, z_rel, teeth) -> np.ndarray:
    """The probed flank surface points (..., 3) [mm] at the broadcast positions (NaN where none was found)."""
    p, n = nominal_flank(gear, datum, side, roll_angle, z_rel, teeth)
    d = probe_growing(wp, p, n, reaches(gear))
    return p + d[..., None] * n
