"""Cutting edges: the involute edge and the conjugate edge designed by the envelope method (um = micrometres)."""

import math

import numpy as np
import pytest

from cutting.edge import conjugate_edge, involute_edge, make_edge, tooth_intrusion
from cutting.gear import Gear
from cutting.skiving import SkivingSetup

DEG = math.pi / 180
PHI = np.linspace(-0.7, 0.7, 4001)  # cutter angles through one tooth passage


def probe_setup() -> SkivingSetup:
    """The probe of domain.md section 1: external spur z2 = 25, cutter z0 = 17, Sigma = 20 deg."""
    return SkivingSetup(Gear(25, 2.0, 20 * DEG, 0.0, 20.0), Gear(17, 2.0, 20 * DEG, 20 * DEG, 10.0), 1000, 0.15, (4.5,))


@pytest.fixture(scope="module")
def probe_edges():
    st = probe_setup()
    return st, involute_edge(st, 60), conjugate_edge(st, 60)


def test_involute_edge_is_the_end_plane_section(probe_edges):
    st, ie, _ = probe_edges
    c = st.cutter
    r = ie.radii[ie.radii > c.base_radius]
    th = ie.theta["left"][ie.radii > c.base_radius]
    # the transverse involute of the cutter: theta = s_t/d + inv(alpha_t) - inv(alpha_y)
    alpha_y = np.arccos(c.base_radius / r)
    expected = (
        c.transverse_tooth_thickness / c.reference_diameter
        + (math.tan(c.transverse_pressure_angle) - c.transverse_pressure_angle)
        - (np.tan(alpha_y) - alpha_y)
    )
    assert np.allclose(th, expected, atol=1e-13)
    assert np.allclose(ie.theta["right"], -ie.theta["left"], atol=1e-13)


def test_conjugate_edge_departs_like_the_probe(probe_edges):
    """domain.md: thicker than the involute edge by 0 um at the cutter's pitch radius, ~1-1.5 um towards tip."""
    st, ie, ce = probe_edges
    dev = (ce.theta["left"] - ie.theta["left"]) * ie.radii * 1e3
    assert np.allclose(dev, -(ce.theta["right"] - ie.theta["right"]) * ie.radii * 1e3, atol=1e-6)  # symmetric
    at_pitch = np.interp(st.cutter.reference_radius, ie.radii, dev)
    assert abs(at_pitch) < 0.05
    assert 1.0 < dev[-1] < 2.5  # at the cutter tip
    assert np.all(dev > -1e-6)  # never thinner than the involute edge


def test_conjugate_edge_touches_but_never_enters_the_teeth(probe_edges):
    st, ie, ce = probe_edges
    conj = tooth_intrusion(st, ce.outline, PHI)
    assert conj.max() < 1e-6  # mm: enters no tooth
    inv = tooth_intrusion(st, ie.outline, PHI)
    assert inv.max() < 1e-6
    # the conjugate edge is thicker, so over the generating zone it comes closer to the teeth
    gen = (ie.radii > st.cutter.reference_radius - 1.5) & (ie.radii < st.cutter.reference_radius + 1.5)
    n = len(ie.radii)
    right_idx = np.arange(n)[gen]
    assert np.all(conj[right_idx] >= inv[right_idx] - 1e-9)


def test_spur_cutter_on_helical_internal_gear_is_already_conjugate():
    """Sigma = beta2 with a spur cutter: the envelope coincides with the involute edge (to 0.05 um)."""
    st = SkivingSetup(
        Gear(60, 2.0, 20 * DEG, 20 * DEG, 20.0, internal=True), Gear(25, 2.0, 20 * DEG, 0.0, 10.0), 2000, 0.2, (4.5,)
    )
    ie, ce = involute_edge(st, 40), conjugate_edge(st, 40)
    involute_part = ie.radii > st.cutter.base_radius  # below it the edge is a radial line, not an involute
    dev = (ce.theta["left"] - ie.theta["left"]) * ie.radii
    assert np.abs(dev[involute_part]).max() * 1e3 < 0.05
    assert tooth_intrusion(st, ce.outline, PHI).max() < 1e-6


def test_edge_kind_is_checked():
    with pytest.raises(ValueError, match="unknown edge"):
        make_edge(probe_setup(), "parabolic")
