"""Span measurement W_k: two parallel anvil planes over k teeth, rocked to the minimum, on the scanned flanks.

The anvils touch the outer flanks of k consecutive teeth (the right flank of the first, the left flank of the
last, counting counter-clockwise). Each flank is scanned around the nominal contact line (roll length W_kt / 2
from the base tangent's tangent point, across the face within the helix evaluation range), refined around the
points that stand out most towards the anvil. For a plane direction n the width is
max(n . p, last tooth's left flank) - min(n . p, first tooth's right flank); the measured W_k is the minimum
over n (the micrometer is rocked until it reads least), searched around the nominal normal (the base tangent,
tilted by the base helix angle for helical gears).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize

from cutting.flank import flank_normals, twist_rate
from cutting.gear import Gear
from metrology import thickness_nominal as nominal
from metrology.datum import Datum
from metrology.workpiece import Workpiece, flank_surface

#: scan of a flank around the anvil's contact: roll length +-ROLL_HALF [mm] x FACE_POINTS across the face
ROLL_HALF = 0.25
ROLL_POINTS = 11
FACE_POINTS = 41
REFINE_BEST = 4
REFINE_POINTS = 5


def _anvil_normal(gear: Gear, datum: Datum, i: int, k: int) -> np.ndarray:
    """The nominal anvil normal of the group starting at nominal tooth i (pointing from its first to its last
    tooth's side)."""
    pitch = 2 * math.pi / gear.teeth
    phi = datum.rotation + (i + (k - 1) / 2) * pitch
    tau = -math.atan(gear.base_radius * twist_rate(gear))
    return np.array([-math.sin(phi) * math.cos(tau), math.cos(phi) * math.cos(tau), math.sin(tau)])


def _generator_slope(gear: Gear, side: str, xi_c: float) -> float:
    """d(xi)/dz along the helicoid's straight generator through roll angle xi_c at mid face: the line an anvil
    plane touches (the flank normal keeps its direction along it): +-2 pi / p_z, the sign by the flank."""
    rate = twist_rate(gear)
    if rate == 0.0:
        return 0.0
    n0 = flank_normals(gear, side, xi_c, 0.0, 0)
    return min(
        (s * rate for s in (1.0, -1.0)), key=lambda k: np.linalg.norm(flank_normals(gear, side, xi_c + k, 1.0, 0) - n0)
    )


def _scan(wp: Workpiece, gear: Gear, datum: Datum, side: str, xi_c: float, z_half: float, sign: float, k: int):
    """Per tooth, the scanned points of its ``side`` flank near the anvil contact; ``sign`` +1 where the anvil
    rests on the largest n . p (the group's last tooth), -1 on the smallest (its first)."""
    rb = gear.base_radius
    teeth = np.arange(gear.teeth)
    u = np.linspace(-ROLL_HALF, ROLL_HALF, ROLL_POINTS)
    zs = np.linspace(-z_half, z_half, FACE_POINTS)
    xi = (xi_c + u / rb)[:, None] + _generator_slope(gear, side, xi_c) * zs[None, :]
    zz = 0 * u[:, None] + zs[None, :]
    pts = flank_surface(wp, gear, datum, side, xi[None], zz[None], teeth[:, None, None]).reshape(gear.teeth, -1, 3)
    first = (teeth - (k - 1)) % gear.teeth if sign > 0 else teeth  # the group each flank belongs to
    normals = np.array([_anvil_normal(gear, datum, int(i), k) for i in first])
    score = -sign * np.einsum("tpc,tc->tp", pts, normals)
    score = np.where(np.isfinite(score), score, np.inf)
    best = np.argsort(score, axis=1)[:, :REFINE_BEST]
    du, dz = (u[1] - u[0]) / 1.5, (zs[1] - zs[0]) / 1.5
    fu, fz = np.linspace(-du, du, REFINE_POINTS), np.linspace(-dz, dz, REFINE_POINTS)
    bx, bz = xi.ravel()[best], zz.ravel()[best]
    rxi = bx[:, :, None, None] + fu[None, None, :, None] / rb
    rz = np.clip(bz[:, :, None, None] + fz[None, None, None, :], -z_half, z_half)
    refined = flank_surface(wp, gear, datum, side, rxi, rz, teeth[:, None, None, None]).reshape(gear.teeth, -1, 3)
    out = []
    for t in range(gear.teeth):
        p = np.concatenate([pts[t], refined[t]])
        out.append(p[np.isfinite(p).all(axis=1)])
    return out


def measure_span(wp: Workpiece, gear: Gear, datum: Datum, k: int, z_half: float) -> np.ndarray:
    """W_k [mm] for every group of k teeth (row i starts at nominal tooth i); external gears only. The anvils
    touch within |z| <= ``z_half`` of mid face."""
    d_c = nominal.span_contact_diameter(gear, k)
    xi_c = math.sqrt(max((d_c / 2) ** 2 - gear.base_radius**2, 0.0)) / gear.base_radius
    right = _scan(wp, gear, datum, "right", xi_c, z_half, -1.0, k)
    left = _scan(wp, gear, datum, "left", xi_c, z_half, 1.0, k)
    pitch = 2 * math.pi / gear.teeth
    tau0 = -math.atan(gear.base_radius * twist_rate(gear))  # anvil normal tilt on a helical gear
    out = np.full(gear.teeth, np.nan)
    for i in range(gear.teeth):
        a = right[i]
        b = left[(i + k - 1) % gear.teeth]
        if len(a) == 0 or len(b) == 0:
            continue
        phi_g = datum.rotation + (i + (k - 1) / 2) * pitch
        origin = np.array([math.cos(phi_g), math.sin(phi_g), 0.0]) * gear.reference_radius
        a, b = a - origin, b - origin  # keeps the projections small: better conditioned

        def width(x: np.ndarray, a=a, b=b, phi_g=phi_g) -> float:
            phi, tau = phi_g + x[0], tau0 + x[1]
            n = np.array([-math.sin(phi) * math.cos(tau), math.cos(phi) * math.cos(tau), math.sin(tau)])
            return float((b @ n).max() - (a @ n).min())

        opts = {"xatol": 1e-10, "fatol": 1e-12, "maxiter": 2000}
        # the anvils rock by a few microradians on a real gear; beyond ROCK the contact would leave the scanned band
        # (it moves by rho * angle along the profile) and a plane slipping past the band's edge reads too little
        rock = ROLL_HALF / (2 * max(xi_c * gear.base_radius, ROLL_HALF))
        res = minimize(width, np.zeros(2), method="Nelder-Mead", bounds=[(-rock, rock)] * 2, options=opts)
        out[i] = res.fun
    return out
