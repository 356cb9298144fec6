"""The shape every process has: the stages of a job, the options each takes, and what each makes.

A process (skiving, thread cutting, form milling, face contours, vibration turning) takes a parsed
:class:`virtual_machine.job.Job` through the stages it has, each a method that writes its files into ``out`` and
returns a :class:`Product`:

- ``setup``: the setting sheet (no files): what the machine is set to;
- ``simulate``: the machine moves through the job without cutting (where the process has such a run);
- ``cut``: the ideal machine cuts the workpiece, which is measured;
- ``run``: the simulated machine cuts it under its own forces; measured, reported, optionally recorded.

``Process.stages`` declares the stages a process has and the options dataclass of each
(:mod:`virtual_machine.processes.options`). :meth:`Process.perform` is the one entry the CLI, the Python API and
the studies use: it refuses a stage the process lacks and an option its stage does not take (InputError naming
it), and writes the stage's files through a staging folder so that ``out`` only ever holds one run's complete
outputs (:mod:`virtual_machine.output.staging`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any, ClassVar

from cutting.errors import InputError, Problem
from virtual_machine.job import Job
from virtual_machine.output.json_file import json_text
from virtual_machine.output.progress import Reporter
from virtual_machine.output.staging import StagedOutputs
from virtual_machine.processes.options import StageOptions, stage_options

STAGES = ("setup", "simulate", "cut", "run")


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


class Process:
    """One process: the job kind it takes, its stages and their options.

    A subclass sets ``kind``, ``title`` and ``stages`` and implements the stages it lists, each
    ``stage(job, out, options, reporter) -> Product`` (``setup(job, options)``: no files). ``hints`` says, for a
    stage it lacks, what to use instead.
    """

    #: the job kind (virtual_machine.job.Job.kind) this process takes
    kind: ClassVar[str]
    #: what it makes, in a few words
    title: ClassVar[str]
    #: the stages it has and the options dataclass of each
    stages: ClassVar[dict[str, type[StageOptions]]]
    #: for a stage it lacks: what to use instead
    hints: ClassVar[dict[str, str]] = {}

    def options(self, stage: str, given: dict[str, Any] | None = None) -> StageOptions:
        """The stage's options from those ``given`` by name (None: not given); InputError for a stage this process
        lacks or an option its stage does not take."""
        if stage not in self.stages:
            raise self._no(stage)
        return stage_options(self.kind, self.title, stage, self.stages[stage], given or {})

    def takes(self, stage: str, option: str) -> bool:
        """Whether this process's ``stage`` takes ``option``."""
        return stage in self.stages and option in {f.name for f in fields(self.stages[stage])}

    def perform(
        self, stage: str, job: Job, out: Path | None = None, *, reporter: Reporter | None = None, **given: Any
    ) -> Product:
        """Run ``stage`` of ``job`` with the options ``given`` (None: not given), its files written into ``out``
        (a staging folder beside it until the stage is complete; ``setup`` writes none)."""
        options = self.options(stage, given)
        if stage == "setup":
            return self.setup(job, options)
        if out is None:
            raise InputError(Problem("--out", None, f"`{stage}` writes files", "give the folder to write them in"))
        rrd = getattr(options, "rrd", None)
        with StagedOutputs(Path(out), rrd) as staging:
            if rrd is not None:
                options = replace(options, rrd=staging.rrd_staged)
            made = getattr(self, stage)(job, staging.folder, options, reporter)
            data, text, files = staging.publish(made.data, made.text)
        return Product(made.stage, data, text, files, Path(out))

    def setup(self, job: Job, options: StageOptions | None = None) -> Product:
        """The setting sheet."""
        raise self._no("setup")

    def simulate(
        self, job: Job, out: Path, options: StageOptions | None = None, reporter: Reporter | None = None
    ) -> Product:
        """The machine moves through the job; writes the motion."""
        raise self._no("simulate")

    def cut(
        self, job: Job, out: Path, options: StageOptions | None = None, reporter: Reporter | None = None
    ) -> Product:
        """The ideal machine (or a recorded motion) cuts the workpiece; measured."""
        raise self._no("cut")

    def run(
        self, job: Job, out: Path, options: StageOptions | None = None, reporter: Reporter | None = None
    ) -> Product:
        """The simulated machine cuts the workpiece under its forces; measured, reported."""
        raise self._no("run")

    def _no(self, stage: str) -> InputError:
        hint = self.hints.get(stage, "use one of its stages: " + ", ".join(f"`skive {s}`" for s in self.stages))
        return InputError(Problem("job", self.kind, f"a {self.title} job has no `{stage}` stage", hint))

    def _options(self, stage: str, options: StageOptions | None) -> Any:
        """The stage's options as given, or its defaults (a stage called directly, without :meth:`perform`)."""
        return self.stages[stage]() if options is None else options


def run_identity(job: Job, **documents: str) -> dict[str, Any]:
    """What a run's recording is known by (:class:`virtual_machine.output.recorder.Recorder`'s keywords): its own
    recording id, from the job's text and the run's start, and the job text (and any ``documents``, e.g. the setting
    sheet) to read beside it."""
    from virtual_machine.output.recorder import run_recording_id

    source = Path(job.source)
    text = source.read_text(encoding="utf-8") if source.is_file() else f"# job {job.source}: not a file\n"
    return {"recording_id": run_recording_id(text), "documents": {"job": text, **documents}}


def reporter_or_default(reporter: Reporter | None) -> Reporter:
    return reporter if reporter is not None else Reporter()
