"""The nominal flank: involute helicoids of both flanks of every tooth, external and internal.

This is the design surface that the cutter edge is built from and that the measurement compares
against. Frame and sign conventions are those of :mod:`cutting.gear`.

Flank names follow the measuring-machine convention: look at the gear from +z and turn it so the
tooth tip points up; the flank on the left is ``"left"``. For an external gear the left flank lies on
the counter-clockwise (+theta) side of the tooth centre; for an internal gear the tooth tip points
inwards, so the left flank lies on the clockwise (-theta) side.

In a transverse section at height z the flank of tooth k is the polar curve

    theta(r, z) = 2 pi k / z_teeth + 2 pi z / p_z + side_sign * psi(r)

with psi the half thickness angle (:meth:`Gear.half_thickness_angle`) and p_z the signed lead.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from cutting.gear import Gear

Side = Literal["left", "right"]
SIDES: tuple[Side, Side] = ("left", "right")


def side_sign(gear: Gear, side: Side) -> int:
    """+1 if ``side`` lies on the counter-clockwise (+theta) side of the tooth centre, else -1."""
    if side not in SIDES:
        raise ValueError(f"flank side must be 'left' or 'right', got {side!r}")
    ccw = side == "left"
    if gear.internal:
        ccw = not ccw
    return 1 if ccw else -1


def twist_rate(gear: Gear) -> float:
    """Rotation of the transverse section per mm of axial position, 2 pi / p_z [rad/mm] (0 for spur)."""
    return 0.0 if gear.helix_angle == 0.0 else 2 * np.pi / gear.lead


def tooth_centre_angle(gear: Gear, tooth: ArrayLike, z: ArrayLike) -> np.ndarray:
    """Polar angle of the centre line of tooth ``tooth`` at axial position ``z`` [rad]."""
    return 2 * np.pi * np.asarray(tooth, dtype=float) / gear.teeth + twist_rate(gear) * np.asarray(z, dtype=float)


def flank_polar_angle(gear: Gear, radius: ArrayLike, z: ArrayLike, side: Side, tooth: ArrayLike = 0) -> np.ndarray:
    """Polar angle theta of the nominal flank at radius r and axial position z [rad] (r >= r_b)."""
    return tooth_centre_angle(gear, tooth, z) + side_sign(gear, side) * np.asarray(gear.half_thickness_angle(radius))


def roll_to_radius(gear: Gear, roll_angle: ArrayLike) -> np.ndarray:
    """Radius of the involute point with roll angle xi: r = r_b sqrt(1 + xi^2) [mm]."""
    xi = np.asarray(roll_angle, dtype=float)
    return gear.base_radius * np.sqrt(1.0 + xi * xi)


def flank_points(gear: Gear, side: Side, roll_angle: ArrayLike, z: ArrayLike, tooth: ArrayLike = 0) -> np.ndarray:
    """Points of the nominal flank, shape ``broadcast(roll_angle, z, tooth) + (3,)`` [mm].

    ``roll_angle`` xi = tan(alpha_y) parameterises the involute (roll length = r_b xi).
    """
    xi, zz, k = np.broadcast_arrays(np.asarray(roll_angle, float), np.asarray(z, float), np.asarray(tooth, float))
    r = roll_to_radius(gear, xi)
    theta = flank_polar_angle(gear, r, zz, side, k)
    return np.stack([r * np.cos(theta), r * np.sin(theta), zz], axis=-1)


def flank_normals(gear: Gear, side: Side, roll_angle: ArrayLike, z: ArrayLike, tooth: ArrayLike = 0) -> np.ndarray:
    """Unit normals of the nominal flank pointing out of the material (into the tooth space).

    In the transverse plane the normal lies along the base tangent:
    n_t = side_sign cos(alpha_y) e_theta + sense sin(alpha_y) e_r (sense = +1 external, -1 internal);
    the helicoid adds n_z = -side_sign r_b 2 pi / p_z, so |n_z| / |n_t| = tan(beta_b).
    """
    xi, zz, k = np.broadcast_arrays(np.asarray(roll_angle, float), np.asarray(z, float), np.asarray(tooth, float))
    r = roll_to_radius(gear, xi)
    theta = flank_polar_angle(gear, r, zz, side, k)
    s = side_sign(gear, side)
    cos_a = gear.base_radius / r
    sin_a = xi * cos_a
    e_r = np.stack([np.cos(theta), np.sin(theta)], axis=-1)
    e_t = np.stack([-np.sin(theta), np.cos(theta)], axis=-1)
    n_xy = s * cos_a[..., None] * e_t + gear.sense * sin_a[..., None] * e_r
    n_z = np.full(xi.shape, -s * gear.base_radius * twist_rate(gear))
    n = np.concatenate([n_xy, n_z[..., None]], axis=-1)
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


def base_tangent_deviation(gear: Gear, points: ArrayLike, side: Side, tooth: ArrayLike | None = None) -> np.ndarray:
    """Deviation of measured points from the nominal flank along the base tangent [mm].

    e = side_sign * r_b * (theta - theta_nominal(r, z)), excess material positive (ISO 1328-1 sign).
    ``tooth`` None picks, for each point, the tooth whose nominal flank is nearest in angle. The
    deviation is transverse; multiply by cos(beta_b) for the value normal to the helicoid.
    """
    p = np.asarray(points, dtype=float)
    r = np.hypot(p[..., 0], p[..., 1])
    theta = np.arctan2(p[..., 1], p[..., 0])
    nominal0 = flank_polar_angle(gear, r, p[..., 2], side, 0)
    pitch = 2 * np.pi / gear.teeth
    if tooth is None:
        d = theta - nominal0
        d = d - pitch * np.round(d / pitch)
    else:
        d = theta - (nominal0 + pitch * np.asarray(tooth, dtype=float))
        d = (d + np.pi) % (2 * np.pi) - np.pi
    return side_sign(gear, side) * gear.base_radius * d
