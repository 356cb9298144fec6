"""Electric servo motors: armature-controlled DC motor and current-controlled synchronous motor.

M1/M2/M3 (seed 000 fig. 4: "AC synchronous or high-torque DC"), M2 (seed 001 fig. 2), M1/M2 (fig. 3).
The shaft speed comes from the physics each tick; the motor returns its torque [N m] to the physics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ._params import non_negative, positive


@dataclass(slots=True, kw_only=True)
class DCMotor:
    """Armature-controlled DC motor behind a drive with a current limit.

    ::

        L di/dt = V - R i - k_e omega        torque = k_t i

    integrated exactly over the tick for constant ``V`` and ``omega``:
    ``i = i_inf + (i - i_inf) exp(-dt R/L)`` with ``i_inf = (V - k_e omega)/R`` (``L = 0``: ``i = i_inf``),
    then clamped to ``+-current_limit``.

    Parameters
    ----------
    resistance : float
        Armature resistance R [ohm], > 0.
    inductance : float
        Armature inductance L [H], >= 0.
    torque_constant : float
        k_t [N m/A], > 0.
    current_limit : float
        Drive current limit [A], > 0.
    back_emf : float or None
        k_e [V s/rad], > 0; None means ``k_e = k_t`` (SI units).

    Attributes
    ----------
    voltage : float
        Input: armature voltage [V].
    omega : float
        Input: shaft speed [rad/s].
    current : float
        Output: armature current [A].
    torque : float
        Output: electromagnetic torque [N m].
    at_limit : bool
        Output: True when the current is clamped.
    """

    resistance: float
    inductance: float
    torque_constant: float
    current_limit: float
    back_emf: float | None = None
    voltage: float = field(default=0.0, init=False)
    omega: float = field(default=0.0, init=False)
    current: float = field(default=0.0, init=False)
    torque: float = field(default=0.0, init=False)
    at_limit: bool = field(default=False, init=False)

    def __post_init__(self) -> None:
        self.resistance = positive("resistance", self.resistance)
        self.inductance = non_negative("inductance", self.inductance)
        self.torque_constant = positive("torque_constant", self.torque_constant)
        self.current_limit = positive("current_limit", self.current_limit)
        k_e = self.torque_constant if self.back_emf is None else self.back_emf
        self.back_emf = positive("back_emf", k_e)

    def update(self, dt: float) -> None:
        r = self.resistance
        i_inf = (self.voltage - self.back_emf * self.omega) / r
        i = i_inf if self.inductance == 0.0 else i_inf + (self.current - i_inf) * math.exp(-dt * r / self.inductance)
        limit = self.current_limit
        self.at_limit = not -limit <= i <= limit
        if self.at_limit:
            i = limit if i > 0.0 else -limit
        self.current = i
        self.torque = self.torque_constant * i

    def reset(self) -> None:
        self.voltage = 0.0
        self.omega = 0.0
        self.current = 0.0
        self.torque = 0.0
        self.at_limit = False


@dataclass(slots=True, kw_only=True)
class SynchronousMotor:
    """Current-controlled AC synchronous servo motor (permanent magnet, field-oriented drive).

    The current loop is a first-order lag with ``tau = 1/(2 pi bandwidth)``, discretised exactly::

        i += (1 - exp(-dt/tau)) * (clamp(current_command, +-current_limit) - i)      torque = k_t i

    Parameters
    ----------
    torque_constant : float
        k_t [N m/A], > 0.
    current_limit : float
        Drive current limit [A], > 0.
    bandwidth : float
        Current-loop bandwidth [Hz], > 0.

    Attributes
    ----------
    current_command : float
        Input: commanded current [A].
    current : float
        Output: current [A].
    torque : float
        Output: torque [N m].
    at_limit : bool
        Output: True when the command exceeds the current limit.
    """

    torque_constant: float
    current_limit: float
    bandwidth: float
    current_command: float = field(default=0.0, init=False)
    current: float = field(default=0.0, init=False)
    torque: float = field(default=0.0, init=False)
    at_limit: bool = field(default=False, init=False)

    def __post_init__(self) -> None:
        self.torque_constant = positive("torque_constant", self.torque_constant)
        self.current_limit = positive("current_limit", self.current_limit)
        self.bandwidth = positive("bandwidth", self.bandwidth)

    def update(self, dt: float) -> None:
        cmd = self.current_command
        limit = self.current_limit
        self.at_limit = not -limit <= cmd <= limit
        if self.at_limit:
            cmd = limit if cmd > 0.0 else -limit
        i = self.current - math.expm1(-dt * 2.0 * math.pi * self.bandwidth) * (cmd - self.current)
        self.current = i
        self.torque = self.torque_constant * i

    def reset(self) -> None:
        self.current_command = 0.0
        self.current = 0.0
        self.torque = 0.0
        self.at_limit = False


@dataclass(slots=True, kw_only=True)
class InductionMotor:
    """Squirrel-cage induction motor on a frequency converter: the main motor M of S1-S3 (seed 000 figs. 1-3)
    and the master spindle motor of seed 001 fig. 2 ("asynchronous with a frequency converter").

    The linear part of the torque-slip curve, with the converter's frequency as a fraction of nominal
    (V/f control keeps the slip speed for a given torque)::

        omega_sync = scale * sync_speed
        torque = clamp(rated_torque * (omega_sync - omega) / (rated_slip * sync_speed), +-breakdown * rated_torque)

    Parameters
    ----------
    sync_speed : float
        Synchronous speed at nominal frequency [rad/s], > 0.
    rated_torque : float
        [N m], > 0.
    rated_slip : float
        Slip at rated torque, in (0, 1).
    breakdown : float
        Breakdown torque over rated torque, > 1 (2.5 typical).

    Attributes
    ----------
    scale : float
        Input: converter frequency / nominal (run-up ramp), >= 0.
    omega : float
        Input: rotor speed [rad/s].
    torque : float
        Output: [N m].
    at_limit : bool
        Output: True at the breakdown torque.
    """

    sync_speed: float
    rated_torque: float
    rated_slip: float
    breakdown: float = 2.5
    scale: float = field(default=0.0, init=False)
    omega: float = field(default=0.0, init=False)
    torque: float = field(default=0.0, init=False)
    at_limit: bool = field(default=False, init=False)

    def __post_init__(self) -> None:
        self.sync_speed = positive("sync_speed", self.sync_speed)
        self.rated_torque = positive("rated_torque", self.rated_torque)
        if not 0.0 < self.rated_slip < 1.0:
            raise ValueError(f"rated_slip = {self.rated_slip!r}: must be between 0 and 1 (0.02-0.05 typical)")
        if not self.breakdown > 1.0:
            raise ValueError(f"breakdown = {self.breakdown!r}: must be > 1 (2-3 typical)")

    def update(self, dt: float) -> None:
        t = self.rated_torque * (self.scale * self.sync_speed - self.omega) / (self.rated_slip * self.sync_speed)
        limit = self.breakdown * self.rated_torque
        self.at_limit = not -limit <= t <= limit
        if self.at_limit:
            t = limit if t > 0.0 else -limit
        self.torque = t

    def reset(self) -> None:
        self.scale = 0.0
        self.omega = 0.0
        self.torque = 0.0
        self.at_limit = False
