"""A store of finished cases that studies share: a case whose job has run before (in another study, or by whoever
filled the store) is taken from it instead of run again.

The store is a directory (a study file's ``cache = "DIR"``, relative to the study file, or ``pipeline.run(...,
cache=DIR)``) of ``<key>.json`` files, each the result a study worker returns for a case (status, error, wall time,
measurement document: see :func:`virtual_machine.studies.runner.run_case`) with the job it ran. The key is the
sha256 of skive's version (:func:`virtual_machine.version.skive_version`: its release and the fingerprint of its code
and data) and the job's content (:func:`job_content`: the keys and values, whatever their order, comments or layout),
so a one-at-a-time study's base case and the base job run by another study, or the job file itself, share an entry,
and a result of other code is never served: after an upgrade, or any change to the code, the case runs again.
Only cases that finished ("ok") are stored: a failure may be the worker's, not the job's. An entry is written
atomically (a reader never sees half of it), so studies on several machines may share one directory.
"""

from __future__ import annotations

import hashlib
import json
import os
import tomllib
from pathlib import Path
from typing import Any

import tomli_w

from virtual_machine.version import skive_version


def job_content(job_text: str) -> str:
    """The job's canonical TOML: its tables and keys sorted, comments and layout gone."""

    def ordered(node: Any) -> Any:
        if isinstance(node, dict):
            return {k: ordered(node[k]) for k in sorted(node)}
        if isinstance(node, list):
            return [ordered(v) for v in node]
        return node

    return tomli_w.dumps(ordered(tomllib.loads(job_text)))


def content_key(job_text: str, version: str | None = None, stage: str = "run") -> str:
    """The store's key of a job run by skive ``version`` (default: this one): the sha256 of the version and the
    job's canonical content (and of the stage, for a case that is not a `skive run`: a cut and a run of one job are
    two results)."""
    version = skive_version() if version is None else version
    head = version if stage == "run" else f"{version}\nstage {stage}"
    return hashlib.sha256(f"{head}\n{job_content(job_text)}".encode()).hexdigest()


class CaseCache:
    """The finished cases in ``directory`` (created when the first case is stored) that skive ``version`` (default:
    this one) made."""

    def __init__(self, directory: str | Path, version: str | None = None) -> None:
        self.directory = Path(directory)
        self.version = skive_version() if version is None else version

    def path(self, job_text: str, stage: str = "run") -> Path:
        return self.directory / f"{content_key(job_text, self.version, stage)}.json"

    def get(self, job_text: str, stage: str = "run") -> dict[str, Any] | None:
        """The stored result of this job's ``stage`` (status, error, wall_s, measurement), or None."""
        path = self.path(job_text, stage)
        try:
            entry = json.loads(path.read_text())
        except (FileNotFoundError, json.JSONDecodeError):
            return None
        result = entry.get("result")
        if entry.get("key") != path.stem or entry.get("version") != self.version:
            return None
        if not isinstance(result, dict) or result.get("status") != "ok":
            return None
        return result

    def put(self, job_text: str, result: dict[str, Any], stage: str = "run") -> bool:
        """Store a finished case's result of ``stage`` (a failed one is not stored: returns False)."""
        if result.get("status") != "ok":
            return False
        self.directory.mkdir(parents=True, exist_ok=True)
        path = self.path(job_text, stage)
        kept = {k: result[k] for k in ("status", "error", "wall_s", "measurement")}
        entry = {"key": path.stem, "version": self.version, "job": job_content(job_text), "result": kept}
        tmp = path.with_name(f"{path.stem}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps(entry))
        tmp.replace(path)
        return True

    def __len__(self) -> int:
        return len(list(self.directory.glob("*.json"))) if self.directory.is_dir() else 0
