"""The Python API: what the CLI does, as functions that return what they made.

    from virtual_machine import load_job, run
    result = run(load_job("assets/jobs/default.toml"), out="out")
    result.measurement["iso1328"]["class"]["overall"]     # the gear's ISO 1328-1 class
    result.report_path                                    # out/report.html

Each stage takes a job (a :class:`virtual_machine.job.Job`, or the path of a job file) and goes through the job's
process (:data:`virtual_machine.processes.PROCESSES`), exactly as `skive setup|simulate|cut|run` do; each returns a
:class:`virtual_machine.processes.Product` (``data``, ``text``, ``files``, ``out``). Progress goes to stderr as on
the command line (a line per stage, bars on a terminal); ``quiet=True`` silences it. Errors in the input raise
:class:`cutting.errors.InputError` (its message says what is wrong and how to fix it), before anything runs; every
error skive raises is a :class:`cutting.errors.SkiveError`. A stage's files appear in ``out`` only when it is
complete (:mod:`virtual_machine.output.staging`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from virtual_machine.job import Job, default_job_path, load_job
from virtual_machine.output.json_file import write_json
from virtual_machine.output.progress import Reporter
from virtual_machine.output.staging import StagedOutputs, sha256_of
from virtual_machine.processes import Product, process_for

JobLike = Job | str | Path


def _job(job: JobLike | None) -> Job:
    if isinstance(job, Job):
        return job
    return load_job(default_job_path() if job is None else job)


def _perform(stage: str, job: JobLike | None, out: str | Path | None, quiet: bool = False, **options: Any) -> Product:
    j = _job(job)
    folder = None if out is None else Path(out)
    return process_for(j).perform(stage, j, folder, reporter=Reporter(quiet=quiet), **options)


def setup(job: JobLike | None = None, *, structure: str | None = None) -> Product:
    """The setting sheet of ``job`` (default: the default job); ``structure``: another machine structure."""
    return _perform("setup", job, None, structure=structure)


def simulate(
    job: JobLike | None = None,
    out: str | Path = "out",
    *,
    duration: float | None = None,
    rrd: str | Path | None = None,
    structure: str | None = None,
    synchronization: str | None = None,
    adaptive_correction: bool | None = None,
    quiet: bool = False,
) -> Product:
    """The machine runs through the job without cutting (``duration`` [s] of machine time at most), the [machine]
    keys given here replacing the job's; writes the motion into ``out``."""
    return _perform(
        "simulate",
        job,
        out,
        quiet,
        duration=duration,
        rrd=None if rrd is None else Path(rrd),
        structure=structure,
        synchronization=synchronization,
        adaptive_correction=adaptive_correction,
    )


def cut(
    job: JobLike | None = None,
    out: str | Path = "out",
    *,
    edge: str | None = None,
    workers: int | None = None,
    trajectory: str | Path | None = None,
    mesh_tolerance: float | None = None,
    removal: str | None = None,
    quiet: bool = False,
) -> Product:
    """The ideal machine (or the simulated motion in ``trajectory``, a `simulate` trajectory.npz) cuts the
    workpiece; it is measured and written into ``out``. ``mesh_tolerance`` [um]: gear.stl's sweep error;
    ``removal``: "dexel" (default) or "manifold"."""
    return _perform(
        "cut",
        job,
        out,
        quiet,
        edge=edge,
        workers=workers,
        trajectory=None if trajectory is None else Path(trajectory),
        mesh_tolerance=mesh_tolerance,
        removal=removal,
    )


def run(
    job: JobLike | None = None,
    out: str | Path = "out",
    *,
    rrd: str | Path | None = None,
    workers: int | None = None,
    mesh_tolerance: float | None = None,
    removal: str | None = None,
    quiet: bool = False,
) -> Product:
    """The simulated machine cuts the workpiece under its cutting forces; measured, the report (and with ``rrd``
    the Rerun recording) written into ``out``. ``result.measurement`` is measurement.json's document."""
    rec = None if rrd is None else Path(rrd)
    return _perform("run", job, out, quiet, rrd=rec, workers=workers, mesh_tolerance=mesh_tolerance, removal=removal)


def measure(mesh: str | Path, job: str | Path | None = None, out: str | Path | None = None) -> dict[str, Any]:
    """Measure a gear mesh (STL, PLY, OBJ, 3MF, GLB) as the gear of ``job``'s [gear] section (default: the default
    job's), as a gear measuring machine does; with ``out``, write measurement.json and the charts there."""

    from metrology.charts import finite, write_charts
    from metrology.datum import load_mesh
    from metrology.measure import MeasureOptions, measure_gear
    from virtual_machine.job import load_gear_section

    gear, options = load_gear_section(default_job_path() if job is None else job)
    design = options.pop("design")
    result = measure_gear(load_mesh(Path(mesh)), gear, MeasureOptions.from_job(options, design), str(mesh))
    doc = {**finite(result), "solid_sha256": {Path(mesh).name: sha256_of(Path(mesh))}}  # the mesh it measured
    if out is not None:  # the files appear together, or not at all
        with StagedOutputs(Path(out)) as staging:
            write_json(staging.folder / "measurement.json", doc)
            write_charts(staging.folder, result)
            doc, _, _ = staging.publish(doc, "")
    return doc


def study(
    study_file: str | Path,
    out: str | Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    target_class: int | None = None,
    retry_failed: bool = False,
    progress=None,
):
    """Run the cases of a study file on Dask (a local cluster of ``workers``, or the ``scheduler`` at that address)
    and write results.csv, the error budget and report.html into ``out``; returns the study's outcome (its
    ``budget``, ``run`` and ``report``). ``progress(done, failed, total, seconds_left)`` follows the cases."""
    from virtual_machine.studies import pipeline

    return pipeline.run(
        Path(study_file), Path(out), workers, scheduler, target_class, progress, retry_failed=retry_failed
    )


def diagnose(
    measured: str | Path,
    job: str | Path,
    out: str | Path = "out",
    *,
    cache: str | Path | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    stage: str = "exact",
    progress=None,
):
    """Which machine-geometry errors most likely made the ``measured`` gear (skive's measurement.json or the CSV of
    docs/diagnose.md) of ``job``: the sensitivity study around the job (from the case store ``cache`` where it is
    there; ``workers`` 0: in this process), the fit, and diagnosis.json and diagnosis.png in ``out``. Returns the
    outcome (``diagnosis.causes`` best first, each with ``key``, ``value``, ``confidence``)."""
    from virtual_machine.diagnose.pipeline import run_diagnosis

    return run_diagnosis(
        Path(measured),
        Path(job),
        Path(out),
        None if cache is None else Path(cache),
        workers,
        scheduler,
        stage,
        progress=progress,
    )
