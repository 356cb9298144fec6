"""The exact swept surface: probed against swept volumes known in closed form, then on a skiving cut (the
reference that tells the mesh's sampling error from the physics, feed marks)."""

import dataclasses
import functools
import math

import numpy as np
import pytest

from cutting.flank import flank_normals, flank_points
from cutting.gear import Gear
from cutting.skiving.edge import CuttingEdge, make_edge
from cutting.skiving.exact_solve import ItemSolver
from cutting.skiving.exact_sweep import PassTable, SweptVolumes, surface_from_intervals
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.sampled_motion import ideal_samples
from cutting.skiving.trajectory import ideal_passes
from metrology.measure import MeasureOptions, profile_range

DEG = math.pi / 180
EXACT = 5e-5  # the bound on the numerical error of an exact probe: 0.05 um


def _edge(outline: np.ndarray) -> CuttingEdge:
    return CuttingEdge("test", np.asarray(outline, float), np.zeros(1), {}, 0.0, 0.0)


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


class Translation:
    """A tooth frame turned by R and moving at constant velocity v from p0."""

    def __init__(self, rot: np.ndarray, p0: np.ndarray, v: np.ndarray):
        self.rot, self.p0, self.v = rot, p0, v

    def pose(self, t):
        t = np.atleast_1d(np.asarray(t, float))
        return np.broadcast_to(self.rot, (len(t), 3, 3)).copy(), self.p0 + t[:, None] * self.v


RECT = np.array([[0.0, -1.0], [2.0, -1.0], [2.0, 1.0], [0.0, 1.0]])  # x 0..2, y -1..1, counter-clockwise


def test_a_translating_straight_edge_sweeps_an_oblique_prism_probed_exactly():
    """The rectangle moving at v (through its plane and along it) sweeps a prism; its side face through the edge
    y = 1 is the plane spanned by R e_x and v. Probes from inside the prism (air) across that face, at random
    points and tilts, land on the plane within 0.05 um (measured ~1e-9 mm), and across the end cap too."""
    rng = np.random.default_rng(3)
    rot = _rotation([0.3, -0.5, 0.8], 0.7)
    v = rot @ np.array([0.4, 0.3, -1.0]) * 5.0  # mm/s: through the rake plane, and along it
    p0 = np.array([1.0, 2.0, 3.0])
    motion = Translation(rot, p0, v)
    gear = Gear(60, 1.0, 20 * DEG, 0.0, 20.0)  # a blank of radius 31, face +-10: the prism lies inside it
    table = PassTable.from_windows(motion, np.array([0.0]), np.array([1.0]), np.array([0.0]), RECT)
    sv = SweptVolumes(gear, _edge(RECT), [], tables=[table])
    ex, ey, ez = rot[:, 0], rot[:, 1], rot[:, 2]
    a = p0 + ey  # a point of the face through the edge y = 1
    n_face = np.cross(ex, v)
    n_face *= np.sign(n_face @ ey) / np.linalg.norm(n_face)  # out of the prism
    k = 200
    x, f = rng.uniform(0.2, 1.8, k), rng.uniform(0.1, 0.9, k)
    depth = rng.uniform(-0.004, 0.004, k)  # points a few um either side of the face
    p = a + x[:, None] * ex + f[:, None] * v + depth[:, None] * n_face
    tilt = rng.normal(size=(k, 3)) * 0.3
    u = -n_face + tilt - (tilt @ n_face)[:, None] * n_face  # into the prism (air), tilted up to ~17 deg
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    expected = -((p - a) @ n_face) / (u @ n_face)
    got = sv.probe(p, u, 0.02)
    assert np.isfinite(got).all()
    assert np.abs(got - expected).max() <= EXACT
    # the end cap: the rectangle at the first pose; the prism lies on the side v points to
    cap_n = -ez * np.sign(ez @ v)  # out of the prism
    q = p0 + np.array([1.0, 0.2, 0]) @ np.array([ex, ey, ez]) + 0.003 * cap_n
    got = sv.probe(q[None, :], -cap_n[None, :], 0.02)
    assert abs(got[0] - 0.003) <= EXACT  # 3 um of material before the probe reaches the cap


def test_surface_from_intervals_joins_overlaps_and_stops_at_material():
    # line 0: air [0.5, 1] and [-0.2, 0.6]: surface at -0.2; a material gap [-0.5, -0.3] below it
    # line 1: +reach is material: NaN; line 2: removed throughout: NaN
    line = np.array([0, 0, 0, 1, 2])
    start = np.array([0.5, -0.2, -1.0, -0.5, -1.0])
    end = np.array([1.0, 0.6, -0.5, 0.5, 1.0])
    got = surface_from_intervals(3, line, start, end, 1.0)
    assert got[0] == pytest.approx(-0.2)
    assert np.isnan(got[1]) and np.isnan(got[2])


class RackStrokes:
    """Passage k: a rack tooth at the roll phi_k = k dphi of a gear of pitch radius r, stroking down through the
    face in [k, k + 1] s; its rake plane is the transverse plane. In the gear frame the rack's pitch line is
    tangent to the pitch circle at the angle -phi_k, shifted along it by r phi_k."""

    def __init__(self, r: float, dphi: float, half_face: float):
        self.r, self.dphi, self.h = r, dphi, half_face

    def pose(self, t):
        t = np.atleast_1d(np.asarray(t, float))
        k = np.floor(t - 1e-12)
        phi = k * self.dphi
        z = self.h - 2 * self.h * (t - k)
        # tooth frame -> fixed: x (depth, towards the gear centre) -> -X, y -> +Y, z -> -Z; pitch point (r, r phi)
        base = np.diag([-1.0, 1.0, -1.0])
        c, s = np.cos(-phi), np.sin(-phi)
        turn = np.zeros((len(t), 3, 3))
        turn[:, 0, 0], turn[:, 0, 1], turn[:, 1, 0], turn[:, 1, 1], turn[:, 2, 2] = c, -s, s, c, 1.0
        origin = np.stack([np.full_like(t, self.r), self.r * phi, z], -1)
        return turn @ base, np.einsum("nij,nj->ni", turn, origin)


def _rack_tooth(alpha: float, half_width: float, h: float) -> np.ndarray:
    """Trapezoid in the tooth frame: x from -h to h (tip towards the gear centre), flanks y = +-(w - x tan a)."""
    ta = math.tan(alpha)
    return np.array(
        [[-h, -(half_width + h * ta)], [h, -(half_width - h * ta)], [h, half_width - h * ta], [-h, half_width + h * ta]]
    )


def test_rack_strokes_generate_an_involute_probed_exactly():
    """Straight rack flanks at the rolls k dphi envelope the involute of r_b = r cos(alpha): the exact surface is
    the union of the trapezoids, computed here independently in the transverse plane; it equals the probe within
    0.05 um and lies between the involute and the cusps rho dphi^2 / 8 of that envelope (tangents rho dphi apart)."""
    r, alpha, dphi, w0 = 20.0, 20 * DEG, 0.01, 0.6
    rb = r * math.cos(alpha)
    tooth = _rack_tooth(alpha, w0, 1.5)
    ks = np.arange(-40, 41)
    t0 = ks.astype(float) + 1e-9
    table = PassTable.from_windows(RackStrokes(r, dphi, 3.0), t0, t0 + 1 - 2e-9, np.zeros(len(ks)), tooth)
    sv = SweptVolumes(Gear(40, 1.0, alpha, 0.0, 4.0), _edge(tooth), [], tables=[table])  # blank r <= 21, |z| <= 2
    # the flank y = w0 - x tan(a) touches the involute at the foot of the pitch point (r, 0) on it: at roll phi
    # P = (r, 0) + (w0 + r phi) cos(a) n (fixed frame, n its normal out of the tooth), in the gear frame R(-phi) P
    n = np.array([-math.sin(alpha), math.cos(alpha)])
    phi = np.linspace(-0.08, 0.02, 41)
    pts, dirs = [], []
    for f in phi:
        turn = np.array([[math.cos(-f), -math.sin(-f)], [math.sin(-f), math.cos(-f)]])
        pts.append(np.r_[turn @ (np.array([r, 0.0]) + (w0 + r * f) * math.cos(alpha) * n), 0.0])
        dirs.append(np.r_[-(turn @ n), 0.0])  # into the tooth's region: out of the gear's material
    pts, dirs = np.array(pts), np.array(dirs)
    rho = np.sqrt(np.hypot(pts[:, 0], pts[:, 1]) ** 2 - rb**2)  # the involute's radius of curvature there
    expected = np.array([_rack_union(tooth, r, dphi, ks, p, u, 0.02) for p, u in zip(pts, dirs, strict=True)])
    got = sv.probe(pts, dirs, 0.02)
    assert np.isfinite(got).all() and np.isfinite(expected).all()
    assert np.abs(got - expected).max() <= EXACT
    cusp = rho * dphi**2 / 8  # tangency points rho dphi apart along a curve of curvature radius rho
    assert (got >= -1e-9).all() and (got <= 1.05 * cusp).all()  # excess material, never into the involute
    assert (got / cusp).max() > 0.5  # and the cusps are really there


def _rack_union(tooth: np.ndarray, r: float, dphi: float, ks: np.ndarray, p, u, reach: float) -> float:
    """Independent 2D reference: passage k removes the part of the line inside the trapezoid at roll k dphi
    (gear frame -> fixed frame: turn by +phi; fixed -> tooth frame: x = r - X, y = Y - r phi)."""
    starts, ends = [], []
    for k in ks:
        f = k * dphi
        turn = np.array([[math.cos(f), -math.sin(f)], [math.sin(f), math.cos(f)]])
        pf, uf = turn @ p[:2], turn @ u[:2]
        pt, ut = np.array([r - pf[0], pf[1] - r * f]), np.array([-uf[0], uf[1]])
        lo, hi = -reach, reach
        for i in range(len(tooth)):  # clip by each side's half plane (counter-clockwise: inside on the left)
            a, e = tooth[i], tooth[(i + 1) % len(tooth)] - tooth[i]
            c0 = e[0] * (pt[1] - a[1]) - e[1] * (pt[0] - a[0])
            c1 = e[0] * ut[1] - e[1] * ut[0]
            if c1 > 0:
                lo = max(lo, -c0 / c1)
            elif c1 < 0:
                hi = min(hi, -c0 / c1)
            elif c0 < 0:
                lo, hi = 1.0, -1.0
        if lo < hi:
            starts.append(lo), ends.append(hi)
    line = np.zeros(len(starts), dtype=int)
    return float(surface_from_intervals(1, line, np.array(starts), np.array(ends), reach)[0])


# ---- a skiving cut ----------------------------------------------------------------------------------------------


def setup(feed: float = 0.2) -> SkivingSetup:
    return SkivingSetup(Gear(16, 1.0, 20 * DEG, 0.0, 2.0), Gear(11, 1.0, 20 * DEG, 20 * DEG, 5.0), 2000, feed, (2.25,))


def flank_line(g: Gear, side: str, n: int = 15) -> tuple[np.ndarray, np.ndarray]:
    """Points and outward normals along the evaluated profile of tooth 2 at z = 0."""
    l0, l1 = profile_range(g, MeasureOptions())  # the profile evaluation range of the measurement
    xi = np.linspace(l0, l1, n) / g.base_radius
    return flank_points(g, side, xi, 0.0, 2), flank_normals(g, side, xi, 0.0, 2)


@functools.cache
def finishing(feed: float) -> SweptVolumes:
    """The exact swept volumes of the (only) pass at ``feed``, conjugate edge."""
    st = setup(feed)
    return SweptVolumes(st.gear, make_edge(st, "conjugate"), ideal_passes(st))


def test_points_in_the_space_are_cut_points_in_the_tooth_are_not():
    sv = finishing(0.2)
    p, n = flank_line(sv.gear, "left")
    assert not sv.inside(p + 0.05 * n).any()  # 50 um into the space: air
    assert sv.inside(p - 0.05 * n).all()  # 50 um into the tooth: material
    assert not sv.inside(np.array([[0.0, 0.0, 1.5]])).any()  # above the face: air


def test_conjugate_edge_never_undercuts_and_leaves_feed_marks_that_shrink_with_the_feed():
    """The exact cut lies on or outside the nominal flank; what it leaves are the feed marks between generating
    lines, and they shrink when the feed does."""
    g = setup().gear
    tops = {}
    for feed in (0.2, 0.1):
        p, n = flank_line(g, "right")
        d = finishing(feed).probe(p, n, 0.02)
        assert np.isfinite(d).all()
        assert d.min() > -2e-5
        tops[feed] = d.max()
    assert tops[0.1] < 0.6 * tops[0.2]  # feed marks go with the feed squared: 0.25 in theory


def _polygon_distance(poly: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Unsigned distance of the points (x, y) to the closed polygon, segment by segment."""
    a, b = poly, np.roll(poly, -1, axis=0)
    e = b - a
    w = np.stack([x, y], -1)[:, None, :] - a[None]
    s = np.clip((w * e[None]).sum(-1) / (e * e).sum(-1)[None], 0.0, 1.0)
    return np.linalg.norm(w - s[..., None] * e[None], axis=-1).min(axis=1)


def test_the_compiled_estimate_stays_within_its_bound_of_the_exact_distance():
    """What settles a (line, passage) pair without solving it: the rake-plane position from the pose table
    (quadratic in time) and the outline's raster. Against the exact crossing (the motion solved to 1e-10 mm) and
    the exact distance to the polygon, over points near the edge of many passages: within ESTIMATE_ERROR
    (1.67 um); measured 0.06 um (the exact node distances make the bilinear lookup far better than its bound)."""
    from cutting.skiving.exact_kernels import _sdf, in_plane
    from cutting.skiving.exact_sweep import ESTIMATE_ERROR, RASTER_BAND, RASTER_CELL, RASTER_PAD

    sv = finishing(0.2)
    tb, ct = sv.tables[0], sv._compiled
    rng = np.random.default_rng(5)
    m = rng.integers(0, len(tb.m), 400)
    j = rng.integers(8, 56, 400)
    # points on the edge outline at sample j, moved up to 30 um in and out of the plane and within it
    poly = np.concatenate([sv.outline.lower, sv.outline.upper[::-1][1:-1]])
    k = rng.integers(0, len(poly), 400)
    local = poly[k] + rng.normal(scale=0.015, size=(400, 2))
    q = np.einsum("nij,nj->ni", tb.rot[m, j, :, :2], local) + tb.origin[m, j] + rng.normal(scale=0.01, size=(400, 3))
    got, ok_all = np.empty(400), np.empty(400, bool)
    for i in range(400):
        ok, x, y = in_plane(ct.table, int(m[i]), 0, 64, *q[i])
        ok_all[i] = ok
        got[i] = _sdf(ct.sdf, float(ct.sdf_lo[0]), float(ct.sdf_lo[1]), RASTER_CELL, -RASTER_PAD, x, y)
    row, jj, ga, gb = sv._events(tb, m, np.zeros(400, int), np.full(400, 64), q)
    assert ok_all[row].all() and len(row) > 350
    _, x, y = sv._solve_time(tb, m[row], q[row], jj, ga, gb)
    sign = np.where(sv.outline.margin(x, y) > 0, 1.0, -1.0)
    exact = sign * _polygon_distance(poly, x, y)
    band = np.abs(exact) < RASTER_BAND - 2 * RASTER_CELL  # beyond, the raster holds +-band: a bound of its side
    err = np.abs(got[row] - exact)[band]
    assert band.sum() > 250 and err.max() <= ESTIMATE_ERROR, err.max()
    far = got[row][~band]
    assert np.all(np.abs(far) <= np.abs(exact[~band]) + ESTIMATE_ERROR) and np.all(far * exact[~band] > 0)


@pytest.mark.parametrize("reach", [0.02, 0.1])
def test_the_compiled_settling_gives_the_table_wide_surface(reach):
    """The compiled path (settle what the table can, solve the rest) and the table-wide path (every near pair
    solved) probe the same surface: within 1e-6 um, both on the flank and across the space to the tip."""
    sv = finishing(0.2)
    g = sv.gear
    lines = [flank_line(g, side, 40) for side in ("left", "right")]
    p = np.concatenate([q for q, _ in lines])
    u = np.concatenate([n for _, n in lines])
    fast = sv.probe(p, u, reach)
    line, start, end = sv.removed_intervals(p, u, reach)
    slow = surface_from_intervals(len(p), line, start, end, reach)
    assert np.array_equal(np.isnan(fast), np.isnan(slow))
    assert np.isfinite(fast).sum() > 60
    both = np.isfinite(fast)
    assert np.abs(fast[both] - slow[both]).max() < 1e-9


# ---- the compiled item solve -------------------------------------------------------------------------------------


@functools.cache
def sampled(feed: float) -> SweptVolumes:
    """The pass of :func:`finishing` as a sampled motion (the ideal one sampled at 4 kHz), same edge."""
    st, edge = setup(feed), finishing(feed).edge
    return SweptVolumes(st.gear, edge, [ideal_samples(m) for m in ideal_passes(st)])


class Delegate:
    """A motion the compiled item solve does not know: the pose of another motion, through Python."""

    def __init__(self, motion):
        self.motion = motion

    def pose(self, t):
        return self.motion.pose(t)


def _flank_lines(g: Gear) -> tuple[np.ndarray, np.ndarray]:
    lines = [flank_line(g, side, 40) for side in ("left", "right")]
    return np.concatenate([q for q, _ in lines]), np.concatenate([n for _, n in lines])


@pytest.mark.parametrize("kind", ["ideal", "sampled"])
def test_the_compiled_pose_is_the_motions_pose(kind):
    """What the compiled item solve evaluates: the tooth frame of a passage at any time (for a sampled motion
    between samples and beyond them, where it clips) equals PassTable.exact_pose to rounding."""
    from cutting.skiving.exact_solve import _tooth_pose

    sv = finishing(0.2) if kind == "ideal" else sampled(0.2)
    tb, solver = sv.tables[0], sv._solver
    # both motions have a compiled pose, so the sweep took the compiled solve, over every passage of its tables
    assert isinstance(solver, ItemSolver) and len(solver.motion[0]) == sum(len(t.m) for t in sv.tables)
    rng = np.random.default_rng(7)
    g = rng.integers(0, len(tb.m), 300)
    t = rng.uniform(-0.01, tb.motion.duration + 0.01, 300)
    rot, org = tb.exact_pose(g, t)
    for k in range(300):
        r, o = _tooth_pose(solver.motion, solver.tables, int(g[k]), float(t[k]))
        assert np.abs(np.reshape(r, (3, 3)) - rot[k]).max() < 1e-14
        assert np.abs(np.array(o) - org[k]).max() < 1e-12


@pytest.mark.parametrize("kind", ["ideal", "sampled"])
def test_the_compiled_item_solve_gives_the_python_intervals(kind, monkeypatch):
    """The unsettled items of real probe lines (flank normals, and across the space to the tip): the compiled
    solve (numba) and the numpy one (the motion's pose in Python) give the same removed intervals within 1e-9 mm,
    so the same surface. Measured: ~1e-14 mm."""
    sv = finishing(0.2) if kind == "ideal" else sampled(0.2)
    solver = sv._solver
    # both motions have a compiled pose, so the sweep took the compiled solve, over every passage of its tables
    assert isinstance(solver, ItemSolver) and len(solver.motion[0]) == sum(len(t.m) for t in sv.tables)
    p, u = _flank_lines(sv.gear)
    for reach in (0.02, 0.1):
        points, roots = solver.points, solver.roots_found
        with monkeypatch.context() as mp:  # the compiled path must not fall back to the numpy one
            mp.setattr(SweptVolumes, "_margin_exact", lambda *a: pytest.fail("numpy item solve"))
            fast = sv.settled_intervals(p, u, reach)
            fast_d = sv.probe(p, u, reach)
        assert solver.points - points > 300 and solver.roots_found - roots > 50  # real work, on this path
        with monkeypatch.context() as mp:
            mp.setattr(sv, "_solver", None)
            slow = sv.settled_intervals(p, u, reach)
            slow_d = sv.probe(p, u, reach)
        assert np.array_equal(fast[0], slow[0])  # the same items, in the same order (one pass)
        assert np.abs(fast[1] - slow[1]).max() < 1e-9 and np.abs(fast[2] - slow[2]).max() < 1e-9
        assert np.array_equal(np.isnan(fast_d), np.isnan(slow_d)) and np.isfinite(fast_d).sum() > 60
        both = np.isfinite(fast_d)
        assert np.abs(fast_d[both] - slow_d[both]).max() < 1e-9


def test_a_motion_without_a_compiled_pose_takes_the_numpy_item_solve():
    """The same passages with the pose behind a Python object: no compiled pose, so the numpy path; it gives the
    compiled path's surface."""
    from cutting.skiving.exact_solve import IDEAL, SAMPLED, compiled_pose

    sv = finishing(0.2)
    tb = sv.tables[0]
    assert compiled_pose(tb.motion)[0] == IDEAL and compiled_pose(sampled(0.2).tables[0].motion)[0] == SAMPLED
    assert compiled_pose(Delegate(tb.motion)) is None
    other = SweptVolumes(sv.gear, sv.edge, [], tables=[dataclasses.replace(tb, motion=Delegate(tb.motion))])
    assert other._solver is None
    p, u = _flank_lines(sv.gear)
    got, want = other.probe(p, u, 0.1), sv.probe(p, u, 0.1)
    assert other.work[4] > 100  # items solved, in numpy
    assert np.array_equal(np.isnan(got), np.isnan(want)) and np.isfinite(got).sum() > 60
    both = np.isfinite(got)
    assert np.abs(got[both] - want[both]).max() < 1e-9


def test_the_bucketed_outline_lookup_is_numpys_interp():
    """The compiled outline margin finds a chain's segment from a bucket of x instead of bisecting: on the default
    job's edge, at 20k x across and beyond the chains (ends, vertices, repeated x), it gives np.interp's value bit
    for bit, so the margin is Outline.margin's."""
    from cutting.skiving.exact_solve import _interp_from, outline_margin, stacked_outlines, with_rows
    from cutting.skiving.exact_sweep import Outline
    from virtual_machine.job import default_job_path, load_job

    job = load_job(default_job_path())
    outline = Outline(make_edge(job.skiving, "conjugate").outline)
    packed = with_rows(stacked_outlines([outline]), None)
    lx, ly, ux, uy, x0, x1, lb, l0, ls, ub, u0, us, _ = (a[0] if np.ndim(a) else a for a in packed)
    rng = np.random.default_rng(7)
    x = np.concatenate([rng.uniform(x0 - 0.1, x1 + 0.1, 20000), lx, ux, [x0, x1, np.nextafter(x1, 0.0)]])
    for xp, fp, start, lo, scale in ((lx, ly, lb, l0, ls), (ux, uy, ub, u0, us)):
        got = np.array([_interp_from(v, xp, fp, start, lo, scale) for v in x])
        assert np.array_equal(got, np.interp(x, xp, fp))
    y = rng.uniform(-3.0, 3.0, len(x))
    got = np.array([outline_margin(packed, 0, a, b) for a, b in zip(x, y, strict=True)])
    assert np.array_equal(got, outline.margin(x, y))


def test_each_passage_reads_its_own_tooths_outline():
    """A cutter whose teeth carry their own profile deviations: the compiled margin of passage g is the polygon of
    the tooth at its mesh (tooth (-m) mod z0) bit for bit, its chains padded to the longest tooth's; the teeth's
    outlines lie within ``spread`` of the edge's (the certificates' widening)."""
    from cutting.skiving.exact_solve import outline_margin
    from cutting.skiving.exact_sweep import Outline, ToothOutlines
    from cutting.skiving.tooling import CutterErrors
    from virtual_machine.job import default_job_path, load_job

    st = load_job(default_job_path()).skiving
    z0 = st.cutter.teeth
    slope = tuple(0.004 * math.sin(2 * math.pi * k / z0) for k in range(z0))
    errors = CutterErrors(profile_slope=(slope, 0.0), profile_form=(0.0, 0.003))
    edge = make_edge(dataclasses.replace(st, cutter_errors=errors), "conjugate")
    outlines = ToothOutlines(edge)
    teeth = edge.tooth_outlines()
    assert len(teeth) == z0 and 0.002 < outlines.spread < 0.006
    assert outlines.spread == pytest.approx(max(np.linalg.norm(p - edge.outline, axis=1).max() for p in teeth))
    m = np.array([0, 1, 5, -3, 2 * z0 + 4])
    packed = outlines.compiled(m)
    rng = np.random.default_rng(3)
    for g, mg in enumerate(m):
        own = Outline(teeth[(-mg) % z0])
        x = np.concatenate([rng.uniform(own.x0 - 0.05, own.x1 + 0.05, 3000), own.lower[:, 0], own.upper[:, 0]])
        y = rng.uniform(-2.0, 2.0, len(x))
        got = np.array([outline_margin(packed, g, a, b) for a, b in zip(x, y, strict=True)])
        assert np.array_equal(got, own.margin(x, y))
        assert np.array_equal(outlines.margin(np.full(len(x), mg), x, y), own.margin(x, y))
