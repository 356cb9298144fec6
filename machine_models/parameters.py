"""Physical parameters of the skiving machine model: each with its unit and where its default comes from.

The defaults describe a mid-size vertical skiving machine for gears of 50-250 mm (a 1980s electronic-gearbox
machine of seed 000 fig. 4 refitted with modern servo drives): a work table on a gear stage, a directly
belt-driven tool spindle on a swivel head, a vertical carriage on a ball screw. They are plausible orders of
magnitude, not one maker's data; the parameter table of docs/machines.md repeats them with the reasoning.

Units are SI (m, kg, s, rad, N, N m) as MuJoCo uses them; the job files and the cutting engine use mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from typing import Any

from machine_models.loop import LoopMode, parse_loop

ARCSEC = math.pi / 180 / 3600
RPM = 2 * math.pi / 60  # rad/s per rpm


@dataclass(frozen=True)
class DriveStage:
    """One transmission stage: motor -> (compliance + backlash) -> driven joint.

    ``ratio``: driven joint motion per motor radian (rad/rad, or m/rad for a screw and nut);
    ``stiffness``: of the stage referred to the driven joint (N m/rad, or N/m); None = rigid (a stiff
    equality constraint, the "ideal" drive); ``backlash``: total dead band at the driven joint (rad or m);
    ``damping``: of the stage referred to the driven joint (N m s/rad or N s/m), acting on the relative
    velocity across the stage (lubricant film and structure).
    """

    ratio: float
    stiffness: float | None
    backlash: float = 0.0
    damping: float = 0.0

    def check(self, name: str) -> list[str]:
        out = []
        if not math.isfinite(self.ratio) or self.ratio == 0:
            out.append(f"{name}.ratio = {self.ratio}: must be finite and non-zero")
        if self.stiffness is not None and not (self.stiffness > 0 and math.isfinite(self.stiffness)):
            out.append(f"{name}.stiffness = {self.stiffness}: must be > 0 (or omitted for a rigid stage)")
        if not self.backlash >= 0:
            out.append(f"{name}.backlash = {self.backlash}: must be >= 0")
        if self.backlash > 0 and self.stiffness is None:
            out.append(f"{name}.backlash = {self.backlash}: a stage with backlash needs a contact stiffness")
        if not self.damping >= 0:
            out.append(f"{name}.damping = {self.damping}: must be >= 0")
        return out


@dataclass(frozen=True)
class SkivingMachineParams:
    """Masses, inertias, drives and friction of the skiving machine (see the module docstring for units)."""

    # ---- what the machine takes (the size's class, machine_models/sizes.py) ------------------------------
    #: m: the largest workpiece (external: its tip circle; ring gear: the outside of its rim)
    workpiece_diameter_limit: float = 0.08
    #: m: the largest normal module its cutters and spindles are built for
    module_limit: float = 1.5e-3

    # ---- work spindle (B2/B4): table, fixture and blank on a gear stage from servo motor M2 -------------
    work_inertia: float = 0.15  # kg m^2: table 300 mm x 60 mm steel (0.12) + fixture (blank: from its geometry)
    work_friction: float = 1.5  # N m: two preloaded angular-contact bearings at speed
    work_motor_inertia: float = 4.0e-3  # kg m^2: 10 N m class AC servo motor rotor
    work_motor_torque: float = 60.0  # N m: peak torque of M2 (current limit of power amplifier 11)
    #: rad/s: the table's top speed, 3000 rpm: its bearings at a speed factor n dm of 0.6e6 mm/min (grease-lubricated
    #: precision bearings) on a 200 mm pitch diameter; a job that needs more is refused before the run
    work_speed_limit: float = 314.0
    #: M2 -> table: 1:2 precision spur stage, 1e6 N m/rad (table bearing + stage, referred to the table),
    #: 20 arcsec backlash (a precision stage, DIN 3967 "reduced" class)
    work_drive: DriveStage = field(default_factory=lambda: DriveStage(0.5, 1.0e6, 20 * ARCSEC, 60.0))
    #: rad/s^2: the CNC's limit on the table's acceleration in the run-up (virtual_machine/runtime/program.py): M2 holds
    #: 740 and saturates at 1000 on the default job, so the ramp lengthens for fast jobs instead of losing
    #: synchronism; a larger table accelerates slower (machine_models/sizes.py)
    work_acceleration: float = 600.0

    # ---- tool spindle (B1): cutter and arbor, belt from servo motor M1 ----------------------------------
    tool_inertia: float = 0.012  # kg m^2: spindle shaft and arbor; the cutter is added from its geometry
    tool_friction: float = 0.5  # N m: spindle bearings
    tool_motor_inertia: float = 3.0e-3  # kg m^2
    tool_motor_torque: float = 40.0  # N m: M1 peak (amplifier 3)
    #: rad/s: the tool spindle's top speed, 6000 rpm: its bearings at n dm = 0.6e6 mm/min on a 100 mm pitch diameter
    tool_speed_limit: float = 628.0
    #: M1 -> spindle: 1:1 toothed belt, 2e4 N m/rad torsional (belt span stiffness at the pulley radius)
    tool_drive: DriveStage = field(default_factory=lambda: DriveStage(1.0, 2.0e4, 0.0, 8.0))

    # ---- carriage (P3) on vertical ways, ball screw (TV) from servo motor M3 -----------------------------
    carriage_mass: float = 250.0  # kg: carriage + swivel head + tool spindle unit
    ways_friction: float = 150.0  # N: linear guides (rolling) under preload
    #: share of the carriage weight carried by the hydraulic counterbalance; the rest keeps the nut on one flank
    counterbalance: float = 0.85
    screw_inertia: float = 1.5e-3  # kg m^2: 40 mm ball screw, 1.2 m long
    #: m: the carriage's travel along the work axis on that screw (its length less the nut and the end bearings); a
    #: pass's stroke (the face, the cutter's run-in and run-out) must fit in it
    carriage_travel: float = 1.0
    feed_motor_inertia: float = 1.5e-3  # kg m^2
    feed_motor_torque: float = 20.0  # N m: M3 peak (amplifier 18)
    #: M3 -> screw: rigid coupling, 3e3 N m/rad torsional (the screw shaft, referred to the screw)
    feed_drive: DriveStage = field(default_factory=lambda: DriveStage(1.0, 3.0e3, 0.0, 0.5))
    #: screw -> carriage (ratio = pitch / 2 pi, set from the job): axial 4e8 N/m (screw, nut, bearings), 3 um play
    nut_stiffness: float | None = 4.0e8  # N/m; None = rigid
    nut_backlash: float = 3.0e-6  # m
    nut_damping: float = 2.0e4  # N s/m
    #: relative lead error of the screw: its real lead is the job's lead_screw_pitch x (1 + this), which the CNC
    #: does not know (ISO 3408-3 class 5 allows about 23 um per 300 mm, 8e-5); signed
    lead_screw_pitch_error: float = 0.0

    # ---- radial slide (pass depth): position-controlled, held stiffly during a pass ---------------------
    radial_mass: float = 180.0  # kg
    radial_stiffness: float = 2.0e8  # N/m: servo + screw stiffness holding the depth
    radial_damping: float = 2.0e5  # N s/m

    # ---- S1 mechanical (seed 000 fig. 1): one main motor, change-gear chains lumped per kinematic link -------
    main_motor_inertia: float = 0.06  # kg m^2: 11 kW 4-pole induction motor rotor + pulley
    main_motor_torque: float = 75.0  # N m: rated torque (11 kW at 1450 rpm)
    main_motor_slip: float = 0.03  # rated slip of the induction motor (fed by a frequency converter)
    #: M1 -> iv -> tool spindle (ratio from the sheet): belts and gears, 1.5e4 N m/rad at the spindle
    speed_chain: DriveStage = field(default_factory=lambda: DriveStage(1.0, 1.5e4, 0.0, 5.0))
    #: B1 -> 3 -> 4 -> ix -> 5 and TV -> 11 -> 13 -> iy -> 14: the change-gear guitars on their banjos, referred to
    #: the guitar's output shaft (5 or 14): 2e4 N m/rad and 2 arcmin (change gears run with generous backlash)
    ix_stage: DriveStage = field(default_factory=lambda: DriveStage(1.0, 2.0e4, 120 * ARCSEC, 2.0))
    iy_stage: DriveStage = field(default_factory=lambda: DriveStage(1.0, 2.0e4, 120 * ARCSEC, 2.0))
    guitar_shaft_inertia: float = 3.0e-3  # kg m^2: shaft 5 / 14 with its change gears
    #: differential -> 6 -> 7 -> 8 -> work spindle 9, referred to the work spindle: the dividing worm gear;
    #: 1.5e5 N m/rad and 40 arcsec (the seed names the chain's torsional stiffness as S1's accuracy limit)
    generating_chain: DriveStage = field(default_factory=lambda: DriveStage(1.0, 1.5e5, 40 * ARCSEC, 40.0))
    #: work spindle -> is -> TV, referred to the lead screw: 600 N m/rad, 0.1 deg backlash of the feed gears
    feed_chain: DriveStage = field(default_factory=lambda: DriveStage(1.0, 600.0, math.radians(0.1), 1.0))
    traverse_motor_inertia: float = 1.0e-3  # kg m^2: setting-traverse motor (S1: M2 via clutch 15)
    traverse_motor_torque: float = 15.0  # N m

    # ---- S2/S3 hydraulic shaft: stepping motors GShD driving the chains -------------------------------------
    hydraulic_motor_inertia: float = 2.0e-3  # kg m^2: vane motor rotor and its gear
    hydraulic_stiffness: float = 3.0e3  # N m/rad: oil column between the valve and the vanes (bulk modulus)
    hydraulic_damping: float = 3.0  # N m s/rad
    hydraulic_leakage: float = 2.0e-5  # rad/s per N m: leakage past the vanes makes the motor slip under load
    hydraulic_torque_limit: float = 60.0  # N m: relief pressure x displacement
    #: GShD1/GShD2 -> differential -> work spindle (S2), GShD -> tool spindle (S3), referred to the driven spindle
    differential_stage: DriveStage = field(default_factory=lambda: DriveStage(1.0, 1.5e5, 30 * ARCSEC, 40.0))

    # ---- the tool-work loop's structural modes (machine_models/loop.py; docs/machines.md, "The loop") -------
    #: at the tool (between the swivel head and the tool spindle) and at the workpiece (under the work spindle);
    #: () is a rigid structure (the axes' own compliance, the radial servo and the nut, stays)
    loop: tuple[LoopMode, ...] = ()

    # ---- simulation ---------------------------------------------------------------------------------------
    timestep: float = 1.25e-4  # s: 8 kHz physics, two sub-steps of a 4 kHz servo
    integrator: str = "implicitfast"  # damping implicit; the stages' springs stay well below 1/(2 pi h)

    def problems(self) -> list[str]:
        error, self_ = self.lead_screw_pitch_error, replace(self, lead_screw_pitch_error=0.0)  # signed: own check
        out = common_problems(self_, ("work_inertia", "tool_inertia", "carriage_mass", "screw_inertia", "radial_mass"))
        if not (math.isfinite(error) and abs(error) < 0.05):
            out.append(f"lead_screw_pitch_error = {error}: must be a relative error within +-0.05 (e.g. 8e-5)")
        for name in (
            "tool_speed_limit",
            "work_speed_limit",
            "carriage_travel",
            "workpiece_diameter_limit",
            "module_limit",
        ):
            if not getattr(self, name) > 0:
                out.append(f"{name} = {getattr(self, name)}: must be > 0 (a top speed in rad/s, a length in m)")
        if not self.work_acceleration > 0:
            out.append(f"work_acceleration = {self.work_acceleration}: must be > 0 rad/s^2 (the table's run-up)")
        for i, mode in enumerate(self.loop):
            out += mode.problems(f"loop[{i}]")
        carried = sum(m.mass for m in self.loop if m.at == "tool" and m.kind == "translation")
        if carried > self.radial_mass:
            out.append(
                f"loop: the tool's translational modes have {carried:.0f} kg of modal mass, more than the radial "
                f"slide's {self.radial_mass:.0f} kg that carries them (stiffer or higher modes, or more radial_mass)"
            )
        return out

    def stiff(self) -> SkivingMachineParams:
        """The ideal machine: every stage rigid and free of backlash, no friction, a rigid loop (for the proofs)."""
        return rigid(self, work_friction=0.0, tool_friction=0.0, ways_friction=0.0, loop=())

    def with_overrides(self, values: dict[str, Any]) -> SkivingMachineParams:
        return override(self, values)


def common_problems(params, positive: tuple[str, ...]) -> list[str]:
    """The checks every machine's parameters share: stages, non-negative finite numbers, the named positive
    ones, a nut's backlash needing its stiffness, the time step and the integrator."""
    out: list[str] = []
    for f in fields(params):
        v = getattr(params, f.name)
        if isinstance(v, DriveStage):
            out += v.check(f.name)
        elif isinstance(v, float) and not (v >= 0 and math.isfinite(v)):
            out.append(f"{f.name} = {v}: must be a finite number >= 0")
    for name in positive:
        if not getattr(params, name) > 0:
            out.append(f"{name} = {getattr(params, name)}: must be > 0 (a body needs mass, a motor torque)")
    if params.nut_stiffness is None and params.nut_backlash > 0:
        out.append(f"nut_backlash = {params.nut_backlash}: a nut with backlash needs nut_stiffness")
    if params.nut_stiffness is not None and not params.nut_stiffness > 0:
        out.append(f"nut_stiffness = {params.nut_stiffness}: must be > 0 (or omitted for a rigid nut)")
    balance = getattr(params, "counterbalance", None)  # the machines whose vertical slide has one
    if balance is not None and not 0 <= balance <= 1:
        out.append(f"counterbalance = {balance}: must be between 0 and 1")
    if not 0 < params.timestep <= 1e-3:
        out.append(f"timestep = {params.timestep}: must be in (0, 1e-3] s")
    if params.integrator not in ("implicitfast", "RK4", "Euler", "implicit"):
        out.append(f"integrator = {params.integrator!r}: use 'implicitfast', 'RK4', 'Euler' or 'implicit'")
    return out


def rigid(params, **also: Any):
    """``params`` with every drive stage rigid and free of backlash, a rigid nut, and ``also`` (no friction)."""
    stages = {
        f.name: replace(getattr(params, f.name), stiffness=None, backlash=0.0)
        for f in fields(params)
        if isinstance(getattr(params, f.name), DriveStage)
    }
    return replace(params, **stages, nut_stiffness=None, nut_backlash=0.0, **also)


def _check_type(key: str, value: Any, current: Any, may_be_rigid: bool) -> None:
    """TypeError unless ``value`` has the type of the parameter's default ``current`` (a number for a number or a
    rigid stage's None; a stiffness may be None, i.e. rigid)."""
    if value is None and may_be_rigid:
        return
    if isinstance(current, bool):
        ok = isinstance(value, bool)
    elif isinstance(current, int | float) or current is None:
        ok = isinstance(value, int | float) and not isinstance(value, bool)
    else:
        ok = isinstance(value, type(current))
    if not ok:
        kind = "a number" if isinstance(current, int | float) or current is None else type(current).__name__
        raise TypeError(f"{key!r} must be {kind}, not {value!r}" + (' (or "rigid")' if may_be_rigid else ""))


def parameter(params, key: str) -> Any:
    """The value of the parameter ``key`` of ``params`` (a drive stage's field as ``"work_drive.backlash"``);
    KeyError saying which part of the name is wrong."""
    head, _, tail = key.partition(".")
    if head not in {f.name for f in fields(params)}:
        raise KeyError(f"unknown machine parameter {key!r}")
    value = getattr(params, head)
    if not tail:
        return value
    if not isinstance(value, DriveStage):
        raise KeyError(f"{head!r} is not a drive stage: {key!r} names nothing")
    if tail not in {f.name for f in fields(DriveStage)}:
        raise KeyError(f"unknown drive stage field {key!r} (use ratio, stiffness, backlash, damping)")
    return getattr(value, tail)


def override(params, values: dict[str, Any]):
    """``params`` (a frozen dataclass of machine parameters) changed by a flat dict; a drive stage's fields as
    ``"work_drive.backlash"``; a stiffness ``"rigid"`` makes the stage (or the nut) rigid (job files have no
    null). Unknown names raise KeyError naming them."""
    top: dict[str, Any] = {}
    stages: dict[str, dict[str, Any]] = {}
    for key, value in values.items():
        if value == "rigid" and (key.endswith(".stiffness") or key == "nut_stiffness"):
            value = None
        head, _, tail = key.partition(".")
        default = parameter(params, key)
        current = getattr(params, head)
        if head == "loop" and not tail:  # a list of modes (tables), checked as a whole
            top[head] = parse_loop(value)
            continue
        if tail:
            _check_type(key, value, default, tail == "stiffness")
            stages.setdefault(head, {})[tail] = value
        else:
            if isinstance(current, DriveStage):
                raise TypeError(
                    f"{key!r} is a drive stage, not a number: set its fields as a table, [machine.model.{key}] "
                    "with ratio, stiffness, backlash, damping"
                )
            _check_type(key, value, current, key == "nut_stiffness")
            top[head] = value
    for head, changes in stages.items():
        top[head] = replace(getattr(params, head), **changes)
    return replace(params, **top)
