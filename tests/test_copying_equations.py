"""Seed 003's equations 4-6 and 17 (the copying method's transfer angles, the change to tool coordinates and the
Bezier path) against cases worked by hand (issue 28's proofs; eq. 1's Delta-y term is issue 28's item 3)."""

import math

import numpy as np

from cutting.form_milling.copying_path import FlankPath, _rotation, transfer_angles


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
    r = _rotation(math.radians(20), math.radians(10))
    assert np.allclose(r @ [0, 0, 1], [0.173648178, -0.336824089, 0.925416578], atol=1e-9)
    assert np.allclose(np.degrees(transfer_angles((r @ [0, 0, 1])[None])[0]), [20.0, 10.0], atol=1e-9)
    assert np.allclose(r.T @ r, np.eye(3), atol=1e-15)
    flat = _rotation(0.0, math.radians(10))
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
