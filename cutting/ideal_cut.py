"""The ideal reference cut of a job: exact kinematics, every pass, swept-volume removal, the gear mesh."""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass

import manifold3d as mf
import numpy as np
import trimesh

from cutting.edge import CuttingEdge, make_edge
from cutting.engine import cut_passes
from cutting.holder import check_holder_side
from cutting.removal import DEFAULT_SLAB, CutResult, expected_genus
from cutting.skiving import SkivingSetup
from cutting.trajectory import ideal_passes


@dataclass
class CutReport:
    result: CutResult
    edge: CuttingEdge
    seconds: float
    pass_seconds: list[float]
    stock_triangles: int
    pass_triangles: list[int]


def default_workers() -> int:
    """One worker process per core, at most 8."""
    return max(1, min(os.cpu_count() or 1, 8))


def cut_ideal(
    setup: SkivingSetup,
    edge_kind: str,
    finishing_tol: float,
    roughing_tol: float,
    progress: Callable[[int, int, int], None] | None = None,
    workers: int | None = None,
    slab: float = DEFAULT_SLAB,
    motions: list | None = None,
) -> CutReport:
    """Cut every pass with the ideal motion, or along ``motions`` (e.g. a simulated machine's sampled passes,
    cutting.sampled_motion). ``progress(pass_index, done, total)`` reports tooth passages."""
    t_start = time.perf_counter()
    edge = make_edge(setup, edge_kind)
    motions = ideal_passes(setup) if motions is None else motions
    check_holder_side(motions, edge, setup.cutter.face_width, setup.holder_diameter_value)
    tols = [finishing_tol if m.index == len(setup.passes) - 1 else roughing_tol for m in motions]
    run = cut_passes(setup.gear, edge, motions, tols, workers or default_workers(), slab, progress)
    result = run.result
    if result.gear.status() != mf.Error.NoError or result.gear.is_empty():
        raise RuntimeError(f"the removal left no valid solid ({result.gear.status()})")
    if result.gear.genus() != expected_genus(setup.gear):
        raise RuntimeError(
            f"the removal left a solid of genus {result.gear.genus()} (a gear has {expected_genus(setup.gear)}): "
            "voids or tunnels where the stock's cells meet; report it with the job (the cells' union is at fault)"
        )
    return CutReport(
        result, edge, time.perf_counter() - t_start, run.pass_seconds, run.stock_triangles, run.pass_triangles
    )


def to_trimesh(solid: mf.Manifold) -> trimesh.Trimesh:
    m = solid.to_mesh64()
    return trimesh.Trimesh(np.asarray(m.vert_properties)[:, :3], np.asarray(m.tri_verts), process=False)
