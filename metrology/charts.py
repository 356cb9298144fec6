"""Measuring-machine charts: profile and helix traces with the tolerance band, pitch bars with the
cumulative curve. Written as PNG with matplotlib's Agg backend (no display needed)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from metrology.modification import chart_teeth

SIDES = ("left", "right")


def _trace_chart(
    path: Path,
    title: str,
    x_label: str,
    axis: np.ndarray,
    traces: dict[str, np.ndarray],
    numbers: list[int],
    band_um: float | None,
    band_label: str,
) -> None:
    """Traces drawn like a gear chart: deviation across, the flank coordinate up; one column per tooth."""
    fig, axes = plt.subplots(1, 2 * len(numbers), figsize=(2.0 * 2 * len(numbers), 6), sharey=True)
    for s, side in enumerate(SIDES):
        for j, n in enumerate(numbers):
            ax = axes[s * len(numbers) + j]
            e = traces[side][n - 1]
            ok = np.isfinite(e)
            ax.plot(e[ok], axis[ok], color="tab:blue", lw=1.2)
            if ok.sum() > 2:
                coef = np.polyfit(axis[ok], e[ok], 1)
                ax.plot(np.polyval(coef, axis[ok]), axis[ok], color="tab:orange", lw=0.8, ls="--")
                if band_um is not None:
                    mid = float(np.mean(e[ok]))
                    ax.axvspan(mid - band_um / 2, mid + band_um / 2, color="tab:green", alpha=0.12)
            ax.axvline(0.0, color="k", lw=0.5)
            ax.set_title(f"{side} {n}", fontsize=9)
            ax.set_xlim(
                -max(5.0, (band_um or 0) * 0.75, np.nanmax(np.abs(e)) * 1.3 if ok.any() else 0),
                max(5.0, (band_um or 0) * 0.75, np.nanmax(np.abs(e)) * 1.3 if ok.any() else 0),
            )
            ax.tick_params(labelsize=7)
            ax.set_xlabel("um", fontsize=8)
    axes[0].set_ylabel(x_label)
    fig.suptitle(f"{title}  (band: {band_label})", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def pitch_chart(path: Path, result: dict[str, Any]) -> None:
    """Single pitch deviations as bars and the cumulative pitch deviation as a curve, both flanks."""
    tol = result["iso1328"].get("tolerances") or {}
    fig, axes = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    for ax, side in zip(axes, SIDES, strict=True):
        p = result["pitch"][side]
        n = np.arange(1, len(p["f_pi"]) + 1)
        ax.bar(n, p["f_pi"], color="tab:blue", alpha=0.7, label="f_pi")
        ax.plot(n, p["F_pi"], color="tab:red", marker=".", label="F_pi")
        if tol.get("f_p"):
            for v in (tol["f_p"], -tol["f_p"]):
                ax.axhline(v, color="tab:blue", ls=":", lw=0.8)
        ax.axhline(0, color="k", lw=0.5)
        ax.set_ylabel(f"{side} [um]")
        ax.set_title(
            f"{side}: f_p = {p['f_p']:.2f} um, F_p = {p['F_p']:.2f} um, F_pk(k={p['k']}) = {p['F_pk']:.2f} um",
            fontsize=9,
        )
        ax.legend(fontsize=8, loc="upper right")
    axes[-1].set_xlabel("tooth")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_charts(out: Path, result: dict[str, Any]) -> list[Path]:
    """profile.png, helix.png, pitch.png and topography.png in ``out``; returns the paths."""
    out.mkdir(parents=True, exist_ok=True)
    tr = result["_traces"]
    order = tr["order"]  # nominal tooth index of tooth numbers 1..z
    z = len(order)
    numbers = chart_teeth(z)
    iso = result["iso1328"]
    tol = iso.get("tolerances") or {}
    cls = iso.get("tolerances_class")
    label = f"ISO 1328-1 class {cls}" if cls else "no ISO class"
    prof = {s: np.asarray(tr["profile"][s])[order] * 1e3 for s in SIDES}
    helix = {s: np.asarray(tr["helix"][s])[order] * 1e3 for s in SIDES}
    paths = [out / "profile.png", out / "helix.png", out / "pitch.png"]
    _trace_chart(
        paths[0],
        "Profile (mid section)",
        "roll length [mm]",
        np.asarray(tr["L_mm"]),
        prof,
        numbers,
        tol.get("F_alpha"),
        f"F_alpha {label}",
    )
    _trace_chart(
        paths[1],
        "Helix (reference cylinder)",
        "z [mm]",
        np.asarray(tr["z_mm"]),
        helix,
        numbers,
        tol.get("F_beta"),
        f"F_beta {label}",
    )
    pitch_chart(paths[2], result)
    if result.get("topography"):
        paths.append(topography_chart(out / "topography.png", result["topography"]))
    return paths


def finite(obj: Any) -> Any:
    """JSON-safe copy: NaN/inf -> None, numpy scalars -> Python numbers, private keys dropped."""
    if isinstance(obj, dict):
        return {k: finite(v) for k, v in obj.items() if not str(k).startswith("_")}
    if isinstance(obj, list | tuple):
        return [finite(v) for v in obj]
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def topography_chart(path: Path, topo: dict[str, Any]) -> Path:
    """The flank topography as a colour map per flank (deviation over roll length x face, mean of the scanned
    teeth, um); with a design, a second row shows the deviation from it."""
    L, z = np.asarray(topo["L_mm"]), np.asarray(topo["z_mm"])
    designed = any(np.any(np.asarray(topo[s]["design_um"], dtype=float) != 0) for s in SIDES)
    rows = [("deviation_um", "measured")] + ([("against_design_um", "against the design")] if designed else [])
    fig, axes = plt.subplots(len(rows), 2, figsize=(10, 3.6 * len(rows)), squeeze=False)
    for i, (key, what) in enumerate(rows):
        grids = [np.asarray(topo[s][key], dtype=float) for s in SIDES]
        lim = max(float(np.nanmax(np.abs(g))) if np.isfinite(g).any() else 0.0 for g in grids) or 1.0
        for j, (side, grid) in enumerate(zip(SIDES, grids, strict=True)):
            ax = axes[i][j]
            mesh = ax.pcolormesh(z, L, grid, cmap="RdBu", vmin=-lim, vmax=lim, shading="nearest")
            ax.set_title(f"{side} flank, {what}")
            ax.set_xlabel("z [mm]")
            ax.set_ylabel("roll length [mm]")
            fig.colorbar(mesh, ax=ax, label="um (excess material > 0)")
    teeth = ", ".join(str(t) for t in topo["teeth"])
    fig.suptitle(f"Flank topography, mean of teeth {teeth}")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path
