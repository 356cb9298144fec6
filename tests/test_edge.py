"""Cutting edges: the involute edge and the conjugate edge designed by the envelope method (um = micrometres)."""

import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from cutting.gear import Gear
from cutting.skiving.edge import (
    _on_flank,
    conjugate_edge,
    envelope_bound,
    involute_edge,
    make_edge,
    mate_flank,
    tooth_intrusion,
)
from cutting.skiving.kinematics import SkivingSetup

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


def scalar_envelope_bound(st, rho, th0, mate, sgn, phi, band) -> tuple[float, float]:
    """One radius as the edge was first built: the grid's extreme, then a bounded scalar search around it.

    Returns (grid extreme, refined extreme) of sgn * theta_t (inf where no instant bounds). The search runs on the
    angle from the bracket's start: scipy's tolerance adds sqrt(eps) * |x| to xatol, which at |phi0| ~ 0.3 rad
    stops ~5e-9 rad short of a contact leaving the flank (~1 nm on the edge).
    """
    th, ok, de = _on_flank(st, rho, th0, mate, phi, band)
    cand = np.where(ok & (sgn * de < 0), sgn * th, np.inf)
    k = int(np.argmin(cand))
    if not np.isfinite(cand[k]):
        return np.inf, np.inf
    lo, hi = phi[max(k - 1, 0)], phi[min(k + 1, len(phi) - 1)]

    def bound(u: float) -> float:
        t, valid, d = _on_flank(st, rho, th0, mate, np.array([lo + u]), band)
        return float(sgn * t[0]) if valid[0] and sgn * d[0] < 0 else 1e9

    best = minimize_scalar(bound, bounds=(0.0, hi - lo), method="bounded", options={"xatol": 1e-12})
    return cand[k], min(cand[k], best.fun)


def test_vectorized_refinement_matches_a_scalar_bounded_search(probe_edges):
    """One golden-section search over all radii finds the bound that a bounded scalar search finds radius by radius."""
    st, ie, _ = probe_edges
    g = st.gear
    phi = np.linspace(-0.5 * math.pi, 0.5 * math.pi, 1500)
    band = (g.base_radius, g.tip_radius)
    idx = np.array([0, 12, 24, 42, 54])  # below the generating zone (no bound), at its lower end, over it
    for side, sgn in (("left", 1.0), ("right", -1.0)):
        mate = mate_flank(st, side)
        vec, _ = envelope_bound(st, ie.radii[idx], ie.theta[side][idx], mate, sgn, phi, band)
        refined_by = []
        for j, i in enumerate(idx):
            grid, scalar = scalar_envelope_bound(st, ie.radii[i], ie.theta[side][i], mate, sgn, phi, band)
            if np.isinf(scalar):
                assert vec[j] == np.inf
                continue
            assert abs(vec[j] - scalar) * ie.radii[i] < 1e-9  # mm
            refined_by.append((grid - scalar) * ie.radii[i])
        assert np.isinf(vec[0]) and max(refined_by) > 1e-6  # the refinement matters: > 1 um at the zone's lower end
