"""Span measurement W_k on the mesh: two parallel anvil planes over k teeth, rocked to the minimum.

The anvils touch the outer flanks of k consecutive teeth (the right flank of the first, the left flank of
the last, counting counter-clockwise). For a plane direction n the width is
max(n . p, last tooth's left flank) - min(n . p, first tooth's right flank); the measured W_k is the
minimum over n (the micrometer is rocked until it reads least), searched around the nominal normal
(the base tangent, tilted by the base helix angle for helical gears). The support of a triangle mesh
is attained at its vertices, so using the flank vertices is exact for the mesh.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize

from cutting.flank import flank_polar_angle, side_sign, twist_rate
from cutting.gear import Gear
from metrology.datum import Datum
from metrology.sections import MeshData


def flank_vertices(mesh: MeshData, gear: Gear, datum: Datum, side: str, r_lo: float, r_hi: float):
    """Vertices near the nominal ``side`` flanks between radii r_lo..r_hi, with their nominal tooth index."""
    v = mesh.vertices
    r = mesh.radius
    zr = v[:, 2] - datum.z_mid
    band = (r >= r_lo) & (r <= r_hi)
    theta = np.arctan2(v[:, 1], v[:, 0])
    pitch = 2 * math.pi / gear.teeth
    d = theta - flank_polar_angle(gear, np.maximum(r, gear.base_radius), zr, side, 0) - datum.rotation
    k = np.round(d / pitch)
    e = side_sign(gear, side) * gear.base_radius * (d - k * pitch)
    sel = band & (np.abs(e) < 0.25 * gear.mn * math.pi / 2)
    return v[sel], k[sel].astype(int) % gear.teeth


def measure_span(mesh: MeshData, gear: Gear, datum: Datum, k: int, r_lo: float, r_hi: float) -> np.ndarray:
    """W_k [mm] for every group of k teeth (row i starts at nominal tooth i); external gears only."""
    right, k_right = flank_vertices(mesh, gear, datum, "right", r_lo, r_hi)
    left, k_left = flank_vertices(mesh, gear, datum, "left", r_lo, r_hi)
    pitch = 2 * math.pi / gear.teeth
    tau0 = -math.atan(gear.base_radius * twist_rate(gear))  # anvil normal tilt on a helical gear
    out = np.full(gear.teeth, np.nan)
    for i in range(gear.teeth):
        a = right[k_right == i]
        b = left[k_left == (i + k - 1) % gear.teeth]
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
        res = minimize(width, np.zeros(2), method="Nelder-Mead", options=opts)
        out[i] = res.fun
    return out
