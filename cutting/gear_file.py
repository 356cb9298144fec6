"""gear.stl: the cut solid written as a file a user can open, at a stated tolerance.

The removal's solid carries the sweep's fine structure (where consecutive passages' sheets meet, a triangle
every few tens of micrometres), which makes spur_external's gear millions of triangles even at a 10 um sweep
error. The file is therefore the solid simplified by manifold (edge collapses asked to move no surface by more than
half the given tolerance, see SIMPLIFY_SHARE: the file's bound is the sweep error plus that tolerance), then written
in float32, as STL is. Float32 can fold two vertices of a sub-nanometre edge onto one point (where the stock's cells
were united); such edges are collapsed in the file so that it reads back watertight. The micrometre truth is not the
file: it is the exact swept surface (``cutting/skiving/exact_sweep.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import manifold3d as mf
import numpy as np
import trimesh

#: manifold's simplify(eps) holds each edge collapse within eps, not their sum: on helical_internal's dexel solid
#: (long strips from slice to slice) simplify(10 um) moved the flanks by up to 21 um along the measured traces,
#: simplify(5 um) by 9.3 um. The file asks it for this share of its tolerance, and is measured within it
SIMPLIFY_SHARE = 0.5


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
    that merge makes degenerate dropped (an edge collapse). Returns the mesh and the number of merged vertices.

    Coinciding vertices that no edge joins are a pinch, not a short edge: the surface touches itself there (two
    cuts that meet along a line, leaving material, or air, of zero width). manifold keeps the two sheets apart by
    their topology, a file has only positions: merged, the line would carry four triangles. Such copies are moved
    apart by a few float32 steps (tens of nanometres), each towards its own triangles, before writing."""
    m = solid.to_mesh64()
    verts64 = np.asarray(m.vert_properties)[:, :3].astype(float)
    faces = np.asarray(m.tri_verts, dtype=np.int64)
    verts64 = separate_pinches(verts64, faces)
    verts = verts64.astype(np.float32)
    unique, inverse = np.unique(verts, axis=0, return_inverse=True)
    merged = len(verts) - len(unique)
    faces = inverse.reshape(-1)[faces]
    keep = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 2] != faces[:, 0])
    mesh = trimesh.Trimesh(unique.astype(np.float64), faces[keep], process=False)
    return mesh, merged


def separate_pinches(verts: np.ndarray, faces: np.ndarray, steps: int = 16) -> np.ndarray:
    """``verts`` with every pinch opened: of the vertices that share a float32 position, those that edges do not
    join (the copies of a point where the surface touches itself) are moved ``steps`` float32 steps apart, each
    group of joined ones along the direction from the other copies' triangles to its own (into its own side,
    whether that is material or air)."""
    f32 = verts.astype(np.float32)
    _, inverse, counts = np.unique(f32, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.reshape(-1)
    shared = np.nonzero(counts[inverse] > 1)[0]
    if shared.size == 0:
        return verts
    step = steps * float(np.spacing(np.float32(np.abs(f32).max())))
    out = verts.copy()
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    edges = edges[np.isin(edges[:, 0], shared) & np.isin(edges[:, 1], shared)]
    joined = {(int(a), int(b)) for a, b in edges if inverse[a] == inverse[b]}
    for position in np.unique(inverse[shared]):
        members = [int(v) for v in shared[inverse[shared] == position]]
        copies = _components(members, joined)
        if len(copies) < 2:
            continue  # a short edge: the weld collapses it
        centres = [_incident_centre(verts, faces, copy) for copy in copies]
        for copy, centre in zip(copies, centres, strict=True):
            others = np.mean([c for c in centres if c is not centre], axis=0)
            d = centre - others
            norm = float(np.linalg.norm(d))
            if norm > 0:
                out[copy] += step * d / norm
    return out


def _components(members: list[int], joined: set[tuple[int, int]]) -> list[list[int]]:
    """The members grouped by the edges that join them."""
    parent = {v: v for v in members}

    def root(v: int) -> int:
        while parent[v] != v:
            v = parent[v]
        return v

    for a, b in joined:
        if a in parent and b in parent:
            parent[root(a)] = root(b)
    groups: dict[int, list[int]] = {}
    for v in members:
        groups.setdefault(root(v), []).append(v)
    return list(groups.values())


def _incident_centre(verts: np.ndarray, faces: np.ndarray, copy: list[int]) -> np.ndarray:
    """Mean of the centroids of the triangles that use any vertex of ``copy``."""
    tri = faces[np.isin(faces, copy).any(axis=1)]
    return verts[tri].mean(axis=(0, 1))


def write_gear_stl(solid: mf.Manifold, path: str | Path, simplification: float) -> GearFile:
    """Write ``solid`` to ``path`` as binary STL, simplified within ``simplification`` [mm] (0: as cut).

    Raises ``ValueError`` for a negative tolerance. A file that still does not close after the float32 weld is
    written all the same and reported (``watertight`` False) rather than lost."""
    if not simplification >= 0.0:
        raise ValueError(f"the simplification of gear.stl must be >= 0 mm, got {simplification!r}")
    solid_triangles = solid.num_tri()
    light = solid.simplify(SIMPLIFY_SHARE * simplification) if simplification > 0.0 else solid
    mesh, merged = float32_mesh(light)
    watertight = bool(mesh.is_watertight and mesh.is_winding_consistent)
    mesh.export(str(path), file_type="stl")
    return GearFile(mesh, simplification, solid_triangles, merged, watertight)
