"""The compiled margin of the form-milled gear's exact swept surface (cutting.form_milling.sweep_kernels) against
its numpy reference (MilledGear._margin_numpy): the same value to 1e-12 mm at points near the flanks and across
the spaces, for a disc mill on a spur and on a helical gear, a finger mill in an internal ring, and a pass with
noisy centres as a machine's record has them; with sign_only too."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cutting.flank import SIDES, flank_normals, flank_points
from cutting.form_milling.finger import finger_passes, fit_finger_mill
from cutting.form_milling.helical import envelope_mill, helical_pass
from cutting.form_milling.sweep import MilledGear, MillPassPoses
from cutting.gear import Gear
from metrology.measure import MeasureOptions, profile_range

SPUR = Gear(teeth=20, normal_module=2.0, face_width=10.0)
HELICAL = Gear(teeth=20, normal_module=2.0, helix_angle=math.radians(20.0), face_width=10.0)
RING = Gear(teeth=60, normal_module=2.0, face_width=20.0, internal=True)


def disc_passes(gear: Gear, noise: float = 0.0) -> list[MillPassPoses]:
    """Two set-over disc mill passes (path points 0.1 mm either side of the symmetry line) of spaces -1, 0, 1; the
    centres moved by gaussian ``noise`` [mm] (a recorded path)."""
    mill = envelope_mill(gear, 25.0)
    z = np.arange(-21.0, 21.0 + 1e-9, 0.05)
    rng = np.random.default_rng(7)
    out = []
    for k in (-1, 0, 1):
        for x in (-0.1, 0.1):
            p = helical_pass(gear, mill, k % gear.teeth, z, x)
            centre = p.centre + noise * rng.standard_normal(p.centre.shape)
            out.append(MillPassPoses(p.space, p.side, p.t, centre, p.axis))
    return out


def cut_of(case: str) -> MilledGear:
    """The case's milled gear (built when its test runs, not at collection)."""
    if case == "ring":
        mill = fit_finger_mill(RING, 0.2)
        return MilledGear(RING, mill, finger_passes(RING, mill, 0.2, spaces=[0, 1]))
    gear = HELICAL if case == "helical" else SPUR
    return MilledGear(gear, envelope_mill(gear, 25.0), disc_passes(gear, 1e-4 if case == "recorded" else 0.0))


def points(gear: Gear, rng: np.random.Generator, n: int = 600) -> np.ndarray:
    """Points within 0.05 mm of the flanks of teeth 0, 1 and 2 (over the profile and the face), and points
    anywhere in spaces -1..1 between the root and the tip circle."""
    lo, hi = profile_range(gear, MeasureOptions())
    out = []
    for side in SIDES:
        for tooth in (0, 1, 2):
            xi = rng.uniform(min(lo, hi), max(lo, hi), n // 6) / gear.base_radius
            z = rng.uniform(-0.6, 0.6, n // 6) * gear.face_width
            p = flank_points(gear, side, xi, z, tooth).reshape(-1, 3)
            d = flank_normals(gear, side, xi, z, tooth).reshape(-1, 3)
            out.append(p + rng.uniform(-0.05, 0.05, (len(p), 1)) * d)
    r = rng.uniform(min(gear.root_radius, gear.tip_radius), max(gear.root_radius, gear.tip_radius), n)
    a = rng.uniform(-1.0, 2.0, n) * 2 * math.pi / gear.teeth
    out.append(np.column_stack([r * np.cos(a), r * np.sin(a), rng.uniform(-0.6, 0.6, n) * gear.face_width]))
    return np.concatenate(out)


@pytest.mark.parametrize("case", ["spur", "helical", "recorded", "ring"])
def test_the_kernel_margin_is_the_numpy_margin(case):
    cut = cut_of(case)
    q = points(cut.gear, np.random.default_rng(3))
    for sign_only in (False, True):
        got, want = cut.margin(q, sign_only), cut._margin_numpy(q, sign_only)
        assert np.abs(got - want).max() < 1e-12, (sign_only, np.abs(got - want).max())
    margin = cut.margin(q)
    assert (margin < 0).any() and ((margin > 0) & (margin < 0.05)).any()  # the points straddle the cut surface
    assert np.array_equal(cut.margin(q, True) < 0, margin < 0)  # sign_only keeps the sign
    assert cut.margin(q[:0]).shape == (0,)
