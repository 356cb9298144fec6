"""A form-milling job (kind "form_milling", the copying method of seed 003): [gear], [mill], [process], [machine],
and optionally [measurement] and [modification] (virtual_machine.job.gear_sections).

[mill] the profiled disc mill: its outer diameter (mm), teeth, and its clearance in the tooth space (mm; one pass
per flank). [process] the table feed (mm/min), the mill speed (rpm), the path points per half face width, the runs of
the accuracy check on the machine, the material, and the tolerances of the swept volumes and gear.stl (mm).
Its [machine] only overrides the form-milling machine's model ([machine.model]). The gear must be one the copying
method can make (external spur), the mill must fit its tooth space.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from cutting.errors import InputError, Problem
from cutting.form_milling import PATH_FORMS
from cutting.gear import Gear, check_gear
from cutting.modification import Modification, design_problems
from virtual_machine.job.gear_sections import GEAR_KEYS, OPTIONAL_SECTIONS, gear_from, parse_optional_sections
from virtual_machine.job.head import MODEL_ONLY_MACHINE_KEYS, Job, model_problems
from virtual_machine.job.keys import (
    MATERIAL,
    REQUIRED,
    STL_TOLERANCE,
    Key,
    at_least,
    one_of,
    parse_sections,
    positive,
    unknown_sections,
)

MILL_KEYS: dict[str, Key] = {
    "diameter": Key(
        float, REQUIRED, "mm", "outer diameter of the profiled disc mill (copying method, seed 003)", positive
    ),
    "teeth": Key(int, 12, "", "teeth of the mill (feed per tooth)", at_least(1)),
    "clearance": Key(
        float, 0.2, "mm", "the mill is this much narrower than the tooth space: one pass per flank", positive
    ),
}

FORM_PROCESS_KEYS: dict[str, Key] = {
    "feed": Key(float, 300.0, "mm/min", "table feed of the mill along the face", positive),
    "mill_speed": Key(float, 250.0, "rpm", "mill spindle speed", positive),
    "path_points": Key(int, 10, "", "path points n per half face width (seed 003: z_i = i b / (2 n))", at_least(2)),
    "path_form": Key(
        str,
        "spline",
        "",
        "the path through its points: 'spline' (C2, one cubic Bezier per interval) or 'bezier' (the seed's single "
        "cubic Bezier over the face, eq. 17)",
        one_of(*PATH_FORMS),
    ),
    "mill_axis": Key(
        str,
        "turned",
        "",
        "'turned': the mill's axis follows the path's transfer angles (seed 003, eq. 6; the machine's swivel head B "
        "and table A); 'fixed': the axis stays tangential (the accuracy check's corrections make up for it)",
        one_of("turned", "fixed"),
    ),
    "machine_iterations": Key(
        int, 2, "", "runs of the accuracy check on the simulated machine (1: the planned path only)", at_least(1)
    ),
    "material": MATERIAL,
    "sweep_error": Key(float, 0.005, "mm", "chord error allowed in the mill's swept volumes (gear.stl)", positive),
    "stl_tolerance": STL_TOLERANCE,
}

SECTIONS_FORM = {"gear": GEAR_KEYS, "mill": MILL_KEYS, "process": FORM_PROCESS_KEYS, "machine": MODEL_ONLY_MACHINE_KEYS}


@dataclass(frozen=True)
class FormMillingPayload:
    """The gear to mill, [mill], the measurement options and the designed topography."""

    gear: Gear
    mill: dict[str, Any]
    measurement: dict[str, Any]
    modification: Modification | None = None


def _form_mill_machine():
    from machine_models.form_mill import FormMillParams

    return FormMillParams()


def parse_form_milling_job(data: dict[str, Any], source: str) -> Job:
    """Validate a form-milling job. Raises :class:`InputError` with every problem."""
    problems: list[Problem] = []
    if "cutter" in data:
        problems.append(
            Problem(
                "mill",
                "[mill] and [cutter]",
                "a job cuts with either a skiving cutter or a disc mill",
                "remove [cutter] (form milling) or [mill] (skiving)",
            )
        )
    listed = (*SECTIONS_FORM, *OPTIONAL_SECTIONS)
    problems += unknown_sections(data, (*listed, "cutter"), listed)
    parsed = parse_sections(data, SECTIONS_FORM, problems)
    measurement, modification = parse_optional_sections(data, problems)
    problems += model_problems(parsed["machine"].get("model"), _form_mill_machine)
    g, mill = parsed["gear"], parsed["mill"]
    gear = None
    if set(GEAR_KEYS) <= set(g):
        gear = gear_from(g)
        problems += check_gear(gear, "gear")
        from cutting.form_milling.mill import check_copying_gear

        problems += [
            Problem("gear", "internal" if gear.internal else f"helix_angle = {g['helix_angle']}", why, "")
            for why in check_copying_gear(gear)
        ]
        if gear.helix_angle != 0.0:
            problems.append(
                Problem(
                    "gear.helix_angle",
                    g["helix_angle"],
                    "a form-milling job makes spur gears for now: the 15 steps plan a helical pinion with the set-over "
                    "mill on the ideal machine (cutting.form_milling.copying_path.plan_copying, tested), but the job's "
                    "machine run, forces and report are not yet proven on a helical space",
                    "set helix_angle = 0, or plan it from Python with plan_copying",
                )
            )
        sound = not problems  # the mill and the design are checked on a gear the copying method can make
        if sound and set(MILL_KEYS) <= set(mill):
            problems += _mill_problems(gear, mill)
        if sound and modification is not None:
            problems += design_problems(modification, gear)
    if problems:
        raise InputError(problems, source)
    payload = FormMillingPayload(gear, mill, measurement, modification)
    return Job(source, "form_milling", parsed["machine"], parsed["process"], payload)


def _mill_problems(gear: Gear, mill: dict[str, Any]) -> list[Problem]:
    """A mill too small for the tooth depth, or a clearance the tooth space cannot give."""
    out = []
    depth = gear.tip_radius - gear.root_radius
    if mill["diameter"] / 2 < depth + 10.0:
        out.append(
            Problem(
                "mill.diameter",
                mill["diameter"],
                f"the mill's radius must exceed the tooth depth {depth:.2f} mm by its 10 mm hub",
                f"use a diameter of at least {2 * (depth + 10.0):.0f} mm",
            )
        )
    from cutting.gear import form_roll_length

    d_form = 2 * math.hypot(gear.base_radius, form_roll_length(gear))
    space = math.pi * d_form / gear.teeth - gear.transverse_thickness_at(d_form)
    if mill["clearance"] > 0.5 * space:
        out.append(
            Problem(
                "mill.clearance",
                mill["clearance"],
                f"the tooth space is only {space:.3f} mm wide at the form circle: the mill would have no periphery",
                f"use a clearance below {0.5 * space:.3f} mm (e.g. 0.2 mm)",
            )
        )
    return out
