"""ISO 1328-1:2013 flank tolerances (um) against values worked by hand from the class-5 formulas.

Class-5 formulas (d, mn, b in mm): fpT = 0.001d + 0.4mn + 5; FpT = 0.002d + 0.55 sqrt(d) + 0.7mn + 12;
fHaT = 0.4mn + 0.001d + 4; ffaT = 0.55mn + 5; FaT = sqrt(fHaT^2 + ffaT^2); fHbT = 0.05 sqrt(d) + 0.35 sqrt(b) + 4;
ffbT = 0.07 sqrt(d) + 0.45 sqrt(b) + 4; FbT = sqrt(fHbT^2 + ffbT^2); FrT = 0.9 FpT;
FpkT = fpT + (4k/z)(0.001d + 0.55 sqrt(d) + 0.3mn + 7). Class A: times sqrt(2)^(A-5), then round once:
> 10 um to 1, 5..10 um to 0.5, < 5 um to 0.1, ties up.
"""

import math

import pytest

from metrology.tolerances import (
    CLASSES,
    PARAMETERS,
    check_class,
    default_sector_pitches,
    grade,
    helix_form,
    helix_slope,
    overall_class,
    profile_form,
    profile_slope,
    reference_diameter,
    round_tolerance,
    runout,
    sector_pitch,
    single_pitch,
    step_factor,
    tolerances,
    total_cumulative_pitch,
    total_helix,
    total_profile,
    validate,
)

# issue gear (spur): z = 40, mn = 3, d = 120, b = 30
SPUR = {"z": 40, "mn": 3.0, "b": 30.0, "beta_deg": 0.0}
# helical gear: z = 30, mn = 2, beta = 20 deg, b = 20 -> d = 60 / cos 20 deg = 60 / 0.93969262 = 63.850666 mm
HELICAL = {"z": 30, "mn": 2.0, "b": 20.0, "beta_deg": 20.0}


def test_issue_vector_class6_spur():
    # d = 120, sqrt(120) = 10.954451, sqrt(2) = 1.4142136
    # fpT5 = 0.12 + 1.2 + 5 = 6.32                                        -> x1.4142 = 8.9378   -> 9.0 (0.5 band)
    # FpT5 = 0.24 + 0.55*10.954451 + 2.1 + 12 = 0.24 + 6.024948 + 14.1 = 20.364948 -> 28.8004 -> 29
    # fHaT5 = 1.2 + 0.12 + 4 = 5.32, ffaT5 = 1.65 + 5 = 6.65
    # FaT5 = sqrt(5.32^2 + 6.65^2) = sqrt(28.3024 + 44.2225) = sqrt(72.5249) = 8.516156 -> 12.0437 -> 12
    A, d, mn = 6, 120.0, 3.0
    assert single_pitch(A, d, mn) == 9.0
    assert total_cumulative_pitch(A, d, mn) == 29.0
    assert total_profile(A, d, mn) == 12.0
    t = tolerances(A, **SPUR)
    assert (t["f_p"], t["F_p"], t["F_alpha"]) == (9.0, 29.0, 12.0)
    assert single_pitch(A, d, mn, rounded=False) == pytest.approx(6.32 * math.sqrt(2), abs=1e-12)
    assert total_profile(A, d, mn, rounded=False) == pytest.approx(12.04366, abs=1e-5)
    # fHaT6 = 5.32*1.4142 = 7.5236 -> 7.5; ffaT6 = 6.65*1.4142 = 9.4045 -> 9.5; FrT6 = 0.9*28.8004 = 25.92 -> 26
    assert (t["f_Halpha"], t["f_falpha"], t["F_r"]) == (7.5, 9.5, 26.0)


def test_helical_class5_every_tolerance():
    # d = 63.850666, sqrt(d) = 7.990661, sqrt(b) = sqrt(20) = 4.472136; k = z/8 = 3.75 -> 4
    # fpT5  = 0.063851 + 0.8 + 5 = 5.863851                              -> 6.0   (0.5 band: 11.73 -> 12 halves)
    # FpT5  = 0.127701 + 0.55*7.990661 + 1.4 + 12 = 0.127701 + 4.394864 + 13.4 = 17.922565 -> 18
    # fHaT5 = 0.8 + 0.063851 + 4 = 4.863851                              -> 4.9   (0.1 band)
    # ffaT5 = 1.1 + 5 = 6.1                                              -> 6.0   (0.5 band: 12.2 -> 12 halves)
    # FaT5  = sqrt(4.863851^2 + 6.1^2) = sqrt(23.657 + 37.21) = 7.801733 -> 8.0
    #         (from the rounded components: sqrt(4.9^2 + 6.0^2) = 7.746 -> 7.5; the module rounds once)
    # fHbT5 = 0.05*7.990661 + 0.35*4.472136 + 4 = 0.399533 + 1.565248 + 4 = 5.964781 -> 6.0
    # ffbT5 = 0.07*7.990661 + 0.45*4.472136 + 4 = 0.559346 + 2.012461 + 4 = 6.571807 -> 6.5
    # FbT5  = sqrt(5.964781^2 + 6.571807^2) = sqrt(35.5786 + 43.1886) = 8.875092 -> 9.0 (17.75 -> 18 halves)
    # FrT5  = 0.9*17.922565 = 16.130308                                  -> 16
    # FpkT5 = 5.863851 + (16/30)(0.063851 + 4.394864 + 0.6 + 7) = 5.863851 + 0.533333*12.058715 = 12.295165 -> 12
    d = reference_diameter(30, 2.0, 20.0)
    assert d == pytest.approx(63.850666, abs=1e-6)
    assert default_sector_pitches(30) == 4
    expected = {
        "f_p": 6.0,
        "F_p": 18.0,
        "F_pk": 12.0,
        "F_alpha": 8.0,
        "f_Halpha": 4.9,
        "f_falpha": 6.0,
        "F_beta": 9.0,
        "f_Hbeta": 6.0,
        "f_fbeta": 6.5,
        "F_r": 16.0,
    }
    assert tolerances(5, **HELICAL) == expected
    raw = tolerances(5, **HELICAL, rounded=False)
    assert raw["f_p"] == pytest.approx(5.863851, abs=1e-6)
    assert raw["F_p"] == pytest.approx(17.922565, abs=1e-6)
    assert raw["F_alpha"] == pytest.approx(7.801733, abs=1e-6)
    assert raw["F_beta"] == pytest.approx(8.875092, abs=1e-6)
    assert raw["F_pk"] == pytest.approx(12.295165, abs=1e-6)
    # single functions agree with the dict
    assert total_helix(5, d, 20.0) == 9.0 and helix_slope(5, d, 20.0) == 6.0 and helix_form(5, d, 20.0) == 6.5
    assert sector_pitch(5, d, 2.0, 30, 4) == 12.0 and runout(5, d, 2.0) == 16.0
    assert profile_slope(5, d, 2.0) == 4.9 and profile_form(5, 2.0) == 6.0


def test_helical_classes_7_and_9():
    # class 7 = 2 x class-5 unrounded values above:
    # fp 11.727702 -> 12; Fp 35.845130 -> 36; fHa 9.727702 -> 9.5 (19.46 halves -> 19); ffa 12.2 -> 12;
    # Fa 15.603467 -> 16 (rounded components: sqrt(9.5^2 + 12^2) = 15.305 -> 15); fHb 11.929562 -> 12;
    # ffb 13.143615 -> 13; Fb 17.750184 -> 18; Fr 32.260617 -> 32; Fpk 24.590330 -> 25
    assert tolerances(7, **HELICAL) == {
        "f_p": 12.0,
        "F_p": 36.0,
        "F_pk": 25.0,
        "F_alpha": 16.0,
        "f_Halpha": 9.5,
        "f_falpha": 12.0,
        "F_beta": 18.0,
        "f_Hbeta": 12.0,
        "f_fbeta": 13.0,
        "F_r": 32.0,
    }
    # class 9 = 4 x class 5:
    # fp 23.455403 -> 23; Fp 71.690260 -> 72; fHa 19.455403 -> 19; ffa 24.4 -> 24; Fa 31.206933 -> 31;
    # fHb 23.859123 -> 24; ffb 26.287230 -> 26; Fb 35.500369 -> 36 (rounded components: sqrt(24^2 + 26^2)
    # = 35.384 -> 35); Fr 64.521234 -> 65; Fpk 49.180660 -> 49
    assert tolerances(9, **HELICAL) == {
        "f_p": 23.0,
        "F_p": 72.0,
        "F_pk": 49.0,
        "F_alpha": 31.0,
        "f_Halpha": 19.0,
        "f_falpha": 24.0,
        "F_beta": 36.0,
        "f_Hbeta": 24.0,
        "f_fbeta": 26.0,
        "F_r": 65.0,
    }
    # class 3 = class 5 / 2, all in the 0.1 band except Fp, Fpk, Fr:
    # fp 2.931925 -> 2.9; fHa 2.431925 -> 2.4; Fa 3.900867 -> 3.9; Fp 8.961282 -> 9.0; Fr 8.065154 -> 8.0
    t3 = tolerances(3, **HELICAL)
    assert (t3["f_p"], t3["f_Halpha"], t3["F_alpha"], t3["F_p"], t3["F_r"]) == (2.9, 2.4, 3.9, 9.0, 8.0)


def test_rounding_bands_and_ties():
    # bands: > 10 to 1, 5..10 to 0.5, < 5 to 0.1; the band follows the unrounded value
    assert round_tolerance(12.04) == 12.0 and round_tolerance(10.2) == 10.0 and round_tolerance(10.6) == 11.0
    assert round_tolerance(9.9) == 10.0 and round_tolerance(7.74) == 7.5 and round_tolerance(5.0) == 5.0
    assert round_tolerance(4.97) == 5.0 and round_tolerance(4.86) == 4.9 and round_tolerance(0.04) == 0.0
    assert round_tolerance(9.6) == 9.5 and round_tolerance(10.4) == 10.0 and round_tolerance(5.2) == 5.0
    assert round_tolerance(4.94) == 4.9 and round_tolerance(5.24) == 5.0 and round_tolerance(5.26) == 5.5
    # ties go up (banker's rounding would give 9.0, 12, 4.2, 36)
    assert round_tolerance(9.25) == 9.5 and round_tolerance(9.75) == 10.0
    assert round_tolerance(12.5) == 13.0 and round_tolerance(36.5) == 37.0
    assert round_tolerance(4.25) == 4.3
    # float noise near a step does not flip
    assert round_tolerance(8.999999999) == 9.0 and round_tolerance(9.000000001) == 9.0
    with pytest.raises(ValueError, match="finite"):
        round_tolerance(-1.0)


def test_tie_cases_from_formulas():
    # class 3, mn = 2: ffaT = (0.55*2 + 5)/2 = 6.1/2 = 3.05 -> 3.1 (stored as 3.0499999999999998:
    # round(x, 1) gives 3.0)
    assert profile_form(3, 2.0, rounded=False) == pytest.approx(3.05, abs=1e-12)
    assert profile_form(3, 2.0) == 3.1
    # class 9, mn = 7.5: ffaT = 4*(0.55*7.5 + 5) = 4*9.125 = 36.5 -> 37 (banker's: 36)
    assert profile_form(9, 7.5) == 37.0
    # class 5, spur z = 50, mn = 5, d = 250: fpT = 0.25 + 2 + 5 = 7.25 -> 7.5 (banker's: 7.0);
    # fHaT = 2 + 0.25 + 4 = 6.25 -> 6.5
    assert single_pitch(5, 250.0, 5.0) == 7.5
    assert profile_slope(5, 250.0, 5.0) == 6.5
    t = tolerances(5, 50, 5.0, 40.0, 0.0)
    assert (t["f_p"], t["f_Halpha"]) == (7.5, 6.5)
    # same gear, runout from the unrounded FpT: sqrt(250) = 15.811388,
    # FpT5 = 0.5 + 0.55*15.811388 + 3.5 + 12 = 24.696264 -> 25; FrT5 = 0.9*24.696264 = 22.226637 -> 22
    # (0.9 times the rounded FpT would be 22.5 -> 23)
    assert (t["F_p"], t["F_r"]) == (25.0, 22.0)


def test_step_factor_doubles_every_two_classes():
    assert step_factor(5) == 1.0 and step_factor(7) == 2.0 and step_factor(1) == 0.25 and step_factor(11) == 8.0
    assert step_factor(6) == math.sqrt(2) and step_factor(4) == pytest.approx(1 / math.sqrt(2), abs=1e-15)
    for gear in (SPUR, HELICAL, {"z": 97, "mn": 4.5, "b": 55.0, "beta_deg": -33.0}):
        for A in range(1, 10):
            lo = tolerances(A, **gear, rounded=False)
            hi = tolerances(A + 2, **gear, rounded=False)
            for name in PARAMETERS:
                assert hi[name] == 2 * lo[name], (gear, A, name)
            one_up = tolerances(A + 1, **gear, rounded=False)
            assert one_up["F_p"] == pytest.approx(math.sqrt(2) * lo["F_p"], rel=1e-15)
    d = 120.0
    for A in range(1, 10):
        for fn in (single_pitch, total_cumulative_pitch, profile_slope, total_profile, runout):
            assert fn(A + 2, d, 3.0, rounded=False) == 2 * fn(A, d, 3.0, rounded=False)
        for fn in (helix_slope, helix_form, total_helix):
            assert fn(A + 2, d, 30.0, rounded=False) == 2 * fn(A, d, 30.0, rounded=False)
        assert profile_form(A + 2, 3.0, rounded=False) == 2 * profile_form(A, 3.0, rounded=False)


def test_tolerances_grow_with_class():
    for name in PARAMETERS:
        values = [tolerances(A, **HELICAL)[name] for A in CLASSES]
        assert values == sorted(values) and values[0] < values[-1]


def test_grade_at_and_just_above_tolerance():
    # spur issue gear, f_p by class: 1.6 2.2 3.2 4.5 6.5 9.0 13 18 25 36 51
    #   class 6: 6.32*1.4142 = 8.94 -> 9.0; class 11: 6.32*8 = 50.56 -> 51
    assert [tolerances(A, **SPUR)["f_p"] for A in CLASSES] == [1.6, 2.2, 3.2, 4.5, 6.5, 9.0, 13, 18, 25, 36, 51]
    assert grade(9.0, "f_p", **SPUR) == 6
    assert grade(9.0 * 1.01, "f_p", **SPUR) == 7
    assert grade(6.5, "f_p", **SPUR) == 5 and grade(6.5 * 1.01, "f_p", **SPUR) == 6
    assert grade(0.0, "f_p", **SPUR) == 1
    assert grade(51.0, "f_p", **SPUR) == 11
    assert grade(51.0 * 1.01, "f_p", **SPUR) is None
    # F_alpha: class 6 = 12 (the standard's worked vector), class 7 = 8.516156*2 = 17.03 -> 17
    assert grade(12.0, "F_alpha", **SPUR) == 6 and grade(12.12, "F_alpha", **SPUR) == 7
    # signed slope: magnitude; f_Halpha class 6 = 5.32*1.4142 = 7.52 -> 7.5, class 7 = 10.64 -> 11
    assert grade(-7.5, "f_Halpha", **SPUR) == 6 and grade(7.5, "f_Halpha", **SPUR) == 6
    assert grade(-7.575, "f_Halpha", **SPUR) == 7
    with pytest.raises(ValueError, match="unknown parameter 'f_x'"):
        grade(1.0, "f_x", **SPUR)
    with pytest.raises(ValueError, match="finite"):
        grade(float("nan"), "f_p", **SPUR)


def test_overall_class_is_the_worst():
    # f_p 8.0: class 5 = 6.5 < 8.0 <= class 6 = 9.0 -> 6
    # F_p 30: class 6 = 29 < 30 <= class 7 = 20.364948*2 = 40.73 -> 41 -> 7
    # F_alpha 7.0: class 4 = 8.516156/1.4142 = 6.02 -> 6.0 < 7.0 <= class 5 = 8.516 -> 8.5 -> 5
    # f_Halpha -3.0: class 3 = 5.32/2 = 2.66 -> 2.7 < 3.0 <= class 4 = 3.76 -> 3.8 -> 4
    measured = {"f_p": 8.0, "F_p": 30.0, "F_alpha": 7.0, "f_Halpha": -3.0}
    assert overall_class(measured, **SPUR) == {"f_p": 6, "F_p": 7, "F_alpha": 5, "f_Halpha": 4, "overall": 7}
    # one parameter worse than class 11 (F_p class 11 = 20.364948*8 = 162.9 -> 163) -> overall None
    worse = overall_class({**measured, "F_p": 170.0}, **SPUR)
    assert worse["F_p"] is None and worse["overall"] is None and worse["f_p"] == 6
    with pytest.raises(ValueError, match="at least one"):
        overall_class({}, **SPUR)
    with pytest.raises(ValueError, match="unknown parameter"):
        overall_class({"Fp": 3.0}, **SPUR)


def test_sector_pitch_k():
    # default k = z/8 half up, at least 2: z = 40 -> 5, z = 20 -> 2.5 -> 3, z = 12 -> 1.5 -> 2, z = 8 -> 2
    assert [default_sector_pitches(z) for z in (40, 20, 12, 8, 5)] == [5, 3, 2, 2, 2]
    # spur issue gear, class 5, k = 5: 6.32 + (20/40)(0.12 + 6.024948 + 0.9 + 7) = 6.32 + 7.022474 = 13.342474 -> 13
    assert sector_pitch(5, 120.0, 3.0, 40, 5, rounded=False) == pytest.approx(13.342474, abs=1e-6)
    assert sector_pitch(5, 120.0, 3.0, 40, 5) == 13.0  # from the rounded fpT: 6.5 + 7.022474 = 13.52 -> 14
    assert tolerances(5, **SPUR)["F_pk"] == 13.0
    # k = 2: 6.32 + 0.2*14.044948 = 9.128990 -> 9.0
    assert tolerances(5, **SPUR, k=2)["F_pk"] == 9.0
    with pytest.raises(ValueError, match="k = 21"):
        sector_pitch(5, 120.0, 3.0, 40, 21)


@pytest.mark.parametrize(
    ("args", "match"),
    [
        ((4, 20.0, 5.0, 20.0, 0.0), r"z = 4 .*5 <= z <= 1000"),
        ((40, 16000.0, 3.0, 20.0, 0.0), r"d = 16000.0 .*5 <= d <= 15000 mm"),
        ((40, 120.0, 0.4, 20.0, 0.0), r"mn = 0.4 .*0.5 <= mn <= 70 mm"),
        ((40, 120.0, 3.0, 3.0, 0.0), r"b = 3.0 .*4 <= b <= 1200 mm"),
        ((40, 120.0, 3.0, 20.0, 46.0), r"beta_deg = 46.0 .*\|beta_deg\| <= 45 deg"),
        ((40, 120.0, 3.0, 20.0, -46.0), r"beta_deg = -46.0"),
        ((40, float("nan"), 3.0, 20.0, 0.0), r"d = nan"),
    ],
)
def test_validate_rejects_out_of_range(args, match):
    with pytest.raises(ValueError, match=match) as info:
        validate(*args)
    assert "do not extrapolate" in str(info.value)


def test_validate_accepts_bounds():
    validate(5, 5.0, 0.5, 4.0, -45.0)
    validate(1000, 15000.0, 70.0, 1200.0, 45.0)


@pytest.mark.parametrize("A", [0, 12, -1, 6.0, True, "6"])
def test_class_out_of_range(A):
    with pytest.raises(ValueError, match="accuracy class A"):
        check_class(A)
    with pytest.raises(ValueError, match="accuracy class A"):
        single_pitch(A, 120.0, 3.0)
    with pytest.raises(ValueError, match="accuracy class A"):
        tolerances(A, **SPUR)


def test_each_function_checks_class_and_range():
    for call in (
        lambda A: single_pitch(A, 120.0, 3.0),
        lambda A: total_cumulative_pitch(A, 120.0, 3.0),
        lambda A: profile_slope(A, 120.0, 3.0),
        lambda A: profile_form(A, 3.0),
        lambda A: total_profile(A, 120.0, 3.0),
        lambda A: helix_slope(A, 120.0, 30.0),
        lambda A: helix_form(A, 120.0, 30.0),
        lambda A: total_helix(A, 120.0, 30.0),
        lambda A: runout(A, 120.0, 3.0),
        lambda A: sector_pitch(A, 120.0, 3.0, 40, 5),
    ):
        with pytest.raises(ValueError, match="A = 12"):
            call(12)
    with pytest.raises(ValueError, match=r"mn = 0\.4"):
        profile_form(5, 0.4)
    with pytest.raises(ValueError, match="b = 1300"):
        helix_form(5, 120.0, 1300)
    with pytest.raises(ValueError, match="z = 1001"):
        sector_pitch(5, 120.0, 3.0, 1001, 5)


def test_tolerances_validates_derived_diameter():
    # z = 1000, mn = 20 -> d = 20000 mm > 15000
    with pytest.raises(ValueError, match="d = 20000"):
        tolerances(6, 1000, 20.0, 100.0, 0.0)
    # z = 5, mn = 0.5 -> d = 2.5 mm < 5
    with pytest.raises(ValueError, match=r"d = 2\.5"):
        tolerances(6, 5, 0.5, 10.0, 0.0)
    with pytest.raises(ValueError, match="beta_deg = 46"):
        tolerances(6, 40, 3.0, 30.0, 46)
    with pytest.raises(ValueError, match="z = 4"):
        grade(1.0, "f_p", 4, 3.0, 30.0, 0.0)
    with pytest.raises(ValueError, match="z must be a whole number"):
        tolerances(6, 40.5, 3.0, 30.0, 0.0)
