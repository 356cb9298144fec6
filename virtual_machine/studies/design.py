"""The cases of a study: each a complete job (the base job with the varied keys set), checked by the job schema
before any case runs, and named by its position in the design and the hash of its job text.

- one-at-a-time: the base job (case c000), then each part's values in turn with every other part at its base;
  a value equal to the base is the base case and is not run twice;
- grid: every combination (full factorial), in the order of the [[vary]] tables;
- monte-carlo: ``samples`` draws from numpy's PCG64 seeded with ``seed``, part by part in the order of the
  [[vary]] tables, so the same study file gives the same cases on any machine and with any number of workers;
- a case with every part at its base value is the base job itself (its keys as the base job has them, written
  there or left at their defaults: the same content, so a case store shares it with any other run of that job);
  in any other case every varied key is written.
"""

from __future__ import annotations

import hashlib
import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np
import tomli_w

from cutting.errors import InputError, Problem
from virtual_machine.job import parse_job
from virtual_machine.studies.spec import Study, Vary, set_key, typed


@dataclass(frozen=True)
class Case:
    """One run of the study: its id, the value of each varied key, and the job it runs (as TOML text)."""

    id: str
    values: dict[str, Any]
    job_text: str

    @property
    def job_hash(self) -> str:
        return job_hash(self.job_text)


def job_hash(text: str) -> str:
    """The sha256 of a job's text: what `skive run` records as run.job.sha256, and how a resumed study knows a
    case it has already run."""
    return hashlib.sha256(text.encode()).hexdigest()


def design(study: Study) -> list[dict[str, Any]]:
    """The varied values of every case, in the design's order."""
    varies = study.varies
    base = {v.key: v.base for v in varies}
    if study.method == "one-at-a-time":
        rows = [dict(base)]
        for v in varies:
            rows += [{**base, v.key: x} for x in v.values or () if not _same(x, v.base)]
        return rows
    if study.method == "grid":
        return [
            dict(zip([v.key for v in varies], combo, strict=True))
            for combo in itertools.product(*[v.values or () for v in varies])
        ]
    rng = np.random.default_rng(study.seed)
    draws = {v.key: _draw(v, rng, study.samples) for v in varies}
    return [{v.key: draws[v.key][i] for v in varies} for i in range(study.samples)]


def _draw(v: Vary, rng: np.random.Generator, n: int) -> list[Any]:
    if v.distribution == "normal":
        x = rng.normal(v.mean, v.std, n)
    elif v.distribution == "uniform":
        x = rng.uniform(v.lo, v.hi, n)
    else:
        picks = rng.integers(0, len(v.values or ()), n)
        return [v.values[int(i)] for i in picks]
    return [typed(float(a), v.base) for a in x]


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, int | float) and isinstance(b, int | float) and not isinstance(a, bool):
        return float(a) == float(b)
    return a == b


def cases(study: Study) -> list[Case]:
    """Every case as a job, each parsed by the job schema: InputError names the case, the key and why, before
    anything runs."""
    rows = design(study)
    width = max(3, len(str(len(rows))))
    out, problems = [], []
    start = 0 if study.method == "one-at-a-time" else 1  # c000 is the base case
    base = {v.key: v.base for v in study.varies}
    for i, values in enumerate(rows):
        case_id = f"c{i + start:0{width}d}"
        data = study.base_data
        if any(not _same(value, base[key]) for key, value in values.items()):  # else: the base job itself
            for key, value in values.items():
                data = set_key(data, key, value)
        text = tomli_w.dumps(data)
        try:
            parse_job(data, f"{study.path} case {case_id}")
        except InputError as exc:
            for p in exc.problems:
                varied = p.key in values or p.key.startswith("machine.model")
                problems.append(
                    Problem(p.key, p.value, f"case {case_id} ({_case_text(values)}): {p.reason}", p.hint)
                    if varied
                    else p
                )
            continue
        out.append(Case(case_id, values, text))
    if problems:
        raise InputError(_unique(problems), str(study.path))
    return out


def _case_text(values: dict[str, Any]) -> str:
    return ", ".join(f"{k} = {v!r}" for k, v in values.items())


def _unique(problems: list[Problem]) -> list[Problem]:
    seen, out = set(), []
    for p in problems:
        if str(p) not in seen:
            seen.add(str(p))
            out.append(p)
    return out
