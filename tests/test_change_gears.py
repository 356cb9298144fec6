"""Tests of virtual_machine.setting.change_gears: exact ratios, optimality against brute force, rules, errors."""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from fractions import Fraction

import numpy as np
import pytest

from virtual_machine.setting.change_gears import (
    STANDARD_SET,
    ChangeGearSet,
    GearTrain,
    choose_change_gears,
    reachable_range,
)

TOL = 1e-12  # stage-ratio bound tolerance documented by the module

SMALL_SET = ChangeGearSet(
    name="small",
    teeth=(24, 24, 30, 36, 41, 45, 52, 60, 72, 72),
    min_clearance_teeth=20,
    min_stage_ratio=0.25,
    max_stage_ratio=4.0,
)
UNIQUE_SET = ChangeGearSet(name="unique", teeth=tuple(sorted(set(STANDARD_SET.teeth))))


# ----------------------------------------------------------------------------------------------------
# independent brute force: loops over *physical* gears (indices), not over distinct tooth counts
# ----------------------------------------------------------------------------------------------------


def _stage_ok(p: np.ndarray, q: np.ndarray, gs: ChangeGearSet) -> np.ndarray:
    r = p / q
    return (r >= gs.min_stage_ratio * (1 - TOL)) & (r <= gs.max_stage_ratio * (1 + TOL))


_BRUTE_CACHE: dict[tuple[str, int], np.ndarray] = {}


def all_admissible(gs: ChangeGearSet, stages: int) -> np.ndarray:
    """Every admissible train as rows (a, b) or (a, b, c, d), distinct by tooth counts."""
    key = (gs.name, stages)
    if key in _BRUTE_CACHE:
        return _BRUTE_CACHE[key]
    teeth = np.asarray(gs.teeth, dtype=np.int64)
    n = teeth.size
    idx = np.arange(n)
    if stages == 1:
        ia, ib = np.meshgrid(idx, idx, indexing="ij")
        a, b = teeth[ia.ravel()], teeth[ib.ravel()]
        ok = (ia.ravel() != ib.ravel()) & _stage_ok(a, b, gs)
        trains = np.stack([a, b], axis=1)[ok]
    else:
        ib, ic, id_ = (x.ravel() for x in np.meshgrid(idx, idx, idx, indexing="ij"))
        distinct_bcd = (ib != ic) & (ib != id_) & (ic != id_)
        chunks = []
        for ia in range(n):  # vectorised over b, c, d for each physical gear a
            m = distinct_bcd & (ib != ia) & (ic != ia) & (id_ != ia)
            b, c, d = teeth[ib[m]], teeth[ic[m]], teeth[id_[m]]
            a = np.full_like(b, teeth[ia])
            ok = _stage_ok(a, b, gs) & _stage_ok(c, d, gs)
            ok &= (a + b >= c + gs.min_clearance_teeth) & (c + d >= b + gs.min_clearance_teeth)
            chunks.append(np.stack([a, b, c, d], axis=1)[ok])
        trains = np.concatenate(chunks)
    code = np.zeros(len(trains), dtype=np.int64)
    for k in range(trains.shape[1]):
        code = code * 1024 + trains[:, k]
    _, first = np.unique(code, return_index=True)
    trains = trains[first]
    _BRUTE_CACHE[key] = trains
    return trains


def brute_force_best(target: float, gs: ChangeGearSet, stages: int) -> tuple[float, tuple[int, ...]]:
    """Smallest |relative error| and the train chosen by the documented rule, by exhaustive search."""
    trains = all_admissible(gs, stages)
    num = trains[:, 0] * (trains[:, 2] if stages == 2 else 1)
    den = trains[:, 1] * (trains[:, 3] if stages == 2 else 1)
    err = np.abs(num / den - target) / target
    best_err = float(err.min())
    near = trains[err <= best_err + 1e-12]
    exact_t = Fraction(target)

    def key(t: np.ndarray) -> tuple:
        ratio = Fraction(int(np.prod(t[0::2])), int(np.prod(t[1::2])))
        return (abs(ratio - exact_t), int(t.sum()), tuple(int(x) for x in t))

    best = min(near, key=key)
    return best_err, tuple(int(x) for x in best)


def assert_admissible(train: GearTrain, gs: ChangeGearSet) -> None:
    used, available = Counter(train.teeth), Counter(gs.teeth)
    assert all(used[t] <= available[t] for t in used), (train.teeth, gs.teeth)
    for p, q in zip(train.driving, train.driven, strict=True):
        assert gs.min_stage_ratio * (1 - TOL) <= p / q <= gs.max_stage_ratio * (1 + TOL)
    if train.stages == 2:
        a, b, c, d = train.teeth
        assert a + b >= c + gs.min_clearance_teeth
        assert c + d >= b + gs.min_clearance_teeth


# ----------------------------------------------------------------------------------------------------
# exact ratios
# ----------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("stages", [1, 2])
@pytest.mark.parametrize("exact", [Fraction(23, 40), Fraction(25, 60), Fraction(23, 20), Fraction(37, 97), Fraction(1)])
def test_exact_ratio_is_hit_exactly(exact: Fraction, stages: int) -> None:
    train = choose_change_gears(float(exact), stages=stages)
    assert train.exact_ratio == exact
    assert train.ratio == float(exact)
    assert train.relative_error == 0.0
    assert train.stages == stages
    assert_admissible(train, STANDARD_SET)


@pytest.mark.parametrize(
    "exact",
    [
        Fraction(53 * 71, 60 * 97),
        Fraction(89 * 43, 100 * 47),
        Fraction(59 * 67, 73 * 79),
        Fraction(83, 41) / 3,
    ],
)
def test_exact_two_stage_prime_ratios(exact: Fraction) -> None:
    # ratios with large primes in numerator and denominator need the primes in the set
    train = choose_change_gears(float(exact))
    assert train.exact_ratio == exact
    assert train.relative_error == 0.0
    assert_admissible(train, STANDARD_SET)


def test_known_answers_and_describe() -> None:
    two = choose_change_gears(0.575)
    assert (two.driving, two.driven) == ((23, 25), (20, 50))  # smallest teeth sum 118 among exact trains
    assert two.describe() == "a/b * c/d = 23/20 * 25/50 = 0.575000000 (error +0.0e+00)"
    one = choose_change_gears(0.575, stages=1)
    assert (one.driving, one.driven) == ((23,), (40,))
    assert one.describe() == "a/b = 23/40 = 0.575000000 (error +0.0e+00)"
    near = choose_change_gears(math.pi / 3)
    assert near.describe() == "a/b * c/d = 34/61 * 62/33 = 1.047193244 (error -4.1e-06)"
    assert near.relative_error == pytest.approx((34 * 62 / (61 * 33) - math.pi / 3) / (math.pi / 3), rel=1e-12)


def test_gear_train_properties() -> None:
    t = GearTrain(target=1.0, driving=(41,), driven=(40,))
    assert t.exact_ratio == Fraction(41, 40)
    assert t.ratio == 1.025
    assert t.relative_error == pytest.approx(0.025, rel=1e-14)
    assert t.teeth == (41, 40)
    assert t.describe() == "a/b = 41/40 = 1.025000000 (error +2.5e-02)"
    t2 = GearTrain(target=2.0, driving=(30, 50), driven=(60, 20))
    assert t2.teeth == (30, 60, 50, 20)
    assert t2.ratio == 1.25
    assert t2.relative_error == -0.375
    with pytest.raises(ValueError, match=r"driven.*has 1 gears but driving has 2"):
        GearTrain(target=1.0, driving=(30, 40), driven=(30,))
    with pytest.raises(ValueError, match=r"target.*finite number > 0"):
        GearTrain(target=-1.0, driving=(30,), driven=(30,))
    with pytest.raises(ValueError, match=r"driving.*1 or 2 positive tooth counts"):
        GearTrain(target=1.0, driving=(30, 40, 50), driven=(30, 40, 50))


# ----------------------------------------------------------------------------------------------------
# optimality against brute force
# ----------------------------------------------------------------------------------------------------

_RNG = np.random.default_rng(20240611)
RANDOM_TARGETS = [float(x) for x in _RNG.uniform(0.25, 4.0, size=6)]
TWO_STAGE_TARGETS = [
    math.pi / 3,
    0.8660254037844386,
    1 / 1.0973,
    math.e / 2,
    math.sqrt(2),
    0.05,
    17.3,
    *RANDOM_TARGETS,
]


@pytest.mark.parametrize("target", TWO_STAGE_TARGETS)
def test_two_stage_is_optimal(target: float) -> None:
    train = choose_change_gears(target, stages=2)
    best_err, best_teeth = brute_force_best(target, STANDARD_SET, 2)
    assert abs(abs(train.relative_error) - best_err) <= 1e-15
    assert train.teeth == best_teeth  # same tie-break as documented
    assert_admissible(train, STANDARD_SET)


@pytest.mark.parametrize("target", [*TWO_STAGE_TARGETS[:4], 0.2, 5.0, *RANDOM_TARGETS])
def test_one_stage_is_optimal(target: float) -> None:
    train = choose_change_gears(target, stages=1)
    best_err, best_teeth = brute_force_best(target, STANDARD_SET, 1)
    assert abs(abs(train.relative_error) - best_err) <= 1e-15
    assert train.teeth == best_teeth
    assert_admissible(train, STANDARD_SET)


@pytest.mark.parametrize(
    ("target", "stages"),
    [(t, 1) for t in (0.34, 0.77, 1.0, 1.234567, 2.5, 2.99)]
    + [(t, 2) for t in (0.12, 0.3, 0.77, 1.0, 1.234567, 2.5, 3.9, 8.5)],
)
def test_custom_set_is_optimal(target: float, stages: int) -> None:
    train = choose_change_gears(target, SMALL_SET, stages=stages)
    best_err, best_teeth = brute_force_best(target, SMALL_SET, stages)
    assert abs(abs(train.relative_error) - best_err) <= 1e-15
    assert train.teeth == best_teeth
    assert_admissible(train, SMALL_SET)


def test_two_stage_beats_one_stage_on_irrational_targets() -> None:
    for target in (math.pi / 3, 0.8660254037844386, 1 / 1.0973):
        one = abs(choose_change_gears(target, stages=1).relative_error)
        two = abs(choose_change_gears(target, stages=2).relative_error)
        assert two < one / 10
        assert two < 2e-5


# ----------------------------------------------------------------------------------------------------
# multiplicity and rules
# ----------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("target", [1.0, 0.25, 4.0, 2.25, 1.5, 0.64])
def test_no_duplicate_tooth_count_from_a_set_without_duplicates(target: float) -> None:
    for stages in (1, 2):
        train = choose_change_gears(target, UNIQUE_SET, stages=stages)
        assert len(set(train.teeth)) == len(train.teeth), train.teeth
        best_err, best_teeth = brute_force_best(target, UNIQUE_SET, stages)
        assert train.teeth == best_teeth
        assert abs(abs(train.relative_error) - best_err) <= 1e-15


def test_multiplicity_decides_one_stage_unit_ratio() -> None:
    assert choose_change_gears(1.0, STANDARD_SET, stages=1).teeth == (30, 30)  # two 30-tooth gears
    with_pair = ChangeGearSet(name="pair", teeth=(40, 40, 50))
    assert choose_change_gears(1.0, with_pair, stages=1).teeth == (40, 40)
    without = ChangeGearSet(name="no pair", teeth=(40, 50, 60))
    train = choose_change_gears(1.0, without, stages=1)
    assert train.teeth == (50, 60)  # |5/6 - 1| = 1/6 beats 6/5 (1/5) and 5/4 (1/4)
    assert train.relative_error == pytest.approx(-1 / 6, rel=1e-14)


def test_engagement_rule_is_enforced() -> None:
    # SMALL_SET (clearance 20): without the rule the tie-break picks 24/30 * 45/36, which fouls
    loose = dataclasses.replace(SMALL_SET, name="small loose", min_clearance_teeth=0)
    loose_train = choose_change_gears(1.0, loose)
    assert loose_train.teeth == (24, 30, 45, 36) == brute_force_best(1.0, loose, 2)[1]
    a, b, c, _ = loose_train.teeth
    assert a + b < c + SMALL_SET.min_clearance_teeth  # violates a + b >= c + clearance
    strict_train = choose_change_gears(1.0, SMALL_SET)
    assert strict_train.teeth == (36, 24, 30, 45)
    assert strict_train.relative_error == 0.0
    # a tight rule (60 teeth) costs accuracy: 2.4e-8 with clearance 15, 5.5e-6 with 60, both optimal
    tight = dataclasses.replace(STANDARD_SET, name="standard tight", min_clearance_teeth=60)
    target = 1.7616736991767346
    normal_train, tight_train = choose_change_gears(target), choose_change_gears(target, tight)
    assert normal_train.teeth == (70, 34, 83, 97)
    assert tight_train.teeth == (90, 61, 80, 67)
    assert abs(normal_train.relative_error) < 3e-8 < 5e-6 < abs(tight_train.relative_error) < 6e-6
    for gs, train in ((STANDARD_SET, normal_train), (tight, tight_train)):
        best_err, best_teeth = brute_force_best(target, gs, 2)
        assert train.teeth == best_teeth
        assert abs(abs(train.relative_error) - best_err) <= 1e-15
        assert_admissible(train, gs)


def test_reachable_range_matches_brute_force() -> None:
    low, high = reachable_range(STANDARD_SET, 2)
    assert (low, high) == (460 / 9800, 9800 / 460)  # 23/100 * 20/98 and its inverse
    for gs in (STANDARD_SET, SMALL_SET):
        for stages in (1, 2):
            trains = all_admissible(gs, stages)
            ratios = np.prod(trains[:, 0::2], axis=1) / np.prod(trains[:, 1::2], axis=1)
            assert reachable_range(gs, stages) == (ratios.min(), ratios.max())
    assert reachable_range(STANDARD_SET, 1) == (0.2, 5.0)


def test_extreme_targets_are_reachable() -> None:
    low, high = reachable_range()
    top = choose_change_gears(high)
    assert top.exact_ratio == Fraction(9800, 460)
    assert_admissible(top, STANDARD_SET)
    assert choose_change_gears(low).exact_ratio == Fraction(460, 9800)
    # rounding slack: a target a hair above the maximum still returns the extreme train
    assert choose_change_gears(high * (1 + 1e-12)).exact_ratio == Fraction(9800, 460)


# ----------------------------------------------------------------------------------------------------
# errors
# ----------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("bad", [0.0, -0.5, math.nan, math.inf, -math.inf])
def test_bad_target(bad: float) -> None:
    with pytest.raises(ValueError, match=r"target = .*not a finite ratio > 0"):
        choose_change_gears(bad)


def test_target_out_of_reach() -> None:
    with pytest.raises(
        ValueError, match=r"outside the range reachable.*'standard'.*2 stage.*\[0\.0469387755, 21\.3043478\]"
    ):
        choose_change_gears(100.0)
    with pytest.raises(ValueError, match=r"outside the range reachable.*\[0\.2, 5\].*stages=2"):
        choose_change_gears(6.0, stages=1)
    with pytest.raises(ValueError, match="outside the range reachable"):
        choose_change_gears(0.01)
    with pytest.raises(ValueError, match="outside the range reachable"):
        choose_change_gears(9800 / 460 * (1 + 1e-6))


@pytest.mark.parametrize("stages", [0, 3, -1, 1.5, True, "2"])
def test_bad_stages(stages: object) -> None:
    with pytest.raises(ValueError, match=r"stages = .*use 1 \(a/b\) or 2"):
        choose_change_gears(1.0, stages=stages)  # type: ignore[arg-type]


def test_bad_gear_sets() -> None:
    with pytest.raises(ValueError, match=r"empty.*at least 2 tooth counts"):
        ChangeGearSet(name="none", teeth=())
    with pytest.raises(ValueError, match=r"single gear"):
        ChangeGearSet(name="one", teeth=(40,))
    with pytest.raises(ValueError, match=r"positive integers"):
        ChangeGearSet(name="neg", teeth=(40, -3))
    with pytest.raises(ValueError, match=r"positive integers"):
        ChangeGearSet(name="float", teeth=(40, 30.5))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"min_clearance_teeth.*integer >= 0"):
        ChangeGearSet(name="clr", teeth=(40, 30), min_clearance_teeth=-1)
    with pytest.raises(ValueError, match=r"0 < min_stage_ratio <= max_stage_ratio"):
        ChangeGearSet(name="ratios", teeth=(40, 30), min_stage_ratio=2.0, max_stage_ratio=0.5)
    with pytest.raises(ValueError, match=r"name.*non-empty string"):
        ChangeGearSet(name="", teeth=(40, 30))
    three = ChangeGearSet(name="three", teeth=[30, 40, 50])  # type: ignore[arg-type]
    assert three.teeth == (30, 40, 50)  # lists are stored as tuples
    with pytest.raises(ValueError, match=r"3 gears cannot form a 2-stage train.*at least 4 gears"):
        choose_change_gears(1.0, three, stages=2)
    nothing = ChangeGearSet(name="nothing", teeth=(20, 200))
    with pytest.raises(ValueError, match=r"no 1-stage train satisfies stage ratios in \[0\.2, 5\]"):
        choose_change_gears(1.0, nothing, stages=1)
    crowded = ChangeGearSet(name="crowded", teeth=(20, 21, 22, 23), min_clearance_teeth=50)
    with pytest.raises(ValueError, match=r"no 2-stage train.*engagement rule \(clearance 50 teeth\)"):
        choose_change_gears(1.0, crowded)
    with pytest.raises(TypeError, match="not a ChangeGearSet"):
        choose_change_gears(1.0, (20, 30, 40, 50))  # type: ignore[arg-type]
