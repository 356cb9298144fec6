"""gear.stl: the cut solid written as a file a user can open, at a stated tolerance.

The removal's solid carries the sweep's fine structure (where consecutive passages' sheets meet, a triangle
every few tens of micrometres), which makes spur_external's gear millions of triangles even at a 10 um sweep
error. The file is therefore the solid simplified by manifold (edge collapses that move no surface by more than
the given tolerance: the file's bound is the sweep error plus that tolerance), then written in float32, as STL
is. Float32 can fold two vertices of a sub-nanometre edge onto one point (where the stock's cells were united);
such edges are collapsed in the file so that it reads back watertight. The micrometre truth is not the file: it
is the exact swept surface (``cutting/exact_sweep.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import manifold3d as mf
import numpy as np
import trimesh


@dataclass(frozen=True)
class GearFile:
    """What was written: the mesh as the file holds it, and how it departs from the cut solid."""

    mesh: trimesh.Trimesh  # the file's triangles (float32 vertices, welded)
    simplification: float  # the tolerance the simplification was allowed [mm] (0: none)
    solid_triangles: int  # triangles of the cut solid before simplification
    welded_vertices: int  # vertices float32 folds onto another (their edges collapsed in the file)
    watertight: bool  # the file read as a closed, consistently oriented surface

    @property
    def bytes(self) -> int:
        return 84 + 50 * len(self.mesh.faces)  # binary STL: header, count, 50 bytes per triangle

    def summary(self) -> dict[str, float | int | bool]:
        """The file's figures for measurement.json."""
        return {
            "triangles": len(self.mesh.faces),
            "megabytes": round(self.bytes / 1e6, 3),
            "simplification_um": self.simplification * 1e3,
            "solid_triangles": self.solid_triangles,
            "welded_vertices": self.welded_vertices,
            "watertight": self.watertight,
        }


def float32_mesh(solid: mf.Manifold) -> tuple[trimesh.Trimesh, int]:
    """The solid's triangles with float32 vertices, vertices that coincide in float32 merged and the triangles
    that merge makes degenerate dropped (an edge collapse). Returns the mesh and the number of merged vertices."""
    m = solid.to_mesh64()
    verts = np.asarray(m.vert_properties)[:, :3].astype(np.float32)
    faces = np.asarray(m.tri_verts, dtype=np.int64)
    unique, inverse = np.unique(verts, axis=0, return_inverse=True)
    merged = len(verts) - len(unique)
    faces = inverse.reshape(-1)[faces]
    keep = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 2] != faces[:, 0])
    mesh = trimesh.Trimesh(unique.astype(np.float64), faces[keep], process=False)
    return mesh, merged


def write_gear_stl(solid: mf.Manifold, path: str | Path, simplification: float) -> GearFile:
    """Write ``solid`` to ``path`` as binary STL, simplified within ``simplification`` [mm] (0: as cut).

    Raises ``ValueError`` for a negative tolerance. A file that still does not close after the float32 weld is
    written all the same and reported (``watertight`` False) rather than lost."""
    if not simplification >= 0.0:
        raise ValueError(f"the simplification of gear.stl must be >= 0 mm, got {simplification!r}")
    solid_triangles = solid.num_tri()
    light = solid.simplify(simplification) if simplification > 0.0 else solid
    mesh, merged = float32_mesh(light)
    watertight = bool(mesh.is_watertight and mesh.is_winding_consistent)
    mesh.export(str(path), file_type="stl")
    return GearFile(mesh, simplification, solid_triangles, merged, watertight)
