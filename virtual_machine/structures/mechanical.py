"""S1 mechanical structure (seed 000 fig. 1; machines EZ-13, EZ-24, EZ-165): one main motor and change gears.

The main motor M1 (induction, frequency converter for the run-up) drives the tool spindle through iv and,
through the chains of the model (ix, the differential with iy, is), the work spindle and the lead screw.
Nothing is controlled in the generating and tooth-line links: their accuracy is that of the gears, their
stiffness and backlash. The CNC part added here for the part program engages clutch 12 (the feed chain)
for each stroke, counts the stroke on an encoder on the lead screw, and returns the carriage with the
setting-traverse motor M2 through clutch 15 (seed: "Vs(P5): M2 -> clutch 15 -> 11 -> TV").
"""

from __future__ import annotations

import math

from virtual_machine.controllers import InductionMotor
from virtual_machine.structures.axis import AxisTuning, ServoAxis, StrokeCounter
from virtual_machine.structures.mechatronic import CncState


class MechanicalS1:
    sensors = ("TV",)
    speeds = ("M1", "M2")
    actuators = ("M1", "M2")

    def __init__(
        self,
        motor: InductionMotor,
        p: int,
        encoder_lines: int,
        traverse_inertia: float,
        tv0: float,
        traverse: AxisTuning | None = None,
    ):
        self.p = p
        self.m1 = motor
        self.stroke = StrokeCounter(encoder_lines, p, tv0)
        self.traverse = ServoAxis(
            traverse or AxisTuning(40.0, 60.0, peak_torque=15.0), p, encoder_lines, 1.0, traverse_inertia, True, tv0
        )
        self.rad = 2 * math.pi / p
        self.screw_pulses = 0
        self.b4_pulses = 0  # B4 follows the lead screw through the helix chain: the return needs no B4 pulses
        self._target = 0
        self._was_feeding = False

    def b4_for_screw(self, screw_pulses: int) -> int:
        return self.b4_pulses

    def clutches(self, cnc: CncState) -> dict[str, bool]:
        """Clutch 12 (feed chain) during a stroke, clutch 15 (setting traverse) otherwise."""
        return {"feed_chain": cnc.feed, "traverse": not cnc.feed}

    def tick(self, dt: float, cnc: CncState, angles: tuple[float, ...], speeds: tuple[float, ...]):
        tv = angles[0]
        self.screw_pulses = self.stroke.pulses(tv, dt)
        self.m1.scale, self.m1.omega = cnc.scale, speeds[0]
        self.m1.update(dt)
        if cnc.feed:
            self._was_feeding = True
            return self.m1.torque, 0.0
        if self._was_feeding:  # clutch 15 takes the screw where the stroke left it
            self._target = self.screw_pulses
            self.traverse.amplifier.reset()
            self._was_feeding = False
        self._target += cnc.rapid_screw
        torque = self.traverse.update(dt, cnc.rapid_screw * self.rad / dt, self._target, tv, speeds[1])
        return self.m1.torque, torque
