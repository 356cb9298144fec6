"""Pulse-train blocks: reference generator, frequency divider, summator (seed 000 fig. 4, seed 001).

A pulse train is carried per servo tick as a signed ``int``: the number of pulses during the tick
(negative = reverse-direction pulses).  Frequencies up to 1e9 Hz are handled by integer arithmetic,
never by a loop per pulse.  ``position`` is the cumulative count since construction or ``reset()``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ._params import integer_at_least, integer_in, non_negative


@dataclass(slots=True)
class ReferenceGenerator:
    """Reference pulse generator 14 (seed 000 fig. 4), generator 5 (seed 001 fig. 3).

    ``phase += frequency*dt; out = floor(phase); phase -= out``: the fraction of a pulse is carried
    to the next tick, so ``position = floor(frequency * elapsed time)`` (to float rounding of ``dt``).

    Parameters
    ----------
    frequency : float
        Pulse frequency [Hz], finite, >= 0; may be reassigned at run time.

    Attributes
    ----------
    out : int
        Output: pulses this tick.
    position : int
        Output: total pulses.
    """

    frequency: float
    out: int = field(default=0, init=False)
    position: int = field(default=0, init=False)
    _phase: float = field(default=0.0, init=False, repr=False)

    def __post_init__(self) -> None:
        self.frequency = non_negative("frequency", self.frequency)

    def update(self, dt: float) -> None:
        phase = self._phase + self.frequency * dt
        n = math.floor(phase)
        self._phase = phase - n
        self.out = n
        self.position += n

    def reset(self) -> None:
        self.out = 0
        self.position = 0
        self._phase = 0.0


class FrequencyDivider:
    """Frequency divider = pulse counter + coefficient block: one output pulse per ``k`` input pulses.

    Dividers 6/7/21/22 (seed 000 fig. 4), counter 7 + block 8 (seed 001 fig. 2), counters 9/10
    (seed 001 fig. 3).  The counter holds an integer remainder ``r`` in ``[0, k)``::

        out = (r + inp) // k        r = (r + inp) mod k        (floor division)

    which for constant ``k`` equals ``floor((s + inp)/k) - floor(s/k)`` with ``s`` the total input:
    a pulse is emitted whenever the input position crosses a multiple of ``k``, in either direction,
    so counting back down undoes the output exactly.  Quantisation is real: the output is an integer.

    Parameters
    ----------
    k : int
        Division coefficient, integer >= 1.  May be reassigned at run time (checked); the counter keeps
        its content, and content >= the new ``k`` overflows into the next tick's output.

    Attributes
    ----------
    inp : int
        Input: pulses this tick (signed).
    out : int
        Output: pulses this tick (signed).
    position : int
        Output: total output pulses.
    remainder : int
        State: counter content, in ``[0, k)`` after each update.
    """

    __slots__ = ("_k", "inp", "out", "position", "remainder")

    def __init__(self, k: int) -> None:
        self.k = k
        self.reset()

    @property
    def fine_position(self) -> float:
        """Output position with the counted fraction of the next pulse, ``position + remainder / k``.

        The pulses of a real train are spread evenly over a tick; a converter that integrates them sees this
        position at the tick's end, without the +-1 pulse jitter of counting whole pulses per tick."""
        return self.position + self.remainder / self._k

    @property
    def k(self) -> int:
        """Division coefficient (integer >= 1)."""
        return self._k

    @k.setter
    def k(self, value: int) -> None:
        self._k = integer_at_least("k", value, 1)

    def update(self, dt: float) -> None:
        n, self.remainder = divmod(self.remainder + self.inp, self._k)
        self.out = n
        self.position += n

    def reset(self) -> None:
        self.inp = 0
        self.out = 0
        self.position = 0
        self.remainder = 0

    def __repr__(self) -> str:
        return f"FrequencyDivider(k={self._k}, remainder={self.remainder}, position={self.position})"


@dataclass(slots=True)
class Summator:
    """Summator 9 (seed 000 fig. 4): adds two signed pulse trains, ``out = a + sign*b``.

    Coincident pulses are both counted (no pulse is lost).  The same equation holds if ``a`` and ``b``
    carry analog values.

    Parameters
    ----------
    sign : int
        Sign of input ``b``: +1 or -1.

    Attributes
    ----------
    a, b : int
        Inputs: pulses this tick (signed).
    out : int
        Output: pulses this tick (signed).
    """

    sign: int = 1
    a: int = field(default=0, init=False)
    b: int = field(default=0, init=False)
    out: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        self.sign = integer_in("sign", self.sign, (1, -1))

    def update(self, dt: float) -> None:
        self.out = self.a + self.sign * self.b

    def reset(self) -> None:
        self.a = 0
        self.b = 0
        self.out = 0


class RateMultiplier:
    """Coefficient block with two integers (a rate multiplier): the counter adds ``n`` per input pulse and
    emits one pulse per ``k`` counted, so ``out = in * n / k`` exactly on average (seed 001 fig. 2, counter 7 +
    block 8; the master-slave links of seed 000). A plain divider is the case ``n = 1``.

    ::

        out = (r + n * inp) // k        r = (r + n * inp) mod k

    Parameters
    ----------
    n : int
        Pulses added per input pulse, integer >= 1.
    k : int
        Pulses per output pulse, integer >= 1.

    Attributes
    ----------
    inp : int
        Input: pulses this tick (signed).
    out : int
        Output: pulses this tick (signed).
    position : int
        Output: total output pulses.
    """

    __slots__ = ("inp", "k", "n", "out", "position", "remainder")

    def __init__(self, n: int, k: int) -> None:
        self.n = integer_at_least("n", n, 1)
        self.k = integer_at_least("k", k, 1)
        self.reset()

    @property
    def fine_position(self) -> float:
        """Output position with the counted fraction of the next pulse (see FrequencyDivider.fine_position)."""
        return self.position + self.remainder / self.k

    def update(self, dt: float) -> None:
        m, self.remainder = divmod(self.remainder + self.n * self.inp, self.k)
        self.out = m
        self.position += m

    def reset(self) -> None:
        self.inp = 0
        self.out = 0
        self.position = 0
        self.remainder = 0
