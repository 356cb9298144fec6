"""Whether a face coupling is within the face-contour machine's reach (machine_models/face_contour_machine.py:
``head_speed_limit``, ``workpiece_diameter_limit``) and whether its motors take the cut (the cycle's heaviest pass
against their peak torques): checked before the run, so that a head speed above the head's top speed, a coupling
larger than the table takes or a feed the head motor cannot cut is an input error naming both figures, not a run-up
of millions of turns or a servo that runs away."""

from __future__ import annotations

import math

from cutting.errors import MachineLimitError, Problem
from cutting.face_contour.forces import FaceLoad, sizing
from cutting.face_contour.slots import FaceCoupling
from machine_models.face_contour_machine import FaceMachineParams
from machine_models.parameters import RPM
from virtual_machine.output.formatting import three_figures
from virtual_machine.reach.limits import Limit, refuse

MACHINE = "face-contour machine"


def check_face_reach(c: FaceCoupling, params: FaceMachineParams, tool_rpm: float) -> None:
    """Refuse (MachineLimitError) a coupling the machine cannot cut: a head speed above its top speed, a coupling
    larger than its table takes (``head_speed_limit``, ``workpiece_diameter_limit``), naming both figures."""
    omega = tool_rpm * RPM
    limits = (
        Limit(
            "head_speed_limit",
            omega,
            params.head_speed_limit,
            "rad/s",
            f"the head H turns at {three_figures(tool_rpm)} rpm, above its top speed "
            f"{three_figures(params.head_speed_limit / RPM)} rpm",
            "a lower process.tool_speed",
        ),
        Limit(
            "workpiece_diameter_limit",
            2 * c.outer_radius * 1e-3,
            params.workpiece_diameter_limit,
            "m",
            f"a coupling of {three_figures(2 * c.outer_radius)} mm exceeds what the table takes, "
            f"{three_figures(params.workpiece_diameter_limit * 1e3)} mm",
            "a smaller coupling (coupling.outer_radius)",
        ),
    )
    refuse(MACHINE, limits)


#: share of a motor's peak torque the cutting load may take (the rest: the servo's acceleration, friction)
CUT_TORQUE_SHARE = 0.8


def check_cutting_load(c: FaceCoupling, load: FaceLoad, params: FaceMachineParams) -> dict[str, dict[str, float]]:
    """The motors' torques under the cycle's heaviest pass (:func:`cutting.face_contour.forces.sizing`: the head
    torque on MH, the work's on MA, the thrust on MZ); a motor the cut would take beyond CUT_TORQUE_SHARE of its
    peak refuses the job before the run (MachineLimitError on ``coupling.feed``, naming the motor, the torque needed
    and the feed that would do). The motors' other loads (friction, the slide's unbalanced weight, the servo's
    acceleration) take the rest of the peak. Returns the sizing."""
    lead = params.screw_pitch / (2 * math.pi)
    motors = {
        "MH": (abs(params.head_drive.ratio), params.h_motor_torque),
        "MA": (abs(params.work_drive.ratio), params.a_motor_torque),
        "MZ": (abs(params.z_drive.ratio) * lead, params.z_motor_torque),
    }
    size = sizing(c, load.material, load.window, motors, CUT_TORQUE_SHARE, load.edge_radius)
    problems = [
        Problem(
            "coupling.feed",
            c.S,
            f"the heaviest pass (layer m S = {c.m * c.S:.4g} mm, F_c {row['F_c_N']:.0f} N, thrust "
            f"{row['thrust_N']:.0f} N in {load.material.key}) needs {row['needed_N_m']:.1f} N m of {name}, beyond "
            f"{CUT_TORQUE_SHARE:.0%} of its {row['peak_N_m']:g} N m peak",
            f"a feed of {row['feed_mm']:.4g} mm per tool revolution or less, or a stronger "
            f"machine.model.{name[1].lower()}_motor_torque",
        )
        for name, row in size.items()
        if "feed_mm" in row
    ]
    if problems:
        raise MachineLimitError(problems)
    return size
