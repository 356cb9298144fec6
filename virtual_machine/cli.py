"""The ``skive`` command line. It only assembles stages and prints; the work lives in the packages."""

from __future__ import annotations

import json
import os
import signal
import sys
from pathlib import Path

# the command line renders nothing with MuJoCo (recordings go to Rerun): no GL context, and mujoco's import skips
# glfw's (0.13 s of every run's start); a user's own MUJOCO_GL wins
os.environ.setdefault("MUJOCO_GL", "disable")

import click

from cutting.errors import InputError, Problem, SkiveError, UnmeasurableGearError
from virtual_machine.job import STRUCTURES, default_job_path, load_job
from virtual_machine.job.kinds import GRADED
from virtual_machine.output.formatting import format_measurement
from virtual_machine.output.json_file import json_text
from virtual_machine.output.progress import Progress, Reporter
from virtual_machine.processes import process_for
from virtual_machine.processes.options import DEFAULT_VIEWER, REMOVALS

MESH_TOLERANCE_HELP = (
    "Sweep error of the finishing pass's manifold solid [um] (default: the job's process.sweep_error), and the most "
    "gear.stl's simplification may add (process.stl_tolerance, if larger). The gear is measured on its exact swept "
    "surface either way; a finer mesh costs time and a larger gear.stl."
)


REMOVAL_HELP = (
    "How the cut removes material: 'dexel' (the blank as lines cut exactly passage by passage, the solid made once "
    "at the end) or 'manifold' (the reference: every passage's swept tube subtracted by manifold3d)."
)


def _fail(exc: BaseException) -> None:
    click.echo(f"skive: {exc}", err=True)
    sys.exit(2)


def _terminate(signum: int, _frame) -> None:
    """SIGTERM ends the command as Ctrl-C does: cleanup blocks run (a stage's staging folder is removed)."""
    raise SystemExit(128 + signum)


class _Commands(click.Group):
    """The commands, each of whose errors is reported here once: skive's own (bad input, a job beyond its machine, a
    run that failed: exit 2, the message says what to change) and the file system's."""

    def invoke(self, ctx: click.Context):
        signal.signal(signal.SIGTERM, _terminate)
        try:
            return super().invoke(ctx)
        except (SkiveError, OSError) as exc:
            _fail(exc)


def _perform(stage: str, path: Path, out: Path | None = None, quiet: bool = False, **options):
    """``stage`` of the job at ``path`` through its process, with the options the user gave (None: not given)."""
    job = load_job(path)
    return process_for(job).perform(stage, job, out, reporter=Reporter(quiet=quiet), **options)


@click.group(cls=_Commands, help="skive: a physics-based virtual gear-skiving machine.")
def main() -> None:
    pass


@main.command(help="Print the machine setting sheet of JOB (default: the default job).")
@click.argument("job", required=False, type=click.Path(path_type=Path))
@click.option("--structure", type=click.Choice(STRUCTURES), help="Machine structure (default: the job's).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of text.")
@click.option(
    "--balance-passes",
    is_flag=True,
    default=None,
    help="Skiving: also propose radial increments giving every pass the same largest uncut chip (takes ~5-40 s).",
)
def setup(job: Path | None, structure: str | None, as_json: bool, balance_passes: bool | None) -> None:
    sheet = _perform("setup", job or default_job_path(), structure=structure, balance_passes=balance_passes)
    click.echo(sheet.json() if as_json else sheet.text)


@main.command(help="Measure a gear MESH (STL, PLY, OBJ, 3MF, GLB) as the gear of JOB's [gear] section.")
@click.argument("mesh", type=click.Path(path_type=Path))
@click.option("--job", "job_path", type=click.Path(path_type=Path), help="Job file (default: the default job).")
@click.option("--json", "as_json", is_flag=True, help="Print the measurement JSON instead of the summary.")
@click.option("--out", type=click.Path(path_type=Path), help="Write measurement.json and the charts here.")
def measure(mesh: Path, job_path: Path | None, as_json: bool, out: Path | None) -> None:
    from virtual_machine import api

    doc = api.measure(mesh, job_path, out)
    if as_json:
        click.echo(json_text(doc))
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
@click.option("--removal", type=click.Choice(REMOVALS), help=REMOVAL_HELP)
def cut(
    job: Path | None,
    out: Path,
    edge: str | None,
    workers: int | None,
    trajectory: Path | None,
    mesh_tolerance: float | None,
    removal: str | None,
) -> None:
    made = _perform(
        "cut",
        job or default_job_path(),
        out,
        edge=edge,
        workers=workers,
        trajectory=trajectory,
        removal=removal,
        mesh_tolerance=mesh_tolerance,
    )
    click.echo(made.text)


@main.command(help="Run JOB on the simulated machine: cut the gear under its cutting forces, measure it, report.")
@click.argument("job", required=False, type=click.Path(path_type=Path))
@click.option("--out", type=click.Path(path_type=Path), default=Path("out"), show_default=True)
@click.option("--rrd", type=click.Path(dir_okay=False, path_type=Path), help="Also write the Rerun recording here.")
@click.option("--workers", type=click.IntRange(1, 64), help="Removal processes (default: one per core, at most 8).")
@click.option("--mesh-tolerance", type=click.FloatRange(min=0.0, min_open=True), metavar="UM", help=MESH_TOLERANCE_HELP)
@click.option("--removal", type=click.Choice(REMOVALS), help=REMOVAL_HELP)
@click.option(
    "--view",
    metavar="URL",
    is_flag=False,
    flag_value=DEFAULT_VIEWER,
    help=f"Stream the run to a Rerun viewer as it goes, then its recording (alone: {DEFAULT_VIEWER}, `rerun`'s).",
)
def run(
    job: Path | None,
    out: Path,
    rrd: Path | None,
    workers: int | None,
    mesh_tolerance: float | None,
    removal: str | None,
    view: str | None,
) -> None:
    options = {"rrd": rrd, "workers": workers, "mesh_tolerance": mesh_tolerance, "removal": removal, "view": view}
    click.echo(_perform("run", job or default_job_path(), out, **options).text)


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
    from virtual_machine import api
    from virtual_machine.studies.cache import CaseCache
    from virtual_machine.studies.design import cases
    from virtual_machine.studies.runner import finished
    from virtual_machine.studies.spec import load_study

    # every check before any case runs
    spec = load_study(study_file)
    store = CaseCache(spec.cache) if spec.cache is not None else None
    # the cases to run now: not finished before, and not in the study's case store (those are reused)
    todo = sum(
        finished(out, c, retry_failed) is None and (store is None or store.get(c.job_text, spec.stage) is None)
        for c in cases(spec)
    )
    bar = Progress("study", max(todo, 1), "cases", step=1 / todo if 0 < todo <= 100 else 0.01, value_format="{:.0f}")

    def progress(done: int, failed: int, total: int, left: float | None) -> None:
        info: dict[str, object] = {"failed": failed}
        if left is not None:
            info["left"] = f"~{left / 60:.1f} min"
        bar.update_to(done, **info)

    try:
        outcome = api.study(
            study_file,
            out,
            workers=workers,
            scheduler=scheduler,
            target_class=target,
            progress=progress,
            retry_failed=retry_failed,
        )
    finally:
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
    if budget.class_counts:  # the cases' classes: a population's distribution (Monte Carlo)
        shown = ", ".join(f"{'>11' if c > 11 else c}: {k}" for c, k in budget.class_counts.items())
        line = f"  the cases' classes: {shown}"
        if budget.target is not None:
            line += f"; P(class <= {budget.target}) = {budget.p_at_most(budget.target):.2f}"
        lines.append(line)
    for p in budget.parameters:
        if p.answer is not None and not p.answer.meets:
            lines.append(f"  class {p.answer.target} {p.name} (<= {p.answer.tolerance:g} um): {p.answer.note}")
    lines.append(f"  files: {out / 'results.csv'}, {out / 'budget.json'}, {outcome.report}, {out / 'cases'}/")
    return "\n".join(lines)


@main.command(
    help="Run each JOB and fail (exit 1) when a gear is worse than ISO 1328-1 class N, naming the parameters; with "
    "--junit a JUnit XML report (one test case per job) for CI dashboards."
)
@click.argument("jobs", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--max-class", "max_class", type=click.IntRange(1, 11), required=True, help="Worst class accepted.")
@click.option("--json", "as_json", is_flag=True, help="Print the verdict as JSON (a list for several jobs).")
@click.option(
    "--out",
    type=click.Path(path_type=Path),
    default=Path("out"),
    show_default=True,
    help="Output folder (several jobs: one folder each beneath it, named by the job file).",
)
@click.option("--junit", type=click.Path(path_type=Path), help="Write the verdicts as JUnit XML to this file.")
@click.option(
    "--confidence",
    type=click.FloatRange(0.0, 1.0, min_open=True, max_open=True),
    help="Answer for a population of machines and cutters: pass when at least this share of a Monte-Carlo study's "
    "cases makes class N or better (docs/skiving-run.md).",
)
@click.option("--samples", type=click.IntRange(2, 100000), default=40, show_default=True, help="--confidence: cases.")
@click.option("--seed", type=int, default=1, show_default=True, help="--confidence: the draw's seed.")
@click.option(
    "--machine-tolerances",
    type=click.Choice(["job", "small", "medium", "large"]),
    default="job",
    show_default=True,
    help="--confidence: the machine size whose geometric tolerances the machines are drawn from (job: the job's).",
)
@click.option("--cutter-class", type=click.Choice(["AA", "A", "B"]), help="--confidence: draw the cutters too.")
@click.option(
    "--stage", type=click.Choice(["run", "cut"]), default="run", show_default=True, help="--confidence: each case's."
)
@click.option("--workers", type=click.IntRange(0, 64), help="--confidence: Dask workers (0: in this process).")
@click.option("--scheduler", help="--confidence: run the cases on an existing Dask cluster (tcp://host:port).")
def check(
    jobs: tuple[Path, ...],
    max_class: int,
    as_json: bool,
    out: Path,
    junit: Path | None,
    confidence: float | None,
    samples: int,
    seed: int,
    machine_tolerances: str,
    cutter_class: str | None,
    stage: str,
    workers: int | None,
    scheduler: str | None,
) -> None:
    import time

    from virtual_machine.output.check import class_verdict, format_verdict, junit_xml
    from virtual_machine.output.model_scope import scope_lines

    loaded = [load_job(job) for job in jobs]  # every job parses before any runs: a bad one costs no run
    for job, j in zip(jobs, loaded, strict=True):
        if j.kind not in GRADED:
            raise InputError(
                Problem(str(job), j.kind, "skive check grades gears by ISO 1328-1", "use `skive run` for this job")
            )
    results, verdicts = [], []
    for job, j in zip(jobs, loaded, strict=True):
        where = out if len(jobs) == 1 else out / job.stem
        t0 = time.perf_counter()
        if confidence is not None:  # a population of machines and cutters
            from virtual_machine.studies import pipeline
            from virtual_machine.studies.population import format_population, population_verdict, study_text

            folder = where / "population"
            folder.mkdir(parents=True, exist_ok=True)
            spec = folder / "study.toml"
            spec.write_text(study_text(job, samples, seed, machine_tolerances, cutter_class, stage))
            outcome = pipeline.run(spec, folder, workers, scheduler, max_class)
            verdict = population_verdict(outcome, max_class, confidence)
            results.append((str(job), verdict, time.perf_counter() - t0, None))
            verdicts.append({"job": str(job), **verdict})
            if not as_json:
                click.echo(format_population(verdict, str(job)))
            continue
        try:
            doc = process_for(j).perform("run", j, where, reporter=Reporter(quiet=True)).data
        except UnmeasurableGearError as exc:  # a gear that cannot be measured fails any class
            click.echo(f"FAIL {job}: {exc}", err=True)
            results.append((str(job), None, time.perf_counter() - t0, str(exc)))
            continue
        verdict = {**class_verdict(doc, j.gear, max_class), "model_scope": doc.get("model_scope")}
        results.append((str(job), verdict, time.perf_counter() - t0, None))
        verdicts.append({"job": str(job), **verdict})
        if not as_json:
            click.echo(format_verdict(verdict, str(job)))
            if verdict["model_scope"]:  # what the verdict holds and what it does not
                click.echo("\n".join(scope_lines(verdict["model_scope"])))
    if as_json:
        click.echo(json.dumps(verdicts[0] if len(jobs) == 1 and verdicts else verdicts, indent=2))
    if junit is not None:
        junit.parent.mkdir(parents=True, exist_ok=True)
        junit.write_text(junit_xml(results, max_class))
    if any(err is not None or not v["pass"] for _, v, _, err in results):
        sys.exit(1)


@main.command(
    help="Name the machine-geometry errors most likely to have made the MEASURED gear of JOB (skive's "
    "measurement.json, or a CSV of profile and helix traces and single pitch deviations: docs/diagnose.md), each with "
    "its estimated value and confidence, from a sensitivity study around the job (kept in a case store)."
)
@click.argument("measured", type=click.Path(path_type=Path))
@click.option("--job", "job_path", type=click.Path(path_type=Path), required=True, help="The job that cut the gear.")
@click.option("--out", type=click.Path(path_type=Path), default=Path("out"), show_default=True)
@click.option("--json", "as_json", is_flag=True, help='Print {"causes": [{"key", "value", "confidence"}, ...]}.')
@click.option(
    "--cache",
    type=click.Path(path_type=Path),
    help="The case store of the sensitivity studies (default: ~/.cache/skive/cases, or $XDG_CACHE_HOME/skive/cases).",
)
@click.option("--workers", type=click.IntRange(0, 64), help="Dask workers for the study (0: in this process).")
@click.option("--scheduler", help="Run the study on an existing Dask cluster (tcp://host:port).")
@click.option(
    "--stage",
    type=click.Choice(["exact", "cut", "run"]),
    default="exact",
    show_default=True,
    help="What each case of the study runs: the exact swept surface measured, `skive cut` or `skive run`.",
)
def diagnose(
    measured: Path,
    job_path: Path,
    out: Path,
    as_json: bool,
    cache: Path | None,
    workers: int | None,
    scheduler: str | None,
    stage: str,
) -> None:
    from virtual_machine import api
    from virtual_machine.diagnose.pipeline import diagnosis_json, format_diagnosis

    bar: Progress | None = None

    def progress(done: int, failed: int, total: int) -> None:
        nonlocal bar
        if bar is None:
            bar = Progress("sensitivity study", total, "cases", step=1 / total, value_format="{:.0f}")
        bar.update_to(done, failed=failed)

    try:
        outcome = api.diagnose(
            measured, job_path, out, cache=cache, workers=workers, scheduler=scheduler, stage=stage, progress=progress
        )
    finally:
        if bar is not None:
            bar.close()
    if as_json:
        click.echo(json.dumps(diagnosis_json(outcome.diagnosis, outcome.measured, str(job_path)), indent=2))
    else:
        click.echo(format_diagnosis(outcome))


@main.command(help="Draw each pass's stability lobes (critical radial infeed against tool speed) of a skiving JOB.")
@click.argument("job", required=False, type=click.Path(path_type=Path))
@click.option("--out", type=click.Path(path_type=Path), default=Path("out"), show_default=True)
@click.option("--json", "as_json", is_flag=True, help="Print the passes' figures as JSON.")
def stability(job: Path | None, out: Path, as_json: bool) -> None:
    from virtual_machine.processes.skiving.stability import pass_stability, stability_chart
    from virtual_machine.setting.machine_layout import machine_params

    j = load_job(job or default_job_path())
    if j.kind != "skiving":
        raise InputError(Problem("job", j.kind, "skive stability draws a skiving job's lobes", "give a skiving job"))
    results = pass_stability(
        j.skiving, machine_params(j), j.process.material, j.cutter_options.edge_radius,
        structure=j.machine.structure, adaptive=j.machine.adaptive_correction,
    )  # fmt: skip
    out.mkdir(parents=True, exist_ok=True)
    doc = {"job": str(job or default_job_path()), "passes": [r.summary() for r in results]}
    (out / "stability.json").write_text(json_text(doc))
    stability_chart(results, out / "stability.png", f"stability lobes: {Path(doc['job']).name}")
    if as_json:
        click.echo(json.dumps({"job": doc["job"], "passes": [{k: v for k, v in p.items() if k != "lobes"}
                                                             for p in doc["passes"]]}, indent=2))  # fmt: skip
        return
    for p in doc["passes"]:
        crit, margin = p["critical_infeed_mm"], p["margin"]
        verdict = "stable" if p["stable"] else "CHATTERS"
        at = f" at {p['chatter_frequency_hz']:.0f} Hz" if p["chatter_frequency_hz"] else ""
        first = f"{crit:.3f} mm" if crit is not None else "none up to 4x its infeed"
        click.echo(
            f"pass {p['pass']}: infeed {p['infeed_mm']:.3f} mm at {p['tool_speed_rpm']:.0f} rpm: {verdict}, margin "
            + (f"{margin:.2f}" if margin is not None else "unlimited (no regenerative chip)")
            + f"{at}; the least infeed that chatters at this speed: {first}"
        )
    click.echo(f"files: {out / 'stability.json'}, {out / 'stability.png'}")


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
    overrides = {"structure": structure, "synchronization": synchronization, "adaptive_correction": correction}
    # with --json stdout carries the JSON: no progress on stderr either
    made = _perform("simulate", job or default_job_path(), out, as_json, duration=duration, rrd=rrd, **overrides)
    click.echo(made.json() if as_json else made.text)


if __name__ == "__main__":
    main()
