"""Sampling a tooth passage per block of outline sides, and the zipped tube built from it."""

import math

import manifold3d as mf
import numpy as np
import pytest

from cutting.gear import Gear
from cutting.skiving.edge import involute_edge
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.passages import in_blank_envelope
from cutting.skiving.solids import blank
from cutting.skiving.sweep import ZippedSweep, outline_points, place, sample_blocks, sample_window, split_sides, tube

DEG = math.pi / 180


def small_setup() -> SkivingSetup:
    return SkivingSetup(Gear(16, 1.0, 20 * DEG, 0.0, 2.0), Gear(11, 1.0, 20 * DEG, 20 * DEG, 5.0), 2000, 0.2, (2.25,))


def _area(outline: np.ndarray) -> float:
    x, y = outline[:, 0], outline[:, 1]
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def test_every_block_meets_the_bound_at_points_the_sampling_never_looked_at():
    """Between its samples, every point of a block's sides stays within the bound of its chord: checked at the
    quarter points of every interval (a parabola's deviation there is 3/4 of the midpoint's)."""
    st = small_setup()
    pts = outline_points(involute_edge(st, 30).outline)
    pose = st.cutter_pose
    n = len(pts)
    for tol in (4e-3, 1e-3):
        s = sample_blocks(pose, pts, -0.5, 0.5, tol)
        assert 0 < s.error <= tol
        for b, t in enumerate(s.times):
            own = np.nonzero(s.block_of_side == b)[0]
            corners = pts[np.unique(np.r_[own, (own + 1) % n])]
            tq = t[:-1] + 0.25 * np.diff(t)
            p0, p1, pq = (place(corners, *pose(x)) for x in (t[:-1], t[1:], tq))
            assert np.linalg.norm(pq - (0.75 * p0 + 0.25 * p1), axis=2).max() <= tol


def test_blocks_far_from_the_blank_keep_their_first_samples():
    """Sides that never come near the workpiece (the chord inside the cutter body) need no refinement, so the
    tube has far fewer facets than with one grid for every side."""
    st = small_setup()
    pts = outline_points(split_sides(involute_edge(st, 30).outline, 0.2))  # as the cutter splits it
    g = st.gear

    def near(w):
        return in_blank_envelope(g, w, 0.1)

    s = sample_blocks(st.cutter_pose, pts, -0.4, 0.4, 1e-3, near)
    common, _ = sample_window(st.cutter_pose, pts, -0.4, 0.4, 1e-3, near)
    assert min(len(t) for t in s.times) == 8  # the start grid: 7 steps
    assert s.quads < 0.8 * len(pts) * (len(common) - 1)
    # a warm start from its own times passes at once and gives the same times
    again = sample_blocks(st.cutter_pose, pts, -0.4, 0.4, 1e-3, near, start=s.times)
    assert all(np.array_equal(a, b) for a, b in zip(again.times, s.times, strict=True))


def _prism(times: list[np.ndarray], length: float = 3.0):
    """A straight translation along the rake normal, each outline point sampled at its own times in [0, 1]."""
    edge = involute_edge(small_setup(), 30)

    def pose(t):
        t = np.atleast_1d(t)
        return np.repeat(np.eye(3)[None], len(t), axis=0), np.column_stack([0 * t, 0 * t, length * t])

    return edge.outline, ZippedSweep(edge.outline, times, pose)


def test_a_zipped_translation_is_a_prism():
    """Paths sampled at different times (shared ends): the zipper closes a manifold of volume area x length."""
    rng = np.random.default_rng(1)
    outline = involute_edge(small_setup(), 30).outline
    times = [np.unique(np.r_[0.0, rng.uniform(0, 1, rng.integers(0, 9)), 1.0]) for _ in outline]
    outline, sweep = _prism(times)
    solid = sweep.solid()
    assert solid.status() == mf.Error.NoError and solid.genus() == 0
    assert solid.volume() == pytest.approx(_area(outline) * 3.0, rel=1e-9)


def test_a_sub_tube_cuts_every_path_at_its_ends():
    """The sub-tube between two grid samples inserts both into every path: the parts tile the whole tube."""
    rng = np.random.default_rng(2)
    outline = involute_edge(small_setup(), 30).outline
    times = [np.unique(np.r_[0.0, rng.uniform(0, 1, 5), 1.0]) for _ in outline]
    outline, sweep = _prism(times)
    n = len(sweep.grid)
    lo, mid, hi = 2, n // 2, n - 3
    parts = [sweep.solid(lo, mid), sweep.solid(mid, hi)]
    length = 3.0 * (sweep.grid[hi] - sweep.grid[lo])
    assert sum(p.volume() for p in parts) == pytest.approx(_area(outline) * length, rel=1e-9)
    _, _, g, first, counts = sweep.mesh(lo, mid)
    assert (g[first] == lo).all() and (g[first + counts - 1] == mid).all()
    assert ((g >= lo) & (g <= mid)).all()


def test_the_zipped_tube_and_a_common_grid_cut_the_same_blank():
    """Inside the blank the block-sampled tube and the tube of one common grid differ by no more than the
    bound: their symmetric difference there is below (tol x twice the area it could spread over)."""
    st = small_setup()
    edge = involute_edge(st, 30)
    pts = outline_points(edge.outline)
    g = st.gear

    def pose(t):
        return st.cutter_pose(t * 0.02)  # 0.02 rad of cutter per unit: the passage through the mesh

    def near(w):
        return in_blank_envelope(g, w, 0.1)

    tol = 2e-3
    s = sample_blocks(pose, pts, -20.0, 20.0, tol, near)
    zipped = ZippedSweep(edge.outline, s.path_times(), pose).solid()
    fine, _ = sample_window(pose, pts, -20.0, 20.0, tol / 10, near)
    common = tube(edge.outline, *pose(fine))
    b = blank(g)
    a, c = zipped ^ b, common ^ b
    assert a.volume() > 1.0  # the tooth does pass through the blank
    diff = (a - c).volume() + (c - a).volume()
    assert diff < 1.1 * tol * a.surface_area()
