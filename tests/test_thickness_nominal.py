"""Nominal span and dimension over/between balls, against published values, hand values and independent
numerical constructions built only from Gear.half_thickness_angle (and the lead, for helical gears)."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

from cutting.gear import Gear
from metrology.thickness_nominal import (
    BALL_SERIES_MM,
    ball_contact_diameter,
    ball_diameter,
    ideal_ball_diameter,
    involute_limits,
    measuring_circle_diameter,
    over_balls,
    span,
    span_contact_diameter,
    span_min_face_width,
    span_teeth,
)

DEG = math.pi / 180


def spur20(**kw) -> Gear:
    return Gear(20, 2.0, 20 * DEG, 0.0, 20.0, **kw)


# ---- independent flank geometry -------------------------------------------------------------------
def flank_point(gear: Gear, centre: float, side: int, r: float, zz: float = 0.0) -> np.ndarray:
    """Point of the flank of the tooth centred at polar angle ``centre`` (at z = 0): side +1 = +theta side.

    theta = centre + 2 pi zz / p_z + side * psi(r), psi from Gear.half_thickness_angle.
    """
    twist = 0.0 if gear.helix_angle == 0.0 else 2 * math.pi / gear.lead
    th = centre + twist * zz + side * gear.half_thickness_angle(r)
    return np.array([r * math.cos(th), r * math.sin(th), zz])


def support(gear, centre, side, u, sign, zz=0.0):
    """sign * max over the flank (at axial zz) of sign * (P . u) in the transverse plane: (value, radius)."""
    rb = gear.base_radius
    f = lambda r: -sign * float(flank_point(gear, centre, side, r, zz)[:2] @ u)  # noqa: E731
    res = minimize_scalar(f, bounds=(rb * (1 + 1e-12), 3 * rb), method="bounded", options={"xatol": 1e-11})
    assert rb * 1.001 < res.x < 3 * rb * 0.999, "support point must be an interior tangency"
    return -sign * res.fun, res.x


def numeric_span(gear: Gear, k: int):
    """Distance between the two parallel anvil planes tangent to the outer flanks of teeth 0 .. k-1.

    Transverse support lines perpendicular to the bisector of the k teeth give h(zz); for a plane
    tangent along a line, n ~ (u, c) with h(zz) + c zz constant, so c = -dh/dzz (equal on both flanks
    for parallel planes) and W_k = (h+ - h-) / sqrt(1 + c^2). Returns (W_k, |angle of n to the
    transverse plane|, transverse contact radii at zz = 0).
    """
    z = gear.teeth
    phi = math.pi * (k - 1) / z
    u = np.array([-math.sin(phi), math.cos(phi)])
    top = 2 * math.pi * (k - 1) / z
    hp0, rp = support(gear, top, +1, u, +1)
    hm0, rm = support(gear, 0.0, -1, u, -1)
    dz = 3.0
    cp = -(support(gear, top, +1, u, +1, dz)[0] - hp0) / dz
    cm = -(support(gear, 0.0, -1, u, -1, dz)[0] - hm0) / dz
    assert cp == pytest.approx(cm, abs=1e-10)  # the two tangent planes are parallel
    c = 0.5 * (cp + cm)
    return (hp0 - hm0) / math.sqrt(1 + c * c), math.atan(abs(c)), (rp, rm)


def flank_distance(gear: Gear, centre: np.ndarray, helical: bool) -> tuple[float, float]:
    """Shortest distance from ``centre`` to the flank on the +theta side of tooth 0 and the radius where it occurs."""
    rb = gear.base_radius

    def at_z(zz):
        f = lambda r: float(np.linalg.norm(flank_point(gear, 0.0, +1, r, zz) - centre))  # noqa: E731
        res = minimize_scalar(f, bounds=(rb * (1 + 1e-12), 2 * rb), method="bounded", options={"xatol": 1e-11})
        return res.fun, res.x

    if not helical:
        return at_z(0.0)
    res = minimize_scalar(lambda zz: at_z(zz)[0], bounds=(-5.0, 5.0), method="bounded", options={"xatol": 1e-11})
    return at_z(res.x)


def numeric_over_balls(gear: Gear, D: float) -> tuple[float, float]:
    """Ball centre on the space centre line (angle pi/z) at the radius where it is D/2 from the flank.

    Returns (M, contact diameter). M from the two ball centres placed in opposite spaces in one
    transverse plane: |C1 - C2| + D (external) or |C1 - C2| - D (internal).
    """
    z = gear.teeth
    phi = math.pi / z
    helical = gear.helix_angle != 0.0

    def centre(rho, ang=phi):
        return np.array([rho * math.cos(ang), rho * math.sin(ang), 0.0])

    g = lambda rho: flank_distance(gear, centre(rho), helical)[0] - D / 2  # noqa: E731
    # Scan for the crossing: external, the gap to the flank grows outwards; internal, it shrinks outwards.
    # (Near the base circle the nearest flank point is the end of the involute: no tangency, skip it.)
    grid = gear.reference_radius + gear.mn * np.linspace(-2.0, 2.0, 41)
    vals = [g(rho) for rho in grid]
    want = (lambda a, b: a < 0 < b) if not gear.internal else (lambda a, b: a > 0 > b)
    i = next(i for i in range(40) if want(vals[i], vals[i + 1]))
    rho = brentq(g, grid[i], grid[i + 1], xtol=1e-13)
    contact_r = flank_distance(gear, centre(rho), helical)[1]
    j = z // 2  # opposite space: pi apart (z even) or pi - pi/z apart (z odd)
    sep = float(np.linalg.norm(centre(rho) - centre(rho, phi + 2 * math.pi * j / z)))
    return sep + (-D if gear.internal else D), 2 * contact_r


# ---- span -----------------------------------------------------------------------------------------
def test_span_published_values():
    g = spur20()
    # ISO 21771 / DIN 3960 check value: W3 = 15.321 mm, W4 = 21.225 mm (published to 1 um).
    assert abs(span(g, 3) - 15.321) < 5e-4
    assert abs(span(g, 4) - 21.225) < 5e-4
    # by hand: 2 cos20 (2.5 pi + 20 inv20) = 1.8793852 * (7.8539816 + 0.2980877) = 15.3208788
    assert span(g, 3) == pytest.approx(15.3208788, abs=1e-6)
    assert span(g, 4) == pytest.approx(21.2251416, abs=1e-6)
    assert span_teeth(g) == 3


def test_span_profile_shift_term_is_exact():
    for beta in (0.0, 15 * DEG, -25 * DEG):
        g0 = Gear(31, 2.5, 20 * DEG, beta)
        for x in (-0.3, 0.2, 0.5):
            gx = Gear(31, 2.5, 20 * DEG, beta, profile_shift=x)
            for k in (4, 5):
                assert span(gx, k) - span(g0, k) == pytest.approx(2 * x * 2.5 * math.sin(20 * DEG), abs=1e-12)


@pytest.mark.parametrize(
    "gear,k",
    [
        (spur20(), 3),
        (Gear(37, 3.0, 20 * DEG, 0.0, profile_shift=0.4), 5),
        (Gear(31, 2.0, 20 * DEG, 20 * DEG, 30.0, profile_shift=0.25), 4),
        (Gear(45, 1.5, 25 * DEG, -30 * DEG, 30.0, profile_shift=-0.2), 7),
    ],
)
def test_span_against_independent_plane_construction(gear, k):
    w, lean, (rp, rm) = numeric_span(gear, k)
    assert span(gear, k) == pytest.approx(w, abs=1e-9)
    assert lean == pytest.approx(abs(gear.base_helix_angle), abs=1e-9)  # plane normal inclined at beta_b
    # the transverse contacts are symmetric about the bisector in this section: d_M of the docstring
    assert 2 * rp == pytest.approx(span_contact_diameter(gear, k), abs=1e-6)
    assert 2 * rm == pytest.approx(span_contact_diameter(gear, k), abs=1e-6)


def test_span_contact_diameter_by_hand():
    g = spur20()
    # sqrt(db^2 + W3^2) = sqrt(37.5877048^2 + 15.3208788^2) = 40.5902067
    assert span_contact_diameter(g, 3) == pytest.approx(40.5902067, abs=1e-6)
    assert g.rack_form_diameter < span_contact_diameter(g, 2) < span_contact_diameter(g, 4) < g.tip_diameter_value


def test_span_teeth_classic_rule_for_spur_20deg():
    for z in range(10, 201):
        k = span_teeth(Gear(z, 2.0))
        if z % 9 == 0:
            # k* = z/9 + 0.5 is exactly half-way; the contact of the smaller k is closer in diameter
            assert k == max(2, z // 9), z
        else:
            assert k == max(2, min(z - 1, round(z / 9 + 0.5))), z


def test_span_teeth_follows_derived_k_star_with_shift_and_helix():
    """k* = z (tan(alpha_yt) - inv(alpha_t)) / pi - 2 x tan(alpha_n) / pi + 1/2, cos(alpha_yt) = d_b / (d + 2 x mn)."""
    checked = 0
    for z in (17, 24, 33, 48, 71, 101):
        for x in (-0.2, 0.0, 0.3, 0.6):
            for beta in (0.0, 12 * DEG, 30 * DEG):
                g = Gear(z, 2.0, 20 * DEG, beta, 40.0, profile_shift=x)
                if x < g.min_profile_shift:
                    continue
                at = g.transverse_pressure_angle
                ayt = math.acos(g.base_diameter / (g.reference_diameter + 2 * x * g.mn))
                k_star = (
                    z * (math.tan(ayt) - (math.tan(at) - at)) / math.pi - 2 * x * math.tan(g.alpha_n) / math.pi + 0.5
                )
                if abs(k_star % 1 - 0.5) < 0.2:  # near a tie the diameter criterion may pick the other one
                    continue
                assert span_teeth(g) == round(k_star), (z, x, beta)
                checked += 1
    assert checked > 30


def test_span_teeth_picks_contact_closest_to_measuring_circle():
    g = Gear(43, 2.0, 20 * DEG, 18 * DEG, 40.0, profile_shift=0.35)
    k = span_teeth(g)
    dy = measuring_circle_diameter(g)
    assert dy == pytest.approx(g.reference_diameter + 0.7 * 2.0)
    assert abs(span_contact_diameter(g, k) - dy) < abs(span_contact_diameter(g, k - 1) - dy)
    assert abs(span_contact_diameter(g, k) - dy) < abs(span_contact_diameter(g, k + 1) - dy)


def test_span_min_face_width():
    spur = spur20()
    assert span_min_face_width(spur, 3) == pytest.approx(5.0, abs=1e-12)
    g = Gear(31, 2.0, 20 * DEG, 20 * DEG, 30.0)
    bb = math.asin(math.sin(20 * DEG) * math.cos(20 * DEG))  # 18.747 deg
    w = span(g, 4)
    assert span_min_face_width(g, 4, anvil_width=8.0) == pytest.approx(w * math.sin(bb) + 8.0 * math.cos(bb), abs=1e-12)
    left = Gear(31, 2.0, 20 * DEG, -20 * DEG, 30.0)
    assert span_min_face_width(left, 4, 8.0) == pytest.approx(span_min_face_width(g, 4, 8.0), abs=1e-12)
    with pytest.raises(ValueError, match="anvil_width"):
        span_min_face_width(g, 4, anvil_width=0.0)


def test_span_errors():
    internal = Gear(60, 2.0, internal=True)
    with pytest.raises(ValueError, match="internal gear"):
        span_teeth(internal)
    with pytest.raises(ValueError, match="internal gear"):
        span(internal, 7)
    g = spur20()
    for bad in (0, 20, -1, 2.5, True, "3"):
        with pytest.raises(ValueError, match="spanned teeth k"):
            span(g, bad)
    # W5 = 27.13 mm would need contact at d = 46.6 mm, above the tip (44 mm)
    with pytest.raises(ValueError, match="above the tip"):
        span(g, 5)
    with pytest.raises(TypeError):
        span_teeth("not a gear")
    with pytest.raises(ValueError, match="normal_module"):
        span(Gear(20, -2.0), 3)
    with pytest.raises(ValueError, match="at least 3"):
        span_teeth(Gear(2, 2.0))


# ---- balls ----------------------------------------------------------------------------------------
def test_over_balls_by_hand():
    """z = 20, m = 2, 20 deg, x = 0, D = 3.5 mm, worked on a calculator (DIN 3960 formula):

    inv(alpha_K) = inv 20 + D/(z m cos 20) - pi/(2z) = 0.0149044 + 0.0931156 - 0.0785398 = 0.0294801
    alpha_K = 24.8687 deg, cos = 0.9072737; d_K = d_b / cos = 37.5877048 / 0.9072737 = 41.42929
    z even: M = d_K + D = 44.92929 mm.
    """
    g = spur20()
    assert over_balls(g, 3.5) == pytest.approx(44.92929, abs=1e-5)


@pytest.mark.parametrize(
    "gear,D",
    [
        (spur20(), 3.5),
        (Gear(21, 2.0), 3.5),
        (spur20(profile_shift=0.3), 3.75),
        (Gear(23, 2.0, profile_shift=0.3), 3.75),
        (Gear(60, 2.0, internal=True), 3.5),
        (Gear(61, 2.0, internal=True, profile_shift=0.3), 3.0),
        (Gear(60, 2.0, internal=True, profile_shift=-0.25), 3.5),
    ],
)
def test_over_balls_against_independent_circle_construction(gear, D):
    m_num, dy_num = numeric_over_balls(gear, D)
    assert over_balls(gear, D) == pytest.approx(m_num, abs=1e-9)
    assert ball_contact_diameter(gear, D) == pytest.approx(dy_num, abs=1e-5)


@pytest.mark.parametrize(
    "gear,D",
    [
        (Gear(30, 2.0, 20 * DEG, 20 * DEG, 40.0), 3.5),
        (Gear(31, 2.0, 20 * DEG, -25 * DEG, 40.0, profile_shift=0.3), 3.75),
        (Gear(60, 2.0, 20 * DEG, 20 * DEG, 40.0, internal=True), 3.5),
        (Gear(59, 2.0, 20 * DEG, 15 * DEG, 40.0, internal=True, profile_shift=0.2), 3.25),
    ],
)
def test_over_balls_helical_against_sphere_on_helicoid(gear, D):
    """A sphere touching the 3D helicoid (shortest distance over radius and axial position): the
    DIN form with D / (z mn cos(alpha_n)) and the transverse inv(alpha_t) is exact for balls."""
    m_num, dy_num = numeric_over_balls(gear, D)
    assert over_balls(gear, D) == pytest.approx(m_num, abs=1e-9)
    assert ball_contact_diameter(gear, D) == pytest.approx(dy_num, abs=1e-5)


def test_internal_sign_of_profile_shift():
    """x > 0 thickens an internal gear's teeth: the spaces narrow, the balls stay nearer the axis, M shrinks."""
    base = Gear(60, 2.0, internal=True)
    shifted = Gear(60, 2.0, internal=True, profile_shift=0.2)
    assert over_balls(shifted, 3.5) < over_balls(base, 3.5)
    # and the exact size of the change, from the independent construction
    assert over_balls(shifted, 3.5) == pytest.approx(numeric_over_balls(shifted, 3.5)[0], abs=1e-6)


def test_ideal_and_standard_ball():
    g = spur20()
    ideal = ideal_ball_diameter(g)
    assert ball_contact_diameter(g, ideal) == pytest.approx(40.0, abs=1e-9)  # on the reference circle
    assert ideal == pytest.approx(3.44890, abs=1e-5)
    assert ball_diameter(g) == 3.5 and 3.5 in BALL_SERIES_MM
    # rack limit pi mn / (2 cos alpha_n) = 1.6716 mn; the 1.68 mn rule of thumb lies within 3 % for z >= 20
    assert ideal_ball_diameter(Gear(20000, 1.0)) == pytest.approx(math.pi / (2 * math.cos(20 * DEG)), rel=1e-4)
    for z in (20, 40, 100):
        assert ideal_ball_diameter(Gear(z, 1.0)) == pytest.approx(1.68, rel=0.03)
    # profile-shifted: contact on d + 2 x mn
    gx = spur20(profile_shift=0.4)
    assert ball_contact_diameter(gx, ideal_ball_diameter(gx)) == pytest.approx(41.6, abs=1e-9)
    # internal z = 60, m = 2: contact on d = 120 mm with D = 3.3124 mm -> 3.5 mm; M between balls
    gi = Gear(60, 2.0, internal=True)
    assert ball_contact_diameter(gi, ideal_ball_diameter(gi)) == pytest.approx(120.0, abs=1e-9)
    assert ball_diameter(gi) == 3.5
    lo, hi = involute_limits(gi)
    assert lo < ball_contact_diameter(gi, 3.5) < 120.0 < hi  # a larger ball touches nearer the (inner) tip
    # helical: contact on d
    gh = Gear(31, 3.0, 20 * DEG, 25 * DEG, 30.0)
    assert ball_contact_diameter(gh, ideal_ball_diameter(gh)) == pytest.approx(gh.reference_diameter, abs=1e-9)


def test_ball_errors():
    g = spur20()
    for bad in (0.0, -1.0, float("nan"), "x"):
        with pytest.raises(ValueError, match="ball diameter D"):
            over_balls(g, bad)
    with pytest.raises(ValueError, match="too small"):
        over_balls(g, 2.0)  # falls between the flanks: inv(alpha_K) < 0
    with pytest.raises(ValueError, match="below the form diameter"):
        over_balls(g, 2.4)  # touches at d = 37.597 mm < d_Ff = 37.640 mm
    with pytest.raises(ValueError, match="above the tip"):
        over_balls(g, 8.0)  # touches at d = 44.75 mm > d_a = 44 mm
    with pytest.raises(ValueError, match="too large"):
        over_balls(Gear(60, 2.0, internal=True), 5.0)
    with pytest.raises(ValueError, match="inside the tip circle"):
        over_balls(Gear(60, 2.0, internal=True), 4.5)
    # tip turned down to 40.05 mm: the 3.5 mm ball would touch at 40.08 mm, on the tip edge
    with pytest.raises(ValueError, match="not on the involute"):
        ball_diameter(spur20(tip_diameter=40.05))
    with pytest.raises(ValueError, match="larger than every size"):
        ball_diameter(g, series=(1.0, 2.0, 3.0))
