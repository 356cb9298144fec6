"""Named machine sizes: the skiving machine of :mod:`machine_models.parameters` built for small, medium and large
gears, and the rule that picks a job's size from its workpiece's diameter and module.

``small`` is the original parameter set, unchanged (:class:`SkivingMachineParams` defaults): a 300 mm table on a
1:2 stage from a 10 N m class servo (60 N m peak), a 40 N m tool motor on a belt; its default gears are those of the
default job (up to 80 mm and module 1.5). ``medium`` and ``large`` are the same machine grown to the workpiece
classes of the dedicated power-skiving machines, whose model numbers name their largest workpiece diameter in mm
(issue 26 lists Liebherr LK 180/280/300/500, Gleason 100PS/300PS/400PS, Mitsubishi MSS300):

=========  ==============  ========  ==========  ======================================================
size       workpiece [mm]  module    table, k    stands for
=========  ==============  ========  ==========  ======================================================
small      <= 80           <= 1.5    300 mm, 1   the original defaults (gears of the default job's size)
medium     <= 250          <= 4      400, 4/3    the 180-300 mm class (e.g. LK 180/280/300, 300PS, MSS300)
large      <= 500          <= 8      630, 2.1    the 400-500 mm class (e.g. LK 500, 400PS)
=========  ==============  ========  ==========  ======================================================

Where the figures come from. Only the class (the largest workpiece diameter, as the model numbers name it) is taken
from the market. The makers' data sheets (drive powers, speeds, torques, module ranges) could not be read in this
project's environment: its searchable copies of the web held none (docs/machines.md, "Machine sizes"), so no
maker's figure is claimed. Everything else is derived, and says so:

- geometry: each size is the small machine scaled by k = table diameter / 300 mm;
- inertias of bodies ~ k^5 (rho D^4 h), masses ~ k^3, friction torques and forces ~ k^3 (they follow the weight
  and the bearing preload), torsional stiffness of shafts, belts and stages ~ k^3 (G I_p / l ~ D^4 / D), linear
  stiffness of nut, screw and slide ~ k (E A / l), damping so that every stage keeps its damping ratio
  (c ~ sqrt(k J): k^4 torsional, k^2 linear), backlash and lead errors unchanged (the same precision class), the
  hydraulic motors' leakage ~ k^-3 (the same slip at their own torque limit);
- top speeds of the tool spindle and the table ~ 1/k (their bearings' pitch diameter grows with k at the same speed
  factor n dm = 0.6e6 mm/min: small 6000 / 3000 rpm, medium 4500 / 2250, large 2860 / 1430) and the carriage's
  travel ~ k (small 1.0 m on its 1.2 m screw, medium 1.33, large 2.1 m): a job beyond them is refused before the
  run (virtual_machine/processes/skiving/machine_reach.py), as is a workpiece or module beyond the size's class;
- motors from power and base speed: peak torque = 1.5 x the rated torque P / omega_base (the amplifier's current
  limit), rotor inertia ~ (peak torque)^(5/3) (geometrically similar motors, T ~ L^3, J ~ L^5): medium tool
  spindle 20 kW at 1500 rpm (127 N m rated, 191 N m peak), work axis 150 N m peak through its 1:2 stage, feed
  50 N m; large tool spindle 40 kW at 1000 rpm (382 N m rated, 573 N m peak), work 560 N m, feed 180 N m; the main
  motor of S1-S3 22 kW (medium) and 45 kW (large) at 1450 rpm (rated torque; 2.5x at breakdown);
- the CNC's run-up acceleration of the table keeps the small machine's share of what M2 can give the bare table
  (600 rad/s^2 with 60 N m on 0.0415 kg m^2 at the motor): medium 353, large 137 rad/s^2;
- every value rounded to three significant figures: orders of magnitude, not the digits of a data sheet.

The stages' frequencies fall with size (tool belt 459 / 231 / 168 Hz, work stage 1324 / 954 / 627 Hz, screw
318 / 234 / 153 Hz without cutter and blank), staying above the 80 Hz (tool, work) and 40 Hz (feed) speed loops
whose gains follow the inertias (virtual_machine/structures/axis.py). The motors were sized against the jobs each
size must hold (virtual_machine/processes/skiving/cutting_load.py, tests/test_machine_sizes.py): spur_external (z
40, mn 2) and
helical_internal (z 60, mn 2, ring) on medium need M1 26 of 191 N m and M2 21 of 150 N m; a mn 4 gear of 208 mm
at 120 m/min needs M1 92 N m on medium, a mn 7 gear of 434 mm 267 N m of the large machine's 573.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

from machine_models.parameters import DriveStage, SkivingMachineParams

SIZE_NAMES = ("small", "medium", "large")

#: table diameter of the small machine [mm], the scale's reference (machine_models/parameters.py: work_inertia)
SMALL_TABLE = 300.0

_INERTIAS = (
    "work_inertia",
    "tool_inertia",
    "screw_inertia",
    "guitar_shaft_inertia",
)
_MOTOR_INERTIAS = {  # rotor inertia -> the motor's peak torque it follows
    "work_motor_inertia": "work_motor_torque",
    "tool_motor_inertia": "tool_motor_torque",
    "feed_motor_inertia": "feed_motor_torque",
    "main_motor_inertia": "main_motor_torque",
    "traverse_motor_inertia": "traverse_motor_torque",
    "hydraulic_motor_inertia": "hydraulic_torque_limit",
}
_MASSES = ("carriage_mass", "radial_mass")
_WEIGHT_LIKE = ("work_friction", "tool_friction", "ways_friction", "traverse_motor_torque", "hydraulic_torque_limit")
_LINEAR = {"nut_stiffness": 1, "radial_stiffness": 1, "nut_damping": 2, "radial_damping": 2}
#: top speeds ~ 1/k (the bearings' pitch diameter grows with k at the same speed factor n dm), travel ~ k
_SPEED_LIMITS = ("tool_speed_limit", "work_speed_limit")
_LENGTHS = ("carriage_travel",)


@dataclass(frozen=True)
class MachineSize:
    """One size: the largest workpiece it takes, its parameters, and what it stands for."""

    name: str
    table_diameter: float  # mm: the scale of the machine (k = table / 300 mm)
    params: SkivingMachineParams
    like: str  # the class of real machines it stands for

    @property
    def scale(self) -> float:
        return self.table_diameter / SMALL_TABLE

    @property
    def workpiece_diameter(self) -> float:
        """Largest blank diameter [mm] (external: tip; ring gear: outside of the rim)."""
        return self.params.workpiece_diameter_limit * 1e3

    @property
    def module(self) -> float:
        """Largest normal module [mm]."""
        return self.params.module_limit * 1e3

    def holds(self, workpiece_diameter: float, module: float) -> bool:
        """Whether a workpiece of ``workpiece_diameter`` [mm] and normal ``module`` [mm] is within this size."""
        return workpiece_diameter <= self.workpiece_diameter + 1e-9 and module <= self.module + 1e-9


def scaled(base: SkivingMachineParams, k: float, **motors: float) -> SkivingMachineParams:
    """``base`` grown by the linear scale ``k`` by the rules of the module docstring; ``motors`` sets the motors'
    peak torques [N m] (``tool_motor_torque`` ...; the others follow the weight rule, k^3) and their rotors follow
    them (J ~ T^(5/3)); ``work_acceleration`` may be given too."""
    values: dict = {}
    for f in fields(base):
        v = getattr(base, f.name)
        if f.name in _INERTIAS:
            values[f.name] = v * k**5
        elif f.name in _MASSES or f.name in _WEIGHT_LIKE:
            values[f.name] = v * k**3
        elif f.name in _SPEED_LIMITS:
            values[f.name] = v / k
        elif f.name in _LENGTHS:
            values[f.name] = v * k
        elif f.name in _LINEAR:
            values[f.name] = None if v is None else v * k ** _LINEAR[f.name]
        elif f.name == "hydraulic_stiffness":
            values[f.name] = v * k**3
        elif f.name == "hydraulic_damping":
            values[f.name] = v * k**4
        elif f.name == "hydraulic_leakage":
            values[f.name] = v / k**3
        elif isinstance(v, DriveStage):
            stiff = None if v.stiffness is None else v.stiffness * k**3
            values[f.name] = replace(v, stiffness=stiff, damping=v.damping * k**4)
    for name in ("tool_motor_torque", "work_motor_torque", "feed_motor_torque", "main_motor_torque"):
        values[name] = motors.pop(name, getattr(base, name) * k**3)
    for rotor, torque in _MOTOR_INERTIAS.items():
        values[rotor] = getattr(base, rotor) * (values[torque] / getattr(base, torque)) ** (5 / 3)
    values.update(motors)
    return replace(base, **{k: _round(v) for k, v in values.items()})


def _round(v):
    """Three significant figures: the rules give orders of magnitude, not the digits of a data sheet."""
    if isinstance(v, DriveStage):
        return replace(v, stiffness=_round(v.stiffness), damping=_round(v.damping))
    if isinstance(v, float) and v != 0 and math.isfinite(v):
        return float(f"{v:.3g}")
    return v


def _rated_peak(power_kw: float, base_rpm: float) -> float:
    """Peak torque [N m] of a motor of ``power_kw`` at ``base_rpm``: 1.5 x its rated torque P / omega."""
    return 1.5 * power_kw * 1e3 / (base_rpm * 2 * math.pi / 60)


def _run_up(params: SkivingMachineParams) -> float:
    """The table's run-up acceleration limit [rad/s^2] at the small machine's share of what M2 gives the bare
    table (600 rad/s^2 of the 1446 rad/s^2 at its motor)."""
    small = SkivingMachineParams()

    def capability(p: SkivingMachineParams) -> float:
        r = p.work_drive.ratio
        return p.work_motor_torque / (p.work_motor_inertia + p.work_inertia * r**2) * abs(r)

    return small.work_acceleration * capability(params) / capability(small)


def _size(name: str, workpiece: float, module: float, table: float, like: str, **motors: float) -> MachineSize:
    """Size ``name`` for workpieces up to ``workpiece`` [mm] and ``module`` [mm] on a ``table`` [mm]."""
    params = scaled(SkivingMachineParams(), table / SMALL_TABLE, **motors)
    params = replace(
        params,
        work_acceleration=_round(_run_up(params)),
        workpiece_diameter_limit=workpiece * 1e-3,
        module_limit=module * 1e-3,
    )
    return MachineSize(name, table, params, like)


SIZES: dict[str, MachineSize] = {
    "small": MachineSize(
        "small", SMALL_TABLE, SkivingMachineParams(), "the original defaults (machine_models/parameters.py)"
    ),
    "medium": _size(
        "medium",
        250.0,
        4.0,
        400.0,
        "the 180-300 mm class (e.g. Liebherr LK 180/280/300, Gleason 300PS, Mitsubishi MSS300)",
        tool_motor_torque=_rated_peak(20.0, 1500.0),
        work_motor_torque=150.0,
        feed_motor_torque=50.0,
        main_motor_torque=22e3 / (1450 * 2 * math.pi / 60),
    ),
    "large": _size(
        "large",
        500.0,
        8.0,
        630.0,
        "the 400-500 mm class (e.g. Liebherr LK 500, Gleason 400PS)",
        tool_motor_torque=_rated_peak(40.0, 1000.0),
        work_motor_torque=560.0,
        feed_motor_torque=180.0,
        main_motor_torque=45e3 / (1450 * 2 * math.pi / 60),
    ),
}


def size_for(workpiece_diameter: float, module: float) -> MachineSize:
    """The smallest size that holds a workpiece of ``workpiece_diameter`` [mm] (the blank the machine carries:
    ``virtual_machine.setting.machine_layout.workpiece_diameter``) and normal ``module`` [mm]; the largest if none
    does (the check before a run then says whether its motors hold the cut)."""
    for size in SIZES.values():
        if size.holds(workpiece_diameter, module):
            return size
    return SIZES[SIZE_NAMES[-1]]


def size_params(name: str) -> SkivingMachineParams:
    """The parameters of size ``name`` (KeyError naming the valid ones)."""
    if name not in SIZES:
        raise KeyError(f"unknown machine size {name!r}: use one of {', '.join(SIZE_NAMES)}")
    return SIZES[name].params
