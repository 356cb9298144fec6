"""Change-gear ("guitar") selection: the best a/b or (a/b)*(c/d) from a finite set of change gears.

Mechanical gear-cutting machines set their index, feed and differential ratios with change gears on a swinging
bracket, the "guitar". The gears come from a finite set, so a ratio can only be approximated, and gear cutting needs
it to about 1e-6 relative or better wherever the set allows: :func:`choose_change_gears` returns the *best*
admissible :class:`GearTrain` (an exact search), :func:`reachable_range` the ratios a set can realise at all. The
default set is :data:`STANDARD_SET`; a job may supply its own :class:`ChangeGearSet`. Invalid inputs raise
``ValueError`` (``TypeError`` for a wrong type) whose message names the input, the value, why it is wrong and what
would be valid. The search's cost per ratio: docs/performance.md, "Benchmarks".
"""

from __future__ import annotations

import functools
import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

__all__ = [
    "STANDARD_SET",
    "ChangeGearSet",
    "GearTrain",
    "choose_change_gears",
    "reachable_range",
]

_STAGE_RATIO_TOL = 1e-12  # relative tolerance on the stage-ratio bounds (0.2 must admit 20/100)
_TIE_EPS = 1e-12  # float |relative error| window within which candidates are compared exactly
_RANGE_SLACK = 1e-9  # relative slack on the reachable range (tolerates rounding of extreme targets)
_FIRST_WINDOW = 8  # neighbours examined per side in the first branch-and-bound round (doubles after)


def _problem(key: str, value: object, reason: str, hint: str) -> str:
    return f"{key} = {value!r}: {reason}; {hint}"


def _is_int(x: object) -> bool:
    return isinstance(x, numbers.Integral) and not isinstance(x, bool)


def _is_real(x: object) -> bool:
    return isinstance(x, numbers.Real) and not isinstance(x, bool)


# ----------------------------------------------------------------------------------------------------
# data types
# ----------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ChangeGearSet:
    """A finite set of change gears and the mounting rules of the guitar that carries them.

    A train from the set is admissible when every physical gear is used at most once (the set is a multiset), every
    stage ratio (a/b, and c/d) lies within the stage-ratio bounds, and two stages obey the guitar engagement rule,
    the classic design rule that keeps a gear from fouling the shaft of the gear it does not mesh with::

        a + b >= c + min_clearance_teeth    and    c + d >= b + min_clearance_teeth

    Parameters
    ----------
    name : str
        Name of the set, used in messages.
    teeth : tuple of int
        Tooth counts of the physical gears, a multiset: a tooth count listed twice means two physical
        gears, so it may appear twice in one train.  Any iterable of positive integers is accepted and
        stored as a tuple in the given order.  At least 2 gears (4 for two-stage trains).
    min_clearance_teeth : int, default 15
        Guitar engagement rule for two-stage trains: ``a + b >= c + min_clearance_teeth`` and
        ``c + d >= b + min_clearance_teeth`` (centre distances large enough that gear c clears the
        shaft of gear a and gear b clears the shaft of gear d).  ``>= 0``.
    min_stage_ratio, max_stage_ratio : float, default 0.2 and 5.0
        Each stage ratio a/b, c/d must lie in ``[min_stage_ratio, max_stage_ratio]`` (inclusive, with a 1e-12
        relative tolerance so that decimal bounds such as 0.2 admit 20/100).  Finite,
        ``0 < min_stage_ratio <= max_stage_ratio``.

    Raises
    ------
    ValueError
        If the set is empty or has fewer than 2 gears, a tooth count is not a positive integer, the
        clearance is negative, or the stage-ratio bounds are not finite with ``0 < min <= max``.
    """

    name: str
    teeth: tuple[int, ...]
    min_clearance_teeth: int = 15
    min_stage_ratio: float = 0.2
    max_stage_ratio: float = 5.0

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise ValueError(_problem("name", self.name, "not a non-empty string", "give the set a name"))
        try:
            teeth = tuple(self.teeth)
        except TypeError:
            raise ValueError(
                _problem(
                    f"{self.name}.teeth",
                    self.teeth,
                    "not an iterable of tooth counts",
                    "give a tuple of positive integers, e.g. (20, 25, 30, 40)",
                )
            ) from None
        if len(teeth) < 2:
            raise ValueError(
                _problem(
                    f"{self.name}.teeth",
                    teeth,
                    f"the set is {'empty' if not teeth else 'a single gear'}",
                    "give at least 2 tooth counts (4 for two-stage trains)",
                )
            )
        bad = [t for t in teeth if not _is_int(t) or t < 1]
        if bad:
            raise ValueError(
                _problem(
                    f"{self.name}.teeth",
                    bad[0],
                    "tooth counts must be positive integers",
                    "give integers >= 1, e.g. (20, 25, 30, 40)",
                )
            )
        object.__setattr__(self, "teeth", tuple(int(t) for t in teeth))
        if not _is_int(self.min_clearance_teeth) or self.min_clearance_teeth < 0:
            raise ValueError(
                _problem(
                    f"{self.name}.min_clearance_teeth",
                    self.min_clearance_teeth,
                    "not a non-negative integer",
                    "use an integer >= 0 (15 is customary; 0 disables the engagement rule)",
                )
            )
        lo, hi = self.min_stage_ratio, self.max_stage_ratio
        if not (_is_real(lo) and _is_real(hi) and math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi):
            raise ValueError(
                _problem(
                    f"{self.name}.min_stage_ratio/max_stage_ratio",
                    (lo, hi),
                    "stage-ratio bounds must be finite with 0 < min_stage_ratio <= max_stage_ratio",
                    "use e.g. (0.2, 5.0)",
                )
            )
        object.__setattr__(self, "min_clearance_teeth", int(self.min_clearance_teeth))
        object.__setattr__(self, "min_stage_ratio", float(lo))
        object.__setattr__(self, "max_stage_ratio", float(hi))


_STANDARD_TEETH = (
    20, 23, 24, 25, 30, 30, 33, 34, 35, 37, 40, 40, 41, 43, 45, 47, 50, 50, 53, 55, 58, 59, 60, 60,
    61, 62, 65, 67, 70, 70, 71, 73, 75, 79, 80, 80, 83, 85, 89, 90, 92, 95, 97, 98, 100,
)  # fmt: skip

STANDARD_SET: ChangeGearSet = ChangeGearSet(name="standard", teeth=_STANDARD_TEETH)
"""The default change-gear set: 45 gears, 39 distinct tooth counts.

Modelled on the change-gear sets supplied with mechanical hobbing and gear-shaping machines (sets of
roughly 40 to 50 gears from 20 to 100 teeth, with the round counts duplicated), and chosen so that every
prime that occurs in tooth counts up to 100 of the cut gears is present as a factor (23, 37, 41, 43, 47,
53, 59, 61, 67, 71, 73, 79, 83, 89, 97; 29 and 31 via 58 and 62): an index ratio with such a prime in
its numerator or denominator can be met exactly.  Tooth counts::

    20, 23, 24, 25, 30 (x2), 33, 34, 35, 37, 40 (x2), 41, 43, 45, 47, 50 (x2), 53, 55, 58, 59,
    60 (x2), 61, 62, 65, 67, 70 (x2), 71, 73, 75, 79, 80 (x2), 83, 85, 89, 90, 92, 95, 97, 98, 100

Rules: ``min_clearance_teeth = 15``, stage ratios in ``[0.2, 5.0]``.  A job may supply its own
:class:`ChangeGearSet` (the one of its machine) instead.
"""


@dataclass(frozen=True)
class GearTrain:
    """A change-gear train (a/b) or (a/b)*(c/d) chosen for a target ratio.

    A one-stage train is a single pair a/b (a driving, b driven); a two-stage train is (a/b)*(c/d) with b and c
    keyed to a common intermediate shaft.

    Parameters
    ----------
    target : float
        The ratio asked for; finite and > 0.
    driving : tuple of int
        Tooth counts of the driving gears, ``(a,)`` or ``(a, c)``.
    driven : tuple of int
        Tooth counts of the driven gears, ``(b,)`` or ``(b, d)``; same length as ``driving``.

    Raises
    ------
    ValueError
        If the target is not finite and > 0, or the tooth tuples are not 1 or 2 positive integers each
        with equal lengths.
    """

    target: float
    driving: tuple[int, ...]
    driven: tuple[int, ...]

    def __post_init__(self) -> None:
        if not _is_real(self.target) or not math.isfinite(self.target) or self.target <= 0:
            raise ValueError(_problem("target", self.target, "not a finite number > 0", "give a ratio > 0"))
        object.__setattr__(self, "target", float(self.target))
        for key in ("driving", "driven"):
            value = getattr(self, key)
            try:
                teeth = tuple(value)
            except TypeError:
                teeth = None
            if teeth is None or len(teeth) not in (1, 2) or not all(_is_int(t) and t >= 1 for t in teeth):
                raise ValueError(
                    _problem(key, value, "not 1 or 2 positive tooth counts", "give e.g. (23,) or (23, 50)")
                )
            object.__setattr__(self, key, tuple(int(t) for t in teeth))
        if len(self.driving) != len(self.driven):
            raise ValueError(
                _problem(
                    "driven",
                    self.driven,
                    f"has {len(self.driven)} gears but driving has {len(self.driving)}",
                    "give one driven gear per driving gear",
                )
            )

    @property
    def stages(self) -> int:
        """Number of stages (1 or 2)."""
        return len(self.driving)

    @property
    def exact_ratio(self) -> Fraction:
        """Achieved ratio as an exact fraction: product of driving over product of driven teeth."""
        return Fraction(math.prod(self.driving), math.prod(self.driven))

    @property
    def ratio(self) -> float:
        """Achieved ratio, :attr:`exact_ratio` rounded once to float."""
        return float(self.exact_ratio)

    @property
    def relative_error(self) -> float:
        """Signed relative error ``(ratio - target) / target``."""
        return (self.ratio - self.target) / self.target

    @property
    def teeth(self) -> tuple[int, ...]:
        """Tooth counts in guitar order: ``(a, b)`` or ``(a, b, c, d)``."""
        return tuple(t for pair in zip(self.driving, self.driven, strict=True) for t in pair)

    def describe(self) -> str:
        """One-line description.

        Returns
        -------
        str
            e.g. ``"a/b * c/d = 23/80 * 50/25 = 0.575000000 (error +0.0e+00)"`` or
            ``"a/b = 23/40 = 0.575000000 (error +0.0e+00)"``.
        """
        names = " * ".join(("a/b", "c/d")[: self.stages])
        pairs = " * ".join(f"{p}/{q}" for p, q in zip(self.driving, self.driven, strict=True))
        return f"{names} = {pairs} = {self.ratio:.9f} (error {self.relative_error:+.1e})"


# ----------------------------------------------------------------------------------------------------
# pair table and search machinery
# ----------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _PairTable:
    """Admissible ordered stage pairs of a set, sorted by ratio (arrays are read-only)."""

    counts: np.ndarray  # multiplicity of each distinct tooth count, indexed like the *_idx arrays
    drv: np.ndarray  # driving teeth of each pair (int64)
    dvn: np.ndarray  # driven teeth of each pair (int64)
    drv_idx: np.ndarray  # index of the driving tooth count in the distinct values
    dvn_idx: np.ndarray
    ratio: np.ndarray  # drv / dvn, ascending


@functools.lru_cache(maxsize=32)
def _pair_table(gear_set: ChangeGearSet) -> _PairTable:
    values, counts = np.unique(np.asarray(gear_set.teeth, dtype=np.int64), return_counts=True)
    i, j = np.meshgrid(np.arange(values.size), np.arange(values.size), indexing="ij")
    i, j = i.ravel(), j.ravel()
    ratio = values[i] / values[j]
    ok = (i != j) | (counts[i] >= 2)  # the same tooth count twice needs two physical gears
    ok &= ratio >= gear_set.min_stage_ratio * (1 - _STAGE_RATIO_TOL)
    ok &= ratio <= gear_set.max_stage_ratio * (1 + _STAGE_RATIO_TOL)
    i, j, ratio = i[ok], j[ok], ratio[ok]
    order = np.lexsort((values[j], values[i], ratio))  # by ratio, then a, then b: deterministic
    arrays = {
        "counts": counts,
        "drv": values[i[order]],
        "dvn": values[j[order]],
        "drv_idx": i[order],
        "dvn_idx": j[order],
        "ratio": ratio[order],
    }
    for a in arrays.values():
        a.setflags(write=False)
    return _PairTable(**arrays)


def _admissible(tab: _PairTable, clearance: int, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Mask of two-stage trains (pair ``rows`` as a/b, pair ``cols`` as c/d) that obey the rules.

    Each pair obeys the stage-ratio and its own multiplicity rule already; this checks the engagement
    rule and that no tooth count is used more often than the set holds it.
    """
    a, b, c, d = tab.drv[rows], tab.dvn[rows], tab.drv[cols], tab.dvn[cols]
    ok = (a + b >= c + clearance) & (c + d >= b + clearance)
    idx = (tab.drv_idx[rows], tab.dvn_idx[rows], tab.drv_idx[cols], tab.dvn_idx[cols])
    for k, x in enumerate(idx):
        uses = 1 + sum((x == y).astype(np.int64) for m, y in enumerate(idx) if m != k)
        ok &= uses <= tab.counts[x]
    return ok


def _branch_and_bound(
    tab: _PairTable,
    clearance: int,
    start: np.ndarray,
    objective: Callable[[np.ndarray, np.ndarray], np.ndarray],
    eps: float,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Minimise ``objective(row, col)`` over admissible two-stage trains (row = a/b, col = c/d pair).

    ``start[row]`` splits the sorted pair list so that the objective is non-decreasing moving away from
    the split on either side, for that row.  Returns all admissible (row, col) whose objective is within
    ``eps`` of the minimum, and the minimum (``inf`` if there is no admissible train).
    """
    n = tab.ratio.size
    lo = start.astype(np.int64).copy()  # examined columns of each row: [lo, hi)
    hi = lo.copy()
    active = np.arange(n)
    best = math.inf
    kept_rows: list[np.ndarray] = []
    kept_cols: list[np.ndarray] = []
    kept_vals: list[np.ndarray] = []
    width = _FIRST_WINDOW
    while active.size:
        steps = np.arange(width)
        cols = np.concatenate([lo[active, None] - 1 - steps, hi[active, None] + steps], axis=1)
        rows = np.broadcast_to(active[:, None], cols.shape)
        inside = (cols >= 0) & (cols < n)
        r, c = rows[inside], cols[inside]
        ok = _admissible(tab, clearance, r, c)
        r, c = r[ok], c[ok]
        if r.size:
            v = objective(r, c)
            best = min(best, float(v.min()))
            keep = v <= best + eps
            kept_rows.append(r[keep])
            kept_cols.append(c[keep])
            kept_vals.append(v[keep])
        lo[active] = np.maximum(lo[active] - width, 0)
        hi[active] = np.minimum(hi[active] + width, n)
        # a side stays open while its next unexamined neighbour could still be within eps of the best
        go_on = np.zeros(active.size, dtype=bool)
        for open_side, nxt in ((lo[active] > 0, lo[active] - 1), (hi[active] < n, hi[active])):
            if open_side.any():
                go_on[open_side] |= objective(active[open_side], nxt[open_side]) <= best + eps
        active = active[go_on]
        width *= 2
    if not kept_rows:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, best
    r, c, v = np.concatenate(kept_rows), np.concatenate(kept_cols), np.concatenate(kept_vals)
    keep = v <= best + eps
    return r[keep], c[keep], best


def _ratio_of(tab: _PairTable, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Correctly rounded float ratio of the two-stage trains (exact integer products, one division)."""
    return (tab.drv[rows] * tab.drv[cols]) / (tab.dvn[rows] * tab.dvn[cols])


def _pick_exact(target: float, driving: np.ndarray, driven: np.ndarray) -> GearTrain:
    """Best train among candidates (rows of ``driving``/``driven``) under the documented exact key."""
    num = np.prod(driving, axis=1)
    den = np.prod(driven, axis=1)
    g = np.gcd(num, den)
    reduced, inverse = np.unique(np.stack([num // g, den // g], axis=1), axis=0, return_inverse=True)
    inverse = np.asarray(inverse).reshape(-1)
    exact_target = Fraction(target)
    errors = [abs(Fraction(int(p), int(q)) - exact_target) for p, q in reduced]
    e_min = min(errors)
    winners = np.flatnonzero(np.array([e == e_min for e in errors])[inverse])
    teeth = np.stack([driving[winners], driven[winners]], axis=2).reshape(winners.size, -1)  # a, b, c, d
    keys = [teeth[:, k] for k in range(teeth.shape[1] - 1, -1, -1)] + [teeth.sum(axis=1)]
    best = teeth[np.lexsort(keys)[0]]
    driving_teeth = tuple(int(t) for t in best[0::2])
    return GearTrain(target=target, driving=driving_teeth, driven=tuple(int(t) for t in best[1::2]))


@functools.lru_cache(maxsize=64)
def _reachable(gear_set: ChangeGearSet, stages: int) -> tuple[float, float]:
    tab = _pair_table(gear_set)
    n = tab.ratio.size
    if n == 0:
        return math.inf, -math.inf
    if stages == 1:
        return float(tab.ratio[0]), float(tab.ratio[-1])
    clr = gear_set.min_clearance_teeth
    rows_lo, _, low = _branch_and_bound(tab, clr, np.zeros(n, dtype=np.int64), lambda r, c: _ratio_of(tab, r, c), 0.0)
    _, _, neg_high = _branch_and_bound(tab, clr, np.full(n, n, dtype=np.int64), lambda r, c: -_ratio_of(tab, r, c), 0.0)
    if not rows_lo.size:
        return math.inf, -math.inf
    return low, -neg_high


# ----------------------------------------------------------------------------------------------------
# public functions
# ----------------------------------------------------------------------------------------------------


def _check_set_and_stages(gear_set: ChangeGearSet, stages: int) -> None:
    if not isinstance(gear_set, ChangeGearSet):
        raise TypeError(
            _problem("gear_set", gear_set, "not a ChangeGearSet", "pass STANDARD_SET or a ChangeGearSet(...)")
        )
    if not _is_int(stages) or stages not in (1, 2):
        raise ValueError(_problem("stages", stages, "unsupported number of stages", "use 1 (a/b) or 2 ((a/b)*(c/d))"))
    if len(gear_set.teeth) < 2 * stages:
        raise ValueError(
            _problem(
                f"{gear_set.name}.teeth",
                gear_set.teeth,
                f"{len(gear_set.teeth)} gears cannot form a {stages}-stage train",
                f"give at least {2 * stages} gears or use stages=1",
            )
        )


def reachable_range(gear_set: ChangeGearSet = STANDARD_SET, stages: int = 2) -> tuple[float, float]:
    """Smallest and largest ratio an admissible train of the set can realise.

    Parameters
    ----------
    gear_set : ChangeGearSet, default STANDARD_SET
        The change gears and guitar rules.
    stages : {1, 2}, default 2
        One-stage (a/b) or two-stage ((a/b)*(c/d)) trains.

    A target outside this range (by more than 1e-9 relative, which tolerates float rounding of a target that *is*
    the extreme ratio) is rejected by :func:`choose_change_gears`: no change-gear setting can approximate it in the
    sense required for gear cutting.

    Returns
    -------
    (float, float)
        ``(min_ratio, max_ratio)``; the result is cached per set and number of stages.

    Raises
    ------
    ValueError
        If ``stages`` is not 1 or 2, the set has too few gears, or no train at all is admissible
        (stage-ratio bounds or engagement rule too tight for the set).
    """
    _check_set_and_stages(gear_set, stages)
    low, high = _reachable(gear_set, stages)
    if low > high:
        engagement = f" and the engagement rule (clearance {gear_set.min_clearance_teeth} teeth)" if stages == 2 else ""
        raise ValueError(
            _problem(
                f"{gear_set.name}",
                gear_set.teeth,
                f"no {stages}-stage train satisfies stage ratios in "
                f"[{gear_set.min_stage_ratio:g}, {gear_set.max_stage_ratio:g}]{engagement}",
                "widen the stage-ratio bounds, lower min_clearance_teeth or add gears",
            )
        )
    return low, high


def choose_change_gears(target: float, gear_set: ChangeGearSet = STANDARD_SET, stages: int = 2) -> GearTrain:
    """Best change-gear train for a target ratio.

    Parameters
    ----------
    target : float
        Ratio to realise (output speed / input speed of the guitar); finite, > 0 and within
        :func:`reachable_range` of the set (1e-9 relative slack).
    gear_set : ChangeGearSet, default STANDARD_SET
        The change gears available and the guitar rules (stage-ratio bounds, engagement clearance).
    stages : {1, 2}, default 2
        1 for a single pair a/b, 2 for (a/b)*(c/d).

    Returns
    -------
    GearTrain
        The admissible train (:class:`ChangeGearSet`) with the smallest |relative error|; ties broken by the
        smallest total number of teeth, then the lexicographically smallest (a, b, c, d) (see Notes).  Its
        ``relative_error`` is the error actually achieved; the set may not allow 1e-6.

    Raises
    ------
    ValueError
        If the target is not finite and > 0, ``stages`` is not 1 or 2, the set has fewer than
        ``2 * stages`` gears or admits no train, or the target lies outside the reachable range (the
        message states the range).
    TypeError
        If ``gear_set`` is not a :class:`ChangeGearSet`.

    Notes
    -----
    The best train's key is, in order:

    1. smallest |ratio - target|, compared exactly: the achieved ratio is an exact fraction of tooth products and
       the target is taken as the exact binary value of the float (so the comparison is the same as comparing
       |relative error|, without rounding ties);
    2. smallest total number of teeth (a + b, or a + b + c + d): smaller, lighter gears;
    3. lexicographically smallest ``(a, b)`` or ``(a, b, c, d)``.

    The result is therefore unique and deterministic.

    One stage: all admissible ordered pairs of tooth counts are evaluated (vectorised; ~1500 pairs). Two stages:
    meet in the middle. The admissible pairs are sorted by ratio; for every first-stage pair (a, b) the second stage
    ideally equals ``target / (a/b)``, located by bisection (``np.searchsorted``). On each side of that point the
    error grows monotonically with the distance in the sorted list, so the neighbours are examined outward in
    growing windows, checking the engagement and multiplicity rules on each 4-tuple, and a side is abandoned as soon
    as its next unexamined neighbour is already worse than the best admissible train found so far (branch and
    bound). This is exact, not heuristic: the tests compare it against an exhaustive search over all admissible
    4-tuples. Near-ties in floating point (within 1e-12) are resolved with exact rational arithmetic.

    Examples
    --------
    >>> choose_change_gears(23 / 40).describe()
    'a/b * c/d = 23/20 * 25/50 = 0.575000000 (error +0.0e+00)'
    """
    if not _is_real(target) or not math.isfinite(target) or target <= 0:
        raise ValueError(
            _problem("target", target, "not a finite ratio > 0", "give a positive finite ratio, e.g. 0.575")
        )
    target = float(target)
    _check_set_and_stages(gear_set, stages)
    low, high = reachable_range(gear_set, stages)
    if not low * (1 - _RANGE_SLACK) <= target <= high * (1 + _RANGE_SLACK):
        raise ValueError(
            _problem(
                "target",
                target,
                f"outside the range reachable with change-gear set {gear_set.name!r} in {stages} stage(s), "
                f"[{low:.9g}, {high:.9g}]",
                "use a target in that range"
                + (", stages=2" if stages == 1 else "")
                + ", another gear set, or split the ratio elsewhere in the kinematic chain",
            )
        )
    tab = _pair_table(gear_set)
    if stages == 1:
        err = np.abs(tab.ratio - target) / target
        cand = np.flatnonzero(err <= err.min() + _TIE_EPS)
        return _pick_exact(target, tab.drv[cand, None], tab.dvn[cand, None])

    def rel_error(r: np.ndarray, c: np.ndarray) -> np.ndarray:
        return np.abs(_ratio_of(tab, r, c) - target) / target

    start = np.searchsorted(tab.ratio, target / tab.ratio)
    rows, cols, _ = _branch_and_bound(tab, gear_set.min_clearance_teeth, start, rel_error, _TIE_EPS)
    driving = np.stack([tab.drv[rows], tab.drv[cols]], axis=1)
    driven = np.stack([tab.dvn[rows], tab.dvn[cols]], axis=1)
    return _pick_exact(target, driving, driven)
