"""The rake face as the tool designer places it (docs/cutter.md): an end plane offset along the cutter axis, or a
stepped face normal to each tooth's direction, either inclined by a rake angle. The edge is designed for it, so a new
cutter on the ideal machine still cuts the ideal gear: known answer, the same gear as the end-plane cutter's (its feed
marks alone)."""

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
UM = 1e3

#: the default job's gear and cutter, one pass at a fine feed (feed marks of 0.6 um)
FINE = SkivingSetup(Gear(20, 1.0, 20 * DEG, 0.0, 4.0), Gear(17, 1.0, 20 * DEG, 20 * DEG, 10.0), 3000, 0.05, (2.25,))


def measured(rake: RakeFace) -> dict:
    return measured_setup(replace(FINE, rake=rake))


def test_stepped_face_is_normal_to_the_tooth_direction():
    c = FINE.cutter
    st = replace(FINE, rake=RakeFace("stepped", 0.0))
    xi = math.sqrt(c.reference_radius**2 - c.base_radius**2) / c.base_radius
    # the tooth direction on the reference cylinder: the mean of both flanks' helix tangents at tooth 0
    tangent = sum(flank_points(c, s, xi, 1e-3, 0) - flank_points(c, s, xi, 0.0, 0) for s in ("left", "right"))
    normal = st.rake_frame[:, 2]
    tangent /= np.linalg.norm(tangent)
    assert abs(abs(float(normal @ tangent)) - 1.0) < 1e-6


#: the issue's tool: rake angle 5 deg, face 3 mm off the common perpendicular, 6 deg clearance
RAKE5 = RakeFace("plane", 3.0, 6 * DEG, 0.0, 5 * DEG)
FACES = [RakeFace("plane", 3.0), RakeFace("stepped", 0.0), RakeFace("stepped", 3.0), RAKE5]


def test_rake_angle_inclines_the_face_towards_the_body():
    """The face passes through the reference circle at the offset and falls away behind the tip edge by tan(gamma)
    per mm inwards in its normal plane, towards the body (-z of an external job's cutter frame; a stepped face's normal
    plane leans by beta0); the tip's middle, cut along the face's normal as it is without the rake angle, out of the
    body, works at the rake angle (the end plane: and at the tip clearance; the definitions, ISO 3002-1:
    gamma_n + alpha_n + beta_n = 90 deg)."""
    from cutting.skiving.tooling import rotation
    from cutting.skiving.working_angles import Relief, angles_of, edge_frames

    for kind, lean in (("plane", 1.0), ("stepped", math.cos(20 * DEG))):
        st = replace(FINE, rake=replace(RAKE5, kind=kind))
        r0, ra0 = st.cutter.reference_radius, st.cutter_tip_diameter / 2
        assert st.body_side == -1.0
        assert st.face_height(r0) == pytest.approx(3.0, abs=1e-12)
        assert st.face_height(r0 - 1.0) == pytest.approx(3.0 - math.tan(5 * DEG) * lean, abs=2e-4)
        q = st.rake_frame
        assert np.hypot(*(q[:2, :3] @ [st.face_radius(ra0), 0.0, 0.0] + q[:2, 3])) == pytest.approx(ra0, abs=1e-12)
        edge = make_edge(st, "conjugate")
        frames = edge_frames(st, edge, Relief.of(st))
        mid = int(np.flatnonzero(frames.part == "tip").mean())
        # in the rake frame: the face's normal before the rake angle turned it, away from the body
        v = rotation((0.0, 1.0, 0.0), -5 * DEG).T @ np.array([0.0, 0.0, 1.0])
        rake, clearance, wedge, _, _ = angles_of(frames.tangent[mid], frames.rake[mid], frames.flank[mid], v)
        assert math.degrees(rake) == pytest.approx(5.0, abs=0.01)
        if kind == "plane":  # the tip cone's relief runs along the axis: the stepped face's normal plane leans on it
            assert math.degrees(clearance) == pytest.approx(6.0, abs=0.01)
        assert math.degrees(rake + clearance + wedge) == pytest.approx(90.0, abs=1e-9)
        # and the plane face without a rake angle at 0 deg
        flat = replace(st, rake=replace(st.rake, rake_angle=0.0))
        f0 = edge_frames(flat, make_edge(flat, "conjugate"), Relief.of(flat))
        v0 = np.array([0.0, 0.0, 1.0])  # the face's own normal
        assert math.degrees(angles_of(f0.tangent[mid], f0.rake[mid], f0.flank[mid], v0)[0]) == pytest.approx(
            0.0, abs=0.01
        )


@pytest.mark.parametrize("rake", FACES)
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


@pytest.mark.parametrize("rake", FACES)
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


def regrind_prediction(worn: SkivingSetup) -> dict[str, float]:
    """The first-order profile slope a regrind makes (docs/cutter.md, "Regrind"): the reground edge departs from the
    reground cutter's own conjugate edge (designed afresh) by m(L0) along the base tangent; the gear's flank moves by
    -k m where the envelope says each edge radius generates it (k the transfer of
    :func:`cutting.skiving.cutter_profile.generating_map`, cos(beta_b0) on the end plane). Where either edge keeps its
    involute section (the corner below the generating zone) the first order does not hold: the envelope of the
    neighbouring radii generates the gear there; those gear rolls (the last few percent near the gear's tip) are
    left out of the fitted line. Returns the predicted f_Halpha per flank [um]."""
    from cutting.skiving.cutter_profile import generating_map

    new, fresh = worn.new_tool(), replace(worn, rake=replace(worn.rake, regrind=0.0))
    edge, ideal = make_edge(worn, "conjugate"), make_edge(fresh, "conjugate")
    new_edge, new_section, fresh_section = make_edge(new, "conjugate"), involute_edge(new), involute_edge(fresh)
    rb = worn.cutter.base_radius

    def roll(radii: np.ndarray) -> np.ndarray:
        return np.sqrt(np.maximum(radii**2 - rb**2, 0.0))

    lo, hi = measured_setup(worn, MID)["evaluation"]["profile_roll_mm"]
    predicted = {}
    for side, sign in (("left", 1.0), ("right", -1.0)):
        more_tool = sign * (edge.theta[side] - ideal.theta[side]) * rb
        kept = np.concatenate(
            [
                roll(new_edge.radii)[new_edge.theta[side] == new_section.theta[side]],
                roll(ideal.radii)[ideal.theta[side] == fresh_section.theta[side]],
            ]
        )
        l2, l0, k = generating_map(fresh, ideal, side)
        gear_roll = np.linspace(lo, hi, 200)
        at = np.interp(gear_roll, l2, l0)
        ok = at > kept.max() + 0.05 if len(kept) else np.ones(len(at), bool)
        gear = -np.interp(at, roll(edge.radii), more_tool) * np.interp(gear_roll, l2, k) * UM
        predicted[side] = np.polyfit(gear_roll[ok], gear[ok], 1)[0] * (hi - lo)
    return predicted


#: the regrind test reads the mid section's profile slope and pitch alone: its reground cuts have the profile measured
#: in that section alone (the same figures, a quarter less probing); F_alpha is the worst of three sections
MID = MeasureOptions(sections=(0.5,))


@functools.cache
def measured_setup(st: SkivingSetup, opt: MeasureOptions | None = None) -> dict:
    gear = st.gear
    return measure_gear(SweptVolumes(gear, make_edge(st, "conjugate"), ideal_passes(st)), gear, opt or MeasureOptions())


#: a cutter with room for 2 mm of regrind (x0 = 0.25: 0.21 of it goes)
ROOMY = replace(FINE, cutter=replace(FINE.cutter, profile_shift=0.25))


@pytest.mark.parametrize(
    "new, regrind",
    [(FINE, 1.5), (replace(ROOMY, rake=replace(RAKE5, offset=0.0)), 2.0), (replace(ROOMY, rake=RAKE5), 2.0)],
    ids=["plane", "rake5", "rake5-offset3"],  # the last: the tool, its face 3 mm off the common perpendicular
)
def test_a_reground_tool_cuts_the_profile_slope_its_relief_predicts(new: SkivingSetup, regrind: float):
    """A regrind of d takes d' tan(alpha_a) / mn off the teeth's profile shift (d' = d / cos(gamma) along the axis): the
    face cuts a thinner section of the relieved teeth, the shop sets it to the same tooth thickness (a smaller centre
    distance), and the edge keeps the new tool's departure from its involute section at each roll length L0
    (docs/cutter.md, "Regrind"); the gear's profile slope departs from the ideal gear's (the one the reground cutter,
    designed afresh, cuts at the same setting) as :func:`regrind_prediction` says, within 10 %. The new tool's own gear
    is not the reference: near its corner a new cutter with x0 = 0.25 on an offset face leaves 1.3 um at the start of
    the evaluation range, which the regrind does not make."""
    from cutting.skiving.kinematics import reground

    worn = reground(new, regrind)
    fresh = replace(worn, rake=replace(worn.rake, regrind=0.0))
    depth = regrind / math.cos(new.rake.rake_angle)
    assert worn.cutter.x == pytest.approx(new.cutter.x - depth * math.tan(6 * DEG) / FINE.cutter.mn)
    assert worn.generated_root_diameter == pytest.approx(new.generated_root_diameter, abs=1e-9)
    predicted = regrind_prediction(worn)
    before = measured_setup(new) if new == FINE else measured_setup(new, MID)  # FINE's: the test above measured it
    after, ideal = measured_setup(worn, MID), measured_setup(fresh, MID)
    for side in ("left", "right"):
        change = after["profile"][side]["f_Halpha_mean"] - ideal["profile"][side]["f_Halpha_mean"]
        assert change == pytest.approx(predicted[side], rel=0.10)
        assert abs(change) > 2.0  # the shops' known problem: a regrind tilts the profile
        assert abs(after["pitch"][side]["f_p"] - before["pitch"][side]["f_p"]) < 0.3
