"""What the tests share: the shipped jobs' folder (not relative to the working directory) and a largest deviation that
cannot pass on missing values."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: the shipped job files, wherever pytest is started from
ROOT = Path(__file__).resolve().parents[1]
JOBS = ROOT / "assets" / "jobs"


def finite_max(values, share: float) -> float:
    """The largest |value| of ``values``, asserting that at least ``share`` of them are finite: np.nanmax alone
    passes a measurement that came back NaN almost everywhere (and fails only when all of it is NaN)."""
    v = np.abs(np.asarray(values, dtype=float))
    finite = np.isfinite(v)
    got = float(finite.mean()) if v.size else 0.0
    assert got >= share, f"only {got:.1%} of {v.size} values are finite (at least {share:.0%} expected)"
    return float(v[finite].max())
