"""Job files: TOML describing the gear (or thread, coupling, turned shaft) to make, the tool, the process and the
machine.

A job is a head every job has ([machine], [process], its source and kind; :mod:`.head`) and the sections of its kind,
in the kind's :class:`Job` subclass, parsed by the kind's own module: :mod:`.skiving` (:class:`SkivingJob`: [gear],
[cutter]), :mod:`.thread` ([thread]), :mod:`.form_milling` ([gear], [mill]), :mod:`.face_contour` ([coupling]) and
:mod:`.turning` ([turning], [vibration]); :mod:`.kinds` tells them apart and dispatches. Every key is declared once
(:mod:`.keys`) with its type, unit, default and check, and [machine] and [process] are parsed once into typed
sections; the loader reports *all* problems of a job at once, each naming the key, the value, why and what would be
valid. Units: mm, degrees, rpm, Hz; helix angles signed, right hand positive.
"""

from virtual_machine.job.face_contour import COUPLING_KEYS, FACE_PROCESS_KEYS, FaceContourJob
from virtual_machine.job.form_milling import FORM_PROCESS_KEYS, MILL_KEYS, FormMillingJob
from virtual_machine.job.gear_sections import (
    GEAR_KEYS,
    MEASUREMENT_KEYS,
    MODIFICATION_KEYS,
    OPTIONAL_SECTIONS,
    load_gear_section,
)
from virtual_machine.job.head import (
    MACHINE_KEYS,
    STRUCTURES,
    SYNCHRONIZATIONS,
    Job,
    default_job_path,
    flatten_model,
    machine_constants,
    read_toml,
    with_machine,
)
from virtual_machine.job.keys import REQUIRED, Key, parse_section
from virtual_machine.job.kinds import KINDS, load_job, parse_job
from virtual_machine.job.skiving import CUTTER_KEYS, PROCESS_KEYS, SECTIONS_GEAR, SkivingJob, dexel_spacing
from virtual_machine.job.thread import THREAD_KEYS, THREAD_PROCESS_KEYS, ThreadJob
from virtual_machine.job.turning import TURNING_KEYS, TURNING_PROCESS_KEYS, VIBRATION_KEYS, TurningJob

__all__ = [
    "COUPLING_KEYS",
    "CUTTER_KEYS",
    "FACE_PROCESS_KEYS",
    "FORM_PROCESS_KEYS",
    "GEAR_KEYS",
    "KINDS",
    "MACHINE_KEYS",
    "MEASUREMENT_KEYS",
    "MILL_KEYS",
    "MODIFICATION_KEYS",
    "OPTIONAL_SECTIONS",
    "PROCESS_KEYS",
    "REQUIRED",
    "SECTIONS_GEAR",
    "STRUCTURES",
    "SYNCHRONIZATIONS",
    "THREAD_KEYS",
    "THREAD_PROCESS_KEYS",
    "TURNING_KEYS",
    "TURNING_PROCESS_KEYS",
    "VIBRATION_KEYS",
    "FaceContourJob",
    "FormMillingJob",
    "Job",
    "Key",
    "SkivingJob",
    "ThreadJob",
    "TurningJob",
    "default_job_path",
    "dexel_spacing",
    "flatten_model",
    "load_gear_section",
    "load_job",
    "machine_constants",
    "parse_job",
    "parse_section",
    "read_toml",
    "with_machine",
]
