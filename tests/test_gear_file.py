"""gear.stl: simplified within its stated tolerance, welded so that float32 cannot open it, errors on bad input."""

from __future__ import annotations

import os

import manifold3d as mf
import numpy as np
import pytest
import trimesh

from cutting.gear_file import write_gear_stl
from cutting.skiving.ideal_cut import to_trimesh


def cube_with_fold(offset: float = 1e-8) -> mf.Manifold:
    """A 2 mm cube at x = 50 mm whose one edge is split 1e-8 mm from its end: a valid manifold whose short edge
    float32 folds onto one point (as where the removal's stock cells are united)."""
    m = mf.Manifold.cube((2.0, 2.0, 2.0)).translate((50.0, 0.0, 0.0)).to_mesh64()
    v = np.asarray(m.vert_properties)[:, :3].copy()
    f = np.asarray(m.tri_verts).copy()
    a, b = f[0][0], f[0][1]
    other = next(i for i, t in enumerate(f) if i != 0 and a in t and b in t)
    v = np.vstack([v, v[a] + offset * (v[b] - v[a]) / np.linalg.norm(v[b] - v[a])])
    mid = len(v) - 1
    tris = []
    for i, t in enumerate(f):
        if i in (0, other):  # split both triangles on the edge (a, b) at the new vertex
            r = next(r for r in range(3) if {t[r], t[(r + 1) % 3]} == {a, b})
            x, y, z = t[r], t[(r + 1) % 3], t[(r + 2) % 3]
            tris += [[x, mid, z], [mid, y, z]]
        else:
            tris.append(list(t))
    solid = mf.Manifold(mf.Mesh64(vert_properties=v, tri_verts=np.array(tris, dtype=np.uint64)))
    assert solid.status() == mf.Error.NoError and solid.num_tri() == 14
    return solid


def test_a_sub_float32_edge_is_collapsed_so_the_file_reads_back_watertight(tmp_path):
    solid = cube_with_fold()
    to_trimesh(solid).export(tmp_path / "plain.stl")
    assert not trimesh.load(tmp_path / "plain.stl").is_watertight  # the defect the weld removes
    written = write_gear_stl(solid, tmp_path / "gear.stl", 0.0)
    back = trimesh.load(tmp_path / "gear.stl")
    assert written.watertight and back.is_watertight
    assert written.welded_vertices == 1 and len(back.faces) == 12
    assert back.volume == pytest.approx(8.0, abs=1e-9)
    assert os.path.getsize(tmp_path / "gear.stl") == written.bytes == 84 + 50 * 12


def surface_radii(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Distances from the origin of each triangle's centroid and edge midpoints (where a flat facet inscribed
    in a sphere dips deepest)."""
    t = vertices[faces]
    points = [t.mean(axis=1), (t[:, 0] + t[:, 1]) / 2, (t[:, 1] + t[:, 2]) / 2, (t[:, 2] + t[:, 0]) / 2]
    return np.linalg.norm(np.concatenate(points), axis=1)


def test_simplification_moves_the_surface_less_than_its_tolerance(tmp_path):
    # a sphere of 20 mm, finely tessellated: its facets dip s0 below the sphere; simplified within 5 um (manifold
    # asked for half of it: gear_file.SIMPLIFY_SHARE), the file's surface may dip at most s0 + 5 um, and it is lighter
    radius, tol = 20.0, 0.005
    sphere = mf.Manifold.sphere(radius, 640)
    m = sphere.to_mesh64()
    s0 = radius - surface_radii(np.asarray(m.vert_properties)[:, :3], np.asarray(m.tri_verts)).min()
    written = write_gear_stl(sphere, tmp_path / "gear.stl", tol)
    assert written.watertight and written.solid_triangles == sphere.num_tri()
    assert len(written.mesh.faces) < 0.8 * sphere.num_tri()  # measured 0.78
    radii = surface_radii(np.asarray(written.mesh.vertices), np.asarray(written.mesh.faces))
    assert radius - radii.min() <= s0 + tol + 1e-5  # [mm]: plus float32 rounding at 20 mm
    assert radius - radii.min() > s0 + 0.2 * tol  # the simplification did use its tolerance (0.42)
    assert radii.max() <= radius + 1e-5  # vertices are the solid's own (on the sphere)
    assert written.summary()["simplification_um"] == pytest.approx(5.0)


def test_a_negative_tolerance_is_refused(tmp_path):
    with pytest.raises(ValueError, match=r"simplification of gear\.stl must be >= 0"):
        write_gear_stl(mf.Manifold.cube((1.0, 1.0, 1.0)), tmp_path / "gear.stl", -0.001)
    assert not (tmp_path / "gear.stl").exists()


@pytest.mark.parametrize("kind", ["material", "air"])
def test_a_pinch_is_opened_so_the_file_reads_back_watertight(tmp_path, kind):
    """Two cubes of material (or two cavities in a block) touching along an edge: manifold keeps the two sheets
    apart by topology, a file by position only. The writer moves the copies a few float32 steps apart, each to its
    own side, so the file closes and nothing overlaps: volume within 1e-5 mm^3, copies 1e-7..1e-4 mm apart."""
    cube = mf.Manifold.cube((1.0, 1.0, 1.0))
    if kind == "material":
        solid = cube + cube.translate((1.0, 1.0, 0.0))
    else:
        block = mf.Manifold.cube((4.0, 4.0, 2.0)).translate((-2.0, -2.0, -1.0))
        solid = block - cube.translate((-1.0, -1.0, -0.5)) - cube.translate((0.0, 0.0, -0.5))
    written = write_gear_stl(solid, tmp_path / "gear.stl", 0.0)
    back = trimesh.load(tmp_path / "gear.stl")
    assert written.watertight and back.is_watertight and back.is_winding_consistent
    assert back.volume == pytest.approx(solid.volume(), abs=1e-5)
    # the file is a valid solid for manifold too (no face crosses another): as many bodies as the solid had
    again = mf.Manifold(
        mf.Mesh(vert_properties=np.asarray(back.vertices, np.float32), tri_verts=np.asarray(back.faces, np.uint32))
    )
    assert again.status() == mf.Error.NoError and len(again.decompose()) == len(solid.decompose())
    corner = np.array([1.0, 1.0] if kind == "material" else [0.0, 0.0])  # the line x, y = corner holds the pinch
    v = back.vertices[np.linalg.norm(back.vertices[:, :2] - corner, axis=1) < 1e-3]
    v = v[np.abs(v[:, 2] - v[0, 2]) < 1e-3]  # the copies of one end of that line
    assert len(v) == 2 and 1e-7 < np.linalg.norm(v[0] - v[1]) < 1e-4
