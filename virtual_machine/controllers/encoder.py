"""Incremental encoder: shaft angle -> integer count (seed 000 fig. 4, seed 001 figs. 2/3)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ._params import finite, integer_at_least, integer_in


@dataclass(slots=True)
class Encoder:
    """Incremental encoder IP1/IP2/IP3 (seed 000 fig. 4), encoders 6/12 (seed 001 fig. 2), 7/8 (fig. 3).

    ::

        position = floor((angle - angle0) * lines * quadrature / (2 pi))     count = position - previous

    Parameters
    ----------
    lines : int
        Lines per revolution, integer >= 1.
    quadrature : int
        Counts per line: 1, 2 or 4 (x4 quadrature decoding).
    angle0 : float
        Shaft angle [rad] at which ``position`` is 0 (the angle at construction).

    Attributes
    ----------
    angle : float
        Input: shaft angle [rad], continuous (not wrapped), any sign.
    position : int
        Output: counts since ``angle0``.
    count : int
        Output: counts this tick (signed).
    """

    lines: int
    quadrature: int = 4
    angle0: float = 0.0
    angle: float = field(default=0.0, init=False)
    position: int = field(default=0, init=False)
    count: int = field(default=0, init=False)
    _counts_per_rad: float = field(default=0.0, init=False, repr=False)

    def __post_init__(self) -> None:
        self.lines = integer_at_least("lines", self.lines, 1)
        self.quadrature = integer_in("quadrature", self.quadrature, (1, 2, 4))
        self.angle0 = finite("angle0", self.angle0)
        self._counts_per_rad = self.lines * self.quadrature / (2.0 * math.pi)
        self.reset()

    @property
    def counts_per_rev(self) -> int:
        """Counts per revolution, ``lines * quadrature``."""
        return self.lines * self.quadrature

    @property
    def fine_position(self) -> float:
        """The position with the fraction of the next count: what a converter integrating the evenly spaced
        edges of a turning shaft sees at the tick's end (no +-1 count jitter per tick)."""
        return (self.angle - self.angle0) * self._counts_per_rad

    def update(self, dt: float) -> None:
        p = math.floor((self.angle - self.angle0) * self._counts_per_rad)
        self.count = p - self.position
        self.position = p

    def reset(self) -> None:
        self.angle = self.angle0
        self.position = 0
        self.count = 0
