"""Probing a triangle mesh along lines against known answers (lengths in mm).

Flat faces give analytic distances (tolerance 1e-9 mm, far above float64 rounding at these sizes); curved
surfaces are checked against the plane of the triangle hit, computed here independently, and against their
chordal error. Lines exactly through vertices and edges must count each crossing once. Random batches must
agree with a brute-force reference (every line against every triangle, Moller-Trumbore) written here.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from cutting.gear import Gear
from metrology.mesh_probe import MERGE_DISTANCE, MeshWorkpiece
from metrology.reference_gear import reference_gear_mesh
from metrology.sections import MeshData

TOL = 1e-9  # mm
HALF = np.array([1.0, 1.5, 2.0])  # half extents of the test box


def workpiece(m: trimesh.Trimesh) -> MeshWorkpiece:
    return MeshWorkpiece(MeshData(m.vertices, m.faces))


# ---- a brute-force reference: every line against every triangle ---------------------------------------
def brute_crossings(v, f, o, d, lo, hi):
    """(line, d, entering) like MeshWorkpiece.crossings, by Moller-Trumbore against all triangles."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    e1, e2 = b - a, c - a
    normal = np.cross(e1, e2)
    lines, ds, ents = [], [], []
    for i in range(len(o)):
        p = np.cross(d[i], e2)
        det = np.einsum("ij,ij->i", e1, p)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            s = o[i] - a
            u = np.einsum("ij,ij->i", s, p) * inv
            q = np.cross(s, e1)
            w = (q @ d[i]) * inv
            t = np.einsum("ij,ij->i", e2, q) * inv
        hit = (det != 0) & (u >= 0) & (w >= 0) & (u + w <= 1) & (t >= lo[i]) & (t <= hi[i])
        t, ent = t[hit], normal[hit] @ d[i] < 0
        order = np.lexsort((t, ent))
        t, ent = t[order], ent[order]
        keep = np.append(True, (np.diff(t) > MERGE_DISTANCE / np.linalg.norm(d[i])) | (ent[1:] != ent[:-1]))[: t.size]
        t, ent = t[keep], ent[keep]
        order = np.argsort(t, kind="stable")
        lines.append(np.full(len(t), i))
        ds.append(t[order])
        ents.append(ent[order])
    return np.concatenate(lines), np.concatenate(ds), np.concatenate(ents)


def brute_probe(v, f, points, u, reach):
    line, d, ent = brute_crossings(v, f, points, u, -reach, reach)
    out = np.full(len(points), np.nan)
    for i in range(len(points)):
        di, ei = d[line == i], ent[line == i]
        if di.size and not ei[-1]:  # the first crossing met from +reach enters material towards -d
            out[i] = di[-1]
    return out


# ---- meshes -------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def rotated_box():
    """The box 2 x 3 x 4 turned by an arbitrary rotation and moved: (workpiece, rotation matrix, centre)."""
    rot = Rotation.from_rotvec([0.7, -1.1, 0.4]).as_matrix()
    centre = np.array([12.3, -4.5, 7.8])
    m = trimesh.creation.box(extents=2 * HALF)
    m.vertices = m.vertices @ rot.T + centre
    return workpiece(m), rot, centre


@pytest.fixture(scope="module")
def small_gear():
    """A helical gear of 3836 triangles: flanks, and end faces of slivers across the whole gear."""
    g = Gear(12, 1.0, 20 * math.pi / 180, 15 * math.pi / 180, 4.0)
    return reference_gear_mesh(g, flank_points=8, arc_points=3, z_divisions=6)


def face_frames(rot, centre):
    """(face centre, outward normal, in-plane axes, half thickness across) of the six faces of the box."""
    out = []
    for k in range(3):
        for s in (-1.0, 1.0):
            n = s * rot[:, k]
            others = [j for j in range(3) if j != k]
            out.append((centre + HALF[k] * n, n, [(rot[:, j], HALF[j]) for j in others], HALF[k]))
    return out


# ---- the box: analytic distances ----------------------------------------------------------------------
def test_box_probe_gives_the_analytic_distance(rotated_box):
    wp, rot, centre = rotated_box
    rng = np.random.default_rng(3)
    for fc, n, axes, half in face_frames(rot, centre):
        m = 50
        off = rng.uniform(-0.3, 0.3, m)  # the probe point's height above the face
        p = fc + off[:, None] * n
        for axis, h in axes:
            p += rng.uniform(-0.9, 0.9, m)[:, None] * h * axis
        d = wp.probe(p, np.tile(n, (m, 1)), 0.5)
        assert np.abs(d + off).max() < TOL  # the face is at d = -off
        # pointing into the face: the +reach end is in material -> NaN; reaching through the box: the far face
        on = p - off[:, None] * n
        assert np.isnan(wp.probe(on, np.tile(-n, (m, 1)), 0.5)).all()
        far = wp.probe(on, np.tile(-n, (m, 1)), 2 * half + 0.5)
        assert np.abs(far - 2 * half).max() < TOL
        # entirely in air within reach, entirely in material within reach
        assert np.isnan(wp.probe(fc + 1.0 * n, n, 0.5)).all()
        assert np.isnan(wp.probe(fc - 0.6 * n, n, 0.5)).all()


def test_box_crossings_enter_then_leave(rotated_box):
    wp, rot, centre = rotated_box
    for fc, n, _, half in face_frames(rot, centre):
        o = fc + 5.0 * n + 0.2 * np.cross(n, rot[:, 0] + rot[:, 1])  # off the face centre (no edge)
        line, d, ent = wp.crossings(o[None], -n[None], 0.0, 20.0)
        assert line.tolist() == [0, 0]
        assert ent.tolist() == [True, False]
        assert np.abs(d - [5.0, 5.0 + 2 * half]).max() < TOL
        # the same line limited to [0, 6]: only the entry
        line, d, ent = wp.crossings(o[None], -n[None], 0.0, 5.5)
        assert ent.tolist() == [True]


def test_reach_and_range_arrays(rotated_box):
    wp, rot, centre = rotated_box
    fc, n, _, _ = face_frames(rot, centre)[1]
    p = np.tile(fc + 0.2 * n, (3, 1))
    d = wp.probe(p, np.tile(n, (3, 1)), np.array([0.1, 0.3, 5.0]))
    assert np.isnan(d[0]) and abs(d[1] + 0.2) < TOL and abs(d[2] + 0.2) < TOL
    # into the box (2 thick) from 0.2 above: in at 0.2, out at 2.2
    line, d, ent = wp.crossings(p, np.tile(-n, (3, 1)), np.array([0.0, 0.0, 0.3]), np.array([0.1, 1.0, 9.0]))
    assert line.tolist() == [1, 2] and ent.tolist() == [True, False]
    assert np.abs(d - [0.2, 2.2]).max() < TOL
    empty = wp.crossings(np.empty((0, 3)), np.empty((0, 3)), 0.0, 1.0)
    assert all(len(x) == 0 for x in empty)
    assert wp.kind == "mesh"
    lo, hi = wp.bounds()
    corners = (np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)]) * HALF) @ rot.T + centre
    assert np.allclose(lo, corners.min(axis=0), atol=1e-12) and np.allclose(hi, corners.max(axis=0), atol=1e-12)


# ---- a sphere: the plane of the triangle hit, and the chordal error -----------------------------------
def test_sphere_radial_probes():
    R = 10.0
    m = trimesh.creation.icosphere(subdivisions=5, radius=R)
    wp = workpiece(m)
    rng = np.random.default_rng(5)
    u = rng.normal(size=(400, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    p = R * u
    d = wp.probe(p, u, 0.2)
    # independently: the triangle whose cone from the centre holds u, and the plane of that triangle
    tri = m.vertices[m.faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    edge_planes = np.stack([np.cross(tri[:, j], tri[:, (j + 1) % 3]) for j in range(3)], 1)  # (F, 3, 3)
    holds = (np.einsum("fjk,nk->nfj", edge_planes, u) >= 0).all(axis=2)
    face = np.argmax(holds, axis=1)
    assert holds[np.arange(len(u)), face].all()
    n_hit = normal[face]
    expected = np.einsum("ij,ij->i", n_hit, tri[face, 0] - p) / np.einsum("ij,ij->i", n_hit, u)
    assert np.abs(d - expected).max() < TOL
    # flat triangles lie inside the sphere, by at most the sagitta of the widest triangle's circumcircle
    a = np.linalg.norm(tri[:, 1] - tri[:, 2], axis=1)
    b = np.linalg.norm(tri[:, 2] - tri[:, 0], axis=1)
    c = np.linalg.norm(tri[:, 0] - tri[:, 1], axis=1)
    circumradius = a * b * c / (2 * np.linalg.norm(normal, axis=1))
    sagitta = R - math.sqrt(R**2 - circumradius.max() ** 2)
    assert (d <= TOL).all() and (d >= -sagitta - TOL).all()
    assert d.min() < -0.5 * sagitta  # the chordal error is really seen


def test_lines_exactly_through_vertices_and_edges():
    m = trimesh.creation.icosphere(subdivisions=3, radius=10.0)
    wp = workpiece(m)
    v = m.vertices
    mid = 0.5 * (v[m.edges_unique[:, 0]] + v[m.edges_unique[:, 1]])
    for target in (v, mid):
        # from outside, radially through the vertex (edge) and the centre: in at d = 1, out at d = 3
        line, d, ent = wp.crossings(2 * target, -target, 0.0, 3.5)
        assert np.bincount(line, minlength=len(target)).tolist() == [2] * len(target)
        assert ent.reshape(-1, 2).tolist() == [[True, False]] * len(target)
        assert np.abs(d.reshape(-1, 2)[:, 0] - 1.0).max() < TOL
        # the tie rule alone gives one crossing per triangle fan: no copies to merge
        line, _, _ = wp._crossings(2 * target, -target, 0.0, 3.5, merge=False)
        assert np.bincount(line, minlength=len(target)).tolist() == [2] * len(target)
        # any direction through a vertex or edge of a closed surface crosses it an even number of times
        u = np.random.default_rng(7).normal(size=target.shape)
        line, _, _ = wp._crossings(target, u / np.linalg.norm(u, axis=1, keepdims=True), -30.0, 30.0, merge=False)
        assert (np.bincount(line, minlength=len(target)) % 2 == 0).all()


def test_axis_aligned_box_edges_and_corners():
    """Exact small-integer geometry: lines along axes through the face diagonal, along box edges, through corners."""
    wp = workpiece(trimesh.creation.box(extents=(2.0, 2.0, 2.0)))
    o = np.array([[0, 0, 5], [0.5, 0.5, 5], [1, 1, 5], [1, 0, 5], [5, 5, 5], [5, 0, 0], [1, 1, 1]], dtype=float)
    D = np.array([[0, 0, -1], [0, 0, -1], [0, 0, -1], [0, 0, -1], [-1, -1, -1], [-1, 0, 0], [1, -1, 0]], float)
    for merge in (True, False):
        line, d, ent = wp._crossings(o, D, -10.0, 10.0, merge=merge)
        counts = np.bincount(line, minlength=len(o))
        # through the shared diagonal of a face (its centre): once in, once out; (0.5, 0.5) is off the diagonal
        assert counts[:2].tolist() == [2, 2]
        assert d[line == 0].tolist() == [4.0, 6.0] and ent[line == 0].tolist() == [True, False]
        # along an edge or in the plane of a face: the line only touches, an even count
        assert counts[2] % 2 == 0 and counts[3] % 2 == 0
        # corner to corner through the body: in at (1,1,1), out at (-1,-1,-1)
        assert d[line == 4].tolist() == [4.0, 6.0] and ent[line == 4].tolist() == [True, False]
        assert d[line == 5].tolist() == [4.0, 6.0]
        # through a corner, touching only: entering and leaving at the same place, or nothing
        assert counts[6] in (0, 2)
    points = np.array([[0, 0, 0], [0.999999, 0.999999, -0.999999], [1.000001, 0, 0], [0, 0, -1.000001], [3, 3, 3]])
    assert wp.inside(points).tolist() == [True, True, False, False, False]
    # points whose inside() ray passes through a corner (within rounding): into the box, or touching it only
    u = wp.inside_direction()
    assert (u > 0).all()
    for corner, expect in (([1, 1, 1], True), ([-1, -1, -1], False), ([1, -1, 1], False), ([-1, 1, 1], False)):
        p = np.asarray(corner, float) - 0.5 * u
        assert wp.inside(p[None])[0] == expect


def test_inside_rotated_box(rotated_box):
    wp, rot, centre = rotated_box
    rng = np.random.default_rng(11)
    local = rng.uniform(-1.2, 1.2, size=(3000, 3)) * HALF
    local[:500] = rng.choice([-1, 1], size=(500, 3)) * HALF * rng.choice([1 - 1e-6, 1 + 1e-6], size=(500, 3))
    expected = np.all(np.abs(local) < HALF, axis=1)
    points = local @ rot.T + centre
    assert (wp.inside(points) == expected).all()
    assert not wp.inside(np.array([[100.0, 0, 0], [-50, 3, 2]])).any()


# ---- a thin wall: several surfaces on one line --------------------------------------------------------
def test_annulus_first_surface_from_the_air_side():
    m = trimesh.creation.annulus(r_min=5.0, r_max=6.0, height=4.0, sections=64)
    wp = workpiece(m)
    y0, z0 = 0.3, 0.7

    def polygon_x(r: float) -> float:
        """Where y = y0 crosses the polygon of radius r on the +x side (vertices at angles 2 pi k / 64)."""
        a = np.linspace(0, 2 * math.pi, 65)
        pts = r * np.stack([np.cos(a), np.sin(a)], 1)
        for p, q in itertools.pairwise(pts):
            if (p[1] - y0) * (q[1] - y0) <= 0 and p[0] > 0:
                return p[0] + (y0 - p[1]) / (q[1] - p[1]) * (q[0] - p[0])
        raise AssertionError

    x_in, x_out = polygon_x(5.0), polygon_x(6.0)  # symmetric about the y axis too (64 sections)
    line, d, ent = wp.crossings(np.array([[-10.0, y0, z0]]), np.array([[1.0, 0, 0]]), 0.0, 20.0)
    assert line.tolist() == [0] * 4
    assert ent.tolist() == [True, False, True, False]
    assert np.abs(d - (10 + np.array([-x_out, -x_in, x_in, x_out]))).max() < TOL
    p = np.array([[-5.5, y0, z0]] * 3)
    u = np.array([[1.0, 0, 0]] * 3)
    got = wp.probe(p, u, np.array([12.0, 11.0, 10.0]))
    assert abs(got[0] - (x_out + 5.5)) < TOL  # +end in air beyond the right wall: its outer surface
    assert np.isnan(got[1])  # +end inside the right wall
    assert abs(got[2] - (-x_in + 5.5)) < TOL  # +end in the bore: the left wall's inner surface


# ---- random batches against the brute-force reference ------------------------------------------------
def test_random_batches_match_brute_force(small_gear):
    v, f = np.asarray(small_gear.vertices), np.asarray(small_gear.faces)
    wp = workpiece(small_gear)
    rng = np.random.default_rng(13)
    n = 300
    lo_box, hi_box = v.min(axis=0) - 1, v.max(axis=0) + 1
    o = rng.uniform(lo_box, hi_box, size=(n, 3))
    d = rng.normal(size=(n, 3))
    d[: n // 3] /= np.linalg.norm(d[: n // 3], axis=1, keepdims=True)  # some unit, some not
    lo = -rng.uniform(0, 3, n)
    hi = rng.uniform(0, 3, n)
    lo[:50], hi[:50] = -40.0, 40.0  # long lines through the whole gear
    got = wp.crossings(o, d, lo, hi)
    ref = brute_crossings(v, f, o, d, lo, hi)
    assert len(ref[0]) > 200
    assert np.array_equal(got[0], ref[0]) and np.array_equal(got[2], ref[2])
    assert np.abs(got[1] - ref[1]).max() < TOL
    # probes from points near the surface along the outward normal of a random triangle, several reaches
    face = rng.integers(0, len(f), n)
    normal = small_gear.face_normals[face]
    points = v[f[face]].mean(axis=1) + rng.uniform(-0.05, 0.05, n)[:, None] * normal
    reach = rng.choice([0.01, 0.05, 0.3, 1.0], n)
    got = wp.probe(points, normal, reach)
    ref = brute_probe(v, f, points, normal, reach)
    assert np.array_equal(np.isnan(got), np.isnan(ref)) and np.isfinite(got).sum() > n // 2
    assert np.nanmax(np.abs(got - ref)) < TOL
    # inside(): parity along another direction, by brute force
    q = rng.uniform(lo_box, hi_box, size=(n, 3))
    up = np.tile([0.1234, -0.2345, 0.9641], (n, 1))
    line, _, _ = brute_crossings(v, f, q, up, np.zeros(n), np.full(n, 100.0))
    expected = np.bincount(line, minlength=n) % 2 == 1
    assert (wp.inside(q) == expected).all() and 0 < expected.sum() < n


def test_structure_is_built_once(small_gear):
    wp = workpiece(small_gear)
    p = np.asarray(small_gear.vertices[:10])
    wp.probe(p, np.tile([1.0, 0, 0], (10, 1)), 0.1)
    tree = wp.tree
    wp.inside(p)
    assert wp.tree is tree


# ---- the tree of triangle boxes -------------------------------------------------------------------------
def test_tree_holds_every_triangle_once_inside_its_boxes(small_gear):
    from metrology.mesh_bvh import LEAF

    v, f = np.asarray(small_gear.vertices), np.asarray(small_gear.faces)
    tree = workpiece(small_gear).tree
    leaf = tree.child < 0
    assert sorted(tree.order.tolist()) == list(range(len(f)))
    held = np.concatenate([tree.order[s : s + c] for s, c in zip(tree.start[leaf], tree.count[leaf], strict=True)])
    assert sorted(held.tolist()) == list(range(len(f)))  # each triangle in exactly one leaf
    assert tree.count[leaf].max() <= LEAF  # distinct centres: every leaf split down to its size
    tri = v[f]
    for node in np.nonzero(leaf)[0]:
        faces = tree.order[tree.start[node] : tree.start[node] + tree.count[node]]
        assert (tri[faces].min(axis=(0, 1)) >= tree.node_lo[node]).all()
        assert (tri[faces].max(axis=(0, 1)) <= tree.node_hi[node]).all()
    inner = np.nonzero(~leaf)[0]
    for side in (0, 1):  # a node's box holds its children's
        assert (tree.node_lo[tree.child[inner] + side] >= tree.node_lo[inner]).all()
        assert (tree.node_hi[tree.child[inner] + side] <= tree.node_hi[inner]).all()


def test_many_crossings_on_a_line_and_triangles_sharing_a_centre():
    """A stack of 30 plates (60 crossings on a line through all: more than a line keeps at first) and a fan of
    triangles with one common centre (a leaf the tree cannot split)."""
    plates = [trimesh.creation.box(extents=(4.0, 4.0, 0.5)) for _ in range(30)]
    for k, m in enumerate(plates):
        m.apply_translation((0.0, 0.0, 1.0 * k))
    stack = trimesh.util.concatenate(plates)
    wp = workpiece(stack)
    o = np.array([[0.3, -0.2, -5.0], [1.1, 0.7, -5.0], [9.0, 0.0, -5.0]])
    line, d, ent = wp.crossings(o, np.tile([0.0, 0.0, 1.0], (3, 1)), 0.0, 50.0)
    expect = 5.0 + np.sort(np.concatenate([np.arange(30) - 0.25, np.arange(30) + 0.25]))
    for i in (0, 1):
        assert np.abs(d[line == i] - expect).max() < TOL
        assert ent[line == i].tolist() == [True, False] * 30
    assert not (line == 2).any()
    # 64 triangles in a fan of directions, each moved so that its centroid is the origin: the centres coincide,
    # the boxes do not
    a = np.linspace(0, 2 * math.pi, 65)[:-1]
    v, f = [], []
    for k, ang in enumerate(a):
        p = np.array(
            [
                [0.0, 0, 0],
                [3 * math.cos(ang), 3 * math.sin(ang), 1.0],
                [3 * math.cos(ang + 0.3), 3 * math.sin(ang + 0.3), -1.0],
            ]
        )
        p -= p.mean(axis=0)
        v.append(p)
        f.append([3 * k, 3 * k + 1, 3 * k + 2])
    v, f = np.concatenate(v), np.array(f)
    wp = MeshWorkpiece(MeshData(v, f))
    assert wp.tree.count.max() == len(f)  # one leaf holds them all
    rng = np.random.default_rng(3)
    o = rng.uniform(-3, 3, size=(200, 3))
    u = rng.normal(size=(200, 3))
    lo, hi = np.full(200, -10.0), np.full(200, 10.0)
    got = wp._crossings(o, u, lo, hi, merge=False)
    ref = brute_crossings(v, f, o, u, lo, hi)
    assert len(ref[0]) > 50
    assert np.array_equal(got[0], ref[0]) and np.array_equal(got[2], ref[2])
    assert np.abs(got[1] - ref[1]).max() < TOL
