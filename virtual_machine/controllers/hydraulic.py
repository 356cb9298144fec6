"""Hydraulic shaft: hydraulic pulse generator (GGI) and hydraulic stepping motor (GShD).

Seed 000 figs. 2/3: GGI1..GGI3 turned by the master axis send oil pulses to GShD1..GShD3 on the slave
axis, one step per pulse.  A GGI with ``windows`` windows driving a GShD with ``steps_per_rev`` steps
gives the slave/master ratio ``windows/steps_per_rev``: a discrete set of ratios (one per disc).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ._params import finite, integer_at_least, non_negative, positive

TWO_PI = 2.0 * math.pi


@dataclass(slots=True)
class HydraulicPulseGenerator:
    """Hydraulic pulse generator GGI1..GGI3: a coding disc with ``windows`` windows on the master shaft.

    ::

        position = floor((angle - angle0) * windows / (2 pi))       out = position - previous

    Parameters
    ----------
    windows : int
        Windows on the disc (pulses per revolution), integer >= 1.
    angle0 : float
        Shaft angle [rad] at which ``position`` is 0.

    Attributes
    ----------
    angle : float
        Input: master shaft angle [rad], continuous, any sign.
    out : int
        Output: pulses this tick (signed).
    position : int
        Output: total pulses.
    """

    windows: int
    angle0: float = 0.0
    angle: float = field(default=0.0, init=False)
    out: int = field(default=0, init=False)
    position: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        self.windows = integer_at_least("windows", self.windows, 1)
        self.angle0 = finite("angle0", self.angle0)
        self.reset()

    @property
    def fine_position(self) -> float:
        """Windows passed, with the fraction of the next: what the stepping motor integrates when its steps come
        faster than the servo tick (then they are spread evenly over it, not lumped at its end)."""
        return (self.angle - self.angle0) * self.windows / TWO_PI

    def update(self, dt: float) -> None:
        p = math.floor((self.angle - self.angle0) * self.windows / TWO_PI)
        self.out = p - self.position
        self.position = p

    def reset(self) -> None:
        self.angle = self.angle0
        self.out = 0
        self.position = 0


@dataclass(slots=True, kw_only=True)
class HydraulicSteppingMotor:
    """Hydraulic stepping motor GShD1..GShD3: one step of ``2 pi/steps_per_rev`` per pulse, held by oil.

    Each tick, with ``T`` the previous output torque::

        commanded = steps * 2 pi/steps_per_rev - creep,     creep += leakage * T * dt
        command_rate = (commanded - commanded_previous) / dt
        torque = clamp(stiffness*(commanded - angle) + damping*(command_rate - omega), +-torque_limit)

    The oil column is a torsional spring (``stiffness``) with ``damping``; under load oil leaks past the
    vanes, so the motor slips behind its steps at ``leakage * torque`` [rad/s] (the creep is permanent).

    Parameters
    ----------
    steps_per_rev : int
        Steps per revolution, integer >= 1.
    stiffness : float
        Oil compliance as torque per lag angle [N m/rad], > 0.
    damping : float
        Viscous damping [N m s/rad], >= 0.
    leakage : float
        Slip rate per torque [rad/s per N m], >= 0.
    torque_limit : float
        Torque limit (relief valve) [N m], > 0.

    Attributes
    ----------
    pulses : int
        Input: pulses this tick (signed).
    angle : float
        Input: motor shaft angle [rad] from the physics.
    omega : float
        Input: motor shaft speed [rad/s] from the physics.
    steps : int
        State: total pulses received.
    commanded : float
        Output: commanded angle [rad] including the leakage creep.
    torque : float
        Output: torque on the shaft [N m].
    at_limit : bool
        Output: True when the torque is clamped.
    """

    steps_per_rev: int
    stiffness: float
    damping: float
    leakage: float
    torque_limit: float
    pulses: int = field(default=0, init=False)
    angle: float = field(default=0.0, init=False)
    omega: float = field(default=0.0, init=False)
    steps: int = field(default=0, init=False)
    commanded: float = field(default=0.0, init=False)
    torque: float = field(default=0.0, init=False)
    at_limit: bool = field(default=False, init=False)
    _creep: float = field(default=0.0, init=False, repr=False)

    def __post_init__(self) -> None:
        self.steps_per_rev = integer_at_least("steps_per_rev", self.steps_per_rev, 1)
        self.stiffness = positive("stiffness", self.stiffness)
        self.damping = non_negative("damping", self.damping)
        self.leakage = non_negative("leakage", self.leakage)
        self.torque_limit = positive("torque_limit", self.torque_limit)

    def update(self, dt: float) -> None:
        self._creep += self.leakage * self.torque * dt
        self.steps += self.pulses
        commanded = self.steps * TWO_PI / self.steps_per_rev - self._creep
        rate = (commanded - self.commanded) / dt
        self.commanded = commanded
        t = self.stiffness * (commanded - self.angle) + self.damping * (rate - self.omega)
        limit = self.torque_limit
        self.at_limit = not -limit <= t <= limit
        if self.at_limit:
            t = limit if t > 0.0 else -limit
        self.torque = t

    def reset(self) -> None:
        self.pulses = 0
        self.angle = 0.0
        self.omega = 0.0
        self.steps = 0
        self.commanded = 0.0
        self.torque = 0.0
        self.at_limit = False
        self._creep = 0.0
