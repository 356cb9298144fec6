"""[machine.model.geometry]: the skiving machine's geometric errors (cutting/skiving/machine_geometry.py; issue 43).

The names are fixed (tests outside the project use them); units as every job's: mm, deg, and mm per 100 mm of travel
for the squareness and the spindle's tilt. Every key is a study key like any other
(``machine.model.geometry.centre_distance_offset``).
"""

from __future__ import annotations

import math
from typing import Any

from cutting.errors import Problem
from cutting.skiving.machine_geometry import MachineGeometry
from virtual_machine.job.keys import Check, Key, parse_section


def within(limit: float, unit: str, beyond: str = "a set-up error, not the machine's geometry") -> Check:
    """A signed error no larger than ``limit``: beyond it the value is a slip of units or ``beyond`` says what (the
    limits are guards against a slip of units, chosen (a guess, not a cited figure) well beyond any machine's
    geometric errors or drift; they are not tolerances)."""

    def check(v: float) -> tuple[str, str] | None:
        if not math.isfinite(v):
            return "must be a finite number", f"give the value in {unit}"
        if abs(v) > limit:
            return f"beyond +-{limit:g} {unit}: {beyond}", f"the value in {unit}"
        return None

    return check


SQ = "mm/100 mm"
ARCSEC = math.pi / 180 / 3600


def _phase(what: str) -> Key:
    return Key(float, 0.0, "deg", what, within(1e6, "deg"))


GEOMETRY_KEYS: dict[str, Key] = {
    "shaft_angle_error": Key(float, 0.0, "deg", "the swivel head's real angle minus the set one", within(1.0, "deg")),
    "centre_distance_offset": Key(
        float, 0.0, "mm", "the real centre distance minus the commanded (positive: farther apart)", within(1.0, "mm")
    ),
    "cutter_offset_error": Key(
        float, 0.0, "mm", "the cutter centre off the axes' common perpendicular, along y", within(1.0, "mm")
    ),
    "carriage_squareness_x": Key(
        float, 0.0, SQ, "the carriage's travel off parallel to the work axis, towards +x", within(0.5, SQ)
    ),
    "carriage_squareness_y": Key(
        float, 0.0, SQ, "the carriage's travel off parallel to the work axis, towards +y", within(0.5, SQ)
    ),
    "lead_screw_periodic_error": Key(
        float, 0.0, "mm", "the carriage's periodic position error, one period a screw turn", within(0.05, "mm")
    ),
    "lead_screw_periodic_phase": _phase("its phase at mid face"),
    "work_spindle_radial_error": Key(
        float, 0.0, "mm", "the work spindle's once-per-revolution radial error motion", within(0.1, "mm")
    ),
    "work_spindle_radial_phase": _phase("towards this angle of the blank (0: the centre of space 0)"),
    "work_spindle_tilt_error": Key(
        float, 0.0, SQ, "the work spindle's once-per-revolution tilt error motion", within(0.5, SQ)
    ),
    "work_spindle_tilt_phase": _phase("where the blank's face is lifted most"),
    "tool_encoder_eccentricity": Key(
        float, 0.0, "arcsec", "the tool spindle's encoder's once-per-turn error (its graduation off centre)",
        within(60.0, "arcsec"),
    ),
    "tool_encoder_phase": _phase("its phase against the tool spindle's angle"),
    "work_encoder_eccentricity": Key(
        float, 0.0, "arcsec", "the work spindle's encoder's once-per-turn error", within(60.0, "arcsec")
    ),
    "work_encoder_phase": _phase("its phase against the work spindle's angle"),
}  # fmt: skip


def without_geometry(model: dict[str, Any] | None) -> tuple[dict[str, Any] | None, Any]:
    """[machine.model] without its geometry table (the machine model's parameters are the rest), and that table
    (None when absent)."""
    return without_table(model, "geometry")


def without_table(model: dict[str, Any] | None, name: str) -> tuple[dict[str, Any] | None, Any]:
    """[machine.model] without its table ``name`` (geometry, thermal: not the MuJoCo model's parameters), and that
    table (None when absent)."""
    if not isinstance(model, dict) or name not in model:
        return model, None
    return {k: v for k, v in model.items() if k != name}, model[name]


def parse_geometry(table: Any, lead_screw_pitch: float, problems: list[Problem]) -> MachineGeometry:
    """[machine.model.geometry] (None: an exact machine); problems appended. ``lead_screw_pitch`` [mm]: the
    period of the screw's periodic error."""
    if table is None:
        return MachineGeometry(lead_screw_pitch=lead_screw_pitch)
    before = len(problems)
    v = parse_section("machine.model.geometry", table, GEOMETRY_KEYS, problems)
    if len(problems) > before or not v:
        return MachineGeometry(lead_screw_pitch=lead_screw_pitch)
    per_mm = 1e-2  # mm per 100 mm -> mm/mm
    return MachineGeometry(
        shaft_angle_error=math.radians(v["shaft_angle_error"]),
        centre_distance_offset=v["centre_distance_offset"],
        cutter_offset_error=v["cutter_offset_error"],
        carriage_squareness_x=v["carriage_squareness_x"] * per_mm,
        carriage_squareness_y=v["carriage_squareness_y"] * per_mm,
        lead_screw_periodic_error=v["lead_screw_periodic_error"],
        lead_screw_periodic_phase=math.radians(v["lead_screw_periodic_phase"]),
        lead_screw_pitch=lead_screw_pitch,
        work_spindle_radial_error=v["work_spindle_radial_error"],
        work_spindle_radial_phase=math.radians(v["work_spindle_radial_phase"]),
        work_spindle_tilt_error=v["work_spindle_tilt_error"] * per_mm,
        work_spindle_tilt_phase=math.radians(v["work_spindle_tilt_phase"]),
        tool_encoder_eccentricity=v["tool_encoder_eccentricity"] * ARCSEC,
        tool_encoder_phase=math.radians(v["tool_encoder_phase"]),
        work_encoder_eccentricity=v["work_encoder_eccentricity"] * ARCSEC,
        work_encoder_phase=math.radians(v["work_encoder_phase"]),
    )
