"""Profile and helix traces: the probe moved along the nominal flank and touching the workpiece along its normal.

A profile trace runs in a transverse section at chosen roll lengths, a helix trace on a cylinder at chosen
heights; at each point the probe touches along the flank normal and reads the normal deviation, converted to the
deviation along the base tangent in the transverse plane (:func:`metrology.workpiece.flank_deviation`):

    e = d_normal / cos(beta_b)      [mm, excess material > 0]

Both return arrays (teeth, points) in nominal tooth index order, NaN where the probe found no flank.
"""

from __future__ import annotations

import numpy as np

from cutting.flank import SIDES
from cutting.gear import Gear
from metrology.datum import Datum
from metrology.workpiece import Workpiece, flank_deviation


def _roll_angle(gear: Gear, radius) -> np.ndarray:
    return np.sqrt(np.maximum(np.asarray(radius, dtype=float) ** 2 - gear.base_radius**2, 0.0)) / gear.base_radius


def profile_trace(wp: Workpiece, gear: Gear, datum: Datum, z_rel: float, radii: np.ndarray) -> dict[str, np.ndarray]:
    """Deviations e[side] of shape (z, len(radii)) [mm] in the transverse section at ``z_rel`` from mid face."""
    xi = _roll_angle(gear, radii)[None, :]
    teeth = np.arange(gear.teeth)[:, None]
    return {side: flank_deviation(wp, gear, datum, side, xi, z_rel, teeth) for side in SIDES}


def helix_trace(wp: Workpiece, gear: Gear, datum: Datum, radius: float, z_rel: np.ndarray) -> dict[str, np.ndarray]:
    """Deviations e[side] of shape (z, len(z_rel)) [mm] on the cylinder ``radius`` at heights ``z_rel``."""
    xi = _roll_angle(gear, radius)
    teeth = np.arange(gear.teeth)[:, None]
    return {side: flank_deviation(wp, gear, datum, side, xi, np.asarray(z_rel)[None, :], teeth) for side in SIDES}
