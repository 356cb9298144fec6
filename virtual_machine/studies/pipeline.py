"""`skive study`: check the study file and every case, run the cases on Dask, write the budget and report.html."""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from metrology import tolerances as iso
from virtual_machine.job import parse_job
from virtual_machine.studies.budget import Budget, error_budget
from virtual_machine.studies.cache import CaseCache
from virtual_machine.studies.design import cases as study_cases
from virtual_machine.studies.runner import StudyRun, run_study
from virtual_machine.studies.spec import Study, load_study

#: progress(done, failed, total, seconds_left or None)
StudyProgress = Callable[[int, int, int, float | None], None]


@dataclass
class StudyOutcome:
    study: Study
    run: StudyRun
    budget: Budget
    total_cases: int
    report: Path


def gear_data(study: Study) -> tuple[int, float, float, float, int]:
    """(z, mn, b, beta_deg, k_sector) of the base job's gear: what the ISO 1328-1 tolerances need."""
    job = parse_job(study.base_data, str(study.base_path))
    g = job.gear
    k = job.measurement.get("sector_teeth") or iso.default_sector_pitches(g.teeth)
    return g.teeth, g.mn, g.face_width, math.degrees(g.beta), k


def run(
    path: Path,
    out: Path,
    workers: int | None = None,
    scheduler: str | None = None,
    target: int | None = None,
    progress: StudyProgress | None = None,
    on_case=None,
    retry_failed: bool = False,
    cache: Path | None = None,
) -> StudyOutcome:
    """Every check first (InputError before any case runs), then the cases, then the budget and the report.
    ``cache``: the case store the study shares with others (default: the study file's ``cache``, else none)."""
    from virtual_machine.studies.report import write_study_report

    study = load_study(path)
    cases = study_cases(study)
    t0 = time.perf_counter()

    def hook(case_id, record, done, failed, total) -> None:
        if progress is not None:
            elapsed = time.perf_counter() - t0
            progress(done, failed, total, elapsed / done * (total - done) if done else None)
        if on_case is not None:
            on_case(case_id, record, done, failed, total)

    store = cache if cache is not None else study.cache
    store_ = CaseCache(store) if store else None
    result = run_study(study, cases, out, workers, scheduler, hook, retry_failed, store_, study.stage)
    budget = error_budget(study, result.results, gear_data(study), target)
    (out / "budget.json").write_text(json.dumps(budget_json(budget), indent=2))
    report = write_study_report(
        out / "report.html", study, result.results, budget, len(cases), result.wall_s, result.workers, store
    )
    return StudyOutcome(study, result, budget, len(cases), report)


def budget_json(budget: Budget) -> dict:
    """The budget as plain data (budget.json beside results.csv)."""
    from dataclasses import asdict

    def clean(v):
        if isinstance(v, float) and not math.isfinite(v):
            return None
        if isinstance(v, dict):
            return {k: clean(x) for k, x in v.items()}
        if isinstance(v, list | tuple):
            return [clean(x) for x in v]
        return v

    return clean(asdict(budget))
