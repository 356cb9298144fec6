"""The options a process's stage takes, declared as dataclasses: one per stage and process.

A process lists its stages and their option classes (``Process.stages``); the command line and the API hand the
options the user gave by name, and :func:`stage_options` makes the stage's dataclass of them. An option the stage
does not take is an input error naming the option, the job kind and what the stage does take, instead of being
ignored (``--removal manifold`` on a turning job used to run as if it had not been said).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from cutting.errors import InputError, Problem
from cutting.skiving.edge import EDGE_KINDS
from virtual_machine.job import Job, with_machine


@dataclass(frozen=True)
class StageOptions:
    """Options of a stage that takes none."""


@dataclass(frozen=True)
class SheetOptions(StageOptions):
    """A setting sheet of another machine structure than the job's (skiving, thread cutting)."""

    structure: str | None = None


@dataclass(frozen=True)
class SkivingSheetOptions(SheetOptions):
    """The skiving setting sheet; ``balance_passes``: also propose radial increments that give every pass the same
    largest uncut chip (:func:`cutting.skiving.pass_balance.balance_passes`)."""

    balance_passes: bool = False


@dataclass(frozen=True)
class RecordedOptions(StageOptions):
    """A stage that can write a Rerun recording (``rrd``: its path)."""

    rrd: Path | None = None


@dataclass(frozen=True)
class MachineSimulateOptions(RecordedOptions):
    """The machine through the job without cutting: ``duration`` [s] of machine time at most, and [machine] keys
    replacing the job's (structure, synchronization, adaptive correction)."""

    duration: float | None = None
    structure: str | None = None
    synchronization: str | None = None
    adaptive_correction: bool | None = None

    def machine_of(self, job: Job) -> Job:
        """``job`` with the [machine] keys these options replace."""
        return with_machine(
            job,
            structure=self.structure,
            synchronization=self.synchronization,
            adaptive_correction=self.adaptive_correction,
        )


@dataclass(frozen=True)
class SkivingCutOptions(StageOptions):
    """The ideal (or a recorded) motion cuts the gear: the cutter's ``edge``, the manifold removal's ``workers``, a
    ``trajectory`` file of `skive simulate` to cut along, the ``removal`` ("dexel" or "manifold") and the mesh's
    ``mesh_tolerance`` [um]."""

    edge: str | None = None
    workers: int | None = None
    trajectory: Path | None = None
    removal: str = "dexel"
    mesh_tolerance: float | None = None


@dataclass(frozen=True)
class SkivingRunOptions(RecordedOptions):
    """The simulated machine cuts the gear: the manifold removal's ``workers``, the ``removal``, the mesh's
    ``mesh_tolerance`` [um] and ``view``, a Rerun viewer's address to stream the run to."""

    workers: int | None = None
    removal: str = "dexel"
    mesh_tolerance: float | None = None
    view: str | None = None


REMOVALS = ("dexel", "manifold")
#: where a Rerun viewer started with no arguments (`rerun`) listens for recordings (`skive run --view`)
DEFAULT_VIEWER = "rerun+http://127.0.0.1:9876/proxy"


def option_flag(name: str) -> str:
    """The command-line spelling of an option."""
    return "--" + name.replace("_", "-")


def stage_options(kind: str, title: str, stage: str, cls: type[StageOptions], given: dict[str, Any]) -> StageOptions:
    """The stage's options made from ``given`` (None values: not given). An option ``cls`` does not declare is an
    InputError naming it, the job kind and the options the stage takes."""
    names = [f.name for f in fields(cls)]
    taken = {k: v for k, v in given.items() if v is not None}
    problems = [
        Problem(
            option_flag(k),
            v,
            f"a {title} job's `{stage}` does not take this option (job kind {kind!r})",
            f"leave it out; `{stage}` takes " + (", ".join(option_flag(n) for n in names) if names else "no options"),
        )
        for k, v in taken.items()
        if k not in names
    ]
    problems += _value_problems(taken)
    if problems:
        raise InputError(problems)
    return cls(**taken)


def _value_problems(taken: dict[str, Any]) -> list[Problem]:
    """The options' values that no stage takes."""
    out = []
    if taken.get("removal") not in (None, *REMOVALS):
        out.append(Problem("--removal", taken["removal"], "unknown removal", "use 'dexel' or 'manifold'"))
    if taken.get("edge") not in (None, *EDGE_KINDS):
        out.append(Problem("--edge", taken["edge"], "unknown edge", "use 'conjugate' or 'involute'"))
    tol = taken.get("mesh_tolerance")
    if tol is not None and not tol > 0:
        out.append(Problem("--mesh-tolerance", tol, "must be positive", "give micrometres > 0"))
    workers = taken.get("workers")
    if workers is not None and not (isinstance(workers, int) and workers >= 1):
        out.append(Problem("--workers", workers, "must be a whole number >= 1", "e.g. --workers 2"))
    duration = taken.get("duration")
    if duration is not None and not duration > 0:
        out.append(Problem("--duration", duration, "must be positive", "give seconds of machine time > 0"))
    return out
