"""Study files: which job keys a study varies, how, and what tolerance each machine part is held to.

A study file names a base job and a list of ``[[vary]]`` entries::

    base = "../jobs/default.toml"            # relative to the study file
    method = "one-at-a-time"                 # or "grid" (full factorial) or "monte-carlo"
    samples = 50                             # monte-carlo only
    seed = 1                                 # monte-carlo only: the same seed draws the same cases
    cache = "../cases"                       # optional: a case store shared with other studies (study/cache.py)
    cutter_class = "A"                       # monte-carlo only: the cutters drawn from a tolerance class (AA, A, B)
    machine_tolerances = "medium"            # monte-carlo only: the machines drawn from a size's geometric tolerances
    stage = "run"                            # what each case runs: "run" (the simulated machine) or "cut" (ideal)
    [[vary]]
    key = "machine.model.work_drive.backlash"  # any job key, dotted
    label = "work-drive backlash"            # the part's name in the report (default: the key)
    values = [1e-4, 5e-4, 1e-3]              # or range = [lo, hi] with steps = n
    tolerance = 2e-4                         # the part's stated tolerance about its base value (error budget)
    # monte-carlo: distribution = "normal" (mean, std) or "uniform" (lo, hi); values = [...] draws among them

Every key is checked against the job schema (virtual_machine/job/) before anything runs: a misspelt key
names the valid ones, an empty range or a value the job refuses is reported with the key and why.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from cutting.errors import InputError, Problem
from virtual_machine.job import (
    OPTIONAL_SECTIONS,
    REQUIRED,
    SECTIONS_GEAR,
    parse_job,
    read_toml,
)
from virtual_machine.job.cutter_sections import CUTTER_ERROR_KEYS
from virtual_machine.job.kinds import GRADED
from virtual_machine.job.skiving import SKIVING_OPTIONAL

METHODS = ("one-at-a-time", "grid", "monte-carlo")
DISTRIBUTIONS = ("normal", "uniform")
STUDY_KEYS = ("base", "method", "samples", "seed", "cache", "vary", "cutter_class", "machine_tolerances", "stage")
#: what a study's cases run (virtual_machine/studies/runner.py: STAGES); a study grades classes, so not "exact"
STUDY_STAGES = ("run", "cut")
VARY_KEYS = ("key", "label", "values", "range", "steps", "distribution", "mean", "std", "lo", "hi", "tolerance")
MODEL_PREFIX = "machine.model."
GEOMETRY_PREFIX = "machine.model.geometry."
THERMAL_PREFIX = "machine.model.thermal."


@dataclass(frozen=True)
class Vary:
    """One varied part: the job ``key`` (dotted), its ``label``, its ``base`` value in the base job (defaults
    resolved), the studied ``values`` (one-at-a-time, grid; discrete choices in a Monte-Carlo study) or a
    ``distribution`` with its parameters, and the part's stated ``tolerance`` about its base value (None: not
    stated; the budget then reports the part's effect but does not stack it)."""

    key: str
    label: str
    base: Any
    values: tuple[Any, ...] | None = None
    distribution: str | None = None
    mean: float | None = None
    std: float | None = None
    lo: float | None = None
    hi: float | None = None
    tolerance: float | None = None

    @property
    def numeric(self) -> bool:
        """Whether the key is a number (or a switch, taken as 0/1): sensitivities per unit make sense."""
        return isinstance(self.base, int | float)

    def describe(self) -> str:
        if self.distribution == "normal":
            return f"normal(mean {self.mean:g}, std {self.std:g})"
        if self.distribution == "uniform":
            return f"uniform({self.lo:g}, {self.hi:g})"
        return ", ".join(_show(v) for v in self.values or ())


@dataclass(frozen=True)
class Study:
    path: Path
    base_path: Path
    base_data: dict[str, Any]  # the base job as read from TOML
    method: str
    varies: tuple[Vary, ...]
    samples: int = 0
    seed: int = 0
    cache: Path | None = None  # the case store shared with other studies (absolute), or none
    stage: str = "run"  # what each case runs: `skive run` or `skive cut`

    @property
    def name(self) -> str:
        return self.path.stem


def _show(v: Any) -> str:
    return repr(v) if isinstance(v, list | str) else f"{v:g}" if isinstance(v, float) else str(v)


def get_key(data: dict[str, Any], key: str) -> Any:
    """The value at dotted ``key`` of a job dict, KeyError if absent."""
    node: Any = data
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            raise KeyError(key)
        node = node[part]
    return node


def set_key(data: dict[str, Any], key: str, value: Any) -> dict[str, Any]:
    """A deep copy of the job dict with dotted ``key`` set to ``value`` (tables created as needed)."""
    out = copy.deepcopy(data)
    node = out
    parts = key.split(".")
    for part in parts[:-1]:
        node = node.setdefault(part, {})
        if not isinstance(node, dict):
            raise KeyError(key)
    node[parts[-1]] = value
    return out


def base_value(data: dict[str, Any], key: str) -> Any:
    """The value the base job has for ``key``: its own, else the schema's default (machine parameters from
    machine_models/parameters.py). A key the schema does not know raises InputError naming the valid ones."""
    try:
        return get_key(data, key)
    except KeyError:
        pass
    section, _, rest = key.partition(".")
    if key == "machine.size":  # the base job's own size, or the one its gear gets by default
        from virtual_machine.setting.machine_layout import machine_size

        return machine_size(parse_job(data))
    if key == "machine.thermal_state":  # no thermal model in the base job: the machine is cold
        return "cold"
    if key.startswith(THERMAL_PREFIX):  # the thermal model's figures: job keys of their own (the defaults' figures)
        from virtual_machine.job.thermal_section import THERMAL_KEYS

        name = key[len(THERMAL_PREFIX) :]
        if name not in THERMAL_KEYS:
            valid = ", ".join(THERMAL_PREFIX + k for k in THERMAL_KEYS)
            raise InputError(Problem(key, None, "unknown thermal model key", f"valid keys: {valid}"))
        return THERMAL_KEYS[name].default
    if key.startswith(GEOMETRY_PREFIX):  # the machine's geometric errors: job keys of their own (0 by default)
        from virtual_machine.job.geometry_section import GEOMETRY_KEYS

        name = key[len(GEOMETRY_PREFIX) :]
        if name not in GEOMETRY_KEYS:
            valid = ", ".join(GEOMETRY_PREFIX + k for k in GEOMETRY_KEYS)
            raise InputError(Problem(key, None, "unknown machine geometry key", f"valid keys: {valid}"))
        return GEOMETRY_KEYS[name].default
    if key.startswith(MODEL_PREFIX):
        from machine_models.parameters import SkivingMachineParams, parameter
        from virtual_machine.setting.machine_layout import machine_params

        params = machine_params(parse_job(data))  # the base job's size and model (the job was parsed before)
        try:
            return parameter(params, key[len(MODEL_PREFIX) :])
        except KeyError as exc:
            names = ", ".join(f.name for f in fields(SkivingMachineParams))
            raise InputError(Problem(key, None, str(exc.args[0]), f"valid parameters: {names}")) from None
    sections = {**SECTIONS_GEAR, **OPTIONAL_SECTIONS, **SKIVING_OPTIONAL, "cutter.errors": CUTTER_ERROR_KEYS}
    if key.startswith("cutter.errors."):  # the one nested table of a job's keys
        section, rest = "cutter.errors", key[len("cutter.errors.") :]
    if section not in sections:
        valid = ", ".join(sections)
        raise InputError(Problem(key, None, f"unknown job section {section!r}", f"valid sections: {valid}"))
    keys = sections[section]
    if rest not in keys:
        valid = ", ".join(f"{section}.{k}" for k in keys) + (
            ", machine.model.<parameter>" if section == "machine" else ""
        )
        raise InputError(Problem(key, None, "unknown job key", f"valid keys: {valid}"))
    default = keys[rest].default
    if default is REQUIRED:  # a required key is always in a valid base job
        raise InputError(Problem(key, None, "the base job lacks this required key", "add it to the base job"))
    return default


def typed(value: Any, base: Any) -> Any:
    """A studied value in the base value's type: integers stay integers (a range or a draw is rounded)."""
    if isinstance(base, bool) or not isinstance(base, int) or isinstance(value, bool):
        return value
    if isinstance(value, float) and math.isfinite(value):
        return round(value)
    return value


def load_study(path: str | Path) -> Study:
    """Read and check a study file; InputError lists every problem (none of the cases has run)."""
    path = Path(path)
    source = str(path)
    data = read_toml(path)
    problems: list[Problem] = []
    for k in data:
        if k not in STUDY_KEYS:
            problems.append(Problem(k, data[k], "unknown study key", "valid keys: " + ", ".join(STUDY_KEYS)))
    method = data.get("method", "one-at-a-time")
    if method not in METHODS:
        problems.append(Problem("method", method, "unknown method", "use one of " + ", ".join(map(repr, METHODS))))
    samples, seed = data.get("samples", 0), data.get("seed", 0)
    if method == "monte-carlo" and not (isinstance(samples, int) and not isinstance(samples, bool) and samples >= 2):
        problems.append(Problem("samples", samples, "a Monte-Carlo study needs samples >= 2", "e.g. samples = 50"))
    if not isinstance(seed, int) or isinstance(seed, bool):
        problems.append(Problem("seed", seed, "must be an integer", "e.g. seed = 1"))
    cache = data.get("cache")
    if cache is not None and not (isinstance(cache, str) and cache):
        problems.append(Problem("cache", cache, "must be a directory path", 'e.g. cache = "../cases"'))
        cache = None
    stage = data.get("stage", "run")
    if stage not in STUDY_STAGES:
        problems.append(Problem("stage", stage, "not a stage a study's cases run", 'use "run" or "cut"'))
    base_path, base_data = _base_job(path, data, problems, source)
    entries = data.get("vary", [])
    if "cutter_class" in data:
        entries = [
            *(entries if isinstance(entries, list) else []),
            *_cutter_class(data["cutter_class"], method, base_data, problems),
        ]
    if "machine_tolerances" in data:
        entries = [
            *(entries if isinstance(entries, list) else []),
            *machine_tolerance_entries(data["machine_tolerances"], method, base_data, problems),
        ]
    varies = _varies(entries, method, base_data, problems)
    if problems:
        raise InputError(problems, source)
    return Study(
        path,
        base_path,
        base_data,
        method,
        varies,
        samples if method == "monte-carlo" else 0,
        seed,
        (path.parent / cache).resolve() if cache else None,
        stage,
    )


def _cutter_class(cls: Any, method: str, base_data: dict[str, Any], problems: list[Problem]) -> list[dict]:
    """[[vary]] tables that draw the study's cutters from a tolerance class (cutting/skiving/cutter_classes.py, the
    base job's module): each deviation uniform within its tolerance (the runouts from 0 to it at any phase, the
    profile slopes within +-half of it, the form up to half of it: FfS bounds their sum), the single pitch
    deviations a random cutter within +-its tolerance (a fresh seed per case). An assumption on how a class's
    cutters spread, not a published distribution: a class says only what no cutter of it exceeds."""
    from cutting.skiving.cutter_classes import CLASSES, cutter_tolerances

    if method != "monte-carlo":
        problems.append(Problem("cutter_class", cls, "draws cutters: a Monte-Carlo study's", 'method = "monte-carlo"'))
        return []
    if cls not in CLASSES:
        problems.append(Problem("cutter_class", cls, "unknown class", "use one of " + ", ".join(map(repr, CLASSES))))
        return []
    if isinstance(base_data.get("cutter", {}).get("errors", {}).get("pitch"), list):
        problems.append(
            Problem("cutter_class", cls, "the base job's cutter has its own pitch deviations", "remove them")
        )
        return []
    t = cutter_tolerances(cls, parse_job(base_data).gear.mn)
    e = "cutter.errors."
    out = [
        {"key": e + "radial_runout", "distribution": "uniform", "lo": 0.0, "hi": t["radial_runout"],
         "tolerance": t["radial_runout"]},
        {"key": e + "radial_runout_phase", "distribution": "uniform", "lo": 0.0, "hi": 360.0},
        {"key": e + "axial_runout", "distribution": "uniform", "lo": 0.0, "hi": t["axial_runout"],
         "tolerance": t["axial_runout"]},
        {"key": e + "axial_runout_phase", "distribution": "uniform", "lo": 0.0, "hi": 360.0},
        {"key": e + "pitch_tolerance", "values": [t["pitch"]]},
        {"key": e + "seed", "distribution": "uniform", "lo": 0.0, "hi": 1.0e6},
    ]  # fmt: skip
    for side in ("left", "right"):
        half = t["profile"] / 2
        out.append({"key": f"{e}profile_slope_{side}", "distribution": "uniform", "lo": -half, "hi": half,
                    "tolerance": half})  # fmt: skip
        out.append({"key": f"{e}profile_form_{side}", "distribution": "uniform", "lo": 0.0, "hi": half,
                    "tolerance": half})  # fmt: skip
    for entry in out:
        entry["label"] = f"cutter class {cls}: {entry['key'][len(e) :].replace('_', ' ')}"
    return out


def machine_tolerance_entries(size: Any, method: str, base_data: dict[str, Any], problems: list[Problem]) -> list[dict]:
    """[[vary]] tables that draw the study's machines from a size's geometric tolerances
    (machine_models/geometry_tolerances.py; "job": the base job's own size): each signed error uniform within
    +-its tolerance, each once-per-turn or periodic error's amplitude uniform in [0, tolerance] at a uniform phase.
    An assumption on how machines built to a tolerance spread, not a measured distribution."""
    from machine_models.geometry_tolerances import PHASED, SCALE, SIGNED, geometry_tolerances

    key = "machine_tolerances"
    if method != "monte-carlo":
        problems.append(Problem(key, size, "draws machines: a Monte-Carlo study's", 'method = "monte-carlo"'))
        return []
    if size == "job":
        from virtual_machine.setting.machine_layout import machine_size

        size = machine_size(parse_job(base_data))
    if size not in SCALE:
        valid = ", ".join(map(repr, [*SCALE, "job"]))
        problems.append(Problem(key, size, "unknown machine size", f"use one of {valid}"))
        return []
    own = base_data.get("machine", {}).get("model", {}).get("geometry", {})
    if own:
        fix = "remove it, or vary it yourself"
        problems.append(Problem(key, size, "the base job has its own machine geometry", fix))
        return []
    t = geometry_tolerances(size)
    out = []
    for name in SIGNED:
        out.append({"key": GEOMETRY_PREFIX + name, "distribution": "uniform", "lo": -t[name], "hi": t[name],
                    "tolerance": t[name]})  # fmt: skip
    for name, phase in PHASED.items():
        out.append({"key": GEOMETRY_PREFIX + name, "distribution": "uniform", "lo": 0.0, "hi": t[name],
                    "tolerance": t[name]})  # fmt: skip
        out.append({"key": GEOMETRY_PREFIX + phase, "distribution": "uniform", "lo": 0.0, "hi": 360.0})
    for entry in out:
        entry["label"] = f"{size} machine: {entry['key'][len(GEOMETRY_PREFIX) :].replace('_', ' ')}"
    return out


def _base_job(path: Path, data: dict[str, Any], problems: list[Problem], source: str) -> tuple[Path, dict[str, Any]]:
    """The base job's path and TOML; InputError (with the study's ``problems`` so far) when it is missing, not a
    valid job, or not a gear the budget can grade."""
    if "base" not in data or not isinstance(data["base"], str):
        raise InputError(
            [*problems, Problem("base", data.get("base"), "missing", 'e.g. base = "../jobs/default.toml"')], source
        )
    base_path = (path.parent / data["base"]).resolve()
    if not base_path.is_file():
        raise InputError(
            [
                *problems,
                Problem(
                    "base",
                    data["base"],
                    f"no job file at {base_path} (the path is relative to the study file's folder)",
                    f"give the path of a .toml job file relative to {path.resolve().parent}, "
                    'e.g. base = "../jobs/default.toml"',
                ),
            ],
            source,
        )
    base_data = read_toml(base_path)
    base_job = parse_job(base_data, str(base_path))  # the base job itself must be valid
    if base_job.kind not in GRADED:
        raise InputError(
            Problem(
                "base",
                data["base"],
                f"a study budgets a gear's ISO 1328-1 deviations; the base job is a {base_job.kind} job",
                "use a skiving or form-milling job as the base",
            ),
            source,
        )
    return base_path, base_data


def _varies(entries: Any, method: str, base_data: dict[str, Any], problems: list[Problem]) -> tuple[Vary, ...]:
    """The study's [[vary]] entries, each checked against the base job (problems appended)."""
    if not isinstance(entries, list) or not entries:
        problems.append(Problem("vary", entries, "the study varies nothing", "add [[vary]] tables with key = ..."))
        entries = []
    varies, seen = [], set()
    for i, entry in enumerate(entries):
        where = f"vary[{i}]"
        if not isinstance(entry, dict) or not isinstance(entry.get("key"), str):
            problems.append(
                Problem(
                    f"{where}.key",
                    entry,
                    'each [[vary]] needs key = "<dotted job key>"',
                    'e.g. key = "machine.model.work_drive.backlash"',
                )
            )
            continue
        if entry["key"] in seen:
            problems.append(Problem(f"{where}.key", entry["key"], "varied twice", "merge the two [[vary]] tables"))
            continue
        seen.add(entry["key"])
        vary = _vary(entry, where, method, base_data, problems)
        if vary is not None:
            varies.append(vary)
    return tuple(varies)


def _vary(entry: dict, where: str, method: str, base_data: dict, problems: list[Problem]) -> Vary | None:
    key = entry["key"]
    for k in entry:
        if k not in VARY_KEYS:
            problems.append(Problem(f"{where}.{k}", entry[k], "unknown [[vary]] key", "valid: " + ", ".join(VARY_KEYS)))
    try:
        base = base_value(base_data, key)
    except InputError as exc:
        problems.extend(exc.problems)
        return None
    label = str(entry.get("label", key))
    tolerance = entry.get("tolerance")
    if tolerance is not None and not (_number(tolerance) and tolerance >= 0):
        problems.append(Problem(f"{key}.tolerance", tolerance, "must be a number >= 0", "the part's tolerance"))
        tolerance = None
    given = [k for k in ("values", "range", "distribution") if k in entry]
    if len(given) != 1:
        hint = "give values = [...], or range = [lo, hi] with steps = n" + (
            ', or distribution = "normal" | "uniform"' if method == "monte-carlo" else ""
        )
        problems.append(Problem(key, given or None, "needs exactly one of values, range, distribution", hint))
        return None
    if given == ["distribution"]:
        return _distribution(entry, key, label, base, tolerance, method, problems)
    if given == ["values"]:
        values = entry["values"]
        if not isinstance(values, list) or not values:
            problems.append(Problem(f"{key}.values", values, "empty", "list at least one value"))
            return None
    else:
        rng, steps = entry["range"], entry.get("steps")
        if not (isinstance(rng, list) and len(rng) == 2 and all(_number(v) for v in rng)):
            problems.append(Problem(f"{key}.range", rng, "must be [lo, hi]", "e.g. range = [1e-4, 1e-3]"))
            return None
        if not (isinstance(steps, int) and not isinstance(steps, bool) and steps >= 2) or not rng[1] > rng[0]:
            problems.append(
                Problem(
                    f"{key}.range",
                    [rng, steps],
                    "empty range: needs hi > lo and steps >= 2",
                    "e.g. range = [1e-4, 1e-3] with steps = 4",
                )
            )
            return None
        values = [rng[0] + (rng[1] - rng[0]) * i / (steps - 1) for i in range(steps)]
    values = list(dict.fromkeys(typed(v, base) if _number(v) else _hashable(v) for v in values))
    return Vary(key, label, base, values=tuple(_plain(v) for v in values), tolerance=tolerance)


def _distribution(entry, key, label, base, tolerance, method, problems) -> Vary | None:
    dist = entry["distribution"]
    if method != "monte-carlo":
        problems.append(
            Problem(
                f"{key}.distribution",
                dist,
                f"only a Monte-Carlo study draws ({method!r} here)",
                'use values = [...] or range = [lo, hi], or method = "monte-carlo"',
            )
        )
        return None
    if dist not in DISTRIBUTIONS:
        problems.append(
            Problem(f"{key}.distribution", dist, "unknown", "use 'normal' (mean, std) or 'uniform' (lo, hi)")
        )
        return None
    if not (_number(base) and not isinstance(base, bool)):
        problems.append(
            Problem(
                f"{key}.distribution",
                dist,
                f"the key is not a number (base {base!r})",
                "give values = [...] to draw among",
            )
        )
        return None
    if dist == "normal":
        mean, std = entry.get("mean", base), entry.get("std")
        if not (_number(mean) and _number(std) and std > 0):
            problems.append(
                Problem(
                    f"{key}.std",
                    std,
                    "a normal distribution needs std > 0 (and mean, default base)",
                    "e.g. mean = 0.0, std = 4e-5",
                )
            )
            return None
        return Vary(key, label, base, distribution=dist, mean=float(mean), std=float(std), tolerance=tolerance)
    lo, hi = entry.get("lo"), entry.get("hi")
    if not (_number(lo) and _number(hi) and hi > lo):
        problems.append(
            Problem(f"{key}.lo", [lo, hi], "a uniform distribution needs lo < hi", "e.g. lo = 0, hi = 5e-4")
        )
        return None
    return Vary(key, label, base, distribution=dist, lo=float(lo), hi=float(hi), tolerance=tolerance)


def _number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def _hashable(v: Any) -> Any:
    return tuple(v) if isinstance(v, list) else v


def _plain(v: Any) -> Any:
    return list(v) if isinstance(v, tuple) else v
