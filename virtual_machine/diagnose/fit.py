"""Fitting the error sources' values to a measured gear from their signatures (docs/diagnose.md).

The measured gear and every case of the sensitivity study become one vector each, on the base case's grid: every
tooth's profile (mid section, over roll length) and helix (over the face) on both flanks, and the cumulative pitch
deviations (the single ones summed round the gear, their mean removed), each block weighted by one over the square
root of its points (a block counts as much as another, however finely it is probed). The measured gear less the base
case (the job's own ideal cut) is what the sources must explain: y = J x + r, J's columns the cases less the base
case per unit of each probe, plus a nuisance column (the gear turned: a measuring machine's datum is its own).

Which sources: forward selection, the one that lowers the residual most first, as long as the next one removes at
least ``min_gain`` (10 %) of what the chosen ones leave, and 1e-4 of the measured deviation's sum of squares y'y (on
the shipped jobs the injected sources remove 60-99 % of what is left each, the next one 2 % or less). Each chosen
source's value is its least-squares coefficient times its probe (a phased source: the amplitude and phase of its two
coefficients), with the standard error the residual leaves it. Its **confidence** is its partial R^2: the residual's
growth when it is dropped, over that grown residual (a source the others cannot stand in for, fitting what it
explains, is near 1 however small its signature; one that only takes up a little of the residual is near 0); its
**share** is that growth over y'y (how much of the measured deviation it alone explains). The causes are ranked by
confidence (to two places), then share.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from virtual_machine.diagnose.measured import SIDES, MeasuredGear
from virtual_machine.diagnose.sources import Source, amplitude_phase


@dataclass(frozen=True)
class Grid:
    """The positions every gear is compared at: the base case's roll lengths ``L`` and face positions ``z`` [mm],
    its number of teeth, and the widths [mm] of the Gaussian that smooths each profile and helix before the fit
    (what a process leaves at the scale of its feed marks and generating cuts is not a machine's geometry, and it
    moves with every error non-linearly: the fit sees the traces' long waves only)."""

    teeth: int
    L: np.ndarray
    z: np.ndarray
    smooth_L: float = 0.0
    smooth_z: float = 0.0

    @classmethod
    def of(cls, base: MeasuredGear, feed: float = 0.0) -> Grid:
        """The base case's grid; ``feed`` [mm per work turn]: the helix smoothed over half of it (the feed marks'
        period along the face), the profile over a tenth of its range."""

        def positions(kind: str) -> np.ndarray:
            teeth = base.traces.get((kind, SIDES[0]), {})
            return teeth[min(teeth)].position if teeth else np.zeros(0)

        L = positions("profile")
        return cls(base.teeth, L, positions("helix"), 0.1 * float(np.ptp(L)) if len(L) else 0.0, feed / 2)

    @property
    def blocks(self) -> tuple[tuple[str, int], ...]:
        """(name, length) of the vector's blocks, in order."""
        z = self.teeth
        return ("profile", 2 * z * len(self.L)), ("helix", 2 * z * len(self.z)), ("pitch", 2 * z)


def features(gear: MeasuredGear, grid: Grid) -> np.ndarray:
    """The gear as one vector on ``grid`` [um] (NaN where it was not measured: a trace shorter than the grid, a
    tooth missing)."""
    parts = []
    for kind, x in (("profile", grid.L), ("helix", grid.z)):
        for side in SIDES:
            teeth = gear.traces.get((kind, side), {})
            for tooth in range(1, grid.teeth + 1):
                tr = teeth.get(tooth)
                if tr is None or len(tr.position) < 2:
                    parts.append(np.full(len(x), np.nan))
                    continue
                inside = (x >= tr.position[0] - 1e-9) & (x <= tr.position[-1] + 1e-9)
                on_grid = np.where(inside, np.interp(x, tr.position, tr.deviation), np.nan)
                parts.append(smoothed(x, on_grid, grid.smooth_L if kind == "profile" else grid.smooth_z))
    for side in SIDES:
        f_pi = gear.pitch.get(side, {})
        values = np.array([f_pi.get(t, np.nan) for t in range(1, grid.teeth + 1)])
        if np.isnan(values).any():  # a missing pitch breaks the sum round the gear: the flank's pitch is not used
            parts.append(np.full(grid.teeth, np.nan))
            continue
        cumulative = np.concatenate([[0.0], np.cumsum(values[1:])])  # F_pi: tooth 1 the reference
        parts.append(cumulative - cumulative.mean())
    return np.concatenate(parts)


def smoothed(x: np.ndarray, y: np.ndarray, sigma: float) -> np.ndarray:
    """``y`` over ``x`` smoothed by a Gaussian of width ``sigma`` [mm], normalised over the points that hold a value
    (linear in ``y``: the fit's vectors stay a linear map of the traces); NaN stays NaN."""
    if sigma <= 0 or len(x) < 3:
        return y
    ok = np.isfinite(y)
    k = np.exp(-0.5 * ((x[:, None] - x[None, :]) / sigma) ** 2) * ok[None, :]
    out = (k @ np.where(ok, y, 0.0)) / np.maximum(k.sum(1), 1e-300)
    return np.where(ok, out, np.nan)


def weights(grid: Grid, valid: np.ndarray) -> np.ndarray:
    """Each point's weight: one over the square root of its block's valid points."""
    out, at = np.zeros(len(valid)), 0
    for _, n in grid.blocks:
        k = int(valid[at : at + n].sum())
        out[at : at + n] = 1.0 / np.sqrt(k) if k else 0.0
        at += n
    return out


def turn_column(grid: Grid) -> np.ndarray:
    """The nuisance: the gear turned by a small angle moves one flank out and the other in, on every trace point, the
    pitch not at all (its mean is removed)."""
    z = grid.teeth
    sign = []
    for n in (len(grid.L), len(grid.z)):
        sign += [np.ones(z * n), -np.ones(z * n)]
    return np.concatenate([*sign, np.zeros(2 * z)])


@dataclass
class Cause:
    """One source the fit names: its job key, its value [job units] with the standard error the residual leaves it,
    its phase [deg] (a phased source), its confidence (its partial R^2: of what the fit leaves when it is dropped, the
    share it explains) and its share (of the measured deviation, what it alone explains)."""

    key: str
    value: float
    unit: str
    uncertainty: float
    confidence: float
    phase_deg: float | None = None
    share: float = 0.0

    def as_json(self) -> dict:
        out = {"key": self.key, "value": self.value, "confidence": self.confidence, "unit": self.unit,
               "uncertainty": self.uncertainty, "share": self.share}  # fmt: skip
        if self.phase_deg is not None:
            out["phase_deg"] = self.phase_deg
        return out


@dataclass
class Diagnosis:
    """The fit: the ``causes`` best first, R^2 (the share of the measured deviation, weighted as fitted, that the
    causes and the datum's turn explain), the RMS of the measured deviation from the base case and of what the fit
    leaves of it [um, over every point], and the vectors for the chart: that deviation and the fit's."""

    causes: list[Cause]
    r2: float
    measured_rms_um: float
    residual_rms_um: float
    grid: Grid
    measured: np.ndarray = field(repr=False)
    fitted: np.ndarray = field(repr=False)


def diagnose(
    measured: MeasuredGear,
    base: MeasuredGear,
    columns: dict[str, MeasuredGear],
    sources: tuple[Source, ...],
    min_gain: float = 0.1,
    max_sources: int = 6,
    feed: float = 0.0,
) -> Diagnosis:
    """Fit ``measured`` less ``base`` with the sources' columns (``columns``: case id -> its measured gear, the ids of
    :meth:`Source.columns`) as the module says; ``feed``: the job's axial feed [mm per work turn] (the helix traces'
    smoothing)."""
    grid = Grid.of(base, feed)
    b = features(base, grid)
    y = features(measured, grid) - b
    groups = []  # per source: its columns' vectors per unit of the probe
    for s in sources:
        cols = [(features(columns[case_id], grid) - b) for case_id, _ in s.columns()]
        groups.append(np.stack(cols, -1))
    turn = turn_column(grid)[:, None]
    valid = np.isfinite(y) & np.all([np.isfinite(g).all(-1) for g in groups], axis=0)
    w = weights(grid, valid)[valid]
    yw = y[valid] * w
    gw = [g[valid] * w[:, None] for g in groups]
    tw = turn[valid] * w[:, None]

    def solve(chosen: list[int]) -> tuple[float, np.ndarray, np.ndarray]:
        a = np.hstack([tw, *(gw[k] for k in chosen)])
        x, *_ = np.linalg.lstsq(a, yw, rcond=None)
        r = yw - a @ x
        return float(r @ r), x, a

    total = float(yw @ yw)
    chosen: list[int] = []
    rss, _, _ = solve(chosen)
    while len(chosen) < min(max_sources, len(sources)) and total > 0:
        trials = [(solve([*chosen, k])[0], k) for k in range(len(sources)) if k not in chosen]
        best, k = min(trials)
        if rss <= 0 or (rss - best) / rss < min_gain or (rss - best) / total < 1e-4:
            break
        chosen.append(k)
        rss = best
    rss, x, a = solve(chosen)
    dof = max(len(yw) - a.shape[1], 1)
    cov = rss / dof * np.linalg.pinv(a.T @ a)
    causes, at = [], 1  # column 0: the turn
    for k in chosen:
        s, n = sources[k], groups[k].shape[-1]
        coef, var = x[at : at + n], cov[at : at + n, at : at + n]
        unique = solve([j for j in chosen if j != k])[0] - rss
        if n == 1:
            value, err, phase = coef[0] * s.probe, np.sqrt(var[0, 0]) * s.probe, None
        else:
            amp, phase = amplitude_phase(coef[0], coef[1])
            g = coef / amp if amp > 0 else np.zeros(2)
            value, err = amp * s.probe, float(np.sqrt(max(g @ var @ g, 0.0))) * s.probe
        confidence = unique / (unique + rss) if unique + rss > 0 else 0.0
        causes.append(Cause(s.key, float(value), s.unit, float(err), float(confidence), phase,
                            float(unique / total) if total else 0.0))  # fmt: skip
        at += n
    causes.sort(key=lambda c: (-round(c.confidence, 2), -c.share))
    fitted = np.full(len(y), np.nan)
    fitted[valid] = (a @ x) / w
    rms = float(np.sqrt(np.mean(y[valid] ** 2))) if valid.any() else 0.0
    left = float(np.sqrt(np.mean((y[valid] - fitted[valid]) ** 2))) if valid.any() else 0.0
    return Diagnosis(causes, 1 - rss / total if total else 1.0, rms, left, grid, y, fitted)
