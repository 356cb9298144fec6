"""Whole-machine runs that several test files share in one pytest session (the ``shared_runs`` fixture).

A job file is run once per session as a study case runs it (``virtual_machine.studies.runner.run_case``: `skive run`
with one removal process, measured on the exact swept surface of the motion the machine made), and kept in the
session's case store (``virtual_machine.studies.cache``): test_scenarios.py reads the result and the machine's motion
record, and the studies of test_study.py take the same run from the store as a case instead of running it again.
The two files run in different processes (``--dist loadfile``), so a run is made under a file lock: whoever asks
first runs it, the other waits for it and reads it.
"""

from __future__ import annotations

import contextlib
import fcntl
import pickle
from pathlib import Path
from typing import TYPE_CHECKING, Any
from unittest import mock

from virtual_machine.studies.cache import CaseCache, content_key

if TYPE_CHECKING:
    from virtual_machine.runtime.machine_run import MotionRecord


@contextlib.contextmanager
def _locked(path: Path):
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("a") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


class SharedRuns:
    """The session's shared machine runs under ``root`` (one directory for all the session's processes)."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.cache = CaseCache(root / "cases")

    def run(self, job_file: Path) -> tuple[dict[str, Any], MotionRecord]:
        """The job's run as a study case: (result: status, error, wall_s, measurement; the motion record)."""
        text = Path(job_file).read_text()
        key = content_key(text)
        records = self.root / "records" / f"{key}.pkl"
        with _locked(self.root / "locks" / f"{key}.lock"):
            result = self.cache.get(text)
            if result is not None and records.is_file():
                return result, pickle.loads(records.read_bytes())
            result, record = _run_case(Path(job_file).stem, text)
            records.parent.mkdir(parents=True, exist_ok=True)
            records.write_bytes(pickle.dumps(record))
            assert self.cache.put(text, result)
            return result, record


def _run_case(name: str, text: str) -> tuple[dict[str, Any], MotionRecord]:
    """``run_case`` of the job, keeping the motion record of the co-simulation `skive run` made."""
    import virtual_machine.processes.skiving.run as run_module
    from virtual_machine.processes.skiving import machine_added
    from virtual_machine.studies.runner import run_case

    made = []
    cosimulate = run_module.cosimulate

    def keep(*args, **kwargs):
        sim = cosimulate(*args, **kwargs)
        made.append(sim)
        return sim

    # as in a study's worker, where `skive run` makes no ideal-cut reference beside the run (machine_added.py: the
    # study compares its cases itself; 3-5 s of CPU a run here, which no test reads)
    with (
        mock.patch.object(run_module, "cosimulate", keep),
        mock.patch.object(machine_added, "_in_worker", return_value=True),
    ):
        result = run_case(name, text)
    assert result["status"] == "ok", result["error"]
    (sim,) = made
    return result, sim.record
