"""The thread-cutting group Fv(B1 P2) of seed 001 in its three forms, wired from the controller blocks.

Element numbers of the seed's figures are the instance names. Every ``tick(dt, cnc, angles, motor_speeds)``
reads the spindle and lead-screw angles ``(B1, TV)`` [rad] and the motor speeds ``(M1, M2)`` [rad/s] and
returns the torques ``(M1, M2)`` [N m] (M2 = 0 where the form has no M2).

Pulse trains count command pulses of the motor they drive: ``p`` per turn of M2 (the setting formulas
kx = P / (i0 P_TV) and P = i01 (kv/kx) P_TV count M2 turns; the screw turns i0 resp. i01 times as far) and
``p`` per spindle turn. The correction encoder of the carriage (12 in fig. 2, 8 in fig. 3) sits on the lead
screw; its angle is referred to M2 (divided by the screw per motor ratio) so that it counts in the same
pulses. The carriage direction (the thread's hand, R1 of fig. 1) is the sign ``direction`` of the M2 pulses.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

from virtual_machine.controllers import (
    Encoder,
    FrequencyDivider,
    PulseToAnalog,
    RateMultiplier,
    ReferenceGenerator,
    SpeedRegulator,
    SynchronousMotor,
)
from virtual_machine.structures.axis import AxisTuning, ServoAxis


@dataclass
class ThreadCnc:
    """What the CNC sets each tick: the run-up scale of the speed command / reference frequency and the feed gate."""

    scale: float = 0.0  # fraction of the working speed (master speed command, generator 5 frequency)
    feed: bool = True  # the carriage's counter (7 with block 8, or 10) receives pulses


@dataclass(frozen=True)
class ThreadTuning:
    """Drive electronics: the spindle drive (M1: frequency converter of the induction motor, or servo amp 20)
    and the carriage's servo amplifier (11 / 28 driving M2). Peak torques come from the lathe's parameters."""

    spindle: AxisTuning = field(default_factory=lambda: AxisTuning(80.0, 120.0, 1.5, 120.0, 1500.0))
    carriage: AxisTuning = field(default_factory=lambda: AxisTuning(80.0, 120.0, 1.5, 20.0, 1500.0))


class SpeedDrive:
    """A speed-controlled drive without a position loop: PI speed regulator (current limit) + motor.

    The induction motor M with its frequency converter (seed 001: "M1 asynchronous with a frequency converter")
    is modelled as a field-oriented drive, i.e. a current-controlled motor (:class:`SynchronousMotor`) behind a
    :class:`SpeedRegulator` tuned like an axis amplifier: kp = J w / k_t, ki = kp w / 4 (w = 2 pi bandwidth).
    """

    def __init__(self, tuning: AxisTuning, inertia: float):
        w = 2 * math.pi * tuning.speed_bandwidth
        kp_torque = inertia * w
        limit = tuning.peak_torque / tuning.torque_constant
        self.regulator = SpeedRegulator(
            kp_torque / tuning.torque_constant, kp_torque * w / 4 / tuning.torque_constant, limit
        )
        self.motor = SynchronousMotor(
            torque_constant=tuning.torque_constant, current_limit=limit, bandwidth=tuning.current_bandwidth
        )

    def update(self, dt: float, speed_command: float, motor_speed: float) -> float:
        """One tick: motor speed command and tacho [rad/s] -> motor torque [N m]."""
        reg = self.regulator
        reg.speed_command, reg.tacho = speed_command, motor_speed
        reg.update(dt)
        self.motor.current_command = reg.out
        self.motor.update(dt)
        return self.motor.torque


class _FineSteps:
    """Pulses of a counter during this tick with their fractions (``fine_position`` increments): the
    pulse-to-analog converters integrate an evenly spaced train, not whole pulses per tick (see MechatronicS4)."""

    def __init__(self) -> None:
        self.last: dict[int, float] = {}

    def __call__(self, block, slot: int) -> float:
        now = block.fine_position
        step = now - self.last.get(slot, 0.0)
        self.last[slot] = now
        return step


class ThreadMechanical:
    """Fig. 1: one motor M. External link M -> 8 -> R2 -> iv -> 5 (speed); internal link
    B1 <- 3 <- 4 <- 5 -> ix -> R1 -> 6 -> TV -> 7 -> P2 (trajectory) is all mechanics, in the model.

    The only controller is the drive of M (``m1``: speed regulator + motor) holding ``motor_speed`` [rad/s]
    scaled by the CNC's run-up.
    """

    def __init__(self, motor_speed: float, tuning: AxisTuning, inertia: float):
        self.motor_speed = motor_speed
        self.m1 = SpeedDrive(tuning, inertia)

    def tick(self, dt: float, cnc: ThreadCnc, angles: tuple[float, float], motor_speeds: tuple[float, float]):
        return self.m1.update(dt, self.motor_speed * cnc.scale, motor_speeds[0]), 0.0


class ThreadMasterSlave:
    """Fig. 2: the spindle (master) is speed-controlled; the carriage (slave) follows its encoder.

    - master: M1 with its speed drive (``m1``: frequency converter, SpeedRegulator + motor) -> belt -> B1;
    - encoder ``enc6`` on the spindle -> counter 7 + coefficient block 8 (``rate7_8``, a rate multiplier N/K:
      M2 pulses per encoder count) -> pulse-to-analog converter ``pa9`` -> parallel summator 10 (preamp) ->
      power amplifier 11 -> M2 -> TV -> carriage 4; these and the correction module are ``axis``
      (:class:`ServoAxis`): encoder 12 on the screw, sign discriminator 13, phase discriminator 14, keys 15
      (lag, adds) and 16 (lead, subtracts), converter 17 into summator 10.

    The slave copies what the master really does, its mechanical deviations included (seed 001).
    """

    def __init__(
        self,
        spindle_motor_speed: float,
        block_n: int,
        counter_k: int,
        direction: int,
        p: int,
        encoder_lines: int,
        feed_ratio: float,
        inertias: tuple[float, float],
        adaptive: bool,
        tuning: ThreadTuning | None = None,
        angle0: tuple[float, float] = (0.0, 0.0),
        vibration: Callable[[float], float] | None = None,
    ):
        tuning = tuning or ThreadTuning()
        self.spindle_motor_speed, self.direction, self.feed_ratio = spindle_motor_speed, direction, feed_ratio
        #: vibration turning (seed 004): ``vibration(theta)`` M2 command pulses (fractional) added to the slave's
        #: command at the master's angle theta [rad] since the feed engaged (encoder 6, interpolated), so the
        #: vibration is synchronised to the spindle as the feed itself is
        self.vibration = vibration
        self._vib = 0.0
        self._enc0 = None
        self.m1 = SpeedDrive(tuning.spindle, inertias[0])
        self.enc6 = Encoder(encoder_lines, 4, angle0[0])
        self.rate7_8 = RateMultiplier(block_n, counter_k)
        self.pa9 = PulseToAnalog(2 * math.pi / p)
        self.axis = ServoAxis(tuning.carriage, p, encoder_lines, 1.0, inertias[1], adaptive, angle0[1] / feed_ratio)
        self.s10, self.amp11, self.m2 = self.axis.summator, self.axis.amplifier, self.axis.motor
        self.enc12, self.sd13, self.pd14 = self.axis.encoder, self.axis.sign, self.axis.phase
        self.key15, self.key16, self.c17 = self.axis.key_lag, self.axis.key_lead, self.axis.converter
        self.slave_pulses = 0  # signed M2 command position
        self._fine = _FineSteps()

    def tick(self, dt: float, cnc: ThreadCnc, angles: tuple[float, float], motor_speeds: tuple[float, float]):
        t1 = self.m1.update(dt, self.spindle_motor_speed * cnc.scale, motor_speeds[0])
        # ---- master encoder 6 -> counter 7 + block 8 -> 9 -> (10, 11, M2, correction 12..17)
        enc = self.enc6
        enc.angle = angles[0]
        enc.update(dt)
        rate = self.rate7_8
        rate.inp = enc.count if cnc.feed else 0
        rate.update(dt)
        self.slave_pulses += self.direction * rate.out
        vib_step = 0.0
        if self.vibration is not None and cnc.feed:
            if self._enc0 is None:  # the vibration starts with the feed, at the master's angle then
                self._enc0 = enc.fine_position
            theta = (enc.fine_position - self._enc0) * 2 * math.pi / enc.counts_per_rev
            vib = self.direction * self.vibration(theta)
            vib_step, self._vib = vib - self._vib, vib
        self.pa9.inp = self.direction * self._fine(rate, 0) + vib_step
        self.pa9.update(dt)
        t2 = self.axis.update(
            dt, self.pa9.out, self.slave_pulses + round(self._vib), angles[1] / self.feed_ratio, motor_speeds[1]
        )
        return t1, t2


class ThreadEqualCoordinates:
    """Fig. 3: both axes follow reference generator 5; neither sees the other.

    - spindle: generator 5 -> counter 9 (kv) -> converter 13 -> parallel summator 16 -> amp 20 -> M1 -> B1;
      encoder 7, sign/phase discriminators 14/15, converter 17, keys 18 (lag) / 19 (lead) into 16;
    - carriage: generator 5 -> counter 10 (kx) -> converter 21 -> parallel summator 24 -> amp 28 -> M2 -> TV;
      encoder 8 (on the screw), discriminators 22/23, converter 25, keys 26 (lag) / 27 (lead) into 24.

    Each axis is a :class:`ServoAxis` (``spindle``, ``carriage``); the attributes ``s16``, ``amp20``, ... name
    their elements with the seed's numbers. P = i01 (kv / kx) P_TV.
    """

    def __init__(
        self,
        f_ref: float,
        kv: int,
        kx: int,
        direction: int,
        p: int,
        encoder_lines: int,
        spindle_ratio: float,
        feed_ratio: float,
        inertias: tuple[float, float],
        adaptive: bool,
        tuning: ThreadTuning | None = None,
        angle0: tuple[float, float] = (0.0, 0.0),
    ):
        tuning = tuning or ThreadTuning()
        self.f_ref, self.direction, self.feed_ratio = f_ref, direction, feed_ratio
        self.gen5 = ReferenceGenerator(0.0)
        self.d9, self.d10 = FrequencyDivider(kv), FrequencyDivider(kx)
        self.pa13, self.pa21 = PulseToAnalog(2 * math.pi / p), PulseToAnalog(2 * math.pi / p)
        self.spindle = ServoAxis(tuning.spindle, p, encoder_lines, spindle_ratio, inertias[0], adaptive, angle0[0])
        self.carriage = ServoAxis(tuning.carriage, p, encoder_lines, 1.0, inertias[1], adaptive, angle0[1] / feed_ratio)
        a, b = self.spindle, self.carriage
        self.s16, self.amp20, self.m1, self.enc7 = a.summator, a.amplifier, a.motor, a.encoder
        self.sd14, self.pd15, self.c17, self.key18, self.key19 = a.sign, a.phase, a.converter, a.key_lag, a.key_lead
        self.s24, self.amp28, self.m2, self.enc8 = b.summator, b.amplifier, b.motor, b.encoder
        self.sd22, self.pd23, self.c25, self.key26, self.key27 = b.sign, b.phase, b.converter, b.key_lag, b.key_lead
        self.carriage_pulses = 0  # signed M2 command position
        self._fine = _FineSteps()

    def tick(self, dt: float, cnc: ThreadCnc, angles: tuple[float, float], motor_speeds: tuple[float, float]):
        gen = self.gen5
        gen.frequency = self.f_ref * cnc.scale
        gen.update(dt)
        # ---- spindle: 5 -> 9 -> 13 -> 16 -> 20 -> M1
        self.d9.inp = gen.out
        self.d9.update(dt)
        self.pa13.inp = self._fine(self.d9, 0)
        self.pa13.update(dt)
        t1 = self.spindle.update(dt, self.pa13.out, self.d9.position, angles[0], motor_speeds[0])
        # ---- carriage: 5 -> (CNC gate) 10 -> 21 -> 24 -> 28 -> M2
        self.d10.inp = gen.out if cnc.feed else 0
        self.d10.update(dt)
        self.carriage_pulses += self.direction * self.d10.out
        self.pa21.inp = self.direction * self._fine(self.d10, 1)
        self.pa21.update(dt)
        t2 = self.carriage.update(dt, self.pa21.out, self.carriage_pulses, angles[1] / self.feed_ratio, motor_speeds[1])
        return t1, t2
