"""One servo axis of the electronic gearbox: the elements that every axis of seed 000 fig. 4 repeats.

command pulses -> pulse-to-analog converter -> parallel summator -> power amplifier (speed regulator and
current limit) -> motor, with the adaptive correction module beside it: encoder -> sign and phase
discriminators -> converter -> keys (lag adds, lead subtracts) -> the summator's second inputs.
The structure that owns the axis names the instances with the seed's element numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from virtual_machine.controllers import (
    CountToAnalog,
    Encoder,
    Key,
    ParallelSummator,
    PhaseDiscriminator,
    SignDiscriminator,
    SpeedRegulator,
    SynchronousMotor,
)


@dataclass(frozen=True)
class AxisTuning:
    """Drive electronics of one axis; gains follow from the axis inertia and the wanted bandwidths.

    ``speed_bandwidth`` [Hz]: speed loop of the amplifier; ``position_gain`` [1/s]: Kv of the correction
    loop (speed command per unit of phase error); ``torque_constant`` [N m/A]; ``peak_torque`` [N m] sets
    the current limit; ``current_bandwidth`` [Hz] of the motor's current loop.
    """

    speed_bandwidth: float = 80.0
    position_gain: float = 120.0
    torque_constant: float = 1.5
    peak_torque: float = 40.0
    current_bandwidth: float = 1500.0


class ServoAxis:
    """Amplifier, motor and correction module of one axis. ``pulses_per_rev``: command pulses per axis turn;
    ``ratio``: axis turn per motor turn; ``inertia``: at the motor [kg m^2] (rotor + reflected load)."""

    def __init__(
        self,
        tuning: AxisTuning,
        pulses_per_rev: int,
        encoder_lines: int,
        ratio: float,
        inertia: float,
        adaptive: bool,
        angle0: float = 0.0,
    ):
        self.p, self.ratio, self.adaptive = pulses_per_rev, ratio, adaptive
        w = 2 * math.pi * tuning.speed_bandwidth
        kp_torque = inertia * w
        self.summator = ParallelSummator()
        self.amplifier = SpeedRegulator(
            kp=kp_torque / tuning.torque_constant,
            ki=kp_torque * w / 4 / tuning.torque_constant,
            limit=tuning.peak_torque / tuning.torque_constant,
        )
        self.motor = SynchronousMotor(
            torque_constant=tuning.torque_constant,
            current_limit=tuning.peak_torque / tuning.torque_constant,
            bandwidth=tuning.current_bandwidth,
        )
        self.encoder = Encoder(encoder_lines, 4, angle0)
        self.sign = SignDiscriminator()
        self.phase = PhaseDiscriminator()
        self.converter = CountToAnalog(tuning.position_gain * 2 * math.pi / pulses_per_rev)
        self.key_lag, self.key_lead = Key(), Key()

    def update(self, dt: float, command: float, reference: int, axis_angle: float, motor_speed: float) -> float:
        """One tick: ``command`` axis speed [rad/s], ``reference`` pulse position, measured angle and motor speed.
        Returns the motor torque [N m]."""
        enc = self.encoder
        enc.angle = axis_angle
        enc.update(dt)
        feedback = enc.position * self.p // enc.counts_per_rev  # encoder counts in command pulses
        self.sign.reference = self.phase.reference = reference
        self.sign.feedback = self.phase.feedback = feedback
        self.sign.update(dt)
        self.phase.update(dt)
        self.converter.inp = self.phase.out
        self.converter.update(dt)
        self.key_lag.inp = self.key_lead.inp = self.converter.out
        self.key_lag.closed = self.adaptive and self.sign.out < 0  # lagging: add the error
        self.key_lead.closed = self.adaptive and self.sign.out > 0  # leading: subtract it
        self.key_lag.update(dt)
        self.key_lead.update(dt)
        s = self.summator
        s.main, s.add, s.sub = command, self.key_lag.out, self.key_lead.out
        s.update(dt)
        amp = self.amplifier
        amp.speed_command, amp.tacho = s.out / self.ratio, motor_speed
        amp.update(dt)
        self.motor.current_command = amp.out
        self.motor.update(dt)
        return self.motor.torque


class StrokeCounter:
    """The CNC's encoder on the lead screw (S1-S3 have no feed servo): the carriage's travel in command pulses,
    ``p`` per screw turn, which ends a feed stroke and places the return."""

    def __init__(self, encoder_lines: int, pulses_per_rev: int, tv0: float):
        self.encoder = Encoder(encoder_lines, 4, tv0)
        self.p = pulses_per_rev

    def pulses(self, tv: float, dt: float) -> int:
        enc = self.encoder
        enc.angle = tv
        enc.update(dt)
        return enc.position * self.p // enc.counts_per_rev
