"""Face tooth contours by continuous indexing (seed 004): the path against the seed's formulas, the slot bottom's
form at e = 0, flat at the setting sheet's e and reversed beyond it, the manifold cut against the exact slot, the
slot spacing, the controls, bad inputs. Tolerances in mm (1e-3 = 1 um)."""

import math
from dataclasses import replace

import numpy as np
import pytest
from checks import finite_max
from scipy.optimize import brentq

from cutting.face_contour.slots import (
    SWEEP_TOLERANCE,
    ExactSlots,
    FaceCoupling,
    cut_slots,
    cutting_speed,
    eccentric_speed,
    eccentric_tool_speed,
    element_path,
    exact_bottom,
    path_velocity,
    setting_sheet,
)
from metrology.face_slots import FLAT_TOLERANCE, measure_mesh, measure_slots, side_lines, slot_spacing

UM = 1e-3


def seed_tip(c: FaceCoupling, a: float, beta: float, final: bool = False) -> np.ndarray:
    """Eq. 5 by hand for the fixed setting (tool plane at a - lambda, lambda = arcsin(L / (R m)), eq. 1)."""
    lam = math.asin(c.L / (c.R * c.m))
    psi = a * c.m + beta
    feed = c.depth if final else c.S * psi / (2 * math.pi)
    return np.array(
        [
            c.L * math.cos(a) + c.R * math.sin(psi) * math.cos(a - lam),
            c.L * math.sin(a) + c.R * math.sin(psi) * math.sin(a - lam),
            c.R * (1 - math.cos(psi)) - feed,
        ]
    )


@pytest.fixture(scope="module")
def coupling() -> FaceCoupling:
    return FaceCoupling()


@pytest.fixture(scope="module")
def flat(coupling) -> FaceCoupling:
    return replace(coupling, control="eccentric", e=coupling.flat_bottom_eccentricity())


def test_element_path_is_the_seeds_formula():
    """One element's path (and a sector's second element) against eq. 5 by hand at a few angles: within 0.1 um."""
    c = FaceCoupling(elements=2, element_pitch=0.04)
    for j, beta in enumerate(c.phases):
        for a in (-0.013, 0.0, 0.0071, 0.25, 1.9):
            got = element_path(c, a * c.m, j)
            assert np.abs(got - seed_tip(c, a, beta)).max() < 1e-4 * UM
    # the eccentric (eq. 14, N = eccentric_ratio) and the cyclic ratio by hand
    ce = replace(FaceCoupling(), control="eccentric", e=5.0)
    cc = replace(FaceCoupling(), control="cyclic_ratio", ratio_amplitude=0.004)
    for phi in (-0.2, 0.05, 0.3):
        lam = math.asin(ce.L / ((ce.R - ce.eccentric_ratio * ce.e) * ce.m))
        a = phi / ce.m
        along = ce.R * math.sin(phi) - ce.e * math.sin(ce.eccentric_ratio * phi)
        z = ce.R * (1 - math.cos(phi)) - ce.e * (1 - math.cos(ce.eccentric_ratio * phi)) - ce.S * phi / (2 * math.pi)
        hand = [ce.L * math.cos(a) + along * math.cos(a - lam), ce.L * math.sin(a) + along * math.sin(a - lam), z]
        assert np.abs(element_path(ce, phi) - hand).max() < 1e-4 * UM
        a = phi / cc.m - cc.ratio_amplitude * (1 - math.cos(cc.ratio_cycles * phi))
        lam = math.asin(cc.L / (cc.R * cc.m))
        hand = [
            cc.L * math.cos(a) + cc.R * math.sin(phi) * math.cos(a - lam),
            cc.L * math.sin(a) + cc.R * math.sin(phi) * math.sin(a - lam),
            cc.R * (1 - math.cos(phi)) - cc.S * phi / (2 * math.pi),
        ]
        assert np.abs(element_path(cc, phi) - hand).max() < 1e-4 * UM


def test_setting_angle_makes_V_radial_at_M(coupling, flat):
    """Eq. 1 with the tool plane at a - lambda: V at M is radial and |V| is eq. 4's; the seed's printed a + lambda
    would leave V a tangential part 2 L omega_w. With the eccentric: eq. 1 on R - N e, eq. 15/16."""
    w = 2 * math.pi * 5  # tool speed [rad/s]
    for c in (coupling, flat):
        v = path_velocity(c, 0.0, tool_speed=w)
        assert abs(v[1]) < 1e-9 * abs(v[0])
        assert np.linalg.norm(v) == pytest.approx(float(cutting_speed(c, c.L, w)), rel=1e-9)
    c = coupling
    lam, h = math.asin(c.L / (c.R * c.m)), 1e-6
    plus = [c.L * math.sin(a) + c.R * math.sin(a * c.m) * math.sin(a + lam) for a in (-h, h)]
    assert (plus[1] - plus[0]) / (2 * h) == pytest.approx(2 * c.L, rel=1e-6)
    # eq. 15 is the tip's speed about the eccentric's axis; eq. 16 holds the cutting speed
    N, e, R = flat.eccentric_ratio, flat.e, flat.R
    for phi in (0.0, 0.1, 1.0):
        d = (
            np.array([R * math.cos(phi + s) - e * math.cos(N * (phi + s)) for s in (-h, h)]),
            np.array([R * math.sin(phi + s) - e * math.sin(N * (phi + s)) for s in (-h, h)]),
        )
        speed = math.hypot(*(np.diff(x)[0] / (2 * h) for x in d)) * w
        assert float(eccentric_speed(flat, phi, w)) == pytest.approx(speed, rel=1e-8)
        n = float(eccentric_tool_speed(flat, 2000.0, phi))
        assert float(eccentric_speed(flat, phi, 2 * math.pi * n)) == pytest.approx(2000.0, rel=1e-12)


def test_fixed_setting_bottom_is_concave_as_the_path_predicts(coupling):
    """e = 0: the bottom is the tool circle, deeper at M. The path by hand (eq. 5 at full depth, the tip where it
    is at the slot's inner end, middle and outer end) against the exact bottom on the radial centre line: the tip
    edge covers the line a few um off the path, which moves the reading by < 0.1 um."""
    c = coupling
    ends = np.array([c.inner_radius, c.middle_radius, c.outer_radius])

    def z_at(r):
        a = brentq(lambda a: np.hypot(*seed_tip(c, a, 0.0, final=True)[:2]) - r, -0.02, 0.02, xtol=1e-15)
        return seed_tip(c, a, 0.0, final=True)[2]

    hand = np.array([z_at(r) for r in ends])
    exact = exact_bottom(c, ends)
    assert np.abs(exact - hand).max() < 0.1 * UM
    predicted = 0.5 * (hand[0] + hand[2]) - hand[1]  # bottom below the chord: concave
    m = measure_slots(ExactSlots(c), c)[0]
    assert m.shape == "concave"
    assert predicted > 200 * UM
    assert m.form == pytest.approx(predicted, abs=0.1 * UM)
    assert m.bottom[len(m.radii) // 2] == pytest.approx(-c.depth, abs=1e-9)


def test_setting_sheet_eccentricity_makes_the_bottom_flat_and_more_reverses_it(coupling, flat):
    e = flat.e
    assert 0.5 < e / (coupling.R / coupling.eccentric_ratio**2) < 1.5  # near R / N^2
    m = measure_slots(ExactSlots(flat), flat)[0]
    assert m.shape == "flat"
    assert abs(m.form) <= 2 * UM
    assert np.ptp(m.bottom - np.interp(m.radii, m.radii[[0, -1]], m.bottom[[0, -1]])) <= 2 * UM
    less_e, more_e = replace(flat, e=0.5 * e), replace(flat, e=1.5 * e)
    half = measure_slots(ExactSlots(less_e), less_e)[0]
    more = measure_slots(ExactSlots(more_e), more_e)[0]
    assert half.shape == "concave" and half.form > 10 * UM
    assert more.shape == "convex" and more.form < -10 * UM
    assert setting_sheet(coupling)["flat_bottom_e_mm"] == pytest.approx(e, abs=1e-9)


@pytest.mark.parametrize("control", ["fixed", "eccentric"])
def test_manifold_cut_agrees_with_the_exact_slot(coupling, flat, control):
    """Three slots cut with manifold (hull chords within SWEEP_TOLERANCE), probed by rays and a plane section,
    against the exact slot: bottom, its form, sides within the tolerance; the spacing 2 pi / m within tol / L."""
    c = coupling if control == "fixed" else flat
    cut = cut_slots(c, (0, 1, 2))
    tol = SWEEP_TOLERANCE
    assert cut.chord_error <= tol
    assert cut.solid.genus() == 1  # the annulus, no slivers left (the cut's time: benchmarks/bench_face_contour.py)
    mesh, exact = measure_mesh(cut, c), measure_slots(ExactSlots(c), c, (0, 1, 2))
    for a, b in zip(mesh, exact, strict=True):
        assert a.shape == b.shape
        assert np.abs(a.bottom - b.bottom).max() <= tol
        assert abs(a.form - b.form) <= tol
        assert finite_max((a.sides - b.sides) * a.radii, 1.0) <= tol
        assert np.abs(a.side_bow - b.side_bow).max() <= tol
    assert np.abs(slot_spacing(c, exact)).max() < 1e-12
    assert np.abs(slot_spacing(c, mesh)).max() * c.L <= tol
    if control == "eccentric":
        assert abs(mesh[0].form) <= FLAT_TOLERANCE


def test_cyclic_ratio_straightens_the_slot(coupling):
    """The slot's centre line bows by ~ s^2 / (R m) under the fixed setting; the cyclic ratio at the sheet's
    amplitude takes that bow out (the sides keep only their symmetric narrowing with the bottom's rise)."""
    fixed = measure_slots(ExactSlots(coupling), coupling)[0]
    straight = replace(coupling, control="cyclic_ratio", ratio_amplitude=coupling.straight_slot_amplitude())
    cyc = measure_slots(ExactSlots(straight), straight)[0]
    half = 0.5 * (coupling.outer_radius - coupling.inner_radius)
    assert abs(fixed.side_bow.mean()) == pytest.approx(half**2 / (coupling.R * coupling.m), rel=0.1)
    assert abs(cyc.side_bow.mean()) < 0.5 * UM
    assert cyc.form == pytest.approx(fixed.form, abs=0.1 * UM)  # the bottom is the tool circle still


def seed_tip_with_settings(c: FaceCoupling, phi: float) -> np.ndarray:
    """Eq. 5 (final pass, element at beta = 0) with the settings changed during the cut, by hand: the eccentric
    (eq. 14) moves the head centre along the tool plane, the work's move T (1 - cos q_s phi) along the tool axis n
    moves it back across the plane; lambda by eq. 1 on R - N e."""
    e = c.e if c.eccentric_on else 0.0
    N = c.eccentric_ratio
    lam = math.asin(c.L / ((c.R - N * e) * c.m))
    a = phi / c.m
    along = c.R * math.sin(phi) - e * math.sin(N * phi)
    t = c.setting_offset * (1 - math.cos(c.setting_cycles * phi))
    return np.array(
        [
            c.L * math.cos(a) + along * math.cos(a - lam) + t * math.sin(a - lam),
            c.L * math.sin(a) + along * math.sin(a - lam) - t * math.cos(a - lam),
            c.R * (1 - math.cos(phi)) - e * (1 - math.cos(N * phi)) - c.depth,
        ]
    )


def path_centre_bow(c: FaceCoupling, radii: np.ndarray) -> float:
    """The bow [mm] of the tip's path (the slot's centre line) by the formula above, where it crosses ``radii``."""
    angles = []
    for r in radii:
        phi = brentq(lambda x, r=r: np.hypot(*seed_tip_with_settings(c, x)[:2]) - r, -0.2, 0.2, xtol=1e-15)
        p = seed_tip_with_settings(c, phi)
        angles.append(math.atan2(p[1], p[0]))
    return float(side_lines(radii, np.array([angles]))[1][0])


def centre_bow(m) -> float:
    """The measured centre line's bow [mm]: the line midway between the slot's sides."""
    return float(side_lines(m.radii, m.sides.mean(axis=0, keepdims=True))[1][0])


@pytest.mark.parametrize("base", ["fixed", "eccentric"])
def test_work_setting_changed_during_the_cut_straightens_the_slot(coupling, flat, base):
    """The seed's first control on the work: the work's setting changed during the cut (its axis moved along the
    tool axis by T (1 - cos q_s phi), q_s m cycles per workpiece revolution), alone and with the tool's eccentric
    ("tool and work together"). The path is eq. 5 with the moved settings (within 0.1 nm, by hand); the centre-line bow
    it removes, measured on the exact slot and on the manifold cut, equals what the path formula predicts within 1 um
    (the sides are measured half way down, the path is the tip's); the straight slot keeps its bottom (flat with the
    eccentric) and its sides bow < 3 um (the eccentric with the cyclic ratio leaves ~10 um)."""
    before = coupling if base == "fixed" else flat
    after = replace(before, control="work_setting" if base == "fixed" else "eccentric+work_setting")
    after = replace(after, setting_offset=after.straight_slot_offset())
    assert after.setting_offset == pytest.approx(2 * (after.R - after.eccentric_ratio * after.e) / (24 * 36))
    for phi in (-0.05, 0.02, 0.4):
        assert np.abs(element_path(after, phi, final=True) - seed_tip_with_settings(after, phi)).max() < 1e-4 * UM
    m0 = measure_slots(ExactSlots(before), before)[0]
    m1 = measure_slots(ExactSlots(after), after)[0]
    predicted = path_centre_bow(before, m0.radii) - path_centre_bow(after, m1.radii)
    removed = centre_bow(m0) - centre_bow(m1)
    assert abs(predicted) > 18 * UM  # s^2 / ((R - N e) m) at the slot's ends, s = 7.5 mm
    assert removed == pytest.approx(predicted, abs=1 * UM)
    assert abs(centre_bow(m1)) < 1 * UM
    assert m1.form == pytest.approx(m0.form, abs=0.01 * UM)  # the work moves horizontally: the bottom stays
    if base == "eccentric":
        assert m1.shape == "flat"
        assert np.abs(m1.side_bow).max() < 3 * UM
    mesh = measure_mesh(cut_slots(after, (0, 1)), after)
    for m in mesh:
        assert abs(centre_bow(m) - centre_bow(m1)) <= SWEEP_TOLERANCE
    assert np.abs(slot_spacing(after, mesh)).max() * after.L <= SWEEP_TOLERANCE


def test_sector_elements_are_the_element_turned_by_beta_over_m():
    """Under the fixed setting element j's path is element 0's turned by -beta_j / m about the workpiece axis."""
    c = FaceCoupling(elements=3, element_pitch=0.05)
    phi = np.linspace(-0.3, 0.3, 7)
    d = (c.phases[2] - c.phases[0]) / c.m
    p0 = element_path(c, phi - c.phases[0], 0)
    p2 = element_path(c, phi - c.phases[2], 2)
    rot = np.array([[math.cos(-d), -math.sin(-d)], [math.sin(-d), math.cos(-d)]])
    assert np.abs(p0[:, :2] @ rot.T - p2[:, :2]).max() < 1e-9
    assert np.abs(p0[:, 2] - p2[:, 2]).max() < 1e-9
    single = FaceCoupling()
    wide, one = measure_slots(ExactSlots(c), c)[0], measure_slots(ExactSlots(single), single)[0]
    assert np.all(np.diff(wide.sides, axis=0) > np.diff(one.sides, axis=0))


@pytest.mark.parametrize(
    ("change", "name"),
    [
        ({"m": 2, "R": 20.0}, "L"),  # L >= R m: no arcsin
        ({"m": 1}, "m"),
        ({"L": 70.0}, "L"),
        ({"outer_radius": 40.0}, "outer_radius"),
        ({"S": 0.0}, "S"),
        ({"depth": 0.1}, "depth"),  # the pass does not run through the face
        ({"control": "wobble"}, "control"),
        ({"e": 1.0}, "e"),  # an eccentricity without the eccentric control
        ({"control": "eccentric", "e": 40.0}, "e"),  # N e >= R
        ({"control": "cyclic_ratio", "ratio_amplitude": 0.01}, "ratio_amplitude"),  # the workpiece would reverse
        ({"edge_width": 12.0}, "edge_width"),
        ({"elements": 3, "element_pitch": 3.0}, "element_pitch"),
        ({"element_height": 2.0}, "element_height"),
        ({"flank_angle": 1.0}, "flank_angle"),
        ({"eccentric_ratio": 1}, "eccentric_ratio"),
        ({"setting_offset": 0.2}, "setting_offset"),  # a work setting without its control
        ({"control": "work_setting", "setting_offset": 6.0}, "setting_offset"),  # beyond L / 10
        ({"control": "work_setting", "setting_cycles": 0}, "setting_cycles"),
    ],
)
def test_bad_inputs_name_the_field(change, name):
    with pytest.raises(ValueError, match=rf"^{name}:"):
        replace(FaceCoupling(), **change)
