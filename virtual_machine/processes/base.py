"""The shape every process has: the stages of a job and what each makes.

A process (skiving, thread cutting, form milling, face contours, vibration turning) takes a parsed
:class:`virtual_machine.job.Job` through four stages, each a method that writes its files into ``out`` and
returns a :class:`Product`:

- ``setup``: the setting sheet (no files): what the machine is set to;
- ``simulate``: the machine moves through the job without cutting (where the process has such a run);
- ``cut``: the ideal machine cuts the workpiece, which is measured;
- ``run``: the simulated machine cuts it under its own forces; measured, reported, optionally recorded.

A stage a process does not have raises :class:`cutting.errors.InputError` saying which stage to use instead.
The CLI (`skive setup|simulate|cut|run`) and the Python API (:mod:`virtual_machine.api`) are thin layers over
these methods; :data:`virtual_machine.processes.PROCESSES` finds a job's process by its kind.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cutting.errors import InputError, Problem
from virtual_machine.job import Job
from virtual_machine.output.json_file import json_text
from virtual_machine.output.progress import Reporter


@dataclass
class Product:
    """What a stage made: ``data`` (JSON-ready: the setting sheet, the simulation summary or the measurement
    document), ``text`` (what the CLI prints for it), ``files`` (every file written) and ``out`` (their folder)."""

    stage: str
    data: dict[str, Any]
    text: str
    files: list[Path] = field(default_factory=list)
    out: Path | None = None

    @property
    def measurement(self) -> dict[str, Any]:
        """The measurement document of a cut or run (measurement.json)."""
        if self.stage not in ("cut", "run"):
            raise AttributeError(f"a {self.stage} product has no measurement: cut or run the job")
        return self.data

    @property
    def report_path(self) -> Path | None:
        """The run's report page (report.html), if the stage wrote one."""
        page = self.out / "report.html" if self.out is not None else None
        return page if page is not None and page.is_file() else None

    def json(self) -> str:
        """``data`` as the CLI's --json prints it (no NaN or infinity: null)."""
        return json_text(self.data)


def written(out: Path, *names: str) -> list[Path]:
    """The files of ``names`` (globs allowed) that exist in ``out``."""
    files: list[Path] = []
    for name in names:
        files += sorted(out.glob(name)) if any(c in name for c in "*?[") else [out / name]
    return [f for f in files if f.exists()]


class Process(ABC):
    """One process: the job kind it takes and its four stages. Options a stage does not use are ignored."""

    #: the job kind (virtual_machine.job.Job.kind) this process takes
    kind: str
    #: what it makes, in a few words
    title: str

    def setup(self, job: Job, *, structure: str | None = None) -> Product:
        """The setting sheet. ``structure``: another machine structure than the job's (skiving)."""
        raise self._no("setup", "the job's kind has no setting sheet")

    def simulate(
        self,
        job: Job,
        out: Path,
        *,
        duration: float | None = None,
        rrd: Path | None = None,
        reporter: Reporter | None = None,
    ) -> Product:
        """The machine moves through the job (``duration`` [s] of machine time at most); writes the motion."""
        raise self._no("simulate", "use `skive run`")

    def cut(
        self,
        job: Job,
        out: Path,
        *,
        edge: str | None = None,
        workers: int | None = None,
        trajectory: Path | None = None,
        removal: str = "dexel",
        reporter: Reporter | None = None,
    ) -> Product:
        """The ideal machine (or the motion in ``trajectory``) cuts the workpiece; measured."""
        raise self._no("cut", "use `skive run`")

    @abstractmethod
    def run(
        self,
        job: Job,
        out: Path,
        *,
        rrd: Path | None = None,
        workers: int | None = None,
        removal: str = "dexel",
        reporter: Reporter | None = None,
    ) -> Product:
        """The simulated machine cuts the workpiece under its forces; measured, reported (``rrd``: recorded)."""

    def _no(self, stage: str, hint: str) -> InputError:
        return InputError(Problem("job", self.kind, f"a {self.title} job has no `{stage}` stage", hint))


def reporter_or_default(reporter: Reporter | None) -> Reporter:
    return reporter if reporter is not None else Reporter()
