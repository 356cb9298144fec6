"""The relieved teeth behind the rake face held against the gear each pass leaves, over the whole mesh: the body of a
cutter tooth must not enter the finished teeth anywhere from entry to exit (for a ring gear: its meshing
interference, the cutter's teeth meeting the ring's teeth as they roll in and out).

The edge is designed not to enter the nominal teeth (:func:`cutting.skiving.edge.conjugate_edge` clears its tip
corners); the tooth behind it is the relieved cutter (:class:`cutting.skiving.working_angles.Relief`): at an axial
depth delta behind each edge point the section of the cutter with its profile shift smaller by delta tan(alpha_a) / mn
(the point's flank turned by the helix to that depth, its design departure kept), its tip delta tan(alpha_a) lower.
Those points, at depths from 10 um to the cutter's face width, go through the mesh with the ideal kinematics (the
cutter turned over half a turn either side of the mesh), and their deepest intrusion into the finished gear's teeth
(involute band, form circle to tip, as :func:`cutting.skiving.edge.tooth_intrusion` measures it) is the body's
interference. Where the working clearance at the generating contacts is positive the relief keeps the body off the
flank by about delta tan(alpha_s) (the side clearance: 6.9 um at 0.2 mm behind the default job's edge); an
unrelieved cutter on the default job enters its flank by 0.83 um at 1 mm behind the left edge.

The relieved body does meet material: the stock the next passages remove, where the cutting direction at the
tooth's tip runs far off the tooth direction (docs/cutter.md, "The body behind the edge"). That is rubbing on the
transient surface, not damage to the gear, and is reported, not refused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from cutting.errors import InputError, Problem
from cutting.flank import flank_polar_angle, tooth_centre_angle
from cutting.gear import Gear
from cutting.skiving.edge import CuttingEdge, make_edge, tooth_intrusion
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.tooling import inverse
from cutting.skiving.working_angles import Relief, edge_frames, pass_setup

#: an intrusion this deep [mm] is an interference (the edge itself is cleared to 1e-7 mm)
TOLERANCE = 1e-4
#: cutter angles over the mesh, half a turn either side (600 against 1500: the same deepest intrusion to 0.005 um on
#: the shipped jobs)
ANGLES = 600


@dataclass(frozen=True)
class RelievedPoints:
    """Points of the relieved tooth behind the edge, in the rake frame (n, 3), with the axial depth behind the face
    [mm], the edge part and position along the edge [mm] of the edge point each lies behind."""

    points: np.ndarray
    depth: np.ndarray
    part: np.ndarray
    position: np.ndarray


def body_depths(setup: SkivingSetup) -> np.ndarray:
    """Axial depths [mm] behind the face to sample the tooth at: geometric from 10 um to the cutter's face width."""
    width = max(float(setup.cutter.face_width), 0.02)
    return np.geomspace(0.01, width, 12)


def relieved_cutter(setup: SkivingSetup, depth: float) -> tuple[Gear, float]:
    """The cutter's section ``depth`` [mm] behind the rake face under the conical relief: the cutter with its profile
    shift reduced by the tip's drop d tan(alpha_a) / mn, and that drop [mm]."""
    c = setup.cutter
    drop = depth * math.tan(setup.rake.clearance_angle)
    return replace(c, profile_shift=c.x - drop / c.mn), drop


def relieved_points(setup: SkivingSetup, edge: CuttingEdge, depths: np.ndarray) -> RelievedPoints:
    """The relieved tooth behind every edge point at ``depths`` (see the module docstring)."""
    c, q = setup.cutter, setup.rake_frame
    frames = edge_frames(setup, edge, Relief.of(setup))
    p = frames.points @ q[:, :3].T + q[:, 3]  # the edge in the cutter's frame
    rho, theta = np.hypot(p[:, 0], p[:, 1]), np.arctan2(p[:, 1], p[:, 0])
    rho_eff = np.maximum(rho, c.base_radius)  # radial below the base circle
    ra0 = setup.cutter_tip_diameter / 2
    pts, dep, part, pos = [], [], [], []
    for d in depths:
        relieved, drop = relieved_cutter(setup, d)
        z = p[:, 2] + setup.body_side * d
        for name in ("left", "right", "tip"):
            sel = frames.part == name
            if name == "tip":
                r = rho[sel] - drop
                th = theta[sel] + tooth_centre_angle(c, 0, z[sel]) - tooth_centre_angle(c, 0, p[sel, 2])
            else:
                sel = sel & (rho < ra0 - drop)  # under the relieved tip
                r = rho[sel]
                th = theta[sel] + (
                    flank_polar_angle(relieved, rho_eff[sel], z[sel], name)
                    - flank_polar_angle(c, rho_eff[sel], p[sel, 2], name)
                )
            pts.append(np.stack([r * np.cos(th), r * np.sin(th), z[sel]], -1))
            dep.append(np.full(int(sel.sum()), d))
            part.append(frames.part[sel])
            pos.append(frames.position[sel])
    back = inverse(q)
    cutter_frame = np.concatenate(pts)
    return RelievedPoints(
        cutter_frame @ back[:, :3].T + back[:, 3], np.concatenate(dep), np.concatenate(part), np.concatenate(pos)
    )


def body_interference(setup: SkivingSetup, edge: CuttingEdge) -> dict:
    """The relieved tooth's deepest intrusion [mm] into the finished gear's teeth (the last pass's: the stock earlier
    passes leave is the next pass's to cut; the ring gear's teeth meet the cutter's deepest at the final centre
    distance) over the whole mesh, negative for its least clearance, and where: {"body_intrusion_max_mm",
    "depth_mm", "edge", "edge_position_mm"}.

    A cutter's profile deviations are ground on its relieved flanks at every depth (docs/cutter.md, "Regrind"): they
    move the edge, the body behind it and the flank they generate alike, so the clearance is the design's, held
    with the edge as designed (held against the nominal teeth, a deviation of more tool material would read as an
    intrusion of its own size)."""
    if setup.cutter_errors.profile:
        errors = replace(setup.cutter_errors, profile_slope=(0.0, 0.0), profile_form=(0.0, 0.0))
        setup = replace(setup, cutter_errors=errors)
        edge = make_edge(setup, edge.kind)
    body = relieved_points(setup, edge, body_depths(setup))
    grid = np.linspace(-0.5 * math.pi, 0.5 * math.pi, ANGLES)
    depth = tooth_intrusion(pass_setup(setup, len(setup.passes) - 1), body.points, grid)
    j = int(np.argmax(depth))
    return {
        "body_intrusion_max_mm": float(depth[j]),
        "depth_mm": float(body.depth[j]),
        "edge": str(body.part[j]),
        "edge_position_mm": float(body.position[j]),
    }


def check_body_interference(setup: SkivingSetup, edge: CuttingEdge, source: str = "job") -> dict:
    """:func:`body_interference`, refused (InputError) where the relieved tooth enters the finished teeth."""
    p = body_interference(setup, edge)
    if p["body_intrusion_max_mm"] > TOLERANCE:
        raise InputError(
            [
                Problem(
                    "cutter.clearance_angle",
                    round(math.degrees(setup.rake.clearance_angle), 3),
                    f"the relieved tooth {p['depth_mm']:.2f} mm behind the {p['edge']} edge "
                    f"({p['edge_position_mm']:.2f} mm along it) enters the finished teeth by "
                    f"{p['body_intrusion_max_mm'] * 1e3:.2f} um as it goes through the mesh: the cutter's body would "
                    "cut the flank",
                    "raise cutter.clearance_angle, or change the shaft angle (cutter.helix_angle) or "
                    "cutter.rake_face_offset; a ring gear: fewer cutter teeth",
                )
            ],
            source,
        )
    return p
