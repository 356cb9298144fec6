"""The holder-side collision check: hub and holder behind the cutter's teeth must stay out of the blank."""

import math
from dataclasses import replace

import pytest

from cutting.errors import InputError
from cutting.gear import Gear
from cutting.skiving.edge import involute_edge
from cutting.skiving.holder import check_holder_side
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.trajectory import ideal_passes

DEG = math.pi / 180


def setup() -> SkivingSetup:
    return SkivingSetup(Gear(30, 1.0, 20 * DEG, 0.0, 6.0), Gear(17, 1.0, 20 * DEG, 20 * DEG, 10.0), 2000, 0.3, (2.25,))


def test_a_normal_holder_passes():
    st = setup()
    check_holder_side(ideal_passes(st), involute_edge(st, 30), st.cutter.face_width, st.holder_diameter_value)


def test_a_fat_holder_is_named():
    """A holder as wide as the cutter, close behind the rake face, runs into the blank's top face."""
    st = setup()
    with pytest.raises(InputError, match=r"cutter\.holder_diameter") as err:
        check_holder_side(ideal_passes(st), involute_edge(st, 30), 2.0, st.cutter.reference_diameter * 1.2)
    assert "enters the blank" in str(err.value) and "pass 1" in str(err.value)


def test_a_hub_deeper_than_the_teeth_is_named():
    """If the hub reached above the cut depth, the hub (not the teeth) would meet the blank."""
    st = setup()
    edge = involute_edge(st, 30)
    shallow = replace(edge, r_low=edge.r_tip - 1.0)  # teeth only 1 mm deep for a 2.25 mm pass
    with pytest.raises(InputError, match="cutter hub"):
        check_holder_side(ideal_passes(st), shallow, st.cutter.face_width, st.holder_diameter_value)
