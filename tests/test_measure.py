"""Measurement against known answers: analytic gear meshes with imposed deviations (um = micrometres).

Meshes are fine enough that their own chordal error stays far below the 0.2 um acceptance: 100 points
per flank give an involute chord sagitta under 0.05 um over the evaluation range (asserted below), and
helical meshes are divided along the face so that the helix chord sagitta is under 0.02-0.1 um radially.
Each imposed deviation must come back within max(0.2 um, 3 %).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from cutting.errors import InputError
from cutting.flank import flank_polar_angle, side_sign
from cutting.gear import Gear
from metrology import thickness_nominal as nominal
from metrology.datum import check_mesh, measuring_radius
from metrology.measure import MeasureOptions, ball_centre_radius, helix_range, measure, profile_range
from metrology.reference_gear import chordal_error, reference_gear_mesh
from metrology.sections import MeshData
from metrology.tolerances import default_sector_pitches

DEG = math.pi / 180
GEARS = {
    "ext_spur": Gear(30, 2.0, 20 * DEG, 0.0, 12.0),
    "ext_helical": Gear(25, 2.0, 20 * DEG, 18 * DEG, 12.0),
    "int_spur": Gear(50, 2.0, 20 * DEG, 0.0, 12.0, internal=True),
    "int_helical": Gear(50, 2.0, 20 * DEG, -15 * DEG, 10.0, internal=True),
}
FLANK_POINTS = 100


def tol(expected_um: float) -> float:
    return max(0.2, 0.03 * abs(expected_um))


def mesh_of(gear: Gear, deviation=None, along_face: bool = True, **kw) -> MeshData:
    """The gear's mesh, turned by 0.1 pitch, with ``deviation``. One that does not vary ``along_face`` is exact on a
    spur gear without sections along the face: the 24 the reference gear puts under any deviation cost 3/4 of those
    spur tests' time and changed no measured value (measured); a helical gear keeps the sections of its helix."""
    if not along_face and gear.beta == 0:
        kw.setdefault("z_divisions", 0)
    pitch = 2 * math.pi / gear.teeth
    m = reference_gear_mesh(gear, deviation, flank_points=FLANK_POINTS, rotation=0.1 * pitch, helix_sagitta=2e-5, **kw)
    return check_mesh(m)


def unit(x, lo, hi):
    return (x - lo) / (hi - lo)


@pytest.fixture(scope="module", params=list(GEARS))
def gear(request) -> Gear:
    return GEARS[request.param]


# ---- the perfect gear ------------------------------------------------------------------------------
def test_mesh_fine_enough(gear):
    assert chordal_error(gear, FLANK_POINTS) < 1e-4  # worst chord near the base circle: < 0.1 um
    L0, L1 = profile_range(gear, MeasureOptions())
    assert min(L0, L1) > 1.0  # the evaluation range stays off the base circle, where chords are coarsest


def test_perfect_gear_measures_zero(gear):
    res = measure(mesh_of(gear), gear)
    for side in ("left", "right"):
        for key in ("F_alpha", "f_Halpha", "f_falpha"):
            assert abs(res["profile"][side][key]) < 0.2, (side, key, res["profile"][side][key])
        for key in ("F_beta", "f_Hbeta", "f_fbeta"):
            assert abs(res["helix"][side][key]) < 0.2
        assert res["pitch"][side]["f_p"] < 0.05 and res["pitch"][side]["F_p"] < 0.05
        assert len(res["profile"][side]["teeth"]) == gear.teeth
    assert res["runout"]["F_r"] < 0.05
    ob = res["thickness"]["over_balls"]
    assert abs(ob["M_dK_mm"] - ob["M_dK_nominal_mm"]) * 1e3 < 0.2
    if not gear.internal:
        sp = res["thickness"]["span"]
        assert abs(sp["W_k_mm"] - sp["W_k_nominal_mm"]) * 1e3 < 0.2
    assert res["thickness"]["tip_diameter_mm"] == pytest.approx(gear.tip_diameter_value, abs=1e-3)
    assert res["thickness"]["root_diameter_mm"] == pytest.approx(gear.root_diameter_value, abs=1e-3)
    assert res["iso1328"]["class"]["overall"] == 1
    # tooth 1 is the first counter-clockwise from +x: the mesh was turned by 0.1 pitch, so nominal tooth 0
    assert [t["tooth"] for t in res["profile"]["left"]["teeth"]] == list(range(1, gear.teeth + 1))


# ---- profile and helix: slope on the left flanks, crowning on the right -------------------------------
def test_profile_and_helix_deviations(gear):
    L0, L1 = profile_range(gear, MeasureOptions())
    z0, z1 = helix_range(gear)
    fha, ca, fhb, cb = 4.0e-3, 3.0e-3, 5.0e-3, 2.5e-3  # mm

    def dev(side, tooth, L, z):
        u, w = unit(L, L0, L1), unit(z, z0, z1)
        if side == "left":
            return fha * u + fhb * w
        return ca * (1 - (2 * u - 1) ** 2) + cb * (1 - (2 * w - 1) ** 2)

    res = measure(mesh_of(gear, dev), gear)
    left, right = res["profile"]["left"], res["profile"]["right"]
    assert left["f_Halpha"] == pytest.approx(4.0, abs=tol(4.0))
    assert left["F_alpha"] == pytest.approx(4.0, abs=tol(4.0))
    assert left["f_falpha"] < 0.2
    assert left["f_Halpha_mean"] == pytest.approx(4.0, abs=tol(4.0))
    assert right["F_alpha"] == pytest.approx(3.0, abs=tol(3.0))  # parabola over the range: F = f_f = C
    assert right["f_falpha"] == pytest.approx(3.0, abs=tol(3.0))
    assert abs(right["f_Halpha"]) < 0.2
    hl, hr = res["helix"]["left"], res["helix"]["right"]
    assert hl["f_Hbeta"] == pytest.approx(5.0, abs=tol(5.0)) and hl["F_beta"] == pytest.approx(5.0, abs=tol(5.0))
    assert hl["f_fbeta"] < 0.2
    assert hr["F_beta"] == pytest.approx(2.5, abs=tol(2.5)) and hr["f_fbeta"] == pytest.approx(2.5, abs=tol(2.5))
    assert abs(hr["f_Hbeta"]) < 0.2
    # the helix slope shows in every transverse section as a shift only: the profile stays clean there
    for t in left["teeth"]:
        assert t["worst"]["f_Halpha"] == pytest.approx(4.0, abs=tol(4.0))
    assert res["pitch"]["left"]["F_p"] < 0.05  # a uniform flank change moves no pitch


# ---- pitch: a per-tooth pattern of rotations ---------------------------------------------------------
def test_pitch_pattern(gear):
    z = gear.teeth
    r_p = measuring_radius(gear)
    k_idx = np.arange(z)
    arc = 3.0 * np.sin(2 * np.pi * k_idx / z) + 1.5 * ((k_idx % 3) - 1)  # um of arc on the measuring circle
    dtheta = arc * 1e-3 / r_p

    def dev(side, tooth, L, zz):
        return side_sign(gear, side) * gear.base_radius * dtheta[tooth]

    res = measure(mesh_of(gear, dev, along_face=False), gear)
    f_pi = arc - np.roll(arc, 1)
    k = default_sector_pitches(z)
    F_pk = max(abs(np.sum(np.take(f_pi, range(i, i + k), mode="wrap"))) for i in range(z))
    for side in ("left", "right"):
        p = res["pitch"][side]
        assert np.allclose(p["f_pi"], f_pi, atol=0.05)
        assert np.allclose(p["F_pi"], arc - arc[0], atol=0.05)
        assert p["f_p"] == pytest.approx(np.abs(f_pi).max(), abs=tol(np.abs(f_pi).max()))
        assert p["F_p"] == pytest.approx(np.ptp(arc), abs=tol(np.ptp(arc)))
        assert p["F_pk"] == pytest.approx(F_pk, abs=tol(F_pk)) and p["k"] == k
    assert res["profile"]["left"]["F_alpha"] < 0.2  # rigid tooth rotations leave the profile clean


# ---- eccentricity and tooth thickness ----------------------------------------------------------------
def _flank_arc_after_shift(gear: Gear, side: str, tooth: int, offset: float, r_p: float) -> float:
    """Arc position change on the circle r_p of a flank of the nominal gear translated by (offset, 0)."""
    rot = 0.1 * 2 * math.pi / gear.teeth

    def on_circle(r):
        th = flank_polar_angle(gear, r, 0.0, side, tooth) + rot
        return math.hypot(r * math.cos(th) + offset, r * math.sin(th)) - r_p

    r = brentq(on_circle, r_p - 0.2, r_p + 0.2, xtol=1e-14)
    th = flank_polar_angle(gear, r, 0.0, side, tooth) + rot
    moved = math.atan2(r * math.sin(th), r * math.cos(th) + offset)
    nominal_th = flank_polar_angle(gear, r_p, 0.0, side, tooth) + rot
    return r_p * ((moved - nominal_th + math.pi) % (2 * math.pi) - math.pi) * 1e3


def test_eccentricity_and_thickness(gear):
    ex, de = 8e-3, 10e-3  # mm: shift of the gear, and excess material on every flank
    res = measure(
        mesh_of(gear, lambda side, tooth, L, z: np.full(np.shape(L), de), along_face=False, offset=(ex, 0.0)), gear
    )
    D = res["runout"]["ball_diameter_mm"]
    g_thick = Gear(
        gear.teeth,
        gear.mn,
        gear.alpha_n,
        gear.beta,
        gear.face_width,
        profile_shift=gear.x + de * math.cos(gear.base_helix_angle) / (gear.mn * math.sin(gear.alpha_n)),
        internal=gear.internal,
    )
    # runout: ball seats translate with the gear
    pitch = 2 * math.pi / gear.teeth
    rk = ball_centre_radius(g_thick, D)
    phis = 0.1 * pitch + (np.arange(gear.teeth) + 0.5) * pitch
    rho = np.hypot(rk * np.cos(phis) + ex, rk * np.sin(phis))
    assert res["runout"]["F_r"] == pytest.approx(np.ptp(rho) * 1e3, abs=tol(np.ptp(rho) * 1e3))
    assert res["runout"]["F_r"] == pytest.approx(2 * ex * 1e3, rel=0.05)
    # pitch: the flank positions on the measuring circle of the shifted gear
    r_p = measuring_radius(gear)
    for side in ("left", "right"):
        u = np.array([_flank_arc_after_shift(g_thick, side, k, ex, r_p) for k in range(gear.teeth)])
        assert res["pitch"][side]["F_p"] == pytest.approx(np.ptp(u), abs=tol(np.ptp(u)))
    # thickness: the same as a larger profile shift; distances between balls ignore the shift
    ob = res["thickness"]["over_balls"]
    expected_m = nominal.over_balls(g_thick, D)
    assert (ob["M_dK_mm"] - expected_m) * 1e3 == pytest.approx(0.0, abs=0.2)
    assert abs(ob["M_dK_mm"] - ob["M_dK_nominal_mm"]) * 1e3 > 10  # the change is clearly seen
    if not gear.internal:
        sp = res["thickness"]["span"]
        expected_w = sp["W_k_nominal_mm"] + 2 * de * math.cos(gear.base_helix_angle)
        assert (sp["W_k_mm"] - expected_w) * 1e3 == pytest.approx(0.0, abs=0.2)


# ---- evaluation ranges by hand ---------------------------------------------------------------------
def test_evaluation_ranges_by_hand():
    g = Gear(40, 2.0, 20 * DEG, 0.0, 20.0)
    rb = 40 * math.cos(20 * DEG)
    L_form = rb * math.tan(20 * DEG) - 2.0 * (1.25 - 0.38 * (1 - math.sin(20 * DEG))) / math.sin(20 * DEG)
    L_tip = math.sqrt(42.0**2 - rb**2)
    L0, L1 = profile_range(g, MeasureOptions())
    assert L0 == pytest.approx(L_form, abs=1e-12) and L0 == pytest.approx(7.8334, abs=1e-4)
    assert L1 == pytest.approx(L_form + 0.95 * (L_tip - L_form), abs=1e-12)
    assert helix_range(g) == pytest.approx((-9.0, 9.0))  # L_beta = 20 - 2 min(1, 2)
    assert helix_range(Gear(40, 2.0, 20 * DEG, 0.0, 60.0)) == pytest.approx((-28.0, 28.0))  # 60 - 2 mn
    assert measuring_radius(g) == pytest.approx((84 + 75) / 4)
    set_range = profile_range(g, MeasureOptions(profile_start_diameter=78.0, profile_end_diameter=83.0))
    assert set_range == pytest.approx((math.sqrt(39**2 - rb**2), math.sqrt(41.5**2 - rb**2)))


# ---- bad input -------------------------------------------------------------------------------------
def test_bad_meshes_are_refused():
    g = GEARS["ext_spur"]
    m = reference_gear_mesh(g, flank_points=40)
    holed = m.copy()
    holed.update_faces(np.arange(len(holed.faces)) != 5)
    with pytest.raises(InputError, match="not watertight"):
        check_mesh(holed)
    data = check_mesh(m)
    with pytest.raises(InputError, match="z = 31 teeth"):
        measure(data, Gear(31, 2.0, 20 * DEG, 0.0, 12.0))
    with pytest.raises(InputError, match="z = 30 teeth"):  # wrong module: the circle misses the flanks
        measure(data, Gear(30, 2.5, 20 * DEG, 0.0, 12.0))
    lying = m.copy()
    lying.apply_transform(np.array([[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]], dtype=float))
    with pytest.raises(InputError, match="z extent"):
        measure(check_mesh(lying), g)
    tilted = m.copy()
    a = 3 * DEG
    tilted.apply_transform(
        np.array([[1, 0, 0, 0], [0, math.cos(a), -math.sin(a), 0], [0, math.sin(a), math.cos(a), 0], [0, 0, 0, 1]])
    )
    with pytest.raises(InputError, match="axis is not on z"):
        measure(check_mesh(tilted), Gear(30, 2.0, 20 * DEG, 0.0, tilted.extents[2]))


def test_axis_check_uses_the_section_area_centroid():
    """The axis check's section centre is the area centroid: it follows a shifted gear exactly (1e-6 mm) and a
    burr fin at a tooth tip (10 um x 1 mm, as a cut leaves at the entry face) moves it by less than 1 um."""
    import trimesh

    from metrology.datum import _section_centroid

    m = reference_gear_mesh(GEARS["ext_spur"], flank_points=40)
    z = m.bounds[1, 2] - 1.0
    centre = _section_centroid(MeshData(m.vertices, m.faces), z)
    shifted = m.copy()
    shifted.apply_translation([0.05, -0.03, 0.0])
    moved = _section_centroid(MeshData(shifted.vertices, shifted.faces), z)
    assert np.allclose(moved - centre, [0.05, -0.03], atol=1e-6)
    r_tip = float(np.hypot(m.vertices[:, 0], m.vertices[:, 1]).max())
    fin = trimesh.creation.box([1.0, 0.01, 2.5])
    tip = m.vertices[np.argmax(np.hypot(m.vertices[:, 0], m.vertices[:, 1]))]
    angle = math.atan2(tip[1], tip[0])
    fin.apply_transform(trimesh.transformations.rotation_matrix(angle, [0, 0, 1]))
    fin.apply_translation([(r_tip + 0.3) * math.cos(angle), (r_tip + 0.3) * math.sin(angle), z])
    burred = trimesh.boolean.union([m, fin], engine="manifold")
    assert burred.volume > m.volume + 0.01  # the fin is on the gear
    with_fin = _section_centroid(MeshData(burred.vertices, burred.faces), z)
    assert np.linalg.norm(with_fin - centre) < 1e-3


def test_iso_validity_is_enforced_with_a_clear_message():
    """ISO 1328-1:2013 covers b >= 4 mm: a 3 mm gear is measured, but gets no class and says why."""
    g = Gear(30, 2.0, 20 * DEG, 0.0, 3.0)
    res = measure(check_mesh(reference_gear_mesh(g, flank_points=40, rotation=0.05)), g)
    assert res["iso1328"]["class"] is None
    assert "b = 3" in res["iso1328"]["error"] and "4 <= b" in res["iso1328"]["error"]
    assert res["profile"]["left"]["F_alpha"] < 1.0  # the deviations are still reported
