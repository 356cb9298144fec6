"""A face-contour job (kind "face_contour", continuous indexing of a face coupling, seed 004): [coupling],
[process], [machine].

[coupling] the face coupling: its slots m, the radius L of the point M where the cutting speed is radial (mm), the
tool head radius R (mm), the infeed S per tool revolution (mm/rev), the slot depth and the slotted face's radii (mm),
the head's cutting elements (pitch and flank angle in degrees, edge width and height in mm) and the control
('fixed', 'eccentric' with its e in mm and eccentric turns, 'cyclic_ratio' with its cycles and amplitude in
degrees). [process] the tool head speed (rpm), the slots cut, the material and the slots' chord error (mm).
Its [machine] only overrides the face-contour machine's model ([machine.model]).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

from cutting.errors import InputError, Problem
from virtual_machine.job.head import MODEL_ONLY_MACHINE_KEYS, Job, ModelOnlyMachine, model_problems
from virtual_machine.job.keys import (
    MATERIAL,
    REQUIRED,
    Key,
    at_least,
    one_of,
    parse_sections,
    positive,
    section_class,
    unknown_sections,
)

if TYPE_CHECKING:
    from cutting.face_contour.slots import FaceCoupling

COUPLING_KEYS: dict[str, Key] = {
    "slots": Key(int, REQUIRED, "", "number of slots m of the face coupling", at_least(2)),
    "L": Key(float, REQUIRED, "mm", "radius of the point M where the cutting speed is radial (seed 004)", positive),
    "tool_radius": Key(float, REQUIRED, "mm", "tool head radius R to the element tips", positive),
    "feed": Key(float, 0.05, "mm/rev", "infeed S per tool revolution", positive),
    "depth": Key(float, REQUIRED, "mm", "slot depth at M", positive),
    "inner_radius": Key(float, REQUIRED, "mm", "inner radius of the slotted face", positive),
    "outer_radius": Key(float, REQUIRED, "mm", "outer radius of the slotted face", positive),
    "elements": Key(int, 1, "", "cutting elements of the tool head (a sector)", at_least(1)),
    "element_pitch": Key(float, 0.0, "deg", "phase pitch of the elements on the head", at_least(0.0)),
    "edge_width": Key(float, 2.0, "mm", "width of an element's straight tip edge", positive),
    "flank_angle": Key(float, 20.0, "deg", "an element's flank angle", at_least(0.0)),
    "element_height": Key(float, 5.0, "mm", "height of an element above its tip", positive),
    "control": Key(
        str,
        "fixed",
        "",
        "'fixed', 'eccentric', 'cyclic_ratio', 'work_setting' (the work's setting changed during the cut), or "
        "the tool's eccentric with either: 'eccentric+cyclic_ratio', 'eccentric+work_setting' (seed 004)",
        # the literal of cutting.face_contour.slots.CONTROLS (not imported: the job parser stays light)
        one_of(
            "fixed", "eccentric", "cyclic_ratio", "eccentric+cyclic_ratio", "work_setting", "eccentric+work_setting"
        ),
    ),
    "e": Key(float, None, "mm", "eccentricity (default: the setting sheet's flat-bottom e)", at_least(0.0)),
    "eccentric_ratio": Key(int, 4, "", "eccentric turns N per tool revolution", at_least(1)),
    "ratio_cycles": Key(int, 6, "", "cycles q of the speed ratio per tool revolution", at_least(1)),
    "ratio_amplitude": Key(
        float, None, "deg", "amplitude of the ratio's cycle (default: straight slots)", at_least(0.0)
    ),
    "setting_cycles": Key(int, 6, "", "cycles q_s of the work's setting per tool revolution", at_least(1)),
    "setting_offset": Key(
        float,
        None,
        "mm",
        "the work's move T (1 - cos q_s phi) along the tool axis (default: straight slots)",
        at_least(0.0),
    ),
}

FACE_PROCESS_KEYS: dict[str, Key] = {
    "tool_speed": Key(float, 150.0, "rpm", "tool head speed (at M)", positive),
    "head_speed": Key(
        str,
        "constant",
        "",
        "'constant', or 'held': under the eccentric the head's speed follows eq. 16 so the tip's speed stays that "
        "at M (seed 004)",
        one_of("constant", "held"),
    ),
    "master": Key(
        str,
        "head",
        "",
        "what the work, eccentric and cross slide follow: 'head' (the cutter spindle's encoder, seed 001's "
        "master-slave) or 'generator' (the head's command, seed 000's equal coordinates)",
        one_of("head", "generator"),
    ),
    "slots_cut": Key(int, 3, "", "slots cut, recorded and measured (0, 1, ...)", at_least(2)),
    "material": MATERIAL,
    "sweep_error": Key(float, 0.001, "mm", "chord error of the slots' manifold solid", positive),
}

SECTIONS_FACE = {"coupling": COUPLING_KEYS, "process": FACE_PROCESS_KEYS, "machine": MODEL_ONLY_MACHINE_KEYS}


FaceContourProcess = section_class(
    "FaceContourProcess", FACE_PROCESS_KEYS, "[process] of a face-contour job (FACE_PROCESS_KEYS).", __name__
)


@dataclass(frozen=True)
class FaceContourJob(Job):
    """A face-contour job: the face coupling to cut."""

    kind: ClassVar[str] = "face_contour"
    coupling: FaceCoupling


def _face_machine():
    from machine_models.face_contour_machine import FaceMachineParams

    return FaceMachineParams()


def parse_face_contour_job(data: dict[str, Any], source: str) -> FaceContourJob:
    """Validate a face-contour job; the coupling's own checks name their key. Raises :class:`InputError` with every
    problem."""
    problems = unknown_sections(data, SECTIONS_FACE, SECTIONS_FACE)
    parsed = parse_sections(data, SECTIONS_FACE, problems)
    problems += model_problems(parsed["machine"].get("model"), _face_machine)
    coupling = None
    if not problems:
        try:
            coupling = _coupling(parsed["coupling"])
        except ValueError as exc:
            names = {"m": "slots", "R": "tool_radius", "S": "feed"}
            field = str(exc).split(":")[0].split()[0]
            problems.append(
                Problem(f"coupling.{names.get(field, field)}", "", str(exc), "see docs/face-contours-and-turning.md")
            )
        if coupling is not None and parsed["process"]["slots_cut"] > coupling.m:
            problems.append(
                Problem("process.slots_cut", parsed["process"]["slots_cut"], "more than the coupling has", "")
            )
    if problems:
        raise InputError(problems, source)
    machine, process = ModelOnlyMachine(**parsed["machine"]), FaceContourProcess(**parsed["process"])
    return FaceContourJob(source, machine, process, coupling)


def _coupling(c: dict[str, Any]) -> FaceCoupling:
    """The FaceCoupling of [coupling]; an eccentric without e gets the flat-bottom e, a cyclic ratio without its
    amplitude and a work setting without its offset the straight-slot ones (all from the setting sheet)."""
    import dataclasses

    from cutting.face_contour.slots import (
        FaceCoupling,
        flat_bottom_eccentricity,
        straight_slot_amplitude,
        straight_slot_offset,
    )

    coupling = FaceCoupling(
        m=c["slots"],
        L=c["L"],
        R=c["tool_radius"],
        S=c["feed"],
        depth=c["depth"],
        inner_radius=c["inner_radius"],
        outer_radius=c["outer_radius"],
        elements=c["elements"],
        element_pitch=math.radians(c["element_pitch"]),
        edge_width=c["edge_width"],
        flank_angle=math.radians(c["flank_angle"]),
        element_height=c["element_height"],
        control=c["control"],
        e=c["e"] or 0.0,
        eccentric_ratio=c["eccentric_ratio"],
        ratio_cycles=c["ratio_cycles"],
        ratio_amplitude=math.radians(c["ratio_amplitude"] or 0.0),
        setting_cycles=c["setting_cycles"],
        setting_offset=c["setting_offset"] or 0.0,
    )
    # the amplitude first: combined, the flat-bottom e is solved with the ratio's cycle on
    if coupling.cyclic_on and c["ratio_amplitude"] is None:
        coupling = dataclasses.replace(coupling, ratio_amplitude=straight_slot_amplitude(coupling))
    if coupling.eccentric_on and c["e"] is None:
        coupling = dataclasses.replace(coupling, e=flat_bottom_eccentricity(coupling))
    if coupling.work_setting_on and c["setting_offset"] is None:  # after e: T depends on R - N e
        coupling = dataclasses.replace(coupling, setting_offset=straight_slot_offset(coupling))
    return coupling
