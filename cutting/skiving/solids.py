"""Blank and cutter solids (manifold3d), in the work frame and the cutter frame respectively."""

from __future__ import annotations

import manifold3d as mf

from cutting.gear import Gear

CIRCLE_SEGMENTS = 720


def blank(gear: Gear, rim: float | None = None) -> mf.Manifold:
    """External: a cylinder at the tip diameter; internal: a ring whose bore is the tip diameter.

    The face spans z = -b/2 .. +b/2; an internal ring's outside is the root diameter plus ``rim`` (3 mn).
    """
    b = gear.face_width
    if gear.internal:
        outer = gear.root_radius + (3 * gear.mn if rim is None else rim)
        ring = mf.CrossSection.circle(outer, CIRCLE_SEGMENTS) - mf.CrossSection.circle(gear.tip_radius, CIRCLE_SEGMENTS)
        return mf.Manifold.extrude(ring, b).translate((0.0, 0.0, -b / 2))
    return mf.Manifold.cylinder(b, gear.tip_radius, gear.tip_radius, CIRCLE_SEGMENTS).translate((0.0, 0.0, -b / 2))
