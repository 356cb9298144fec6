"""The ideal reference cut of a job: exact kinematics, every pass, swept-volume removal, the gear mesh."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import manifold3d as mf
import numpy as np
import trimesh

from cutting.parallel import default_workers
from cutting.skiving.dexel_cut import cut_dexel
from cutting.skiving.dexel_lines import DexelSpacing
from cutting.skiving.edge import CuttingEdge, make_edge
from cutting.skiving.engine import cut_passes
from cutting.skiving.holder import check_holder_side
from cutting.skiving.interference import check_body_interference
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.passages import CutResult, expected_genus
from cutting.skiving.removal import DEFAULT_SLAB
from cutting.skiving.trajectory import ideal_passes
from cutting.skiving.working_angles import check_working_clearance


@dataclass
class CutReport:
    result: CutResult
    edge: CuttingEdge
    seconds: float
    pass_seconds: list[float]
    stock_triangles: int
    pass_triangles: list[int]
    removal: dict = field(default_factory=lambda: {"kind": "manifold"})  # how the removal went (dexel: its figures)


#: the removals: the dexel workpiece (default), or manifold3d booleans passage by passage (the reference)
REMOVALS = ("dexel", "manifold")


def cut_ideal(
    setup: SkivingSetup,
    edge_kind: str,
    finishing_tol: float,
    roughing_tol: float,
    progress: Callable[[int, int, int], None] | None = None,
    workers: int | None = None,
    slab: float = DEFAULT_SLAB,
    motions: list | None = None,
    removal: str = "dexel",
    spacing: DexelSpacing | None = None,
) -> CutReport:
    """Cut every pass with the ideal motion, or along ``motions`` (e.g. a simulated machine's sampled passes,
    cutting.skiving.sampled_motion). ``progress(pass_index, done, total)`` reports tooth passages. ``removal``: "dexel"
    (``spacing``: the lines, default the gear's) or "manifold" (``finishing_tol``/``roughing_tol``: the tubes' sweep
    errors, ``workers``, ``slab``); the dexel solid is stated to be within ``finishing_tol`` of the exact surface."""
    t_start = time.perf_counter()
    edge = make_edge(setup, edge_kind)
    motions = ideal_passes(setup) if motions is None else motions
    check_holder_side(motions, edge, setup.cutter.face_width, setup.holder_diameter_value)
    check_working_clearance(setup, edge)  # the relieved flank off the flank it generates
    check_body_interference(setup, edge)  # and the relieved tooth off the finished teeth over the whole mesh
    if removal not in REMOVALS:
        raise ValueError(f"removal {removal!r}: use one of {', '.join(REMOVALS)}")
    if removal == "dexel":
        spacing = spacing or DexelSpacing.for_gear(setup.gear, setup.axial_feed)
        dexel = cut_dexel(setup.gear, edge, motions, spacing, finishing_tol, progress)
        _check_solid(dexel.result, setup)
        solid_tris = dexel.result.gear.num_tri()
        return CutReport(
            dexel.result,
            edge,
            time.perf_counter() - t_start,
            dexel.pass_seconds,
            solid_tris,
            [solid_tris] * len(motions),
            dexel.summary(),
        )
    tols = [finishing_tol if m.index == len(setup.passes) - 1 else roughing_tol for m in motions]
    run = cut_passes(setup.gear, edge, motions, tols, workers or default_workers(), slab, progress)
    result = run.result
    _check_solid(result, setup)
    return CutReport(
        result, edge, time.perf_counter() - t_start, run.pass_seconds, run.stock_triangles, run.pass_triangles
    )


def _check_solid(result: CutResult, setup: SkivingSetup) -> None:
    if result.gear.status() != mf.Error.NoError or result.gear.is_empty():
        raise RuntimeError(f"the removal left no valid solid ({result.gear.status()})")
    if result.gear.genus() != expected_genus(setup.gear):
        raise RuntimeError(
            f"the removal left a solid of genus {result.gear.genus()} (a gear has {expected_genus(setup.gear)}): "
            "voids or tunnels in the solid; report it with the job"
        )


def to_trimesh(solid: mf.Manifold) -> trimesh.Trimesh:
    m = solid.to_mesh64()
    return trimesh.Trimesh(np.asarray(m.vert_properties)[:, :3], np.asarray(m.tri_verts), process=False)
