"""Measuring modified teeth: crowning of a trace, and the flank topography.

Crowning (profile C_alpha, helix C_beta) of a deviation trace e(x) over its evaluation range [x0, x1]: the
least-squares parabola through e, and the height of its arc over its chord, positive when the ends lie lower
than the middle (material taken from the ends, as a crowning does):

    e ~ a + b t + c t^2,  t = (x - x_m) / h,  x_m = (x0 + x1) / 2,  h = (x1 - x0) / 2   ->   C = -c

The topography is the deviation over a grid of roll lengths x face positions on a few teeth round the gear, as a
gear measuring machine scans it; with a design it is shown beside the design's own topography.
"""

from __future__ import annotations

import numpy as np

from cutting.flank import SIDES
from cutting.gear import Gear
from metrology.datum import Datum
from metrology.workpiece import Workpiece, flank_deviation

#: topography grid: roll lengths x face positions
GRID = (15, 11)


def chart_teeth(z: int, count: int = 4) -> list[int]:
    """Tooth numbers a measuring machine charts and scans for the topography: ``count`` teeth evenly round the
    gear."""
    return sorted({1 + round(i * z / count) % z for i in range(count)})


def crowning(x: np.ndarray, e: np.ndarray) -> float:
    """C of one trace e(x) [unit of e] over the range of ``x`` (NaN samples skipped)."""
    ok = np.isfinite(e)
    if ok.sum() < 4:
        return float("nan")
    xm, h = (x[0] + x[-1]) / 2, (x[-1] - x[0]) / 2
    c = np.polyfit((x[ok] - xm) / h, e[ok], 2)[0]
    return float(-c)


def crowning_many(x: np.ndarray, e: np.ndarray) -> np.ndarray:
    """:func:`crowning` of every row of ``e`` (teeth x samples)."""
    return np.array([crowning(x, row) for row in e])


def topography(
    wp: Workpiece,
    gear: Gear,
    datum: Datum,
    roll_range: tuple[float, float],
    z_range: tuple[float, float],
    teeth: list[int],
    grid: tuple[int, int] = GRID,
) -> dict[str, object]:
    """Deviation [mm] of each flank over the grid of roll lengths x face positions, on the nominal ``teeth``
    (indices); per side the mean over those teeth (nL, nz) and each tooth's grid."""
    L = np.linspace(*roll_range, grid[0])
    z = np.linspace(*z_range, grid[1])
    xi = (L / gear.base_radius)[None, :, None]
    tooth = np.asarray(teeth)[:, None, None]
    out: dict[str, object] = {"L_mm": L, "z_mm": z}
    for side in SIDES:
        e = flank_deviation(wp, gear, datum, side, xi, z[None, None, :], tooth)
        out[side] = e
    return out
