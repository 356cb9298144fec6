"""Seed 003's equations 1, 4-6 and 17 (the copying method's initial path, transfer angles, the change to tool
coordinates and the Bezier path) against cases worked by hand."""

import math

import numpy as np
import pytest

from cutting.form_milling.copying_path import FlankPath, SingleBezier, initial_path, tool_rotation, transfer_angles
from cutting.gear import Gear
from cutting.modification import FlankDesign, Modification


def test_eq_1_initial_path_worked_by_hand():
    """z = 20, m = 2 mm, alpha = 20 deg, b = 10 mm: r = 20 mm, r_b = 20 cos 20 = 18.7938524 mm; at the pitch circle
    the space is half a pitch wide, so the left flank's pitch point lies theta0 = pi / 40 = 0.0785398 rad left of
    the space's symmetry line: (-20 sin theta0, 20 cos theta0) = (-1.5691819, 19.9383467). A lead crowning of
    20 um takes e = -0.020 (2 z / b)^2 along the base tangent: the section's involute turned by e / r_b, i.e. by
    delta = 0.00106418 rad away from the symmetry line at the end faces (z = +-5) and 0.000266045 rad at z = +-2.5.
    Eq. 1: Delta x = -20 (sin(theta0 + delta) - sin theta0) = -20 (cos theta0 delta - sin theta0 delta^2 / 2)
    = -20 (0.99691733 * 0.00106418 - 0.0784591 * 5.6624e-7) = -0.0212171 mm, Delta y = 20 (cos(theta0 + delta) -
    cos theta0) = -20 (sin theta0 delta + cos theta0 delta^2 / 2) = -0.00168118 mm: the path point at the faces is
    (-0.1 - 0.0212171, 17.5 - 0.00168118) from the left pass's (-c / 2, r_f); at z = +-2.5, Delta x = -0.00530444
    and Delta y = -20 (0.0784591 * 0.000266045 + 0.99691733 * 3.5390e-8) = -0.000418187 mm. The right flank, not
    modified, keeps (c / 2, r_f) = (0.1, 17.5)."""
    gear = Gear(teeth=20, normal_module=2.0, face_width=10.0)
    design = Modification(FlankDesign(lead_crowning=0.020), FlankDesign())
    z = np.array([-5.0, -2.5, 0.0, 2.5, 5.0])
    left = initial_path(gear, design, "left", z, 0.2)
    assert np.allclose(left.x, -0.1 + np.array([-0.0212171, -0.00530444, 0.0, -0.00530444, -0.0212171]), atol=2e-7)
    assert np.allclose(left.y, 17.5 + np.array([-0.00168118, -0.000418187, 0.0, -0.000418187, -0.00168118]), atol=2e-8)
    right = initial_path(gear, design, "right", z, 0.2)
    assert np.allclose(right.x, 0.1, atol=1e-12) and np.allclose(right.y, 17.5, atol=1e-12)


def test_eqs_4_5_transfer_angles_worked_by_hand():
    """Path tangent along (0.1, -0.2, 1): |.| = sqrt(1.05) = 1.0246951, T = (0.0975900, -0.1951800, 0.9759001).
    Eq. 4: psi_x = atan(-T_y / T_z) = atan(0.2) = 0.2 - 0.2^3/3 + 0.2^5/5 - 0.2^7/7 + 0.2^9/9 - ... = 0.19739556.
    Eq. 5: psi_y = asin(T_x) = x + x^3/6 + 3 x^5/40 + 15 x^7/336 (x = 0.09759001) = 0.09759001 + 0.00015491
    + 0.00000066 + 0.00000000 = 0.09774558."""
    t = np.array([[0.1, -0.2, 1.0]]) / math.sqrt(1.05)
    psi_x, psi_y = transfer_angles(t)[0]
    assert abs(psi_x - 0.19739556) < 1e-8
    assert abs(psi_y - 0.09774558) < 1e-8
    # a path along the gear axis: no turn
    assert np.allclose(transfer_angles(np.array([[0.0, 0.0, 1.0]])), 0.0)


def test_eq_6_tool_coordinates_worked_by_hand():
    """psi_x = 20 deg about x after psi_y = 10 deg about y: the tool's axis e_z goes to
    Rx(20) (sin 10, 0, cos 10) = (sin 10, -sin 20 cos 10, cos 20 cos 10) = (0.173648, -0.336824, 0.925417),
    the path tangent that eqs. 4-5 turn back into (20 deg, 10 deg). A flank point one millimetre from the path
    point along the turned x axis, (cos 10, 0, -sin 10) in the gear frame when psi_x = 0, is (1, 0, 0) in tool
    coordinates: on the profiling plane (z_tool = 0), at x_tool = 1 mm."""
    r = tool_rotation(math.radians(20), math.radians(10))
    assert np.allclose(r @ [0, 0, 1], [0.173648178, -0.336824089, 0.925416578], atol=1e-9)
    assert np.allclose(np.degrees(transfer_angles((r @ [0, 0, 1])[None])[0]), [20.0, 10.0], atol=1e-9)
    assert np.allclose(r.T @ r, np.eye(3), atol=1e-15)
    flat = tool_rotation(0.0, math.radians(10))
    point = np.array([math.cos(math.radians(10)), 0.0, -math.sin(math.radians(10))])
    assert np.allclose(point @ flat, [1.0, 0.0, 0.0], atol=1e-12)  # eq. 6 as profiling_sections applies it


def test_eq_17_bezier_path_worked_by_hand():
    """A path x = 0.01 z^2 (a lead crowning of 0.01 mm at z = 1 mm), y = 5 mm, through z = 0, 2, 4 mm: the spline
    is exact on a parabola, so the segment [0, 2] has the control values x0 = 0, x0 + h x'(0) / 3 = 0,
    x1 - h x'(2) / 3 = 0.04 - 2 * 0.04 / 3 = 0.013333, x1 = 0.04; its middle (x0 + 3 c1 + 3 c2 + x1) / 8 = 0.01 =
    x(1). y's control values are all 5."""
    z = np.array([0.0, 2.0, 4.0])
    path = FlankPath("left", z, 0.01 * z**2, np.full(3, 5.0))
    seg = path.bezier()[0]
    assert seg["z"] == [0.0, 2.0]
    assert np.allclose(seg["x"], [0.0, 0.0, 0.04 / 3, 0.04], atol=1e-12)
    assert np.allclose(seg["y"], [5.0] * 4, atol=1e-12)
    c = seg["x"]
    assert abs((c[0] + 3 * c[1] + 3 * c[2] + c[3]) / 8 - 0.01) < 1e-12
    assert np.allclose(path.at(np.array([1.0, 3.0]))[:, 0], [0.01, 0.09], atol=1e-12)


def test_eq_17_single_bezier_worked_by_hand():
    """The seed's one cubic Bezier over the path: x = 0.001 z^3 and y = 5 + 0.03 z through z = 0, 0.5 .. 3 mm. With
    tau = z / 3, x = 0.027 tau^3, whose Bernstein coefficients are (0, 0, 0, 0.027); y = 5 + 0.09 tau has
    (5, 5.03, 5.06, 5.09). The fit is exact on a cubic, so these are its control values, the path's one segment
    carries them, and at z = 1.5 the path is at x = 0.003375, with slope 0.003 z^2 = 0.00675."""
    z = np.linspace(0.0, 3.0, 7)
    path = FlankPath("left", z, 0.001 * z**3, 5 + 0.03 * z, form="bezier")
    (seg,) = path.bezier()
    assert seg["z"] == [0.0, 3.0]
    assert np.allclose(seg["x"], [0.0, 0.0, 0.0, 0.027], atol=1e-12)
    assert np.allclose(seg["y"], [5.0, 5.03, 5.06, 5.09], atol=1e-12)
    assert abs(path.at(np.array([1.5]))[0, 0] - 0.003375) < 1e-12
    t = path.tangent(np.array([1.5]))[0]
    assert abs(t[0] / t[2] - 0.00675) < 1e-12 and abs(t[1] / t[2] - 0.03) < 1e-12
    # not a cubic: the least-squares curve, whose residual is orthogonal to the four Bernstein polynomials
    wavy = 0.01 * np.sin(2 * z)
    fit = SingleBezier(z, wavy)
    tau = z / 3
    basis = np.stack([(1 - tau) ** 3, 3 * tau * (1 - tau) ** 2, 3 * tau**2 * (1 - tau), tau**3], axis=-1)
    assert np.allclose(basis.T @ (wavy - fit(z)), 0.0, atol=1e-15)
    with pytest.raises(ValueError, match="path form"):
        FlankPath("left", z, z, z, form="nurbs")
