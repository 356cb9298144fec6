"""A store of finished cases that studies share: a case whose job has run before (in another study, or by whoever
filled the store) is taken from it instead of run again.

The store is a directory (a study file's ``cache = "DIR"``, relative to the study file, or ``pipeline.run(...,
cache=DIR)``) of ``<key>.json`` files, each the result a study worker returns for a case (status, error, wall time,
measurement document: see :func:`virtual_machine.studies.runner.run_case`) with the job it ran. The key is the
sha256 of the job's content (:func:`job_content`: the keys and values, whatever their order, comments or layout), so
a one-at-a-time study's base case and the base job run by another study, or the job file itself, share an entry.
Only cases that finished ("ok") are stored: a failure may be the worker's, not the job's. An entry is written
atomically (a reader never sees half of it), so studies on several machines may share one directory.

Like a resumed study's finished cases, the entries are trusted: empty the directory after changing skive.
"""

from __future__ import annotations

import hashlib
import json
import os
import tomllib
from pathlib import Path
from typing import Any

import tomli_w


def job_content(job_text: str) -> str:
    """The job's canonical TOML: its tables and keys sorted, comments and layout gone."""

    def ordered(node: Any) -> Any:
        if isinstance(node, dict):
            return {k: ordered(node[k]) for k in sorted(node)}
        if isinstance(node, list):
            return [ordered(v) for v in node]
        return node

    return tomli_w.dumps(ordered(tomllib.loads(job_text)))


def content_key(job_text: str) -> str:
    """The store's key of a job: the sha256 of its canonical content."""
    return hashlib.sha256(job_content(job_text).encode()).hexdigest()


class CaseCache:
    """The finished cases in ``directory`` (created when the first case is stored)."""

    def __init__(self, directory: str | Path) -> None:
        self.directory = Path(directory)

    def path(self, job_text: str) -> Path:
        return self.directory / f"{content_key(job_text)}.json"

    def get(self, job_text: str) -> dict[str, Any] | None:
        """The stored result of this job (status, error, wall_s, measurement), or None."""
        path = self.path(job_text)
        try:
            entry = json.loads(path.read_text())
        except (FileNotFoundError, json.JSONDecodeError):
            return None
        result = entry.get("result")
        if entry.get("key") != path.stem or not isinstance(result, dict) or result.get("status") != "ok":
            return None
        return result

    def put(self, job_text: str, result: dict[str, Any]) -> bool:
        """Store a finished case's result (a failed one is not stored: returns False)."""
        if result.get("status") != "ok":
            return False
        self.directory.mkdir(parents=True, exist_ok=True)
        path = self.path(job_text)
        kept = {k: result[k] for k in ("status", "error", "wall_s", "measurement")}
        entry = {"key": path.stem, "job": job_content(job_text), "result": kept}
        tmp = path.with_name(f"{path.stem}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps(entry))
        tmp.replace(path)
        return True

    def __len__(self) -> int:
        return len(list(self.directory.glob("*.json"))) if self.directory.is_dir() else 0
