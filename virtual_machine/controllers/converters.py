"""Pulse <-> analog converters (seed 000 fig. 4, seed 001 figs. 2/3).

Pulse inputs/outputs are signed ``int`` counts per tick; analog signals are ``float`` [V or the
caller's units].
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ._params import non_negative, nonzero


@dataclass(slots=True)
class PulseToAnalog:
    """Pulse-to-analog (frequency-to-voltage) converter 5/8/20/23 (seed 000 fig. 4), 9 (seed 001 fig. 2),
    13/21 (seed 001 fig. 3).

    The pulse rate ``inp/dt`` passes a first-order low pass with time constant ``tau``, discretised
    exactly for a rate constant over the tick::

        rate += (1 - exp(-dt/tau)) * (inp/dt - rate)        out = gain * rate

    ``tau = 0`` means no filter: ``rate = inp/dt``.

    Parameters
    ----------
    gain : float
        Output per pulse rate [units per (pulse/s)], finite, != 0.
    tau : float
        Filter time constant [s], >= 0.

    Attributes
    ----------
    inp : int
        Input: pulses this tick (signed).
    rate : float
        State: filtered pulse rate [pulses/s].
    out : float
        Output: ``gain * rate`` [units].
    """

    gain: float
    tau: float = 0.0
    inp: int = field(default=0, init=False)
    rate: float = field(default=0.0, init=False)
    out: float = field(default=0.0, init=False)

    def __post_init__(self) -> None:
        self.gain = nonzero("gain", self.gain)
        self.tau = non_negative("tau", self.tau)

    def update(self, dt: float) -> None:
        target = self.inp / dt
        rate = target if self.tau == 0.0 else self.rate - math.expm1(-dt / self.tau) * (target - self.rate)
        self.rate = rate
        self.out = self.gain * rate

    def reset(self) -> None:
        self.inp = 0
        self.rate = 0.0
        self.out = 0.0


@dataclass(slots=True)
class CountToAnalog:
    """Error-count-to-analog converter after a phase discriminator: 29/35/40 (seed 000 fig. 4), 17
    (seed 001 fig. 2), 17/25 (seed 001 fig. 3).

    ``out = gain * inp``, where ``inp`` is an error in counts (a level, not pulses per tick).

    Parameters
    ----------
    gain : float
        Output per count [units/count], finite, != 0.

    Attributes
    ----------
    inp : int
        Input: error [counts].
    out : float
        Output [units].
    """

    gain: float
    inp: int = field(default=0, init=False)
    out: float = field(default=0.0, init=False)

    def __post_init__(self) -> None:
        self.gain = nonzero("gain", self.gain)

    def update(self, dt: float) -> None:
        self.out = self.gain * self.inp

    def reset(self) -> None:
        self.inp = 0
        self.out = 0.0


@dataclass(slots=True)
class AnalogToPulse:
    """Analog-to-pulse converter (voltage-controlled oscillator) 32 (seed 000 fig. 4).

    ``phase += gain*inp*dt; out = floor(phase); phase -= out``: a pulse is emitted each time the integral
    crosses a whole number, in either direction, and the fraction (``0 <= phase < 1``) is kept, so
    ``position = floor(integral of gain*inp dt)``.

    Parameters
    ----------
    gain : float
        Pulse rate per input unit [(pulses/s)/unit], finite, != 0.

    Attributes
    ----------
    inp : float
        Input [units].
    out : int
        Output: pulses this tick (signed).
    position : int
        Output: total pulses.
    """

    gain: float
    inp: float = field(default=0.0, init=False)
    out: int = field(default=0, init=False)
    position: int = field(default=0, init=False)
    _phase: float = field(default=0.0, init=False, repr=False)

    def __post_init__(self) -> None:
        self.gain = nonzero("gain", self.gain)

    def update(self, dt: float) -> None:
        phase = self._phase + self.gain * self.inp * dt
        n = math.floor(phase)
        self._phase = phase - n
        self.out = n
        self.position += n

    def reset(self) -> None:
        self.inp = 0.0
        self.out = 0
        self.position = 0
        self._phase = 0.0
