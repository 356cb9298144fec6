"""Named machine sizes: the skiving machine of :mod:`machine_models.parameters` built for small, medium and large
gears, and the rule that picks a job's size from its workpiece's diameter and module.

``small`` is the original parameter set (:class:`SkivingMachineParams` defaults); ``medium`` and ``large`` are the
same machine grown to the workpiece classes of the dedicated power-skiving machines (up to 250 and 500 mm, modules 4
and 8) by stated scaling rules with the table diameter, their motors derived from power and base speed: no maker's
data sheet is claimed. The classes, the rules, every derived figure and what the motors were sized against:
docs/machines.md ("Machine sizes").
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
