"""S2 hydraulic shaft with differential (seed 000 fig. 2): pulse generators and hydraulic stepping motors.

The main motor M (induction, frequency converter) drives the tool spindle through iv. Master-slave links:
GGI1 on the tool spindle feeds GShD1, GGI2 on the lead screw feeds GShD2; both drive differential 4 to the work
spindle (B2 + B4). GGI3 on the work spindle feeds GShD3, which turns the lead screw (the feed; the CNC gates it
and feeds GShD3 its own pulses for the return stroke). Each ratio is the disc's windows over the motor's steps
per turn: a discrete set, realised by the setting sheet.
"""

from __future__ import annotations

from fractions import Fraction

from virtual_machine.controllers import (
    HydraulicPulseGenerator,
    HydraulicSteppingMotor,
    InductionMotor,
    RateMultiplier,
)
from virtual_machine.structures.axis import StrokeCounter
from virtual_machine.structures.mechatronic import CncState


class StepFeed:
    """Pulses from a coding disc to a stepping motor, per tick. Faster than a step per tick the steps are spread
    evenly over the tick (the disc's fine position): lumping them at the tick's end would kick the oil column
    by +-1 step (and its damping by a step per tick) at the servo rate, an artefact of the sampling. Slower,
    the motor steps as the steps come: the staircase is real and shows as periodic error."""

    __slots__ = ("last",)

    def __init__(self) -> None:
        self.last = 0.0

    def pulses(self, disc: HydraulicPulseGenerator) -> float:
        fine = disc.fine_position
        step = fine - self.last
        self.last = fine
        return step if abs(step) >= 1.0 else float(disc.out)


class HydraulicS2:
    sensors = ("B1", "TV", "B2", "GShD1", "GShD2", "GShD3")
    speeds = ("M1", "GShD1", "GShD2", "GShD3")
    actuators = ("M1", "GShD1", "GShD2", "GShD3")

    def __init__(
        self,
        motor: InductionMotor,
        windows: tuple[int, int | None, int],
        stepping: dict,
        p: int,
        encoder_lines: int,
        feed_ratio: float,
        home: dict[str, float],
    ):
        """``windows``: discs of GGI1..GGI3 (None: GGI2 disengaged, spur gear); ``stepping``: parameters of the
        GShD; ``feed_ratio``: TV per GShD3 rad (signed); ``home``: joint angles at the start."""
        self.p, self.m = p, motor
        self.ggi1 = HydraulicPulseGenerator(windows[0], home["B1"])
        self.ggi2 = HydraulicPulseGenerator(windows[1], home["TV"]) if windows[1] else None
        self.ggi3 = HydraulicPulseGenerator(windows[2], home["B2"])
        self.gshd1, self.gshd2, self.gshd3 = (HydraulicSteppingMotor(**stepping) for _ in range(3))
        self.home = (home["GShD1"], home["GShD2"], home["GShD3"])
        self.stroke = StrokeCounter(encoder_lines, p, home["TV"])
        self.feeds = (StepFeed(), StepFeed(), StepFeed())
        q = stepping["steps_per_rev"]
        f = Fraction(q / (p * abs(feed_ratio))).limit_denominator(2**20)  # GShD3 steps per screw pulse
        self.rapid = RateMultiplier(f.numerator, f.denominator)
        self.rapid_sign = 1 if feed_ratio > 0 else -1
        self.screw_pulses = 0
        self.b4_pulses = 0  # B4 follows the screw through GGI2

    def b4_for_screw(self, screw_pulses: int) -> int:
        return self.b4_pulses

    def clutches(self, cnc: CncState) -> dict[str, bool]:
        return {}

    def tick(self, dt: float, cnc: CncState, angles: tuple[float, ...], speeds: tuple[float, ...]):
        b1, tv, b2, h1, h2, h3 = angles
        self.m.scale, self.m.omega = cnc.scale, speeds[0]
        self.m.update(dt)
        self.screw_pulses = self.stroke.pulses(tv, dt)
        # GGI1 (tool) -> GShD1 ; GGI2 (screw) -> GShD2 ; GGI3 (work) -> GShD3 while feeding, else the CNC's pulses
        self.ggi1.angle = b1
        self.ggi1.update(dt)
        pulses1 = self.feeds[0].pulses(self.ggi1)
        pulses2 = 0.0
        if self.ggi2 is not None:
            self.ggi2.angle = tv
            self.ggi2.update(dt)
            pulses2 = self.feeds[1].pulses(self.ggi2)
        self.ggi3.angle = b2
        self.ggi3.update(dt)
        pulses3 = self.feeds[2].pulses(self.ggi3)
        self.rapid.inp = cnc.rapid_screw
        self.rapid.update(dt)
        if not cnc.feed:
            pulses3 = self.rapid_sign * self.rapid.out
        out = [self.m.torque]
        for motor, pulses, angle, home, omega in zip(
            (self.gshd1, self.gshd2, self.gshd3),
            (pulses1, pulses2, pulses3),
            (h1, h2, h3),
            self.home,
            speeds[1:],
            strict=True,
        ):
            motor.pulses, motor.angle, motor.omega = pulses, angle - home, omega
            motor.update(dt)
            out.append(motor.torque)
        return tuple(out)


class HydraulicS3:
    """S3 hydraulic shaft without differential (seed 000 fig. 3): mathematical summation.

    The main motor M drives the work spindle (the master of ``kx``); the pulse generator's coding disc on it
    feeds the stepping motor GShD that turns the tool: one work turn -> (z2/z0)(1 + s/T) cutter turns, the
    helix folded into the ratio. The feed chain (is) moves the carriage from the work spindle. Without a
    traverse drive the return stroke reverses the feed chain, and a second disc with (z2/z0)(1 - s/T) keeps the
    helix phase while the carriage climbs back ("the number of discs = the number of available ratios").
    """

    sensors = ("B2", "TV", "GShD")
    speeds = ("M1", "GShD")
    actuators = ("M1", "GShD")
    returns_by_reversing = True

    def __init__(
        self,
        motor: InductionMotor,
        windows: tuple[int, int],
        stepping: dict,
        p: int,
        encoder_lines: int,
        home: dict[str, float],
    ):
        self.p, self.m = p, motor
        self.disc_down = HydraulicPulseGenerator(windows[0], home["B2"])  # the stroke's disc
        self.disc_up = HydraulicPulseGenerator(windows[1], home["B2"])  # the return's disc
        self.gshd = HydraulicSteppingMotor(**stepping)
        self.feed_down, self.feed_up = StepFeed(), StepFeed()
        self.home = home["GShD"]
        self.stroke = StrokeCounter(encoder_lines, p, home["TV"])
        self.screw_pulses = 0
        self.b4_pulses = 0

    def b4_for_screw(self, screw_pulses: int) -> int:
        return self.b4_pulses

    def clutches(self, cnc: CncState) -> dict[str, bool]:
        return {"feed_chain": cnc.feed, "feed_reverse": cnc.reverse, "screw_brake": not (cnc.feed or cnc.reverse)}

    def tick(self, dt: float, cnc: CncState, angles: tuple[float, ...], speeds: tuple[float, ...]):
        b2, tv, h = angles
        self.m.scale, self.m.omega = cnc.scale, speeds[0]
        self.m.update(dt)
        self.screw_pulses = self.stroke.pulses(tv, dt)
        for disc in (self.disc_down, self.disc_up):  # both discs turn with the work; one is read
            disc.angle = b2
            disc.update(dt)
        down, up = self.feed_down.pulses(self.disc_down), self.feed_up.pulses(self.disc_up)
        g = self.gshd
        g.pulses = up if cnc.reverse else down
        g.angle, g.omega = h - self.home, speeds[1]
        g.update(dt)
        return self.m.torque, g.torque
