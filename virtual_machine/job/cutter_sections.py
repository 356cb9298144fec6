"""The skiving cutter's rake face and deviations and the blank's clamping: [cutter]'s rake keys, [cutter.errors] and
[workpiece] (mm, degrees), parsed into :mod:`cutting.skiving.tooling`'s frozen records.

Every deviation is a study key like any other (``cutter.errors.radial_runout``); docs/cutter.md gives the geometry.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from cutting.errors import Problem
from cutting.skiving.tooling import RAKE_FACES, Clamping, CutterErrors, Deviation, RakeFace, random_pitch
from virtual_machine.job.keys import Key, at_least, one_of, parse_section


def between(lo: float, hi: float):
    def check(v: float) -> tuple[str, str] | None:
        return None if lo <= v <= hi else (f"outside {lo:g}..{hi:g}", f"give a value from {lo:g} to {hi:g}")

    return check


RAKE_KEYS: dict[str, Key] = {
    "rake_face": Key(
        str,
        "plane",
        "",
        "'plane' (one face normal to the cutter axis) or 'stepped' (each tooth's face normal to its tooth direction)",
        one_of(*RAKE_FACES),
    ),
    "rake_face_offset": Key(
        float, 0.0, "mm", "the rake face's position along the cutter axis from the axes' common perpendicular"
    ),
    # a guess from shaper-cutter practice (docs/cutter.md, "Relief"): no cutter maker's table was at hand
    "clearance_angle": Key(
        float, 6.0, "deg", "tip clearance of the conical relief (the side clearance follows)", between(0.0, 20.0)
    ),
    "regrind": Key(float, 0.0, "mm", "ground off the rake face since the tool was new", at_least(0.0)),
    "rake_angle": Key(
        float,
        0.0,
        "deg",
        "rake angle gamma: the face inclined into a cone, receding into the body inwards of the tip edge",
        between(-20.0, 20.0),
    ),
}

CUTTER_ERROR_KEYS: dict[str, Key] = {
    "radial_runout": Key(
        float, 0.0, "mm", "radial runout of the cutter at its tip (total indicator reading)", at_least(0)
    ),
    "radial_runout_phase": Key(float, 0.0, "deg", "where the radial runout is highest, from tooth 0"),
    "axial_runout": Key(
        float, 0.0, "mm", "axial runout of the rake face at the tip (total indicator reading)", at_least(0)
    ),
    "axial_runout_phase": Key(float, 0.0, "deg", "where the rake face runs farthest along the cutter axis"),
    "pitch": Key(list, None, "mm", "single pitch deviations f_pt, one per cutter pitch (pitch k: teeth k-1 to k)"),
    "pitch_tolerance": Key(float, None, "mm", "a random cutter: single pitch deviations within +-this", at_least(0)),
    "seed": Key(int, 0, "", "the random cutter's seed (with pitch_tolerance)"),
    **{
        f"profile_{kind}_{side}": Key(
            (float, list),
            0.0,
            "mm",
            f"the {side} flanks' profile {kind} deviation ({doc}): one for every tooth, or a list of one per tooth",
        )
        for kind, doc in (("slope", "f_H over the active flank, + more tool material towards its tip"), ("form", "f_f"))
        for side in ("left", "right")
    },
}

WORKPIECE_KEYS: dict[str, Key] = {
    "eccentricity": Key(float, 0.0, "mm", "the blank's axis off the work spindle's axis", at_least(0)),
    "eccentricity_phase": Key(float, 0.0, "deg", "towards this angle of the blank (0: the centre of space 0)"),
    "tilt": Key(float, 0.0, "mm", "axial runout of the blank's face at the reference diameter", at_least(0)),
    "tilt_phase": Key(float, 0.0, "deg", "where the face runs farthest along +z"),
}

#: A deviation above this share of the module is taken for a slip of units (8 for 0.008 mm), not a tolerance: a guess
#: at a guard, not a tolerance figure (cutter and clamping tolerances are micrometres, far below it).
LARGEST_DEVIATION = 0.1


def _size_problems(name: str, values: dict[str, Any], keys: tuple[str, ...], mn: float) -> list[Problem]:
    out = []
    for k in keys:
        v = values.get(k)
        if v is not None and v > LARGEST_DEVIATION * mn:
            out.append(
                Problem(
                    f"{name}.{k}",
                    v,
                    f"above {LARGEST_DEVIATION:g} mn = {LARGEST_DEVIATION * mn:g} mm: a setup error, not a tolerance",
                    "lengths are in mm: 8 um is 0.008",
                )
            )
    return out


def parse_cutter_errors(table: Any, teeth: int, mn: float, problems: list[Problem]) -> CutterErrors:
    """[cutter.errors] of a cutter of ``teeth`` teeth; problems appended."""
    before = len(problems)
    v = parse_section("cutter.errors", table if table is not None else {}, CUTTER_ERROR_KEYS, problems)
    if len(problems) > before or not v:  # a key in error has no value: the problems say what to change
        return CutterErrors()
    profile = {k: _profile_values(k, v[k], teeth, problems) for k in v if k.startswith("profile_")}
    sizes = ("radial_runout", "axial_runout", "pitch_tolerance", *(k for k in v if k.startswith("profile_")))
    size_of = {k: abs(x) if isinstance(x, float) else x for k, x in v.items()}
    size_of.update({k: max(map(abs, np.atleast_1d(x))) for k, x in profile.items()})
    problems += _size_problems("cutter.errors", size_of, sizes, mn)
    pitch: tuple[float, ...] = ()
    if v.get("pitch") is not None and v.get("pitch_tolerance") is not None:
        problems.append(Problem("cutter.errors.pitch", v["pitch"], "given with pitch_tolerance", "give one of the two"))
    elif v.get("pitch") is not None:
        pitch = _pitch_list(v["pitch"], teeth, mn, problems)
    elif v.get("pitch_tolerance"):
        pitch = random_pitch(v["pitch_tolerance"], teeth, v["seed"])
    return CutterErrors(
        v["radial_runout"],
        math.radians(v["radial_runout_phase"]),
        v["axial_runout"],
        math.radians(v["axial_runout_phase"]),
        pitch,
        (profile["profile_slope_left"], profile["profile_slope_right"]),
        (profile["profile_form_left"], profile["profile_form_right"]),
    )


def _profile_values(key: str, raw: float | list, teeth: int, problems: list[Problem]) -> Deviation:
    """A profile deviation: a number for every tooth, or a list of one per tooth (a tuple; all alike: the number)."""
    if not isinstance(raw, list):
        return raw
    if len(raw) != teeth or not all(isinstance(x, int | float) and not isinstance(x, bool) for x in raw):
        hint = f"in mm, tooth 0 first; or one number for every tooth (a list of {len(raw)} given)"
        why = f"must be a list of {teeth} numbers (one per tooth)"
        problems.append(Problem(f"cutter.errors.{key}", raw, why, hint))
        return 0.0
    values = tuple(float(x) for x in raw)
    return values[0] if len(set(values)) == 1 else values


def _pitch_list(raw: list, teeth: int, mn: float, problems: list[Problem]) -> tuple[float, ...]:
    name = "cutter.errors.pitch"
    if len(raw) != teeth or not all(isinstance(x, int | float) and not isinstance(x, bool) for x in raw):
        problems.append(Problem(name, raw, f"must be a list of {teeth} numbers (one per cutter pitch)", "in mm"))
        return ()
    f = tuple(float(x) for x in raw)
    if abs(sum(f)) > 1e-6:
        problems.append(
            Problem(
                name,
                raw,
                f"sums to {sum(f):.6f} mm: single pitch deviations close the circle and sum to 0",
                f"subtract their mean ({sum(f) / teeth:.6f} mm) from each",
            )
        )
    if max(abs(x) for x in f) > LARGEST_DEVIATION * mn:
        problems.append(
            Problem(name, raw, f"a value above {LARGEST_DEVIATION * mn:g} mm: not a tolerance", "lengths are in mm")
        )
    return f


def parse_clamping(table: Any, mn: float, problems: list[Problem]) -> Clamping:
    """[workpiece]; problems appended."""
    if table is None:
        return Clamping()
    before = len(problems)
    v = parse_section("workpiece", table, WORKPIECE_KEYS, problems)
    if len(problems) > before or not v:
        return Clamping()
    problems += _size_problems("workpiece", v, ("eccentricity", "tilt"), mn)
    return Clamping(v["eccentricity"], math.radians(v["eccentricity_phase"]), v["tilt"], math.radians(v["tilt_phase"]))


def rake_face(values: dict[str, Any]) -> RakeFace:
    """The rake face of a parsed [cutter] section."""
    return RakeFace(
        values["rake_face"],
        values["rake_face_offset"],
        math.radians(values["clearance_angle"]),
        values["regrind"],
        math.radians(values["rake_angle"]),
    )


def regrind_problems(setup, regrind: float, width: float) -> list[Problem]:
    """Why the tool of ``setup`` (new) cannot be reground by ``regrind`` [mm]: the body it has, the relieved teeth
    it leaves (their profile shift falls by d tan(alpha_a) / mn: under the cutter's undercut limit they are
    undercut)."""
    if not regrind:
        return []
    r, c = setup.rake, setup.cutter
    depth = dataclasses.replace(r, regrind=regrind).relief_depth(c.helix_angle)
    if depth >= width:
        return [Problem("cutter.regrind", regrind, f"the cutter body is {width:g} mm wide", "a new tool")]
    per_mm = math.tan(r.clearance_angle) / c.mn * depth / regrind if r.clearance_angle else 0.0
    x_left = c.x - per_mm * regrind
    if per_mm and x_left < c.min_profile_shift - 1e-9:
        most = (c.x - c.min_profile_shift) / per_mm
        return [
            Problem(
                "cutter.regrind",
                regrind,
                f"the reground teeth would be undercut (x0 {c.x:+.3f} -> {x_left:+.3f}, "
                f"below {c.min_profile_shift:+.3f})",
                f"regrind at most {most:.2f} mm: beyond, a new tool",
            )
        ]
    return []
