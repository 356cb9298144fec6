"""Involute function and its inverse (ISO 21771 notation: inv(alpha) = tan(alpha) - alpha)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def inv(alpha: ArrayLike) -> np.ndarray | float:
    """Involute function ``inv(alpha) = tan(alpha) - alpha`` (alpha in radians)."""
    a = np.asarray(alpha, dtype=float)
    out = np.tan(a) - a
    return float(out) if out.ndim == 0 else out


def inv_inverse(value: ArrayLike, tol: float = 1e-15) -> np.ndarray | float:
    """Pressure angle alpha (radians) whose involute is ``value`` (>= 0).

    Newton iteration on ``tan(a) - a - value`` from the series start ``a = (3 value)^(1/3)``,
    which converges in a handful of steps for every angle below ~ 80 degrees.
    """
    v = np.asarray(value, dtype=float)
    if np.any(v < 0) or not np.all(np.isfinite(v)):
        raise ValueError(f"inv_inverse needs finite values >= 0, got {value!r}")
    a = np.cbrt(3.0 * v)
    a = np.minimum(a, 1.5)
    for _ in range(60):
        f = np.tan(a) - a - v
        step = f / np.tan(a) ** 2 if np.all(a > 0) else np.where(a > 0, f / np.maximum(np.tan(a) ** 2, 1e-300), 0.0)
        a = a - step
        if np.all(np.abs(step) < tol):
            break
    return float(a) if a.ndim == 0 else a


def roll_angle(radius: ArrayLike, base_radius: float) -> np.ndarray | float:
    """Roll angle xi = tan(alpha_y) of the involute point at ``radius`` (radius >= base radius)."""
    r = np.asarray(radius, dtype=float)
    out = np.sqrt(np.maximum(r * r - base_radius * base_radius, 0.0)) / base_radius
    return float(out) if out.ndim == 0 else out
