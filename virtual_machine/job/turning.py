"""A turning job (kind "turning", vibration turning of seed 004) on the lathe of seed 001: [turning], an optional
[vibration], [process], [machine].

[turning] the workpiece diameter before the cut (mm, sets the spindle speed), the turned length (mm), the feed S0
(mm/rev), the tool's nose radius and the depth of cut (mm). [vibration] the axial feed vibration: its amplitude A
(mm), cycles per spindle revolution, asymmetry xi = T_in / T_out and form ('soft' or 'hard'). [process] the cutting
speed (m/min), the material, the revolutions cut and measured, and the turned surface's chord error (mm). The lathe
is set up as for a thread whose lead is the feed S0 (right hand: the carriage feeds towards the chuck); a vibration
needs its mechatronic master-slave chain.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

from cutting.errors import InputError, Problem
from virtual_machine.job.head import MACHINE_KEYS, Job, MachineSection, model_problems
from virtual_machine.job.keys import (
    CUTTING_SPEED,
    MATERIAL,
    REQUIRED,
    Key,
    at_least,
    one_of,
    parse_section,
    parse_sections,
    positive,
    section_class,
    unknown_sections,
)
from virtual_machine.job.thread import lathe_has_one_size, lathe_machine

if TYPE_CHECKING:
    from cutting.turning.vibration import FeedVibration

TURNING_KEYS: dict[str, Key] = {
    "diameter": Key(float, REQUIRED, "mm", "workpiece diameter before the cut (sets the spindle speed)", positive),
    "length": Key(float, 10.0, "mm", "turned length", positive),
    "feed": Key(float, REQUIRED, "mm/rev", "feed per revolution S0", positive),
    "nose_radius": Key(float, 0.8, "mm", "tool nose radius r_eps", positive),
    "depth": Key(float, 0.3, "mm", "depth of cut a_p (less than the nose radius)", positive),
}

VIBRATION_KEYS: dict[str, Key] = {
    "amplitude": Key(float, REQUIRED, "mm", "axial amplitude A of the feed vibration (seed 004)", at_least(0.0)),
    "cycles_per_rev": Key(
        float, REQUIRED, "", "vibration cycles per spindle revolution (a fraction shifts them)", positive
    ),
    "xi": Key(float, 1.0, "", "asymmetry xi = T_in / T_out (1: symmetric vibration)", positive),
    "form": Key(str, "soft", "", "'soft' (half cosines) or 'hard' (straight strokes)", one_of("soft", "hard")),
}

TURNING_PROCESS_KEYS: dict[str, Key] = {
    "cutting_speed": CUTTING_SPEED,
    "material": MATERIAL,
    "revolutions": Key(int, 40, "", "revolutions cut and measured (after the run-up)", at_least(8)),
    "sweep_error": Key(float, 0.001, "mm", "chord error of the turned surface's manifold solid", positive),
}

SECTIONS_TURNING = {"turning": TURNING_KEYS, "process": TURNING_PROCESS_KEYS, "machine": MACHINE_KEYS}


TurningProcess = section_class(
    "TurningProcess",
    TURNING_PROCESS_KEYS,
    "[process] of a turning job (TURNING_PROCESS_KEYS), with ``passes``: the depth of cut as the lathe's one pass.",
    __name__,
    {"passes": list},
)


@dataclass(frozen=True)
class TurningJob(Job):
    """A turning job: [turning], the lathe's feed as a thread (lead S0, right hand, the diameter and length) and the
    feed vibration (None: plain turning)."""

    kind: ClassVar[str] = "turning"
    thread: dict[str, Any]
    turning: dict[str, Any]
    vibration: FeedVibration | None = None


def parse_turning_job(data: dict[str, Any], source: str) -> TurningJob:
    """Validate a turning job. Raises :class:`InputError` with every problem."""
    listed = (*SECTIONS_TURNING, "vibration")
    problems = unknown_sections(data, listed, listed)
    parsed = parse_sections(data, SECTIONS_TURNING, problems)
    machine = parsed["machine"]
    problems += model_problems(machine.get("model"), lathe_machine) + lathe_has_one_size(machine)
    vib_values = (
        parse_section("vibration", data["vibration"], VIBRATION_KEYS, problems) if "vibration" in data else None
    )
    t = parsed["turning"]
    vibration = None
    if not problems:
        from cutting.turning.vibration import FeedVibration, TurningSetup

        try:
            if vib_values is not None:
                vibration = FeedVibration(
                    vib_values["amplitude"], vib_values["cycles_per_rev"], vib_values["xi"], vib_values["form"]
                )
            TurningSetup(t["diameter"] / 2, t["feed"], t["nose_radius"], t["depth"], vibration)
        except ValueError as exc:
            field = str(exc).split()[0]
            section = "vibration" if field in VIBRATION_KEYS else "turning"
            value = (vib_values if section == "vibration" else t).get(field, "")
            problems.append(Problem(f"{section}.{field}", value, str(exc), "see docs/face-contours-and-turning.md"))
        if vibration is not None and (machine["structure"], machine["synchronization"]) != (
            "mechatronic",
            "master-slave",
        ):
            problems.append(
                Problem(
                    "machine.synchronization",
                    machine["synchronization"],
                    "vibration turning needs the feed axis to follow the spindle's encoder",
                    "set structure = 'mechatronic' and synchronization = 'master-slave'",
                )
            )
    if problems:
        raise InputError(problems, source)
    thread = {"lead": t["feed"], "hand": "right", "diameter": t["diameter"], "length": t["length"]}
    process = TurningProcess(**parsed["process"], passes=[t["depth"]])
    return TurningJob(source, MachineSection(**machine), process, thread, t, vibration)
