"""The nominal flank (involute helicoid): geometry, normals, side convention and the deviation measure."""

import math

import numpy as np
import pytest

from cutting.flank import (
    SIDES,
    base_tangent_deviation,
    flank_normals,
    flank_points,
    flank_polar_angle,
    side_sign,
)
from cutting.gear import Gear

DEG = math.pi / 180
GEARS = {
    "spur_ext": Gear(40, 2.0, 20 * DEG, 0.0, 20.0),
    "helical_ext_left": Gear(31, 3.0, 20 * DEG, -25 * DEG, 30.0, profile_shift=0.2),
    "spur_int": Gear(60, 2.0, 20 * DEG, 0.0, 20.0, internal=True),
    "helical_int": Gear(60, 2.0, 20 * DEG, 20 * DEG, 20.0, internal=True),
}


@pytest.mark.parametrize("name", GEARS)
@pytest.mark.parametrize("side", SIDES)
def test_points_are_involute_and_on_the_surface(name, side):
    g = GEARS[name]
    xi = np.linspace(0.15, 0.6, 7)[:, None]
    z = np.linspace(-8, 8, 5)[None, :]
    p = flank_points(g, side, xi, z, tooth=3)
    r = np.hypot(p[..., 0], p[..., 1])
    # roll length: the tangent from the point to the base circle is r_b * xi
    assert np.allclose(np.sqrt(r**2 - g.base_radius**2), g.base_radius * xi, atol=1e-12)
    assert np.abs(base_tangent_deviation(g, p, side)).max() < 1e-12
    assert np.abs(base_tangent_deviation(g, p, side, tooth=3)).max() < 1e-12


@pytest.mark.parametrize("name", GEARS)
@pytest.mark.parametrize("side", SIDES)
def test_normals_are_normal_and_point_into_the_space(name, side):
    g = GEARS[name]
    xi, z, h = np.array([0.2, 0.35, 0.5]), np.array([-5.0, 0.0, 7.0]), 1e-6
    n = flank_normals(g, side, xi, z, 2)
    d_xi = (flank_points(g, side, xi + h, z, 2) - flank_points(g, side, xi - h, z, 2)) / (2 * h)
    d_z = (flank_points(g, side, xi, z + h, 2) - flank_points(g, side, xi, z - h, 2)) / (2 * h)
    assert np.abs(np.einsum("ij,ij->i", n, d_xi)).max() < 1e-6
    assert np.abs(np.einsum("ij,ij->i", n, d_z)).max() < 1e-6
    # |n_z| / |n_t| = tan(beta_b)
    assert np.allclose(np.abs(n[:, 2]) / np.hypot(n[:, 0], n[:, 1]), abs(math.tan(g.base_helix_angle)), atol=1e-12)
    # stepping out along the normal adds material-free space: deviation = -delta / cos(beta_b) ... sign: excess > 0
    p = flank_points(g, side, xi, z, 2)
    delta = 2e-3
    e = base_tangent_deviation(g, p + delta * n, side)
    assert np.allclose(e, delta / math.cos(g.base_helix_angle), rtol=1e-4)


def test_side_convention_tooth_tip_up():
    """Looking from +z with the tooth tip up, 'left' is on the viewer's left (-x)."""
    ext = GEARS["spur_ext"]  # tooth 10 sits at 90 deg: tip points to +y
    for side, sign in (("left", -1), ("right", 1)):
        p = flank_points(ext, side, 0.3, 0.0, tooth=10)
        assert np.sign(p[0]) == sign
    internal = GEARS["spur_int"]  # tooth 45 sits at 270 deg; its tip points inwards, i.e. to +y
    for side, sign in (("left", -1), ("right", 1)):
        p = flank_points(internal, side, 0.3, 0.0, tooth=45)
        assert np.sign(p[0]) == sign
    assert side_sign(ext, "left") == 1 and side_sign(internal, "left") == -1
    with pytest.raises(ValueError, match="left"):
        side_sign(ext, "up")


def test_space_width_on_the_reference_circle():
    """Spur x = 0: space width on d equals the tooth thickness, pi m / 2 = 3.1416 mm."""
    g = GEARS["spur_ext"]
    r = g.reference_radius
    left0 = flank_polar_angle(g, r, 0.0, "left", 0)
    right1 = flank_polar_angle(g, r, 0.0, "right", 1)
    right0 = flank_polar_angle(g, r, 0.0, "right", 0)
    assert (right1 - left0) * r == pytest.approx(math.pi, abs=1e-12)
    assert (left0 - right0) * r == pytest.approx(math.pi, abs=1e-12)


def test_helix_hand():
    """Right hand: the tooth turns counter-clockwise with +z by z tan(beta) / r on the reference cylinder."""
    g = GEARS["helical_int"]  # beta = +20 deg
    r = g.reference_radius
    turn = flank_polar_angle(g, r, 10.0, "left") - flank_polar_angle(g, r, 0.0, "left")
    assert turn == pytest.approx(10.0 * math.tan(20 * DEG) / r, abs=1e-14)
    lh = GEARS["helical_ext_left"]
    turn = flank_polar_angle(lh, 50.0, 10.0, "right") - flank_polar_angle(lh, 50.0, 0.0, "right")
    assert turn < 0


def test_deviation_of_a_rotated_gear():
    """Turning the whole gear by delta: left flanks gain r_b delta, right flanks lose it (external)."""
    g = GEARS["spur_ext"]
    delta = 1e-4
    c, s = math.cos(delta), math.sin(delta)
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    for side, sign in (("left", 1), ("right", -1)):
        p = flank_points(g, side, np.linspace(0.2, 0.5, 5), 0.0, 7) @ rot.T
        assert np.allclose(base_tangent_deviation(g, p, side), sign * g.base_radius * delta, atol=1e-12)
