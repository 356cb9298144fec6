"""The rake face as the tool designer places it (docs/cutter.md): an end plane offset along the cutter axis, or a
stepped face normal to each tooth's direction. The edge is designed for it, so a new cutter on the ideal machine still
cuts the ideal gear: known answer, the same gear as the end-plane cutter's (its feed marks alone)."""

from __future__ import annotations

import functools
import math
from dataclasses import replace

import numpy as np
import pytest

from cutting.flank import base_tangent_deviation, flank_points
from cutting.gear import Gear
from cutting.skiving.edge import involute_edge, make_edge
from cutting.skiving.exact_sweep import SweptVolumes
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.tooling import CutterErrors, RakeFace, chain, inverse
from cutting.skiving.trajectory import ideal_passes
from metrology.measure import MeasureOptions, measure_gear

DEG = math.pi / 180

#: the default job's gear and cutter, one pass at a fine feed (feed marks of 0.6 um)
FINE = SkivingSetup(Gear(20, 1.0, 20 * DEG, 0.0, 4.0), Gear(17, 1.0, 20 * DEG, 20 * DEG, 10.0), 3000, 0.05, (2.25,))


@functools.cache
def measured(rake: RakeFace) -> dict:
    st = replace(FINE, rake=rake)
    return measure_gear(SweptVolumes(st.gear, make_edge(st, "conjugate"), ideal_passes(st)), st.gear, MeasureOptions())


def test_stepped_face_is_normal_to_the_tooth_direction():
    c = FINE.cutter
    st = replace(FINE, rake=RakeFace("stepped", 0.0))
    xi = math.sqrt(c.reference_radius**2 - c.base_radius**2) / c.base_radius
    # the tooth direction on the reference cylinder: the mean of both flanks' helix tangents at tooth 0
    tangent = sum(flank_points(c, s, xi, 1e-3, 0) - flank_points(c, s, xi, 0.0, 0) for s in ("left", "right"))
    normal = st.rake_frame[:, 2]
    tangent /= np.linalg.norm(tangent)
    assert abs(abs(float(normal @ tangent)) - 1.0) < 1e-6


@pytest.mark.parametrize("rake", [RakeFace("plane", 3.0), RakeFace("stepped", 0.0), RakeFace("stepped", 3.0)])
def test_involute_edge_lies_on_the_cutter_flanks_in_the_rake_face(rake: RakeFace):
    st = replace(FINE, rake=rake)
    edge = involute_edge(st)
    c = st.cutter
    above = edge.radii >= c.base_radius * 1.001
    for side in ("left", "right"):
        th = edge.theta[side][above]
        p = np.stack([edge.radii[above] * np.cos(th), edge.radii[above] * np.sin(th), 0 * th], -1)
        q = p @ st.rake_frame[:, :3].T + st.rake_frame[:, 3]  # into the cutter frame
        assert np.abs(base_tangent_deviation(c, q, side)).max() < 1e-9


@pytest.mark.parametrize("rake", [RakeFace("plane", 3.0), RakeFace("stepped", 0.0), RakeFace("stepped", 3.0)])
def test_a_new_cutter_with_this_rake_face_cuts_the_ideal_gear(rake: RakeFace):
    base, other = measured(RakeFace()), measured(rake)
    for side in ("left", "right"):
        assert abs(other["profile"][side]["f_Halpha_mean"] - base["profile"][side]["f_Halpha_mean"]) < 1.0
        assert abs(other["helix"][side]["f_Hbeta_mean"] - base["helix"][side]["f_Hbeta_mean"]) < 1.0
        assert abs(other["pitch"][side]["f_p"] - base["pitch"][side]["f_p"]) < 1.0
        assert abs(other["profile"][side]["f_falpha"] - base["profile"][side]["f_falpha"]) < 1.0
        assert other["profile"][side]["F_alpha"] < 1.5  # the ideal gear, not merely like the other


def test_frames_compose_and_invert():
    st = replace(FINE, rake=RakeFace("stepped", 2.0), cutter_errors=CutterErrors(0.01, 0.4, 0.02, 1.1))
    f = st.tooth_frames[3]
    assert np.allclose(chain(f, inverse(f)), np.hstack([np.eye(3), np.zeros((3, 1))]), atol=1e-15)
    # the runout's offset is half the TIR, where the phase says
    mount = chain(st.tooth_frames[0], inverse(chain(np.hstack([np.eye(3), np.zeros((3, 1))]), st.rake_frame)))
    assert np.hypot(mount[0, 3], mount[1, 3]) == pytest.approx(0.005, abs=1e-12)
    assert math.atan2(mount[1, 3], mount[0, 3]) == pytest.approx(0.4, abs=1e-12)
