"""The job kinds: which section marks a job of each kind, and the kind's parser.

A job file is read by :func:`load_job` and checked by :func:`parse_job`, which hands it to its kind's parser
(one module per kind). A new process adds its parser's module and one line to :data:`KINDS`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from virtual_machine.job import face_contour, form_milling, skiving, thread, turning
from virtual_machine.job.head import Job, read_toml


@dataclass(frozen=True)
class JobKind:
    """A kind of job: the section whose presence marks it (None: a job marked by none of the others) and its
    parser, ``parse(data, source) -> Job`` (raises InputError with every problem)."""

    section: str | None
    parse: Callable[[dict[str, Any], str], Job]


#: the job kinds (virtual_machine.job.Job.kind) in the order their sections are looked for
KINDS: dict[str, JobKind] = {
    "form_milling": JobKind("mill", form_milling.parse_form_milling_job),
    "turning": JobKind("turning", turning.parse_turning_job),
    "face_contour": JobKind("coupling", face_contour.parse_face_contour_job),
    "thread": JobKind("thread", thread.parse_thread_job),
    "skiving": JobKind(None, skiving.parse_skiving_job),
}
#: the kinds whose workpiece is a gear with an ISO 1328-1 class (`skive check`, the studies' error budget)
GRADED = ("skiving", "form_milling")
#: the kind of a job that none of the sections of KINDS marks
UNMARKED_KIND = "skiving"


def job_kind(data: dict[str, Any]) -> str:
    """The kind of a job (as read from TOML): the first of :data:`KINDS` whose section it has."""
    marked = (k for k, kind in KINDS.items() if kind.section is not None and kind.section in data)
    return next(marked, UNMARKED_KIND)


def parse_job(data: dict[str, Any], source: str = "<job>") -> Job:
    """Validate a job given as a dict (as read from TOML). Raises :class:`InputError` with every problem."""
    return KINDS[job_kind(data)].parse(data, source)


def load_job(path: str | Path) -> Job:
    """Read and validate a TOML job file."""
    return parse_job(read_toml(path), str(path))
