"""The error sources `skive diagnose` can name, and the sensitivity study around a job that gives their signatures.

Each source is a job key with a probe value: a size whose signature stands well above the measurement's rounding
(0.1 um) and well inside the first-order range (the machine geometry's signatures are linear there:
docs/machine_geometry.md). A once-per-turn or periodic source (a phase key beside it) is two columns: the probe at
phase 0 and at phase 90 deg, since e sin(x + phi) = e cos(phi) sin(x) + e sin(phi) cos(x): its amplitude and phase
follow from the two coefficients. The study is one case per column and the base job, each the job's ideal cut on the
machine as built with that one error (the stage "exact" of virtual_machine/studies/runner.py), kept in a case store
so that the next diagnosis of the same job reuses it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import tomli_w

from cutting.errors import InputError, Problem
from virtual_machine.studies.design import Case
from virtual_machine.studies.spec import GEOMETRY_PREFIX, set_key


@dataclass(frozen=True)
class Source:
    """One error source: its job ``key``, the ``probe`` value [job units] its sensitivity is taken at, its ``unit``,
    and its phase key (None: a plain value)."""

    key: str
    probe: float
    unit: str
    phase_key: str | None = None

    @property
    def name(self) -> str:
        return self.key.rsplit(".", 1)[-1]

    def columns(self) -> list[tuple[str, dict[str, Any]]]:
        """(case id, the job keys it sets) of each of this source's columns."""
        if self.phase_key is None:
            return [(self.name, {self.key: self.probe})]
        return [(f"{self.name}@{p}", {self.key: self.probe, self.phase_key: float(p)}) for p in (0, 90)]


def _g(name: str, probe: float, unit: str, phase: str | None = None) -> Source:
    return Source(GEOMETRY_PREFIX + name, probe, unit, GEOMETRY_PREFIX + phase if phase else None)


#: the machine's geometric errors (virtual_machine/job/geometry_section.py), each at its probe value
GEOMETRY_SOURCES: tuple[Source, ...] = (
    _g("centre_distance_offset", 0.010, "mm"),
    _g("shaft_angle_error", 0.05, "deg"),
    _g("cutter_offset_error", 0.050, "mm"),
    _g("carriage_squareness_x", 0.1, "mm/100 mm"),
    _g("carriage_squareness_y", 0.1, "mm/100 mm"),
    _g("lead_screw_periodic_error", 0.005, "mm", "lead_screw_periodic_phase"),
    _g("work_spindle_radial_error", 0.005, "mm", "work_spindle_radial_phase"),
    _g("work_spindle_tilt_error", 0.05, "mm/100 mm", "work_spindle_tilt_phase"),
    _g("tool_encoder_eccentricity", 20.0, "arcsec", "tool_encoder_phase"),
    _g("work_encoder_eccentricity", 20.0, "arcsec", "work_encoder_phase"),
)


def sensitivity_cases(base: dict[str, Any], sources: tuple[Source, ...] = GEOMETRY_SOURCES) -> list[Case]:
    """The base job (case "base", as the job file has it) and one case per source column, each with that error at
    its probe value on top of the base job's own (a job that has an error already is diagnosed for what it adds)."""
    cases = [Case("base", {}, tomli_w.dumps(base))]
    for s in sources:
        for case_id, keys in s.columns():
            data = base
            for key, value in keys.items():
                data = set_key(data, key, _added(base, key, value, s))
            cases.append(Case(case_id, keys, tomli_w.dumps(data)))
    return cases


def _added(base: dict[str, Any], key: str, value: float, source: Source) -> float:
    """The probe on top of the base job's own value of ``key`` (a phase is set, not added; a phased error the base
    job has already cannot take a second one of its kind: refused)."""
    if key == source.phase_key:
        return value
    node: Any = base
    for part in key.split("."):
        node = node.get(part, {}) if isinstance(node, dict) else {}
    own = float(node) if isinstance(node, int | float) and not isinstance(node, bool) else 0.0
    if own and source.phase_key is not None:
        raise InputError(
            Problem(key, own, "the job has this once-per-turn error already: its sensitivity is not a second one",
                    "diagnose against the job without it (set it to 0)")
        )  # fmt: skip
    return own + value


def amplitude_phase(c: float, s: float) -> tuple[float, float]:
    """A phased source's amplitude and phase [deg] from its coefficients at phase 0 (``c``) and 90 deg (``s``)."""
    return math.hypot(c, s), math.degrees(math.atan2(s, c)) % 360.0
