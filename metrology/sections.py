"""Sections of a triangle mesh by level sets: planes z = c and cylinders r = c about the z axis.

Every triangle that the level crosses contributes one straight segment (linear interpolation along its
two crossing edges), so a section is exact for the mesh as given: no resampling, no smoothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class MeshData:
    """Vertices (float64, mm) and triangles of a mesh, with per-triangle ranges cached for fast slicing."""

    vertices: np.ndarray
    faces: np.ndarray

    def __post_init__(self) -> None:
        self.vertices = np.ascontiguousarray(self.vertices, dtype=float)
        self.faces = np.ascontiguousarray(self.faces, dtype=np.int64)
        self.radius = np.hypot(self.vertices[:, 0], self.vertices[:, 1])
        self._ranges: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    def field(self, name: str) -> np.ndarray:
        return self.vertices[:, 2] if name == "z" else self.radius

    def ranges(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        if name not in self._ranges:
            fv = self.field(name)[self.faces]
            self._ranges[name] = (fv.min(axis=1), fv.max(axis=1))
        return self._ranges[name]


def level_segments(mesh: MeshData, name: str, level: float, with_faces: bool = False) -> tuple[np.ndarray, ...]:
    """Segments where the level set ``field == level`` cuts the mesh: two arrays (m, 3) of end points (and with
    ``with_faces`` a third: the index of the triangle each segment lies in).

    ``name`` is "z" (plane) or "r" (cylinder about the z axis). A vertex exactly on the level counts as
    above it, which keeps every crossing triangle to exactly two crossing edges.
    """
    lo, hi = mesh.ranges(name)
    cand = np.nonzero((lo < level) & (hi >= level))[0]
    if cand.size == 0:
        empty = (np.empty((0, 3)), np.empty((0, 3)))
        return (*empty, np.empty(0, dtype=np.int64)) if with_faces else empty
    f = mesh.faces[cand]
    vals = mesh.field(name)[f]
    above = vals >= level
    ends = []
    masks = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        cross = above[:, a] != above[:, b]
        va, vb = vals[:, a], vals[:, b]
        t = np.where(cross, (level - va) / np.where(cross, vb - va, 1.0), 0.0)
        pa, pb = mesh.vertices[f[:, a]], mesh.vertices[f[:, b]]
        pt = pa + t[:, None] * (pb - pa)
        if name == "r":  # straight edge interpolation leaves the cylinder slightly: put the point back on it
            rr = np.hypot(pt[:, 0], pt[:, 1])
            pt[:, :2] *= np.where(rr > 0, level / np.maximum(rr, 1e-300), 1.0)[:, None]
        ends.append(pt)
        masks.append(cross)
    m = np.stack(masks, 1)
    keep = m.sum(1) == 2
    m = m[keep]
    pts = np.stack(ends, 1)[keep]
    first = np.argmax(m, axis=1)
    second = 2 - np.argmax(m[:, ::-1], axis=1)
    idx = np.arange(len(m))
    if with_faces:
        return pts[idx, first], pts[idx, second], cand[keep]
    return pts[idx, first], pts[idx, second]
