"""The point-exact sweep: the reference that tells the cut's sampling error from the physics (feed marks)."""

import functools
import math

import numpy as np
import pytest
import trimesh

from cutting.edge import make_edge
from cutting.exact_sweep import passages, removed, surface_offset
from cutting.flank import flank_normals, flank_points
from cutting.gear import Gear
from cutting.removal import CutResult, Stock, cut
from cutting.skiving import SkivingSetup
from cutting.trajectory import ideal_passes
from metrology.measure import MeasureOptions, profile_range

DEG = math.pi / 180


def setup(feed: float = 0.2) -> SkivingSetup:
    return SkivingSetup(Gear(16, 1.0, 20 * DEG, 0.0, 2.0), Gear(11, 1.0, 20 * DEG, 20 * DEG, 5.0), 2000, feed, (2.25,))


def flank_line(g: Gear, side: str, n: int = 15) -> tuple[np.ndarray, np.ndarray]:
    """Points and outward normals along the evaluated profile of tooth 2 at z = 0."""
    l0, l1 = profile_range(g, MeasureOptions())  # the profile evaluation range of the measurement
    xi = np.linspace(l0, l1, n) / g.base_radius
    return flank_points(g, side, xi, 0.0, 2), flank_normals(g, side, xi, 0.0, 2)


@functools.cache
def finishing(feed: float):
    """The conjugate edge and the passages of the (only) pass at ``feed``."""
    st = setup(feed)
    edge = make_edge(st, "conjugate")
    return edge, [passages(m, edge) for m in ideal_passes(st)]


def test_points_in_the_space_are_cut_points_in_the_tooth_are_not():
    st = setup()
    edge, sets = finishing(0.2)
    p, n = flank_line(st.gear, "left")
    assert removed(p + 0.05 * n, sets, edge).all()  # 50 um into the space: air
    assert not removed(p - 0.05 * n, sets, edge).any()  # 50 um into the tooth: material


def test_conjugate_edge_never_undercuts_and_leaves_feed_marks_that_shrink_with_the_feed():
    """The exact cut lies on or outside the nominal flank (0.02 um bisection resolution); what it leaves are
    the feed marks between generating lines, and they shrink when the feed does."""
    g = setup().gear
    tops = {}
    for feed in (0.2, 0.1):
        edge, sets = finishing(feed)
        p, n = flank_line(g, "right")
        d = surface_offset(p, n, sets, edge, span=0.02, resolution=2e-5)
        assert np.isfinite(d).all()
        assert d.min() > -2e-5
        tops[feed] = d.max()
    assert tops[0.1] < 0.6 * tops[0.2]  # feed marks go with the feed squared: 0.25 in theory


@pytest.mark.parametrize("tol", [6e-3, 1.5e-3])
def test_the_meshed_cut_matches_the_exact_sweep_within_its_sweep_error(tol):
    """Along flank normals, the mesh that the booleans leave and the exact surface differ by no more than the
    reported sweep error (plus the 0.02 um bisection resolution). Measured: 3.8 um at 6 um, 0.94 um at 1.5 um."""
    st = setup()
    edge, sets = finishing(0.2)
    motion = sets[0].motion
    stock = Stock(st.gear)
    res = CutResult(None)
    cut(stock, edge, motion, tol, res)
    assert res.sweep_error <= tol
    m = stock.solid().to_mesh64()
    mesh = trimesh.Trimesh(np.asarray(m.vert_properties)[:, :3], np.asarray(m.tri_verts), process=False)
    tri = mesh.vertices[mesh.faces]
    centres = tri.mean(axis=1)
    for side in ("left", "right"):
        p, n = flank_line(st.gear, side)
        exact = surface_offset(p, n, sets, edge, span=0.02, resolution=2e-5)
        meshed = np.array([_crossing(tri, centres, p[i], n[i]) for i in range(len(p))])
        assert np.isfinite(meshed).all() and np.isfinite(exact).all()
        assert np.abs(meshed - exact).max() <= res.sweep_error + 2e-5, side


def _crossing(tri: np.ndarray, centres: np.ndarray, p: np.ndarray, n: np.ndarray, reach: float = 0.03) -> float:
    """Signed distance d in [-reach, reach] at which the line p + d n crosses the triangles (nearest to p)."""
    near = np.linalg.norm(centres - p, axis=1) < 0.5
    a, b, c = tri[near, 0], tri[near, 1], tri[near, 2]
    e1, e2, s = b - a, c - a, p - a  # Moller-Trumbore with the line's parameter d
    h = np.cross(n, e2)
    det = np.einsum("ij,ij->i", e1, h)
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.einsum("ij,ij->i", s, h) / det
        q = np.cross(s, e1)
        v = (q @ n) / det
        d = np.einsum("ij,ij->i", e2, q) / det
    ok = (np.abs(det) > 1e-15) & (u >= 0) & (v >= 0) & (u + v <= 1) & (np.abs(d) <= reach)
    return float(d[ok][np.argmin(np.abs(d[ok]))]) if ok.any() else float("nan")
