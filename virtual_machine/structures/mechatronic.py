"""S4 mechatronic structure, equal-coordinates scheme (seed 000 fig. 4): the electronic gearbox.

Reference pulse generator 14 feeds four frequency dividers in parallel:

- divider 6 (kv)  -> pulse-to-analog 5  -> parallel summator 4  -> power amp 3  -> M1 -> tool spindle (B1)
- divider 7 (kx)  -> pulse-to-analog 8  -> summator 9 -> parallel summator 10 -> power amp 11 -> M2 -> work (B2)
- divider 22 (ky) -> pulse-to-analog 23 -> summator 9 (the helix's additional rotation B4)
- divider 21 (ks) -> pulse-to-analog 20 -> parallel summator 19 -> power amp 18 -> M3 -> lead screw -> carriage (P3)

Adaptive correction modules (closed keys only with ``adaptive``): tool IP1, discriminators 25/26, converter
29, keys 27/28 into summator 4; work IP2 against the reference of analog-to-pulse converter 32 (from
summator 9), discriminators 30/31, converter 35, keys 33/34 into summator 10; carriage IP3, discriminators
36/37, converter 40, keys 38/39 into summator 19. Every pulse train counts command pulses of its own axis:
``p`` per turn of the spindle or of the lead screw (so c2 = 1 as in the setup sheet).

The CNC gates dividers 21 and 22 (feed on/off) and, for the rapid return, drives both axes with a linear
interpolator that undoes exactly the pulses of the pass, so the helix phase is kept from pass to pass.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from virtual_machine.controllers import (
    AnalogToPulse,
    FrequencyDivider,
    ParallelSummator,
    PulseToAnalog,
    ReferenceGenerator,
)
from virtual_machine.structures.axis import AxisTuning, ServoAxis


@dataclass
class CncState:
    """What the CNC sets each tick: generator run-up scale, feed gate and direction, rapid pulses."""

    scale: float = 0.0  # reference generator frequency as a fraction of f_ref (run-up ramp)
    feed: bool = False  # dividers 21 and 22 receive the generator's pulses
    feed_dir: int = -1  # carriage direction of the feed (-1: down)
    rapid_screw: int = 0  # interpolated pulses this tick for the lead-screw axis (rapid moves)
    rapid_b4: int = 0  # and for the B4 input of summator 9
    reverse: bool = False  # return stroke by reversing the feed chain (S3 has no traverse drive)
    #: the tangential correction of a flank modification (seed 003): where the CNC wants the work's extra turn,
    #: in command pulses of the work axis (fractional), fed to summator 9 with the B4 pulses (S4 only)
    correction_b4: float = 0.0


@dataclass(frozen=True)
class S4Tuning:
    tool: AxisTuning = field(default_factory=lambda: AxisTuning(80.0, 120.0, peak_torque=40.0))
    work: AxisTuning = field(default_factory=lambda: AxisTuning(80.0, 120.0, peak_torque=60.0))
    feed: AxisTuning = field(default_factory=lambda: AxisTuning(40.0, 60.0, peak_torque=20.0))


class _ServoAxes:
    """What both S4 forms share: three servo axes read by encoders IP1..IP3 on B1, B2, TV, tachogenerators on
    the motors, no clutches; converters fed pulse-train increments with their fractions (``_fine``)."""

    sensors = ("B1", "B2", "TV")  # angles the encoders IP1..IP3 read
    speeds = ("M1", "M2", "M3")  # tachogenerators
    actuators = ("M1", "M2", "M3")
    _last: list[float]

    def clutches(self, cnc: CncState) -> dict[str, bool]:
        return {}

    def _fine(self, block, slot: int) -> float:
        """Pulses of ``block`` (a divider or rate multiplier) during this tick counted with their fractions (its
        ``fine_position``): the pulse-to-analog converters integrate an evenly spaced train, not whole pulses per
        tick."""
        now = block.fine_position
        step = now - self._last[slot]
        self._last[slot] = now
        return step


class MechatronicS4(_ServoAxes):
    """The wiring of fig. 4. ``dirs``: signs of B1, B2 (speed ratio) and B4 per feed pulse."""

    def __init__(
        self,
        f_ref: float,
        p: int,
        kv: int,
        kx: int,
        ks: int,
        ky: int | None,
        dir_work: int,
        dir_b4: int,
        encoder_lines: int,
        ratios: tuple[float, float, float],
        inertias: tuple[float, float, float],
        adaptive: bool,
        tuning: S4Tuning | None = None,
        angle0: tuple[float, float, float] = (0.0, 0.0, 0.0),
    ):
        self.f_ref, self.p = f_ref, p
        tuning = tuning or S4Tuning()
        self.dir_work, self.dir_b4 = dir_work, dir_b4
        rad = 2 * math.pi / p  # rad of axis per command pulse
        self.gen14 = ReferenceGenerator(0.0)
        self.d6, self.d7, self.d21 = FrequencyDivider(kv), FrequencyDivider(kx), FrequencyDivider(ks)
        self.d22 = FrequencyDivider(ky) if ky else None
        self.pa5, self.pa8, self.pa20, self.pa23 = (PulseToAnalog(rad) for _ in range(4))
        self.s9 = ParallelSummator()
        self.ap32 = AnalogToPulse(1 / rad)
        self.tool = ServoAxis(tuning.tool, p, encoder_lines, ratios[0], inertias[0], adaptive, angle0[0])
        self.work = ServoAxis(tuning.work, p, encoder_lines, ratios[1], inertias[1], adaptive, angle0[1])
        self.feed = ServoAxis(tuning.feed, p, encoder_lines, ratios[2], inertias[2], adaptive, angle0[2])
        self.b4_pulses = 0  # B4 pulses issued (for the CNC's return move)
        self.screw_pulses = 0
        self._last = [0.0, 0.0, 0.0, 0.0]  # fine positions of dividers 6, 21, 7, 22 at the last tick
        self._b4_per_screw = 0.0 if ky is None else dir_b4 * ks / ky
        self._correction, self._correction_pulses = 0.0, 0  # tangential correction fed so far (fine, whole)

    def b4_for_screw(self, screw_pulses: int) -> int:
        """The B4 pulses that belong to a lead-screw pulse position (the CNC's return move keeps this relation)."""
        return round(screw_pulses * self._b4_per_screw)

    def tick(
        self, dt: float, cnc: CncState, angles: tuple[float, float, float], motor_speeds: tuple[float, float, float]
    ):
        """One servo tick. ``angles``: B1, B2, TV [rad]; ``motor_speeds``: M1, M2, M3 [rad/s].
        Returns the torques of M1, M2, M3 [N m]."""
        gen = self.gen14
        gen.frequency = self.f_ref * cnc.scale
        gen.update(dt)
        # ---- tool spindle: 6 -> 5 -> 4 -> 3 -> M1
        self.d6.inp = gen.out
        self.d6.update(dt)
        self.pa5.inp = self._fine(self.d6, 0)
        self.pa5.update(dt)
        t1 = self.tool.update(dt, self.pa5.out, self.d6.position, angles[0], motor_speeds[0])
        # ---- carriage: CNC gate -> 21 -> 20 -> 19 -> 18 -> M3 (rapid moves: the CNC's interpolator)
        self.d21.inp = gen.out if cnc.feed else 0
        self.d21.update(dt)
        screw = cnc.feed_dir * self.d21.out + cnc.rapid_screw
        self.screw_pulses += screw
        self.pa20.inp = cnc.feed_dir * self._fine(self.d21, 1) + cnc.rapid_screw
        self.pa20.update(dt)
        t3 = self.feed.update(dt, self.pa20.out, self.screw_pulses, angles[2], motor_speeds[2])
        # ---- work spindle: 7 -> 8 and 22 -> 23 -> summator 9 -> (32 reference) -> 10 -> 11 -> M2
        self.d7.inp = gen.out
        self.d7.update(dt)
        self.pa8.inp = self.dir_work * self._fine(self.d7, 2)
        self.pa8.update(dt)
        b4 = cnc.rapid_b4
        b4_fine = float(b4)
        if self.d22 is not None:
            self.d22.inp = gen.out if cnc.feed else 0
            self.d22.update(dt)
            b4 += self.dir_b4 * cnc.feed_dir * self.d22.out
            b4_fine += self.dir_b4 * cnc.feed_dir * self._fine(self.d22, 3)
        if cnc.correction_b4 != self._correction:  # the CNC's tangential correction joins the B4 input
            whole = round(cnc.correction_b4) - self._correction_pulses
            b4 += whole
            self._correction_pulses += whole
            b4_fine += cnc.correction_b4 - self._correction
            self._correction = cnc.correction_b4
        self.b4_pulses += b4
        self.pa23.inp = b4_fine
        self.pa23.update(dt)
        s9 = self.s9
        s9.main, s9.add = self.pa8.out, self.pa23.out
        s9.update(dt)
        self.ap32.inp = s9.out
        self.ap32.update(dt)
        t2 = self.work.update(dt, s9.out, self.ap32.position, angles[1], motor_speeds[1])
        return t1, t2, t3


class MechatronicS4MasterSlave(_ServoAxes):
    """S4 in master-slave form (the tracking synchronisation of seed 000 fig. 2, realised electronically).

    Fv: the tool spindle is the master, run by generator 14 and divider 6 like the equal-coordinates form; the
    work spindle's reference is built from the master's encoder IP1 through a rate multiplier (``mult_x``,
    z0/z2) plus the B4 part from the lead-screw encoder IP3 (``mult_y``, t_TV/T). Fs: the carriage follows the
    work encoder IP2 through ``mult_s`` (s/t_TV per work turn) while the CNC's feed gate is on. A slave thus
    copies what its master really does, including the master's mechanical deviations (seed 001's point); the
    equal-coordinates form compares each axis with the generator only.
    """

    def __init__(
        self,
        f_ref: float,
        p: int,
        kv: int,
        ratio_x: float,
        ratio_y: float,
        ratio_s: float,
        encoder_lines: int,
        ratios: tuple[float, float, float],
        inertias: tuple[float, float, float],
        adaptive: bool,
        tuning: S4Tuning | None = None,
        angle0: tuple[float, float, float] = (0.0, 0.0, 0.0),
    ):
        from fractions import Fraction

        from virtual_machine.controllers import Encoder, RateMultiplier

        tuning = tuning or S4Tuning()
        self.f_ref, self.p = f_ref, p
        rad = 2 * math.pi / p
        self.gen14 = ReferenceGenerator(0.0)
        self.d6 = FrequencyDivider(kv)
        self.pa5, self.pa8, self.pa20 = (PulseToAnalog(rad) for _ in range(3))
        self.tool = ServoAxis(tuning.tool, p, encoder_lines, ratios[0], inertias[0], adaptive, angle0[0])
        self.work = ServoAxis(tuning.work, p, encoder_lines, ratios[1], inertias[1], adaptive, angle0[1])
        self.feed = ServoAxis(tuning.feed, p, encoder_lines, ratios[2], inertias[2], adaptive, angle0[2])
        # master encoders read by the slaves' rate multipliers (the axes' own IP1..IP3 read the same shafts)
        self.ip1, self.ip2, self.ip3 = (Encoder(encoder_lines, 4, a) for a in angle0)
        cpr = 4 * encoder_lines

        def multiplier(ratio: float) -> tuple[RateMultiplier | None, int]:
            """Command pulses of the slave per count of the master's encoder, as n/k integers, and the sign."""
            if ratio == 0:
                return None, 0
            f = Fraction(abs(ratio) * p / cpr).limit_denominator(2**24)
            return RateMultiplier(max(1, f.numerator), f.denominator), (1 if ratio > 0 else -1)

        (self.mult_x, self.sign_x), (self.mult_y, self.sign_y), (self.mult_s, self.sign_s) = (
            multiplier(ratio_x),
            multiplier(ratio_y),
            multiplier(ratio_s),
        )
        self.screw_pulses = 0
        self.b4_pulses = 0  # B4 follows the screw's real motion: the CNC's return needs no B4 pulses
        self._last = [0.0, 0.0, 0.0, 0.0]
        self._work_reference = 0

    def b4_for_screw(self, screw_pulses: int) -> int:
        return self.b4_pulses

    def tick(
        self, dt: float, cnc: CncState, angles: tuple[float, float, float], motor_speeds: tuple[float, float, float]
    ):
        gen = self.gen14
        gen.frequency = self.f_ref * cnc.scale
        gen.update(dt)
        for enc, angle in zip((self.ip1, self.ip2, self.ip3), angles, strict=True):
            enc.angle = angle
            enc.update(dt)
        # ---- master: tool spindle from generator 14 and divider 6
        self.d6.inp = gen.out
        self.d6.update(dt)
        self.pa5.inp = self._fine(self.d6, 0)
        self.pa5.update(dt)
        t1 = self.tool.update(dt, self.pa5.out, self.d6.position, angles[0], motor_speeds[0])
        # ---- slave carriage: work encoder IP2 -> mult_s (feed gate) -> 20 -> 19 -> 18 -> M3
        screw, screw_fine = cnc.rapid_screw, float(cnc.rapid_screw)
        if self.mult_s is not None:
            self.mult_s.inp = self.ip2.count if cnc.feed else 0
            self.mult_s.update(dt)
            screw += self.sign_s * self.mult_s.out
            screw_fine += self.sign_s * self._fine(self.mult_s, 1)
        self.screw_pulses += screw
        self.pa20.inp = screw_fine
        self.pa20.update(dt)
        t3 = self.feed.update(dt, self.pa20.out, self.screw_pulses, angles[2], motor_speeds[2])
        # ---- slave work spindle: IP1 -> mult_x, IP3 -> mult_y -> 8 -> 10 -> 11 -> M2
        self.mult_x.inp = self.ip1.count
        self.mult_x.update(dt)
        ref = self.sign_x * self.mult_x.out
        ref_fine = self.sign_x * self._fine(self.mult_x, 2)
        if self.mult_y is not None:
            self.mult_y.inp = self.ip3.count
            self.mult_y.update(dt)
            ref += self.sign_y * self.mult_y.out
            ref_fine += self.sign_y * self._fine(self.mult_y, 3)
        self._work_reference += ref
        self.pa8.inp = ref_fine
        self.pa8.update(dt)
        t2 = self.work.update(dt, self.pa8.out, self._work_reference, angles[1], motor_speeds[1])
        return t1, t2, t3
