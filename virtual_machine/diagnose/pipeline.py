"""`skive diagnose MEASURED --job JOB`: the checks, the sensitivity study (taken from the case store where it is
there), the fit, diagnosis.json and the chart of measured against fitted traces (docs/diagnose.md)."""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cutting.errors import InputError, Problem, SkiveError
from virtual_machine.diagnose.fit import Diagnosis, diagnose
from virtual_machine.diagnose.measured import MeasuredGear, from_document, read_measured
from virtual_machine.diagnose.sources import GEOMETRY_SOURCES, Source, sensitivity_cases
from virtual_machine.job import load_job, read_toml
from virtual_machine.studies.cache import CaseCache
from virtual_machine.studies.runner import run_study
from virtual_machine.studies.spec import Study, Vary

#: a measured gear's evaluation range must cover this much of the job's (the signatures are the job's ranges)
RANGE_OVERLAP = 0.5


def default_store() -> Path:
    """Where the sensitivity studies are kept between diagnoses: $XDG_CACHE_HOME/skive/cases (~/.cache/...)."""
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "skive" / "cases"


@dataclass
class DiagnoseOutcome:
    diagnosis: Diagnosis
    measured: MeasuredGear
    cases: int
    reused: int
    ran: int
    wall_s: float
    files: list[Path]


def check_identity(measured: MeasuredGear, job) -> None:
    """The measured gear must be the job's: its teeth, normal module and helix angle (else: which differ, and
    what to do)."""
    g = job.gear
    fix = "diagnose a measurement of the job's gear, or give the job of this gear"
    beta = math.degrees(g.beta)
    problems = []
    if measured.teeth != g.teeth:
        why = f"the measured gear has {measured.teeth} teeth, the job's {g.teeth}"
        problems.append(Problem(measured.source, measured.teeth, why, fix))
    if not math.isclose(measured.normal_module, g.mn, rel_tol=1e-6):
        why = f"the measured gear's normal module is {measured.normal_module:g} mm, the job's {g.mn:g} mm"
        problems.append(Problem(measured.source, measured.normal_module, why, fix))
    if abs(measured.helix_angle_deg - beta) > 1e-3:
        why = f"the measured gear's helix angle is {measured.helix_angle_deg:g} deg, the job's {beta:g} deg"
        problems.append(Problem(measured.source, measured.helix_angle_deg, why, fix))
    if problems:
        raise InputError(problems)


def check_ranges(measured: MeasuredGear, base: MeasuredGear) -> None:
    """The measured traces must cover the job's evaluation ranges (at least :data:`RANGE_OVERLAP` of each)."""
    fix = (
        "measure over the job's evaluation ranges (its [measurement] profile_start_diameter, profile_end_diameter), "
        "or give the job of this gear"
    )
    problems = []
    for kind, what in (("profile", "roll length"), ("helix", "face position")):
        ours, theirs = base.range(kind), measured.range(kind)
        if ours is None or theirs is None:
            continue
        overlap = min(ours[1], theirs[1]) - max(ours[0], theirs[0])
        if overlap < RANGE_OVERLAP * (ours[1] - ours[0]):
            span = f"{theirs[0]:.3f}..{theirs[1]:.3f} mm"
            why = f"the measured {kind} traces cover {what} {span}, the job's range {ours[0]:.3f}..{ours[1]:.3f} mm"
            problems.append(Problem(measured.source, span, why, fix))
    if problems:
        raise InputError(problems)


def sensitivity_study(job_path: Path, sources: tuple[Source, ...]) -> tuple[Study, list]:
    """The study around the job (a Study for the runner: its cases and the keys each sets)."""
    data = read_toml(job_path)
    cases = sensitivity_cases(data, sources)
    keys = sorted({k for c in cases for k in c.values})
    varies = tuple(Vary(k, k.rsplit(".", 1)[-1], 0.0, values=()) for k in keys)
    return Study(job_path, job_path, data, "one-at-a-time", varies), cases


def run_diagnosis(
    measured_path: Path,
    job_path: Path,
    out: Path,
    store: Path | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    stage: str = "exact",
    sources: tuple[Source, ...] = GEOMETRY_SOURCES,
    progress=None,
) -> DiagnoseOutcome:
    """Every check first (the job, the measured gear and its identity), then the study (the case store's cases
    reused), the ranges, the fit and the files in ``out``: diagnosis.json, diagnosis.png and the study's cases
    (``out``/study)."""
    t0 = time.perf_counter()
    job = load_job(job_path)
    if getattr(job, "geometry", None) is None:
        raise InputError(Problem(str(job_path), job.kind, "skive diagnose names the machine geometry of a skiving job",
                                 "give the skiving job that cut the gear"))  # fmt: skip
    measured = read_measured(measured_path)
    check_identity(measured, job)
    study, cases = sensitivity_study(job_path, sources)
    cache = CaseCache(store if store is not None else default_store())

    def hook(case_id, record, done, failed, total) -> None:
        if progress is not None:
            progress(done, failed, total)

    result = run_study(study, cases, out / "study", workers, scheduler, hook, False, cache, stage)
    bad = [(cid, r["error"]) for cid, r in result.results.items() if r["status"] != "ok"]
    if bad:
        cid, err = bad[0]
        raise SkiveError(f"the sensitivity study's case {cid} failed: {err.splitlines()[0] if err else '?'} "
                         f"({out / 'study' / 'cases' / cid}); the diagnosis needs every case")  # fmt: skip
    docs = {c.id: json.loads((out / "study" / "cases" / c.id / "measurement.json").read_text()) for c in cases}
    gears = {cid: from_document(doc, cid) for cid, doc in docs.items()}
    check_ranges(measured, gears["base"])
    diagnosis = diagnose(measured, gears["base"], gears, sources, feed=job.process.axial_feed)
    files = write_outputs(out, diagnosis, measured, str(job_path))
    return DiagnoseOutcome(
        diagnosis, measured, len(cases), len(result.reused), len(result.ran), time.perf_counter() - t0, files
    )


def diagnosis_json(d: Diagnosis, measured: MeasuredGear, job: str) -> dict[str, Any]:
    return {
        "measured": measured.source,
        "job": job,
        "causes": [c.as_json() for c in d.causes],
        "fit": {"r2": d.r2, "measured_rms_um": d.measured_rms_um, "residual_rms_um": d.residual_rms_um},
    }


def write_outputs(out: Path, d: Diagnosis, measured: MeasuredGear, job: str) -> list[Path]:
    from virtual_machine.diagnose.chart import fit_chart

    out.mkdir(parents=True, exist_ok=True)
    path = out / "diagnosis.json"
    path.write_text(json.dumps(diagnosis_json(d, measured, job), indent=2))
    return [path, fit_chart(d, out / "diagnosis.png")]


def format_diagnosis(o: DiagnoseOutcome) -> str:
    """The lines a gear engineer reads: the causes best first, the fit, where the study came from."""
    d = o.diagnosis
    lines = [f"DIAGNOSIS  {o.measured.source}  ({o.measured.teeth} teeth, mn {o.measured.normal_module:g} mm)"]
    if not d.causes:
        lines.append("  no machine-geometry source explains the deviation from the job's ideal cut")
    for k, c in enumerate(d.causes, 1):
        phase = f" at {c.phase_deg:.0f} deg" if c.phase_deg is not None else ""
        lines.append(f"  {k}. {c.key} = {c.value:.4g} +- {c.uncertainty:.2g} {c.unit}{phase}  "
                     f"(confidence {c.confidence:.2f})")  # fmt: skip
    lines.append(f"  fit: R^2 {d.r2:.3f}; the measured deviation from the ideal cut {d.measured_rms_um:.2f} um RMS, "
                 f"left unexplained {d.residual_rms_um:.2f} um")  # fmt: skip
    lines.append(f"  sensitivity study: {o.cases} cases ({o.reused} from the case store, {o.ran} run now); "
                 f"{o.wall_s:.1f} s")  # fmt: skip
    lines.append("  files: " + ", ".join(str(f) for f in o.files))
    return "\n".join(lines)
