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
from cutting.skiving.trajectory import PassMotion

#: Length of the holder checked behind the cutter body [mm]: a spindle nose is rarely longer.
HOLDER_LENGTH = 150.0


#: points per ring of the sampled surfaces (every 3 deg)
RING_POINTS = 120


def holder_side_rings(r_hub: float, width: float, r_holder: float, length: float = HOLDER_LENGTH) -> np.ndarray:
    """The sampled surfaces of the hub (z = -width .. 0) and holder (behind it) as rings about the cutter axis:
    rows (radius, z) in the cutter frame, the hub's rings first, then the holder's, then the end faces'."""
    rings = [(r_hub, z) for z in np.linspace(-width, 0.0, max(2, int(width / 0.5) + 1))]
    rings += [(r_holder, z) for z in np.linspace(-width - length, -width, max(2, int(length / 2.0) + 1))]
    for radius, z in ((r_hub, 0.0), (max(r_hub, r_holder), -width), (r_holder, -width - length)):
        rings += [(r, z) for r in np.linspace(0.0, radius, 12)[1:]]
    return np.array(rings)


def holder_side_points(r_hub: float, width: float, r_holder: float, length: float = HOLDER_LENGTH) -> np.ndarray:
    """Surface points (n, 3) in the cutter frame of the hub and holder, ring by ring (:func:`holder_side_rings`)."""
    rings = holder_side_rings(r_hub, width, r_holder, length)
    ang = np.linspace(0.0, 2 * math.pi, RING_POINTS + 1)[:-1]
    x = rings[:, :1] * np.cos(ang)[None, :]
    y = rings[:, :1] * np.sin(ang)[None, :]
    return np.stack([x, y, np.broadcast_to(rings[:, 1:], x.shape)], axis=-1).reshape(-1, 3)


def check_holder_side(
    motions: Sequence[PassMotion], edge: CuttingEdge, width: float, holder_diameter: float, samples: int = 150
) -> None:
    """Raise InputError if the hub or the holder enters the blank during any pass.

    ``width``: the cutter body behind the rake face [mm]; ``holder_diameter`` [mm]. Margin 1 um. The surfaces
    are sampled every 3 deg, 0.5 mm (hub) and 2 mm (holder), the carriage at ``samples`` positions per pass:
    an intrusion shallower than the sagitta of that grid (about 0.1 % of the holder radius) can pass. Only the
    rings whose circle can reach the blank in a pose (by its centre's position and its radius) are placed.
    """
    if not motions:
        return
    setup = motions[0].setup
    g = setup.gear
    r_tip, b2, eps = g.tip_radius, g.face_width / 2, 1e-3
    r_outer = g.root_radius + 3 * g.mn  # the ring's outside (cutting.skiving.solids.blank)
    rings = holder_side_rings(edge.r_low, width, holder_diameter / 2)
    pts = holder_side_points(edge.r_low, width, holder_diameter / 2).reshape(len(rings), RING_POINTS, 3)
    # the body behind the rake face: on -z of the cutter frame for an external job, on +z for an internal one;
    # from the rake face's place along the axis (at the hub: a rake angle lowers the face inwards)
    flip, shift = -setup.body_side, setup.face_height(edge.r_low)
    rings = np.column_stack([rings[:, 0], flip * rings[:, 1] + shift])
    pts = pts * np.array([1.0, 1.0, flip]) + np.array([0.0, 0.0, shift])
    hub = (flip * (rings[:, 1] - shift) > -width - 1e-9) & (rings[:, 0] <= edge.r_low + 1e-9)  # for the message
    for motion in motions:
        t = np.linspace(0.0, motion.duration, samples)
        rot, trans = motion.pose(t)
        # each ring's centre in every pose: a circle of radius R about it stays within R of it
        centre = rot[:, :, 2][:, None, :] * rings[None, :, 1:] + trans[:, None, :]
        rc, radius = np.hypot(centre[..., 0], centre[..., 1]), rings[None, :, 0]
        near = np.abs(centre[..., 2]) < b2 + radius
        if g.internal:
            near &= (rc + radius > r_tip) & (rc - radius < r_outer)
        else:
            near &= rc - radius < r_tip
        i_near, k_near = np.nonzero(near)  # row-major: by pose, then ring (the points' order)
        if not len(i_near):
            continue
        w = np.einsum("nab,npb->npa", rot[i_near], pts[k_near]) + trans[i_near][:, None, :]
        r = np.hypot(w[..., 0], w[..., 1])
        in_face = np.abs(w[..., 2]) < b2 - eps
        inside = in_face & ((r > r_tip + eps) & (r < r_outer - eps) if g.internal else (r < r_tip - eps))
        if not inside.any():
            continue
        first = int(np.argmax(inside.any(axis=1)))
        i, k = int(i_near[first]), int(k_near[first])
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
