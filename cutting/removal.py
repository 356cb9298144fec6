"""Swept-volume removal: the blank minus what the cutter teeth sweep along a pose trajectory.

The stock is kept as angular sectors (one per tooth space, twisted with the helix), so each subtraction
involves only the few sectors a tooth passage reaches and the cost follows what is cut, not the whole
blank. A tooth passage is the interval in which one cutter tooth crosses the mesh zone; its swept volume
is built whole as one tube (:mod:`cutting.sweep`), sampled to the allowed sweep error.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import manifold3d as mf
import numpy as np

from cutting.edge import CuttingEdge
from cutting.flank import twist_rate
from cutting.gear import Gear
from cutting.skiving import rot_z
from cutting.solids import blank
from cutting.sweep import outline_points, place, sample_window, tube
from cutting.trajectory import PassMotion


@dataclass
class Chip:
    """One tooth engagement: pass, cutter tooth, time at the mesh [s], removed volume [mm^3]."""

    pass_index: int
    cutter_tooth: int
    time: float
    volume: float
    sweeps: int


@dataclass
class CutResult:
    gear: mf.Manifold
    chips: list[Chip] = field(default_factory=list)
    sweep_error: float = 0.0  # largest chord deviation of the sweeps [mm]
    subtractions: int = 0
    sweeps: int = 0


class Stock:
    """The workpiece as twisted angular sectors, one per tooth space, boundaries on the tooth centre lines."""

    def __init__(self, gear: Gear, rim: float | None = None):
        self.gear = gear
        self.n = gear.teeth
        solid = blank(gear, rim)
        b = gear.face_width
        r_out = (gear.root_radius + 4 * gear.mn + (rim or 0)) * 1.5 if gear.internal else gear.tip_radius * 1.5
        pitch = 2 * math.pi / self.n
        twist = math.degrees(twist_rate(gear) * b)
        self.twist_rate = twist_rate(gear)
        divisions = 0 if twist == 0 else max(8, int(abs(twist) / 0.5))
        self.tiles: list[mf.Manifold] = []
        for k in range(self.n):
            a0, a1 = k * pitch, (k + 1) * pitch  # tooth centre k to tooth centre k+1: space k in the middle
            wedge = mf.CrossSection(
                [
                    np.array(
                        [
                            [0.0, 0.0],
                            [r_out * math.cos(a0), r_out * math.sin(a0)],
                            [r_out * math.cos(a1), r_out * math.sin(a1)],
                        ]
                    )
                ]
            )
            # extrude twists counter-clockwise with +z for positive degrees, like a right-hand helix
            prism = mf.Manifold.extrude(wedge, b + 2, n_divisions=divisions, twist_degrees=twist)
            prism = prism.translate((0.0, 0.0, -b / 2 - 1)).rotate(
                (0.0, 0.0, math.degrees(-self.twist_rate * (b / 2 + 1)))
            )
            tile = solid ^ prism
            tile.num_tri()
            self.tiles.append(tile)
        self.volumes = [t.volume() for t in self.tiles]

    def sectors(self, pts: np.ndarray) -> list[int]:
        """Indices of the sectors that points (n, 3) of the work frame reach (helix untwisted first)."""
        theta = np.arctan2(pts[:, 1], pts[:, 0]) - self.twist_rate * pts[:, 2]
        pitch = 2 * math.pi / self.n
        k = np.floor(theta / pitch).astype(int) % self.n
        return sorted(set(k.tolist()))

    def subtract(self, tool: mf.Manifold, sectors: Sequence[int]) -> float:
        """Remove ``tool`` from the given sectors; returns the removed volume [mm^3]."""
        removed = 0.0
        for k in sectors:
            cut = self.tiles[k] - tool
            v = cut.volume()  # evaluates the lazy boolean
            removed += self.volumes[k] - v
            self.tiles[k], self.volumes[k] = cut, v
        return removed

    def solid(self) -> mf.Manifold:
        return mf.Manifold.batch_boolean(self.tiles, mf.OpType.Add)


def engagement_half_angle(motion: PassMotion, edge: CuttingEdge) -> float:
    """Cutter rotation from the mesh [rad] beyond which no point of a tooth reaches the blank's radius range."""
    g = motion.setup.gear
    phi = np.linspace(-math.pi, math.pi, 3601)
    rot, trans = motion.setup.cutter_pose(phi, 0.0, motion.centre_distance)
    w = place(outline_points(edge.outline), rot, trans)
    r = np.hypot(w[..., 0], w[..., 1])
    inside = (r > g.tip_radius).any(axis=1) if g.internal else (r < g.tip_radius).any(axis=1)
    if not inside.any():
        raise ValueError(
            f"pass {motion.index + 1}: the cutter never reaches the blank at a = "
            f"{motion.centre_distance:.4f} mm; check process.passes and the cutter tip diameter"
        )
    return float(np.abs(phi[inside]).max()) + 0.02


def cut(
    stock: Stock,
    edge: CuttingEdge,
    motion: PassMotion,
    tol: float,
    result: CutResult,
    progress: Callable[[int, int], None] | None = None,
) -> None:
    """Run one pass of ``motion`` on ``stock``: every tooth passage swept to ``tol`` [mm] and subtracted."""
    setup = motion.setup
    z0 = setup.cutter.teeth
    g = setup.gear
    half = engagement_half_angle(motion, edge)
    dt = half / motion.omega0
    step = 2 * math.pi / z0 / motion.omega0  # one tooth pitch of the cutter
    m_first = math.ceil(-half / (2 * math.pi / z0))
    m_last = math.floor((motion.omega0 * motion.duration + half) / (2 * math.pi / z0))
    pts = outline_points(edge.outline)
    b2 = g.face_width / 2
    total = m_last - m_first + 1
    for count, m in enumerate(range(m_first, m_last + 1)):
        tm = m * step
        j = (-m) % z0  # the cutter tooth at the mesh at tm
        local = rot_z(2 * math.pi * j / z0)

        def pose(t: np.ndarray, local=local) -> tuple[np.ndarray, np.ndarray]:
            rot, trans = motion.pose(t)
            return np.einsum("nij,jk->nik", rot, local), trans

        t0, t1 = max(tm - dt, 0.0), min(tm + dt, motion.duration)
        if t1 <= t0:
            continue
        # keep the part of the window in which the tooth can meet the blank (radius and face), one sample wider
        probe = np.linspace(t0, t1, 65)
        w = place(pts, *pose(probe))
        r = np.hypot(w[..., 0], w[..., 1])
        meets = ((r > g.tip_radius) if g.internal else (r < g.tip_radius)) & (np.abs(w[..., 2]) <= b2)
        hit = np.nonzero(meets.any(axis=1))[0]
        if hit.size == 0:
            continue
        t0, t1 = probe[max(hit[0] - 1, 0)], probe[min(hit[-1] + 1, len(probe) - 1)]
        times, err = sample_window(pose, pts, t0, t1, tol)
        tool = tube(edge.outline, *pose(times))
        reach = place(pts, *pose(times)).reshape(-1, 3)
        sectors = stock.sectors(reach)
        vol = stock.subtract(tool, sectors)
        result.sweeps += len(times) - 1
        result.subtractions += len(sectors)
        result.sweep_error = max(result.sweep_error, err)
        result.chips.append(Chip(motion.index, j, tm, vol, len(times) - 1))
        if progress is not None:
            progress(count + 1, total)
