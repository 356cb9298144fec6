"""The ideal reference cut of a job: exact kinematics, every pass, swept-volume removal, the gear mesh."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import manifold3d as mf
import numpy as np
import trimesh

from cutting.edge import CuttingEdge, make_edge
from cutting.removal import CutResult, Stock, cut
from cutting.skiving import SkivingSetup
from cutting.trajectory import ideal_passes


@dataclass
class CutReport:
    result: CutResult
    edge: CuttingEdge
    seconds: float
    pass_seconds: list[float]


def cut_ideal(
    setup: SkivingSetup,
    edge_kind: str,
    finishing_tol: float,
    roughing_tol: float,
    progress: Callable[[int, int, int], None] | None = None,
) -> CutReport:
    """Cut every pass with the ideal motion. ``progress(pass_index, done, total)`` is called per tooth passage."""
    t_start = time.perf_counter()
    edge = make_edge(setup, edge_kind)
    stock = Stock(setup.gear)
    result = CutResult(None)
    motions = ideal_passes(setup)
    pass_seconds = []
    for motion in motions:
        last = motion.index == len(motions) - 1
        t0 = time.perf_counter()
        cb = None if progress is None else (lambda d, n, i=motion.index: progress(i, d, n))
        cut(stock, edge, motion, finishing_tol if last else roughing_tol, result, cb)
        pass_seconds.append(time.perf_counter() - t0)
    result.gear = stock.solid()
    if result.gear.status() != mf.Error.NoError or result.gear.is_empty():
        raise RuntimeError(f"the removal left no valid solid ({result.gear.status()})")
    return CutReport(result, edge, time.perf_counter() - t_start, pass_seconds)


def to_trimesh(solid: mf.Manifold) -> trimesh.Trimesh:
    m = solid.to_mesh64()
    return trimesh.Trimesh(np.asarray(m.vert_properties)[:, :3], np.asarray(m.tri_verts), process=False)
