"""The cutter's charts of a cut: its working angles along the edge (one row per pass: the working normal rake, the
working normal clearance and the uncut chip thickness over the edge position and the generating position, where the
edge cuts) and the load on each of its teeth (largest chip and chip energy per tooth, one bar group per pass)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from cutting.skiving.working_angles import THICKNESS_STRIDE, PassageAngles
from metrology.charts import agg_figure, save_png

MARGINS = (0.8, 0.9, 0.6, 0.5)  # left, right, bottom, top [in]


def write_cutter_charts(out: Path, result: dict[str, Any]) -> list[Path]:
    """working_angles.png and tool_load.png in ``out`` from the cut's ``_working_angle_maps`` and ``tool_load``
    (either may be missing: its chart is then not drawn)."""
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    maps = result.get("_working_angle_maps")
    if maps:
        paths.append(_angle_maps(out / "working_angles.png", maps))
    load = result.get("tool_load")
    if load:
        paths.append(_tool_load(out / "tool_load.png", load))
    return paths


def _angle_maps(path: Path, maps: list[PassageAngles]) -> Path:
    """Rows: passes; columns: rake [deg], clearance [deg], chip thickness [um], on (edge position, generating)."""
    rows = len(maps)
    fig, grid = agg_figure((13.0, 2.6 * rows + 1.0), (rows, 3), MARGINS, gaps=(0.9, 0.6), dpi=90)
    panels = (
        ("working normal rake [deg]", "rake", "RdBu_r", 1.0),
        ("working normal clearance [deg]", "clearance", "RdBu_r", 1.0),
        ("uncut chip thickness [um]", "thickness", "viridis", 1e3),
    )
    for r, pa in enumerate(maps):
        for c, (title, name, cmap, scale) in enumerate(panels):
            ax = grid[r, c]
            value = getattr(pa, name) * (scale if name == "thickness" else 180.0 / np.pi)
            shown = np.where(pa.cutting, value, np.nan)
            x, y = np.degrees(pa.generating), pa.position
            if name == "thickness":  # probed on a coarser grid (cutting.skiving.working_angles.THICKNESS_STRIDE)
                a, b = THICKNESS_STRIDE
                shown, x, y = shown[::a, ::b], x[::a], y[::b]
            shown = shown.T  # edge position up, generating position across
            finite = shown[np.isfinite(shown)]
            if name == "thickness":
                lo, hi = 0.0, float(finite.max()) if finite.size else 1.0
            else:
                lim = float(np.abs(finite).max()) if finite.size else 1.0
                lo, hi = -lim, lim  # diverging about zero: negative rake or clearance in red
            image = ax.pcolormesh(x, y, shown, cmap=cmap, vmin=lo, vmax=hi, shading="nearest")
            fig.colorbar(image, ax=ax, fraction=0.05, pad=0.02)
            ax.set_title(f"pass {pa.pass_index + 1}: {title}", fontsize=9)
            ax.set_xlabel("generating position (cutter turn from the mesh) [deg]", fontsize=8)
            ax.set_ylabel("edge position (right flank, tip, left flank) [mm]", fontsize=8)
            ax.tick_params(labelsize=7)
    return save_png(fig, path)


def _tool_load(path: Path, passes: list[dict]) -> Path:
    """Per pass: each tooth's largest chip [um] (bars) and chip energy [J] (line on the right axis)."""
    rows = len(passes)
    fig, grid = agg_figure((10.0, 2.4 * rows + 1.0), (rows, 1), MARGINS, gaps=(0.0, 0.6), dpi=90)
    for r, p in enumerate(passes):
        ax = grid[r, 0]
        teeth = [t["tooth"] for t in p["teeth"]]
        ax.bar(teeth, [t["chip_thickness_max_mm"] * 1e3 for t in p["teeth"]], color="#7a9cc6")
        ax.set_ylabel("largest chip [um]", fontsize=8)
        twin = ax.twinx()
        twin.plot(teeth, [t["chip_energy_J"] for t in p["teeth"]], "o-", color="#c0392b", markersize=3)
        twin.set_ylabel("chip energy [J]", fontsize=8, color="#c0392b")
        spread = p.get("chip_thickness_spread")
        ax.set_title(
            f"pass {p['pass']}: tool load per cutter tooth (most loaded: tooth {p['most_loaded_tooth']}"
            + (f", largest chip spread {spread:.3f})" if spread else ")"),
            fontsize=9,
        )
        ax.set_xlabel("cutter tooth", fontsize=8)
        ax.set_xticks(teeth)
        for a in (ax, twin):
            a.tick_params(labelsize=7)
    return save_png(fig, path)
