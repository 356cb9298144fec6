"""ISO 21771 gear quantities against values worked by hand (tolerances in mm unless stated)."""

import math

import pytest

from cutting.gear import Gear, check_gear
from cutting.involute import inv, inv_inverse

DEG = math.pi / 180


def spur40() -> Gear:
    return Gear(40, 2.0, 20 * DEG, 0.0, 20.0)


def helical60_internal() -> Gear:
    return Gear(60, 2.0, 20 * DEG, 20 * DEG, 20.0, internal=True)


def test_involute_and_inverse():
    assert inv(20 * DEG) == pytest.approx(0.014904383867336446, abs=1e-15)  # tan 20 deg - 20 deg
    for a in (0.05, 0.3, 0.6, 1.0, 1.3):
        assert inv_inverse(inv(a)) == pytest.approx(a, abs=1e-13)
    with pytest.raises(ValueError, match=">= 0"):
        inv_inverse(-0.1)


def test_spur_external_by_hand():
    g = spur40()
    assert g.reference_diameter == pytest.approx(80.0, abs=1e-12)
    assert g.base_diameter == pytest.approx(80 * math.cos(20 * DEG), abs=1e-12)  # 75.1754097
    assert g.base_diameter == pytest.approx(75.17540966, abs=1e-8)
    assert g.tip_diameter_value == pytest.approx(84.0) and g.root_diameter_value == pytest.approx(75.0)
    assert g.tooth_depth == pytest.approx(4.5)
    assert g.transverse_pitch == pytest.approx(2 * math.pi, abs=1e-12)
    assert g.transverse_base_pitch == pytest.approx(5.90426, abs=1e-5)
    assert g.normal_tooth_thickness == pytest.approx(math.pi, abs=1e-12)
    assert math.isinf(g.lead) and g.base_helix_angle == 0.0


def test_helical_internal_by_hand():
    g = helical60_internal()
    assert g.transverse_module == pytest.approx(2.1283555, abs=1e-7)
    assert g.reference_diameter == pytest.approx(127.7013327, abs=1e-6)
    assert math.degrees(g.transverse_pressure_angle) == pytest.approx(21.172832, abs=1e-6)
    assert g.base_diameter == pytest.approx(119.080876, abs=1e-6)
    assert math.degrees(g.base_helix_angle) == pytest.approx(18.747237, abs=1e-6)
    assert g.lead == pytest.approx(math.pi * 2 * 60 / math.sin(20 * DEG), abs=1e-9)  # 1102.2483 mm
    assert g.lead == pytest.approx(1102.2483, abs=1e-4)
    # internal: tip inside, root outside; x positive towards the tip (inwards)
    assert g.tip_diameter_value == pytest.approx(127.7013327 - 4.0, abs=1e-6)
    assert g.root_diameter_value == pytest.approx(127.7013327 + 5.0, abs=1e-6)
    shifted = Gear(60, 2.0, 20 * DEG, 20 * DEG, 20.0, profile_shift=0.5, internal=True)
    assert shifted.tip_diameter_value == pytest.approx(g.tip_diameter_value - 2.0, abs=1e-9)


def test_profile_shift_thickens_tooth():
    g = Gear(40, 2.0, 20 * DEG, 0.0, 20.0, profile_shift=0.5)
    assert g.normal_tooth_thickness == pytest.approx(2 * (math.pi / 2 + 2 * 0.5 * math.tan(20 * DEG)), abs=1e-12)
    assert g.normal_tooth_thickness == pytest.approx(3.8695, abs=1e-4)
    assert g.tip_diameter_value == pytest.approx(86.0)


def test_tip_thickness_formula():
    """s_a = d_a (s/d + inv(alpha_t) - inv(alpha_a)) (DIN 3960), spur z = 40: 1.5213 mm."""
    g = spur40()
    alpha_a = math.acos(g.base_diameter / 84.0)
    expected = 84.0 * (math.pi / 80 + inv(20 * DEG) - inv(alpha_a))
    assert g.tip_normal_thickness == pytest.approx(expected, abs=1e-12)
    assert g.tip_normal_thickness == pytest.approx(1.5213, abs=1e-4)


@pytest.mark.parametrize("x", [-0.4, 0.0, 0.3])
def test_internal_tooth_is_the_complement_of_an_external_tooth(x):
    """An internal gear's space equals the tooth of the external gear with -x: psi_int = pi/z - psi_ext(-x)."""
    internal = Gear(60, 2.0, 20 * DEG, 15 * DEG, 20.0, profile_shift=x, internal=True)
    external = Gear(60, 2.0, 20 * DEG, 15 * DEG, 20.0, profile_shift=-x)
    for r in (60.0, 63.0, 66.0):
        assert internal.half_thickness_angle(r) == pytest.approx(
            math.pi / 60 - external.half_thickness_angle(r), abs=1e-14
        )


def test_undercut_limit():
    """x_min = (hf - rho_f (1 - sin alpha)) - z sin^2(alpha)/2 = 0.99997 - 0.70187 = 0.2981 for z = 12."""
    g = Gear(12, 2.0, 20 * DEG, 0.0, 10.0)
    assert g.min_profile_shift == pytest.approx(0.2981, abs=1e-4)
    assert [p.key for p in check_gear(g)] == ["gear.profile_shift"]
    assert check_gear(Gear(12, 2.0, 20 * DEG, 0.0, 10.0, profile_shift=0.3)) == []
    assert Gear(17, 2.0, 20 * DEG, 0.0, 10.0).min_profile_shift == pytest.approx(0.0056, abs=1e-4)  # z_min ~ 17
    assert check_gear(Gear(17, 2.0, 20 * DEG, 0.0, 10.0, profile_shift=0.01)) == []


def test_pointed_and_inverted_diameters():
    pointed = Gear(12, 2.0, 20 * DEG, 0.0, 10.0, profile_shift=1.2)
    assert pointed.tip_normal_thickness < 0.4
    assert "pointed" in str(check_gear(pointed)[0])
    assert check_gear(Gear(40, 2.0, 20 * DEG, 0.0, 20.0, tip_diameter=74.0))[0].key == "gear.tip_diameter"
    internal_bad = Gear(60, 2.0, 20 * DEG, 0.0, 20.0, internal=True, tip_diameter=110.0)  # below d_b = 112.76
    problems = check_gear(internal_bad)
    assert problems[0].key == "gear.tip_diameter" and "base circle" in problems[0].reason


def test_rack_form_diameter():
    """Involute start from the rack: L = r_b tan(alpha) - mn (hf - rho(1 - sin alpha) - x) / sin(alpha)."""
    g = spur40()
    lift = 2.0 * (1.25 - 0.38 * (1 - math.sin(20 * DEG)))
    roll = g.base_radius * math.tan(20 * DEG) - lift / math.sin(20 * DEG)
    assert g.rack_form_diameter == pytest.approx(2 * math.hypot(g.base_radius, roll), abs=1e-12)
    assert g.base_diameter < g.rack_form_diameter < g.reference_diameter
