"""A ball seated in every tooth space, on the flanks the probe scanned: runout and the dimension over balls.

As on a gear measuring machine, the ball is virtual: both flanks of a space are scanned around the nominal
contact points (a patch along the profile and the face, refined around the points nearest the ball), and the
ball of the given diameter is seated on those points: its centre stays in the mid-face plane and moves in
radius and angle until its distance to the scanned points on each side is the ball radius. The scan spacing
is fine enough that the ball cannot settle between two points by more than ~0.02 um (spacing^2 / (8 R)).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq, minimize

from cutting.errors import UnmeasurableError
from cutting.flank import SIDES, flank_points, side_sign
from cutting.gear import Gear
from metrology.datum import Datum
from metrology.workpiece import Workpiece, flank_surface

#: half size of the scanned patch around the nominal contact [mm] and points across it; refinement grid
PATCH_HALF = 0.12
PATCH_POINTS = 9
REFINE_POINTS = 7
REFINE_BEST = 3


def _contact_foot(gear: Gear, side: str, tooth: int, centre: np.ndarray, diameter: float) -> tuple[float, float]:
    """(roll angle, height) of the point of the nominal flank nearest the ball centre (the nominal contact)."""
    rb = gear.base_radius
    r_k = float(np.hypot(centre[0], centre[1]))
    xi0 = math.sqrt(max(r_k**2 - rb**2, 1e-9)) / rb

    def dist(v: np.ndarray) -> float:
        return float(np.linalg.norm(flank_points(gear, side, v[0], v[1], tooth) - centre))

    best = min(
        (
            minimize(
                dist,
                np.array([xi0, s * 0.5 * diameter * math.sin(gear.base_helix_angle)]),
                method="Nelder-Mead",
                options={"xatol": 1e-12, "fatol": 1e-14, "maxiter": 4000},
            )
            for s in (-1.0, 1.0)
        ),
        key=lambda r: r.fun,
    )
    return float(best.x[0]), float(best.x[1])


def scanned_patches(
    wp: Workpiece, gear: Gear, datum: Datum, side: str, teeth: np.ndarray, xi_c: float, z_c: float, target
) -> list[np.ndarray]:
    """Per tooth of ``teeth``, the probed points of the ``side`` flank around (xi_c, z_c) (nominal frame, tooth 0):
    a PATCH_POINTS^2 grid, refined where ``target(tooth_index, points)`` is smallest (REFINE_BEST points, each a
    REFINE_POINTS^2 grid of a third of the spacing). NaN rows dropped."""
    rb = gear.base_radius
    step = 2 * PATCH_HALF / (PATCH_POINTS - 1)
    u = np.linspace(-PATCH_HALF, PATCH_HALF, PATCH_POINTS)
    xi = xi_c + u[:, None] / rb
    zz = z_c + u[None, :] + 0 * xi
    xi = xi + 0 * zz
    pts = flank_surface(wp, gear, datum, side, xi[None], zz[None], teeth[:, None, None])  # (t, n, n, 3)
    coarse = pts.reshape(len(teeth), -1, 3)
    score = np.array([target(i, coarse[i]) for i in range(len(teeth))])  # (t, n*n)
    score = np.where(np.isfinite(score), score, np.inf)
    best = np.argsort(score, axis=1)[:, :REFINE_BEST]
    fine = np.linspace(-step / 1.5, step / 1.5, REFINE_POINTS)
    bx, bz = xi.ravel()[best], zz.ravel()[best]  # (t, k)
    fxi = bx[:, :, None, None] + fine[None, None, :, None] / rb
    fz = bz[:, :, None, None] + fine[None, None, None, :]
    refined = flank_surface(wp, gear, datum, side, fxi, fz, teeth[:, None, None, None]).reshape(len(teeth), -1, 3)
    out = []
    for i in range(len(teeth)):
        p = np.concatenate([coarse[i], refined[i]])
        out.append(p[np.isfinite(p).all(axis=1)])
    return out


def ball_seats(wp: Workpiece, gear: Gear, datum: Datum, diameter: float, centre_radius: float) -> np.ndarray:
    """Centres (z, 3) of a ball of ``diameter`` seated in every space at mid face, touching both flanks.

    Row j is the space after nominal tooth j (between teeth j and j+1). ``centre_radius`` is the nominal
    radius of the ball centre, used as the start.
    """
    pitch = 2 * math.pi / gear.teeth
    half = diameter / 2
    teeth = np.arange(gear.teeth)
    # the space after tooth j: tooth j's counter-clockwise flank, tooth j+1's clockwise flank
    ccw_side = next(s for s in SIDES if side_sign(gear, s) > 0)
    cw_side = next(s for s in SIDES if side_sign(gear, s) < 0)
    c0 = np.array([centre_radius * math.cos(0.5 * pitch), centre_radius * math.sin(0.5 * pitch), 0.0])
    centres = np.column_stack(
        [
            centre_radius * np.cos(datum.rotation + (teeth + 0.5) * pitch),
            centre_radius * np.sin(datum.rotation + (teeth + 0.5) * pitch),
            np.full(gear.teeth, datum.z_mid),
        ]
    )

    def nearest_to_ball(owner_offset: int):
        def target(i: int, pts: np.ndarray) -> np.ndarray:
            return np.linalg.norm(pts - centres[(i - owner_offset) % gear.teeth], axis=1)

        return target

    xi_a, z_a = _contact_foot(gear, ccw_side, 0, c0, diameter)
    xi_b, z_b = _contact_foot(gear, cw_side, 1, c0, diameter)
    # tooth j's ccw flank faces space j; tooth j's cw flank faces space j - 1
    on_cw_of_space = scanned_patches(wp, gear, datum, ccw_side, teeth, xi_a, z_a, nearest_to_ball(0))
    on_ccw_of_space = scanned_patches(wp, gear, datum, cw_side, teeth, xi_b, z_b, nearest_to_ball(1))
    out = np.zeros((gear.teeth, 3))
    for j in range(gear.teeth):
        phi0 = datum.rotation + (j + 0.5) * pitch
        out[j] = _seat(
            on_ccw_of_space[(j + 1) % gear.teeth],
            on_cw_of_space[j],
            half,
            centre_radius,
            phi0,
            pitch,
            gear.mn,
            datum.z_mid,
            diameter,
            j,
        )
    return out


def _seat(
    s_ccw: np.ndarray,
    s_cw: np.ndarray,
    radius: float,
    centre_radius: float,
    phi0: float,
    pitch: float,
    mn: float,
    z_mid: float,
    diameter: float,
    j: int,
) -> np.ndarray:
    """Ball seat between the scanned flank points on either side of the space centre line phi0."""
    if len(s_ccw) == 0 or len(s_cw) == 0:
        raise UnmeasurableError(f"the ball of {diameter:.3f} mm finds no flank on one side of space {j}")

    def point(rho: float, phi: float) -> np.ndarray:
        return np.array([rho * math.cos(phi0 + phi), rho * math.sin(phi0 + phi), z_mid])

    def gap_to(points: np.ndarray, c: np.ndarray) -> float:
        return float(np.sqrt(np.min(np.einsum("ij,ij->i", points - c, points - c))))

    def centred(rho: float) -> tuple[float, float]:
        """Angle at which the ball at radius rho is equidistant from both flanks, and that distance."""

        def gap(phi: float) -> float:
            c = point(rho, phi)
            return gap_to(s_ccw, c) - gap_to(s_cw, c)

        phi = brentq(gap, -0.45 * pitch, 0.45 * pitch, xtol=1e-13)
        return phi, gap_to(s_ccw, point(rho, phi))

    lo, hi = centre_radius - 0.5 * mn, centre_radius + 0.5 * mn
    try:
        rho = brentq(lambda rr: centred(rr)[1] - radius, lo, hi, xtol=1e-10)
    except ValueError as exc:
        msg = f"the ball of {diameter:.3f} mm does not seat in space {j} near r = {centre_radius:.3f} mm"
        raise UnmeasurableError(msg) from exc
    phi, _ = centred(rho)
    return point(rho, phi)
