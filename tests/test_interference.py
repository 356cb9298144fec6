"""The relieved tooth behind the edge held against the finished gear over the whole mesh
(cutting/skiving/interference.py): the relief keeps it off by the side clearance; an unrelieved cutter, or a ring
gear's long cutter, is refused with the place and the depth."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest
from checks import JOBS

from cutting.errors import InputError
from cutting.skiving.edge import make_edge
from cutting.skiving.interference import body_interference, check_body_interference
from cutting.skiving.working_angles import Relief, check_working_clearance
from virtual_machine import load_job

DEG = math.pi / 180


def setup_of(name: str, clearance_deg: float | None = None):
    st = load_job(JOBS / f"{name}.toml").skiving
    if clearance_deg is not None:
        st = replace(st, rake=replace(st.rake, clearance_angle=clearance_deg * DEG))
    return st, make_edge(st, "conjugate")


@pytest.mark.parametrize("name", ["default", "spur_external", "helical_internal"])
def test_the_relief_keeps_the_tooth_off_the_finished_teeth_by_the_side_clearance(name: str):
    """Known answer: the closest the relieved flank comes to the finished flank is just behind the edge, where it
    has receded delta tan(alpha_s) (alpha_s the side clearance, 2.06 deg at 6 deg of tip clearance): at the first
    sampled depth, 10 um, 0.36 um (within 15 %: the working clearance at the contacts is not the side clearance)."""
    st, edge = setup_of(name)
    p = body_interference(st, edge)
    expected = 0.01 * math.tan(Relief.of(st).side_clearance)
    assert p["depth_mm"] == pytest.approx(0.01)
    assert -p["body_intrusion_max_mm"] == pytest.approx(expected, rel=0.15)
    assert check_body_interference(st, edge) == p


def test_an_unrelieved_cutter_would_cut_the_flank_with_its_body():
    st, edge = setup_of("default", 0.0)
    with pytest.raises(InputError) as info:
        check_body_interference(st, edge)
    text = str(info.value)
    assert "cutter.clearance_angle" in text and "enters the finished teeth by 0.8" in text, text
    assert "behind the left edge" in text and "raise cutter.clearance_angle" in text


def test_a_ring_gears_long_cutter_meets_its_teeth_deep_behind_the_face():
    """helical_internal's cutter made 40 mm wide with 4 deg of tip clearance: where the edge generates the flank the
    working clearance is positive (0.38 deg at least: the rubbing check passes), but 40 mm behind the face the
    cutter's teeth, crossed with the ring's axis at 20 deg, meet the ring's teeth in the mesh (0.43 mm): refused
    with the depth and the place. 20 mm wide (the job's) it clears them."""
    st, _ = setup_of("helical_internal", 4.0)
    st = replace(st, cutter=replace(st.cutter, face_width=40.0))
    edge = make_edge(st, "conjugate")
    check_working_clearance(st, edge)
    with pytest.raises(InputError) as info:
        check_body_interference(st, edge)
    text = str(info.value)
    assert "40.00 mm behind the right edge" in text and "fewer cutter teeth" in text, text
    assert body_interference(st, edge)["body_intrusion_max_mm"] == pytest.approx(0.43, abs=0.02)


def test_a_cutter_profile_deviation_moves_the_body_with_the_edge():
    """A profile deviation of more tool material (5 um of slope on both flanks, a list per tooth or one value) is
    ground on the relieved flanks too: the body clears the gear that the deviated edge cuts as the design's clears
    the nominal one (held against the nominal teeth it would read as an intrusion of its own size, and refuse a
    cutter shops use)."""
    from cutting.skiving.tooling import CutterErrors

    st, edge = setup_of("default")
    design = body_interference(st, edge)
    z0 = st.cutter.teeth
    for slope in (0.005, tuple(0.005 * (k % 2) for k in range(z0))):
        worn = replace(st, cutter_errors=CutterErrors(profile_slope=(slope, slope)))
        assert check_body_interference(worn, make_edge(worn, "conjugate")) == design
