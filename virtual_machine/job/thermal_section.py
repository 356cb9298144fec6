"""[machine.model.thermal] and ``machine.thermal_state``: the skiving machine's lumped thermal model (issue 43;
the drift itself: cutting/skiving/thermal_drift.py; the figures and their sources: docs/machine_geometry.md).

Three heat bodies, each first order: the tool head (heated by its spindle's speed), the work spindle (by its speed)
and the structure (by the share of the cutting power that stays in the machine). Each grows at its reference heat
input by the figures below; its input scales as (n / n_ref)^speed_exponent for a spindle and as the power into it
for the structure. ``machine.thermal_state`` is the machine's state when the job starts: "cold" (at its
surroundings' temperature: the state ISO 230-1 measures the geometry in, and the geometric errors'
reference), "warm" (at the steady state of running this job without end), or the hours it has been running this
job since a cold start. Without the key and without the table the machine has no thermal drift.

Which figures are measured and which are guesses (the parameter table of docs/machine_geometry.md says the same):
the tool head's tilt of 50 urad above 5000 rpm is Grama et al. (Procedia CIRP 58 (2017) 457, its abstract: "tilt
(yaw and pitch angles of the order of 50 urad) is visible at speeds greater than 5000 rpm"); the cutting heat's
share into the machine, 0.1, is the order the machining texts give for the workpiece's share (the chips take most:
Trent and Wright, Metal Cutting, ch. 5); every time constant and every growth in um is a guess of the order ISO
230-3 tests show, not a cited figure (no measured warm-up of a skiving machine was at hand): a user with an ISO
230-3 test of the machine gives its own.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

from cutting.errors import Problem
from cutting.skiving.thermal_drift import Lump, ThermalDrift
from virtual_machine.job.geometry_section import within
from virtual_machine.job.keys import Key, at_least, parse_section, positive

STATES = ("cold", "warm")


DRIFT = "not a machine's drift"


def _share(v: float) -> tuple[str, str] | None:
    return None if 0.0 <= v <= 1.0 else ("must lie in [0, 1]", "the share of the cutting power, e.g. 0.1")


THERMAL_KEYS: dict[str, Key] = {
    "tool_head_time_constant": Key(float, 20.0, "min", "the tool head's time constant (a guess)", positive),
    "tool_head_growth_axial": Key(
        float, 20.0, "um", "the tool spindle's growth along its axis at its reference speed (a guess)",
        within(1000.0, "um", DRIFT),
    ),
    "tool_head_growth_x": Key(
        float, 5.0, "um", "the tool head's drift along x at its reference speed, positive: the axes apart (a guess)",
        within(1000.0, "um", DRIFT),
    ),
    "tool_head_tilt": Key(
        float, 50.0, "urad", "the tool spindle's tilt about x at its reference speed (Grama et al. 2017)",
        within(5000.0, "urad", DRIFT),
    ),
    "tool_head_reference_speed": Key(float, 5000.0, "rpm", "the tool spindle's reference speed", positive),
    "work_spindle_time_constant": Key(float, 40.0, "min", "the work spindle's time constant (a guess)", positive),
    "work_spindle_growth_axial": Key(
        float, 10.0, "um", "the work spindle's growth along its axis at its reference speed, lifting the blank "
        "(a guess)", within(1000.0, "um", DRIFT),
    ),
    "work_spindle_growth_x": Key(
        float, 3.0, "um", "the work spindle's drift along x at its reference speed, positive: the axes apart "
        "(a guess)", within(1000.0, "um", DRIFT),
    ),
    "work_spindle_reference_speed": Key(float, 1000.0, "rpm", "the work spindle's reference speed", positive),
    "speed_exponent": Key(
        float, 1.0, "", "a spindle's heat input as (n / n_ref)^exponent (a guess: the bearings' friction power)",
        at_least(0.0),
    ),
    "structure_time_constant": Key(float, 120.0, "min", "the structure's time constant (a guess)", positive),
    "structure_growth_x": Key(
        float, 10.0, "um/kW", "the centre distance's growth per kW of heat into the structure (a guess)",
        within(1000.0, "um/kW", DRIFT),
    ),
    "cutting_heat_share": Key(float, 0.1, "", "the share of the cutting power that heats the structure", _share),
}  # fmt: skip


def _state(v: Any) -> tuple[str, str] | None:
    if isinstance(v, str):
        return None if v in STATES else ("not a known state", 'use "cold", "warm" or the hours since a cold start')
    return None if math.isfinite(v) and v >= 0 else ("must be >= 0 hours", 'the hours since a cold start, or "cold"')


THERMAL_STATE = Key(
    (str, float), None, "h", 'the machine\'s thermal state at the job\'s start: "cold", "warm" or hours running', _state
)


@dataclass(frozen=True)
class ThermalModel:
    """The thermal model's figures in SI (s, mm, rad, W) and the state at the job's start: "cold", "warm" or hours
    [h] since a cold start."""

    state: str | float
    tool_tau: float
    tool_axial: float
    tool_x: float
    tool_tilt: float
    tool_speed_ref: float
    work_tau: float
    work_axial: float
    work_x: float
    work_speed_ref: float
    speed_exponent: float
    structure_tau: float
    structure_x_per_w: float
    cutting_heat_share: float

    def as_job(self) -> dict[str, Any]:
        """The figures in the job's units, keyed as [machine.model.thermal] (the model's scope lists them)."""
        return dict(zip(THERMAL_KEYS, _to_job(self), strict=True))


_SCALES = (60.0, 1e-3, 1e-3, 1e-6, 1.0, 60.0, 1e-3, 1e-3, 1.0, 1.0, 60.0, 1e-6, 1.0)  # job unit -> SI, key by key


def _to_job(m: ThermalModel) -> list[float]:
    values = [getattr(m, f.name) for f in fields(m)][1:]
    return [v / s for v, s in zip(values, _SCALES, strict=True)]


def parse_thermal(table: Any, state: Any, problems: list[Problem]) -> ThermalModel | None:
    """[machine.model.thermal] and ``machine.thermal_state`` (both absent: None, no drift); problems appended."""
    if table is None and state is None:
        return None
    before = len(problems)
    v = parse_section("machine.model.thermal", {} if table is None else table, THERMAL_KEYS, problems)
    s = parse_section("machine", {} if state is None else {"thermal_state": state}, {"thermal_state": THERMAL_STATE},
                      problems)  # fmt: skip
    if len(problems) > before:
        return None
    si = [v[k] * scale for k, scale in zip(THERMAL_KEYS, _SCALES, strict=True)]
    return ThermalModel(s.get("thermal_state") or "cold", *si)


def job_drift(model: ThermalModel, setup, powers: list[float] | None = None) -> ThermalDrift:
    """The drift of a job on ``setup`` (without drift of its own) from ``model``: the lumps in the machine's axes,
    the state at the start, the heat inputs over the program (the spindles' from the run-up on, the cut's while each
    pass's stroke lasts: ``powers`` [W] per pass, None: no cutting heat) and the passes' start times."""
    from cutting.skiving.trajectory import ideal_passes
    from virtual_machine.runtime.program import ProgramSettings, pass_start_times

    tilt = setup.tilt  # the tool axis in the machine: Rx(tilt) (0, 0, 1)
    lumps = (
        Lump("tool head", model.tool_tau,
             (model.tool_x, -model.tool_axial * math.sin(tilt), model.tool_axial * math.cos(tilt), model.tool_tilt)),
        Lump("work spindle", model.work_tau, (model.work_x, 0.0, -model.work_axial, 0.0)),  # the blank lifted
        Lump("structure", model.structure_tau, (model.structure_x_per_w, 0.0, 0.0, 0.0)),  # per W into it
    )  # fmt: skip
    p = model.speed_exponent
    u_tool = (abs(setup.tool_speed) / model.tool_speed_ref) ** p
    u_work = (abs(setup.work_speed) / model.work_speed_ref) ** p
    passes = ideal_passes(setup)
    starts = pass_start_times(setup, ProgramSettings(), passes)
    heat = [model.cutting_heat_share * w for w in (powers or [0.0] * len(passes))]
    steps: list[tuple[float, tuple[float, ...]]] = [(0.0, (u_tool, u_work, 0.0))]
    for t0, motion, q in zip(starts, passes, heat, strict=True):
        steps += [(t0, (u_tool, u_work, q)), (t0 + motion.duration, (u_tool, u_work, 0.0))]
    # a job run without end: the cut's heat at its share of the program's time
    cycle = starts[-1] + passes[-1].duration
    steady = (u_tool, u_work, sum(q * m.duration for q, m in zip(heat, passes, strict=True)) / cycle)
    state = model.state
    if state == "cold":
        start = (0.0, 0.0, 0.0)
    elif state == "warm":
        start = steady
    else:
        hours = float(state) * 3600.0
        start = tuple(u * (1 - math.exp(-hours / lump.tau)) for u, lump in zip(steady, lumps, strict=True))
    return ThermalDrift(lumps, start, tuple(steps), tuple(starts))
