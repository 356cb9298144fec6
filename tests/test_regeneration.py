"""Regenerative chatter's known answer: planing with overlapping cuts on one mode normal to the cut, run in MuJoCo
(virtual_machine/runtime/planing.py), against Tlusty's limit and the stability lobes (cutting/regeneration.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cutting.regeneration import lobes, tlusty_limit
from machine_models.loop import LoopMode, frequency_response
from virtual_machine.runtime.planing import limiting_width, plane

# one mode normal to the cut: 200 Hz, zeta 0.03, 20 N/um; a thrust coefficient of 2000 N/mm^2 on a 50 um chip
MODE = LoopMode("tool", (0.0, 0.0, 1.0), 200.0, 0.03, 2.0e7)
K = 2.0e9  # N/m^2
CHIP = 50e-6
N = np.array([0.0, 0.0, 1.0])
#: Tlusty: Re[G]_min = -1 / (4 k zeta (1 + zeta)), so b_lim = 2 k zeta (1 + zeta) / K = 0.618 mm
B_LIM = 2 * 2.0e7 * 0.03 * 1.03 / K


def g(omega: np.ndarray) -> np.ndarray:
    return frequency_response((MODE,), "tool", omega, N)


OMEGA = 2 * math.pi * np.linspace(150.0, 260.0, 4001)
LOBES = lobes(g, -K * np.outer(N, N), OMEGA, count=8)  # D per unit width: the thrust's, along n


def test_the_lobes_floor_is_tlustys_limit() -> None:
    assert tlusty_limit(g(OMEGA)[:, 2, 2], K) == pytest.approx(B_LIM, rel=1e-3)
    assert float(LOBES.limit.min()) == pytest.approx(B_LIM, rel=1e-3)
    # each lobe's floor is that limit, at the chatter frequency of Re[G]'s minimum, omega_n sqrt(1 + 2 zeta)
    k3 = LOBES.limit[3]
    i = int(np.argmin(k3))
    assert LOBES.omega[i] / (2 * math.pi) == pytest.approx(200.0 * math.sqrt(1.06), rel=2e-3)


def _delays() -> dict[str, float]:
    """Three speeds: the floor of lobe 3, a stability pocket between lobes 3 and 4, and a point on lobe 5's flank."""
    d3 = float(LOBES.delay[3][np.argmin(LOBES.limit[3])])
    d4 = float(LOBES.delay[4][np.argmin(LOBES.limit[4])])
    d5 = float(LOBES.delay[5][np.argmin(LOBES.limit[5])])
    return {"floor": d3, "pocket": 0.5 * (d3 + d4), "flank": d5 * 1.02}


@pytest.mark.parametrize("where", ["floor", "pocket", "flank"])
def test_time_domain_planing_turns_unstable_where_the_lobes_say(where) -> None:
    delay = _delays()[where]
    predicted, freq = LOBES.at(delay)
    assert math.isfinite(predicted) and predicted >= B_LIM * 0.999
    measured = limiting_width(MODE, K, CHIP, delay, 0.5 * predicted, 2.0 * predicted)
    assert measured == pytest.approx(predicted, rel=0.10), (where, measured * 1e3, predicted * 1e3)
    # growing above, decaying below; the vibration at the lobe's chatter frequency
    above = plane(MODE, K, 1.2 * predicted, CHIP, delay)
    below = plane(MODE, K, 0.8 * predicted, CHIP, delay)
    assert above.growth() > 1.0 > below.growth()
    assert above.frequency() == pytest.approx(freq, rel=0.03)
