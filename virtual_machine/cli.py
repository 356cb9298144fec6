"""The ``skive`` command line. It only assembles stages and prints; the work lives in the packages."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import click

from cutting.errors import InputError, Problem
from virtual_machine.formatting import format_gear_stl, format_measurement, format_sheet
from virtual_machine.job import STRUCTURES, default_job_path, load_job
from virtual_machine.progress import Progress, stage
from virtual_machine.setup_sheet import setup_sheet

MESH_TOLERANCE_HELP = (
    "Sweep error of the finishing pass's manifold solid [um] (default: the job's process.sweep_error), and the most "
    "gear.stl's simplification may add (process.stl_tolerance, if larger). The gear is measured on its exact swept "
    "surface either way; a finer mesh costs time and a larger gear.stl."
)


REMOVAL_HELP = (
    "How the cut removes material: 'dexel' (the blank as lines cut exactly passage by passage, the solid made once "
    "at the end) or 'manifold' (the reference: every passage's swept tube subtracted by manifold3d)."
)
REMOVALS = ("dexel", "manifold")


class _NullStream:
    """Where progress goes when stdout carries JSON and stderr should stay quiet too."""

    def write(self, _text: str) -> int:
        return 0

    def flush(self) -> None:
        pass


def _fail(exc: Exception) -> None:
    click.echo(f"skive: {exc}", err=True)
    sys.exit(2)


@click.group(help="skive: a physics-based virtual gear-skiving machine.")
def main() -> None:
    pass


@main.command(help="Print the machine setting sheet of JOB (default: the default job).")
@click.argument("job", required=False, type=click.Path(path_type=Path))
@click.option("--structure", type=click.Choice(STRUCTURES), help="Machine structure (default: the job's).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of text.")
def setup(job: Path | None, structure: str | None, as_json: bool) -> None:
    path = job or default_job_path()
    try:
        j = load_job(path)
        if j.kind == "form_milling":
            _setup_form_milling(j, as_json)
            return
        if j.kind == "face_contour":
            from cutting.face_contour import setting_sheet
            from virtual_machine.face_contour_job import format_setting_sheet, tool_speed

            if as_json:
                click.echo(json.dumps(_finite(setting_sheet(j.coupling, tool_speed(j))), indent=2, allow_nan=False))
            else:
                click.echo(format_setting_sheet(j))
            return
        if j.kind == "turning":
            from cutting.vibration_turning import turned_surface_summary
            from virtual_machine.turning import format_prediction, ideal_setup

            if as_json:
                doc = turned_surface_summary(ideal_setup(j), j.process["revolutions"])
                click.echo(json.dumps(_finite(doc), indent=2, allow_nan=False))
            else:
                click.echo(format_prediction(j))
            return
        sheet = setup_sheet(j, structure)
    except (InputError, ValueError) as exc:
        _fail(exc)
    if as_json:
        click.echo(json.dumps(_finite(sheet.to_json()), indent=2, allow_nan=False))
    else:
        click.echo(format_sheet(sheet, str(path)))


def _setup_form_milling(j, as_json: bool) -> None:
    """The copying method's sheet: the mill, the path points with their corrections, the iterations."""
    from virtual_machine.form_milling import format_plan, plan_job

    plan = plan_job(j, checks=0)
    if as_json:
        click.echo(json.dumps(_finite(plan.summary()), indent=2, allow_nan=False))
    else:
        click.echo(format_plan(plan))


@main.command(help="Measure a gear MESH (STL, PLY, OBJ, 3MF, GLB) as the gear of JOB's [gear] section.")
@click.argument("mesh", type=click.Path(path_type=Path))
@click.option("--job", "job_path", type=click.Path(path_type=Path), help="Job file (default: the default job).")
@click.option("--json", "as_json", is_flag=True, help="Print the measurement JSON instead of the summary.")
@click.option("--out", type=click.Path(path_type=Path), help="Write measurement.json and the charts here.")
def measure(mesh: Path, job_path: Path | None, as_json: bool, out: Path | None) -> None:
    from metrology.charts import finite, write_charts
    from metrology.datum import load_mesh
    from metrology.measure import MeasureOptions, measure_gear
    from virtual_machine.job import load_gear_section

    try:
        gear, options = load_gear_section(job_path or default_job_path())
        design = options.pop("design")
        data = load_mesh(mesh)
        result = measure_gear(data, gear, MeasureOptions.from_job(options, design), str(mesh))
    except (InputError, ValueError, RuntimeError) as exc:
        _fail(exc)
    doc = finite(result)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        (out / "measurement.json").write_text(json.dumps(doc, indent=2, allow_nan=False))
        write_charts(out, result)
    if as_json:
        click.echo(json.dumps(doc, indent=2, allow_nan=False))
    else:
        click.echo(format_measurement(doc, str(mesh)))
        if out is not None:
            click.echo(f"\nwrote {out / 'measurement.json'}, profile.png, helix.png, pitch.png")


@main.command(help="Cut JOB with the ideal kinematics, write DIR/gear.stl and measure it.")
@click.argument("job", required=False, type=click.Path(path_type=Path))
@click.option("--out", type=click.Path(path_type=Path), default=Path("out"), show_default=True)
@click.option("--edge", type=click.Choice(["conjugate", "involute"]), help="Override the job's cutter.edge.")
@click.option("--workers", type=click.IntRange(1, 64), help="Worker processes (default: one per core, at most 8).")
@click.option(
    "--trajectory",
    type=click.Path(exists=True, dir_okay=False, path_type=Path),
    help="Cut along a simulated pose trajectory (trajectory.npz of `skive simulate`) instead of the ideal motion.",
)
@click.option("--mesh-tolerance", type=click.FloatRange(min=0.0, min_open=True), metavar="UM", help=MESH_TOLERANCE_HELP)
@click.option("--removal", type=click.Choice(REMOVALS), default="dexel", show_default=True, help=REMOVAL_HELP)
def cut(
    job: Path | None,
    out: Path,
    edge: str | None,
    workers: int | None,
    trajectory: Path | None,
    mesh_tolerance: float | None,
    removal: str,
) -> None:
    from cutting.gear_file import write_gear_stl
    from cutting.ideal_cut import cut_ideal, default_workers
    from cutting.trajectory import ideal_passes
    from metrology.charts import finite, write_charts
    from virtual_machine.formatting import chip_record, format_removal
    from virtual_machine.job import dexel_spacing
    from virtual_machine.run import measure_written_cut, with_mesh_tolerance

    path = job or default_job_path()
    try:
        j = with_mesh_tolerance(load_job(path), None if mesh_tolerance is None else mesh_tolerance * 1e-3)
        if j.kind == "form_milling":
            _cut_form_milling(j, out, trajectory)
            return
        if j.kind == "face_contour":
            from virtual_machine.face_contour_job import cut_face_job, format_result

            click.echo(format_result(cut_face_job(j, out, stage)))
            click.echo(f"\nwrote {out / 'coupling.stl'}, measurement.json")
            return
        if j.kind in ("turning", "thread"):
            raise InputError(Problem("job", j.kind, "skive cut makes gears and couplings", "use `skive run`"))
    except (InputError, ValueError) as exc:
        _fail(exc)
    st = j.skiving
    bars: dict[int, Progress] = {}

    def progress(i: int, done: int, total: int) -> None:
        if i not in bars:
            bars[i] = Progress(f"pass {i + 1}/{len(st.passes)}", total, "passages")
        bars[i].update_to(done)

    kind = edge or j.cutter_options["edge"]
    motions = None
    plan = None
    if j.modification is not None and trajectory is None:
        from virtual_machine.modification_path import plan_path

        stage("path for the flank modification (seed 003: radial and tangential corrections, accuracy check)")
        plan = plan_path(j)
        motions = plan.motions
    if trajectory is not None:
        from cutting.sampled_motion import sampled_passes
        from virtual_machine.motion_io import load_trajectory

        try:
            motions = sampled_passes(st, load_trajectory(trajectory))
        except (InputError, ValueError, OSError) as exc:
            _fail(exc)
    try:
        report = cut_ideal(
            st,
            kind,
            j.process["sweep_error"],
            j.process["roughing_sweep_error"],
            progress,
            workers,
            motions=motions,
            removal=removal,
            spacing=dexel_spacing(j),
        )
    except InputError as exc:
        _fail(exc)
    for b in bars.values():
        b.close()
    stage("measurement: the exact swept surface and the mesh")
    out.mkdir(parents=True, exist_ok=True)
    stl = write_gear_stl(report.result.gear, out / "gear.stl", j.process["stl_tolerance"])
    result = measure_written_cut(j, report.edge, motions or ideal_passes(st), report.result, stl, out / "gear.stl")
    r = report.result
    result["cut"] = {
        "edge": kind,
        "motion": ("ideal" if plan is None else "ideal, finishing pass along the modification's path")
        if trajectory is None
        else str(trajectory),
        "sweep_error_um": r.sweep_error * 1e3,
        "pass_sweep_error_um": [r.pass_sweep_error.get(i, 0.0) * 1e3 for i in range(len(st.passes))],
        "sweeps": r.sweeps,
        "subtractions": r.subtractions,
        "passages": len(r.chips),
        "triangles": stl.solid_triangles,
        "gear_stl": stl.summary(),
        "workers": workers or default_workers(),
        "seconds": report.seconds,
        "pass_seconds": report.pass_seconds,
        "pass_stock_triangles": report.pass_triangles,
        "machine_seconds": list(st.pass_times),
        "removal": report.removal,
        "chips": [chip_record(c) for c in r.chips],
    }
    if plan is not None:
        from virtual_machine.modification_path import path_summary

        result["modification_path"] = path_summary(plan)
    doc = finite(result)
    (out / "measurement.json").write_text(json.dumps(doc, indent=2, allow_nan=False))
    write_charts(out, result)
    click.echo(format_measurement(doc, str(out / "gear.stl")))
    if plan is not None:
        click.echo(format_path(doc["modification_path"]))
    click.echo(format_removal(result["cut"], len(st.passes), sum(st.pass_times)))
    click.echo(format_gear_stl(result["cut"]["gear_stl"]))


def _cut_form_milling(j, out: Path, trajectory: Path | None) -> None:
    """skive cut of a form-milling job: the ideal machine along the planned path of the profiled mill."""
    from virtual_machine.form_milling import cut_form_job, format_copying

    if trajectory is not None:
        raise InputError(Problem("--trajectory", str(trajectory), "is for skiving jobs", "use `skive run` instead"))
    doc = cut_form_job(j, out, stage)
    click.echo(format_measurement(doc, str(out / "gear.stl")))
    click.echo(format_copying(doc))
    click.echo(format_gear_stl(doc["cut"]["gear_stl"]))


def format_path(path: dict) -> str:
    """The accuracy check's iterations and what the path cannot make."""
    lines = ["", "PATH  the finishing pass's radial and tangential corrections (seed 003's accuracy check)"]
    for where, rows, converged in (
        ("ideal machine", path["iterations"], path["converged"]),
        ("simulated machine", path.get("machine_iterations"), path.get("machine_converged")),
    ):
        if rows is None:
            continue
        for it in rows:
            r, c = it["residual_um"], it["C_beta_um"]
            lines.append(
                f"  {where}, iteration {it['iteration']}: largest residual left {r['left']:.2f} um, right "
                f"{r['right']:.2f} um; C_beta {c['left']:.2f} / {c['right']:.2f} um"
            )
        lines.append(f"  {where}: " + ("converged" if converged else "NOT converged: the residual stopped falling"))
    for side, um in path["beyond_path_um"].items():
        if um > 0.05:
            lines.append(
                f"  {side} flank: {um:.2f} um of the design vary over the profile: a modified cutter makes them"
            )
    return "\n".join(lines)


def _finite(obj: object) -> object:
    """JSON has no inf: an infinite lead (spur gear) becomes null."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_finite(v) for v in obj]
    return obj


@main.command(help="Run JOB on the simulated machine: cut the gear under its cutting forces, measure it, report.")
@click.argument("job", required=False, type=click.Path(path_type=Path))
@click.option("--out", type=click.Path(path_type=Path), default=Path("out"), show_default=True)
@click.option("--rrd", type=click.Path(dir_okay=False, path_type=Path), help="Also write the Rerun recording here.")
@click.option("--workers", type=click.IntRange(1, 64), help="Removal processes (default: one per core, at most 8).")
@click.option("--mesh-tolerance", type=click.FloatRange(min=0.0, min_open=True), metavar="UM", help=MESH_TOLERANCE_HELP)
@click.option("--removal", type=click.Choice(REMOVALS), default="dexel", show_default=True, help=REMOVAL_HELP)
def run(
    job: Path | None, out: Path, rrd: Path | None, workers: int | None, mesh_tolerance: float | None, removal: str
) -> None:
    from virtual_machine.program import program_duration
    from virtual_machine.run import run_job

    path = job or default_job_path()
    try:
        j = load_job(path)
        if j.kind == "thread":  # seed 001's lathe: the stroke, and the thread's lead measured on the path it made
            _simulate_thread(j, path, None, out, False, measurement=True)
            return
        if j.kind == "face_contour":
            from virtual_machine.face_contour_job import format_result, run_face_job

            doc = run_face_job(j, path, out, None, stage, rrd)
            click.echo(format_result(doc))
            click.echo(f"\nwrote {out / 'coupling.stl'}, measurement.json, report.html" + (f", {rrd}" if rrd else ""))
            return
        if j.kind == "turning":
            from virtual_machine.turning import format_run as format_turning
            from virtual_machine.turning import run_turning

            doc = run_turning(j, path, out, rrd, stage)
            click.echo(format_turning(doc))
            click.echo(f"\nwrote {out / 'workpiece.stl'}, measurement.json, report.html" + (f", {rrd}" if rrd else ""))
            return
        if j.kind == "form_milling":
            _run_form_milling(j, path, out, rrd)
            return
        total = program_duration(j.skiving)
    except (InputError, ValueError) as exc:
        _fail(exc)
    bar = Progress("machine and cut", total, "s of machine time", value_format="{:.2f}")

    def progress(t: float, passages: int) -> None:
        bar.set_total(t)
        bar.update_to(t, engagements=passages)

    def announce(name: str) -> None:
        if name != "machine and cut":
            bar.close()
            stage(name)

    from virtual_machine.physics import SimulationDivergedError
    from virtual_machine.run import UnmeasurableGearError
    from virtual_machine.simulate import LostSynchronismError

    try:
        tol = None if mesh_tolerance is None else mesh_tolerance * 1e-3
        doc = run_job(path, out, rrd, progress, announce, workers, tol, removal)
    except (InputError, SimulationDivergedError, LostSynchronismError, UnmeasurableGearError) as exc:
        bar.close()
        _fail(exc)
    click.echo(format_measurement(doc, str(out / "gear.stl")))
    if doc.get("modification_path"):
        click.echo(format_path(doc["modification_path"]))
    click.echo(format_run(doc["run"], out, rrd))


def _run_form_milling(j, path: Path, out: Path, rrd: Path | None) -> None:
    """skive run of a form-milling job: the simulated form-milling machine mills every space."""
    from virtual_machine.form_milling import format_copying, run_form_job
    from virtual_machine.physics import SimulationDivergedError

    bars: list[Progress] = []

    def announce(name: str) -> None:
        for b in bars:
            b.close()
        stage(name)
        if name.startswith("machine"):
            bars.append(Progress("form-milling machine", 1.0, "of the program", value_format="{:.3f}"))

    def progress(fraction: float) -> None:
        if bars:
            bars[-1].update_to(fraction)

    try:
        doc = run_form_job(j, path, out, rrd, progress, announce)
    except (InputError, SimulationDivergedError, ValueError) as exc:
        _fail(exc)
    finally:
        for b in bars:
            b.close()
    click.echo(format_measurement(doc, str(out / "gear.stl")))
    click.echo(format_copying(doc))
    wall = sum(v for k, v in doc["run"]["durations_s"].items() if k != "machine")
    click.echo(
        f"\nrun: {doc['run']['durations_s']['machine']:.1f} s of machine time in {wall:.1f} s; wrote "
        f"{out / 'gear.stl'}, measurement.json, report.html, charts/" + (f", {rrd}" if rrd else "")
    )


@main.command(
    help="Run the cases of STUDY (a study file) on Dask and write results.csv, the error budget and report.html."
)
@click.argument("study_file", metavar="STUDY", type=click.Path(path_type=Path))
@click.option("--out", type=click.Path(path_type=Path), required=True, help="Study directory (resumed if it exists).")
@click.option("--workers", type=click.IntRange(1, 256), help="Local Dask workers (default: one per core).")
@click.option(
    "--scheduler", metavar="ADDRESS", help="An existing Dask scheduler, e.g. tcp://host:8786 (no local cluster)."
)
@click.option(
    "--target-class",
    "target",
    type=click.IntRange(1, 11),
    help="Say what limits ISO 1328-1 class N and what to tighten.",
)
@click.option("--retry-failed", is_flag=True, help="Run the cases that failed before again (finished ones are kept).")
def study(
    study_file: Path, out: Path, workers: int | None, scheduler: str | None, target: int | None, retry_failed: bool
) -> None:
    from virtual_machine.study import pipeline
    from virtual_machine.study.cache import CaseCache
    from virtual_machine.study.design import cases
    from virtual_machine.study.runner import finished
    from virtual_machine.study.spec import load_study

    try:  # every check before any case runs
        spec = load_study(study_file)
        store = CaseCache(spec.cache) if spec.cache is not None else None
        # the cases to run now: not finished before, and not in the study's case store (those are reused)
        todo = sum(
            finished(out, c, retry_failed) is None and (store is None or store.get(c.job_text) is None)
            for c in cases(spec)
        )
    except (InputError, ValueError) as exc:
        _fail(exc)
    bar = Progress("study", max(todo, 1), "cases", step=1 / todo if 0 < todo <= 100 else 0.01, value_format="{:.0f}")

    def progress(done: int, failed: int, total: int, left: float | None) -> None:
        info: dict[str, object] = {"failed": failed}
        if left is not None:
            info["left"] = f"~{left / 60:.1f} min"
        bar.update_to(done, **info)

    try:
        outcome = pipeline.run(study_file, out, workers, scheduler, target, progress, retry_failed=retry_failed)
    except (InputError, ValueError, OSError) as exc:
        bar.close()
        _fail(exc)
    bar.close()
    click.echo(format_study(outcome, out))


def format_study(outcome, out: Path) -> str:
    """The end-of-study lines: cases, the limiting part, the files."""
    run, budget = outcome.run, outcome.budget
    failed = sum(r["status"] != "ok" for r in run.results.values())
    now = f"{len(run.ran)} run now on {run.workers} workers in {run.wall_s:.0f} s" if run.ran else "0 run now"
    lines = [
        "",
        f"STUDY  {outcome.study.path}  ({outcome.study.method}, {outcome.total_cases} cases: "
        f"{len(run.results) - failed} ok, {failed} failed; {now}, {len(run.skipped) - len(run.reused)} already done"
        + (f", {len(run.reused)} reused from the case store)" if run.reused else ")"),
    ]
    worst = budget.limiting()
    if budget.iso_error:
        lines.append(f"  no ISO 1328-1 classes: {budget.iso_error}")
    elif worst is not None:
        p, part = worst
        cls = f"class {p.stacked_class}" if p.stacked_class else "worse than class 11"
        by = f"; largest contribution: {part.label} {part.contribution:.2f} um" if part else ""
        lines.append(f"  limiting: {p.name} {p.stacked:.2f} um ({cls}){by}")
    for p in budget.parameters:
        if p.answer is not None and not p.answer.meets:
            lines.append(f"  class {p.answer.target} {p.name} (<= {p.answer.tolerance:g} um): {p.answer.note}")
    lines.append(f"  files: {out / 'results.csv'}, {out / 'budget.json'}, {outcome.report}, {out / 'cases'}/")
    return "\n".join(lines)


@main.command(help="Run JOB and fail (exit 1) when its gear is worse than ISO 1328-1 class N, naming the parameters.")
@click.argument("job", type=click.Path(path_type=Path))
@click.option("--max-class", "max_class", type=click.IntRange(1, 11), required=True, help="Worst class accepted.")
@click.option("--json", "as_json", is_flag=True, help="Print the verdict as JSON.")
@click.option("--out", type=click.Path(path_type=Path), default=Path("out"), show_default=True)
def check(job: Path, max_class: int, as_json: bool, out: Path) -> None:
    from virtual_machine.check import class_verdict, format_verdict
    from virtual_machine.physics import SimulationDivergedError
    from virtual_machine.run import UnmeasurableGearError, run_job
    from virtual_machine.simulate import LostSynchronismError

    try:
        j = load_job(job)
        doc = run_job(job, out)
    except UnmeasurableGearError as exc:  # a gear that cannot be measured fails any class
        click.echo(f"FAIL {job}: {exc}", err=True)
        sys.exit(1)
    except (InputError, ValueError, SimulationDivergedError, LostSynchronismError) as exc:
        _fail(exc)
    verdict = class_verdict(doc, j.gear, max_class)
    if as_json:
        click.echo(json.dumps({"job": str(job), **verdict}, indent=2))
    else:
        click.echo(format_verdict(verdict, str(job)))
    if not verdict["pass"]:
        sys.exit(1)


def format_run(run: dict, out: Path, rrd: Path | None) -> str:
    """The end-of-run table: stages and their wall time, what the machine and the chips did, the files."""
    d = run["durations_s"]
    wall = sum(v for k, v in d.items() if k != "machine")
    lines = ["", f"RUN  {run['job']['path']}  ({run['machine']['structure']} / {run['machine']['synchronization']})"]
    lines += [f"  {k:18s} {v:8.1f} s" for k, v in d.items() if k != "machine"]
    lines.append(f"  {'total':18s} {wall:8.1f} s for {d['machine']:.2f} s of machine time")
    sync, f = run["synchronisation"]["sync_error_in_cut"], run["forces"]
    if sync:
        lines.append(f"  sync error while cutting: RMS {sync['rms_um']:.3f} um, p-p {sync['peak_to_peak_um']:.3f} um")
    lines.append(
        f"  {run['cut']['passages']} engagements, {run['cut']['chip_volume_mm3']:.1f} mm^3 of chips, peak force "
        f"{f['peak_force_N']:.0f} N, cutting energy {f['chip_energy_J']:.0f} J ({f['material']})"
    )
    lines.append("  " + format_gear_stl(run["cut"]["gear_stl"]))
    if run.get("modification"):
        lines.append(f"  modification: {run['modification']}")
    files = ["gear.stl", "measurement.json", "report.html", "charts/"]
    lines.append(f"  files: {', '.join(str(out / x) for x in files)}" + (f", {rrd}" if rrd else ""))
    return "\n".join(lines)


@main.command(help="Run the machine through JOB's passes (no cutting); write the pose trajectory and motion record.")
@click.argument("job", required=False, type=click.Path(path_type=Path))
@click.option("--duration", type=click.FloatRange(min=0.0, min_open=True), help="Stop after S seconds of machine time.")
@click.option("--out", type=click.Path(path_type=Path), default=Path("out"), show_default=True)
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@click.option("--structure", type=click.Choice(STRUCTURES), help="Override the job's machine.structure.")
@click.option(
    "--synchronization", type=click.Choice(["equal-coordinates", "master-slave"]), help="Override the scheme."
)
@click.option(
    "--correction/--no-correction", default=None, help="Override machine.adaptive_correction (S4 and the thread group)."
)
@click.option("--rrd", type=click.Path(dir_okay=False, path_type=Path), help="Also write a Rerun recording of the run.")
def simulate(
    job: Path | None,
    duration: float | None,
    out: Path,
    as_json: bool,
    structure: str | None,
    synchronization: str | None,
    correction: bool | None,
    rrd: Path | None,
) -> None:
    import time

    from virtual_machine import motion_io
    from virtual_machine.physics import SimulationDivergedError
    from virtual_machine.simulate import LostSynchronismError
    from virtual_machine.simulate import simulate as run

    path = job or default_job_path()
    try:
        j = load_job(path)
    except (InputError, ValueError) as exc:
        _fail(exc)
    overrides = {"structure": structure, "synchronization": synchronization, "adaptive_correction": correction}
    overrides = {k: v for k, v in overrides.items() if v is not None}
    if overrides:
        import dataclasses

        j = dataclasses.replace(j, machine={**j.machine, **overrides})
    if j.kind == "thread":
        _simulate_thread(j, path, duration, out, as_json)
        return
    if j.kind == "face_contour":
        from virtual_machine.face_contour_job import format_simulation, simulate_face_job

        _, summary = simulate_face_job(j)
        out.mkdir(parents=True, exist_ok=True)
        (out / "simulation.json").write_text(json.dumps(_finite(summary), indent=2, allow_nan=False))
        click.echo(json.dumps(_finite(summary), indent=2) if as_json else format_simulation(summary))
        return
    if j.kind == "turning":
        from virtual_machine.turning import format_run as format_turning
        from virtual_machine.turning import simulate_summary

        doc, _, _ = simulate_summary(j)
        out.mkdir(parents=True, exist_ok=True)
        (out / "simulation.json").write_text(json.dumps(_finite(doc), indent=2, allow_nan=False))
        click.echo(json.dumps(_finite(doc), indent=2) if as_json else format_turning(doc))
        return
    if j.kind == "form_milling":
        _fail(
            InputError(
                Problem("job", "[mill]", "a form-milling job is simulated with its cut", "use `skive run` for it"),
                str(path),
            )
        )
    st = j.skiving
    total = duration or (sum(st.pass_times) + 0.5 + 1.2 * (len(st.passes) - 1))  # strokes + run-up + returns (approx.)
    bar = Progress("machine time", total, "s", value_format="{:.2f}", stream=None if not as_json else _NullStream())

    def progress(t: float) -> None:
        bar.set_total(t)
        bar.update_to(t)

    t0 = time.perf_counter()
    try:
        rec = run(j, duration=duration, progress=progress)
    except (InputError, SimulationDivergedError, LostSynchronismError, NotImplementedError) as exc:
        bar.close()
        _fail(exc)
    bar.close()
    wall = time.perf_counter() - t0
    meta = {
        "job": str(path),
        "structure": j.machine["structure"],
        "synchronization": j.machine["synchronization"],
        "adaptive_correction": j.machine["adaptive_correction"],
        "wall_seconds": wall,
    }
    doc = motion_io.save(rec, out, meta, st.gear.teeth)
    if rrd is not None:
        from virtual_machine.recording import write_recording

        write_recording(rrd, model_xml=rec.model_xml, motion=rec, setup=st, charts=[out / "sync_error.png"])
        doc["recording"] = str(rrd)
    if as_json:
        click.echo(json.dumps(doc, indent=2))
        return
    click.echo(
        f"\nSIMULATION  {path}  ({j.machine['structure']}, {j.machine['synchronization']}, "
        f"adaptive correction {'on' if j.machine['adaptive_correction'] else 'off'})"
    )
    click.echo(
        f"{doc['machine_seconds']:.2f} s of machine time in {wall:.1f} s wall "
        f"({doc['machine_seconds'] / wall:.1f}x real time)"
    )
    click.echo("synchronisation error while cutting (arc on the reference circle, um):")
    motors = "/".join(doc["passes"][0]["peak_torque_Nm"]) if doc["passes"] else ""
    click.echo(f"{'pass':>5} {'mean':>8} {'rms':>8} {'rms-mean':>9} {'p-p':>8}   peak torque {motors} [N m]")
    for p in doc["passes"]:
        s, tq = p["sync_error_in_cut"], p["peak_torque_Nm"]
        if s:
            click.echo(
                f"{p['pass'] + 1:>5} {s['mean_um']:8.3f} {s['rms_um']:8.3f} {s['rms_about_mean_um']:9.3f} "
                f"{s['peak_to_peak_um']:8.3f}   " + " / ".join(f"{v:.1f}" for v in tq.values())
            )
    for name, v in doc.get("periodic_part", {}).items():
        click.echo(f"periodic part per {name.replace('_', ' ')}: {v['peak_to_peak_um']:.3f} um p-p")
    click.echo(
        f"written: {out / 'trajectory.npz'}, {out / 'motion.npz'}, {out / 'simulation.json'}, {out / 'sync_error.png'}"
    )


def _simulate_thread(
    j, path: Path, duration: float | None, out: Path, as_json: bool, measurement: bool = False
) -> None:
    """skive simulate for a thread job (seed 001): one threading stroke on the lathe, its lead error; for skive run
    (``measurement``) also measurement.json: the lead of the thread the carriage's path cuts, as a thread measuring
    machine reports it (its deviation along the thread, mean, peak to peak, drift)."""
    import time

    import numpy as np

    from machine_models.thread_lathe import ThreadLatheParams, build_thread_lathe_spec
    from virtual_machine import motion_io
    from virtual_machine.physics import SimulationDivergedError
    from virtual_machine.simulate import LostSynchronismError
    from virtual_machine.simulate_thread import simulate_thread
    from virtual_machine.thread_layout import thread_layout

    t0 = time.perf_counter()
    try:
        rec = simulate_thread(j, duration=duration)
    except (SimulationDivergedError, LostSynchronismError, ValueError) as exc:
        _fail(exc)
    wall = time.perf_counter() - t0
    out.mkdir(parents=True, exist_ok=True)
    params = ThreadLatheParams()
    motion_io.write_model(build_thread_lathe_spec(thread_layout(j, params), params).to_xml(), out)
    np.savez_compressed(
        out / "thread_motion.npz",
        t=rec.t,
        b1=rec.b1,
        p2=rec.p2,
        tv=rec.tv,
        torque=rec.torque,
        lead_error_um=rec.lead_error_um,
        on_thread=rec.on_thread,
    )
    drift, travel = rec.drift() if rec.on_thread.sum() > 2 else (0.0, 0.0)
    doc = {
        "job": str(path),
        "form": rec.form,
        "lead_mm": rec.lead,
        "machine_seconds": float(rec.t[-1]),
        "wall_seconds": wall,
        "lead_error_on_thread": rec.stats(),
        "lead_drift_um": drift,
        "travel_mm": travel,
    }
    (out / "simulation.json").write_text(json.dumps(doc, indent=2))
    if measurement:
        lead = {"lead_mm": rec.lead, "form": rec.form, **(doc["lead_error_on_thread"] or {}), "drift_um": drift}
        (out / "measurement.json").write_text(json.dumps({"thread": lead, "run": doc}, indent=2))
    if as_json:
        click.echo(json.dumps(doc, indent=2))
        return
    s = doc["lead_error_on_thread"]
    click.echo(f"THREAD SIMULATION  {path}  ({rec.form}), lead {rec.lead} mm")
    click.echo(f"{doc['machine_seconds']:.2f} s of machine time in {wall:.1f} s wall")
    if s:
        click.echo(
            f"lead error on the thread: mean {s['mean_um']:.3f} um, p-p {s['peak_to_peak_um']:.3f} um, "
            f"drift {drift:+.3f} um over {abs(travel):.1f} mm"
        )
    files = ["thread_motion.npz", "simulation.json", *(["measurement.json"] if measurement else []), "scene.xml"]
    click.echo("written: " + ", ".join(str(out / f) for f in files))


if __name__ == "__main__":
    main()
