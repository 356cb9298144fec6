"""The cutting engine on a small gear: tubes, sectors, the ideal cut and what the measurement sees."""

import math

import manifold3d as mf
import numpy as np
import pytest
import trimesh

from cutting.errors import InputError
from cutting.gear import Gear
from cutting.skiving.edge import involute_edge
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.passages import CutResult
from cutting.skiving.removal import Stock, cut
from cutting.skiving.solids import blank
from cutting.skiving.sweep import sample_window, tube
from cutting.skiving.trajectory import check_poses, ideal_passes
from metrology.measure import measure
from metrology.sections import MeshData

DEG = math.pi / 180


def small_setup() -> SkivingSetup:
    """z2 = 16, mn = 1, b = 2 mm, helical cutter z0 = 11: small enough to cut in a test."""
    return SkivingSetup(Gear(16, 1.0, 20 * DEG, 0.0, 2.0), Gear(11, 1.0, 20 * DEG, 20 * DEG, 5.0), 2000, 0.2, (2.25,))


def test_sampling_bounds_the_chord_error():
    st = small_setup()
    edge = involute_edge(st, 30)
    pts = np.column_stack([edge.outline, np.zeros(len(edge.outline))])
    pose = st.cutter_pose
    for tol in (4e-3, 1e-3):
        t, err = sample_window(pose, pts, -0.5, 0.5, tol)
        assert err <= tol
        # an independent check at quarter points of every interval: the chord error stays near the bound
        tq = t[:-1] + 0.25 * np.diff(t)
        p0, p1 = (np.einsum("mij,nj->mni", *pose(x)[:1], pts) + pose(x)[1][:, None, :] for x in (t[:-1], t[1:]))
        pq = np.einsum("mij,nj->mni", pose(tq)[0], pts) + pose(tq)[1][:, None, :]
        dev = np.linalg.norm(pq - (0.75 * p0 + 0.25 * p1), axis=2).max()
        assert dev <= tol  # a parabola's deviation at a quarter is 3/4 of the midpoint's


def test_tube_volume_is_outline_area_times_normal_travel():
    """A straight translation along the rake normal: the tube is a prism, volume = area * length."""
    st = small_setup()
    edge = involute_edge(st, 30)
    x, y = edge.outline[:, 0], edge.outline[:, 1]
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    rot = np.repeat(np.eye(3)[None], 5, axis=0)
    trans = np.column_stack([np.zeros(5), np.zeros(5), np.linspace(0, 3.0, 5)])
    solid = tube(edge.outline, rot, trans)
    assert solid.volume() == pytest.approx(area * 3.0, rel=1e-5)


def test_bad_poses_are_refused():
    t = np.array([0.0, 1.0, 2.0])
    rot = np.repeat(np.eye(3)[None], 3, axis=0)
    trans = np.zeros((3, 3))
    check_poses(t, rot, trans)
    with pytest.raises(InputError, match="non-finite"):
        check_poses(t, rot, np.where(np.arange(9).reshape(3, 3) == 4, np.nan, 0.0))
    skew = rot.copy()
    skew[1, 0, 0] = 1.01
    with pytest.raises(InputError, match="not a rigid rotation"):
        check_poses(t, skew, trans)
    with pytest.raises(InputError, match="does not increase"):
        check_poses(np.array([0.0, 1.0, 1.0]), rot, trans)


def test_never_touching_the_blank_is_an_error():
    st = small_setup()
    motion = ideal_passes(st)[0]
    from dataclasses import replace

    far = replace(motion, centre_distance=motion.centre_distance + 5.0)
    res = CutResult(None)
    with pytest.raises(ValueError, match="never reaches the blank"):
        cut(Stock(st.gear), involute_edge(st, 30), far, 5e-3, res)


@pytest.mark.slow
def test_ideal_cut_of_a_small_gear():
    """One full-depth pass at 4 um sweep error: a manifold gear with the right teeth and thickness."""
    st = small_setup()
    stock = Stock(st.gear)
    v_blank = blank(st.gear).volume()
    assert stock.solid().volume() == pytest.approx(v_blank, rel=1e-9)  # the cells tile the blank exactly
    res = CutResult(None)
    cut(stock, involute_edge(st, 40), ideal_passes(st)[0], 4e-3, res)
    solid = stock.solid()
    assert solid.status().name == "NoError" and not solid.is_empty()
    assert res.sweep_error <= 4e-3
    # every chip is what left the stock
    assert sum(c.volume for c in res.chips) == pytest.approx(v_blank - solid.volume(), rel=1e-6)
    m = solid.to_mesh64()
    mesh = trimesh.Trimesh(np.asarray(m.vert_properties)[:, :3], np.asarray(m.tri_verts), process=False)
    assert mesh.is_watertight
    doc = measure(MeshData(mesh.vertices, mesh.faces), st.gear)
    # the chords leave material: at most the sweep error on each flank, plus the involute edge's bow (1.6 um,
    # test_edge.py) and the measurement's own noise (0.3 um)
    span = doc["thickness"]["span"]
    assert 0.0 < (span["W_k_mm"] - span["W_k_nominal_mm"]) * 1e3 < 2 * (res.sweep_error * 1e3 + 1.6 + 0.3)
    # every flank point lies between nominal and nominal + (chord error + feed ridge): so does every pitch
    assert doc["pitch"]["left"]["F_p"] < 4.0 + 1.0 and doc["pitch"]["right"]["F_p"] < 4.0 + 1.0


@pytest.mark.slow
def test_parallel_workers_cut_the_same_gear():
    """Two worker processes (each owning half of the tooth spaces) give the same gear and chips as one. The claim does
    not depend on the job's size: the small gear on a 1 mm face at 0.4 mm/rev (151 passages, not 383)."""
    from cutting.skiving.engine import cut_passes

    st = SkivingSetup(Gear(16, 1.0, 20 * DEG, 0.0, 1.0), small_setup().cutter, 2000, 0.4, (2.25,))
    edge = involute_edge(st, 30)
    motions = ideal_passes(st)
    one = cut_passes(st.gear, edge, motions, [20e-3], workers=1)
    two = cut_passes(st.gear, edge, motions, [20e-3], workers=2)
    assert two.result.gear.volume() == pytest.approx(one.result.gear.volume(), rel=1e-12)
    a, b = one.result.gear, two.result.gear
    assert (a - b).volume() < 1e-9 and (b - a).volume() < 1e-9  # the same solid, not only the same volume
    assert [c.volume for c in two.result.chips] == pytest.approx([c.volume for c in one.result.chips], abs=1e-12)


def _section(solid, z: float) -> tuple[float, float]:
    """Perimeter [mm] of the section z = const and the largest distance of a section point from the blank's
    outer circle inwards [mm] (a wall left inside the gear reaches towards the axis)."""
    from metrology.sections import level_segments

    m = solid.to_mesh64()
    md = MeshData(np.asarray(m.vert_properties)[:, :3], np.asarray(m.tri_verts))
    a, b = level_segments(md, "z", z)
    return float(np.linalg.norm(b - a, axis=1).sum()), float(np.hypot(a[:, 0], a[:, 1]).min())


@pytest.mark.slow
def test_slab_planes_leave_no_trace_in_a_cut_face():
    """A face three slabs wide, cut by two workers: the section exactly on a slab plane is the section a
    hair beside it (same perimeter, nothing inside the root circle). The slabs are 1 mm (a 3 mm face) and the feed
    0.4 mm/rev: the planes' trace does not depend on the slabs' height or the feed, the passages (231, not 468) do."""
    from cutting.skiving.engine import cut_passes

    st = small_setup()
    g = Gear(16, 1.0, 20 * DEG, 0.0, 3.0)
    setup = SkivingSetup(g, st.cutter, 2000, 0.4, (2.25,))
    out = cut_passes(g, involute_edge(setup, 30), ideal_passes(setup), [20e-3], workers=2, slab=1.0)
    solid = out.result.gear
    for plane in (-0.5, 0.5):
        on, r_on = _section(solid, plane)
        beside, _ = _section(solid, plane + 1e-6)
        assert on == pytest.approx(beside, abs=1e-3)
        assert r_on > g.root_radius - 0.01


def test_union_puts_vertices_near_a_slab_plane_back_on_it():
    """Two slabs whose shared face lies within manifold's tolerance of the plane (as a boolean may leave it)
    unite into one solid without a sliver void."""
    import manifold3d as mf

    from cutting.skiving.removal import union_cells

    lower = mf.Manifold.cube((10.0, 10.0, 1.0)).translate((0.0, 0.0, -1.0))
    upper = mf.Manifold.cube((10.0, 10.0, 1.0)).translate((0.0, 0.0, 0.0))

    def lift(v: np.ndarray) -> np.ndarray:  # the shared face slightly off the plane, unevenly
        v = np.array(v, dtype=float)
        on = np.abs(v[:, 2]) < 1e-12
        v[on, 2] = 3e-12 * (1 + v[on, 0])
        return v

    upper = mf.Manifold(mf.Mesh64(**_mesh64(upper.warp_batch(lift)), tolerance=1e-11))
    solid = union_cells({(0, 0): lower, (0, 1): upper}, np.array([-1.0, 0.0, 1.0]))
    assert solid.volume() == pytest.approx(200.0, abs=1e-9)
    assert solid.genus() == 0 and solid.num_tri() <= 24  # one box: no void, no leftover faces
    perimeter, _ = _section(solid, 0.0)
    assert perimeter == pytest.approx(40.0, abs=1e-9)


def _mesh64(solid) -> dict:
    m = solid.to_mesh64()
    return {
        "vert_properties": np.array(m.vert_properties, dtype=float),
        "tri_verts": np.array(m.tri_verts, dtype=np.uint64),
    }


def test_union_evaluates_each_sector_column_before_joining_them() -> None:
    """The cells' union is built in two evaluated stages (the one-batch union of every cell left tunnels on a slab
    plane of a 2 um cut of a small gear: genus 2); checked here on a blank that was not cut: the stages give the
    blank itself (genus 0, its volume), and a cut gear's genus is checked after every cut
    (cutting.skiving.ideal_cut)."""
    import math as _m

    from cutting.gear import Gear
    from cutting.skiving.passages import expected_genus
    from cutting.skiving.removal import Stock, union_cells

    g = Gear(20, 1.0, _m.radians(20), 0.0, 4.0)
    stock = Stock(g, slab=1.0)
    u = union_cells(stock.cells, stock.z_edges)
    assert u.genus() == expected_genus(g) == 0
    assert u.volume() == pytest.approx(_m.pi * g.tip_radius**2 * 4.0, rel=1e-4)


def test_finish_drops_the_pieces_the_cut_set_free() -> None:
    """A sliver cut free (here a 0.1 mm cube beside a 10 mm block) falls off a real blank: the gear is the largest
    body, and the result says how many pieces fell and their volume (to 1e-9 mm^3)."""
    body = mf.Manifold.cube([10.0, 10.0, 10.0])
    sliver = mf.Manifold.cube([0.1, 0.1, 0.1]).translate([12.0, 0.0, 0.0])
    result = CutResult(None)
    result.finish(body + sliver)
    assert result.gear.volume() == pytest.approx(1000.0, abs=1e-9)
    assert result.loose_pieces == 1 and result.loose_volume == pytest.approx(1e-3, abs=1e-9)
    whole = CutResult(None)
    whole.finish(body)
    assert whole.loose_pieces == 0 and whole.gear.volume() == pytest.approx(1000.0, abs=1e-9)
