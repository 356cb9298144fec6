"""Compile every numba kernel a run needs, once, by cutting and probing a tiny gear.

The kernels (cutting/skiving/exact_kernels.py, exact_solve.py, dexel_kernels.py) are cached beside their modules
(``cache=True``): the editable install runs this module (build_backend/skive_build.py), so the first ``skive run``
after the install loads them instead of compiling them (about a minute on two cores). Run it by hand after changing a
kernel: ``python -m cutting.warmup``.
"""

from __future__ import annotations

import math
import time

import numpy as np

from cutting.forces import engagement_sums
from cutting.form_milling.sweep_kernels import interp_guide, milled_margins
from cutting.gear import Gear
from cutting.skiving.chip_of_the_moment import COLUMNS, machine_tick
from cutting.skiving.dexel_cut import cut_dexel
from cutting.skiving.dexel_lines import DexelSpacing
from cutting.skiving.edge import make_edge
from cutting.skiving.exact_sweep import SweptVolumes
from cutting.skiving.ideal_moment import IdealMoment
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.sampled_motion import ideal_samples
from cutting.skiving.sweep import place_few
from cutting.skiving.trajectory import ideal_passes

DEG = math.pi / 180


def warm() -> float:
    """Cut a tiny gear with the dexel workpiece (ideal and sampled motion) and probe its exact swept surface;
    returns the seconds it took."""
    t0 = time.perf_counter()
    setup = SkivingSetup(Gear(16, 1.0, 20 * DEG, 0.0, 1.0), Gear(11, 1.0, 20 * DEG, 20 * DEG, 5.0), 2000, 0.4, (2.25,))
    edge = make_edge(setup, "conjugate")
    motions = ideal_passes(setup)
    spacing = DexelSpacing.for_gear(setup.gear, setup.axial_feed, 0.3, 0.5)
    for m in (motions, [ideal_samples(motions[0], 2000.0)]):
        cut_dexel(setup.gear, edge, m, spacing, 0.01)
    sv = SweptVolumes(setup.gear, edge, motions)
    angle = np.linspace(0.0, 2 * math.pi, 8, endpoint=False)
    r = setup.gear.reference_radius
    points = np.column_stack([r * np.cos(angle), r * np.sin(angle), np.zeros(8)])
    # lines a pitch long cross a flank: the measurement's item solve (exact_margins, exact_roots) compiles too
    sv.probe(points, np.column_stack([-np.sin(angle), np.cos(angle), np.zeros(8)]), 2.0)
    # the co-simulation's load of a servo tick (cutting/skiving/chip_of_the_moment.py): two teeth of a 4-point edge
    frames = np.zeros((2, 3, 4))
    frames[:, :, :3] = np.eye(3)
    edge_pts = np.array([[9.0, -1.0, 0.0], [10.0, -0.5, 0.0], [10.0, 0.5, 0.0], [9.0, 1.0, 0.0]])
    body = np.tile([-1.0, 0.0, 0.0], (3, 1))
    chip = np.array([2000.0, 0.25, 1e-3, 1.6, 3e-3, 10.0, 17.0, 0.5, -0.5])
    state = np.array([0.1, 0.0, 0.0, 0.0, 0.0, 0.7, 0.0, -0.01, 20.0, np.nan, 0.5, 0.3, 9.0, 30.0,
                      0.3, math.pi, 0.0])  # fmt: skip
    machine_tick(
        np.array([0.1, 0.2, 0.0, 0.02]), np.array([200.0, -180.0, -0.005, 0.0]), np.arange(4), np.arange(4),
        np.zeros(6), state, np.zeros((4, 8)), 0, np.zeros((1, 8)), 0, frames, np.eye(3, 4), edge_pts,
        np.array([0.0, 0.0, 1.0]), body, np.array([17.0, 0.0, 5.0]), chip, np.empty((4, COLUMNS)),
        np.empty(4, dtype=np.int64),
    )  # fmt: skip
    # the same chip on the ideal machine, called from Python (the pre-run load estimate and the stability lobes:
    # virtual_machine/reach/skiving_load.py, processes/skiving/stability.py), first pass and a later one
    a = setup.final_centre_distance
    for previous in (None, a + 0.5 * (-1 if setup.gear.internal else 1)):
        moment = IdealMoment(setup, a, previous)
        moment.load(0.0, chip, np.empty((1, COLUMNS)))
        moment.chips(0.0, 0.5, -0.5)
    # and an engagement's load from its chip (the edge at 3 x 5 instants, 4 points)
    t = np.linspace(0.0, 1e-3, 5)
    engagement_sums(place_few(np.zeros((4, 3)), np.zeros((15, 3, 3)), np.zeros((15, 3))), np.ones((5, 4)), t, 1e-6)
    _form_mill()
    return time.perf_counter() - t0


def _form_mill() -> None:
    """The form mill's swept-gear margins (cutting/form_milling/sweep_kernels.py, 5 s to compile): one pass of
    three poses across one of two tooth spaces, a mill profile of three points, both of the kernel's modes."""
    u = np.array([0.0, 1.0, 2.0])
    guide, scale = interp_guide(u)
    centre = np.zeros((3, 3))
    centre[:, 2] = [-1.0, 0.0, 1.0]
    axis = np.tile([1.0, 0.0, 0.0], (3, 1))
    one = np.array([0, 3], np.int64), np.array([[1, 1]], np.int64), np.array([0, 1, 1], np.int64)
    packed = (centre, axis, *one, np.array([0], np.int64), u, np.ones(3), guide, scale, 1.0)
    for sign_only in (False, True):
        milled_margins(np.array([[10.0, 0.0, 0.0], [0.5, 0.2, 0.0]]), sign_only, 2, 0.0, (-100.0, 100.0), packed)


if __name__ == "__main__":
    print(f"skive: the numba kernels are compiled and cached ({warm():.0f} s)")
