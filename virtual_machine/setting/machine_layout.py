"""The machines' numeric layouts from the cutting objects: the skiving machine's from the job's setup and its first
ideal pass, the face-contour machine's from the coupling, the workpiece diameter that picks a machine size, and a
skiving job's machine (its size and parameters).

They read ``cutting`` objects, so they live here rather than in ``machine_models`` (which imports neither ``cutting``
nor ``virtual_machine``): ``machine_models.skiving_machine.build_spec`` and
``machine_models.face_contour_machine.build_face_machine_spec`` build the MJCF models from these numbers.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cutting.gear import Gear
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.trajectory import PassMotion
from machine_models.parameters import SkivingMachineParams, override
from machine_models.parts import MM
from machine_models.sizes import size_for, size_params
from machine_models.skiving_machine import MachineLayout
from virtual_machine.job import Job, flatten_model

if TYPE_CHECKING:  # the face machine's modules load only for a face-contour job (a skiving run never needs them)
    from cutting.face_contour.slots import FaceCoupling
    from machine_models.face_contour_machine import FaceMachineLayout


def skiving_layout(setup: SkivingSetup, lead_screw_pitch_mm: float, first_pass: PassMotion) -> MachineLayout:
    """The skiving machine's layout for ``setup`` (mm -> m): its home at the start of ``first_pass`` (the job's
    first ideal pass, ``cutting.skiving.trajectory.ideal_passes(setup)[0]``, which the caller has computed), the
    axes' tilt and phases, the blank, cutter and holder, and the job's nominal ``lead_screw_pitch_mm``."""
    g, c = setup.gear, setup.cutter
    return MachineLayout(
        centre_distance=first_pass.centre_distance * MM,
        carriage_start=first_pass.s_start * MM,
        tilt=setup.tilt,
        work_phase=setup.work_phase,
        cutter_phase=setup.cutter_phase,
        lead_screw_pitch_mm=lead_screw_pitch_mm,
        # a ring gear's blank is a disc out to its rim (root + 3 mn), as workpiece_diameter counts it
        blank_radius=g.tip_radius * MM if not g.internal else (g.root_radius + 3 * g.mn) * MM,
        blank_width=g.face_width * MM,
        cutter_radius=setup.cutter_tip_diameter / 2 * MM,
        cutter_width=c.face_width * MM,
        holder_radius=setup.holder_diameter_value / 2 * MM,
    )


def workpiece_diameter(gear: Gear) -> float:
    """The blank's diameter the machine carries [mm]: the tip diameter of an external gear, the outside of a ring
    gear's rim (root diameter + 6 mn, as :func:`skiving_layout` sizes the blank); with the normal module it picks
    the machine size (``machine_models.sizes.size_for``)."""
    if gear.internal:
        return gear.root_diameter_value + 6 * gear.mn
    return gear.tip_diameter_value


def face_layout(c: FaceCoupling, blank_thickness: float = 20 * MM, home_z: float = 5 * MM) -> FaceMachineLayout:
    """The face-contour machine's layout for coupling ``c`` (mm -> m): its setting angle (eq. 1, on R - N e under
    the eccentric)."""
    from cutting.face_contour.slots import setting_angle
    from machine_models.face_contour_machine import FaceMachineLayout

    return FaceMachineLayout(
        m=c.m,
        L=c.L * MM,
        R=c.R * MM,
        setting_angle=setting_angle(c),
        inner_radius=c.inner_radius * MM,
        outer_radius=c.outer_radius * MM,
        eccentric=c.eccentric_on,
        e=c.e * MM if c.eccentric_on else 0.0,
        eccentric_ratio=c.eccentric_ratio,
        element_phases=tuple(float(b) for b in c.phases),
        element_height=c.element_height * MM,
        edge_width=c.edge_width * MM,
        blank_thickness=blank_thickness,
        home_z=home_z,
        work_setting=c.work_setting_on,
    )


def machine_size(job: Job) -> str:
    """The name of a skiving job's machine size: ``machine.size``, else the smallest size whose workpiece diameter and
    module hold the gear (machine_models/sizes.py)."""
    return job.machine.size or size_for(workpiece_diameter(job.gear), job.gear.mn).name


def machine_params(job: Job) -> SkivingMachineParams:
    """A skiving job's machine: its size's parameters with the job's [machine.model] overrides on top."""
    return override(size_params(machine_size(job)), flatten_model(job.machine.model))
