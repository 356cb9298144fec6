"""Running a study on Dask distributed: every case an independent task that runs the job as `skive run` does
(machine, cutting forces, cut, exact measurement) and returns its measurement.

The engine is a Dask LocalCluster (one single-threaded worker process per core, or ``workers``) or an existing
cluster (``scheduler``, e.g. ``tcp://host:port``). A task runs its case in a scratch directory of its worker and
returns the measurement document, so workers need no shared file system; this process writes
``cases/<id>/job.toml``, ``cases/<id>/measurement.json`` and ``cases/<id>/result.json`` as each case finishes,
and rewrites ``results.csv`` (every finished case, in case order). A study that is interrupted resumes: a case
whose result.json holds its job hash is not run again. A case that fails (the machine loses synchronism, the
gear cannot be measured, anything else) is recorded with its error; the others go on.

Each case cuts with one removal process (the Dask worker is the unit of parallelism), so its result does not
depend on how many workers the study has: the same study gives the same table with 1 or N workers.

With a case store (:mod:`virtual_machine.studies.cache`), a case whose job the store holds is not run: its stored
result is written as the case's (result.json says ``"reused": true``), and every case that finishes is stored.
"""

from __future__ import annotations

import csv
import json
import logging
import math
import tempfile
import time
import traceback
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cutting.errors import SkiveError
from virtual_machine.studies.cache import CaseCache
from virtual_machine.studies.design import Case
from virtual_machine.studies.spec import Study

SIDES = ("left", "right")
#: measured columns of results.csv per flank: (block of measurement.json, name), in um
FLANK_COLUMNS = (
    ("profile", "F_alpha"),
    ("profile", "f_Halpha"),
    ("profile", "f_Halpha_mean"),
    ("profile", "f_falpha"),
    ("helix", "F_beta"),
    ("helix", "f_Hbeta"),
    ("helix", "f_Hbeta_mean"),
    ("helix", "f_fbeta"),
    ("pitch", "f_p"),
    ("pitch", "F_p"),
    ("pitch", "F_pk"),
)
MEASURED = (*(f"{name}_{side}" for _, name in FLANK_COLUMNS for side in SIDES), "F_r", "class", "sync_rms_um")

#: on_case(case_id, result, done, failed, total): called after each case is written
CaseHook = Callable[[str, dict[str, Any], int, int, int], None]


#: what a study's case runs: `skive run` (the simulated machine), `skive cut` (the ideal kinematics on the machine as
#: built), or "exact" (that cut's exact swept surface measured, without the solid: a skiving job's geometric
#: sensitivities at a tenth of a cut's time; virtual_machine/processes/skiving/machine_added.exact_measurement)
STAGES = ("run", "cut", "exact")


def run_case(case_id: str, job_text: str, stage: str = "run") -> dict[str, Any]:
    """One case on a worker: the job run as `skive run` runs it (its process's run, one removal process, nothing
    printed; or the ``stage`` of :data:`STAGES`), in a scratch directory. Returns status, error, wall time and the
    measurement document (or, for a gear that could not be measured, the run's facts), never raises for a failing
    case."""
    from virtual_machine.job import load_job
    from virtual_machine.output.progress import Reporter
    from virtual_machine.processes import process_for

    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix=f"skive-{case_id}-") as tmp:
        job = Path(tmp) / "job.toml"
        job.write_text(job_text)
        out = Path(tmp) / "out"
        try:
            parsed = load_job(job)
            if stage == "exact":
                from virtual_machine.processes.skiving.machine_added import exact_measurement

                doc = exact_measurement(parsed)
            else:
                process = process_for(parsed)
                one = {"workers": 1} if process.takes(stage, "workers") else {}  # a worker runs one removal process
                doc = process.perform(stage, parsed, out, reporter=Reporter(quiet=True), **one).data
            status, error = "ok", ""
        except Exception as exc:  # a failing case is a result of the study, not the end of it
            status, error = "failed", f"{type(exc).__name__}: {exc}"
            kept = out / "measurement.json"  # an unmeasurable gear keeps the run's facts
            doc = json.loads(kept.read_text()) if kept.is_file() else {}
            if not isinstance(exc, SkiveError):  # a defect, not the machine or the job: keep where it happened
                error += "\n" + traceback.format_exc(limit=6)
            if str(out) in error:  # the scratch directory is gone: name what the study keeps instead
                error = error.replace(str(out) + "/", "") + (
                    f" (the study keeps cases/{case_id}/measurement.json; `skive run cases/{case_id}/job.toml` "
                    "writes the case's gear.stl again)"
                )
            error = error.replace(str(job), f"cases/{case_id}/job.toml")  # the job as the study keeps it
    return {"id": case_id, "status": status, "error": error, "wall_s": time.perf_counter() - t0, "measurement": doc}


def measured_row(doc: dict[str, Any]) -> dict[str, Any]:
    """The results.csv columns of one measurement document (missing parts left empty)."""
    row: dict[str, Any] = {}
    for block, name in FLANK_COLUMNS:
        for side in SIDES:
            row[f"{name}_{side}"] = doc.get(block, {}).get(side, {}).get(name)
    row["F_r"] = doc.get("runout", {}).get("F_r")
    iso = doc.get("iso1328") or {}
    row["class"] = (iso.get("class") or {}).get("overall")
    sync = (doc.get("run") or {}).get("synchronisation", {}).get("sync_error_in_cut") or {}
    row["sync_rms_um"] = sync.get("rms_um")
    return row


@dataclass
class StudyRun:
    """What a study run leaves: every finished case's result (id -> result.json), the cases it ran now, those it
    did not (``skipped``: finished before, or ``reused`` from the case store), the wall time, and the paths
    written."""

    results: dict[str, dict[str, Any]]
    ran: list[str]
    skipped: list[str]
    wall_s: float
    workers: int
    csv: Path
    reused: list[str] = field(default_factory=list)


def run_study(
    study: Study,
    cases: Sequence[Case],
    out: Path,
    workers: int | None = None,
    scheduler: str | None = None,
    on_case: CaseHook | None = None,
    retry_failed: bool = False,
    cache: CaseCache | None = None,
    stage: str = "run",
) -> StudyRun:
    """Run every case not finished yet on Dask (``retry_failed``: and those that failed before); write the case
    files and results.csv as each case finishes. ``cache``: take the cases it holds from it instead of running
    them, and store every case that finishes in it. ``stage``: what each case runs (:data:`STAGES`); ``workers``
    0: every case in this process, one after the other (no cluster to start: a handful of short cases)."""
    from dask.distributed import Client, LocalCluster, as_completed

    out.mkdir(parents=True, exist_ok=True)
    results = {c.id: r for c in cases if (r := finished(out, c, retry_failed)) is not None}
    pending = [c for c in cases if c.id not in results]
    reused: list[str] = []
    for c in list(pending):
        stored = cache.get(c.job_text, stage) if cache is not None else None
        if stored is not None:
            results[c.id] = write_case(out, c, {**stored, "id": c.id}, reused=True)
            reused.append(c.id)
            pending.remove(c)
    for c in pending:
        (out / "cases" / c.id).mkdir(parents=True, exist_ok=True)
        (out / "cases" / c.id / "job.toml").write_text(c.job_text)
    path = write_csv(out, study, cases, results)
    t0 = time.perf_counter()
    ran: list[str] = []
    if not pending:
        return StudyRun(results, ran, sorted(results), 0.0, 0, path, reused)
    by_id = {c.id: c for c in cases}
    failed = 0

    def finish(case: Case, result: dict[str, Any]) -> None:
        """A case's files, its entry in the store, results.csv and the hook, as it finishes."""
        nonlocal failed
        record = write_case(out, case, result)
        if cache is not None:
            cache.put(case.job_text, result, stage)
        results[case.id] = record
        ran.append(case.id)
        failed += record["status"] != "ok"
        write_csv(out, study, cases, results)
        if on_case is not None:
            on_case(case.id, record, len(ran), failed, len(pending))

    if workers == 0 and not scheduler:
        for c in pending:
            finish(c, run_case(c.id, c.job_text, stage))
        skipped = sorted(set(results) - set(ran))
        return StudyRun(results, ran, skipped, time.perf_counter() - t0, 1, path, reused)
    cluster = None
    if scheduler:
        client = Client(scheduler)
    else:
        n = min(workers or default_study_workers(), len(pending))  # no idle workers to start
        cluster = LocalCluster(
            n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=logging.ERROR
        )
        client = Client(cluster)
    try:
        n_workers = len(client.scheduler_info(n_workers=-1)["workers"]) or 1
        futures = {
            client.submit(run_case, c.id, c.job_text, stage, key=f"skive-case-{stage}-{c.id}-{c.job_hash[:16]}"): c.id
            for c in pending
        }
        for future in as_completed(futures):
            case_id = futures[future]
            try:
                result = future.result()
            except Exception as exc:  # the worker itself died (memory, a crash): the case failed, the study goes on
                result = {
                    "id": case_id,
                    "status": "failed",
                    "error": f"{type(exc).__name__}: {exc}",
                    "wall_s": math.nan,
                    "measurement": {},
                }
            finish(by_id[case_id], result)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    skipped = sorted(set(results) - set(ran))
    return StudyRun(results, ran, skipped, time.perf_counter() - t0, n_workers, path, reused)


def default_study_workers() -> int:
    from cutting.parallel import default_workers

    return default_workers()


def finished(out: Path, case: Case, retry_failed: bool = False) -> dict[str, Any] | None:
    """The stored result of ``case`` if it ran with this very job (same hash), else None (also for a failed case
    when ``retry_failed``: after a fix, or a worker that died)."""
    path = out / "cases" / case.id / "result.json"
    if not path.is_file():
        return None
    try:
        record = json.loads(path.read_text())
    except json.JSONDecodeError:  # cut short while written: run it again
        return None
    if record.get("job_hash") != case.job_hash or (retry_failed and record.get("status") != "ok"):
        return None
    return record


def write_case(out: Path, case: Case, result: dict[str, Any], reused: bool = False) -> dict[str, Any]:
    """cases/<id>/measurement.json and result.json (written last, atomically: a resumed study trusts it);
    ``reused``: the result came from the case store, not from a run of this study."""
    folder = out / "cases" / case.id
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "job.toml").write_text(case.job_text)
    doc = result["measurement"]
    if doc:
        (folder / "measurement.json").write_text(json.dumps(doc, indent=2))
    record = {
        "id": case.id,
        "job_hash": case.job_hash,
        "values": case.values,
        "status": result["status"],
        "error": result["error"],
        "wall_s": result["wall_s"],
        "measured": measured_row(doc),
    }
    if reused:
        record["reused"] = True
    tmp = folder / "result.json.tmp"
    tmp.write_text(json.dumps(record, indent=2))
    tmp.replace(folder / "result.json")
    return record


def csv_columns(study: Study) -> list[str]:
    return ["case", "job_hash", *(v.key for v in study.varies), *MEASURED, "wall_s", "status", "error"]


def write_csv(out: Path, study: Study, cases: Sequence[Case], results: dict[str, dict[str, Any]]) -> Path:
    """results.csv: one row per finished case, in case order (the same file whatever order they finished in)."""
    path = out / "results.csv"
    tmp = out / "results.csv.tmp"
    with tmp.open("w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(csv_columns(study))
        for c in cases:
            r = results.get(c.id)
            if r is None:
                continue
            values = [_cell(r["values"].get(v.key)) for v in study.varies]
            measured = [_cell(r["measured"].get(m)) for m in MEASURED]
            # the message on one line (an input error lists its problems below its head), without a traceback
            error = " ".join(line.strip() for line in r["error"].split("\nTraceback")[0].splitlines())
            writer.writerow([c.id, c.job_hash, *values, *measured, _cell(r["wall_s"]), r["status"], error])
    tmp.replace(path)
    return path


def _cell(v: Any) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, list):
        return json.dumps(v)
    return str(v)
