"""Measuring modified teeth: crowning of a trace, and the flank topography.

Crowning (profile C_alpha, helix C_beta) of a deviation trace e(x) over its evaluation range [x0, x1]: the
least-squares parabola through e, and the height of its arc over its chord, positive when the ends lie lower
than the middle (material taken from the ends, as a crowning does):

    e ~ a + b t + c t^2,  t = (x - x_m) / h,  x_m = (x0 + x1) / 2,  h = (x1 - x0) / 2   ->   C = -c

Twist S_beta of a topography e(L, z): the helix slope at the top of the profile evaluation range minus that at
its bottom, as a gear measuring machine reports it (ISO 21771's flank twist over the evaluation range; the design's
cutting.modification.FlankDesign.twist is the same over the whole active profile L_F..L_a, so it reads as
S_beta (L1 - L0) / (L_a - L_F) here), from the least-squares quadric over the grid

    e ~ a + b z + c L + d z^2 + f L^2 + g z L   ->   S_beta = g b_face (L1 - L0)

(the other terms take up crowning and helix and profile slope).

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


def twist(L: np.ndarray, z: np.ndarray, e: np.ndarray, face_width: float) -> float:
    """S_beta [unit of e] of the topography ``e`` (len(L) x len(z), NaN samples skipped) over roll lengths ``L``
    and face positions ``z`` [mm]: the helix slope's change over the face width from L[0] to L[-1]."""
    LL, zz = np.meshgrid(np.asarray(L, float), np.asarray(z, float), indexing="ij")
    ok = np.isfinite(e)
    if ok.sum() < 8:
        return float("nan")
    lc, zc = LL[ok] - LL[ok].mean(), zz[ok] - zz[ok].mean()
    basis = np.stack([np.ones_like(lc), zc, lc, zc**2, lc**2, zc * lc], axis=1)
    coef = np.linalg.lstsq(basis, np.asarray(e, float)[ok], rcond=None)[0]
    return float(coef[5] * face_width * (L[-1] - L[0]))


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
