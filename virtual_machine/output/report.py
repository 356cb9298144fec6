"""report.html: the one page a gear engineer reads after a run, and the run's time chart.

Self-contained (the charts are embedded as PNG data), no script, no external style: it opens anywhere and can
be archived with the gear.
"""

from __future__ import annotations

import base64
import html
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from virtual_machine.output.formatting import class_table
from virtual_machine.runtime.machine_run import SEGMENTS

STYLE = """
body { font-family: sans-serif; max-width: 1100px; margin: 2em auto; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.15em; border-bottom: 1px solid #ccc; padding-bottom: 0.2em; }
table { border-collapse: collapse; margin: 0.5em 0 1em; } td, th { padding: 0.2em 0.8em; text-align: right; }
th { background: #eee; } td:first-child, th:first-child { text-align: left; }
tr.fail td { background: #fde2e2; } .verdict { font-size: 1.2em; font-weight: bold; }
pre { background: #f6f6f6; padding: 0.8em; font-size: 0.8em; overflow-x: auto; }
img { max-width: 100%; border: 1px solid #ddd; margin: 0.3em 0; }
"""


def run_chart(path: Path, record, load_rows: np.ndarray, chips: list[tuple[float, float]]) -> Path:
    """Synchronisation error, cutting force and torque about the work axis, and chip volume over machine time.

    Drawn as :mod:`metrology.charts` draws (imported here: matplotlib only when a chart is drawn): a bare Agg
    figure with a fixed layout [in], light ticks, a fast PNG, the garbage collector paused."""
    from metrology.charts import paused_gc

    with paused_gc():
        return _run_chart(path, record, load_rows, chips)


def _run_chart(path: Path, record, load_rows: np.ndarray, chips: list[tuple[float, float]]) -> Path:
    """:func:`run_chart`'s figure (a function of its own: it is garbage when the garbage collector resumes)."""
    from metrology.charts import agg_figure, light_ticks, save_png

    fig, grid = agg_figure((10.0, 8.0), (3, 1), (1.02, 0.79, 0.585, 0.15), (0.0, 0.2), dpi=100, sharex=True)
    ax = grid[:, 0]
    feed = record.segment == SEGMENTS.index("feed")  # the run-up's transient would hide the micrometres
    ax[0].plot(record.t, np.where(feed, record.sync_um, np.nan), lw=0.5, color="tab:blue", label="feed stroke")
    ax[0].plot(record.t, np.where(record.cutting, record.sync_um, np.nan), lw=0.7, color="tab:red", label="cutting")
    ax[0].set_ylabel("sync error [um]\n(arc on d)")
    ax[0].legend(loc="upper right")
    twins = []
    if len(load_rows):
        t, f = load_rows[:, 0], np.linalg.norm(load_rows[:, 1:4], axis=1)
        ax[1].plot(t, f, lw=0.5, color="tab:orange", label="|F| on the workpiece [N]")
        twin = ax[1].twinx()
        twins.append(twin)
        twin.plot(t, load_rows[:, 4], lw=0.5, color="tab:green", label="torque about the work axis [N m]")
        twin.set_ylabel("torque [N m]")
        twin.legend(loc="upper left")
        ax[1].legend(loc="upper right")
    ax[1].set_ylabel("cutting force [N]")  # a run without forces leaves this panel empty: no legend
    if chips:
        tc, vc = np.array(chips).T
        ax[2].plot(tc, vc, ".", ms=2, color="tab:purple")
    ax[2].set_ylabel("chip volume [mm^3]\nper engagement")
    ax[2].set_xlabel("machine time [s]")
    light_ticks(*ax, *twins)
    return save_png(fig, path)


def thermal_chart(path: Path, drift, strokes: list[tuple[float, float]], end: float) -> Path:
    """The machine's thermal drift over the job (cutting/skiving/thermal_drift.py): x, y, z [um] and the tilt [urad]
    against machine time, the feed strokes shaded."""
    from metrology.charts import agg_figure, light_ticks, paused_gc, save_png

    with paused_gc():
        t = np.linspace(0.0, end, 400)
        d = drift.offsets(t)
        fig, grid = agg_figure((10.0, 4.5), (2, 1), (1.02, 0.79, 0.585, 0.15), (0.0, 0.2), dpi=100, sharex=True)
        ax = grid[:, 0]
        for k, (name, colour) in enumerate((("x (centre distance)", "tab:red"), ("y", "tab:green"), ("z", "tab:blue"))):
            ax[0].plot(t, d[:, k] * 1e3, lw=1.0, color=colour, label=name)
        ax[1].plot(t, d[:, 3] * 1e6, lw=1.0, color="tab:purple", label="tilt about x (shaft angle)")
        for a in ax:
            for t0, t1 in strokes:
                a.axvspan(t0, t1, color="0.9", lw=0)
            a.legend(loc="upper left")
        ax[0].set_ylabel("drift [um]")
        ax[1].set_ylabel("tilt [urad]")
        ax[1].set_xlabel("machine time [s] (feed strokes shaded)")
        light_ticks(*ax)
        return save_png(fig, path)


def html_table(head: list[str], rows: list[list[Any]], fails: set[int] | None = None) -> str:
    """An HTML table, every cell escaped (None as "-", floats to 2 decimals); rows in ``fails`` shaded."""
    out = ["<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + "</tr>"]
    for k, row in enumerate(rows):
        cls = ' class="fail"' if fails and k in fails else ""
        out.append(f"<tr{cls}>" + "".join(f"<td>{html.escape(_fmt(v))}</td>" for v in row) + "</tr>")
    return "\n".join(out) + "</table>"


def _fmt(v: Any) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.2f}" if abs(v) < 1e4 else f"{v:.4g}"
    return str(v)


def image_tag(png: Path | bytes, alt: str | None = None) -> str:
    """A PNG (a file, or its bytes) embedded in the page; ``alt`` defaults to the file's stem."""
    data = png if isinstance(png, bytes) else Path(png).read_bytes()
    text = alt if alt is not None else Path(png).stem
    return f'<img alt="{html.escape(text)}" src="data:image/png;base64,{base64.b64encode(data).decode()}">'


def write_page(path: Path, title: str, body: Sequence[str]) -> Path:
    """One self-contained HTML page in the reports' style: the ``body`` fragments under ``title``."""
    page = (
        f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>'
        f"<style>{STYLE}</style></head><body>\n" + "\n".join(body) + "\n</body></html>\n"
    )
    Path(path).write_text(page)
    return Path(path)


def write_report(
    path: Path,
    title: str,
    doc: dict[str, Any],
    job_text: str,
    sheet_text: str,
    charts: list[Path],
    run_png: Path,
    thermal_png: Path | None = None,
) -> Path:
    """Write the page: verdict, job, class table, charts, run facts, setting sheet."""
    run = doc["run"]
    iso = doc["iso1328"]
    cls = (iso.get("class") or {}).get("overall")
    tol_class = iso.get("tolerances_class")
    rows, fails = [], set()
    for k, (key, left, right, tol, c) in enumerate(class_table(doc)):
        rows.append([key, left, right, tol, c])
        worst = max(abs(left), abs(right or 0.0))
        if tol is not None and worst > tol:
            fails.add(k)
    verdict = (
        f"ISO 1328-1:2013 class of the gear: {cls}" if cls is not None else f"ISO 1328-1: {iso.get('error', 'n/a')}"
    )
    th = doc["thickness"]
    span = th["span"]
    thickness = [
        ["over balls M_dK [mm]", th["over_balls"]["M_dK_mm"], th["over_balls"]["M_dK_nominal_mm"]],
    ]
    if span.get("k"):
        thickness.append([f"span W_{span['k']} [mm]", span["W_k_mm"], span["W_k_nominal_mm"]])
    thickness += [
        ["tip diameter [mm]", th["tip_diameter_mm"], th["tip_diameter_nominal_mm"]],
        ["root diameter [mm]", th["root_diameter_mm"], th["root_diameter_nominal_mm"]],
    ]
    sync = run["synchronisation"]["sync_error_in_cut"]
    forces = run["forces"]
    facts = [
        ["machine", f"{run['machine']['structure']} / {run['machine']['synchronization']}"],
        ["machine time [s]", run["durations_s"]["machine"]],
        [
            "sync error while cutting, RMS / p-p [um]",
            f"{sync.get('rms_um', 0):.3f} / {sync.get('peak_to_peak_um', 0):.3f}",
        ],
        ["tooth engagements cut", run["cut"]["passages"]],
        ["chip volume [mm^3]", run["cut"]["chip_volume_mm3"]],
        ["peak cutting force [N]", forces["peak_force_N"]],
        ["peak torque about the work axis [N m]", forces["peak_work_torque_Nm"]],
        ["cutting energy [J]", forces["chip_energy_J"]],
        ["mean chip thickness [mm]", forces["median_chip_thickness_mm"]],
        ["material", f"{forces['material']} (kc1.1 {forces['kc11']:g} N/mm^2, mc {forces['mc']:g})"],
        ["force granularity", forces["granularity"]],
        ["sweep error, finishing pass [um]", run["cut"]["pass_sweep_error_um"][-1]],
    ]
    stages = [[k, v] for k, v in run["durations_s"].items() if k != "machine"]
    wp_kind = (doc.get("workpiece") or {}).get("kind", "mesh")
    tol_note = f"tolerances of class {tol_class}" if tol_class else "no ISO tolerances"
    body = [
        f"<h1>{html.escape(title)}</h1>",
        f'<p class="verdict">{html.escape(verdict)}</p>',
        f"<p>Job <code>{html.escape(run['job']['path'])}</code>; skive {html.escape(run['versions']['skive'])}; "
        "the gear is what the swept-volume removal left along the motion the simulated machine made under the "
        f"chips' cutting forces. Measured workpiece: <b>{html.escape(wp_kind)}</b>, probed along the nominal "
        "directions with the nominal gear data alone.</p>",
        f"<h2>ISO 1328-1 deviations [um] ({html.escape(tol_note)}; rows over tolerance shaded)</h2>",
        html_table(["parameter", "left", "right", "tolerance", "class"], rows, fails),
        *_mesh_rows(doc.get("mesh")),
        "<h2>Size</h2>",
        html_table(["", "measured", "nominal"], thickness),
        *_added_rows(run.get("machine_added")),
        *_scope_rows(doc.get("model_scope")),
        "<h2>Profile, helix and pitch</h2>",
        *[image_tag(c) for c in charts],
        "<h2>Synchronisation error, cutting force and chips over time</h2>",
        image_tag(run_png),
        *(["<h2>The machine's thermal drift over the job</h2>", image_tag(thermal_png)] if thermal_png else []),
        "<h2>Run</h2>",
        html_table(["", ""], facts),
        html_table(["stage", "wall time [s]"], stages),
        "<h2>Setting sheet</h2>",
        f"<pre>{html.escape(sheet_text)}</pre>",
        "<h2>Job file</h2>",
        f"<pre>{html.escape(job_text)}</pre>",
    ]
    return write_page(path, title, body)


def _scope_rows(scope: dict | None) -> list[str]:
    """The model's scope: the error sources the verdict holds (with their values) and the known ones it does not."""
    if not scope:
        return []
    included = [[it["source"], f"{it['value']} {it['unit']}".strip(), it["key"]] for it in scope["included"]]
    left_out = [[it["source"], it["why"]] for it in scope["not_included"]]
    return [
        "<h2>The model's scope</h2>",
        "<p>The class above holds these error sources, with their values in this job:</p>",
        html_table(["source", "value", "job key"], included),
        "<p>and not these:</p>",
        html_table(["source", "why"], left_out),
    ]


def _added_rows(added: dict | None) -> list[str]:
    """What the machine added: this gear's deviations minus the ideal cut's (the same job with exact kinematics)."""
    if not added:
        return []
    if "deviations_um" not in added:
        return [
            "<h2>What the machine added</h2>",
            f"<p>The ideal cut could not be measured: {html.escape(str(added.get('error')))}</p>",
        ]
    rows = [[k, v.get("left"), v.get("right")] for k, v in added["deviations_um"].items()]
    rows += [[k.replace("_um", " (size)"), v, None] for k, v in added["size"].items()]
    c = added["class"]
    return [
        "<h2>What the machine added [um]</h2>",
        f"<p>This gear minus the ideal cut of the same job (the same cutter and clamping, exact kinematics, measured "
        f"the same way): class {c['run']} against the ideal cut's {c['ideal_cut']}.</p>",
        html_table(["parameter", "left", "right"], rows),
    ]


def _mesh_rows(mesh: dict | None) -> list[str]:
    """The mesh's measurement beside the exact one: its values, the differences, the bound they must keep."""
    if not mesh:
        return []
    if mesh.get("error"):
        return [
            "<h2>The mesh beside it</h2>",
            f"<p>The manifold mesh <code>{html.escape(str(mesh['name']))}</code> could not be measured (the exact "
            f"measurement above does not need it): {html.escape(mesh['error'])}</p>",
        ]
    rows = [[k, mesh["measured"][k], mesh["difference_um"][k]] for k in mesh["measured"]]
    rows += [[k.replace("_um", ""), None, v] for k, v in mesh["size_difference_um"].items()]
    verdict = "within" if mesh["within_bound"] else "outside"
    note = (
        f"<p>The manifold mesh <code>{html.escape(str(mesh['name']))}</code> ({mesh['triangles']} triangles, sweep "
        f"error &le; {mesh['sweep_bound_um']:.2f} um, simplified within {mesh.get('simplification_um', 0.0):.2f} um) "
        f"measured the same way: class {mesh['class']}. Along the "
        f"profile and helix traces it differs from the exact surface by at most {mesh['trace_difference_um']:.2f} um, "
        f"{verdict} its bound of {mesh['trace_bound_um']:.2f} um.</p>"
    )
    return [
        "<h2>The mesh beside it</h2>",
        note,
        html_table(["parameter (worst flank)", "mesh [um]", "exact - mesh [um]"], rows),
    ]
