"""A thread job (kind "thread") on the lathe of seed 001: [thread], [process], [machine].

[thread] the thread's lead P (mm), hand, major diameter (mm, sets the spindle speed) and threaded length (mm);
[process] the cutting speed at the thread diameter (m/min), the radial infeed passes (mm) and the material.
Its [machine] is the lathe's (head.MACHINE_KEYS; the lathe comes in one size). Like a gear job it may carry
[measurement] and [modification], checked but unused.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from cutting.errors import InputError, Problem
from virtual_machine.job.gear_sections import OPTIONAL_SECTIONS, parse_optional_sections
from virtual_machine.job.head import MACHINE_KEYS, Job, MachineSection, model_problems
from virtual_machine.job.keys import (
    CUTTING_SPEED,
    MATERIAL,
    PASSES,
    REQUIRED,
    Key,
    one_of,
    parse_sections,
    positive,
    section_class,
    unknown_sections,
)

THREAD_KEYS: dict[str, Key] = {
    "lead": Key(float, REQUIRED, "mm", "thread lead P", positive),
    "hand": Key(str, "right", "", "'right' or 'left'", one_of("right", "left")),
    "diameter": Key(float, REQUIRED, "mm", "thread major diameter (sets the spindle speed)", positive),
    "length": Key(float, 30.0, "mm", "threaded length", positive),
}

THREAD_PROCESS_KEYS: dict[str, Key] = {"cutting_speed": CUTTING_SPEED, "passes": PASSES, "material": MATERIAL}

SECTIONS_THREAD = {"thread": THREAD_KEYS, "process": THREAD_PROCESS_KEYS, "machine": MACHINE_KEYS}


ThreadProcess = section_class("ThreadProcess", THREAD_PROCESS_KEYS, "[process] of a thread job.", __name__)


@dataclass(frozen=True)
class ThreadJob(Job):
    """A thread job: [thread] (lead, hand, diameter, length)."""

    kind: ClassVar[str] = "thread"
    thread: dict[str, Any]


def lathe_machine():
    """The default parameters of the lathe of seed 001 (thread and turning jobs)."""
    from machine_models.thread_lathe import ThreadLatheParams

    return ThreadLatheParams()


def lathe_has_one_size(machine: dict[str, Any]) -> list[Problem]:
    """machine.size chooses among the skiving machine's sizes; the lathe of seed 001 has one."""
    if machine.get("size") is None:
        return []
    return [
        Problem(
            "machine.size",
            machine["size"],
            "the lathe of seed 001 (thread and turning jobs) comes in one size",
            "remove machine.size (its parameters are set in [machine.model])",
        )
    ]


def parse_thread_job(data: dict[str, Any], source: str) -> ThreadJob:
    """Validate a thread job. Raises :class:`InputError` with every problem."""
    if "gear" in data:
        raise InputError(
            Problem(
                "thread",
                "[thread] and [gear]",
                "a job describes either a gear or a thread",
                "remove one of the two sections",
            ),
            source,
        )
    problems = unknown_sections(data, (*SECTIONS_THREAD, *OPTIONAL_SECTIONS), SECTIONS_THREAD)
    parsed = parse_sections(data, SECTIONS_THREAD, problems)
    parse_optional_sections(data, problems)
    machine = parsed["machine"]
    problems += model_problems(machine.get("model"), lathe_machine)
    problems += lathe_has_one_size(machine)
    if problems:
        raise InputError(problems, source)
    return ThreadJob(source, MachineSection(**machine), ThreadProcess(**parsed["process"]), parsed["thread"])
