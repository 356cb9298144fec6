"""A helical tooth space by the copying method (issue 28, item 1): the disc mill set over at the helix angle with
the envelope profile, checked by the exact swept surface of its screw motion against the nominal helicoid."""

import math

import numpy as np

from cutting.flank import flank_normals, flank_points
from cutting.form_milling.helical import contact_profile, envelope_mill, helical_pass, mill_axis
from cutting.form_milling.mill import designed_section, section_rolls
from cutting.form_milling.sweep import MilledGear
from cutting.gear import Gear, form_roll_length
from cutting.modification import roll


def test_on_a_spur_gear_the_envelope_is_the_section():
    """beta = 0: the normal of every profile point meets the mill's axis in the centre plane z = 0, and the mill's
    axial profile (u, R - rho) is the space's section relative to the path point (exactly)."""
    gear = Gear(teeth=20, normal_module=2.0, face_width=10.0)
    L = section_rolls(gear, 21)
    radius = 25.0
    centre = np.array([0.0, gear.root_radius + radius, 0.0])
    for side in ("left", "right"):
        u, rho, z = contact_profile(gear, side, L, centre, mill_axis(gear))
        section = designed_section(gear, None, side, L, 0.0)
        assert np.abs(z).max() < 1e-12
        assert np.abs(u - section[:, 0]).max() < 1e-12
        assert np.abs(radius - rho - (section[:, 1] - gear.root_radius)).max() < 1e-12


def test_the_set_over_mill_cuts_the_helicoid():
    """beta = 20 deg, z = 20, mn = 2: the mill set over at the helix angle, its edges the envelope (the contact of
    the profile lies up to 2.6 mm off the mill's centre plane), fed along the space's screw motion: its exact swept
    surface is the nominal helicoid within 0.1 um on both flanks over the profile and the face (measured 0.035 um;
    the Bezier edges' fit is 0.05 um). The section copied instead (the spur method) would miss by tens of um."""
    gear = Gear(teeth=20, normal_module=2.0, helix_angle=math.radians(20.0), face_width=10.0)
    mill = envelope_mill(gear, 25.0)
    z = np.arange(-21.0, 21.0 + 1e-9, 0.05)
    cut = MilledGear(gear, mill, [helical_pass(gear, mill, k % gear.teeth, z) for k in (-1, 0, 1)], "helical")
    L = np.linspace(form_roll_length(gear) + 0.05, roll(gear, gear.tip_diameter_value) - 0.05, 9)
    LL, zz = np.meshgrid(L, np.linspace(-4.0, 4.0, 5))
    for side, tooth in (("left", 0), ("right", 1)):
        xi = LL / gear.base_radius
        p = flank_points(gear, side, xi, zz, tooth).reshape(-1, 3)
        n = flank_normals(gear, side, xi, zz, tooth).reshape(-1, 3)
        d = cut.probe(p, n, 0.05)
        assert np.isfinite(d).all()
        assert np.abs(d).max() < 1e-4, np.abs(d).max()
    # the contact really leaves the centre plane: the spur method's section would not do
    centre = np.array([0.0, gear.root_radius + 25.0, 0.0])
    _, _, contact_z = contact_profile(gear, "left", section_rolls(gear, 11), centre, mill_axis(gear))
    assert np.ptp(contact_z) > 3.0
