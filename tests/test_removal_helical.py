"""Form milling's manifold removal on helical spaces (cutting/form_milling/removal.py): the set-over disc mill fed
along a space's screw motion, and the same pass disturbed as a machine would make it (not a screw), removed by
manifold and probed against the exact swept surface (cutting/form_milling/sweep.py) within the sweep's tolerance."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.integrate import quad

from cutting.flank import SIDES, flank_normals, flank_points
from cutting.form_milling.helical import envelope_mill, helical_pass
from cutting.form_milling.mill import space_tooth
from cutting.form_milling.removal import (
    PATH_SHARE,
    PROFILE_SHARE,
    cut_gear,
    frusta_points,
    pose_frames,
    profile_slices,
    thin_moves,
    thin_poses,
)
from cutting.form_milling.sweep import MilledGear, MillPassPoses
from cutting.gear import Gear, form_roll_length
from cutting.modification import roll
from metrology.mesh_probe import MeshWorkpiece
from metrology.sections import MeshData

#: the helical pinion of docs/form-milling.md: beta = 20 deg, z = 20, mn = 2, b = 10 mm; the set-over mill of
#: radius 25 mm
HELICAL = Gear(teeth=20, normal_module=2.0, helix_angle=math.radians(20.0), face_width=10.0)
FEED = np.arange(-21.0, 21.0 + 1e-9, 0.05)
TOL = 0.005


@pytest.fixture(scope="module")
def mill():
    return envelope_mill(HELICAL, 25.0)


def disturbed(p: MillPassPoses, amplitude: float) -> MillPassPoses:
    """The pass as a machine makes it: the centre off by ``amplitude`` [mm] radially and tangentially with two
    wavelengths (3 and 0.7 mm of feed), the axis tilted by amplitude / 25 mm alike: no screw motion any more."""
    z = p.centre[:, 2]
    r = np.hypot(p.centre[:, 0], p.centre[:, 1])
    radial = np.column_stack([p.centre[:, 0] / r, p.centre[:, 1] / r, 0 * z])
    tangential = np.column_stack([-radial[:, 1], radial[:, 0], 0 * z])
    wave = np.sin(2 * np.pi * z / 3.0) + 0.4 * np.sin(2 * np.pi * z / 0.7 + 1.0)
    centre = p.centre + amplitude * (wave[:, None] * radial + np.cos(2 * np.pi * z / 2.2)[:, None] * tangential)
    axis = p.axis + (amplitude / 25.0) * wave[:, None] * radial
    return MillPassPoses(p.space, p.side, p.t, centre, axis / np.linalg.norm(axis, axis=1, keepdims=True))


def flank_probe(gear: Gear, exact: MilledGear, solid, zs=(-4.0, 0.0, 4.0)) -> tuple[float, float]:
    """Largest |exact| and |exact - mesh| [mm] on both flanks of space 0 (7 profile points x the face positions)."""
    mesh = solid.to_mesh()
    wp = MeshWorkpiece(MeshData(np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts)), "cut")
    L = np.linspace(form_roll_length(gear) + 0.05, roll(gear, gear.tip_diameter_value) - 0.05, 7)
    xi, zz = np.meshgrid(L / gear.base_radius, zs)
    worst_exact = worst = 0.0
    for side in SIDES:
        tooth = space_tooth(gear, 0, side)
        p = flank_points(gear, side, xi, zz, tooth).reshape(-1, 3)
        n = flank_normals(gear, side, xi, zz, tooth).reshape(-1, 3)
        d_exact, d_mesh = exact.probe(p, n, 0.05), wp.probe(p, n, 0.05)
        assert np.isfinite(d_exact).all() and np.isfinite(d_mesh).all()
        worst_exact = max(worst_exact, float(np.abs(d_exact).max()))
        worst = max(worst, float(np.abs(d_exact - d_mesh).max()))
    return worst_exact, worst


def test_the_helical_space_removed_by_manifold_is_the_exact_surface_within_the_sweep_error(mill):
    """beta = 20 deg, one space cut by one screw pass (the mill without clearance cuts both flanks): the manifold
    solid's flanks are the exact swept surface's within tol + 1 um (tol = 5 um: the profile's, the circles' and
    the path's chords and a turning frustum's hull; measured 4.3 um, 5.7 um with the profile at half the tolerance),
    and the exact surface is the nominal helicoid within 0.1 um. The chip is the nominal transverse space between
    root and tip circles (the reference outline below the base circle) times the face within 2 % (measured
    -0.7 %)."""
    p = helical_pass(HELICAL, mill, 0, FEED)
    res = cut_gear(HELICAL, mill, [p], TOL)
    worst_exact, worst = flank_probe(HELICAL, MilledGear(HELICAL, mill, [p]), res.gear_solid)
    assert worst_exact < 1e-4
    assert worst < TOL + 1e-3, worst

    def width(r: float) -> float:
        return (2 * math.pi / HELICAL.teeth - 2 * HELICAL.half_thickness_angle(max(r, HELICAL.base_radius))) * r

    area = quad(width, HELICAL.root_radius, HELICAL.tip_radius, points=[HELICAL.base_radius], limit=200)[0]
    assert res.chips[0][2] == pytest.approx(area * HELICAL.face_width, rel=0.02)


def test_a_disturbed_pass_is_removed_within_the_sweep_error(mill):
    """The same pass disturbed by 3 um waves of the centre (3 and 0.7 mm of feed) and the axis (1.2e-4 rad), as a
    simulated machine records it: the thinning keeps more poses (102 against the screw's 31: the waves' chords), and the
    solid's flanks are still the exact surface's (of the disturbed poses) within tol + 1 um (measured 1.9 um)."""
    p = disturbed(helical_pass(HELICAL, mill, 0, FEED), 0.003)
    points = np.vstack(frusta_points(HELICAL, mill, TOL))
    kept = thin_moves(p, pose_frames(p), points, TOL * PATH_SHARE)
    assert len(kept) > 60
    res = cut_gear(HELICAL, mill, [p], TOL)
    exact = MilledGear(HELICAL, mill, [p])
    worst_exact, worst = flank_probe(HELICAL, exact, res.gear_solid, zs=(-3.7, 0.3, 4.2))
    assert worst_exact > 1e-3  # the waves are in the flank
    assert worst < TOL + 1e-3, worst


def test_thinning_checks_the_cutting_part_and_holds_its_bound(mill):
    """The helical pass: every kept move keeps every polygon point of the cutting part within the path's share
    (0.4 tol) of its chord at every recorded pose (checked here on all points, not only the corners of their box
    that the thinning uses), and needs the poses the screw motion's geometry asks (31, moves of 1.4 mm) where the
    old bound (centre + reach x turn) keeps more (48, moves of 0.9 mm): it no longer counts the far side of the disc.

    The counts from the geometry: the screw turns every point about the gear axis by kappa = 2 pi / p_z = 2 sin(beta)
    / (mn z) per mm of feed (p_z = pi mn z / sin(beta)), so a point at radius rho from the axis runs on a helix whose
    chord over a move of dz misses it by rho (1 - cos(kappa dz / 2)) at the middle. The thinning checks the corners
    of the cutting part's box: the farthest at rho = 26.2 mm. The old bound adds to the centre's helix (radius r_c)
    reach t^2 / 2 for the axis turning by t = 2 asin(sin(gamma) sin(kappa dz / 4)) either side of the middle (gamma
    the axis's angle to the gear axis). The longest move of whole feed steps that holds the share sets the count."""
    p = helical_pass(HELICAL, mill, 0, FEED)
    frames = pose_frames(p)
    points = np.vstack(frusta_points(HELICAL, mill, TOL))
    kept = thin_moves(p, frames, points, TOL * PATH_SHARE)
    assert kept[0] == 0 and kept[-1] == len(FEED) - 1
    reach = math.hypot(mill.radius, mill.width / 2)
    old = thin_poses(p, TOL * PATH_SHARE, reach)

    kappa = 2 * math.sin(HELICAL.helix_angle) / (HELICAL.mn * HELICAL.teeth)
    step = FEED[1] - FEED[0]
    corners = np.array(list(itertools.product(*zip(points.min(axis=0), points.max(axis=0), strict=True))))
    rho = float(np.hypot(*(p.centre[0] + corners @ frames[0])[:, :2].T).max())
    r_c = float(np.hypot(*p.centre[0, :2]))
    sin_gamma = float(np.hypot(*p.axis[0, :2]) / np.linalg.norm(p.axis[0]))

    def new_miss(dz: float) -> float:
        return rho * (1 - math.cos(kappa * dz / 2))

    def old_miss(dz: float) -> float:
        t = 2 * math.asin(sin_gamma * math.sin(kappa * dz / 4))
        return r_c * (1 - math.cos(kappa * dz / 2)) + reach * t * t / 2

    for got, miss in ((kept, new_miss), (old, old_miss)):
        samples = max(m for m in range(1, len(FEED)) if miss(m * step) <= TOL * PATH_SHARE)
        assert np.all(np.diff(got)[:-1] == samples), (samples, np.diff(got))
        assert len(got) == 1 + math.ceil((len(FEED) - 1) / samples)
    assert len(kept) < len(old)
    world = p.centre[:, None, :] + np.einsum("mj,nji->nmi", points, frames)
    worst = 0.0
    for i, j in itertools.pairwise(kept):
        d = p.centre[j] - p.centre[i]
        s = (p.centre[i + 1 : j] - p.centre[i]) @ d / (d @ d)
        chord = world[i][None] + s[:, None, None] * (world[j] - world[i])[None]
        if j > i + 1:
            worst = max(worst, float(np.linalg.norm(world[i + 1 : j] - chord, axis=2).max()))
    assert worst <= TOL * PATH_SHARE + 1e-12


def test_the_disc_cuts_only_with_the_arc_that_reaches_the_blank(mill):
    """A disc's frusta are polygons only over the arc of each circle that comes within the tooth depth of the tip
    circle (+2 tol, +0.05 rad): the periphery's +-0.66 rad, less higher up the edge; a frustum whose lowest points
    stay above the tip circle would be left out (here none: the profile's ends, TIP_MARGIN above the tip, are
    4.83 and 4.49 mm up the edge, the depth 4.51 mm)."""
    us, _ = profile_slices(mill, TOL * PROFILE_SHARE)
    pieces = frusta_points(HELICAL, mill, TOL)
    assert len(us) - 1 == 27 and len(pieces) == 27
    depth = HELICAL.tip_radius - HELICAL.root_radius + 2 * TOL
    for q in pieces:
        r = np.hypot(q[:, 0], q[:, 1])
        assert np.all(q[:, 0] > 0)  # the side towards the gear axis only
        assert np.max(np.abs(np.arctan2(q[:, 1], q[:, 0]))) <= math.acos((mill.radius - depth) / r.max()) + 0.05 + 1e-12


def test_the_arc_away_from_the_contact_can_be_coarse(mill, monkeypatch):
    """Per move a disc's arc keeps its fine polygon only about the contact (about half of its points on this pass)
    and a point every 0.1 rad elsewhere: the removed volume is the full polygons' (the chip to 1e-9; measured to all
    digits), since what the coarse chords leave at one pose the polygon's inside sweeps at the next."""
    import cutting.form_milling.removal as removal

    p = helical_pass(HELICAL, mill, 0, FEED)
    pieces = frusta_points(HELICAL, mill, TOL)
    frames = pose_frames(p)
    kept = thin_moves(p, frames, np.vstack(pieces), TOL * PATH_SHARE)
    a, b = kept[len(kept) // 2], kept[len(kept) // 2 + 1]
    turn, shift = frames[a] @ frames[b].T, frames[a] @ (p.centre[b] - p.centre[a])
    share = sum(len(removal.contact_band(q, turn, shift)) for q in pieces) / sum(len(q) for q in pieces)
    assert 0.3 < share < 0.7
    banded = cut_gear(HELICAL, mill, [p], TOL).chips[0][2]
    monkeypatch.setattr(removal, "contact_band", lambda q, turn, shift: np.arange(len(q)))
    full = cut_gear(HELICAL, mill, [p], TOL).chips[0][2]
    assert banded == pytest.approx(full, rel=1e-9)
