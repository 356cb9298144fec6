"""Every process skive runs, by the job kind it takes: one registry for the CLI, the API and the studies.

A new process is a subclass of :class:`Process` in a module here and one line in :data:`PROCESSES`.
"""

from __future__ import annotations

from cutting.errors import InputError, Problem
from virtual_machine.job import Job
from virtual_machine.processes.base import Process, Product
from virtual_machine.processes.face_contour import FaceContour
from virtual_machine.processes.form_milling import FormMilling
from virtual_machine.processes.skiving import Skiving
from virtual_machine.processes.thread import ThreadCutting
from virtual_machine.processes.turning import VibrationTurning

#: the processes by job kind (virtual_machine.job.Job.kind)
PROCESSES: dict[str, Process] = {
    p.kind: p for p in (Skiving(), ThreadCutting(), FormMilling(), FaceContour(), VibrationTurning())
}


def process_for(job: Job) -> Process:
    """The process that takes ``job``."""
    try:
        return PROCESSES[job.kind]
    except KeyError:
        raise InputError(
            Problem("job", job.kind, "no process takes this kind of job", f"one of {', '.join(PROCESSES)}"),
            job.source,
        ) from None


__all__ = ["PROCESSES", "Process", "Product", "process_for"]
