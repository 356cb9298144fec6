"""The finger mill of the copying method (seed 003): its profile copies the tooth space, its exact
swept surface is the involute (internal spur z = 60, external spur mn = 8), measured by the project's metrology; the
manifold removal takes out the space's volume; bad mills and gears are refused with the fix."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.integrate import quad

from cutting.flank import SIDES, flank_normals, flank_points
from cutting.form_milling.finger import (
    FingerMill,
    check_finger,
    finger_pass,
    finger_passes,
    finger_rolls,
    finger_section,
    fit_finger_mill,
    pass_length,
    path_point,
    plan_finger,
)
from cutting.form_milling.forces import FingerLoad
from cutting.form_milling.mill import BezierChain, check_copying_gear, section_normals, space_tooth
from cutting.form_milling.removal import cut_gear
from cutting.form_milling.sweep import MilledGear
from cutting.gear import Gear, form_roll_length
from cutting.materials import material
from cutting.modification import FlankDesign, Modification, roll
from metrology.datum import Datum, establish_datum
from metrology.flank_lines import evaluate_many
from metrology.measure import MeasureOptions, helix_range, measure_gear, profile_range
from metrology.mesh_probe import MeshWorkpiece
from metrology.modification import crowning
from metrology.sections import MeshData
from metrology.workpiece import flank_deviation

#: an internal spur: z = 60, m = 2, b = 20 mm
INTERNAL = Gear(teeth=60, normal_module=2.0, face_width=20.0, internal=True)
#: a large module external spur: z = 20, mn = 8, b = 16 mm
LARGE = Gear(teeth=20, normal_module=8.0, face_width=16.0)
UM = 1e3


@pytest.fixture(scope="module")
def internal_mill() -> FingerMill:
    return fit_finger_mill(INTERNAL, 0.2)


# ---- the mill -------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("gear", [INTERNAL, LARGE], ids=["internal", "external_mn8"])
def test_the_finger_profile_copies_the_space_section(gear):
    """rho(v) is the flank section's distance from an axis c/2 off the symmetry line, for both flanks, within the
    Bezier fit (0.05 um); an internal space narrows towards its root (the finger is thinnest at its tip), an
    external one widens."""
    mill = fit_finger_mill(gear, 0.2)
    L = finger_rolls(gear)
    for side in SIDES:
        v, rho = finger_section(gear, None, side, 0.2, L).T
        assert np.abs(mill.rho(np.minimum(v, mill.width)) - rho).max() < 5e-5
    v, rho = mill.table
    assert v[0] == 0.0 and np.all(np.diff(rho) > 0)  # thinnest at the tip, for both kinds
    assert 0.4 < mill.tip_radius < mill.radius
    # the nominal space: an internal one's width at the root circle is the space angle there (z = 60, m = 2:
    # 1.09 mm), the tip's radius half of it less c/2
    half = INTERNAL.root_radius * (math.pi / INTERNAL.teeth - INTERNAL.half_thickness_angle(INTERNAL.root_radius))
    if gear is INTERNAL:
        assert mill.tip_radius == pytest.approx(half - 0.1, abs=2e-3)


def test_the_disc_mill_refuses_an_internal_gear_and_names_the_finger_mill():
    assert check_copying_gear(INTERNAL, "finger") == []
    (why,) = check_copying_gear(INTERNAL)
    assert "disc mill" in why and "finger mill" in why
    assert check_copying_gear(LARGE) == [] == check_copying_gear(LARGE, "finger")


# ---- the exact swept surface, measured -----------------------------------------------------------------------
def test_internal_spur_finger_passes_cut_the_involute_measured(internal_mill):
    """z = 60, m = 2, b = 20 internal, every space cut by the left and the right pass on the nominal straight path.
    The measuring machine's datum (tooth flanks round the mid-section circle) finds the gear on the nominal frame;
    profile at 15/50/85 % of the face and helix over L_beta on teeth 1 and 2 (40 points each), evaluated per
    ISO 1328-1: F_alpha, f_Halpha, F_beta, f_Hbeta all within 0.1 um of 0 (measured F_alpha 0.021 um,
    f_Halpha 0.013 um, F_beta 0.0000 um: the Bezier fit of the profile is all that is left)."""
    gear, mill = INTERNAL, internal_mill
    cut = MilledGear(gear, mill, finger_passes(gear, mill, 0.2, step=0.2), "finger-milled ring")
    datum = establish_datum(cut, gear)
    assert abs(datum.rotation) < 1e-7 and abs(datum.z_mid) < 1e-6
    number = {int(datum.number(k)): k for k in range(gear.teeth)}
    teeth = np.array([[number[1]], [number[2]]])
    L0, L1 = profile_range(gear, MeasureOptions())
    L = np.linspace(L0, L1, 40)
    zh = np.linspace(*helix_range(gear), 40)
    xi_ref = math.sqrt(gear.reference_radius**2 - gear.base_radius**2) / gear.base_radius
    for side in SIDES:
        for f in (0.15, 0.5, 0.85):
            e = flank_deviation(
                cut, gear, datum, side, L[None, :] / gear.base_radius, (f - 0.5) * gear.face_width, teeth
            )
            ev = evaluate_many(L, e)
            assert np.isfinite(e).all()
            assert ev["F"].max() * UM < 0.1 and np.abs(ev["f_H"]).max() * UM < 0.1, (side, f, ev)
        e = flank_deviation(cut, gear, datum, side, xi_ref, zh[None, :], teeth)
        ev = evaluate_many(zh, e)
        assert np.isfinite(e).all()
        assert ev["F"].max() * UM < 0.1 and np.abs(ev["f_H"]).max() * UM < 0.1, (side, ev)


def test_external_module_8_finger_passes_measured():
    """z = 20, mn = 8, b = 16 external, every space cut: the whole measurement (measure_gear, 30 points a trace)
    within 0.1 um of the nominal gear on profile and helix (measured F_alpha 0.032 um, f_Halpha -0.006 um,
    F_beta 0.0000 um) and pitch (f_p, F_p < 0.01 um), the tip diameter the blank's, the root the path's."""
    gear = LARGE
    mill = fit_finger_mill(gear, 0.2)
    cut = MilledGear(gear, mill, finger_passes(gear, mill, 0.2, step=0.2), "finger-milled pinion")
    doc = measure_gear(cut, gear, MeasureOptions(profile_points=30, helix_points=30))
    for side in SIDES:
        prof, helix, pitch = doc["profile"][side], doc["helix"][side], doc["pitch"][side]
        assert prof["F_alpha"] < 0.1 and abs(prof["f_Halpha"]) < 0.1, prof
        assert helix["F_beta"] < 0.1 and abs(helix["f_Hbeta"]) < 0.1, helix
        assert pitch["F_p"] < 0.01 and pitch["f_p"] < 0.01
    assert doc["thickness"]["tip_diameter_mm"] == pytest.approx(gear.tip_diameter_value, abs=1e-4)
    assert doc["thickness"]["root_diameter_mm"] == pytest.approx(gear.root_diameter_value, abs=1e-4)


def test_a_moved_path_moves_the_flank_by_the_move_along_its_normal(internal_mill):
    """A tip centre moved by (dx, dy) in the space frame moves the cut flank by (dx, dy) . n_s (n_s the flank's
    normal there): the path's corrections act on the finger's flank as on the disc's."""
    gear, mill = INTERNAL, internal_mill
    z = np.arange(-15.0, 15.01, 0.2)
    dx, dy = 0.004, -0.007

    def cut(shift: tuple[float, float]) -> MilledGear:
        xy = {s: np.tile(np.add(path_point(gear, s, 0.2), shift), (len(z), 1)) for s in SIDES}
        return MilledGear(gear, mill, [finger_pass(gear, mill, 0, s, z, 0.2, xy[s]) for s in SIDES])

    base, moved = cut((0.0, 0.0)), cut((dx, dy))
    L = np.linspace(form_roll_length(gear) - 0.3, roll(gear, gear.tip_diameter_value) + 0.3, 7)
    for side in SIDES:
        tooth = space_tooth(gear, 0, side)
        p = flank_points(gear, side, L / gear.base_radius, 0.0, tooth)
        n = flank_normals(gear, side, L / gear.base_radius, 0.0, tooth)
        change = moved.probe(p, n, 0.05) - base.probe(p, n, 0.05)
        assert np.allclose(change, section_normals(gear, side, L) @ [dx, dy], atol=2e-5)  # 0.02 um


@pytest.mark.parametrize(
    "gear",
    [
        Gear(teeth=60, normal_module=2.0, face_width=20.0, internal=True, helix_angle=math.radians(15.0)),
        Gear(teeth=20, normal_module=2.0, face_width=10.0, helix_angle=math.radians(20.0)),
    ],
    ids=["internal_beta15", "external_beta20"],
)
def test_the_helical_finger_cuts_the_helicoid(gear):
    """A helical space: the finger's radius is the envelope of the helicoid under the space's screw motion (its
    contact up to rho tan(beta) off its centre plane: 0.13-0.53 mm internal, 0.34-1.19 mm external), the passes
    follow the screw (the tip centre turning by 2 pi / p_z per mm of feed). Its exact swept surface is the nominal
    helicoid within 0.1 um on both flanks over the profile and 80 % of the face (measured 0.014 um internal,
    0.038 um external: the Bezier fit)."""
    mill = fit_finger_mill(gear, 0.2)
    half = pass_length(gear, mill)
    z = np.arange(-half, half + 0.05, 0.1)
    cut = MilledGear(gear, mill, [finger_pass(gear, mill, k % gear.teeth, s, z) for k in (-1, 0, 1) for s in SIDES])
    L = np.linspace(form_roll_length(gear), roll(gear, gear.tip_diameter_value), 9)
    LL, zz = np.meshgrid(L, np.linspace(-0.4, 0.4, 5) * gear.face_width)
    for side in SIDES:
        tooth = space_tooth(gear, 0, side)
        p = flank_points(gear, side, LL / gear.base_radius, zz, tooth).reshape(-1, 3)
        n = flank_normals(gear, side, LL / gear.base_radius, zz, tooth).reshape(-1, 3)
        d = cut.probe(p, n, 0.05)
        assert np.isfinite(d).all() and np.abs(d).max() < 1e-4, np.abs(d).max()


# ---- the manifold removal --------------------------------------------------------------------------------------
@pytest.mark.parametrize("beta", [0.0, 15.0], ids=["spur", "helical_beta15"])
def test_manifold_removal_takes_the_space_volume_and_matches_the_exact_surface(beta):
    """One space of the internal z = 60 ring, both passes removed from the ring blank by manifold (hulls of the mill's
    frusta between poses, 5 um): the chips add up to the nominal space's transverse area between the tip and root
    circles, A = int_ra^rf (2 pi / z - 2 psi(r)) r dr = 12.93 mm^2, times b within 2 % (measured -0.10 % spur,
    -0.11 % helical; the left pass takes all but the strip the clearance leaves, c x depth x b), and each pass's chip
    is the force model's area times b within 2 %. The solid's flanks are the exact surface's within the sweep's
    tolerance."""
    gear = Gear(teeth=60, normal_module=2.0, face_width=20.0, internal=True, helix_angle=math.radians(beta))
    mill = fit_finger_mill(gear, 0.2)
    area = quad(lambda r: (2 * math.pi / gear.teeth - 2 * gear.half_thickness_angle(r)) * r, gear.tip_radius,
                gear.root_radius, epsabs=1e-12)[0]  # fmt: skip
    tol = 0.005
    passes = finger_passes(gear, mill, 0.2, spaces=[0], step=0.2)
    res = cut_gear(gear, mill, passes, tol)
    removed = sum(c[2] for c in res.chips)
    assert removed == pytest.approx(area * gear.face_width, rel=0.02)
    strip = 0.2 * gear.tooth_depth * gear.face_width
    assert res.chips[1][2] == pytest.approx(strip, rel=0.1)
    # the force model's removal per mm of feed (cutting/form_milling/forces.py) is each pass's chip over the face:
    # on the helical space the transverse section (the finger's own axial silhouette is 3.3 % narrower)
    areas = FingerLoad(gear, mill, material("16MnCr5"), 600.0, 8000.0, 0.2).areas
    for chip, side in zip(res.chips, SIDES, strict=True):
        assert areas[side] * gear.face_width == pytest.approx(chip[2], rel=0.02), (side, areas, chip)
    mesh = res.gear_solid.to_mesh()
    wp = MeshWorkpiece(MeshData(np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts)), "ring")
    exact = MilledGear(gear, mill, passes)
    L = np.linspace(form_roll_length(gear) - 0.2, roll(gear, gear.tip_diameter_value) + 0.2, 7)
    xi, zz = np.meshgrid(L / gear.base_radius, [-6.0, 0.0, 6.0])
    for side in SIDES:
        tooth = space_tooth(gear, 0, side)
        p = flank_points(gear, side, xi, zz, tooth).reshape(-1, 3)
        n = flank_normals(gear, side, xi, zz, tooth).reshape(-1, 3)
        d_exact, d_mesh = exact.probe(p, n, 0.05), wp.probe(p, n, 0.05)
        assert np.isfinite(d_mesh).all()
        assert np.abs(d_exact).max() < 1e-4 and np.abs(d_exact - d_mesh).max() < tol + 1e-3


def test_manifold_removal_of_a_large_external_space():
    """mn = 8, z = 20: one space's chips against the nominal space between the root and tip circles with the
    reference gear's outline (metrology.reference_gear: the involute, a radial line below the base circle, here
    5.2 mm above the root), A = 235.5 mm^2, times b within 2 % (measured -0.74 %: the finger's flat tip leaves
    x^2 / 2 r_f above the root circle at its corners, its flanks run on along their tangents below the form
    circle, inside the radial lines)."""
    gear = LARGE
    mill = fit_finger_mill(gear, 0.2)
    psi = np.vectorize(lambda r: gear.half_thickness_angle(max(r, gear.base_radius)))
    area = quad(lambda r: (2 * math.pi / gear.teeth - 2 * psi(r)) * r, gear.root_radius, gear.tip_radius,
                points=[gear.base_radius], epsabs=1e-10)[0]  # fmt: skip
    res = cut_gear(gear, mill, finger_passes(gear, mill, 0.2, spaces=[0], step=0.2), 0.005)
    assert sum(c[2] for c in res.chips) == pytest.approx(area * gear.face_width, rel=0.02)
    assert res.chips[1][2] == pytest.approx(0.2 * gear.tooth_depth * gear.face_width, rel=0.1)


# ---- bad input ---------------------------------------------------------------------------------------------------
def test_a_clearance_that_leaves_no_tip_is_refused():
    """c = 1.2 mm is wider than the internal space at its root (1.09 mm): the finger's flanks meet above the root."""
    with pytest.raises(ValueError, match=r"cannot reach the root.*reduce the clearance"):
        fit_finger_mill(INTERNAL, 1.2)
    with pytest.raises(ValueError, match="c >= 0"):
        fit_finger_mill(INTERNAL, -0.1)


def test_a_mill_too_thick_for_the_space_is_refused(internal_mill):
    """The mill fitted with c = 0.2 mm run with passes 0.2 mm off the symmetry line (c = 0.4 mm) overcuts each flank
    by 0.1 mm, and so does the mill of a module 2.2 mm ring in the module 2 ring's space."""
    with pytest.raises(ValueError, match=r"100\.0 um wider than the left flank's section.*fitted to this gear"):
        finger_passes(INTERNAL, internal_mill, 0.4, spaces=[0])
    bigger = fit_finger_mill(Gear(teeth=60, normal_module=2.2, face_width=20.0, internal=True), 0.2)
    with pytest.raises(ValueError, match="too thick for the space"):
        check_finger(INTERNAL, bigger, 0.2)
    check_finger(INTERNAL, internal_mill, 0.2)  # its own clearance: it touches the flank
    check_finger(INTERNAL, internal_mill, 0.1)  # nearer the symmetry line it leaves 50 um on each flank: no overcut


def test_a_mill_too_short_to_reach_the_root_is_refused(internal_mill):
    """A chain ending 1.7 mm from the tip cannot cut from the root out to the tip circle (tooth depth 4.5 mm)."""
    c = internal_mill.flank.control
    short = FingerMill(BezierChain(c[:1]), 4)
    assert short.width < 2.0
    with pytest.raises(ValueError, match="does not reach from the root to the tip circle"):
        finger_passes(INTERNAL, short, 0.2, spaces=[0])


def test_a_profile_that_is_not_single_valued_is_refused():
    """A radius curve that turns back along the axis (an S in v) is no solid of revolution's profile."""
    control = np.array([[[0.0, 1.0], [2.0, 1.2], [-1.0, 1.5], [1.0, 2.0]]])
    with pytest.raises(ValueError, match="not single-valued"):
        _ = FingerMill(BezierChain(control)).table


def test_a_helical_finger_fitted_to_a_design_is_refused():
    """A helical space's finger is the envelope of the nominal helicoid: the design is made by the path."""
    gear = Gear(teeth=60, normal_module=2.0, face_width=20.0, internal=True, helix_angle=math.radians(15.0))
    design = Modification(FlankDesign(lead_crowning=0.01), FlankDesign(lead_crowning=0.01))
    with pytest.raises(ValueError, match=r"envelope of its nominal helicoid.*without a design"):
        fit_finger_mill(gear, design=design)


def test_the_pass_clears_both_faces(internal_mill):
    """The pass starts and ends with the mill clear of the blank: its tip centre beyond each face by R + 0.5 mm."""
    (p, _) = finger_passes(INTERNAL, internal_mill, 0.2, spaces=[3])
    half = pass_length(INTERNAL, internal_mill)
    assert p.centre[0, 2] == pytest.approx(-half) and p.centre[-1, 2] == pytest.approx(half, abs=0.1)
    assert half - INTERNAL.face_width / 2 > internal_mill.radius
    # the axis points from the tip inwards, along the space's symmetry line: towards the gear axis
    a = 2 * math.pi * 3.5 / INTERNAL.teeth
    assert np.allclose(p.axis[0], [-math.cos(a), -math.sin(a), 0.0])


# ---- the copying plan with the finger mill ------------------------------------------------------------------------
def test_the_finger_plan_makes_a_lead_crowned_internal_spur():
    """Seed 003's steps with the finger mill: lead crowning 10 um on both flanks of the internal spur. The path
    (11 points, spline) stands after 3 iterations, the accuracy check (the exact swept surface against the design
    at every path point) ends within 0.1 um (measured 0.15 -> 0.024 um). Measured on teeth 1 and 2 (the gear on
    its nominal frame, as the datum finds a finger-milled ring: the test above): the helix over L_beta against the
    design F_beta < 0.1 um (measured 0.018), its crowning C_beta within 0.05 um of the design's 8.100 um over L_beta
    (measured 8.118), the profiles at 15/50/85 % of the face F_alpha < 0.1 um against the design (measured
    0.032)."""
    gear = INTERNAL
    design = Modification(FlankDesign(lead_crowning=0.010), FlankDesign(lead_crowning=0.010))
    plan = plan_finger(gear, design, 0.2, n=5)
    geo = [it["path_change_um"] for it in plan.iterations if it["step"] == "path"]
    checks = [it["max_residual_um"] for it in plan.iterations if it["step"] == "accuracy check"]
    assert geo[-1] < 1e-4 and checks[-1] < 0.1
    left = plan.paths[SIDES[0]]
    assert np.ptp(left.x) > 0.008  # the crowning is made by the path: the tip centre moves ~10 um sideways
    summary = json.loads(json.dumps(plan.summary()))
    assert summary["mill"]["type"] == "finger" and len(summary["path_bezier"]["left"]) == 10
    cut = MilledGear(gear, plan.mill, plan.all_passes(0.2, spaces=[-1, 0, 1]), "crowned ring")
    datum = Datum(0.0, gear.face_width, 0.0, 0, gear.teeth)
    teeth = np.array([[0], [1]])
    zh = np.linspace(*helix_range(gear), 40)
    L_ref = math.sqrt(gear.reference_radius**2 - gear.base_radius**2)
    L = np.linspace(*profile_range(gear, MeasureOptions()), 40)
    for side in SIDES:
        e = flank_deviation(cut, gear, datum, side, L_ref / gear.base_radius, zh[None, :], teeth)
        want = design.deviation(gear, side, L_ref, zh)
        assert evaluate_many(zh, e - want)["F"].max() * UM < 0.1
        for row in e:
            assert abs(crowning(zh, row) - crowning(zh, want)) * UM < 0.05
        for f in (0.15, 0.5, 0.85):
            zz = (f - 0.5) * gear.face_width
            e = flank_deviation(cut, gear, datum, side, L[None, :] / gear.base_radius, zz, teeth)
            ev = evaluate_many(L, e - design.deviation(gear, side, L, zz))
            assert ev["F"].max() * UM < 0.1, (side, f, ev)


def test_the_finger_plan_makes_a_crowned_and_twisted_helical_ring():
    """Seed 003's steps with the finger on a helical ring (z 40, beta 15 deg, b 20): lead crowning 10 um and twist
    6 um on both flanks. The finger (the envelope of the nominal helicoid) touches each flank up to 0.9 mm off its
    axis, so the path points go on past the faces (23 instead of 21) and step 15 reads them along the contact
    curves: 10.1 -> 2.14 -> 0.38 um in three rounds. Probed over the evaluation ranges (15 roll lengths x 11 face
    positions, both flanks): the topography within 1 um of the design (measured 0.55 / 0.60 um), the twist as the
    measuring machine reads it (metrology.modification.twist) within 1 um (measured 6.26 / 6.52 against 6.07),
    C_beta over the helix range within 0.5 um of the design's (8.40 / 8.40 against 8.10)."""
    from metrology.modification import twist

    gear = Gear(teeth=40, normal_module=2.0, helix_angle=math.radians(15.0), face_width=20.0, internal=True)
    design = FlankDesign(lead_crowning=0.010, twist=0.006)
    plan = plan_finger(gear, Modification(design, design))
    checks = [it["max_residual_um"] for it in plan.iterations if it["step"] == "accuracy check"]
    assert checks[-1] < 1.0 < checks[0] and plan.contact and len(plan.paths["left"].z) > 21
    cut = MilledGear(gear, plan.mill, plan.check_passes(0), "helical ring")
    lr, lt = roll(gear, gear.root_diameter_value), roll(gear, gear.tip_diameter_value)
    L = np.linspace(lr + 0.02 * (lt - lr), lt - 0.05 * (lt - lr), 15)
    z = np.linspace(-0.45 * gear.face_width, 0.45 * gear.face_width, 11)
    LL, zz = np.meshgrid(L, z, indexing="ij")
    cos_b = math.cos(gear.base_helix_angle)
    for side in SIDES:
        tooth = space_tooth(gear, 0, side)
        p = flank_points(gear, side, LL / gear.base_radius, zz, tooth).reshape(-1, 3)
        n = flank_normals(gear, side, LL / gear.base_radius, zz, tooth).reshape(-1, 3)
        e = (cut.probe(p, n, 0.05) / cos_b).reshape(LL.shape)  # along the base tangent, as the design's e
        want = design.deviation(gear, LL, zz)
        assert np.abs(e - want).max() * UM < 1.0
        assert abs(twist(L, z, e, gear.face_width) - twist(L, z, want, gear.face_width)) * UM < 1.0
        assert abs(crowning(z, e.mean(axis=0)) - crowning(z, want.mean(axis=0))) * UM < 0.5
