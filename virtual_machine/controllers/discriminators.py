"""Sign and phase discriminators of the correction modules (seed 000 fig. 4, seed 001 figs. 2/3).

Both compare two cumulative integer pulse positions in the same units: ``reference`` (the commanded
position, e.g. a divider's ``position``) and ``feedback`` (an encoder's ``position``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ._params import integer_at_least


@dataclass(slots=True)
class SignDiscriminator:
    """Sign discriminator 25/30/36 (seed 000 fig. 4), 13 (seed 001 fig. 2), 14/22 (seed 001 fig. 3).

    Sign convention of the seed: **lag -> negative, lead -> positive**.  With
    ``e = reference - feedback`` [counts]::

        out = -1  if e >  deadband      (feedback lags the reference)
        out = +1  if e < -deadband      (feedback leads the reference)
        out =  0  otherwise

    Parameters
    ----------
    deadband : int
        Error [counts] tolerated without a sign, integer >= 0.

    Attributes
    ----------
    reference, feedback : int
        Inputs: cumulative positions [counts].
    out : int
        Output: -1, 0 or +1.
    """

    deadband: int = 0
    reference: int = field(default=0, init=False)
    feedback: int = field(default=0, init=False)
    out: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        self.deadband = integer_at_least("deadband", self.deadband, 0)

    def update(self, dt: float) -> None:
        e = self.reference - self.feedback
        if e > self.deadband:
            self.out = -1
        elif e < -self.deadband:
            self.out = 1
        else:
            self.out = 0

    def reset(self) -> None:
        self.reference = 0
        self.feedback = 0
        self.out = 0


@dataclass(slots=True)
class PhaseDiscriminator:
    """Phase discriminator 26/31/37 (seed 000 fig. 4), 14 (seed 001 fig. 2), 15/23 (seed 001 fig. 3).

    ``out = |reference - feedback|`` [counts]: the magnitude of the error; its sign comes from the
    sign discriminator.

    Attributes
    ----------
    reference, feedback : int
        Inputs: cumulative positions [counts].
    out : int
        Output: absolute error [counts].
    """

    reference: int = field(default=0, init=False)
    feedback: int = field(default=0, init=False)
    out: int = field(default=0, init=False)

    def update(self, dt: float) -> None:
        self.out = abs(self.reference - self.feedback)

    def reset(self) -> None:
        self.reference = 0
        self.feedback = 0
        self.out = 0
