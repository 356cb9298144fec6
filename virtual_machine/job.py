"""Job files: TOML describing the gear (or thread) to make, the cutter, the process and the machine.

Every key is declared once in the tables below with its type, unit, default and check; the loader
reports *all* problems of a job at once, each naming the key, the value, why and what would be valid.
Units: mm, degrees, rpm, Hz; helix angles signed, right hand positive.
"""

from __future__ import annotations

import difflib
import math
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from cutting.errors import InputError, Problem
from cutting.gear import Gear, check_gear
from cutting.modification import FlankDesign, Modification, design_problems
from cutting.skiving.setup import SkivingSetup, check_setup
from machine_models.sizes import SIZE_NAMES

REQUIRED = object()
STRUCTURES = ("mechanical", "hydraulic-differential", "hydraulic-shaft", "mechatronic")
SYNCHRONIZATIONS = ("equal-coordinates", "master-slave")
SIDES = ("left", "right")
MAX_HELIX = 45.0


@dataclass(frozen=True)
class Key:
    """One job key: expected type, default (REQUIRED if none), unit, meaning and an optional check.

    ``check(value)`` returns ``None`` when fine, else ``(reason, hint)``.
    """

    kind: type | tuple[type, ...]
    default: Any
    unit: str
    doc: str
    check: Callable[[Any], tuple[str, str] | None] | None = None


def _positive(v: float) -> tuple[str, str] | None:
    return None if v > 0 else ("must be > 0", "give a positive number")


def _helix(v: float) -> tuple[str, str] | None:
    if abs(v) < MAX_HELIX:
        return None
    return (
        f"|helix angle| must be below {MAX_HELIX:.0f} deg (ISO 1328-1 validity, skiving practice)",
        "use a helix angle between -45 and +45 deg",
    )


def _pressure(v: float) -> tuple[str, str] | None:
    return None if 10.0 <= v <= 35.0 else ("normal pressure angle outside 10..35 deg", "20 deg is the standard value")


def _one_of(*options: str) -> Callable[[str], tuple[str, str] | None]:
    def check(v: str) -> tuple[str, str] | None:
        return None if v in options else ("not a known value", "use one of " + ", ".join(repr(o) for o in options))

    return check


def _at_least(lo: float) -> Callable[[float], tuple[str, str] | None]:
    def check(v: float) -> tuple[str, str] | None:
        return None if v >= lo else (f"must be >= {lo:g}", f"give a value of at least {lo:g}")

    return check


def _passes(v: list) -> tuple[str, str] | None:
    if not v:
        return ("needs at least one pass", "e.g. [2.0, 1.5, 0.8, 0.2]; the last is the finishing pass")
    if not all(isinstance(p, int | float) and not isinstance(p, bool) for p in v):
        return ("must be a list of numbers [mm]", "e.g. [2.0, 1.5, 0.8, 0.2]")
    if any(p <= 0 for p in v):
        return ("every radial infeed increment must be > 0 mm", "drop zero or negative increments")
    return None


def _change_gears(v: list) -> tuple[str, str] | None:
    if len(v) < 4 or not all(isinstance(t, int) and not isinstance(t, bool) and 12 <= t <= 200 for t in v):
        return ("must list at least 4 tooth counts, integers 12..200", "e.g. [20, 23, 24, 25, 30, ...]")
    return None


GEAR_KEYS: dict[str, Key] = {
    "teeth": Key(int, REQUIRED, "", "number of teeth z2", _at_least(5)),
    "normal_module": Key(float, REQUIRED, "mm", "normal module mn", _positive),
    "pressure_angle": Key(float, 20.0, "deg", "normal pressure angle alpha_n", _pressure),
    "helix_angle": Key(float, 0.0, "deg", "reference helix angle beta2, right hand positive", _helix),
    "face_width": Key(float, REQUIRED, "mm", "face width b", _positive),
    "profile_shift": Key(float, 0.0, "", "profile shift coefficient x2 (positive towards the tooth tip)"),
    "internal": Key(bool, False, "", "true for an internal (ring) gear"),
    "tip_diameter": Key(float, None, "mm", "tip diameter da2 (default from the ISO 53 A basic rack)", _positive),
    "root_diameter": Key(float, None, "mm", "root diameter df2 (default from the ISO 53 A basic rack)", _positive),
}

CUTTER_KEYS: dict[str, Key] = {
    "teeth": Key(int, REQUIRED, "", "number of cutter teeth z0", _at_least(8)),
    "helix_angle": Key(float, REQUIRED, "deg", "cutter helix angle beta0, right hand positive", _helix),
    "profile_shift": Key(float, 0.0, "", "cutter profile shift x0"),
    "tip_diameter": Key(
        float, None, "mm", "cutter tip diameter da0 (default: cuts the gear's root exactly)", _positive
    ),
    "width": Key(float, None, "mm", "cutter body width behind the rake face (default 10 mn)", _positive),
    "holder_diameter": Key(
        float, None, "mm", "diameter of the holder behind the cutter body (default half the cutter's d0)", _positive
    ),
    "edge": Key(
        str,
        "conjugate",
        "",
        "cutting edge: 'conjugate' (envelope method) or 'involute'",
        _one_of("conjugate", "involute"),
    ),
}

PROCESS_KEYS: dict[str, Key] = {
    "tool_speed": Key(float, REQUIRED, "rpm", "cutter spindle speed n0", _positive),
    "axial_feed": Key(float, REQUIRED, "mm/rev", "axial feed s per workpiece revolution", _positive),
    "passes": Key(
        list, REQUIRED, "mm", "radial infeed increments from first touch; the last is the finishing pass", _passes
    ),
    "feed_direction": Key(str, "down", "", "'down' (towards -z) or 'up'", _one_of("down", "up")),
    "material": Key(str, "16MnCr5", "", "workpiece material (cutting forces, later issues)"),
    "clearance": Key(float, 1.0, "mm", "axial approach and overrun added to the engagement zone", _at_least(0.0)),
    # defaults from benchmarks/bench_mesh_tolerance.py (docs/cutting.md, "The manifold solid's tolerance")
    "sweep_error": Key(
        float,
        0.010,
        "mm",
        "the solid's tolerance against the exact surface (manifold: the finishing pass's chord error)",
        _positive,
    ),
    "roughing_sweep_error": Key(float, 0.020, "mm", "chord error allowed in the roughing passes (manifold)", _positive),
    # defaults from benchmarks/bench_dexel.py (docs/cutting.md, "The dexel workpiece", "Spacing")
    "dexel_profile_spacing": Key(float, None, "mm", "dexel rays along the space's profile (default 0.1 mn)", _positive),
    "dexel_face_spacing": Key(float, None, "mm", "dexel slices along the face (default 0.2 mn)", _positive),
    "stl_tolerance": Key(
        float, 0.010, "mm", "how far simplifying gear.stl may move its surface (0: the solid as cut)", _at_least(0.0)
    ),
}

THREAD_KEYS: dict[str, Key] = {
    "lead": Key(float, REQUIRED, "mm", "thread lead P", _positive),
    "hand": Key(str, "right", "", "'right' or 'left'", _one_of("right", "left")),
    "diameter": Key(float, REQUIRED, "mm", "thread major diameter (sets the spindle speed)", _positive),
    "length": Key(float, 30.0, "mm", "threaded length", _positive),
}

THREAD_PROCESS_KEYS: dict[str, Key] = {
    "cutting_speed": Key(float, REQUIRED, "m/min", "cutting speed at the thread diameter", _positive),
    "passes": PROCESS_KEYS["passes"],
    "material": PROCESS_KEYS["material"],
}

MILL_KEYS: dict[str, Key] = {
    "diameter": Key(
        float, REQUIRED, "mm", "outer diameter of the profiled disc mill (copying method, seed 003)", _positive
    ),
    "teeth": Key(int, 12, "", "teeth of the mill (feed per tooth)", _at_least(1)),
    "clearance": Key(
        float, 0.2, "mm", "the mill is this much narrower than the tooth space: one pass per flank", _positive
    ),
}

FORM_PROCESS_KEYS: dict[str, Key] = {
    "feed": Key(float, 300.0, "mm/min", "table feed of the mill along the face", _positive),
    "mill_speed": Key(float, 250.0, "rpm", "mill spindle speed", _positive),
    "path_points": Key(int, 10, "", "path points n per half face width (seed 003: z_i = i b / (2 n))", _at_least(2)),
    "machine_iterations": Key(
        int, 2, "", "runs of the accuracy check on the simulated machine (1: the planned path only)", _at_least(1)
    ),
    "material": PROCESS_KEYS["material"],
    "sweep_error": Key(float, 0.005, "mm", "chord error allowed in the mill's swept volumes (gear.stl)", _positive),
    "stl_tolerance": PROCESS_KEYS["stl_tolerance"],
}

TURNING_KEYS: dict[str, Key] = {
    "diameter": Key(float, REQUIRED, "mm", "workpiece diameter before the cut (sets the spindle speed)", _positive),
    "length": Key(float, 10.0, "mm", "turned length", _positive),
    "feed": Key(float, REQUIRED, "mm/rev", "feed per revolution S0", _positive),
    "nose_radius": Key(float, 0.8, "mm", "tool nose radius r_eps", _positive),
    "depth": Key(float, 0.3, "mm", "depth of cut a_p (less than the nose radius)", _positive),
}

VIBRATION_KEYS: dict[str, Key] = {
    "amplitude": Key(float, REQUIRED, "mm", "axial amplitude A of the feed vibration (seed 004)", _at_least(0.0)),
    "cycles_per_rev": Key(
        float, REQUIRED, "", "vibration cycles per spindle revolution (a fraction shifts them)", _positive
    ),
    "xi": Key(float, 1.0, "", "asymmetry xi = T_in / T_out (1: symmetric vibration)", _positive),
    "form": Key(str, "soft", "", "'soft' (half cosines) or 'hard' (straight strokes)", _one_of("soft", "hard")),
}

TURNING_PROCESS_KEYS: dict[str, Key] = {
    "cutting_speed": THREAD_PROCESS_KEYS["cutting_speed"],
    "material": PROCESS_KEYS["material"],
    "revolutions": Key(int, 40, "", "revolutions cut and measured (after the run-up)", _at_least(8)),
    "sweep_error": Key(float, 0.001, "mm", "chord error of the turned surface's manifold solid", _positive),
}

COUPLING_KEYS: dict[str, Key] = {
    "slots": Key(int, REQUIRED, "", "number of slots m of the face coupling", _at_least(2)),
    "L": Key(float, REQUIRED, "mm", "radius of the point M where the cutting speed is radial (seed 004)", _positive),
    "tool_radius": Key(float, REQUIRED, "mm", "tool head radius R to the element tips", _positive),
    "feed": Key(float, 0.05, "mm/rev", "infeed S per tool revolution", _positive),
    "depth": Key(float, REQUIRED, "mm", "slot depth at M", _positive),
    "inner_radius": Key(float, REQUIRED, "mm", "inner radius of the slotted face", _positive),
    "outer_radius": Key(float, REQUIRED, "mm", "outer radius of the slotted face", _positive),
    "elements": Key(int, 1, "", "cutting elements of the tool head (a sector)", _at_least(1)),
    "element_pitch": Key(float, 0.0, "deg", "phase pitch of the elements on the head", _at_least(0.0)),
    "edge_width": Key(float, 2.0, "mm", "width of an element's straight tip edge", _positive),
    "flank_angle": Key(float, 20.0, "deg", "an element's flank angle", _at_least(0.0)),
    "element_height": Key(float, 5.0, "mm", "height of an element above its tip", _positive),
    "control": Key(
        str,
        "fixed",
        "",
        "'fixed', 'eccentric' or 'cyclic_ratio' (seed 004)",
        _one_of("fixed", "eccentric", "cyclic_ratio"),
    ),
    "e": Key(float, None, "mm", "eccentricity (default: the setting sheet's flat-bottom e)", _at_least(0.0)),
    "eccentric_ratio": Key(int, 4, "", "eccentric turns N per tool revolution", _at_least(1)),
    "ratio_cycles": Key(int, 6, "", "cycles q of the speed ratio per tool revolution", _at_least(1)),
    "ratio_amplitude": Key(
        float, None, "deg", "amplitude of the ratio's cycle (default: straight slots)", _at_least(0.0)
    ),
}

FACE_PROCESS_KEYS: dict[str, Key] = {
    "tool_speed": Key(float, 150.0, "rpm", "tool head speed", _positive),
    "slots_cut": Key(int, 3, "", "slots cut, recorded and measured (0, 1, ...)", _at_least(2)),
    "material": PROCESS_KEYS["material"],
    "sweep_error": Key(float, 0.001, "mm", "chord error of the slots' manifold solid", _positive),
}

MACHINE_KEYS: dict[str, Key] = {
    "structure": Key(str, "mechatronic", "", "kinematic structure (seed 000 figs 1-4)", _one_of(*STRUCTURES)),
    "size": Key(
        str,
        None,
        "",
        "machine size (machine_models/sizes.py); default: the smallest that holds the gear's diameter and module",
        _one_of(*SIZE_NAMES),
    ),
    "synchronization": Key(
        str, "equal-coordinates", "", "electronic synchronisation scheme (seed 001)", _one_of(*SYNCHRONIZATIONS)
    ),
    "adaptive_correction": Key(bool, True, "", "sign/phase discriminator correction of the electronic links"),
    "c1": Key(float, 1.0, "", "product of the fixed ratios of the generating chain (B1 -> B2)", _positive),
    "c2": Key(
        float,
        None,
        "",
        "product of the fixed ratios of the tooth-line chain (lead screw -> B4); "
        "default 1/24 for mechanical/hydraulic structures, 1 for mechatronic",
        _positive,
    ),
    "c3": Key(float, 0.5, "", "product of the fixed ratios motor M1 -> tool spindle (speed chain)", _positive),
    "c4": Key(float, 0.5, "mm", "carriage travel per work revolution with is = 1 (feed chain)", _positive),
    "i_sigma": Key(
        float, 0.5, "", "differential ratio with one input held (bevel differential, carrier out)", _positive
    ),
    "lead_screw_pitch": Key(float, 10.0, "mm", "lead-screw pitch t_TV", _positive),
    "motor_speed": Key(float, 1450.0, "rpm", "main motor speed n_M (4-pole induction motor)", _positive),
    "reference_frequency": Key(
        float,
        1e9,
        "Hz",
        "reference pulse generator 14 (seed 000) / 5 (seed 001); high "
        "enough that kv, a multiple of z0, still sets n0 to better than 1 %",
        _positive,
    ),
    "command_pulses_per_rev": Key(
        int, 10000, "1/rev", "command pulses per revolution of each servo axis", _at_least(1)
    ),
    "encoder_lines": Key(int, 5000, "1/rev", "lines of the encoders (4 counts per line)", _at_least(1)),
    "hydraulic_steps_per_rev": Key(
        int, 3600, "1/rev", "steps per revolution of a hydraulic stepping motor", _at_least(1)
    ),
    "hydraulic_max_windows": Key(
        int, 20000, "", "largest window count of a coding disc of a pulse generator", _at_least(1)
    ),
    "change_gears": Key(list, None, "", "change-gear set (tooth counts; repeat a count for two gears)", _change_gears),
    "i0": Key(float, 1.0, "", "thread group: ratio motor M2 -> lead screw (seed 001 fig 2)", _positive),
    "i01": Key(float, 1.0, "", "thread group: product of the fixed ratios spindle -> lead screw (seed 001)", _positive),
    "model": Key(
        dict,
        None,
        "SI",
        "physical parameters of the MuJoCo machine overriding those of its size (machine_models/sizes.py, "
        "parameters.py; table in docs/machines.md), e.g. [machine.model.work_drive] backlash = 1e-4",
    ),
}

MEASUREMENT_KEYS: dict[str, Key] = {
    "profile_start_diameter": Key(
        float, None, "mm", "start of the profile evaluation range (active profile start)", _positive
    ),
    "profile_end_diameter": Key(float, None, "mm", "end of the profile evaluation range", _positive),
    "sector_teeth": Key(int, None, "", "k of the sector pitch deviation F_pk (default z/8)", _at_least(1)),
    "span_teeth": Key(int, None, "", "spanned teeth k of W_k (default DIN 3960 / 21773)", _at_least(1)),
    "ball_diameter": Key(float, None, "mm", "ball for over-balls and runout (default DIN 3977 size)", _positive),
}

MODIFICATION_KEYS: dict[str, Key] = {
    "lead_crowning": Key(float, 0.0, "mm", "lead crowning C_beta: the face ends this much below mid face"),
    "end_relief": Key(float, 0.0, "mm", "end relief C_I at each end face", _at_least(0.0)),
    "end_relief_length": Key(float, 0.0, "mm", "length of the end relief from each end face", _at_least(0.0)),
    "profile_crowning": Key(float, 0.0, "mm", "profile crowning C_alpha over the active profile"),
    "tip_relief": Key(float, 0.0, "mm", "tip relief C_a at the tip", _at_least(0.0)),
    "tip_relief_diameter": Key(float, None, "mm", "where the tip relief starts, d_Ca", _positive),
    "helix_angle_modification": Key(float, 0.0, "mm", "helix slope f_Hbeta over the face width (+: more towards +z)"),
    "twist": Key(float, 0.0, "mm", "twist S_beta: helix slope at the tip minus at the root"),
}
FLANK_MODIFICATION_KEYS: dict[str, Key] = {
    **{k: Key(key.kind, None, key.unit, key.doc, key.check) for k, key in MODIFICATION_KEYS.items()},
    "patch": Key(list, None, "mm", "bicubic Bezier patch: 4 x 4 control points [roll length L, z, deviation e]"),
}

#: c2 default per structure (see MACHINE_KEYS["c2"]).
C2_DEFAULT = {"mechanical": 1 / 24, "hydraulic-differential": 1 / 24, "hydraulic-shaft": 1 / 24, "mechatronic": 1.0}


def machine_constants(machine: dict[str, Any], structure: str) -> dict[str, Any]:
    """The [machine] values with the structure-dependent defaults resolved for ``structure``."""
    out = dict(machine)
    if out.get("c2") is None:
        out["c2"] = C2_DEFAULT.get(structure, 1.0)
    return out


SECTIONS_GEAR = {"gear": GEAR_KEYS, "cutter": CUTTER_KEYS, "process": PROCESS_KEYS, "machine": MACHINE_KEYS}
OPTIONAL_SECTIONS = {"measurement": MEASUREMENT_KEYS, "modification": MODIFICATION_KEYS}
SECTIONS_THREAD = {"thread": THREAD_KEYS, "process": THREAD_PROCESS_KEYS, "machine": MACHINE_KEYS}
#: a form-milling job (the copying method of seed 003): its machine section only overrides the model's parameters
#: a turning job (vibration turning, seed 004) on the lathe of seed 001
SECTIONS_TURNING = {"turning": TURNING_KEYS, "process": TURNING_PROCESS_KEYS, "machine": MACHINE_KEYS}
#: a face-contour job (continuous indexing of a face coupling, seed 004)
SECTIONS_FACE = {"coupling": COUPLING_KEYS, "process": FACE_PROCESS_KEYS, "machine": {"model": MACHINE_KEYS["model"]}}
SECTIONS_FORM = {
    "gear": GEAR_KEYS,
    "mill": MILL_KEYS,
    "process": FORM_PROCESS_KEYS,
    "machine": {"model": MACHINE_KEYS["model"]},
}


def flatten_model(model: dict[str, Any] | None) -> dict[str, Any]:
    """[machine.model] as flat keys: nested tables become dotted names ("work_drive.backlash")."""
    out: dict[str, Any] = {}
    for k, v in (model or {}).items():
        if isinstance(v, dict):
            out.update({f"{k}.{kk}": vv for kk, vv in flatten_model(v).items()})
        else:
            out[k] = v
    return out


def model_problems(model: dict[str, Any] | None, kind: str) -> list[Problem]:
    """Every key of [machine.model] must name a parameter of the job's machine, with a valid value."""
    if not model:
        return []
    from dataclasses import fields

    from machine_models.form_mill import FormMillParams
    from machine_models.parameters import SkivingMachineParams, override
    from machine_models.thread_lathe import ThreadLatheParams

    lathe = ThreadLatheParams
    from machine_models.face_contour_machine import FaceMachineParams

    machines = {"thread": lathe, "turning": lathe, "form_milling": FormMillParams, "face_contour": FaceMachineParams}
    base = machines.get(kind, SkivingMachineParams)()
    names = ", ".join(f.name for f in fields(base))
    out = []
    good = {}
    for key, value in flatten_model(model).items():
        try:
            override(base, {key: value})
            good[key] = value
        except (KeyError, TypeError) as exc:
            out.append(Problem(f"machine.model.{key}", value, str(exc.args[0]), f"valid parameters: {names}"))
    params = override(base, good)
    return out + [
        Problem("machine.model", good, p, "see the parameter table in docs/machines.md") for p in params.problems()
    ]


def _lathe_has_one_size(machine: dict[str, Any]) -> list[Problem]:
    """machine.size chooses among the skiving machine's sizes; the lathe of seed 001 has one."""
    if machine.get("size") is None:
        return []
    return [
        Problem(
            "machine.size",
            machine["size"],
            "the lathe of seed 001 (thread and turning jobs) comes in one size",
            "remove machine.size (its parameters are set in [machine.model])",
        )
    ]


def _type_name(kind: type | tuple[type, ...]) -> str:
    names = {int: "an integer", float: "a number", bool: "true or false", str: "a string", list: "a list"}
    return names.get(kind, str(kind))


def _coerce(raw: Any, key: Key) -> tuple[Any, str | None]:
    """Value of the declared type, or an error message. Integers are accepted where numbers are."""
    if key.kind is float:
        if isinstance(raw, bool) or not isinstance(raw, int | float):
            return None, "expected a number"
        if not math.isfinite(raw):
            return None, "expected a finite number"
        return float(raw), None
    if key.kind is int:
        if isinstance(raw, bool) or not isinstance(raw, int):
            return None, "expected an integer"
        return raw, None
    if not isinstance(raw, key.kind):
        return None, f"expected {_type_name(key.kind)}"
    return raw, None


def parse_section(name: str, table: Any, keys: dict[str, Key], problems: list[Problem]) -> dict[str, Any]:
    """Typed values of one section with defaults filled in; problems appended, never raised here."""
    out: dict[str, Any] = {}
    if not isinstance(table, dict):
        problems.append(Problem(name, table, "must be a table", f"write it as [{name}] with key = value lines"))
        return out
    for k in table:
        if k not in keys:
            close = [
                c for c in keys if c.replace("_", "") in k.replace("_", "") or k.replace("_", "") in c.replace("_", "")
            ] or difflib.get_close_matches(k, list(keys), n=1, cutoff=0.8)  # a letter left out, swapped, doubled
            hint = f"did you mean {close[0]!r}? " if close else ""
            problems.append(Problem(f"{name}.{k}", table[k], "unknown key", hint + "valid keys: " + ", ".join(keys)))
    for k, key in keys.items():
        if k not in table:
            if key.default is REQUIRED:
                problems.append(
                    Problem(
                        f"{name}.{k}",
                        None,
                        f"missing required key ({key.doc})",
                        f"add {k} = <{_type_name(key.kind)}{', ' + key.unit if key.unit else ''}>",
                    )
                )
            else:
                out[k] = key.default
            continue
        value, err = _coerce(table[k], key)
        if err:
            problems.append(Problem(f"{name}.{k}", table[k], err, f"{key.doc} [{key.unit or '-'}]"))
            continue
        if key.check is not None:
            bad = key.check(value)
            if bad:
                problems.append(Problem(f"{name}.{k}", table[k], bad[0], bad[1]))
                continue
        out[k] = value
    return out


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


@dataclass(frozen=True)
class Job:
    """A parsed, validated job. ``kind`` is "gear" (skiving), "form_milling" (the copying method) or "thread";
    unused sections are None."""

    source: str
    kind: str
    machine: dict[str, Any]
    process: dict[str, Any]
    gear: Gear | None = None
    cutter: Gear | None = None
    cutter_options: dict[str, Any] | None = None
    thread: dict[str, Any] | None = None
    measurement: dict[str, Any] | None = None
    modification: Modification | None = None  # the designed flank topography ([modification])
    mill: dict[str, Any] | None = None  # the profiled disc mill ([mill]) of a form-milling job
    turning: dict[str, Any] | None = None  # [turning] of a turning job (its [thread] the lathe's feed as a lead)
    vibration: Any = None  # the feed vibration (cutting.turning.vibration.FeedVibration) or None
    coupling: Any = None  # the face coupling (cutting.face_contour.slots.FaceCoupling) of a face-contour job

    @property
    def skiving(self) -> SkivingSetup:
        if self.gear is None or self.cutter is None:
            raise ValueError(f"{self.source} is a {self.kind.replace('_', '-')} job; it has no skiving setup")
        p = self.process
        return SkivingSetup(
            self.gear,
            self.cutter,
            p["tool_speed"],
            p["axial_feed"],
            tuple(p["passes"]),
            p["feed_direction"],
            p["clearance"],
            holder_diameter=(self.cutter_options or {}).get("holder_diameter"),
        )


def _gear_from(values: dict[str, Any]) -> Gear:
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


def parse_job(data: dict[str, Any], source: str = "<job>") -> Job:
    """Validate a job given as a dict (as read from TOML). Raises :class:`InputError` with every problem."""
    problems: list[Problem] = []
    is_thread = "thread" in data
    if "mill" in data:
        return _parse_form_job(data, source)
    if "turning" in data:
        return _parse_turning_job(data, source)
    if "coupling" in data:
        return _parse_face_job(data, source)
    if is_thread and "gear" in data:
        raise InputError(
            Problem(
                "thread",
                "[thread] and [gear]",
                "a job describes either a gear or a thread",
                "remove one of the two sections",
            ),
            source,
        )
    sections = SECTIONS_THREAD if is_thread else SECTIONS_GEAR
    for name in data:
        if name not in sections and name not in OPTIONAL_SECTIONS:
            problems.append(
                Problem(
                    name, "[section]", "unknown section", "valid sections: " + ", ".join(f"[{s}]" for s in sections)
                )
            )
    parsed = {name: parse_section(name, data.get(name, {}), keys, problems) for name, keys in sections.items()}
    measurement = parse_section("measurement", data.get("measurement", {}), MEASUREMENT_KEYS, problems)
    modification = parse_modification(data.get("modification"), problems)
    machine = parsed["machine"]
    problems += model_problems(machine.get("model"), "thread" if is_thread else "gear")
    if is_thread:
        problems += _lathe_has_one_size(machine)
        if problems:
            raise InputError(problems, source)
        return Job(source, "thread", machine, parsed["process"], thread=parsed["thread"])

    # Geometry checks run as soon as their own keys are sound, so they are reported beside key errors.
    g, c = parsed["gear"], parsed["cutter"]
    gear_ok = set(GEAR_KEYS) <= set(g)
    cutter_ok = gear_ok and set(CUTTER_KEYS) <= set(c)
    gear = cutter = None
    if gear_ok:
        gear = _gear_from(g)
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
    if gear is not None and modification is not None:
        problems += design_problems(modification, gear)
    if problems:
        raise InputError(problems, source)
    job = Job(
        source,
        "gear",
        machine,
        parsed["process"],
        gear=gear,
        cutter=cutter,
        cutter_options={"edge": c["edge"], "holder_diameter": c["holder_diameter"]},
        measurement=measurement,
        modification=modification,
    )
    problems += check_setup(job.skiving)
    if problems:
        raise InputError(problems, source)
    return job


def _parse_face_job(data: dict[str, Any], source: str) -> Job:
    """A face-contour job (seed 004): [coupling], [process], [machine]; the coupling's own checks name their key."""
    problems: list[Problem] = []
    for name in data:
        if name not in SECTIONS_FACE:
            problems.append(
                Problem(name, "[section]", "unknown section", "valid sections: [coupling], [process], [machine]")
            )
    parsed = {name: parse_section(name, data.get(name, {}), keys, problems) for name, keys in SECTIONS_FACE.items()}
    problems += model_problems(parsed["machine"].get("model"), "face_contour")
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
    return Job(source, "face_contour", parsed["machine"], parsed["process"], coupling=coupling)


def _coupling(c: dict[str, Any]):
    """The FaceCoupling of [coupling]; an eccentric without e gets the flat-bottom e, a cyclic ratio without its
    amplitude the straight-slot one (both from the setting sheet)."""
    import dataclasses

    from cutting.face_contour.slots import FaceCoupling, flat_bottom_eccentricity, straight_slot_amplitude

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
    )
    if coupling.control == "eccentric" and c["e"] is None:
        coupling = dataclasses.replace(coupling, e=flat_bottom_eccentricity(coupling))
    if coupling.control == "cyclic_ratio" and c["ratio_amplitude"] is None:
        coupling = dataclasses.replace(coupling, ratio_amplitude=straight_slot_amplitude(coupling))
    return coupling


def _parse_turning_job(data: dict[str, Any], source: str) -> Job:
    """A turning job on the lathe of seed 001: [turning], an optional [vibration], [process], [machine]. The lathe
    is set up as for a thread whose lead is the feed S0 (right hand: the carriage feeds towards the chuck)."""
    problems: list[Problem] = []
    for name in data:
        if name not in SECTIONS_TURNING and name != "vibration":
            problems.append(
                Problem(
                    name,
                    "[section]",
                    "unknown section",
                    "valid sections: " + ", ".join(f"[{s}]" for s in (*SECTIONS_TURNING, "vibration")),
                )
            )
    parsed = {name: parse_section(name, data.get(name, {}), keys, problems) for name, keys in SECTIONS_TURNING.items()}
    machine = parsed["machine"]
    problems += model_problems(machine.get("model"), "turning") + _lathe_has_one_size(machine)
    vib_values = (
        parse_section("vibration", data["vibration"], VIBRATION_KEYS, problems) if "vibration" in data else None
    )
    t = parsed["turning"]
    vibration = None
    if not problems:
        from cutting.turning.vibration import FeedVibration, TurningSetup

        try:
            if vib_values is not None:
                vibration = FeedVibration(
                    vib_values["amplitude"], vib_values["cycles_per_rev"], vib_values["xi"], vib_values["form"]
                )
            TurningSetup(t["diameter"] / 2, t["feed"], t["nose_radius"], t["depth"], vibration)
        except ValueError as exc:
            field = str(exc).split()[0]
            section = "vibration" if field in VIBRATION_KEYS else "turning"
            problems.append(Problem(f"{section}.{field}", "", str(exc), "see docs/face-contours-and-turning.md"))
        if vibration is not None and (machine["structure"], machine["synchronization"]) != (
            "mechatronic",
            "master-slave",
        ):
            problems.append(
                Problem(
                    "machine.synchronization",
                    machine["synchronization"],
                    "vibration turning needs the feed axis to follow the spindle's encoder",
                    "set structure = 'mechatronic' and synchronization = 'master-slave'",
                )
            )
    if problems:
        raise InputError(problems, source)
    thread = {"lead": t["feed"], "hand": "right", "diameter": t["diameter"], "length": t["length"]}
    process = {**parsed["process"], "passes": [t["depth"]]}
    return Job(source, "turning", machine, process, thread=thread, turning=t, vibration=vibration)


def _parse_form_job(data: dict[str, Any], source: str) -> Job:
    """A form-milling job: [gear], [mill], [process], [machine], [measurement], [modification]."""
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
    for name in data:
        if name not in SECTIONS_FORM and name not in OPTIONAL_SECTIONS and name != "cutter":
            problems.append(
                Problem(
                    name,
                    "[section]",
                    "unknown section",
                    "valid sections: " + ", ".join(f"[{s}]" for s in (*SECTIONS_FORM, *OPTIONAL_SECTIONS)),
                )
            )
    parsed = {name: parse_section(name, data.get(name, {}), keys, problems) for name, keys in SECTIONS_FORM.items()}
    measurement = parse_section("measurement", data.get("measurement", {}), MEASUREMENT_KEYS, problems)
    modification = parse_modification(data.get("modification"), problems)
    problems += model_problems(parsed["machine"].get("model"), "form_milling")
    g, mill = parsed["gear"], parsed["mill"]
    gear = None
    if set(GEAR_KEYS) <= set(g):
        gear = _gear_from(g)
        problems += check_gear(gear, "gear")
        from cutting.form_milling.mill import check_copying_gear

        problems += [
            Problem("gear", "internal" if gear.internal else f"helix_angle = {g['helix_angle']}", why, "")
            for why in check_copying_gear(gear)
        ]
        sound = not problems  # the mill and the design are checked on a gear the copying method can make
        if sound and set(MILL_KEYS) <= set(mill):
            problems += _mill_problems(gear, mill)
        if sound and modification is not None:
            problems += design_problems(modification, gear)
    if problems:
        raise InputError(problems, source)
    return Job(
        source,
        "form_milling",
        parsed["machine"],
        parsed["process"],
        gear=gear,
        measurement=measurement,
        modification=modification,
        mill=mill,
    )


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


def read_toml(path: str | Path) -> dict[str, Any]:
    """The TOML of a job file, or an InputError naming the file."""
    p = Path(path)
    if not p.is_file():
        raise InputError(
            Problem(
                "job", str(p), "no such file", "give the path of a .toml job file, e.g. assets/jobs/spur_external.toml"
            )
        )
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise InputError(
            Problem("job", str(p), f"not valid TOML: {exc}", "fix the syntax at the line shown"), str(p)
        ) from exc
    return data


def load_job(path: str | Path) -> Job:
    """Read and validate a TOML job file."""
    return parse_job(read_toml(path), str(path))


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
    measurement = parse_section("measurement", data.get("measurement", {}), MEASUREMENT_KEYS, problems)
    modification = parse_modification(data.get("modification"), problems)
    if not problems:
        gear = _gear_from(g)
        problems += check_gear(gear, "gear")
        if modification is not None and not problems:
            problems += design_problems(modification, gear)
    if problems:
        raise InputError(problems, str(path))
    return gear, {**measurement, "design": modification}


def dexel_spacing(job: Job):
    """The dexel lines of a skiving job: the process's spacings, else the gear's defaults
    (cutting.skiving.dexel_lines)."""
    from cutting.skiving.dexel_lines import DexelSpacing

    p = job.process
    return DexelSpacing.for_gear(job.gear, p["axial_feed"], p.get("dexel_profile_spacing"), p.get("dexel_face_spacing"))


def with_machine(job: Job, **overrides: Any) -> Job:
    """The job with [machine] keys replaced (``None``: kept as the job says), e.g. another structure."""
    given = {k: v for k, v in overrides.items() if v is not None}
    return replace(job, machine={**job.machine, **given}) if given else job


def default_job_path() -> Path:
    """The default job shipped in assets/jobs/ beside the packages."""
    return Path(__file__).resolve().parent.parent / "assets" / "jobs" / "default.toml"
