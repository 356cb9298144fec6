"""Measuring-machine charts: profile and helix traces with the tolerance band, pitch bars with the
cumulative curve. Written as PNG with matplotlib's Agg backend (no display needed).

Every run draws them, so they are drawn for speed (a quarter of the time of plain pyplot code or less):

- a bare :class:`~matplotlib.figure.Figure` on an Agg canvas (no pyplot state, nothing to close) with a fixed
  layout in inches (``tight_layout`` draws the whole figure once more to measure it) and titles at a fixed height
  (an automatic one measures the tick labels below it);
- light ticks (:func:`light_ticks`): matplotlib makes each tick of five artists, about a millisecond apiece;
- the trace charts' tooth panels as columns of one axes, framed and ticked here (an axes each cost its ticks);
- many bars or traces as one collection;
- the PNG written here (:func:`write_png`: a fifth of the time of PIL's adaptive filters, files of their size);
- the garbage collector paused while a figure lives (:func:`paused_gc`)."""

from __future__ import annotations

import gc
import math
import struct
import zlib
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import matplotlib as mpl
import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.figure import Figure
from matplotlib.font_manager import FontProperties
from matplotlib.lines import TICKDOWN, TICKLEFT, TICKRIGHT, Line2D
from matplotlib.ticker import MaxNLocator, NullLocator
from matplotlib.transforms import ScaledTranslation, Transform

from metrology.modification import chart_teeth

mpl.use("Agg")  # for pyplot users importing this module (as before); the charts here draw on their own Agg canvas

SIDES = ("left", "right")

#: matplotlib's defaults [pt]: major ticks' length, line width and gap to the label; label and title pads
TICK_SIZE, TICK_WIDTH, TICK_PAD, LABEL_PAD, TITLE_PAD = 3.5, 0.8, 3.5, 4.0, 6.0
#: the trace charts' layout [in]: margins (left, right, bottom, top) and the gap between the tooth panels
TRACE_MARGINS = (0.68, 0.18, 0.51, 0.64)
TRACE_GAP = 0.25


@contextmanager
def paused_gc() -> Iterator[None]:
    """The cyclic garbage collector paused while a chart is drawn (use as decorator: the figure must be garbage
    at the exit), its figure (some 10^4 objects in reference cycles) freed by one collection of the young
    generation after: while the figure lives the collector would walk it again and again, promote it, and in the
    end walk the whole heap of the run."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()
            gc.collect(0)


def agg_figure(
    size: tuple[float, float],
    grid: tuple[int, int],
    margins: tuple[float, float, float, float],
    gaps: tuple[float, float] = (0.0, 0.0),
    dpi: float = 100.0,
    **subplots: Any,
) -> tuple[Figure, np.ndarray]:
    """A figure of ``size`` (width, height) [in] at ``dpi`` on an Agg canvas, with a ``grid`` (rows, columns) of
    axes laid out with fixed ``margins`` (left, right, bottom, top) and ``gaps`` (between columns, between rows)
    [in]: what ``tight_layout`` finds, without drawing the figure to find it. ``subplots``: passed on (sharex, ...).
    Returns the figure and its axes as a 2-D array."""
    (width, height), (rows, cols) = size, grid
    left, right, bottom, top = margins
    wgap, hgap = gaps
    cell_w = (width - left - right - (cols - 1) * wgap) / cols
    cell_h = (height - bottom - top - (rows - 1) * hgap) / rows
    fig = Figure(figsize=size, dpi=dpi)
    FigureCanvasAgg(fig)
    layout = {
        "left": left / width,
        "right": 1 - right / width,
        "bottom": bottom / height,
        "top": 1 - top / height,
        "wspace": wgap / cell_w,
        "hspace": hgap / cell_h,
    }
    return fig, fig.subplots(rows, cols, squeeze=False, gridspec_kw=layout, **subplots)


def save_png(fig: Figure, path: Path) -> Path:
    """Draw ``fig`` at its dpi and write it to ``path`` as an RGB PNG (the figure is opaque: no alpha to store)."""
    fig.canvas.draw()
    rgba = np.asarray(fig.canvas.buffer_rgba())
    # each pixel's RGB as one 3-byte item: numpy copies those 3x faster than rgba[..., :3]
    rgb = np.ascontiguousarray(rgba.view([("rgb", "V3"), ("alpha", "u1")])["rgb"]).view(np.uint8)
    write_png(path, rgb.reshape(rgba.shape[0], rgba.shape[1], 3), fig.dpi)
    return Path(path)


def write_png(path: Path, rgb: np.ndarray, dpi: float) -> None:
    """An 8-bit RGB image (rows, columns, 3) as PNG, every row filtered "Up" (less the row above: a chart's rows
    repeat) and deflated at level 1: a fifth of the time of PIL's adaptive filters for files of about their size."""
    h, w, _ = rgb.shape
    rows = np.ascontiguousarray(rgb, dtype=np.uint8).reshape(h, w * 3)
    up = np.empty((h, w * 3 + 1), np.uint8)
    up[:, 0] = 2  # the filter type of each row
    up[0, 1:] = rows[0]
    np.subtract(rows[1:], rows[:-1], out=up[1:, 1:])  # modulo 256

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    per_metre = round(dpi / 0.0254)
    Path(path).write_bytes(
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))  # 8 bits, truecolour, no interlace
        + chunk(b"pHYs", struct.pack(">IIB", per_metre, per_metre, 1))
        + chunk(b"IDAT", zlib.compress(up.tobytes(), 1))
        + chunk(b"IEND", b"")
    )


def light_ticks(*axes: Axes) -> None:
    """Draw the ticks of ``axes`` as matplotlib would, but lightly: matplotlib makes every tick of five artists,
    about a millisecond each (these charts have a hundred), :func:`draw_ticks` an axis' marks as one line of
    markers and its labels as texts. The ticks are those the axis' locator puts in view, labelled by its
    formatter; then its own are switched off. Call when the data are in: the view limits freeze. An axis with an
    offset or a scale (``1e3``) or mathtext labels keeps matplotlib's ticks."""
    renderer = axes[0].figure.canvas.get_renderer()
    ticks = []
    for ax in axes:
        ax.set_xlim(ax.get_xlim())
        ax.set_ylim(ax.get_ylim())
        for axis in (ax.xaxis, ax.yaxis):
            lo, hi = sorted(axis.get_view_interval())
            slack = 1e-9 * (hi - lo)
            locs = [v for v in axis.get_majorticklocs() if lo - slack <= v <= hi + slack]
            formatter = axis.get_major_formatter()
            texts = formatter.format_ticks(locs)
            if axis.get_visible() and locs and not formatter.get_offset() and "$" not in "".join(texts):
                ticks.append((ax, axis, locs, texts))
    for ax, axis, locs, texts in ticks:  # after all are read: shared axes share their locator
        axis.set_major_locator(NullLocator())
        draw_ticks(ax, axis.axis_name, locs, texts, renderer)


def draw_ticks(ax: Axes, name: str, locs: list[float], texts: list[str], renderer: Any) -> None:
    """Ticks at ``locs`` on the x (bottom) or y (left or right, as its ticks are set) axis ``name`` of ``ax``: the
    marks, the ``texts`` as labels (unless the axis' labels are off, as on an inner shared axis) and the axis label
    placed past them as matplotlib places it. Size, width and pad of the ticks from the rcParams."""
    fig = ax.figure
    axis = ax.xaxis if name == "x" else ax.yaxis
    params = axis.get_tick_params()
    right = name == "y" and params.get("right", False) and not params.get("left", True)
    size, width, pad = (mpl.rcParams[f"{name}tick.major.{key}"] for key in ("size", "width", "pad"))
    out = 1 if right else -1  # away from the axes, for a y axis
    if name == "x":
        along, marker, xy = ax.get_xaxis_transform(), TICKDOWN, (locs, [0] * len(locs))
        shift, align = (0, -(size + pad)), {"ha": "center", "va": "top"}
    else:
        along, xy = ax.get_yaxis_transform(), ([int(right)] * len(locs), locs)
        marker = TICKRIGHT if right else TICKLEFT
        shift, align = (out * (size + pad), 0), {"ha": "left" if right else "right", "va": "center_baseline"}
    ax.add_artist(Line2D(*xy, transform=along, ls="none", marker=marker, ms=size, mew=width, color="k", clip_on=False))
    if not params.get("labelbottom" if name == "x" else "labelright" if right else "labelleft", True):
        return
    font = FontProperties(size=params.get("labelsize", mpl.rcParams[f"{name}tick.labelsize"]))
    label_at = offset(fig, along, *shift)
    for text, x, y in zip(texts, *xy, strict=True):
        ax.text(x, y, text, transform=label_at, fontproperties=font, **align)
    # the axis label past the tick labels: their widths, or their height as a line of text's ("lp": the descent)
    extents = [renderer.get_text_width_height_descent(t, font, ismath=False) for t in [*texts, "lp"]]
    across = max(w for w, _, _ in extents) if name == "y" else max(h - d for _, h, d in extents) + extents[-1][2]
    reach = size + pad + axis.labelpad + across * 72 / fig.dpi
    if name == "x":
        axis.set_label_coords(0.5, 0, offset(fig, ax.transAxes, 0, -reach))
    else:
        axis.set_label_coords(int(right), 0.5, offset(fig, ax.transAxes, out * reach, 0))


def offset(fig: Figure, transform: Transform, dx: float, dy: float) -> Transform:
    """``transform`` shifted by (dx, dy) points on ``fig``."""
    return transform + ScaledTranslation(dx / 72, dy / 72, fig.dpi_scale_trans)


def tick_texts(values: np.ndarray) -> list[str]:
    """Tick labels as matplotlib's ScalarFormatter writes them: as many decimals as the finest needs, a true minus."""
    decimals = max((len(f"{v:g}".partition(".")[2]) for v in values), default=0)
    return [f"{v + 0.0:.{decimals}f}".replace("-", "\N{MINUS SIGN}") for v in values]


@paused_gc()
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
    """Traces drawn like a gear chart: deviation across, the flank coordinate up; one panel per flank and tooth,
    each with its own symmetric deviation scale (at least +-5 um and 3/4 of the band), the tolerance band about the
    trace's mean, the straight line fitted to it and the zero line.

    The panels are columns of one axes, framed and ticked here (as an axes each, their ticks were most of the
    chart's time): panel k spans x = k * pitch -+ 1, a deviation e [um] drawn at k * pitch + e / lim. The axes'
    own y axis ticks and labels the first panel."""
    cols = 2 * len(numbers)
    width, height = 2.0 * cols, 6.0
    left, right, _, _ = TRACE_MARGINS
    panel_in = (width - left - right - (cols - 1) * TRACE_GAP) / cols
    pitch = 2.0 + 2.0 * TRACE_GAP / panel_in  # panel centre to panel centre in x (a panel is 2 wide)
    nbins = max(1, min(9, int(panel_in * 72 / (7 * 3))))  # what matplotlib's AutoLocator takes for the width
    panels = [(side, n, traces[side][n - 1]) for side in SIDES for n in numbers]
    finite = np.isfinite(np.array([e for *_, e in panels]))
    ys = axis[finite.any(axis=0)] if finite.any() else axis
    margin = 0.05 * float(ys.max() - ys.min()) or 0.5  # matplotlib's autoscale margin
    y0, y1 = float(ys.min()) - margin, float(ys.max()) + margin

    fig, grid = agg_figure((width, height), (1, 1), TRACE_MARGINS, dpi=110)
    ax = grid[0, 0]
    ax.set_xlim(-1.0, (cols - 1) * pitch + 1.0)
    ax.set_ylim(y0, y1)
    ax.spines[:].set_visible(False)
    ax.tick_params(labelsize=7)
    ax.xaxis.set_major_locator(NullLocator())  # each panel has its own ticks, below
    ax.set_ylabel(x_label)
    strip = ax.get_xaxis_transform()  # x in data, y across the axes (0 bottom, 1 top)
    title_at = offset(fig, strip, 0, TITLE_PAD)
    tick_label_at = offset(fig, strip, 0, -(TICK_SIZE + TICK_PAD))
    x_label_at = offset(fig, strip, 0, -(TICK_SIZE + TICK_PAD + 7 * 1.2 + LABEL_PAD))  # below the tick labels
    lines, fits, bands, frames, xticks = [], [], [], [], []
    for k, (side, n, e) in enumerate(panels):
        c = k * pitch
        ok = np.isfinite(e)
        lim = max(5.0, (band_um or 0) * 0.75, np.nanmax(np.abs(e)) * 1.3 if ok.any() else 0)
        lines.append(np.column_stack([c + e[ok] / lim, axis[ok]]))
        if ok.sum() > 2:
            fit = np.polyval(np.polyfit(axis[ok], e[ok], 1), axis[ok])
            fit[np.abs(fit) > lim] = np.nan  # outside the panel
            fits.append(np.column_stack([c + fit / lim, axis[ok]]))
            if band_um is not None:
                mid = float(np.mean(e[ok]))
                lo, hi = c + max(-1.0, (mid - band_um / 2) / lim), c + min(1.0, (mid + band_um / 2) / lim)
                bands.append([(lo, 0), (hi, 0), (hi, 1), (lo, 1)])
        frames.append([(c - 1, 0), (c + 1, 0), (c + 1, 1), (c - 1, 1)])
        ax.text(c, 1, f"{side} {n}", transform=title_at, ha="center", va="baseline", fontsize=9)
        ax.text(c, 0, "um", transform=x_label_at, ha="center", va="top", fontsize=8)
        ticks = MaxNLocator(nbins, steps=[1, 2, 2.5, 5, 10]).tick_values(-lim, lim)
        ticks = ticks[np.abs(ticks) <= lim * (1 + 1e-9)]
        for t, text in zip(ticks, tick_texts(ticks), strict=True):
            ax.text(c + t / lim, 0, text, transform=tick_label_at, ha="center", va="top", fontsize=7)
        xticks += list(c + ticks / lim)
    ax.add_collection(PolyCollection(bands, transform=strip, color="tab:green", alpha=0.12), autolim=False)  # axvspan
    frame = {"facecolor": "none", "edgecolor": "k", "lw": TICK_WIDTH, "zorder": 2.5, "clip_on": False}  # spines
    ax.add_collection(PolyCollection(frames, transform=strip, **frame), autolim=False)
    ax.add_collection(LineCollection(lines, color="tab:blue", lw=1.2))
    ax.add_collection(LineCollection(fits, color="tab:orange", lw=0.8, linestyles="--"))
    centres = pitch * np.arange(cols)
    ax.vlines(centres, 0, 1, transform=strip, color="k", lw=0.5)
    marks = {"ls": "none", "color": "k", "ms": TICK_SIZE, "mew": TICK_WIDTH, "clip_on": False}
    ax.plot(xticks, np.zeros(len(xticks)), transform=strip, marker=TICKDOWN, **marks)
    # y tick marks on the other panels' left edges (unlabelled, as on shared axes); the axes' ticks the first's
    yticks = [t for t in ax.get_yticks() if y0 <= t <= y1]
    ax.plot(np.repeat(centres[1:] - 1.0, len(yticks)), np.tile(yticks, cols - 1), marker=TICKLEFT, **marks)
    light_ticks(ax)
    fig.suptitle(f"{title}  (band: {band_label})", fontsize=10)
    save_png(fig, path)


@paused_gc()
def pitch_chart(path: Path, result: dict[str, Any]) -> None:
    """Single pitch deviations as bars and the cumulative pitch deviation as a curve, both flanks."""
    tol = result["iso1328"].get("tolerances") or {}
    fig, grid = agg_figure((10.0, 6.0), (2, 1), (0.8, 0.15, 0.59, 0.34), (0.0, 0.39), dpi=110, sharex=True)
    axes = grid[:, 0]
    for ax, side in zip(axes, SIDES, strict=True):
        p = result["pitch"][side]
        f_pi = np.asarray(p["f_pi"], dtype=float)
        n = np.arange(1, len(f_pi) + 1)
        ax.plot(n, p["F_pi"], color="tab:red", marker=".", label="F_pi")
        bars = [
            [(x - 0.4, 0), (x - 0.4, h), (x + 0.4, h), (x + 0.4, 0)]
            for x, h in zip(n, f_pi, strict=True)
            if np.isfinite(h)
        ]
        ax.add_collection(PolyCollection(bars, color="tab:blue", alpha=0.7, lw=0, label="f_pi"))  # ax.bar's look
        if tol.get("f_p"):
            for v in (tol["f_p"], -tol["f_p"]):
                ax.axhline(v, color="tab:blue", ls=":", lw=0.8)
        ax.axhline(0, color="k", lw=0.5)
        ax.set_ylabel(f"{side} [um]")
        ax.set_title(
            f"{side}: f_p = {p['f_p']:.2f} um, F_p = {p['F_p']:.2f} um, F_pk(k={p['k']}) = {p['F_pk']:.2f} um",
            fontsize=9,
            y=1.0,  # fixed: nothing is above the axes
        )
        ax.legend(fontsize=8, loc="upper right")
    axes[-1].set_xlabel("tooth")
    light_ticks(*axes)
    save_png(fig, path)


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


#: the one colour map of flank deviations, in the topography chart and on the recording's 3D gear: excess material
#: (> 0, ISO 1328-1's sign) red, missing material blue, zero white-grey; symmetric about zero
DEVIATION_CMAP = "RdBu_r"


def deviation_limit(topo: dict[str, Any], key: str = "deviation_um") -> float:
    """The colour scale's limit [um] of a topography: its largest |deviation| over both flanks (1 without data)."""
    grids = [np.asarray(topo[s][key], dtype=float) for s in SIDES]
    return max(float(np.nanmax(np.abs(g))) if np.isfinite(g).any() else 0.0 for g in grids) or 1.0


def deviation_rgba(deviation_um: np.ndarray, limit_um: float) -> np.ndarray:
    """RGBA (uint8, n x 4) of deviations [um] on :data:`DEVIATION_CMAP` over +-``limit_um`` (clipped), as the
    topography chart draws them; NaN: grey (off the flanks)."""
    d = np.asarray(deviation_um, dtype=float)
    f = (np.clip(np.nan_to_num(d) / limit_um, -1.0, 1.0) + 1.0) / 2.0
    out = np.round(mpl.colormaps[DEVIATION_CMAP](f) * 255).astype(np.uint8)
    out[np.isnan(d)] = (128, 128, 128, 255)
    return out


@paused_gc()
def topography_chart(path: Path, topo: dict[str, Any]) -> Path:
    """The flank topography as a colour map per flank (deviation over roll length x face, mean of the scanned
    teeth, um); with a design, a second row shows the deviation from it."""
    L, z = np.asarray(topo["L_mm"]), np.asarray(topo["z_mm"])
    designed = any(np.any(np.asarray(topo[s]["design_um"], dtype=float) != 0) for s in SIDES)
    rows = [("deviation_um", "measured")] + ([("against_design_um", "against the design")] if designed else [])
    # fixed places [in], as tight_layout put them: a colour bar beside each map, room for its labels after it
    width, height, bar_gap, bar_w = 10.0, 3.6 * len(rows), 0.21, 0.12
    beside = bar_gap + bar_w
    margins = (0.54, beside + 0.79, 0.59, 0.68)
    fig, axes = agg_figure((width, height), (len(rows), 2), margins, (beside + 1.18, 0.8), dpi=90)
    for i, (key, what) in enumerate(rows):
        grids = [np.asarray(topo[s][key], dtype=float) for s in SIDES]
        lim = deviation_limit(topo, key)
        for j, (side, grid) in enumerate(zip(SIDES, grids, strict=True)):
            ax = axes[i][j]
            mesh = ax.pcolormesh(z, L, grid, cmap=DEVIATION_CMAP, vmin=-lim, vmax=lim, shading="nearest")
            ax.set_title(f"{side} flank, {what}", y=1.0)
            ax.set_xlabel("z [mm]")
            ax.set_ylabel("roll length [mm]")
            box = ax.get_position()
            cax = fig.add_axes((box.x1 + bar_gap / width, box.y0, bar_w / width, box.height))
            fig.colorbar(mesh, cax=cax, label="um (excess material > 0)")
            light_ticks(ax, cax)
    teeth = ", ".join(str(t) for t in topo["teeth"])
    fig.suptitle(f"Flank topography, mean of teeth {teeth}")
    return save_png(fig, path)
