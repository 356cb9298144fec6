"""What every job has: its source, its kind, [machine] and [process]; each kind's :class:`Job` subclass adds its own
sections.

[machine] is the machine that makes the part: its kinematic structure and synchronisation (seeds 000, 001), the
fixed ratios of its chains, its pulse generators and encoders, its change gears, its size and [machine.model], the
physical parameters of its MuJoCo model overriding those of its size (SI units, machine_models/parameters.py).
A form-milling or face-contour job's [machine] only overrides the model (:data:`MODEL_ONLY_MACHINE_KEYS`).
Units: mm, rpm, Hz. [process] is the kind's own (its module declares it); each is parsed once into a typed section
(:func:`virtual_machine.job.keys.section_class`). :func:`read_toml` reads a job file.
"""

from __future__ import annotations

import tomllib
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, ClassVar

from cutting.errors import InputError, Problem
from machine_models.sizes import SIZE_NAMES
from virtual_machine.job.keys import Key, at_least, one_of, positive, section_class

STRUCTURES = ("mechanical", "hydraulic-differential", "hydraulic-shaft", "mechatronic")
SYNCHRONIZATIONS = ("equal-coordinates", "master-slave")


def _change_gears(v: list) -> tuple[str, str] | None:
    if len(v) < 4 or not all(isinstance(t, int) and not isinstance(t, bool) and 12 <= t <= 200 for t in v):
        return ("must list at least 4 tooth counts, integers 12..200", "e.g. [20, 23, 24, 25, 30, ...]")
    return None


MACHINE_KEYS: dict[str, Key] = {
    "structure": Key(str, "mechatronic", "", "kinematic structure (seed 000 figs 1-4)", one_of(*STRUCTURES)),
    "size": Key(
        str,
        None,
        "",
        "machine size (machine_models/sizes.py); default: the smallest that holds the gear's diameter and module",
        one_of(*SIZE_NAMES),
    ),
    "synchronization": Key(
        str, "equal-coordinates", "", "electronic synchronisation scheme (seed 001)", one_of(*SYNCHRONIZATIONS)
    ),
    "adaptive_correction": Key(bool, True, "", "sign/phase discriminator correction of the electronic links"),
    "c1": Key(float, 1.0, "", "product of the fixed ratios of the generating chain (B1 -> B2)", positive),
    "c2": Key(
        float,
        None,
        "",
        "product of the fixed ratios of the tooth-line chain (lead screw -> B4); "
        "default 1/24 for mechanical/hydraulic structures, 1 for mechatronic",
        positive,
    ),
    "c3": Key(float, 0.5, "", "product of the fixed ratios motor M1 -> tool spindle (speed chain)", positive),
    "c4": Key(float, 0.5, "mm", "carriage travel per work revolution with is = 1 (feed chain)", positive),
    "i_sigma": Key(
        float, 0.5, "", "differential ratio with one input held (bevel differential, carrier out)", positive
    ),
    "lead_screw_pitch": Key(float, 10.0, "mm", "lead-screw pitch t_TV", positive),
    "motor_speed": Key(float, 1450.0, "rpm", "main motor speed n_M (4-pole induction motor)", positive),
    "reference_frequency": Key(
        float,
        1e9,
        "Hz",
        "reference pulse generator 14 (seed 000) / 5 (seed 001); high "
        "enough that kv, a multiple of z0, still sets n0 to better than 1 %",
        positive,
    ),
    "command_pulses_per_rev": Key(int, 10000, "1/rev", "command pulses per revolution of each servo axis", at_least(1)),
    "encoder_lines": Key(int, 5000, "1/rev", "lines of the encoders (4 counts per line)", at_least(1)),
    "hydraulic_steps_per_rev": Key(
        int, 3600, "1/rev", "steps per revolution of a hydraulic stepping motor", at_least(1)
    ),
    "hydraulic_max_windows": Key(
        int, 20000, "", "largest window count of a coding disc of a pulse generator", at_least(1)
    ),
    "change_gears": Key(list, None, "", "change-gear set (tooth counts; repeat a count for two gears)", _change_gears),
    "i0": Key(float, 1.0, "", "thread group: ratio motor M2 -> lead screw (seed 001 fig 2)", positive),
    "i01": Key(float, 1.0, "", "thread group: product of the fixed ratios spindle -> lead screw (seed 001)", positive),
    "model": Key(
        dict,
        None,
        "SI",
        "physical parameters of the MuJoCo machine overriding those of its size (machine_models/sizes.py, "
        "parameters.py; table in docs/machines.md), e.g. [machine.model.work_drive] backlash = 1e-4",
    ),
}

#: [machine] of a machine that is set by its model alone (form milling, face contours)
MODEL_ONLY_MACHINE_KEYS: dict[str, Key] = {"model": MACHINE_KEYS["model"]}

#: c2 default per structure (see MACHINE_KEYS["c2"]).
C2_DEFAULT = {"mechanical": 1 / 24, "hydraulic-differential": 1 / 24, "hydraulic-shaft": 1 / 24, "mechatronic": 1.0}


def machine_constants(machine: Any, structure: str) -> Any:
    """[machine] with the structure-dependent defaults resolved for ``structure``."""
    return replace(machine, c2=C2_DEFAULT.get(structure, 1.0)) if machine.c2 is None else machine


def flatten_model(model: dict[str, Any] | None) -> dict[str, Any]:
    """[machine.model] as flat keys: nested tables become dotted names ("work_drive.backlash")."""
    out: dict[str, Any] = {}
    for k, v in (model or {}).items():
        if isinstance(v, dict):
            out.update({f"{k}.{kk}": vv for kk, vv in flatten_model(v).items()})
        else:
            out[k] = v
    return out


def model_problems(model: dict[str, Any] | None, machine: Callable[[], Any]) -> list[Problem]:
    """Every key of [machine.model] must name a parameter of the job's machine, with a valid value.

    ``machine()`` gives the default parameters of the job's machine (machine_models/); it is called, and its
    module imported, only when the job overrides some."""
    if not model:
        return []
    from dataclasses import fields

    from machine_models.parameters import override

    base = machine()
    names = ", ".join(f.name for f in fields(base))
    out = []
    good = {}
    for key, value in flatten_model(model).items():
        try:
            override(base, {key: value})
            good[key] = value
        except KeyError as exc:
            out.append(Problem(f"machine.model.{key}", value, str(exc.args[0]), f"valid parameters: {names}"))
        except TypeError as exc:
            out.append(Problem(f"machine.model.{key}", value, str(exc), "see the parameter table in docs/machines.md"))
    params = override(base, good)
    return out + [
        Problem("machine.model", good, p, "see the parameter table in docs/machines.md") for p in params.problems()
    ]


#: [machine] of the machines set by their structure (skiving, the lathe of seed 001): typed values
MachineSection = section_class(
    "MachineSection",
    MACHINE_KEYS,
    "[machine] of a skiving, thread or turning job: its structure and synchronisation, the fixed ratios of its chains, "
    "its pulse generators and encoders, its change gears, its size and [machine.model] (see MACHINE_KEYS).",
    __name__,
)
#: [machine] of the machines set by their model alone (form milling, face contours)
ModelOnlyMachine = section_class(
    "ModelOnlyMachine",
    MODEL_ONLY_MACHINE_KEYS,
    "[machine] of a form-milling or face-contour job: [machine.model] only.",
    __name__,
)


@dataclass(frozen=True)
class Job:
    """A parsed, validated job: its source, its [machine] and [process] as typed sections, and, in the subclass of
    its ``kind`` (one module per kind: :mod:`.skiving`, :mod:`.thread`, :mod:`.form_milling`, :mod:`.face_contour`,
    :mod:`.turning`), the sections only that kind has (a thread job has no ``gear``)."""

    source: str
    machine: Any
    process: Any
    #: the job kind ("skiving", "thread", "form_milling", "face_contour" or "turning"; virtual_machine.job.kinds)
    kind: ClassVar[str] = ""


def read_toml(path: str | Path) -> dict[str, Any]:
    """The TOML of a job file, or an InputError naming the file."""
    p = Path(path)
    if not p.is_file():
        raise InputError(
            Problem(
                "job", str(p), "no such file", "give the path of a .toml job file, e.g. assets/jobs/spur_external.toml"
            )
        )
    raw = p.read_bytes()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        column = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        raise InputError(
            Problem(
                "job",
                str(p),
                f"not UTF-8 text: byte 0x{raw[exc.start]:02x} at line {line}, column {column} is not valid UTF-8",
                "save the file as UTF-8 (a TOML file must be UTF-8), or remove that character",
            ),
            str(p),
        ) from exc
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(
            Problem("job", str(p), f"not valid TOML: {exc}", "fix the syntax at the line shown"), str(p)
        ) from exc
    return data


def with_machine(job: Job, **overrides: Any) -> Job:
    """The job with [machine] keys replaced (``None``: kept as the job says), e.g. another structure."""
    given = {k: v for k, v in overrides.items() if v is not None}
    return replace(job, machine=replace(job.machine, **given)) if given else job


def default_job_path() -> Path:
    """The default job shipped in assets/jobs/ beside the packages."""
    return Path(__file__).resolve().parents[2] / "assets" / "jobs" / "default.toml"
