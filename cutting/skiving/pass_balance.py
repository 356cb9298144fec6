"""The passes' balance: each pass's largest uncut chip thickness, and radial increments that give every pass the same.

A skiving machine cuts a gear's depth in several passes (multi-cut strategies); the chip of a pass grows with its
radial increment but not in proportion (the tip's chip about as the increment, the flanks' as the increment times the
feed), so equal increments load the passes unequally: the default job's roughing pass (1.75 mm) takes a 1.24 mm chip,
its finishing pass (0.5 mm) 0.49 mm. :func:`balance_passes` keeps the number of passes and the total depth and moves
the increments until every pass's largest chip is the same (within ``tolerance``), from the working-angle maps of the
setup alone (:func:`cutting.skiving.working_angles.working_angle_maps`: the exact swept workpiece before each pass's
middle passage and that passage's own sweep).

Each step takes the chip as a power of the increment, h_i = c_i d_i^p_i (p_i from the last two steps of pass i, 0.75
to start: the default job's two passes give 0.74), solves for the increments that give one chip H to all passes and
sum to the depth D: d_i = (H / c_i)^(1 / p_i), then Newton on H. The largest chip is not smooth in the increments:
it sits on a few points of the tip's corner and jumps where its place moves (the default job's first pass: 0.38 mm
of chip at 0.82 mm of increment, 0.85 at 0.90), so the steps can overshoot; the proposal is the best step's, with the
spread it reached.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from cutting.skiving.edge import CuttingEdge
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.working_angles import working_angle_maps

#: the chip's exponent in the increment to start from (the default job's two passes: log(1.243 / 0.490) / log(3.5))
START_EXPONENT = 0.75
#: the exponents a step may take (a pass whose chip barely moves must not throw its increment far)
EXPONENTS = (0.3, 1.5)


@dataclass(frozen=True)
class PassBalance:
    """A proposal of radial increments [mm] and the largest chip [mm] each pass takes with them; ``before``: the
    job's increments and chips; ``steps``: the map evaluations it took."""

    passes: tuple[float, ...]
    chips: tuple[float, ...]
    before_passes: tuple[float, ...]
    before_chips: tuple[float, ...]
    steps: int

    @property
    def spread(self) -> float:
        """The largest chip over the smallest (1: balanced)."""
        return max(self.chips) / min(self.chips)

    def as_dict(self) -> dict:
        return {
            "passes_mm": list(self.passes),
            "chip_thickness_max_mm": list(self.chips),
            "spread": self.spread,
            "job_passes_mm": list(self.before_passes),
            "job_chip_thickness_max_mm": list(self.before_chips),
            "job_spread": max(self.before_chips) / min(self.before_chips),
            "steps": self.steps,
        }


#: the chip on every instant and edge point of the map: the printed maps' coarser grid (every 2nd instant, 3rd point)
#: misses the largest chip by up to half on the default job, which sits on a few points of the tip's corner
STRIDE = (1, 1)


def largest_chips(setup: SkivingSetup, edge: CuttingEdge) -> tuple[float, ...]:
    """Each pass's largest uncut chip thickness [mm] (its middle passage's map, every point)."""
    maps = working_angle_maps(setup, edge, STRIDE)
    return tuple(float(np.nanmax(pa.thickness)) if np.isfinite(pa.thickness).any() else 0.0 for pa in maps)


def balance_passes(
    setup: SkivingSetup,
    edge: CuttingEdge,
    tolerance: float = 0.05,
    steps: int = 6,
    progress: Callable[[int, tuple[float, ...], tuple[float, ...]], None] | None = None,
) -> PassBalance:
    """Radial increments for ``setup``'s number of passes and total depth that give every pass the same largest chip
    (the largest over the smallest within 1 + ``tolerance``), at most ``steps`` map evaluations after the job's own;
    else the most even of them.
    ``progress(step, increments, chips)`` hears each evaluation. The edge does not depend on the increments."""
    d = np.array(setup.passes, dtype=float)
    depth = float(d.sum())
    h = np.array(largest_chips(setup, edge))
    before = (tuple(d), tuple(h))
    if progress:
        progress(0, tuple(d), tuple(h))
    if len(d) < 2 or h.max() / max(h.min(), 1e-12) <= 1 + tolerance:
        return PassBalance(tuple(d), tuple(h), *before, 1)
    p = np.full(len(d), START_EXPONENT)
    last: tuple[np.ndarray, np.ndarray] | None = None
    done = 1
    best = (h.max() / h.min(), d, h)
    for step in range(1, steps + 1):
        if last is not None:  # each pass's exponent from its last two steps
            d0, h0 = last
            moved = (np.abs(np.log(d / d0)) > 1e-3) & (h > 0) & (h0 > 0)
            p = np.where(moved, np.log(h / np.where(h0 > 0, h0, 1)) / np.where(moved, np.log(d / d0), 1), p)
            p = np.clip(p, *EXPONENTS)
        c = h / d**p
        target = _common_chip(c, p, depth)
        last = (d, h)
        d = (target / c) ** (1 / p)
        d *= depth / d.sum()  # exact to rounding
        h = np.array(largest_chips(replace(setup, passes=tuple(float(x) for x in d)), edge))
        done += 1
        if progress:
            progress(step, tuple(d), tuple(h))
        spread = h.max() / max(h.min(), 1e-12)
        if spread < best[0]:
            best = (spread, d, h)
        if spread <= 1 + tolerance:
            break
    _, d, h = best  # the largest chip is not smooth in the increments (it jumps where its place on the edge does)
    return PassBalance(tuple(float(x) for x in d), tuple(float(x) for x in h), *before, done)


def _common_chip(c: np.ndarray, p: np.ndarray, depth: float) -> float:
    """The chip H at which the increments (H / c_i)^(1 / p_i) sum to ``depth`` (Newton on log H: the sum grows
    monotonically with H)."""
    log_h = float(np.log(np.mean(c * (depth / len(c)) ** p)))
    for _ in range(50):
        d = np.exp((log_h - np.log(c)) / p)
        f = float(d.sum()) - depth
        step = f / float((d / p).sum())
        log_h -= step
        if abs(step) < 1e-12:
            break
    return math.exp(log_h)
