"""Evaluation of a profile or helix trace per ISO 1328-1:2013: total, slope and form deviation.

The mean line is the least-squares straight line through the deviation trace e(x) over the evaluation
range (the design profile/helix is the nominal flank, so e is already relative to it):

- total deviation  F = max(e) - min(e)                         (F_alpha, F_beta)
- slope deviation  f_H = line(x_end) - line(x_start)           (f_Halpha, f_Hbeta), x_end towards the
  tip for a profile, towards +z for a helix: positive means more material there
- form deviation   f_f = max(e - line) - min(e - line)         (f_falpha, f_fbeta)
"""

from __future__ import annotations

import numpy as np


def evaluate(x: np.ndarray, e: np.ndarray) -> dict[str, float]:
    """F, f_H, f_f [same unit as e] of one trace e(x); x ordered from the start to the end of the range."""
    ok = np.isfinite(e)
    if ok.sum() < 3:
        return {"F": float("nan"), "f_H": float("nan"), "f_f": float("nan")}
    xs, es = x[ok], e[ok]
    slope, intercept = np.polyfit(xs, es, 1)
    line = slope * xs + intercept
    resid = es - line
    return {
        "F": float(es.max() - es.min()),
        "f_H": float(slope * (x[-1] - x[0])),
        "f_f": float(resid.max() - resid.min()),
    }


def evaluate_many(x: np.ndarray, e: np.ndarray) -> dict[str, np.ndarray]:
    """:func:`evaluate` for every row of ``e`` (teeth x samples)."""
    rows = [evaluate(x, row) for row in e]
    return {key: np.array([r[key] for r in rows]) for key in ("F", "f_H", "f_f")}
