"""Regenerative chatter: the stability of a cut whose chip is the surface an earlier cut left, T seconds ago.

The dynamic part of the cutting force is delta F = lambda D (Delta(t) - Delta(t - T)): Delta the tool's displacement
relative to the workpiece, D [N/m] the oriented cutting coefficients of the engaged edge at unit scale (for an edge
element of width b cutting along e_c with the cut surface's normal n towards the tool, thrust and passive directions
n, p and linearised coefficients K' = dF/dh per unit width: D = sum b (K'_c e_c - K'_t n + K'_p p) n^T; a
chip-thinning displacement along n lowers every component), averaged over a tooth period (the zeroth-order, average
force approach: Altintas and Budak, Annals of the CIRP 44/1 (1995) 357), and lambda the scale of the cut (the chip
width, or the infeed through the width it engages). With the loop's relative frequency response G(i omega) (tool
plus workpiece, m/N) the cut is on the stability limit where

    det(I - lambda (1 - exp(-i omega T)) G(i omega) D) = 0.

For an eigenvalue mu of G D this is lambda (1 - exp(-i omega T)) = 1 / mu: a real, positive lambda needs
lambda = 1 / (2 Re mu) (Re mu > 0) and omega T = pi + 2 arg(mu) + 2 pi k, k = 0, 1, ... (the lobes). One mode normal
to the cut, D = -K b n n^T: mu = -K G and lambda_lim b = -1 / (2 K Re G), Tlusty's limit (tests/test_regeneration.py).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

FrequencyResponse = Callable[[np.ndarray], np.ndarray]  # omega (n,) -> G (n, 3, 3) [m/N]


@dataclass(frozen=True)
class Lobes:
    """Stability lobes: per lobe k (``k`` (m,)), over the chatter frequency ``omega`` (n,) [rad/s], the delay
    ``delay`` (m, n) [s] and the limiting scale ``limit`` (m, n) (inf where no eigenvalue can chatter)."""

    k: np.ndarray
    omega: np.ndarray
    delay: np.ndarray
    limit: np.ndarray

    def at(self, delay: float) -> tuple[float, float]:
        """The least limit of any lobe at ``delay`` [s] and its chatter frequency [Hz] (inf, nan where no lobe
        reaches it): :meth:`limits` at one delay."""
        limit, freq = self.limits(np.array([delay]))
        return float(limit[0]), float(freq[0])

    def limits(self, delays: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The least limit over all lobes at each of ``delays`` [s] and its chatter frequency [Hz]: each lobe's limit
        interpolated along its delay (the lobe's samples sorted by delay)."""
        delays = np.asarray(delays, dtype=float)
        best = np.full(len(delays), np.inf)
        freq = np.full(len(delays), np.nan)
        for d, lim in zip(self.delay, self.limit, strict=True):
            ok = np.isfinite(lim) & np.isfinite(d)
            if ok.sum() < 2:
                continue
            order = np.argsort(d[ok])
            x, y, w = d[ok][order], lim[ok][order], self.omega[ok][order]
            inside = (delays >= x[0]) & (delays <= x[-1])
            v = np.where(inside, np.interp(delays, x, y), np.inf)
            better = v < best
            best = np.where(better, v, best)
            freq = np.where(better, np.interp(delays, x, w) / (2 * math.pi), freq)
        return best, freq


def lobes(g: FrequencyResponse | np.ndarray, d: np.ndarray, omega: np.ndarray, count: int = 8) -> Lobes:
    """The lobes of the loop ``g`` (its response function, or its response at ``omega`` already, (n, 3, 3)) and the
    oriented coefficients ``d`` (3, 3) [N/m] over the chatter frequencies ``omega`` [rad/s]: for each frequency every
    eigenvalue of G D with Re mu > 0 gives a limit 1 / (2 Re mu) at the delays (pi + 2 arg mu + 2 pi k) / omega; per
    frequency and lobe the least limit is kept."""
    omega = np.asarray(omega, dtype=float)
    response = g if isinstance(g, np.ndarray) else g(omega)
    mu = np.linalg.eigvals(response @ np.asarray(d, dtype=float))  # (n, 3)
    k = np.arange(count)
    delay = np.full((count, len(omega)), np.nan)
    limit = np.full((count, len(omega)), np.inf)
    for j in range(mu.shape[1]):
        m = mu[:, j]
        ok = m.real > 1e-300
        lam = np.where(ok, 1.0 / (2 * np.where(ok, m.real, 1.0)), np.inf)
        theta = np.mod(math.pi + 2 * np.angle(m), 2 * math.pi)
        for kk in k:
            t = (theta + 2 * math.pi * kk) / omega
            better = ok & (lam < limit[kk])
            limit[kk] = np.where(better, lam, limit[kk])
            delay[kk] = np.where(better, t, delay[kk])
    return Lobes(k, omega, delay, limit)


def tlusty_limit(g: np.ndarray, coefficient: float) -> float:
    """Tlusty's absolute limit b_lim = -1 / (2 K Re[G]_min) [m] of one direction's frequency response ``g`` (n,)
    [m/N] and the specific force K [N/m^2] in that direction."""
    worst = float(np.min(np.real(g)))
    if worst >= 0:
        return math.inf
    return -1.0 / (2 * coefficient * worst)
