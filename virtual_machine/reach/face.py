"""Whether a face coupling is within the face-contour machine's reach (machine_models/face_contour_machine.py:
``head_speed_limit``, ``workpiece_diameter_limit``): checked before the run (:func:`cnc.simulate_face_contour`), so
that a head speed above the head's top speed or a coupling larger than the table takes is an input error naming both
figures, not a run-up of millions of turns."""

from __future__ import annotations

from cutting.errors import InputError, Problem
from cutting.face_contour.slots import FaceCoupling
from machine_models.face_contour_machine import FaceMachineParams
from machine_models.parameters import RPM
from virtual_machine.output.formatting import three_figures


def check_face_reach(c: FaceCoupling, params: FaceMachineParams, tool_rpm: float) -> None:
    """Refuse (InputError) a coupling the machine cannot cut: a head speed above its top speed, a coupling larger
    than its table takes (``head_speed_limit``, ``workpiece_diameter_limit``), naming both figures."""
    omega = tool_rpm * RPM
    problems = []
    if omega > params.head_speed_limit:
        top = params.head_speed_limit / RPM
        problems.append(
            Problem(
                "process.tool_speed",
                tool_rpm,
                f"the head H turns at {three_figures(tool_rpm)} rpm, above its top speed {three_figures(top)} rpm "
                f"(machine.model.head_speed_limit = {params.head_speed_limit:g} rad/s)",
                f"use a lower process.tool_speed, or machine.model.head_speed_limit >= {omega:.3g} (rad/s) if the "
                "real machine has it",
            )
        )
    if 2 * c.outer_radius * 1e-3 > params.workpiece_diameter_limit:
        problems.append(
            Problem(
                "coupling.outer_radius",
                c.outer_radius,
                f"a coupling of {three_figures(2 * c.outer_radius)} mm exceeds what the table takes, "
                f"{three_figures(params.workpiece_diameter_limit * 1e3)} mm",
                "use a smaller coupling, or machine.model.workpiece_diameter_limit >= "
                f"{2 * c.outer_radius * 1e-3:.3g} (m) if the real machine takes it",
            )
        )
    if problems:
        raise InputError(problems)
