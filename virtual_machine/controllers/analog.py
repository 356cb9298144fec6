"""Analog blocks: parallel summator, power amplifier, key (seed 000 fig. 4, seed 001 figs. 2/3).

Analog signals are ``float`` in the caller's units (volts for the seed's analog chain).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ._params import nonzero, positive


@dataclass(slots=True)
class ParallelSummator:
    """Parallel summator 4/10/19 (seed 000 fig. 4), 10 (seed 001 fig. 2), 16/24 (seed 001 fig. 3).

    ``out = main + add - sub``: the main (speed) signal plus the correction through the lag key minus
    the correction through the lead key.

    Attributes
    ----------
    main, add, sub : float
        Inputs [units].
    out : float
        Output [units].
    """

    main: float = field(default=0.0, init=False)
    add: float = field(default=0.0, init=False)
    sub: float = field(default=0.0, init=False)
    out: float = field(default=0.0, init=False)

    def update(self, dt: float) -> None:
        self.out = self.main + self.add - self.sub

    def reset(self) -> None:
        self.main = 0.0
        self.add = 0.0
        self.sub = 0.0
        self.out = 0.0


@dataclass(slots=True)
class PowerAmplifier:
    """Power amplifier 3/11/18 (seed 000 fig. 4), 11 (seed 001 fig. 2), 20/28 (seed 001 fig. 3).

    ``out = clamp(gain*inp, -limit, +limit)``; ``saturated = |gain*inp| > limit``.

    Parameters
    ----------
    gain : float
        Gain [output units per input unit], finite, != 0.
    limit : float
        Output limit [output units, e.g. V], > 0.

    Attributes
    ----------
    inp : float
        Input [units].
    out : float
        Output [output units].
    saturated : bool
        Output: True when the output is clamped.
    """

    gain: float
    limit: float
    inp: float = field(default=0.0, init=False)
    out: float = field(default=0.0, init=False)
    saturated: bool = field(default=False, init=False)

    def __post_init__(self) -> None:
        self.gain = nonzero("gain", self.gain)
        self.limit = positive("limit", self.limit)

    def update(self, dt: float) -> None:
        y = self.gain * self.inp
        limit = self.limit
        if y > limit:
            self.out = limit
            self.saturated = True
        elif y < -limit:
            self.out = -limit
            self.saturated = True
        else:
            self.out = y
            self.saturated = False

    def reset(self) -> None:
        self.inp = 0.0
        self.out = 0.0
        self.saturated = False


@dataclass(slots=True)
class Key:
    """Key (switch) 27/28, 33/34, 38/39 (seed 000 fig. 4), 15/16 (seed 001 fig. 2), 18/19, 26/27 (fig. 3).

    ``out = inp if closed else 0.0``.  In the correction module the lag key is closed by a sign
    discriminator output of -1 and the lead key by +1.

    Attributes
    ----------
    inp : float
        Input [units].
    closed : bool
        Input: switch state.
    out : float
        Output [units].
    """

    inp: float = field(default=0.0, init=False)
    closed: bool = field(default=False, init=False)
    out: float = field(default=0.0, init=False)

    def update(self, dt: float) -> None:
        self.out = self.inp if self.closed else 0.0

    def reset(self) -> None:
        self.inp = 0.0
        self.closed = False
        self.out = 0.0
