"""The spindles' torsion at the cutting point, as the machine's drives give it: the tool spindle B1 and the work
spindle B2 each hang on their drive stage (machine_models.parameters.DriveStage: stiffness k and damping c referred
to the spindle, ratio r spindle per motor radian) from a motor whose speed regulator (S4, seed 000 fig. 4:
amplifiers 3 and 11, a PI speed loop on the tachogenerator, virtual_machine.structures.axis.ServoAxis) holds it.

Linearised about the steady cut (the current limit and the pulses' quantisation left out), a torque T on the spindle
turns it by theta_s = H(i omega) T with::

    [ J_m s^2 + r^2 (k + c s) + L(s) (k_p s + k_i)    -r (k + c s) + L(s) (k_p + k_i / s) K_v / r ] [theta_m]   [0]
    [ -r (k + c s)                                    J_s s^2 + k + c s                           ] [theta_s] = [T]

J_m the motor's rotor, J_s the spindle with its cutter or table, fixture and blank (as
machine_models.skiving_machine builds them); the regulator's speed error is the command (the correction module's K_v
times the encoder's error on the spindle, over r; the sign and phase discriminators with their keys make it the
signed error: K_v = 0 without the adaptive correction) less the tachogenerator's motor speed; k_p = J w and
k_i = J w^2 / 4 its gains for the inertia J it was tuned for at the bandwidth w (machine_run.build_structure);
L(s) = e^(-s dt/2) / (1 + s / w_c): the servo tick's hold and the current loop. A tangential force F at the
cutting point, a distance rho from the spindle's axis, gives the torque F rho and moves the point by rho theta_s:
the compliance there is rho^2 H u u^T along the turn's unit direction u. The chain structures (S1-S3) drive their
spindles through change gears or hydraulic motors without this regulator: their stage is taken with the motor side
held (the chain far stiffer than the stage).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cutting.skiving.kinematics import SkivingSetup, rot_x
from machine_models.parameters import DriveStage, SkivingMachineParams
from machine_models.parts import STEEL
from virtual_machine.structures.axis import AxisTuning
from virtual_machine.structures.mechatronic import S4Tuning


@dataclass(frozen=True)
class SpindleDrive:
    """One spindle's drive, linearised (module docstring): ``motor`` J_m and ``spindle`` J_s [kg m^2], the
    ``stage``, the regulator's ``tuning`` and the inertia ``tuned`` [kg m^2, at the motor] its gains were set for
    (None: the motor held), the servo tick ``tick`` [s], whether the correction module closes the position loop
    (``adaptive``)."""

    motor: float
    spindle: float
    stage: DriveStage
    tuning: AxisTuning | None
    tuned: float
    tick: float
    adaptive: bool = True

    def response(self, omega: np.ndarray) -> np.ndarray:
        """H(i omega) [rad/(N m)]: the spindle's turn per torque on it."""
        s = 1j * np.atleast_1d(np.asarray(omega, dtype=float))
        st, r = self.stage, self.stage.ratio
        kv = self.tuning.position_gain if self.tuning is not None and self.adaptive else 0.0
        if st.stiffness is None:  # a rigid stage: the spindle rides on the motor (a held one: no turn at all)
            if self.tuning is None:
                return np.zeros_like(s)
            return 1.0 / ((self.spindle + self.motor / r**2) * s**2 + self._servo(s) * (1 + kv / s) / r**2)
        spring = st.stiffness + st.damping * s
        b = self.spindle * s**2 + spring
        if self.tuning is None:
            return 1.0 / b
        a = self.motor * s**2 + r**2 * spring + self._servo(s)
        across = -r * spring + self._servo(s) / s * kv / r  # the motor's row: the spindle's encoder in the loop
        return a / (a * b + r * spring * across)

    def _servo(self, s: np.ndarray) -> np.ndarray:
        """The regulator's torque per motor radian: L(s) (k_p s + k_i)."""
        if self.tuning is None:
            return np.zeros_like(s)
        w = 2 * math.pi * self.tuning.speed_bandwidth
        kp, ki = self.tuned * w, self.tuned * w * w / 4
        hold = np.exp(-s * self.tick / 2) / (1 + s / (2 * math.pi * self.tuning.current_bandwidth))
        return hold * (kp * s + ki)

    def frequency(self) -> float:
        """The stage's natural frequency with the motor held [Hz] (where the response has its resonance, roughly)."""
        k = self.stage.stiffness
        return math.sqrt(k / self.spindle) / (2 * math.pi) if k else self.tuning.speed_bandwidth if self.tuning else 0.0


def spindle_drives(
    params: SkivingMachineParams,
    setup: SkivingSetup,
    structure: str = "mechatronic",
    adaptive: bool = True,
    servo_substeps: int = 2,
) -> dict[str, SpindleDrive]:
    """The tool's and the work's drives of the job's machine (module docstring), keyed "tool" and "work"."""
    g, mm = setup.gear, 1e-3
    from virtual_machine.setting.machine_layout import workpiece_diameter

    r_blank, r_cut = workpiece_diameter(g) / 2 * mm, setup.cutter_tip_diameter / 2 * mm
    blank = STEEL * math.pi * r_blank**2 * g.face_width * mm
    cutter = STEEL * math.pi * r_cut**2 * setup.cutter.face_width * mm
    servo = structure == "mechatronic"
    tuning = S4Tuning()
    tick = params.timestep * servo_substeps
    tool, work = params.tool_drive, params.work_drive
    return {
        "tool": SpindleDrive(
            params.tool_motor_inertia, params.tool_inertia + cutter * r_cut**2 / 2, tool,
            tuning.tool if servo else None, params.tool_motor_inertia + params.tool_inertia * tool.ratio**2, tick,
            adaptive,
        ),
        "work": SpindleDrive(
            params.work_motor_inertia, params.work_inertia + blank * r_blank**2 / 2, work,
            tuning.work if servo else None, params.work_motor_inertia + params.work_inertia * work.ratio**2, tick,
            adaptive,
        ),
    }  # fmt: skip


def turn_directions(setup: SkivingSetup) -> dict[str, tuple[np.ndarray, float]]:
    """Per spindle the unit direction a small turn moves the cutting point (the pitch point on the mesh line) in the
    machine frame, and the point's distance from the spindle's axis rho [m]."""
    mm = 1e-3
    point = np.array([setup.gear.reference_radius, 0.0, 0.0]) * mm
    centre = np.array([setup.pass_centre_distances[-1], 0.0, 0.0]) * mm
    tool_axis = rot_x(setup.tilt) @ np.array([0.0, 0.0, 1.0])
    out = {}
    for side, turn in (("work", np.cross([0.0, 0.0, 1.0], point)), ("tool", np.cross(tool_axis, point - centre))):
        rho = float(np.linalg.norm(turn))
        out[side] = (turn / rho, rho)
    return out


def torsion_response(drives: dict[str, SpindleDrive], setup: SkivingSetup, omega: np.ndarray) -> np.ndarray:
    """The spindles' torsional compliance at the cutting point [m/N] (n, 3, 3): sum over both of rho^2 H u u^T."""
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    out = np.zeros((len(omega), 3, 3), dtype=complex)
    for side, (u, rho) in turn_directions(setup).items():
        out += rho**2 * drives[side].response(omega)[:, None, None] * np.outer(u, u)[None]
    return out
