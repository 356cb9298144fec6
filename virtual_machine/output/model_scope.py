"""The model's scope in a verdict (issue 43): which error sources a skiving run or cut included, with their values, and
which known ones it did not (measurement.json's ``model_scope``, report.html, `skive check`).

A class verdict is only as good as what the model holds: a gear engineer reads "class 5" beside "the thermal drift
was not modelled". Every source here is one a gear engineer would name; the ones left out say why.
"""

from __future__ import annotations

import math
from dataclasses import fields
from typing import Any

from virtual_machine.job.thermal_section import THERMAL_KEYS

#: the machine geometry's keys and their job units (virtual_machine/job/geometry_section.py)
GEOMETRY_UNITS = {
    "shaft_angle_error": ("deg", math.degrees),
    "centre_distance_offset": ("mm", float),
    "cutter_offset_error": ("mm", float),
    "carriage_squareness_x": ("mm/100 mm", lambda v: v * 100),
    "carriage_squareness_y": ("mm/100 mm", lambda v: v * 100),
    "lead_screw_periodic_error": ("mm", float),
    "work_spindle_radial_error": ("mm", float),
    "work_spindle_tilt_error": ("mm/100 mm", lambda v: v * 100),
    "tool_encoder_eccentricity": ("arcsec", lambda v: math.degrees(v) * 3600),
    "work_encoder_eccentricity": ("arcsec", lambda v: math.degrees(v) * 3600),
}

#: known sources skive does not model yet, and why (each names what would hold it)
NOT_MODELLED = (
    ("the surroundings' temperature (ISO 230-3's ETVE)", "the workshop is at a constant temperature; the machine's "
     "own heat is modelled where the job has a thermal model"),
    ("carriage straightness and angular errors (pitch, yaw, roll)", "only the carriage's squareness is modelled"),
    ("asynchronous spindle error motions", "only the once-per-revolution (synchronous) error motion is modelled"),
    ("tool wear", "the edge stays as ground through the job"),
    ("workpiece material scatter (hardness, heat treatment)", "one material row of assets/materials.toml"),
    ("the measuring machine's own uncertainty", "the gear is probed exactly"),
)  # fmt: skip


def _item(source: str, key: str, value: Any, unit: str = "") -> dict[str, Any]:
    return {"source": source, "key": key, "value": value, "unit": unit}


def _geometry(geometry) -> list[dict[str, Any]]:
    out = []
    for name, (unit, to_job) in GEOMETRY_UNITS.items():
        value = getattr(geometry, name)
        if value:
            out.append(_item(f"machine geometry: {name.replace('_', ' ')}", f"machine.model.geometry.{name}",
                             to_job(value), unit))  # fmt: skip
    return out


def _thermal(job) -> list[dict[str, Any]]:
    """The thermal model's state and figures, and the drift it gives at the finishing pass's start (x, y, z [um],
    tilt [urad])."""
    model = getattr(job, "thermal", None)
    if model is None:
        return []
    drift = job.skiving.thermal
    x, y, z, tilt = drift.offsets(drift.pass_starts[-1])[0]
    state = model.state if isinstance(model.state, str) else f"{model.state:g} h since a cold start"
    out = [_item("thermal drift at the finishing pass (x, y, z um; tilt urad)", "machine.thermal_state",
                 f"{state}: {x * 1e3:+.2f}, {y * 1e3:+.2f}, {z * 1e3:+.2f} um, {tilt * 1e6:+.1f} urad")]  # fmt: skip
    units = {k: key.unit for k, key in THERMAL_KEYS.items()}
    out += [_item(f"thermal model: {k.replace('_', ' ')}", f"machine.model.thermal.{k}", v, units[k])
            for k, v in model.as_job().items()]  # fmt: skip
    return out


def _tooling(job) -> list[dict[str, Any]]:
    """The cutter's and the clamping's sources that are set (the rake face and its relief always act)."""
    st = job.skiving
    r = st.rake
    out = [
        _item("rake face and relief (working angles along the edge)", "cutter.rake_face",
              f"{r.kind}, rake {math.degrees(r.rake_angle):g} deg, clearance {math.degrees(r.clearance_angle):g} "
              f"deg, regrind {r.regrind:g} mm"),
    ]  # fmt: skip
    errors = st.cutter_errors
    for f in fields(errors):
        value = getattr(errors, f.name)
        if f.name.endswith("_phase") or not _nonzero(value):
            continue
        out.append(_item(f"cutter error: {f.name.replace('_', ' ')}", f"cutter.errors.{f.name}", _plain(value), "mm"))
    c = st.clamping
    if c.eccentricity:
        out.append(_item("clamping eccentricity", "workpiece.eccentricity", c.eccentricity, "mm"))
    if c.tilt:
        out.append(_item("clamping tilt (axial runout)", "workpiece.tilt", c.tilt, "mm"))
    return out


def _nonzero(value: Any) -> bool:
    if isinstance(value, int | float):
        return value != 0
    if isinstance(value, tuple | list):
        return any(_nonzero(v) for v in value)
    return bool(value)


def _plain(value: Any) -> Any:
    return list(value) if isinstance(value, tuple) else value


def model_scope(job, params=None, kind: str = "run") -> dict[str, Any]:
    """The scope of a skiving ``job``'s ``kind`` ("run": the simulated machine with its parameters ``params``,
    machine_models/parameters.py; "cut": the ideal kinematics on the machine's geometry): ``included`` (source,
    key, value, unit) and ``not_included`` (source, why)."""
    included: list[dict[str, Any]] = []
    not_included: list[dict[str, str]] = []
    if kind == "run":
        m = job.machine
        included.append(_item("synchronisation by the structure's controllers", "machine.structure",
                              f"{m.structure} ({m.synchronization})"))  # fmt: skip
        from virtual_machine.setting.machine_layout import machine_size

        included.append(_item("drive stages' compliance, backlash and friction; the servo loops", "machine.size",
                              machine_size(job)))  # fmt: skip
        included.append(_item("cutting forces: oblique, per edge element, the chip of the moment", "process.material",
                              job.process.material))  # fmt: skip
        if params is not None and params.loop:
            included.append(_item("the tool-work loop's structural modes", "machine.model.loop",
                                  f"{len(params.loop)} modes"))  # fmt: skip
        else:
            not_included.append({"source": "the tool-work loop's structural modes",
                                 "why": "none given: a rigid structure (give the machine's measured modes in "
                                        "[[machine.model.loop]]; docs/machines.md)"})  # fmt: skip
        if params is not None and params.lead_screw_pitch_error:
            included.append(_item("lead screw pitch error", "machine.model.lead_screw_pitch_error",
                                  params.lead_screw_pitch_error))  # fmt: skip
    else:
        not_included.append(
            {
                "source": "the machine's dynamics (controllers, drives, forces, the loop)",
                "why": "`skive cut` cuts along the ideal kinematics; `skive run` simulates the machine",
            }
        )
    included += _geometry(job.skiving.geometry)
    if job.skiving.geometry.exact:
        not_included.append({"source": "machine geometry errors",
                             "why": "none given: the machine as designed ([machine.model.geometry]; "
                                    "docs/machine_geometry.md)"})  # fmt: skip
    included += _thermal(job)
    if getattr(job, "thermal", None) is None:
        why = ("no thermal model: the machine at its surroundings' temperature (give machine.thermal_state and "
               "[machine.model.thermal]; docs/machine_geometry.md)")  # fmt: skip
        not_included.append(
            {"source": "thermal drift of the tool head, the work spindle and the structure", "why": why}
        )
    included += _tooling(job)
    not_included += [{"source": s, "why": w} for s, w in NOT_MODELLED]
    return {"included": included, "not_included": not_included}


def scope_lines(scope: dict[str, Any]) -> list[str]:
    """The scope as text lines (`skive check`)."""
    out = ["  model scope: included"]
    for it in scope["included"]:
        unit = f" {it['unit']}" if it["unit"] else ""
        out.append(f"    - {it['source']}: {it['value']}{unit} ({it['key']})")
    out.append("  not included")
    out += [f"    - {it['source']}: {it['why']}" for it in scope["not_included"]]
    return out
