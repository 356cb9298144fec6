"""Blank and cutter solids (manifold3d), in the work frame and the cutter frame respectively."""

from __future__ import annotations

import math

import manifold3d as mf
import numpy as np

from cutting.gear import Gear
from cutting.skiving.edge import CuttingEdge

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


def cutter_solid(edge: CuttingEdge, teeth: int, length: float = 10.0, clearance_deg: float = 6.0) -> mf.Manifold:
    """The cutter: z0 teeth of the edge outline on the rake face z = 0, relieved behind it.

    The teeth are extruded away from the rake face (towards -z) and shrink radially by tan(clearance) per mm,
    the clearance behind the cutting edge. For viewing and collision checks; the edge alone removes material.
    """
    teeth_cs = mf.CrossSection.circle(edge.r_low * 1.01, CIRCLE_SEGMENTS)
    for k in range(teeth):
        a = 2 * math.pi * k / teeth
        rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
        teeth_cs = teeth_cs + mf.CrossSection([edge.outline @ rot.T])
    shrink = 1 - length * math.tan(math.radians(clearance_deg)) / edge.r_tip
    body = mf.Manifold.extrude(teeth_cs, length, scale_top=(shrink, shrink))
    return body.mirror((0.0, 0.0, 1.0))  # extrude goes to +z: mirror behind the rake face
