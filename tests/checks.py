"""What the tests share: the shipped jobs' folder (not relative to the working directory), a largest deviation that
cannot pass on missing values and the oblique cutting model's factors typed by hand."""

from __future__ import annotations

import math
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


def oblique_factors(gamma_deg: float, lambda_deg: float, beta_a_deg: float = 30.0) -> tuple[float, float, float]:
    """(K_c, K_t, K_p) / tau_s typed from the formulas of cutting/oblique.py's docstring (Merchant's shear angle,
    Stabler's eta_c = lambda_s), for the tests' hand-worked forces: not the model's code."""
    g, lam, beta_a = (math.radians(x) for x in (gamma_deg, lambda_deg, beta_a_deg))
    eta = lam
    beta_n = math.atan(math.tan(beta_a) * math.cos(eta))
    phi_n = math.pi / 4 - (beta_n - g) / 2
    s = math.sqrt(math.cos(phi_n + beta_n - g) ** 2 + (math.tan(eta) * math.sin(beta_n)) ** 2)
    k_c = (math.cos(beta_n - g) + math.tan(eta) * math.tan(lam) * math.sin(beta_n)) / (math.sin(phi_n) * s)
    k_t = math.sin(beta_n - g) / (math.sin(phi_n) * math.cos(lam) * s)
    k_p = (math.cos(beta_n - g) * math.tan(lam) - math.tan(eta) * math.sin(beta_n)) / (math.sin(phi_n) * s)
    return k_c, k_t, k_p
