"""The skiving setup: shaft angle, centre distances, speed ratio, kinematics and interference."""

import math

import numpy as np
import pytest

from cutting.gear import Gear
from cutting.skiving.kinematics import INTERFERENCE_TOLERANCE, SkivingSetup, check_setup

DEG = math.pi / 180
PASSES = (2.0, 1.5, 0.8, 0.2)


def setup(z2=40, beta2=0.0, z0=23, beta0=20.0, internal=False, x2=0.0, x0=0.0, passes=PASSES, **kw) -> SkivingSetup:
    gear = Gear(z2, 2.0, 20 * DEG, beta2 * DEG, 20.0, profile_shift=x2, internal=internal)
    cutter = Gear(z0, 2.0, 20 * DEG, beta0 * DEG, 20.0, profile_shift=x0)
    return SkivingSetup(gear, cutter, kw.pop("tool_speed", 2500.0), kw.pop("feed", 0.2), passes, **kw)


@pytest.mark.parametrize(
    ("beta2", "beta0", "internal", "sigma"),
    [(0, 20, False, 20), (20, -30, False, -10), (15, 10, False, 25), (20, 0, True, 20), (20, -15, True, 35)],
)
def test_shaft_angle_sign(beta2, beta0, internal, sigma):
    """Sigma = beta2 + beta0 external, beta2 - beta0 internal (domain.md section 1)."""
    st = setup(60 if internal else 40, beta2, 25 if internal else 23, beta0, internal)
    assert math.degrees(st.shaft_angle) == pytest.approx(sigma, abs=1e-12)


def test_spur_external_by_hand():
    st = setup()
    r0 = 23 * 2.0 / math.cos(20 * DEG) / 2  # 24.476089 mm
    assert st.final_centre_distance == pytest.approx(40.0 + r0, abs=1e-12)
    assert st.final_centre_distance == pytest.approx(64.476089, abs=1e-6)
    assert st.cutter_tip_diameter == pytest.approx(2 * (64.476089 - 37.5), abs=2e-6)  # cuts df = 75
    assert st.generated_root_diameter == pytest.approx(75.0, abs=1e-12)
    assert st.touch_centre_distance == pytest.approx(42.0 + st.cutter_tip_diameter / 2, abs=1e-12)
    assert st.full_depth == pytest.approx(4.5, abs=1e-12)
    assert st.pass_centre_distances == pytest.approx((66.976089, 65.476089, 64.676089, 64.476089), abs=1e-6)
    assert st.work_speed == pytest.approx(2500 * 23 / 40)
    v = math.pi * 2 * r0 * 2500 * math.sin(20 * DEG) / 1000  # m/min
    assert st.cutting_speed == pytest.approx(v, abs=1e-9) and v == pytest.approx(131.496, abs=1e-3)
    feed_rate = 0.2 * 1437.5 / 60
    assert st.pass_times == pytest.approx(tuple(t / feed_rate for t in st.pass_travel), rel=1e-12)
    assert all(
        20.0 + 2.0 < t < 20.0 + 2.0 + 2 * st.cutter_tip_diameter / 2 * math.sin(20 * DEG) for t in st.pass_travel
    )


def test_profile_shift_moves_the_centre_distance():
    """Common rack of crossed gears: a = r2 + r0 + (x2 + x0) mn; internal a = r2 - r0 - (x2 + x0) mn."""
    assert setup(x2=0.3, x0=0.1).final_centre_distance - setup().final_centre_distance == pytest.approx(0.8)
    a_int = setup(60, 20, 25, 0, True, x2=0.2, x0=0.1).final_centre_distance
    assert a_int == pytest.approx(60 * 2 / math.cos(20 * DEG) / 2 - 25 - 0.6, abs=1e-12)


@pytest.mark.parametrize(
    ("z2", "beta2", "z0", "beta0", "internal"),
    [(40, 0, 23, 20, False), (40, 15, 31, -5, False), (60, 20, 25, 0, True), (71, -12, 29, 10, True)],
)
@pytest.mark.parametrize(("x2", "x0"), [(0.0, 0.0), (0.3, 0.0), (-0.2, 0.15)])
def test_speed_ratio_is_z0_over_z2(z2, beta2, z0, beta0, internal, x2, x0):
    st = setup(z2, beta2, z0, beta0, internal, x2=x2, x0=x0)
    assert abs(st.speed_ratio) == pytest.approx(z0 / z2, abs=1e-12)
    assert np.sign(st.speed_ratio) == (1 if internal else -1)


def test_profile_shifted_pair_generates_without_interference():
    """The edge rolls on the gear's own reference cylinder whatever x2 and x0 are."""
    for x2, x0 in ((0.3, 0.0), (-0.2, 0.1)):
        assert setup(x2=x2, x0=x0).edge_intrusion() < 0.005
    assert check_setup(setup(12, 0, 23, 20, x2=0.35)) == []


def test_pose_is_rigid_and_follows_the_kinematics():
    st = setup(60, 20, 25, 0, True)
    phi0 = np.linspace(0, 1.0, 11)
    s = np.linspace(-3, 5, 11)
    rot, t = st.cutter_pose(phi0, s)
    assert np.allclose(np.einsum("nij,nkj->nik", rot, rot), np.eye(3), atol=1e-12)
    assert np.allclose(np.linalg.det(rot), 1.0)
    phi2 = st.speed_ratio * phi0 + st.differential_rotation_per_mm * s + st.work_phase
    # the cutter centre sits at (a, 0, s) in the machine frame: in the work frame it is turned back by phi2
    assert np.allclose(np.arctan2(t[:, 1], t[:, 0]), -phi2, atol=1e-12)
    assert np.allclose(t[:, 2], s) and np.allclose(np.hypot(t[:, 0], t[:, 1]), st.final_centre_distance)
    # B4: one lead of carriage travel turns the work back by one revolution
    assert st.differential_rotation_per_mm * st.gear.lead == pytest.approx(-2 * math.pi)


def test_ideal_edge_does_not_enter_the_teeth():
    for st in (setup(), setup(60, 20, 25, 0, True)):
        assert st.edge_intrusion() < 0.005  # the involute edge's own bow is a few micrometres at most


def test_internal_tip_interference_sets_in_as_the_cutter_grows():
    """Internal spur z2 = 60, helical cutter (Sigma = 20 deg): interference appears between z0 = 40 and 50."""
    ok = setup(60, 0, 40, 20, True)
    bad = setup(60, 0, 50, 20, True)
    assert ok.edge_intrusion() < INTERFERENCE_TOLERANCE
    assert bad.edge_intrusion() > 0.1
    assert check_setup(ok) == []
    assert [p.key for p in check_setup(bad)] == ["cutter.teeth"]
    # with parallel axes (a shaper cutter) the classic limit for 20 deg full depth is z2 - z0 of about 8
    parallel = [setup(60, 0, z0, 0, True).edge_intrusion() for z0 in (48, 50, 52, 54)]
    assert parallel[0] < INTERFERENCE_TOLERANCE and parallel[1] < INTERFERENCE_TOLERANCE
    assert parallel[2] > 0.05 and parallel[3] > parallel[2]


def test_check_setup_reports_what_cannot_cut():
    assert check_setup(setup(beta0=0.0))[0].key == "cutter.helix_angle"  # spur + spur: Sigma = 0
    too_big = check_setup(setup(60, 0, 60, 20, True))
    assert too_big[0].key == "cutter.teeth" and "too large" in too_big[0].reason
    # helical internal z2 = 60 with a spur cutter: a 58-tooth cutter (tip 121 mm) cannot pass the bore 123.7 - 4 mm
    assert [p.key for p in check_setup(setup(60, 20, 58, 0, True))] == ["cutter.teeth"]
    assert check_setup(setup(60, 20, 55, 0, True)) == []
    deep = check_setup(setup(passes=(3.0, 2.0)))
    assert deep[0].key == "process.passes" and "4.5000" in deep[0].hint
    assert check_setup(setup(passes=(2.0, 1.0))) == []  # shallower than full depth is allowed


@pytest.mark.parametrize(
    "args", [(60, 0, 50, 20, True), (60, 0, 52, 0, True), (60, 0, 40, 20, True), (20, 0, 17, 20, False)]
)
def test_the_intrusion_looks_closely_only_at_the_teeth_that_can_hold_the_deepest_point(args):
    """edge_intrusion samples every tooth coarsely and only the teeth near the mesh at every angle: the same
    maximum as every tooth at every angle (interfering and clear setups, internal and external)."""
    st = setup(*args)
    phi0 = np.linspace(0.0, 2 * np.pi / st.cutter.teeth, 720, endpoint=False)
    every, _ = st._depth(st.edge_in_work_frame(st.edge_points(), phi0).reshape(-1, 3), 0.0)
    assert st.edge_intrusion() == pytest.approx(float(every.max()), abs=1e-12)
