"""The charts: every panel drawn at the size it always had, matplotlib's ticks and labels reproduced by the light
ticks, the PNG writer, and edge cases (no ISO class, NaN traces, a design, no forces)."""

from __future__ import annotations

import gc
import types
from pathlib import Path

import numpy as np
import pytest
from matplotlib.ticker import ScalarFormatter
from PIL import Image

from metrology.charts import (
    agg_figure,
    light_ticks,
    paused_gc,
    tick_texts,
    write_charts,
    write_png,
)
from virtual_machine.output.report import run_chart
from virtual_machine.runtime.machine_run import SEGMENTS


def measurement(z: int = 20, classed: bool = True, designed: bool = False) -> dict:
    """A measurement document as write_charts reads it: traces [mm], pitch [um], topography [um]."""
    rng = np.random.default_rng(3)
    L, zz = np.linspace(0.5, 5.5, 240), np.linspace(-1.8, 1.8, 200)
    prof = {s: 2e-3 * np.sin(L * (3 + rng.random((z, 1)))) + 1e-3 * (L - 3) for s in ("left", "right")}
    helix = {s: 1.5e-3 * np.sin(zz * (9 + rng.random((z, 1)))) for s in ("left", "right")}
    prof["left"][0, :40] = np.nan  # a trace with a gap
    helix["right"][:] = np.nan  # a flank not measured
    f_pi = {s: rng.normal(0, 0.5, z) for s in ("left", "right")}
    pitch = {
        s: {"f_pi": list(f), "F_pi": list(np.cumsum(f)), "f_p": 0.5, "F_p": 2.0, "F_pk": 1.2, "k": 3}
        for s, f in f_pi.items()
    }
    grid = rng.normal(0, 2, (15, 11))
    topo = {"L_mm": list(np.linspace(0.5, 5.5, 15)), "z_mm": list(np.linspace(-1.8, 1.8, 11)), "teeth": [1, 6]}
    for s in ("left", "right"):
        design = np.full_like(grid, 1.5 if designed else 0.0)
        topo[s] = {"deviation_um": grid.tolist(), "design_um": design.tolist(), "against_design_um": (grid - design)}
    tolerances = {"f_p": 11.0, "F_alpha": 14.0, "F_beta": 14.0} if classed else None
    return {
        "_traces": {"order": list(range(z)), "profile": prof, "helix": helix, "L_mm": L, "z_mm": zz},
        "iso1328": {"tolerances": tolerances, "tolerances_class": 7 if classed else None},
        "pitch": pitch,
        "topography": topo,
    }


def size(path: Path) -> tuple[int, int]:
    with Image.open(path) as im:
        return im.size


@pytest.mark.parametrize(("z", "classed", "designed"), [(20, True, False), (3, False, True)])
def test_write_charts(tmp_path, z, classed, designed):
    paths = write_charts(tmp_path, measurement(z, classed, designed))
    assert [p.name for p in paths] == ["profile.png", "helix.png", "pitch.png", "topography.png"]
    columns = 2 * (4 if z >= 4 else z)  # chart_teeth: 4 teeth, or every tooth of a smaller gear
    assert size(paths[0]) == size(paths[1]) == (round(2.0 * columns * 110), 660)
    assert size(paths[2]) == (1100, 660)
    assert size(paths[3]) == (900, 648 if designed else 324)
    with Image.open(paths[0]) as im:
        rgb = np.asarray(im.convert("RGB")).astype(int)
    blue = (np.abs(rgb - [31, 119, 180]).sum(axis=2) < 60).sum()  # tab:blue traces
    green = (np.abs(rgb - [230, 244, 230]).sum(axis=2) < 6).sum()  # the tolerance band: tab:green, alpha 0.12
    assert blue > 1000
    assert (green > 10000) == classed


def test_run_chart(tmp_path):
    t = np.linspace(0, 3, 3000)
    segment = np.where(t < 1, SEGMENTS.index("runup"), SEGMENTS.index("feed"))
    record = types.SimpleNamespace(t=t, segment=segment, sync_um=np.sin(9 * t), cutting=(t > 1.2) & (t < 2.5))
    loads = np.column_stack([t, 800 * np.sin(t) ** 2, 0 * t, 0 * t, np.cos(40 * t)])
    chips = [(float(x), 0.4 * float(np.sin(x)) ** 2) for x in np.linspace(1.2, 2.5, 300)]
    assert size(run_chart(tmp_path / "run.png", record, loads, chips)) == (1000, 800)
    assert size(run_chart(tmp_path / "quiet.png", record, np.zeros((0, 5)), [])) == (1000, 800)


def test_write_png_round_trip(tmp_path):
    rgb = np.random.default_rng(0).integers(0, 256, (37, 53, 3), dtype=np.uint8)
    write_png(tmp_path / "x.png", rgb, 110)
    with Image.open(tmp_path / "x.png") as im:
        assert im.mode == "RGB" and np.array_equal(np.asarray(im), rgb)
        assert im.info["dpi"] == pytest.approx((110, 110), abs=0.01)


def test_light_ticks_as_matplotlibs():
    """The light ticks sit where matplotlib's would, say what they would, and the axis labels stay clear of them."""

    def figure():
        fig, grid = agg_figure((6.0, 4.0), (2, 1), (0.9, 0.9, 0.6, 0.2), (0.0, 0.3), sharex=True)
        grid[0, 0].plot([0.2, 9.7], [-13.0, 1021.0])
        grid[1, 0].plot([0.2, 9.7], [0.013, -0.002])
        twin = grid[1, 0].twinx()
        twin.plot([0.2, 9.7], [2.5, -7.5])
        for ax, label in zip((*grid[:, 0], twin), "abc", strict=True):
            ax.set_ylabel(label)
        grid[1, 0].set_xlabel("x")
        return fig, [*grid[:, 0], twin]

    def in_view(axis):
        lo, hi = sorted(axis.get_view_interval())
        ticks = axis.get_major_ticks()
        return {
            (round(t.get_loc(), 9), t.label1.get_text() or t.label2.get_text())
            for t in ticks
            if lo <= t.get_loc() <= hi
        }

    fig, axes = figure()
    fig.canvas.draw()
    expected = [(ax.get_xlim(), ax.get_ylim(), in_view(ax.xaxis), in_view(ax.yaxis)) for ax in axes]
    fig, axes = figure()
    light_ticks(*axes)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    for k, (ax, (xlim, ylim, xticks, yticks)) in enumerate(zip(axes, expected, strict=True)):
        assert (ax.get_xlim(), ax.get_ylim()) == (xlim, ylim)
        x_texts = {(round(t.get_position()[0], 9), t.get_text()) for t in ax.texts if t.get_ha() == "center"}
        y_texts = {(round(t.get_position()[1], 9), t.get_text()) for t in ax.texts if t.get_ha() != "center"}
        assert y_texts == yticks
        assert x_texts == (xticks if k == 1 else set())  # the x tick labels on the lower of the shared axes only
        for label in (ax.xaxis.label, ax.yaxis.label):
            box = label.get_window_extent(renderer)
            assert not any(box.overlaps(text.get_window_extent(renderer)) for text in ax.texts)


def test_light_ticks_leave_an_offset_axis_to_matplotlib():
    _, grid = agg_figure((4.0, 3.0), (1, 1), (0.8, 0.2, 0.5, 0.2))
    ax = grid[0, 0]
    ax.plot([0, 1], [1000.0001, 1000.0002])  # an offset: "+1e3"
    light_ticks(ax)
    assert isinstance(ax.yaxis.get_major_formatter(), ScalarFormatter)
    assert len(ax.yaxis.get_majorticklocs()) > 0  # matplotlib's ticks, with their offset text
    assert len(ax.xaxis.get_majorticklocs()) == 0  # the x axis' ticks are light ones


def test_tick_texts_as_scalar_formatter():
    assert tick_texts(np.array([-10.0, -5.0, 0.0, 5.0, 10.0])) == ["\u221210", "\u22125", "0", "5", "10"]
    assert tick_texts(np.array([-5.0, -2.5, -0.0, 2.5])) == ["\u22125.0", "\u22122.5", "0.0", "2.5"]


def test_paused_gc_restores_the_collector():
    with paused_gc():
        assert not gc.isenabled()
    assert gc.isenabled()
    gc.disable()
    try:
        with paused_gc():
            pass
        assert not gc.isenabled()  # the caller's choice kept
    finally:
        gc.enable()
