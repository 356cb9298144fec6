"""The sections of a job that describe a gear, shared by skiving and form-milling jobs.

[gear] the gear to make (mm, degrees; helix angles signed, right hand positive), [measurement] the ISO 1328
measurement's options (mm, tooth counts) and [modification] the designed flank topography (mm; shortcuts for both
flanks, [modification.left] / [modification.right] for one flank, only there a Bezier ``patch``).
:func:`load_gear_section` reads just these, for measuring a gear.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from cutting.errors import InputError, Problem
from cutting.gear import Gear, check_gear
from cutting.modification import FlankDesign, Modification, design_problems
from virtual_machine.job.head import read_toml
from virtual_machine.job.keys import REQUIRED, Key, at_least, parse_section, positive

SIDES = ("left", "right")
MAX_HELIX = 45.0


def helix(v: float) -> tuple[str, str] | None:
    if abs(v) < MAX_HELIX:
        return None
    return (
        f"|helix angle| must be below {MAX_HELIX:.0f} deg (ISO 1328-1 validity, skiving practice)",
        "use a helix angle between -45 and +45 deg",
    )


def _pressure(v: float) -> tuple[str, str] | None:
    return None if 10.0 <= v <= 35.0 else ("normal pressure angle outside 10..35 deg", "20 deg is the standard value")


GEAR_KEYS: dict[str, Key] = {
    "teeth": Key(int, REQUIRED, "", "number of teeth z2", at_least(5)),
    "normal_module": Key(float, REQUIRED, "mm", "normal module mn", positive),
    "pressure_angle": Key(float, 20.0, "deg", "normal pressure angle alpha_n", _pressure),
    "helix_angle": Key(float, 0.0, "deg", "reference helix angle beta2, right hand positive", helix),
    "face_width": Key(float, REQUIRED, "mm", "face width b", positive),
    "profile_shift": Key(float, 0.0, "", "profile shift coefficient x2 (positive towards the tooth tip)"),
    "internal": Key(bool, False, "", "true for an internal (ring) gear"),
    "tip_diameter": Key(float, None, "mm", "tip diameter da2 (default from the ISO 53 A basic rack)", positive),
    "root_diameter": Key(float, None, "mm", "root diameter df2 (default from the ISO 53 A basic rack)", positive),
}

MEASUREMENT_KEYS: dict[str, Key] = {
    "profile_start_diameter": Key(
        float, None, "mm", "start of the profile evaluation range (active profile start)", positive
    ),
    "profile_end_diameter": Key(float, None, "mm", "end of the profile evaluation range", positive),
    "sector_teeth": Key(int, None, "", "k of the sector pitch deviation F_pk (default z/8)", at_least(1)),
    "span_teeth": Key(int, None, "", "spanned teeth k of W_k (default DIN 3960 / 21773)", at_least(1)),
    "ball_diameter": Key(float, None, "mm", "ball for over-balls and runout (default DIN 3977 size)", positive),
}

MODIFICATION_KEYS: dict[str, Key] = {
    "lead_crowning": Key(float, 0.0, "mm", "lead crowning C_beta: the face ends this much below mid face"),
    "end_relief": Key(float, 0.0, "mm", "end relief C_I at each end face", at_least(0.0)),
    "end_relief_length": Key(float, 0.0, "mm", "length of the end relief from each end face", at_least(0.0)),
    "profile_crowning": Key(float, 0.0, "mm", "profile crowning C_alpha over the active profile"),
    "tip_relief": Key(float, 0.0, "mm", "tip relief C_a at the tip", at_least(0.0)),
    "tip_relief_diameter": Key(float, None, "mm", "where the tip relief starts, d_Ca", positive),
    "helix_angle_modification": Key(float, 0.0, "mm", "helix slope f_Hbeta over the face width (+: more towards +z)"),
    "twist": Key(float, 0.0, "mm", "twist S_beta: helix slope at the tip minus at the root"),
}
FLANK_MODIFICATION_KEYS: dict[str, Key] = {
    **{k: Key(key.kind, None, key.unit, key.doc, key.check) for k, key in MODIFICATION_KEYS.items()},
    "patch": Key(list, None, "mm", "bicubic Bezier patch: 4 x 4 control points [roll length L, z, deviation e]"),
}

#: sections a job may add beside its kind's own
OPTIONAL_SECTIONS = {"measurement": MEASUREMENT_KEYS, "modification": MODIFICATION_KEYS}


def gear_from(values: dict[str, Any]) -> Gear:
    """The Gear of a parsed [gear] section (angles in degrees there)."""
    return Gear(
        teeth=values["teeth"],
        normal_module=values["normal_module"],
        pressure_angle=math.radians(values["pressure_angle"]),
        helix_angle=math.radians(values["helix_angle"]),
        face_width=values["face_width"],
        profile_shift=values["profile_shift"],
        internal=values["internal"],
        tip_diameter=values["tip_diameter"],
        root_diameter=values["root_diameter"],
    )


def parse_modification(table: Any, problems: list[Problem]) -> Modification | None:
    """[modification]: shortcuts for both flanks, and [modification.left] / [modification.right] for one flank
    (its own values replace the shared ones; only there a ``patch``). None when the job has no such section."""
    if table is None:
        return None
    if not isinstance(table, dict):
        problems.append(Problem("modification", table, "must be a table", "write it as [modification]"))
        return None
    shared = parse_section(
        "modification", {k: v for k, v in table.items() if k not in SIDES}, MODIFICATION_KEYS, problems
    )
    flanks = {}
    for side in SIDES:
        own = parse_section(f"modification.{side}", table.get(side, {}), FLANK_MODIFICATION_KEYS, problems)
        values = {**shared, **{k: v for k, v in own.items() if v is not None}}
        patch = values.pop("patch", None)
        if patch is not None:
            patch = _patch(patch, f"modification.{side}.patch", problems)
        flanks[side] = FlankDesign(**values, patch=patch)
    return Modification(**flanks)


def _patch(raw: list, key: str, problems: list[Problem]):
    """4 x 4 control points [L, z, e] as nested tuples, or a problem."""
    try:
        rows = tuple(tuple(tuple(float(c) for c in point) for point in row) for row in raw)
    except (TypeError, ValueError):
        rows = ()
    if len(rows) != 4 or any(len(r) != 4 or any(len(p) != 3 for p in r) for r in rows):
        problems.append(
            Problem(
                key,
                "...",
                "must be 4 rows of 4 control points [L, z, e] in mm",
                "e.g. patch = [[[L, z, e], ...4], ...4], L along the rows",
            )
        )
        return None
    return rows


def parse_optional_sections(
    data: dict[str, Any], problems: list[Problem]
) -> tuple[dict[str, Any], Modification | None]:
    """[measurement] (defaults when absent) and [modification] (None when absent)."""
    measurement = parse_section("measurement", data.get("measurement", {}), MEASUREMENT_KEYS, problems)
    return measurement, parse_modification(data.get("modification"), problems)


def load_gear_section(path: str | Path) -> tuple[Gear, dict[str, Any]]:
    """Only the [gear], [measurement] and [modification] sections of a job, validated: what measuring a gear
    needs (the measurement options, with ``design``: the designed topography or None)."""
    data = read_toml(path)
    problems: list[Problem] = []
    if "gear" not in data:
        raise InputError(
            Problem("gear", None, "the job has no [gear] section", "describe the gear to measure"), str(path)
        )
    g = parse_section("gear", data["gear"], GEAR_KEYS, problems)
    measurement, modification = parse_optional_sections(data, problems)
    if not problems:
        gear = gear_from(g)
        problems += check_gear(gear, "gear")
        if modification is not None and not problems:
            problems += design_problems(modification, gear)
    if problems:
        raise InputError(problems, str(path))
    return gear, {**measurement, "design": modification}
