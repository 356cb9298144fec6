"""The speed regulator inside a power amplifier (3, 11, 18 of seed 000 fig. 4).

The seed draws "power amplifier -> motor"; a drive that holds a commanded speed under load has a speed
loop closed on a tachogenerator at the motor. :class:`SpeedRegulator` is that loop: a PI regulator on the
motor speed error whose output, the current command, is limited by the amplifier's current limit. Without
adaptive correction the axis is therefore speed-controlled only: what a load transient costs in position
is never recovered (the point of the correction modules).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ._params import non_negative, positive


@dataclass(slots=True)
class SpeedRegulator:
    """PI speed regulator with current limit and anti-windup (integration stops while saturated outward).

    ::

        e = speed_command - tacho            u = kp e + ki * integral(e dt)       out = clamp(u, +-limit)

    Parameters
    ----------
    kp : float
        Proportional gain [A per rad/s], > 0.
    ki : float
        Integral gain [A per rad], >= 0.
    limit : float
        Current limit of the amplifier [A], > 0.

    Attributes
    ----------
    speed_command : float
        Input: motor speed command [rad/s].
    tacho : float
        Input: motor speed from the tachogenerator [rad/s].
    out : float
        Output: current command [A].
    saturated : bool
        Output: True while the output is at the limit.
    """

    kp: float
    ki: float
    limit: float
    speed_command: float = field(default=0.0, init=False)
    tacho: float = field(default=0.0, init=False)
    out: float = field(default=0.0, init=False)
    saturated: bool = field(default=False, init=False)
    _integral: float = field(default=0.0, init=False, repr=False)

    def __post_init__(self) -> None:
        self.kp = positive("kp", self.kp)
        self.ki = non_negative("ki", self.ki)
        self.limit = positive("limit", self.limit)

    def update(self, dt: float) -> None:
        e = self.speed_command - self.tacho
        integral = self._integral + e * dt
        u = self.kp * e + self.ki * integral
        lim = self.limit
        self.saturated = not -lim <= u <= lim
        if self.saturated:
            u = lim if u > 0.0 else -lim
            if (u > 0.0) == (e > 0.0):  # do not wind up further in the saturated direction
                integral = self._integral
        self._integral = integral
        self.out = u

    def reset(self) -> None:
        self.speed_command = 0.0
        self.tacho = 0.0
        self.out = 0.0
        self.saturated = False
        self._integral = 0.0
