"""The plan of a skiving job: what its stages share, computed once and handed on.

A skiving run builds the machine (its layout starts at the first pass's centre distance), programs the CNC (the
passes' strokes), cuts along the passes and reports the setting sheet. Each of these used to recompute the ideal
passes and the sheet from the job; a :class:`SkivingPlan` is made once per stage chain (``skive run``, ``skive cut``,
``skive simulate``) and every step takes it:

- ``setup``: the cut's kinematics (:class:`cutting.skiving.kinematics.SkivingSetup`);
- ``passes``: the ideal motion of every pass (:func:`cutting.skiving.trajectory.ideal_passes`);
- ``sheet(structure)``: the machine setting sheet (seed 000, S1-S4) of a structure, made on first use.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.trajectory import PassMotion, ideal_passes
from virtual_machine.job import Job
from virtual_machine.setting.sheet import SetupSheet, setup_sheet


@dataclass(frozen=True)
class SkivingPlan:
    """A skiving job's setup, ideal passes and setting sheets (one per structure asked for)."""

    job: Job
    setup: SkivingSetup
    passes: tuple[PassMotion, ...]
    _sheets: dict[str, SetupSheet] = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def of(cls, job: Job) -> SkivingPlan:
        """The plan of ``job`` (a skiving job: others have no ``skiving`` setup)."""
        setup = job.skiving
        return cls(job, setup, tuple(ideal_passes(setup)))

    def sheet(self, structure: str | None = None) -> SetupSheet:
        """The setting sheet for ``structure`` (default: the job's [machine] structure), made once."""
        key = structure or self.job.machine.structure
        if key not in self._sheets:
            self._sheets[key] = setup_sheet(self.job, key)
        return self._sheets[key]


def plan_of(job: Job, plan: SkivingPlan | None) -> SkivingPlan:
    """``plan`` if a previous stage handed one on (it must be ``job``'s), else the job's own."""
    if plan is None:
        return SkivingPlan.of(job)
    if plan.job is not job:
        raise ValueError("the plan handed on was made for another job: make it with SkivingPlan.of(job)")
    return plan
