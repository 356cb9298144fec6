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


def test_a_reground_tool_cuts_the_profile_slope_its_relief_predicts():
    """A regrind of d takes d tan(alpha_a) / mn off the teeth's profile shift: the face cuts a thinner section of the
    relieved teeth, the shop sets it to the same tooth thickness (a smaller centre distance), and the edge keeps the
    new tool's departure from its involute section at each roll length L0 (docs/cutter.md, "Regrind"). The reground
    cutter would need its own envelope's departure; the difference, mapped onto the gear through the generating
    (-cos(beta_b0) along the normal), predicts the profile error the regrind makes: f_Halpha within 10 %."""
    from cutting.skiving.cutter_profile import roll_map
    from cutting.skiving.kinematics import reground

    new, worn = FINE, reground(FINE, 1.5)
    assert worn.cutter.x == pytest.approx(-1.5 * math.tan(6 * DEG) / FINE.cutter.mn)
    assert worn.generated_root_diameter == pytest.approx(new.generated_root_diameter, abs=1e-9)
    cut = {}
    for name, st in (("new", new), ("worn", worn)):
        sweep = SweptVolumes(st.gear, make_edge(st, "conjugate"), ideal_passes(st))
        cut[name] = measure_gear(sweep, st.gear, MeasureOptions())
    fresh = replace(worn, rake=replace(worn.rake, regrind=0.0))  # the reground cutter, designed afresh
    edge, ideal = make_edge(worn, "conjugate"), make_edge(fresh, "conjugate")
    c = worn.cutter
    rb, cos_bb0 = c.base_radius, math.cos(math.asin(math.sin(c.helix_angle) * math.cos(c.alpha_n)))
    lo, hi = cut["worn"]["evaluation"]["profile_roll_mm"]
    for side, sign in (("left", 1.0), ("right", -1.0)):
        more_tool = sign * (edge.theta[side] - ideal.theta[side]) * rb
        l2, l0 = roll_map(fresh, ideal, side)
        roll = np.linspace(lo, hi, 200)
        at = np.interp(np.interp(roll, l2, l0), np.sqrt(np.maximum(edge.radii**2 - rb**2, 0.0)), more_tool)
        line = np.polyfit(roll, -at * cos_bb0 * 1e3, 1)
        change = cut["worn"]["profile"][side]["f_Halpha_mean"] - cut["new"]["profile"][side]["f_Halpha_mean"]
        assert change == pytest.approx(line[0] * (hi - lo), rel=0.10)
        assert abs(change) > 2.0  # the shops' known problem: a regrind tilts the profile
        assert abs(cut["worn"]["pitch"][side]["f_p"] - cut["new"]["pitch"][side]["f_p"]) < 0.3
