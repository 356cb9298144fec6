"""skive run: the simulated machine cuts the gear under its own cutting forces, the gear is measured, and the
run writes gear.stl, measurement.json, report.html, the charts and (optionally) the Rerun recording.

A run is reproducible: nothing in it is random (no seed to set), the physics is single-threaded and the removal
order fixed, so the same job gives the same gear.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from cutting.errors import InputError, Problem, UnmeasurableError, UnmeasurableGearError
from cutting.gear_file import GearFile, write_gear_stl
from cutting.materials import material
from cutting.parallel import default_workers
from cutting.skiving.edge import CuttingEdge
from cutting.skiving.exact_sweep import SweptVolumes, edge_key
from cutting.skiving.interference import body_interference
from cutting.skiving.passages import CutResult
from cutting.skiving.sampled_motion import sampled_passes
from cutting.skiving.tool_load import tool_load
from cutting.skiving.tooling import tooling_summary
from cutting.skiving.trajectory import PassMotion
from cutting.skiving.working_angles import keep_maps, working_angle_maps, working_angle_summaries
from metrology.charts import finite, write_charts
from metrology.cut_measurement import measure_cut, unmeasured_mesh
from metrology.datum import check_mesh
from metrology.measure import MeasureOptions
from metrology.waviness import helix_waviness
from virtual_machine.job import Job, load_job
from virtual_machine.output.cutter_charts import write_cutter_charts
from virtual_machine.output.formatting import format_sheet
from virtual_machine.output.json_file import write_json
from virtual_machine.output.model_scope import model_scope
from virtual_machine.output.motion_io import summary
from virtual_machine.output.report import run_chart, thermal_chart, write_report
from virtual_machine.processes.base import run_identity
from virtual_machine.processes.sheets import sheet_product
from virtual_machine.processes.skiving.cosim import CoSimulation, cosimulate
from virtual_machine.processes.skiving.machine_added import IdealReference
from virtual_machine.processes.skiving.machine_effect import (
    flank_normals,
    generating_point_displacement,
    pass_deflection,
    pass_forces,
)
from virtual_machine.runtime.machine_run import SEGMENTS
from virtual_machine.setting.machine_layout import machine_params
from virtual_machine.setting.plan import SkivingPlan, plan_of
from virtual_machine.version import versions

#: blank snapshots per pass in the recording, evenly through its passages (the dexel removal's are closed meshes of
#: its ray ends, milliseconds each: cutting.skiving.dexel_solid.stock_mesh; the manifold removal's its solid)
SNAPSHOTS_PER_PASS = 5


def run_job(
    job: Job | Path,
    out: Path,
    rrd: Path | None = None,
    progress: Callable[[float, int], None] | None = None,
    stage: Callable[[str], None] | None = None,
    workers: int | None = None,
    mesh_tolerance: float | None = None,
    removal: str = "dexel",
    plan: SkivingPlan | None = None,
    view: str | None = None,
) -> dict[str, Any]:
    """Run ``job`` (or the job file at that path); write its files into ``out``; return the measurement document
    with ``run``.
    ``progress(machine_time, passages)`` follows the co-simulation, ``stage(name)`` announces each stage;
    ``workers``: the manifold removal's processes (default one per core); ``mesh_tolerance`` [mm]: the solid's
    tolerance (default the job's process.sweep_error); ``removal``: "dexel" or "manifold" (the reference); ``plan``:
    the job's setup, ideal passes and setting sheets if the caller made them (every stage of the run takes it);
    ``view``: a Rerun viewer's address: the run's signals streamed to it as the machine runs, then the recording
    (written to ``rrd``, or a scratch file when none is given); refused before anything runs when no viewer answers."""
    announce = stage or (lambda name: None)
    durations: dict[str, float] = {}
    given = job if isinstance(job, Job) else load_job(job)
    job = with_mesh_tolerance(given, mesh_tolerance)
    # the sweep error and the STL tolerance change neither the passes nor the setting sheets
    plan = plan_of(given, plan) if job is given else dataclasses.replace(plan_of(given, plan), job=job)
    path = Path(job.source)
    identity = run_identity(job)  # the run's recording id: from its start
    live = None
    if view is not None:
        from virtual_machine.output.recorder import LiveView

        live = LiveView(view, identity["recording_id"])
    if view is not None and rrd is None:
        rrd = out / "view.rrd.scratch"  # the recording the viewer gets is written somewhere: here, removed after
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    workers = workers or default_workers()
    snapshots = SNAPSHOTS_PER_PASS if rrd else 0
    modification_path = None
    ideal = IdealReference.start(job)  # the ideal cut of the same job, measured while the machine runs
    try:
        if job.modification is None:
            announce("machine and cut")
            sim = cosimulate(
                job,
                progress=progress,
                snapshots_per_pass=snapshots,
                workers=workers,
                removal=removal,
                plan=plan,
                live=live,
            )
        else:  # seed 003: the path planned on the ideal machine, then iterated on the simulated one (not streamed)
            sim, modification_path = _modification_runs(job, plan, announce, snapshots, workers, removal)
    except BaseException:
        IdealReference.cancel(ideal)
        raise
    finally:
        if live is not None:
            live.close()
    durations["machine and cut"] = time.perf_counter() - t0
    announce("measurement")
    t0 = time.perf_counter()
    stl, measurement, added = _measure(job, plan, sim, out, Path(path), durations, ideal)
    mesh = stl.mesh
    durations["measurement"] = time.perf_counter() - t0
    announce("report")
    t0 = time.perf_counter()
    charts = write_charts(out / "charts", measurement) + write_cutter_charts(out / "charts", measurement)
    t_mid, _, volume = engagement_middles(sim)
    run_png = run_chart(out / "charts" / "run.png", sim.record, sim.load_rows, list(zip(t_mid, volume, strict=True)))
    thermal_png = None
    if job.skiving.thermal is not None:  # the drift the run's poses carried
        thermal_png = thermal_chart(out / "charts" / "thermal.png", job.skiving.thermal, *_strokes(sim.record))
    durations["report"] = time.perf_counter() - t0
    if rrd is not None:
        announce("recording")
        t0 = time.perf_counter()
        _record(rrd, job, sim, mesh, measurement, [*charts, run_png], identity, view)
        durations["recording"] = time.perf_counter() - t0
        if rrd.name.endswith(".scratch"):
            rrd.unlink(missing_ok=True)
    if modification_path is not None:
        measurement["modification_path"] = modification_path
    doc = finite(measurement)
    doc["run"] = run_metadata(job, Path(path), sim, durations, stl)
    _flank_marks(doc["run"]["vibration"], measurement, len(job.skiving.passes), job.skiving.axial_feed)
    if added is not None:
        doc["run"]["machine_added"] = finite(added)
    doc["model_scope"] = model_scope(job, machine_params(job), "run")
    write_json(out / "measurement.json", doc)
    sheet = format_sheet(plan.sheet(), str(path))
    title = f"skive run: {Path(path).name}"
    write_report(out / "report.html", title, doc, Path(path).read_text(), sheet, charts, run_png, thermal_png)
    return doc


def _strokes(record) -> tuple[list[tuple[float, float]], float]:
    """The feed strokes' (start, end) machine times of a run's record, and its end."""
    feed = record.segment == SEGMENTS.index("feed")
    out = []
    for k in sorted(set(record.pass_index[feed].tolist())):
        t = record.t[feed & (record.pass_index == k)]
        out.append((float(t[0]), float(t[-1])))
    return out, float(record.t[-1])


def _flank_marks(vibration: list[dict], measurement: dict, passes: int, feed: float) -> None:
    """The finishing pass's vibration entry gets the waviness of the measured helix traces other than the feed
    marks (``flanks``: metrology.waviness.helix_waviness; ``feed`` the axial feed [mm]), the marks it left on the
    flanks beside the wavelength its frequency predicts (``surface_wavelength_mm``)."""
    traces = measurement.get("_traces")
    last = [v for v in vibration if v["pass"] == passes]
    if traces is None or not last:
        return
    marks = helix_waviness(traces["z_mm"], traces["helix"], feed)
    if marks is not None:
        last[0]["flanks"] = marks


def _measure(job: Job, plan: SkivingPlan, sim: CoSimulation, out: Path, path: Path, durations: dict, ideal):
    """gear.stl written, the truth measured (the exact swept surface of the motion the machine made; the mesh
    beside it) and what the machine added against the ideal cut ``ideal`` (an IdealReference or None)."""
    t0 = time.perf_counter()
    stl = write_gear_stl(sim.cut.gear, out / "gear.stl", job.process.stl_tolerance)
    motions = sampled_passes(plan.setup, sim.record.passes)
    made = IdealReference.maps(ideal)  # the tool's working-angle maps, made beside the machine by the reference
    if made is not None and made[0] == edge_key(sim.edge):
        keep_maps(job.skiving, sim.edge, made[1])
    measurement = None
    try:  # a workpiece the measuring machine cannot take (its datum or a ball seat fails) is the cut's fault
        measurement = measure_written_cut(job, sim.edge, motions, sim.cut, stl, out / "gear.stl")
    except (UnmeasurableError, InputError) as exc:
        durations["measurement"] = time.perf_counter() - t0
        raise _unmeasurable(exc, job, path, out, sim, durations, stl) from exc
    finally:
        if measurement is None:  # the measurement failed or the run was stopped: the reference is not needed
            IdealReference.cancel(ideal)
    return stl, measurement, IdealReference.added(ideal, measurement)


def _modification_runs(
    job: Job, plan: SkivingPlan, announce, snapshots: int, workers: int, removal: str
) -> tuple[CoSimulation, dict]:
    """The path of the job's flank modification: planned on the ideal machine (J, feed-forward, accuracy check),
    then iterated on the simulated machine, one co-simulation per iteration; the best one is the run."""
    from virtual_machine.processes.skiving.modification_path import iterate_on_machine, path_summary, plan_path

    announce("path for the flank modification on the ideal machine (seed 003)")
    path = plan_path(job, plan=plan)
    count = [0]

    def run(correction):
        count[0] += 1
        announce(f"machine and cut along the path, iteration {count[0]}")
        return cosimulate(
            job, snapshots_per_pass=snapshots, workers=workers, correction=correction, removal=removal, plan=plan
        )

    made = iterate_on_machine(job, path, run)
    return made.sim, path_summary(path, made)


def measure_written_cut(
    job: Job, edge: CuttingEdge, motions: Sequence[PassMotion], cut: CutResult, stl: GearFile, stl_path: Path
) -> dict[str, Any]:
    """What `skive cut` and `skive run` measure: the exact swept surface of ``motions``, and beside it the written
    gear.stl held to the finishing pass's sweep error plus the file's simplification."""
    opts = MeasureOptions.from_job(job.measurement, job.modification)
    bound = cut.pass_sweep_error.get(len(job.skiving.passes) - 1, cut.sweep_error)
    exact = SweptVolumes(job.gear, edge, motions)  # the truth the measuring machine probes: no chord error
    try:
        mesh = check_mesh(stl.mesh, str(stl_path))
    except InputError as exc:  # the file does not close: say so beside the exact measurement, which stands
        measurement, _ = measure_cut(job.gear, exact, None, opts, bound)
        measurement["mesh"] = unmeasured_mesh(str(stl_path), str(exc), len(stl.mesh.faces))
        return _with_the_tool(measurement, job, edge, cut)
    measurement, _ = measure_cut(job.gear, exact, mesh, opts, bound, str(stl_path), stl.simplification)
    return _with_the_tool(measurement, job, edge, cut)


def _with_the_tool(measurement: dict[str, Any], job: Job, edge: CuttingEdge, cut: CutResult) -> dict[str, Any]:
    """The cutter's side of the cut beside the gear's measurement: its working angles per pass and the relieved
    tooth's clearance to the finished teeth (from the setup), and the load each of its teeth took (from the chips)."""
    maps = working_angle_maps(job.skiving, edge)
    measurement["working_angles"] = working_angle_summaries(job.skiving, edge, job.process.min_working_clearance, maps)
    measurement["body_interference"] = body_interference(job.skiving, edge)
    measurement["_working_angle_maps"] = maps  # for the charts (not in measurement.json)
    measurement["tool_load"] = tool_load(cut.chips, job.skiving, material(job.process.material))
    return measurement


def _unmeasurable(
    exc: Exception, job: Job, path: Path, out: Path, sim: CoSimulation, durations: dict[str, float], stl: GearFile
) -> UnmeasurableGearError:
    """Keep what the run made (gear.stl, and measurement.json with the run's facts and the error) and say why the
    gear could not be measured, with the machine's synchronisation while it cut: what an engineer looks at first."""
    run = run_metadata(job, path, sim, durations, stl)
    write_json(out / "measurement.json", {"error": str(exc), "run": run})
    sync = run["synchronisation"]["sync_error_in_cut"] or {}
    machine = (
        f"the synchronisation error while cutting was {sync['rms_um']:.1f} um RMS, {sync['peak_to_peak_um']:.0f} um "
        "peak to peak"
        if sync
        else "the machine recorded no cutting"
    )
    peak = run["forces"]["peak_force_N"]
    return UnmeasurableGearError(
        f"the gear the machine cut cannot be measured: {exc}. {machine[0].upper()}{machine[1:]}, peak cutting force "
        f"{peak:.0f} N: a tooth is likely damaged. Look at {out / 'gear.stl'} and the run's facts in "
        f"{out / 'measurement.json'}; take less per pass (process.passes), a smaller process.axial_feed, or a stiffer "
        "and stronger machine ([machine.model])"
    )


def with_mesh_tolerance(job: Job, tolerance: float | None) -> Job:
    """The job with the finishing pass's sweep error set to ``tolerance`` [mm] and gear.stl's simplification held
    to it as well (None: as the job says)."""
    if tolerance is None:
        return job
    if not tolerance > 0:
        raise InputError(Problem("--mesh-tolerance", tolerance * 1e3, "must be positive", "give micrometres > 0"))
    stl = min(job.process.stl_tolerance, tolerance)
    return dataclasses.replace(job, process=dataclasses.replace(job.process, sweep_error=tolerance, stl_tolerance=stl))


def run_metadata(job: Job, path: Path, sim: CoSimulation, durations: dict[str, float], stl: GearFile) -> dict:
    """What the run was and what it saw, beside the metrology schema."""
    rec, cut, mat = sim.record, sim.cut, sim.material
    loads = sim.loads
    rows = sim.load_rows if sim.load_rows is not None else np.zeros((0, 5))
    force = np.linalg.norm(rows[:, 1:4], axis=1) if len(rows) else np.zeros(1)
    text = path.read_text()
    moved = {d["pass"]: d for d in pass_deflection(rec, job.skiving)}
    per_pass = [
        {**f, "flank_normal_deflection_um": moved.get(f["pass"], {}).get("flank_normal_deflection_um")}
        for f in pass_forces(loads, rows, len(job.skiving.passes), rec, job.skiving)
    ]
    vibration = [{"pass": k, **d["vibration"], **({"warning": d["warning"]} if "warning" in d else {})}
                 for k, d in moved.items()]  # fmt: skip
    return {
        "job": {"path": str(path), "sha256": hashlib.sha256(text.encode()).hexdigest(), "kind": job.kind},
        "versions": versions(),
        "seed": None,  # nothing random: the same job gives the same gear
        "machine": {k: getattr(job.machine, k) for k in ("structure", "synchronization", "adaptive_correction")},
        "cutter": tooling_summary(job.rake, job.cutter_errors, job.clamping),
        "durations_s": {**{k: round(v, 3) for k, v in durations.items()}, "machine": float(rec.t[-1])},
        "wall_split_s": {k: round(v, 3) for k, v in sim.seconds.items()},
        "synchronisation": summary(rec, job.gear.teeth),
        "forces": {
            "material": mat.key,
            "kc11": mat.kc11,
            "mc": mat.mc,
            "source": mat.source,
            "model": "oblique cutting per edge element: cutting, thrust and passive components (docs/forces.md)",
            "granularity": "the servo tick: each tooth in the cut takes the chip of the moment, between where the "
            "machine puts its edge and the surfaces left before it (one work revolution earlier, the previous pass, "
            "the blank)",
            # the force model's chip against the removal's (the exact geometry of the same motion)
            "model_chip_volume_mm3": float(sum(a.load.model_volume or 0.0 for a in loads)),
            "peak_force_N": float(force.max()),
            "peak_work_torque_Nm": float(np.abs(rows[:, 4]).max()) if len(rows) else 0.0,
            # its range (the cut pulls the work spindle back and forth as teeth enter and leave)
            "work_torque_min_Nm": float(rows[:, 4].min()) if len(rows) else 0.0,
            "work_torque_max_Nm": float(rows[:, 4].max()) if len(rows) else 0.0,
            "chip_energy_J": float(sum(a.load.energy for a in loads)),
            "load_work_J": sim.load_work,
            "median_chip_thickness_mm": float(np.median([a.load.thickness for a in loads])) if loads else 0.0,
            "chip_change_between_engagements": sim.chip_change(),
            # the three components per pass and the tool's displacement normal to the flanks at the generating point
            "passes": per_pass,
        },
        "vibration": vibration,
        "modification": None
        if job.modification is None
        else "the job's [modification] made by the finishing pass's path (radial and tangential corrections), "
        "iterated on this machine; the deviations are measured against the design (modification_path)",
        "cut": {
            "removal": sim.dexel or {"kind": "manifold"},
            "edge": job.cutter_options.edge,
            "passages": len(cut.chips),
            "chip_volume_mm3": float(sum(c.volume for c in cut.chips)),
            "sweeps": cut.sweeps,
            "subtractions": cut.subtractions,
            "pass_sweep_error_um": [cut.pass_sweep_error.get(i, 0.0) * 1e3 for i in range(len(job.skiving.passes))],
            "triangles": stl.solid_triangles,
            "gear_stl": stl.summary(),
        },
    }


def _record(
    rrd: Path,
    job: Job,
    sim: CoSimulation,
    mesh,
    measurement: dict,
    charts: list[Path],
    identity: dict[str, Any],
    view: str | None = None,
) -> None:
    from virtual_machine.output.recording import write_recording

    rows = sim.load_rows
    series = {}
    if rows is not None and len(rows):
        series["cutting force [N]"] = (rows[:, 0], np.linalg.norm(rows[:, 1:4], axis=1))
        series["cutting torque about the work axis [N m]"] = (rows[:, 0], rows[:, 4])
        # the force on the tool along the machine's axes (x the centre distance, y, z the work axis): what bends it
        rec = sim.record
        turn = np.interp(rows[:, 0], rec.t, rec.q[:, 1]) + job.skiving.work_phase
        c, s = np.cos(turn), np.sin(turn)
        on_tool = -np.stack([c * rows[:, 1] - s * rows[:, 2], s * rows[:, 1] + c * rows[:, 2], rows[:, 3]], -1)
        series["force on the tool along x y z [N]"] = (rows[:, 0], on_tool)
    middles = engagement_middles(sim)
    if sim.loads:
        series["chip volume [mm^3]"] = (middles[0], middles[2])
        # each engagement's three components at its middle (one tooth's; the teeth in the cut add up)
        comp = np.array([a.load.components[len(a.load.t) // 2] for a in sim.loads if a.load.components is not None])
        if len(comp) == len(middles[0]):
            series["cutting thrust passive force of a tooth [N]"] = (middles[0], np.abs(comp))
    t, _, disp = generating_point_displacement(sim.record, job.skiving)
    if len(t):
        normal = disp @ flank_normals(job.skiving).T
        series["tool off the flanks at the generating point [um]"] = (t, normal.mean(axis=1))
    write_recording(
        rrd,
        model_xml=sim.record.model_xml,
        motion=sim.record,
        setup=job.skiving,
        snapshots=sim.snapshots,
        gear_mesh=(np.asarray(mesh.vertices), np.asarray(mesh.faces)),
        measurement=measurement,
        charts=charts,
        series=series,
        recording_id=identity["recording_id"],
        documents={
            **identity["documents"],
            "setting_sheet": sheet_product(job, None).text,
            "machine_parameters": machine_parameters_text(job),
        },
        edge=sim.edge,
        view=view,
        engagements=middles if sim.loads else None,
    )


def machine_parameters_text(job: Job) -> str:
    """The machine the run simulated: its size's parameters with the job's [machine.model] on top, every figure (SI
    units as the model takes them), as JSON text for the recording."""
    from virtual_machine.setting.machine_layout import machine_params, machine_size

    params = dataclasses.asdict(machine_params(job))
    head = f"machine size {machine_size(job)!r} with the job's [machine.model]; SI units (m, kg, N, s, rad)\n"
    return head + json.dumps(params, indent=1, default=str)


def engagement_middles(sim: CoSimulation) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each cut engagement at its middle sample: machine time [s] (n,), the engaged edge's centroid in the blank
    frame [mm] (n, 3), the chip's volume [mm^3] (n,): the run chart's and the recording's chips."""
    mid = [len(a.load.t) // 2 for a in sim.loads]
    t = np.array([a.load.t[k] for a, k in zip(sim.loads, mid, strict=True)], dtype=float)
    point = np.array([a.load.point[k] for a, k in zip(sim.loads, mid, strict=True)], dtype=float).reshape(-1, 3)
    return t, point, np.array([a.load.volume for a in sim.loads], dtype=float)
