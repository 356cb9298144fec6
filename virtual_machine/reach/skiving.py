"""Whether a skiving job is within its machine's reach: the workpiece and the module it takes, the tool spindle's
and the table's top speeds and the carriage's travel (machine_models/parameters.py: ``workpiece_diameter_limit``,
``module_limit``, ``tool_speed_limit``, ``work_speed_limit``, ``carriage_travel``; each size has its own,
machine_models/sizes.py). A machine's data sheet bounds the workpiece and module it takes, and its CNC refuses a
spindle speed above its limit and a stroke beyond its travel; so does skive, before the run, naming the limit, what
the job needs, and what would hold it. The motors' torque is the other check (:mod:`.skiving_load`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from cutting.errors import MachineLimitError, Problem
from machine_models.parameters import RPM, SkivingMachineParams, override
from machine_models.sizes import SIZE_NAMES, size_params
from virtual_machine.job import Job, flatten_model
from virtual_machine.output.formatting import three_figures
from virtual_machine.setting.machine_layout import workpiece_diameter


@dataclass(frozen=True)
class Reach:
    """One limit of the machine against what the job needs of it."""

    key: str  # the SkivingMachineParams field ([machine.model] key)
    what: str  # the machine element, as the message names it
    need: float  # what the job needs, in the field's units (rad/s, m)
    limit: float
    show: Callable[[float], str]  # the figure as an engineer reads it (rpm, mm)
    unit: str  # the field's unit

    @property
    def holds(self) -> bool:
        return self.need <= self.limit


def _rpm(v: float) -> str:
    return f"{three_figures(v / RPM)} rpm"


def _mm(v: float) -> str:
    return f"{three_figures(v * 1e3)} mm"


def _module(v: float) -> str:
    return f"{v * 1e3:.3g} mm"


def machine_reach(job: Job, params: SkivingMachineParams) -> list[Reach]:
    """What the job needs of the machine (workpiece, module, spindle speeds, travel), against ``params``' limits."""
    setup = job.skiving
    tool = setup.tool_speed * RPM
    feed = setup.axial_feed * setup.work_speed / 60.0  # mm/s of the carriage
    # the table turns at the generating ratio, plus the helix's differential turn along the feed
    work = abs(setup.speed_ratio) * tool + abs(setup.differential_rotation_per_mm) * feed
    stroke = max(setup.pass_travel) * 1e-3
    return [
        Reach(
            "workpiece_diameter_limit",
            "work spindle B2",
            workpiece_diameter(job.gear) * 1e-3,
            params.workpiece_diameter_limit,
            _mm,
            "m",
        ),
        Reach("module_limit", "tool spindle B1", job.gear.mn * 1e-3, params.module_limit, _module, "m"),
        Reach("tool_speed_limit", "tool spindle B1", tool, params.tool_speed_limit, _rpm, "rad/s"),
        Reach("work_speed_limit", "table (work spindle B2)", work, params.work_speed_limit, _rpm, "rad/s"),
        Reach("carriage_travel", "carriage P3", stroke, params.carriage_travel, _mm, "m"),
    ]


def check_skiving_reach(job: Job, params: SkivingMachineParams, size: str) -> list[Reach]:
    """Refuse (MachineLimitError) a job that needs more than the machine ``params`` (of size ``size``) can give: a
    spindle speed above its top speed, a pass's stroke beyond the carriage's travel. Returns the reach when it
    holds."""
    reach = machine_reach(job, params)
    bad = [r for r in reach if not r.holds]
    if not bad:
        return reach
    model = flatten_model(job.machine.model)
    chosen = "machine.size" if job.machine.size else "the default size for this gear"
    problems = []
    # a larger size that reaches all of it (its spindles turn slower: it may trade one limit for another)
    larger = next(
        (
            name
            for name in SIZE_NAMES[SIZE_NAMES.index(size) + 1 :]
            if all(r.holds for r in machine_reach(job, override(size_params(name), model)))
        ),
        None,
    )
    for r in bad:
        if r.key == "workpiece_diameter_limit":
            what = f"the workpiece's {r.show(r.need)} diameter exceeds what it takes, {r.show(r.limit)}"
            less = "a smaller gear"
        elif r.key == "module_limit":
            what = f"the gear's module {r.show(r.need)} exceeds what it is built for, {r.show(r.limit)}"
            less = "a smaller gear.normal_module"
        elif r.key == "carriage_travel":
            what = (
                f"a pass's stroke (the face, the cutter's run-in and run-out) of {r.show(r.need)} exceeds the "
                f"travel {r.show(r.limit)}"
            )
            less = "a narrower gear.face_width"
        else:
            what = f"the job turns it at {r.show(r.need)}, above its top speed {r.show(r.limit)}"
            less = "a lower process.tool_speed"
        bigger = f'machine.size = "{larger}", or ' if larger else ""
        problems.append(
            Problem(
                "machine.size",
                size,
                f"the {r.what} of the {size} machine ({chosen}) cannot do it: {what} (machine.model.{r.key} = "
                f"{r.limit:g} {r.unit})",
                f"use {bigger}{less}, or machine.model.{r.key} >= {r.need:.3g} ({r.unit}) if the real machine has it"
                + ("" if larger else " (no larger machine size reaches it)"),
            )
        )
    raise MachineLimitError(problems, job.source)
