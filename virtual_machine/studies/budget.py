"""The error budget of a study: for each ISO 1328-1 parameter, each varied part's effect, computed from the
cases alone (nothing typed in).

The budget answers which part's tolerance decides the gear's class and what it must be for a target class.
:func:`error_budget` grades each case (:func:`graded`), takes each part's sensitivity and contribution (one at a
time: :func:`_one_at_a_time`; grid and Monte Carlo: the fit of :func:`_regression`), stacks them (:func:`_stack`) and
answers a target class (:func:`_answer_stack`, :func:`_answer_mc`); the method of each is in its docstring, the
tornado in :class:`PartEffect`. The method and the studies' figures: docs/studies.md, "The budget".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from metrology import tolerances as iso
from virtual_machine.studies.spec import Study, Vary

PARAMETERS = iso.PARAMETERS
Z95 = 1.6448536269514722  # one-sided 95 % of a normal distribution


@dataclass
class PartEffect:
    """One varied part's effect on one parameter. ``low`` and ``high`` are the **tornado**: the parameter at the
    part's lowest and highest studied value (Monte Carlo: at -1 and +1 standard deviation), every other part at its
    base."""

    key: str
    label: str
    sensitivity: float  # um per unit of the key (nan: not a number)
    low: tuple[Any, float]  # (part value, parameter [um]) at the lowest studied value (MC: -1 std)
    high: tuple[Any, float]  # the same at the highest (MC: +1 std)
    tolerance: float | None  # the part's stated tolerance (MC: its standard deviation)
    contribution: float | None  # um
    share: float | None = None  # MC: variance share; OAT/grid: share of the stack's tolerance part


@dataclass
class TargetAnswer:
    target: int
    tolerance: float  # um, ISO 1328-1 for the target class
    meets: bool
    limiting: str | None = None  # label of the part that limits
    required: float | None = None  # the limiting part's tolerance (MC: standard deviation) that meets the target
    note: str = ""


@dataclass
class ParameterBudget:
    name: str
    base: float  # um: the base case (grid: the fit at the base values; MC: the mean)
    stacked: float  # um: worst-case stack (OAT/grid) or 95th percentile of the cases (MC)
    stacked_class: int | None
    parts: list[PartEffect] = field(default_factory=list)
    residual_share: float | None = None  # MC
    answer: TargetAnswer | None = None


@dataclass
class Budget:
    method: str
    cases_ok: int
    cases_failed: int
    parameters: list[ParameterBudget]
    target: int | None
    iso_error: str | None = None  # the gear is outside ISO 1328-1's range: no classes
    #: the cases' ISO 1328-1 classes (the worst parameter's; 12: worse than class 11): how many cases made each
    class_counts: dict[int, int] = field(default_factory=dict)

    def p_at_most(self, n: int) -> float | None:
        """The share of the cases whose gear is class ``n`` or better (None without classes)."""
        total = sum(self.class_counts.values())
        return sum(k for c, k in self.class_counts.items() if c <= n) / total if total else None

    def limiting(self) -> tuple[ParameterBudget, PartEffect | None] | None:
        """The parameter with the worst class at the stacked values and its largest contributor."""
        graded = [p for p in self.parameters if p.stacked_class is not None or self.iso_error is None]
        if not graded:
            return None
        worst = max(graded, key=lambda p: (p.stacked_class or 12, p.stacked))
        parts = [e for e in worst.parts if e.contribution is not None]
        return worst, (max(parts, key=lambda e: e.contribution) if parts else None)


def graded(measured: dict[str, Any]) -> dict[str, float]:
    """The values a case is graded on (um): the worse flank, slope deviations by magnitude (each case's parameter is
    what the class is graded on: ISO 1328-1 grades |f_Halpha|, |f_Hbeta|)."""
    out = {}
    for name in PARAMETERS:
        if name == "F_r":
            v = measured.get("F_r")
            if v is not None:
                out[name] = float(v)
            continue
        sides = [measured.get(f"{name}_{s}") for s in ("left", "right")]
        sides = [abs(float(v)) for v in sides if v is not None]
        if sides:
            out[name] = max(sides)
    return out


def numeric(value: Any) -> float:
    if isinstance(value, bool):
        return float(value)
    if isinstance(value, int | float):
        return float(value)
    return math.nan


def error_budget(
    study: Study,
    records: dict[str, dict[str, Any]],
    gear_data: tuple[int, float, float, float, int | None],
    target: int | None = None,
) -> Budget:
    """The budget of ``records`` (case id -> result.json) for the gear ``(z, mn, b, beta_deg, k_sector)``."""
    ok = {cid: r for cid, r in sorted(records.items()) if r["status"] == "ok"}
    failed = len(records) - len(ok)
    values = {cid: graded(r["measured"]) for cid, r in ok.items()}
    iso_error = None
    try:
        iso.tolerances(11, *gear_data)
    except ValueError as exc:
        iso_error = str(exc)
    params = []
    for name in PARAMETERS:
        ids = [cid for cid in ok if name in values[cid]]
        if not ids:
            continue
        y = np.array([values[cid][name] for cid in ids])
        x = {v.key: [ok[cid]["values"].get(v.key) for cid in ids] for v in study.varies}
        if study.method == "one-at-a-time":
            budget = _one_at_a_time(name, study.varies, ids, x, y)
        else:
            budget = _regression(name, study, x, y)
        if budget is None:
            continue
        if iso_error is None:
            budget.stacked_class = iso.grade(budget.stacked, name, *gear_data)
            if target is not None:
                tol = iso.tolerances(target, *gear_data)[name]
                budget.answer = (_answer_mc if study.method == "monte-carlo" else _answer_stack)(budget, tol, target, y)
        params.append(budget)
    counts: dict[int, int] = {}
    if iso_error is None:  # each case's class: its worst parameter's
        for vals in values.values():
            grades = [iso.grade(v, name, *gear_data) for name, v in vals.items()]
            if grades:
                c = max(g if g is not None else 12 for g in grades)
                counts[c] = counts.get(c, 0) + 1
    return Budget(study.method, len(ok), failed, params, target, iso_error, dict(sorted(counts.items())))


def _one_at_a_time(name, varies: tuple[Vary, ...], ids, x, y) -> ParameterBudget | None:
    """One part at a time: each part's **sensitivity** [um per unit of the key] is the least-squares slope over the
    part's own cases and the base case; its **contribution** |sensitivity| x the part's stated tolerance."""
    base_rows = [i for i in range(len(ids)) if all(_same(x[v.key][i], v.base) for v in varies)]
    if not base_rows:
        return None  # the base case failed: no reference
    p0 = float(y[base_rows[0]])
    parts = []
    for v in varies:
        own = [i for i in range(len(ids)) if all(_same(x[w.key][i], w.base) for w in varies if w.key != v.key)]
        pts = sorted(((x[v.key][i], float(y[i])) for i in own), key=lambda t: _order(t[0]))
        if len(pts) < 2:
            continue
        xs = np.array([numeric(a) for a, _ in pts])
        slope = (
            float(np.polyfit(xs, [b for _, b in pts], 1)[0]) if np.isfinite(xs).all() and np.ptp(xs) > 0 else math.nan
        )
        contribution = abs(slope) * v.tolerance if v.tolerance is not None and math.isfinite(slope) else None
        parts.append(PartEffect(v.key, v.label, slope, pts[0], pts[-1], v.tolerance, contribution))
    return _stack(name, p0, parts)


def _regression(name, study: Study, x, y) -> ParameterBudget | None:
    """Linear least squares over every case: P = P0 + sum b_i (x_i - base_i).

    Grid and Monte Carlo: each part's **sensitivity** is its coefficient b_i in one linear least-squares fit over
    every case and every numeric part at once (a switch counts 0/1). Grid: the **contribution** is |b_i| x the part's
    stated tolerance (stacked by :func:`_stack`). Monte Carlo: |b_i| x the part's standard deviation, and its
    **variance share** b_i cov(x_i, P) / var(P) (Pratt's measure: the shares add up to R^2 of the fit even where a
    finite sample's draws correlate; b_i^2 var(x_i) / var(P) for independent draws; the rest, 1 - R^2, is the
    residual: nonlinearity, interactions)."""
    keys = [v for v in study.varies if v.numeric]
    if len(y) < len(keys) + 1:
        return None
    cols = [np.array([numeric(a) for a in x[v.key]]) - numeric(v.base) for v in keys]
    design = np.column_stack([np.ones(len(y)), *cols]) if cols else np.ones((len(y), 1))
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    p0, b = float(coef[0]), [float(c) for c in coef[1:]]
    parts = []
    if study.method == "monte-carlo":
        var_y = float(np.var(y, ddof=1)) if len(y) > 1 else 0.0
        shares = []
        for v, col, bi in zip(keys, cols, b, strict=True):
            sd = float(np.std(col, ddof=1))
            # b_i cov(x_i, P) / var(P): sums to R^2 exactly, and to b_i^2 var(x_i) / var(P) for independent draws
            share = bi * float(np.cov(col, y)[0, 1]) / var_y if var_y > 0 else 0.0
            shares.append(share)
            centre = float(np.mean(col))  # the draws' mean, about the base value
            at = numeric(v.base) + centre
            low, high = (at - sd, p0 + bi * (centre - sd)), (at + sd, p0 + bi * (centre + sd))
            parts.append(PartEffect(v.key, v.label, bi, low, high, sd, abs(bi) * sd, share))
        mean = float(np.mean(y))
        stacked = float(np.percentile(y, 95))
        out = ParameterBudget(name, mean, stacked, None, sorted(parts, key=lambda e: -(e.share or 0)))
        out.residual_share = max(0.0, 1.0 - sum(shares))
        return out
    for v, col, bi in zip(keys, cols, b, strict=True):
        lo, hi = float(col.min()), float(col.max())
        base = numeric(v.base)
        contribution = abs(bi) * v.tolerance if v.tolerance is not None else None
        parts.append(
            PartEffect(
                v.key, v.label, bi, (base + lo, p0 + bi * lo), (base + hi, p0 + bi * hi), v.tolerance, contribution
            )
        )
    return _stack(name, p0, parts)


def _stack(name: str, p0: float, parts: list[PartEffect]) -> ParameterBudget:
    """Worst case: the base value plus every stated tolerance's contribution (one-at-a-time and grid: the parts
    stacked arithmetically on the base case's value)."""
    stated = sum(e.contribution for e in parts if e.contribution is not None)
    for e in parts:
        if e.contribution is not None:
            e.share = e.contribution / stated if stated > 0 else 0.0
    parts.sort(key=lambda e: -(e.contribution if e.contribution is not None else -1.0))
    return ParameterBudget(name, p0, abs(p0) + stated, None, parts)


def _missed(target: int, tol: float, note: str, limiting: str | None = None, required: float | None = None):
    """A target the stack or the cases do not meet: why, the part that limits and what it needs (if any)."""
    return TargetAnswer(target, tol, False, limiting, required, note)


def _answer_stack(p: ParameterBudget, tol: float, target: int, _y) -> TargetAnswer:
    """One-at-a-time and grid against a target class N, T(N) the parameter's ISO tolerance: the stack
    P0 + sum |s_i| t_i against T; the part with the largest contribution limits; it must be tightened to
    t_i* = (T - P0 - sum_{j != i} |s_j| t_j) / |s_i| (none if that is not positive: the part alone cannot do it)."""
    if p.stacked <= tol:
        return TargetAnswer(target, tol, True)
    base = abs(p.base)
    if base > tol:
        return _missed(
            target,
            tol,
            f"the base case alone ({base:.2f} um) exceeds {tol:g} um: no studied part's tolerance causes it (the "
            "process or a part at its base value does)",
        )
    stated = [e for e in p.parts if e.contribution is not None]
    lim = max(stated, key=lambda e: e.contribution)
    others = sum(e.contribution for e in stated if e is not lim)
    room = tol - base - others
    if room <= 0 or not lim.sensitivity:
        return _missed(
            target,
            tol,
            f"tightening {lim.label} alone cannot reach it: the base case ({base:.2f} um) and the other parts' "
            f"tolerances ({others:.2f} um) take the {tol:g} um already",
            lim.label,
        )
    required = room / abs(lim.sensitivity)
    return _missed(target, tol, f"tighten {lim.label} from {lim.tolerance:.3g} to {required:.3g}", lim.label, required)


def _answer_mc(p: ParameterBudget, tol: float, target: int, y) -> TargetAnswer:
    """Monte Carlo against a target class N, T(N) the parameter's ISO tolerance: the 95th percentile of the cases
    against T; the part with the largest variance share limits; its spread must shrink by k, with
    mean + 1.645 sqrt(var(P) - (1 - k^2) b_i^2 var(x_i)) = T."""
    if p.stacked <= tol:
        return TargetAnswer(target, tol, True)
    mean, var_y = float(np.mean(y)), float(np.var(y, ddof=1))
    if mean >= tol:
        return _missed(
            target, tol, f"the mean of the cases ({mean:.2f} um) exceeds {tol:g} um: tighter spreads cannot help"
        )
    lim = max(p.parts, key=lambda e: e.share or 0.0) if p.parts else None
    if lim is None or not lim.tolerance:
        return _missed(target, tol, "no varied part explains the spread")
    need = ((tol - mean) / Z95) ** 2
    own = (lim.sensitivity * lim.tolerance) ** 2
    k2 = 1.0 - (var_y - need) / own
    if k2 <= 0:
        return _missed(target, tol, f"even a perfect {lim.label} leaves the others' spread above the target", lim.label)
    required = math.sqrt(k2) * lim.tolerance
    note = f"narrow {lim.label} from a standard deviation of {lim.tolerance:.3g} to {required:.3g}"
    return _missed(target, tol, note, lim.label, required)


def _same(a: Any, b: Any) -> bool:
    if (
        isinstance(a, int | float)
        and isinstance(b, int | float)
        and not isinstance(a, bool)
        and not isinstance(b, bool)
    ):
        return float(a) == float(b)
    return a == b


def _order(v: Any) -> tuple:
    n = numeric(v)
    return (0, n, "") if math.isfinite(n) else (1, 0.0, repr(v))


def column_sensitivity(study: Study, records: dict[str, dict[str, Any]], column: str) -> dict[str, float]:
    """Sensitivity [um per unit] of one results.csv column (e.g. the signed ``f_Hbeta_mean_left``) to each numeric
    part, by the study's method as for the budget (nan where the cases cannot tell)."""
    ok = {cid: r for cid, r in sorted(records.items()) if r["status"] == "ok" and r["measured"].get(column) is not None}
    ids = list(ok)
    y = np.array([float(ok[cid]["measured"][column]) for cid in ids])
    x = {v.key: [ok[cid]["values"].get(v.key) for cid in ids] for v in study.varies}
    if study.method == "one-at-a-time":
        p = _one_at_a_time(column, study.varies, ids, x, y)
    else:
        p = _regression(column, study, x, y)
    found = {e.key: e.sensitivity for e in p.parts} if p is not None else {}
    return {v.key: found.get(v.key, math.nan) for v in study.varies}
