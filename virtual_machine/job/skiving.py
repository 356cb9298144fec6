"""A skiving job (kind "skiving", marked by no other kind's section): [gear], [cutter], [process], [machine], and
optionally [measurement] and [modification] (virtual_machine.job.gear_sections).

[cutter] is the skiving cutter (tooth count z0, helix angle beta0 in degrees, right hand positive; its profile
shift, tip diameter, body width and holder diameter in mm; the edge made by the envelope method or an involute; its
rake face), [cutter.errors] its deviations and [workpiece] the blank's clamping (virtual_machine.job.cutter_sections).
[process] the cutter spindle speed n0 (rpm), the axial feed s (mm per workpiece revolution), the radial infeed
passes (mm), the feed direction, the material, the approach and overrun (mm), and the tolerances of the swept solid,
the dexel workpiece and gear.stl (mm). Its [machine] is the skiving machine of seeds 000 and 001 (head.MACHINE_KEYS).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, ClassVar

from cutting.errors import InputError, Problem
from cutting.gear import Gear, check_gear
from cutting.modification import Modification, design_problems
from cutting.skiving.kinematics import SkivingSetup, check_setup, reground
from cutting.skiving.machine_geometry import MachineGeometry
from cutting.skiving.tooling import Clamping, CutterErrors, RakeFace
from virtual_machine.job.cutter_sections import (
    RAKE_KEYS,
    WORKPIECE_KEYS,
    parse_clamping,
    parse_cutter_errors,
    rake_face,
    regrind_problems,
)
from virtual_machine.job.gear_sections import GEAR_KEYS, OPTIONAL_SECTIONS, gear_from, helix, parse_optional_sections
from virtual_machine.job.geometry_section import parse_geometry, without_geometry, without_table
from virtual_machine.job.head import MACHINE_KEYS, Job, MachineSection, model_problems
from virtual_machine.job.keys import (
    MATERIAL,
    PASSES,
    REQUIRED,
    STL_TOLERANCE,
    Key,
    at_least,
    one_of,
    parse_sections,
    positive,
    section_class,
    unknown_sections,
)
from virtual_machine.job.thermal_section import ThermalModel, job_drift, parse_thermal

CUTTER_KEYS: dict[str, Key] = {
    "teeth": Key(int, REQUIRED, "", "number of cutter teeth z0", at_least(8)),
    "helix_angle": Key(float, REQUIRED, "deg", "cutter helix angle beta0, right hand positive", helix),
    "profile_shift": Key(float, 0.0, "", "cutter profile shift x0"),
    "tip_diameter": Key(float, None, "mm", "cutter tip diameter da0 (default: cuts the gear's root exactly)", positive),
    "width": Key(float, None, "mm", "cutter body width behind the rake face (default 10 mn)", positive),
    "holder_diameter": Key(
        float, None, "mm", "diameter of the holder behind the cutter body (default half the cutter's d0)", positive
    ),
    "edge": Key(
        str,
        "conjugate",
        "",
        "cutting edge: 'conjugate' (envelope method) or 'involute'",
        one_of("conjugate", "involute"),
    ),
    # a guess: ground and honed edges of carbide and coated HSS cutters have 5-30 um (docs/forces.md)
    "edge_radius": Key(
        float, 0.010, "mm", "the cutting edge's rounding r_beta (ploughing, minimum chip thickness)", at_least(0.0)
    ),
    **RAKE_KEYS,
}

PROCESS_KEYS: dict[str, Key] = {
    "tool_speed": Key(float, REQUIRED, "rpm", "cutter spindle speed n0", positive),
    "axial_feed": Key(float, REQUIRED, "mm/rev", "axial feed s per workpiece revolution", positive),
    "passes": PASSES,
    "feed_direction": Key(str, "down", "", "'down' (towards -z) or 'up'", one_of("down", "up")),
    "material": MATERIAL,
    "clearance": Key(float, 1.0, "mm", "axial approach and overrun added to the engagement zone", at_least(0.0)),
    # a guess: tool makers keep the working clearance a degree or more to keep the flank off the cut surface
    "min_working_clearance": Key(
        float, 1.0, "deg", "below this working clearance on the generating edge a run warns", at_least(0.0)
    ),
    # defaults from benchmarks/bench_mesh_tolerance.py (docs/cutting.md, "The manifold solid's tolerance")
    "sweep_error": Key(
        float,
        0.010,
        "mm",
        "the solid's tolerance against the exact surface (manifold: the finishing pass's chord error)",
        positive,
    ),
    "roughing_sweep_error": Key(float, 0.020, "mm", "chord error allowed in the roughing passes (manifold)", positive),
    # defaults from benchmarks/bench_dexel.py (docs/cutting.md, "The dexel workpiece", "Spacing")
    "dexel_profile_spacing": Key(float, None, "mm", "dexel rays along the space's profile (default 0.1 mn)", positive),
    "dexel_face_spacing": Key(float, None, "mm", "dexel slices along the face (default 0.2 mn)", positive),
    "stl_tolerance": STL_TOLERANCE,
}

SECTIONS_GEAR = {"gear": GEAR_KEYS, "cutter": CUTTER_KEYS, "process": PROCESS_KEYS, "machine": MACHINE_KEYS}
#: sections a skiving job may add: the blank's clamping (the cutter's deviations are [cutter.errors], in [cutter])
SKIVING_OPTIONAL = {"workpiece": WORKPIECE_KEYS}


SkivingProcess = section_class("SkivingProcess", PROCESS_KEYS, "[process] of a skiving job (PROCESS_KEYS).", __name__)


@dataclass(frozen=True)
class CutterOptions:
    """What [cutter] says beyond the cutter's gear data: the ``edge`` ("conjugate" or "involute"), the
    ``holder_diameter`` [mm] (None: half the cutter's reference diameter) and the ``edge_radius`` [mm] of the
    rounded cutting edge (the force model's)."""

    edge: str = "conjugate"
    holder_diameter: float | None = None
    edge_radius: float = 0.010


@dataclass(frozen=True)
class SkivingJob(Job):
    """A skiving job: the gear to skive, the cutter (a Gear: z0, beta0, x0, da0, its body width as face width), the
    cutter's options, the measurement options and the designed topography; ``skiving`` the crossed-axes setup they
    make with [process] (made once)."""

    kind: ClassVar[str] = "skiving"
    gear: Gear
    cutter: Gear
    cutter_options: CutterOptions
    measurement: dict[str, Any]
    modification: Modification | None = None
    rake: RakeFace = field(default_factory=RakeFace)
    cutter_errors: CutterErrors = field(default_factory=CutterErrors)
    clamping: Clamping = field(default_factory=Clamping)
    #: [machine.model.geometry]: the machine's geometric errors (virtual_machine/job/geometry_section.py)
    geometry: MachineGeometry = field(default_factory=MachineGeometry)
    #: [machine.model.thermal] and machine.thermal_state: the thermal model (virtual_machine/job/thermal_section.py)
    thermal: ThermalModel | None = None

    @cached_property
    def skiving(self) -> SkivingSetup:
        """The setup of the tool as it is: designed new, then reground by ``rake.regrind``; with the machine's
        thermal drift over the job where the job has a thermal model."""
        setup = reground(self.new_tool, self.rake.regrind)
        if self.thermal is None:
            return setup
        powers = None
        if self.thermal.cutting_heat_share and self.thermal.structure_x_per_w:
            from virtual_machine.reach.skiving_load import pass_loads

            loads = pass_loads(setup, self.process.material, edge_radius=self.cutter_options.edge_radius)
            powers = [ld.power for ld in loads]
        return dataclasses.replace(setup, thermal=job_drift(self.thermal, setup, powers))

    @cached_property
    def new_tool(self) -> SkivingSetup:
        """The setup with the tool as new (what its edge is designed for)."""
        p = self.process
        return SkivingSetup(
            self.gear,
            self.cutter,
            p.tool_speed,
            p.axial_feed,
            tuple(p.passes),
            p.feed_direction,
            p.clearance,
            holder_diameter=self.cutter_options.holder_diameter,
            rake=dataclasses.replace(self.rake, regrind=0.0),
            cutter_errors=self.cutter_errors,
            clamping=self.clamping,
            geometry=self.geometry,
        )


def _skiving_machine():
    from machine_models.parameters import SkivingMachineParams

    return SkivingMachineParams()


def parse_skiving_job(data: dict[str, Any], source: str) -> SkivingJob:
    """Validate a skiving job. Raises :class:`InputError` with every problem."""
    problems = unknown_sections(data, (*SECTIONS_GEAR, *OPTIONAL_SECTIONS, *SKIVING_OPTIONAL), SECTIONS_GEAR)
    data, errors_table = _without_cutter_errors(data)
    thermal_state = None
    if isinstance(data.get("machine"), dict) and "thermal_state" in data["machine"]:  # skiving's own [machine] key
        thermal_state = data["machine"]["thermal_state"]
        data = {**data, "machine": {k: v for k, v in data["machine"].items() if k != "thermal_state"}}
    parsed = parse_sections(data, SECTIONS_GEAR, problems)
    measurement, modification = parse_optional_sections(data, problems)
    machine = parsed["machine"]
    model, geometry_table = without_geometry(machine.get("model"))
    model, thermal_table = without_table(model, "thermal")
    machine = {**machine, "model": model}
    problems += model_problems(model, _skiving_machine)
    geometry = parse_geometry(geometry_table, machine.get("lead_screw_pitch", 10.0), problems)
    thermal = parse_thermal(thermal_table, thermal_state, problems)

    # Geometry checks run as soon as their own keys are sound, so they are reported beside key errors.
    g, c = parsed["gear"], parsed["cutter"]
    gear_ok = set(GEAR_KEYS) <= set(g)
    cutter_ok = gear_ok and set(CUTTER_KEYS) <= set(c)
    gear = cutter = None
    if gear_ok:
        gear = gear_from(g)
        problems += check_gear(gear, "gear")
    if cutter_ok:
        cutter = Gear(
            teeth=c["teeth"],
            normal_module=gear.mn,
            pressure_angle=gear.alpha_n,
            helix_angle=math.radians(c["helix_angle"]),
            face_width=c["width"] or gear.mn * 10,  # the body behind the rake face (holder-side collision check)
            profile_shift=c["profile_shift"],
            tip_diameter=c["tip_diameter"],
        )
        if cutter.x < cutter.min_profile_shift - 1e-9:
            problems.append(
                Problem(
                    "cutter.profile_shift",
                    cutter.x,
                    f"the cutter's own teeth would be undercut (z0 = {cutter.z} needs "
                    f"x0 >= {cutter.min_profile_shift:+.4f})",
                    "use more cutter teeth or a larger x0",
                )
            )
    cutter_errors = clamping = None
    if cutter is not None:
        cutter_errors = parse_cutter_errors(errors_table, cutter.z, gear.mn, problems)
        clamping = parse_clamping(data.get("workpiece"), gear.mn, problems)
    if gear is not None and modification is not None:
        problems += design_problems(modification, gear)
    if problems:
        raise InputError(problems, source)
    job = SkivingJob(
        source,
        MachineSection(**machine),
        SkivingProcess(**parsed["process"]),
        gear,
        cutter,
        CutterOptions(c["edge"], c["holder_diameter"], c["edge_radius"]),
        measurement,
        modification,
        rake_face(c),
        cutter_errors,
        clamping,
        geometry,
        thermal,
    )
    problems += regrind_problems(job.new_tool, job.rake.regrind, job.cutter.face_width)
    if problems:
        raise InputError(problems, source)
    problems += check_setup(job.skiving)
    if problems:
        raise InputError(problems, source)
    return job


def _without_cutter_errors(data: dict[str, Any]) -> tuple[dict[str, Any], Any]:
    """The job without [cutter.errors] (parsed on its own), and that table (None when absent)."""
    cutter = data.get("cutter")
    if not isinstance(cutter, dict) or "errors" not in cutter:
        return data, None
    rest = {k: v for k, v in cutter.items() if k != "errors"}
    return {**data, "cutter": rest}, cutter["errors"]


def dexel_spacing(job: SkivingJob):
    """The dexel lines of a skiving job: the process's spacings, else the gear's defaults
    (cutting.skiving.dexel_lines)."""
    from cutting.skiving.dexel_lines import DexelSpacing

    p = job.process
    return DexelSpacing.for_gear(job.gear, p.axial_feed, p.dexel_profile_spacing, p.dexel_face_spacing)
