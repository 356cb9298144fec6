"""Cutting a sequence of passes, in parallel over the tooth spaces.

The cells of different tooth spaces never share a boolean (a cutter tooth in a space meets only that space's
sector: the sectors meet on the tooth centre lines, which no sweep reaches), so the spaces are split between
worker processes, each running every pass on its own share of the stock. The result does not depend on the
number of workers: each cell sees the same subtractions in the same order. manifold3d holds the GIL during a
boolean, so threads would not help; processes do.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import tempfile
import time
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_EXCEPTION, ProcessPoolExecutor, wait
from dataclasses import dataclass, field

import numpy as np

from cutting.gear import Gear
from cutting.skiving.edge import CuttingEdge
from cutting.skiving.passages import CutResult, passage_count
from cutting.skiving.removal import DEFAULT_SLAB, Stock, cut, from_arrays, to_arrays
from cutting.skiving.trajectory import PassMotion

#: progress(pass_index, passages_done, passages_total)
Progress = Callable[[int, int, int], None]


@dataclass
class EngineResult:
    result: CutResult
    stock_triangles: int
    pass_seconds: list[float]
    pass_triangles: list[int]  # stock triangles after each pass: bounded by the cut surface, not the booleans
    stage_seconds: dict[str, float] = field(default_factory=dict)  # cut (with column unions), collect, union


def cut_passes(
    gear: Gear,
    edge: CuttingEdge,
    motions: Sequence[PassMotion],
    tolerances: Sequence[float],
    workers: int = 1,
    slab: float = DEFAULT_SLAB,
    progress: Progress | None = None,
) -> EngineResult:
    """Cut every pass in order on a fresh blank; ``result.gear`` is the union of the sector columns.

    ``workers`` > 1 runs that many processes, each owning a contiguous share of the tooth spaces.
    """
    t_start = time.perf_counter()
    if workers <= 1:
        stock = Stock(gear, slab=slab)
        result = CutResult(None)

        def report(position: int) -> Callable[[int, int], None] | None:
            return None if progress is None else (lambda d, n: progress(motions[position].index, d, n))

        pass_seconds, pass_triangles = _run_passes(stock, edge, motions, tolerances, result, report)
        t_cut = time.perf_counter()
        result.finish_columns(list(stock.columns().values()))
        stages = {"cut": t_cut - t_start, "collect": 0.0, "union": time.perf_counter() - t_cut}
        return EngineResult(result, stock.triangles(), pass_seconds, pass_triangles, stages)

    ctx = mp.get_context("spawn")  # a fork would copy manifold's thread pool state
    done = ctx.Array("i", len(motions))
    totals = [passage_count(m, edge) for m in motions]
    # contiguous shares: a passage is sampled by every worker whose spaces it can reach, so interleaved shares
    # (every space's neighbours owned by the other worker) would have every worker sample nearly every passage
    shares = [[int(k) for k in part] for part in np.array_split(np.arange(gear.teeth), workers)]
    with (
        tempfile.TemporaryDirectory(prefix="skive-cut-") as tmp,
        ProcessPoolExecutor(workers, mp_context=ctx, initializer=_init_worker, initargs=(done,)) as pool,
    ):
        futures = [pool.submit(_worker, gear, edge, list(motions), list(tolerances), slab, s, tmp) for s in shares]
        while True:
            finished, pending = wait(futures, timeout=0.25, return_when=FIRST_EXCEPTION)
            if progress is not None:
                for i, total in enumerate(totals):
                    progress(motions[i].index, min(done[i] // workers, total), total)
            if not pending or any(f.exception() for f in finished):
                break
        parts = [f.result() for f in futures]
        t_cut = time.perf_counter()
        # the workers' sector columns, written to files (a pipe would copy hundreds of MB per worker)
        columns = [from_arrays(*_load(path)) for p in parts for path in p[1]]
    t_collect = time.perf_counter()
    result = CutResult(None)
    first = parts[0][0]
    for chip_index, chip in enumerate(first.chips):
        # each worker cut its share of the chip; the passage was sampled by the workers it can reach
        chip.volume = sum(p[0].chips[chip_index].volume for p in parts)
        chip.sweeps = max(p[0].chips[chip_index].sweeps for p in parts)
        result.chips.append(chip)
    result.sweep_error = max(p[0].sweep_error for p in parts)
    for p in parts:
        for index, err in p[0].pass_sweep_error.items():
            result.pass_sweep_error[index] = max(result.pass_sweep_error.get(index, 0.0), err)
    result.sweeps = sum(chip.sweeps for chip in result.chips)
    result.subtractions = sum(p[0].subtractions for p in parts)
    result.finish_columns(columns)
    stages = {"cut": t_cut - t_start, "collect": t_collect - t_cut, "union": time.perf_counter() - t_collect}
    pass_seconds = [float(x) for x in np.max([p[2] for p in parts], axis=0)]
    pass_triangles = [int(x) for x in np.sum([p[3] for p in parts], axis=0)]
    return EngineResult(result, pass_triangles[-1], pass_seconds, pass_triangles, stages)


_DONE = None
_PARENT = None


def _init_worker(done) -> None:
    global _DONE, _PARENT
    _DONE, _PARENT = done, os.getppid()


def _run_passes(stock, edge, motions, tolerances, result, report) -> tuple[list[float], list[int]]:
    """Every pass in order on ``stock``; ``report(position)`` gives the progress callback of a pass.
    Returns the seconds of each pass and the stock's triangles after it."""
    pass_seconds, pass_triangles = [], []
    for position, (motion, tol) in enumerate(zip(motions, tolerances, strict=True)):
        t0 = time.perf_counter()
        cut(stock, edge, motion, tol, result, report(position))
        pass_seconds.append(time.perf_counter() - t0)
        pass_triangles.append(stock.triangles())
    return pass_seconds, pass_triangles


def _load(path: str) -> tuple[np.ndarray, np.ndarray, float]:
    with np.load(path) as f:
        return f["verts"], f["tris"], float(f["tolerance"])


def _worker(gear, edge, motions, tolerances, slab, sectors, tmp):
    """Cut every pass on the worker's sectors; unite each sector's slabs (in parallel with the other workers) and
    write the column to ``tmp``. Returns the worker's result (chips), the column files, the seconds and the stock
    triangles after each pass."""
    stock = Stock(gear, slab=slab, sectors=sectors)
    result = CutResult(None)

    def report(position: int) -> Callable[[int, int], None]:
        def tick(_done: int, _total: int) -> None:
            if os.getppid() != _PARENT:  # the parent was killed: do not cut on as an orphan
                os._exit(1)
            with _DONE.get_lock():
                _DONE[position] += 1

        return tick

    pass_seconds, pass_triangles = _run_passes(stock, edge, motions, tolerances, result, report)
    paths = []
    for k, column in stock.columns().items():
        verts, tris, tolerance = to_arrays(column)
        paths.append(os.path.join(tmp, f"column_{k}.npz"))
        np.savez(paths[-1], verts=verts, tris=tris, tolerance=tolerance)
    return result, paths, pass_seconds, pass_triangles
