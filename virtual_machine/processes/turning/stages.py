"""Vibration turning (seed 004) on the lathe of seed 001, as `skive setup`, `skive simulate` and `skive run` do it.

The lathe is set up as for a thread whose lead is the feed S0 (master-slave: the carriage's servo follows the
spindle's encoder 6 through counter 7 and block 8); the feed vibration is added to the slave's command at the
spindle's angle (:class:`virtual_machine.structures.thread_group.ThreadMasterSlave`), so the carriage really has
to make it: what the turned surface shows is the path the simulated carriage made (B1, P2 recorded), not the
command. The surface and the chip breaks come from :mod:`cutting.turning.vibration` on that path
(:class:`cutting.turning.vibration.SampledTurning`), its crests are measured by :mod:`metrology.turned_surface`;
`skive run` also cuts it with manifold3d and measures the solid's crests beside the exact envelope.
"""

from __future__ import annotations

import hashlib
import html
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from cutting.turning.vibration import SampledTurning, TurningSetup, cut_workpiece
from machine_models.parameters import override
from machine_models.thread_lathe import ThreadLatheParams
from metrology.turned_surface import crest_heights, solid_crests, turned_surface_summary
from virtual_machine.job import Job, flatten_model
from virtual_machine.output.json_file import write_json

#: settling after the spindle's run-up before the measured revolutions start [s]
SETTLE = 0.2
#: axial angles at which the manifold solid's crests are compared with the envelope's
SOLID_ANGLES = 12


def ideal_setup(job: Job) -> TurningSetup:
    t = job.turning
    return TurningSetup(t["diameter"] / 2, t["feed"], t["nose_radius"], t["depth"], job.vibration)


def spindle_speed(job: Job) -> float:
    """Spindle speed [rev/s] of the cutting speed at the workpiece diameter."""
    return job.process["cutting_speed"] * 1000 / 60 / (math.pi * job.turning["diameter"])


def format_prediction(job: Job) -> str:
    """`skive setup` of a turning job: the geometry the feed and the vibration predict."""
    s = turned_surface_summary(ideal_setup(job), job.process["revolutions"])
    t, v = job.turning, job.vibration
    lines = [
        "VIBRATION TURNING (seed 004) on the lathe of seed 001 (master-slave: the feed follows the spindle's encoder)",
        f"  workpiece {t['diameter']:.2f} mm, feed S0 = {t['feed']:.3f} mm/rev, nose radius {t['nose_radius']:.2f} mm, "
        f"depth {t['depth']:.2f} mm; spindle {spindle_speed(job) * 60:.0f} rpm",
        "  vibration: none (plain turning)"
        if v is None
        else f"  vibration: A = {v.amplitude:.3f} mm, {v.cycles_per_rev:g} cycles/rev "
        f"({v.cycles_per_rev * spindle_speed(job):.1f} Hz), xi = T_in/T_out = {v.xi:g}, {v.form}",
        *_summary_lines(s),
    ]
    return "\n".join(lines)


def _summary_lines(s: dict[str, Any]) -> list[str]:
    sp = s["spacing_um"]
    return [
        f"  distance of successive paths: {sp['min']:.1f} .. {sp['max']:.1f} um (S0 {sp['S0']:.0f} um; "
        f"Delta_max / S0 = {sp['max'] / sp['S0']:.2f})",
        f"  crests: Rt max {s['Rt_max_um']:.2f} um, mean Rt {s['Rt_mean_um']:.2f} um, mean crest "
        f"{s['crest_mean_um']:.2f} um (plain turning {s['plain_turning_crest_um']:.2f} um)",
        f"  chip breaks per revolution: {s['chip_breaks_per_rev']:.2f}"
        + ("" if s["chip_breaks_per_rev"] else " (a continuous chip)"),
    ]


def simulate_turning(
    job: Job, progress: Callable[[float], None] | None = None, params: ThreadLatheParams | None = None
):
    """The lathe turns ``process.revolutions`` revolutions after its run-up; returns the record and the path it
    made as a :class:`SampledTurning` (theta from the first measured revolution, which the vibration met at the
    spindle angle ``path.theta0`` after the feed engaged: :func:`commanded_path`). ``params``: the lathe (default:
    the job's, its [machine.model] over the defaults)."""
    from virtual_machine.runtime.thread_run import simulate_thread

    n = job.process["revolutions"]
    params = params or override(ThreadLatheParams(), flatten_model(job.machine.get("model")))
    duration = params.runup_time + SETTLE + (n + 1) / spindle_speed(job)
    rec = simulate_thread(job, params, duration=duration, vibration=job.vibration)
    if progress is not None:
        progress(1.0)
    theta = rec.b1 - rec.b1[0]
    z = rec.hand_sign * (rec.p2 - rec.p2[0])  # along the feed [mm]
    k0 = int(np.searchsorted(rec.t, rec.runup + SETTLE))
    t = job.turning
    path = SampledTurning(
        t["diameter"] / 2,
        t["feed"],
        t["nose_radius"],
        t["depth"],
        job.vibration,
        theta=theta[k0:] - theta[k0],
        z=z[k0:] - z[k0],
        theta0=float(theta[k0]),
    )
    return rec, path


def commanded_path(job: Job, path: SampledTurning) -> np.ndarray:
    """The commanded axial position [mm] at the path's angles, from the same start (the vibration's phase)."""
    ideal = ideal_setup(job)
    return np.asarray(ideal.path(path.theta + path.theta0)) - float(ideal.path(path.theta0))


def simulate_summary(job: Job) -> dict[str, Any]:
    """`skive simulate` of a turning job: the machine's path against the command, the surface it leaves."""
    rec, path = simulate_turning(job)
    n = min(job.process["revolutions"], path.revolutions)
    commanded = ideal_setup(job)
    dev = (path.z - commanded_path(job, path)) * 1e3
    return (
        {
            "path_deviation_um": {"mean": float(dev.mean()), "peak_to_peak": float(np.ptp(dev))},
            "machine": turned_surface_summary(path, n),
            "commanded": turned_surface_summary(commanded, n),
            "machine_time_s": float(rec.t[-1]),
        },
        rec,
        path,
    )


def run_turning(job: Job, path: Path, out: Path, rrd: Path | None = None, stage=None) -> dict[str, Any]:
    """`skive run` of a turning job: the lathe turns, the surface it leaves is measured exactly and as the
    manifold solid; writes measurement.json, report.html (and the recording)."""
    stage = stage or (lambda name: None)
    durations: dict[str, float] = {}
    t0 = time.perf_counter()
    stage("machine: the lathe turns with the feed vibration")
    doc, rec, sampled = simulate_summary(job)
    durations["machine"] = time.perf_counter() - t0
    stage("the turned surface with manifold3d, its crests against the exact envelope")
    t0 = time.perf_counter()
    n = min(20, sampled.revolutions)
    solid = cut_workpiece(sampled, n, job.process["sweep_error"])
    phis = (np.arange(SOLID_ANGLES) + 0.5) * 2 * math.pi / SOLID_ANGLES
    diffs, rts = [], []
    for phi in phis:
        a, b = solid_crests(solid, float(phi)), crest_heights(sampled.surface(float(phi), n))
        rts.append(a.rt)
        if len(a.height) and len(b.height):
            big = b.height > 5e-4
            if big.any():
                near = np.abs(a.z[:, None] - b.z[big][None, :]).argmin(axis=0)
                diffs.append(np.max(np.abs(a.height[near] - b.height[big])))
    durations["solid"] = time.perf_counter() - t0
    doc["solid"] = {
        "revolutions": n,
        "sweep_error_um": job.process["sweep_error"] * 1e3,
        "Rt_max_um": float(max(rts)) * 1e3,
        "largest_crest_difference_to_envelope_um": float(max(diffs)) * 1e3 if diffs else None,
    }
    out.mkdir(parents=True, exist_ok=True)
    (out / "workpiece.stl").write_bytes(_stl(solid.solid))
    text = Path(path).read_text()
    doc["run"] = {
        "job": {"path": str(path), "sha256": hashlib.sha256(text.encode()).hexdigest(), "kind": job.kind},
        "seed": None,
        "durations_s": {k: round(v, 3) for k, v in durations.items()},
        "spindle_rpm": spindle_speed(job) * 60,
    }
    write_json(out / "measurement.json", doc)
    _report(out / "report.html", path, doc, job)
    if rrd is not None:
        stage("recording")
        _record(rrd, rec, sampled, job)
    return doc


def format_run(doc: dict[str, Any]) -> str:
    m, c = doc["machine"], doc["commanded"]
    lines = [
        "VIBRATION TURNING (seed 004): the path the lathe made",
        f"  carriage against the command: mean {doc['path_deviation_um']['mean']:.2f} um, peak to peak "
        f"{doc['path_deviation_um']['peak_to_peak']:.2f} um",
        *_summary_lines(m),
        f"  (the command alone: Rt max {c['Rt_max_um']:.2f} um, chip breaks {c['chip_breaks_per_rev']:.2f} per rev)",
        f"  the crests' geometric prediction from the path positions: Rt max {m['predicted_Rt_max_um']:.2f} um",
    ]
    if "solid" in doc:
        s = doc["solid"]
        lines.append(
            f"  manifold solid ({s['revolutions']} revs, sweep error {s['sweep_error_um']:.1f} um): Rt max "
            f"{s['Rt_max_um']:.2f} um, crests within {s['largest_crest_difference_to_envelope_um']:.2f} um of "
            "the exact envelope"
        )
    return "\n".join(lines)


def _stl(solid) -> bytes:
    import trimesh

    mesh = solid.to_mesh()
    tm = trimesh.Trimesh(np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts), process=False)
    return tm.export(file_type="stl")


def _report(page: Path, path: Path, doc: dict[str, Any], job: Job) -> None:
    from virtual_machine.output.report import html_table, write_page

    m, c = doc["machine"], doc["commanded"]
    rows = [
        [k.replace("_um", " [um]"), m[k], c[k]]
        for k in ("Rt_max_um", "Rt_mean_um", "crest_mean_um", "predicted_Rt_max_um", "plain_turning_crest_um")
    ]
    rows.append(["chip breaks per revolution", m["chip_breaks_per_rev"], c["chip_breaks_per_rev"]])
    rows.append(["Delta max [um]", m["spacing_um"]["max"], c["spacing_um"]["max"]])
    body = [
        f"<h1>skive run: {html.escape(Path(path).name)}</h1>",
        "<p>Vibration turning (seed 004) on the lathe of seed 001: the surface the simulated carriage's path leaves "
        "(exact envelope of the nose circles), the geometric prediction from the path positions, and the same for "
        "the commanded path.</p>",
        html_table(["", "machine", "command"], rows),
        "<h2>Manifold solid</h2>",
        html_table(["", ""], [[k, v] for k, v in doc["solid"].items()]),
        "<h2>Run</h2>",
        html_table(["", ""], [[k, v] for k, v in doc["run"]["durations_s"].items()]),
        "<h2>Setup</h2>",
        f"<pre>{html.escape(format_prediction(job))}</pre>",
        "<h2>Job file</h2>",
        f"<pre>{html.escape(Path(path).read_text())}</pre>",
    ]
    write_page(page, "skive run", body)


def _record(rrd: Path, rec, sampled: SampledTurning, job: Job) -> None:
    """The carriage's path against the command and the uncut chip thickness over machine time."""
    from virtual_machine.output.recorder import Recorder

    commanded = commanded_path(job, sampled)
    k0 = len(rec.t) - len(sampled.theta)
    t = rec.t[k0:]
    thickness = np.asarray(sampled.uncut_thickness(sampled.theta))
    with Recorder(rrd, "skive_turning") as stream:
        stream.series("lathe/carriage_mm", t, np.column_stack([sampled.z, commanded]), ["made", "commanded"])
        stream.series("lathe/uncut_chip_mm", t, np.clip(thickness, -1.0, 1.0)[:, None], ["uncut chip"])
