"""Collision of the cutter's holder side with the blank: the hub behind the teeth and the spindle holder.

Only the teeth may enter the workpiece. Behind the rake face the cutter is a hub (inside the edge's lowest
radius, ``r_low``) of the cutter's width, then the holder (arbor nut or shank) of ``holder_diameter``. Both
are solids of revolution about the cutter axis, so only the carriage position and centre distance matter:
the check samples their surfaces along every pass and tests them against the blank, which contains
whatever the cut leaves. A point inside the blank is a collision the machine would make.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from cutting.errors import InputError, Problem
from cutting.skiving.edge import CuttingEdge
from cutting.skiving.sweep import place
from cutting.skiving.trajectory import PassMotion

#: Length of the holder checked behind the cutter body [mm]: a spindle nose is rarely longer.
HOLDER_LENGTH = 150.0


def holder_side_points(r_hub: float, width: float, r_holder: float, length: float = HOLDER_LENGTH) -> np.ndarray:
    """Surface points (n, 3) in the cutter frame of the hub (z = -width .. 0) and holder (behind it)."""
    ang = np.linspace(0.0, 2 * math.pi, 121)[:-1]  # 3 deg
    ring = np.column_stack([np.cos(ang), np.sin(ang)])

    def rings(radius: float, z: np.ndarray) -> np.ndarray:
        return np.column_stack([np.tile(ring * radius, (len(z), 1)), np.repeat(z, len(ang))])

    pts = [
        rings(r_hub, np.linspace(-width, 0.0, max(2, int(width / 0.5) + 1))),
        rings(r_holder, np.linspace(-width - length, -width, max(2, int(length / 2.0) + 1))),
    ]
    for radius, z in ((r_hub, 0.0), (max(r_hub, r_holder), -width), (r_holder, -width - length)):
        for r in np.linspace(0.0, radius, 12)[1:]:
            pts.append(rings(r, np.array([z])))
    return np.vstack(pts)


def check_holder_side(
    motions: Sequence[PassMotion], edge: CuttingEdge, width: float, holder_diameter: float, samples: int = 150
) -> None:
    """Raise InputError if the hub or the holder enters the blank during any pass.

    ``width``: the cutter body behind the rake face [mm]; ``holder_diameter`` [mm]. Margin 1 um. The surfaces
    are sampled every 3 deg, 0.5 mm (hub) and 2 mm (holder), the carriage at ``samples`` positions per pass:
    an intrusion shallower than the sagitta of that grid (about 0.1 % of the holder radius) can pass.
    """
    if not motions:
        return
    g = motions[0].setup.gear
    r_tip, b2, eps = g.tip_radius, g.face_width / 2, 1e-3
    r_outer = g.root_radius + 3 * g.mn  # the ring's outside (cutting.skiving.solids.blank)
    pts = holder_side_points(edge.r_low, width, holder_diameter / 2)
    hub = (pts[:, 2] > -width - 1e-9) & (np.hypot(pts[:, 0], pts[:, 1]) <= edge.r_low + 1e-9)  # for the message
    for motion in motions:
        t = np.linspace(0.0, motion.duration, samples)
        rot, trans = motion.pose(t)
        w = place(pts, rot, trans)
        r = np.hypot(w[..., 0], w[..., 1])
        in_face = np.abs(w[..., 2]) < b2 - eps
        inside = in_face & ((r > r_tip + eps) & (r < r_outer - eps) if g.internal else (r < r_tip - eps))
        if not inside.any():
            continue
        i, k = np.unravel_index(int(np.argmax(inside)), inside.shape)
        depth = float(np.where(inside, (r - r_tip) if g.internal else (r_tip - r), 0.0).max())
        where = f"pass {motion.index + 1} at carriage s = {motion.carriage(t[i]):+.2f} mm"
        if hub[k]:
            raise InputError(
                Problem(
                    "cutter.tip_diameter",
                    round(edge.r_tip * 2, 4),
                    f"the cutter hub (inside the teeth, r < {edge.r_low:.3f} mm) enters the blank by up to "
                    f"{depth * 1e3:.0f} um in {where}",
                    "use a cutter with deeper teeth (larger tip diameter for the same root) or shallower passes",
                )
            )
        raise InputError(
            Problem(
                "cutter.holder_diameter",
                holder_diameter,
                f"the cutter holder ({width:.1f} mm behind the rake face) enters the blank by up to "
                f"{depth * 1e3:.0f} um in {where}",
                "use a slimmer holder, a wider cutter body (cutter.width) or a smaller shaft angle",
            )
        )
