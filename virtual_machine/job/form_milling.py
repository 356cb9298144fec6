"""A form-milling job (kind "form_milling", the copying method of seed 003): [gear], [mill], [process], [machine],
and optionally [measurement] and [modification] (virtual_machine.job.gear_sections).

[mill] the profiled mill: its type ("disc", the default, or "finger": an end mill along the space's symmetry line,
whose diameter is fitted to the space), the disc's outer diameter (mm), its teeth, and its clearance in the tooth
space (mm; one pass per flank). [process] the table feed (mm/min), the mill speed (rpm), the path points per half
face width, the runs of the accuracy check on the machine, the material, and the tolerances of the swept volumes and
gear.stl (mm).
Its [machine] only overrides the form-milling machine's model ([machine.model]). The gear must be one the copying
method can make (spur; internal only with the finger mill), the mill must fit its tooth space.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

from cutting.errors import InputError, Problem
from cutting.form_milling import PATH_FORMS
from cutting.gear import Gear, check_gear
from cutting.modification import Modification, design_problems
from virtual_machine.job.gear_sections import GEAR_KEYS, OPTIONAL_SECTIONS, gear_from, parse_optional_sections
from virtual_machine.job.head import MODEL_ONLY_MACHINE_KEYS, Job, ModelOnlyMachine, model_problems
from virtual_machine.job.keys import (
    MATERIAL,
    STL_TOLERANCE,
    Key,
    at_least,
    one_of,
    parse_sections,
    positive,
    section_class,
    unknown_sections,
)

MILL_TYPES = ("disc", "finger")
#: teeth of the mill when [mill] gives none: a disc mill's and a finger (end) mill's
DEFAULT_TEETH = {"disc": 12, "finger": 4}

MILL_KEYS: dict[str, Key] = {
    "type": Key(
        str,
        "disc",
        "",
        "'disc': a profiled disc mill, axis tangential (external gears); 'finger': a profiled end mill whose axis lies "
        "along the space's symmetry line (external and internal gears)",
        one_of(*MILL_TYPES),
    ),
    "diameter": Key(
        float,
        None,
        "mm",
        "outer diameter of the profiled disc mill (copying method, seed 003; required for the disc mill, the finger "
        "mill's is fitted to the space: the parsed job gives its largest diameter)",
        positive,
    ),
    "teeth": Key(int, None, "", "teeth of the mill (feed per tooth; default 12 disc, 4 finger)", at_least(1)),
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


FormMillingProcess = section_class(
    "FormMillingProcess", FORM_PROCESS_KEYS, "[process] of a form-milling job (FORM_PROCESS_KEYS).", __name__
)


@dataclass(frozen=True)
class FormMillingJob(Job):
    """A form-milling job (the copying method): the gear to mill, [mill], the measurement options and the designed
    topography."""

    kind: ClassVar[str] = "form_milling"
    gear: Gear
    mill: dict[str, Any]
    measurement: dict[str, Any]
    modification: Modification | None = None


def _form_mill_machine():
    from machine_models.form_mill import FormMillParams

    return FormMillParams()


def parse_form_milling_job(data: dict[str, Any], source: str) -> FormMillingJob:
    """Validate a form-milling job. Raises :class:`InputError` with every problem."""
    problems: list[Problem] = []
    if "cutter" in data:
        problems.append(
            Problem(
                "mill",
                "[mill] and [cutter]",
                "a job cuts with either a skiving cutter or a profiled (disc or finger) mill",
                "remove [cutter] (form milling) or [mill] (skiving)",
            )
        )
    listed = (*SECTIONS_FORM, *OPTIONAL_SECTIONS)
    problems += unknown_sections(data, (*listed, "cutter"), listed)
    parsed = parse_sections(data, SECTIONS_FORM, problems)
    measurement, modification = parse_optional_sections(data, problems)
    problems += model_problems(parsed["machine"].get("model"), _form_mill_machine)
    g, mill = parsed["gear"], parsed["mill"]
    kind = mill.get("type", "disc")
    if "teeth" in mill and mill["teeth"] is None and kind in DEFAULT_TEETH:
        mill["teeth"] = DEFAULT_TEETH[kind]
    problems += _mill_type_problems(mill, parsed["process"], data.get("process"))
    gear = None
    if set(GEAR_KEYS) <= set(g):
        gear = gear_from(g)
        problems += check_gear(gear, "gear")
        from cutting.form_milling.mill import check_copying_gear

        if kind in MILL_TYPES:
            for why in check_copying_gear(gear, kind):
                if gear.internal and kind == "disc":
                    problems.append(
                        Problem(
                            "mill.type",
                            kind,
                            f"the gear is internal ([gear] internal = true): {why}",
                            'set mill.type = "finger" (and leave mill.diameter out: the finger is fitted to the space)',
                        )
                    )
                else:
                    problems.append(Problem("gear", f"helix_angle = {g['helix_angle']}", why, ""))
        sound = not problems  # the mill and the design are checked on a gear the copying method can make
        if sound and set(MILL_KEYS) <= set(mill) and kind == "disc" and mill["diameter"] is not None:
            problems += _mill_problems(gear, mill)
        if sound and set(MILL_KEYS) <= set(mill) and kind == "finger" and mill["diameter"] is None:
            found, fitted = _finger_problems(gear, mill, modification)
            problems += found
            mill["diameter"] = fitted  # derived: the finger's largest diameter as fitted to the space
        if sound and modification is not None:
            problems += design_problems(modification, gear)
    if problems:
        raise InputError(problems, source)
    machine, process = ModelOnlyMachine(**parsed["machine"]), FormMillingProcess(**parsed["process"])
    return FormMillingJob(source, machine, process, gear, mill, measurement, modification)


def _mill_type_problems(mill: dict[str, Any], process: dict[str, Any], raw_process: Any) -> list[Problem]:
    """The keys each mill type needs or cannot take: the disc's diameter, the finger's none (its radius is fitted
    to the space) and no ``process.mill_axis`` (its axis stays along the symmetry line)."""
    kind = mill.get("type")
    out = []
    if kind == "disc" and "diameter" in mill and mill["diameter"] is None:
        out.append(
            Problem(
                "mill.diameter",
                None,
                "missing required key for the disc mill (outer diameter of the profiled disc mill)",
                'add diameter = <number, mm>, or set mill.type = "finger"',
            )
        )
    if kind == "finger" and mill.get("diameter") is not None:
        out.append(
            Problem(
                "mill.diameter",
                mill["diameter"],
                "a finger mill's diameter is not chosen: its radius is fitted to the tooth space (seed 003, eq. 9)",
                "remove mill.diameter (skive setup prints the fitted diameter)",
            )
        )
    if kind == "finger" and isinstance(raw_process, dict) and "mill_axis" in raw_process:
        out.append(
            Problem(
                "process.mill_axis",
                process.get("mill_axis", raw_process["mill_axis"]),
                "the finger mill's axis stays along the space's symmetry line (a turn would move its silhouette "
                "along the face): it has no turned or fixed axis",
                "remove process.mill_axis",
            )
        )
    return out


def _finger_problems(
    gear: Gear, mill: dict[str, Any], modification: Modification | None
) -> tuple[list[Problem], float | None]:
    """A finger mill the space cannot give (a clearance that leaves no tip, an undercut section), and else the
    fitted finger's largest diameter [mm] (seed 003, eq. 9: fitted to the designed space at mid face; on a helical
    gear the envelope of the nominal helicoid, the design being the path's)."""
    from cutting.form_milling.finger import fit_finger_mill

    design = None if gear.helix_angle else modification
    try:
        fitted = fit_finger_mill(gear, mill["clearance"], design, mill["teeth"])
    except ValueError as exc:
        return [Problem("mill.clearance", mill["clearance"], str(exc), "use a smaller clearance (e.g. 0.2 mm)")], None
    return [], 2 * fitted.radius


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
