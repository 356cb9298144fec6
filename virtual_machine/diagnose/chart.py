"""The diagnosis chart: the measured deviation from the job's ideal cut against the fit's, for the profiles and
helices of four teeth on both flanks and the cumulative pitch round the gear (diagnosis.png)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from metrology.modification import chart_teeth
from virtual_machine.diagnose.fit import Diagnosis
from virtual_machine.diagnose.measured import SIDES


def fit_chart(d: Diagnosis, path: Path) -> Path:
    """Measured (solid) against fitted (dashed), um, each tooth's traces stacked a step apart."""
    g = d.grid
    z = g.teeth
    fig = Figure(figsize=(11, 9), dpi=90)
    FigureCanvasAgg(fig)
    axes = fig.subplots(3, 2)
    teeth = chart_teeth(z)
    at = 0
    step = max(float(np.nanmax(np.abs(d.measured))) if np.isfinite(d.measured).any() else 1.0, 1.0) * 1.5
    for row, (kind, x, label) in enumerate((("profile", g.L, "roll length L [mm]"), ("helix", g.z, "z [mm]"))):
        for col, side in enumerate(SIDES):
            ax = axes[row][col]
            n = len(x)
            for j, tooth in enumerate(teeth):
                sl = slice(at + (tooth - 1) * n, at + tooth * n)
                ax.plot(x, d.measured[sl] + j * step, color="C0", lw=1.2, label="measured" if j == 0 else None)
                ax.plot(x, d.fitted[sl] + j * step, color="C3", lw=1.0, ls="--", label="fitted" if j == 0 else None)
                ax.text(x[-1], j * step, f" {tooth}", va="center", fontsize=8)
            ax.set_title(f"{kind}, {side} flank (teeth {', '.join(map(str, teeth))})", fontsize=10)
            ax.set_xlabel(label, fontsize=9)
            ax.set_ylabel("um from the ideal cut", fontsize=9)
            at += z * n
    for col, side in enumerate(SIDES):
        ax = axes[2][col]
        sl = slice(at + col * z, at + (col + 1) * z)
        k = np.arange(1, z + 1)
        ax.plot(k, d.measured[sl], "o-", color="C0", ms=3, label="measured")
        ax.plot(k, d.fitted[sl], "s--", color="C3", ms=3, label="fitted")
        ax.set_title(f"cumulative pitch, {side} flank", fontsize=10)
        ax.set_xlabel("tooth", fontsize=9)
        ax.set_ylabel("um", fontsize=9)
    axes[0][0].legend(fontsize=8, loc="upper left")
    causes = "; ".join(f"{c.key.rsplit('.', 1)[-1]} {c.value:.3g} {c.unit}" for c in d.causes[:3]) or "none"
    more = f" and {len(d.causes) - 3} more" if len(d.causes) > 3 else ""
    fig.suptitle(f"measured against fitted (R^2 {d.r2:.3f})\n{causes}{more}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    return path
