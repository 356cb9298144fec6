"""The removal side of the co-simulation: tooth passages submitted as the machine makes them, chips returned.

Three backends with one interface, and :class:`NoRemoval`, which cuts nothing. :class:`DexelRemoval` (the default)
cuts the passages on the dexel workpiece, a batch at a time, in this process (the kernel runs on every core). The
manifold removal (the reference) has :class:`InlineRemoval`, which cuts each passage at once in this process, and
:class:`ParallelRemoval` gives each worker process a share of the tooth spaces (as cutting.skiving.engine does): every
worker receives every passage and cuts the cells it owns, so a passage's chip is the sum of the workers' parts and
is finished when the slowest worker has done it. Workers take the passages in order (one queue each), so chips
finish in order. The result does not depend on the number of workers: each cell sees the same subtractions in
the same order.
"""

from __future__ import annotations

import math
import multiprocessing as mp
import queue
import traceback
from collections.abc import Sequence

import manifold3d as mf
import numpy as np

from cutting.gear import Gear
from cutting.skiving.dexel import DexelWorkpiece
from cutting.skiving.dexel_cut import chip_of
from cutting.skiving.dexel_lines import DexelSpacing, gear_phase
from cutting.skiving.dexel_solid import dexel_solid, stock_mesh
from cutting.skiving.edge import CuttingEdge
from cutting.skiving.exact_sweep import PassTable, tooth_spread
from cutting.skiving.passages import Chip, CutResult, blank_window_of, engagement_half_angle
from cutting.skiving.removal import PassCutter, Stock, from_arrays, to_arrays
from cutting.skiving.sampled_motion import SampledMotion
from cutting.skiving.sweep import outline_points, simplify_outline
from cutting.skiving.trajectory import PassMotion

#: a snapshot of the stock (the recording's) is thinned to about this many vertices: every ray and slice of the
#: fans would be 91k on the default job, 894k on helical_internal (21 MB a snapshot with its normals); thinned by 2
#: (25k) the default's volume moves 0.03 %, thinned by 4 (87k) helical_internal's 0.20 %
SNAPSHOT_VERTICES = 50_000


def solid_mesh(solid: mf.Manifold) -> tuple[np.ndarray, np.ndarray]:
    """A manifold solid's mesh (vertices (n, 3) [mm], triangles (m, 3))."""
    mesh = solid.to_mesh()
    return np.asarray(mesh.vert_properties)[:, :3].copy(), np.asarray(mesh.tri_verts).copy()


#: the samples of one passage: t [s from the stroke's start], rot, trans [mm], cutter angle, carriage, centre distance
Samples = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]
Finished = tuple[int, int, Chip | None]  # pass index, passage, chip (None: the tooth stayed clear of the blank)


def _merged(pending: list[tuple[int, int, Samples]]):
    """The pending passages as (pass, (samples over the union of theirs, passages)), consecutive passages of one pass
    whose sample slices overlap put together."""
    groups: list[tuple[int, list, list[int]]] = []
    for index, m, samples in pending:
        if groups and groups[-1][0] == index and samples[0][0] <= groups[-1][1][0][-1]:
            cols = groups[-1][1]
            new = samples[0] > cols[0][-1]
            groups[-1][1][:] = [np.concatenate([c, s[new]]) for c, s in zip(cols, samples, strict=True)]
            groups[-1][2].append(m)
        else:
            groups.append((index, list(samples), [m]))
    return [(index, (tuple(cols), ms)) for index, cols, ms in groups]


class DexelRemoval:
    """Cuts on the dexel workpiece in this process: the passages submitted since the last call are cut together
    when a chip is asked for (each line takes them in time order, so the batch does not change the cut)."""

    def __init__(
        self, gear: Gear, edge: CuttingEdge, plans: Sequence[PassMotion], spacing: DexelSpacing, tolerance: float
    ):
        self.workpiece: DexelWorkpiece | None = None  # made at the first passage: its fans follow the motion's phase
        self._spacing = spacing
        self.result = CutResult(None, sweep_error=tolerance)
        self.result.pass_sweep_error = {plan.index: tolerance for plan in plans}
        self._plans, self._edge, self._gear = plans, edge, gear
        self._halves = {plan.index: engagement_half_angle(plan, edge) for plan in plans}
        self._points = outline_points(simplify_outline(edge.outline, 0.02)[0])  # for the blank window
        self._spread = tooth_spread(edge)  # the teeth's own outlines off the edge's (the tables' bounds grow by it)
        self._pending: list[tuple[int, int, Samples]] = []
        #: (pass, passage) -> the motion its chip was cut along, until the co-simulation takes it for the force
        self.motions: dict[tuple[int, int], SampledMotion] = {}
        self.land_touched = 0  # land rays the cut touched (cutting.skiving.dexel_solid.tube_ends), as of the last solid

    def submit(self, index: int, m: int, samples: Samples) -> None:
        if self.workpiece is None:
            phase = gear_phase(SampledMotion(self._plans[index].setup, index, *samples, checked=True))
            self.workpiece = DexelWorkpiece.for_gear(self._gear, self._edge, self._spacing, phase=phase)
        self._pending.append((index, m, samples))

    def finished(self, block: bool = False) -> list[Finished]:
        """Every passage submitted so far, cut (``block`` is moot: the cut happens here). Consecutive passages of a
        stroke share one motion over the union of their samples (the same poses: each interval's interpolation
        reads only its neighbouring samples, which every slice holds around its window)."""
        pending, self._pending = self._pending, []
        z0 = self._plans[0].setup.cutter.teeth
        pitch = 2 * np.pi / z0
        tables, keys, windows = [], [], []
        out: list[Finished] = []
        for index, group in _merged(pending):
            # the machine's own relative poses (cosim.relative_pose): rotations by construction
            motion = SampledMotion(self._plans[index].setup, index, *group[0], checked=True)
            half = self._halves[index]
            ms = np.array(group[1])
            t0 = np.maximum(np.asarray(motion.time_at_angle(ms * pitch - half), dtype=float), 0.0)
            t1 = np.minimum(np.asarray(motion.time_at_angle(ms * pitch + half), dtype=float), motion.duration)
            live = t1 > t0  # a window outside the stroke has nothing to cut
            out += [(index, int(m), None) for m in ms[~live]]
            if not live.any():
                continue
            ms, t0, t1 = ms[live], t0[live], t1[live]
            st = motion.setup
            frames = st.passage_frames(ms)
            table = PassTable.from_windows(motion, t0, t1, frames, self._edge.outline, ms, st.blank_frame, self._spread)
            tables.append(table)
            for k, (m, a, b) in enumerate(zip(ms, t0, t1, strict=True)):
                # the part of the window the tooth spends in the blank's envelope: where the force acts (every
                # passage is cut whatever this says: the cut is exact, the window only approximate); probed at
                # the table's poses (the tooth's, over the window)
                found = blank_window_of(self._gear, self._points, table.t[k], table.rot[k], table.origin[k])
                keys.append((index, int(m), motion))
                windows.append(found[:2] if found is not None else (float(a), float(b)))
        chips = self.workpiece.cut(tables) if tables else []
        for (index, m, motion), dexel, (start, end) in zip(keys, chips, windows, strict=True):
            chip = chip_of(dexel, motion.setup, motion, start, end)
            self.result.chips.append(chip)
            out.append((index, m, chip))
            if chip.volume > 0:
                self.motions[index, m] = motion
        return out

    def solid(self) -> mf.Manifold:
        if self.workpiece is None:  # nothing was cut: the blank
            self.workpiece = DexelWorkpiece.for_gear(self._gear, self._edge, self._spacing)
        solid, self.land_touched = dexel_solid(self.workpiece)
        return solid

    def stock_mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """The stock as it stands, a closed mesh for a picture (:func:`cutting.skiving.dexel_solid.stock_mesh`:
        milliseconds, no boolean), thinned to about SNAPSHOT_VERTICES; the same triangles every time."""
        if self.workpiece is None:
            self.workpiece = DexelWorkpiece.for_gear(self._gear, self._edge, self._spacing)
        ln = self.workpiece.lines
        stride = max(1, math.ceil(math.sqrt(ln.spaces * ln.slices * ln.rays / SNAPSHOT_VERTICES)))
        return stock_mesh(self.workpiece, stride, stride)

    def close(self) -> CutResult:
        self.finished()
        self.result.gear = self.solid()
        return self.result


class NoRemoval:
    """No workpiece: every passage is handed back without a chip. For a run whose gear is read only from the
    passages' exact swept surfaces (cutting.skiving.exact_sweep.SweptVolumes of the record's passes, as a measurement
    reads them) and whose forces are the chip of the moment, which reads those surfaces too: the machine's motion,
    loads and gear are the dexel run's; the chips' volumes (``sim.loads``' removal side), the solid and the snapshots
    are absent."""

    def __init__(self) -> None:
        self.result = CutResult(None)
        self._done: list[Finished] = []

    def submit(self, index: int, m: int, samples: Samples) -> None:
        self._done.append((index, m, None))

    def finished(self, block: bool = False) -> list[Finished]:
        done, self._done = self._done, []
        return done

    def close(self) -> CutResult:
        return self.result


class InlineRemoval:
    """Cuts in this process, at once."""

    def __init__(self, gear: Gear, edge: CuttingEdge, plans: Sequence[PassMotion], tols: Sequence[float]):
        self.stock = Stock(gear)
        self.result = CutResult(None)
        self._plans, self._edge, self._tols = plans, edge, tols
        self._cutters: dict[int, PassCutter] = {}
        self._done: list[Finished] = []

    def submit(self, index: int, m: int, samples: Samples) -> None:
        cutter = self._cutters.get(index)
        if cutter is None:
            cutter = self._cutters[index] = PassCutter(
                self.stock, self._edge, self._plans[index], self._tols[index], self.result
            )
        motion = SampledMotion(self._plans[index].setup, index, *samples)
        self._done.append((index, m, cutter.cut_passage(m, motion)))

    def finished(self, block: bool = False) -> list[Finished]:
        done, self._done = self._done, []
        return done

    def stock_mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """The stock as it stands, a closed mesh for a picture (the solid's)."""
        return solid_mesh(self.solid())

    def solid(self) -> mf.Manifold:
        return self.stock.solid()

    def close(self) -> CutResult:
        self.result.finish_columns(list(self.stock.columns().values()))
        return self.result


def _column_meshes(stock: Stock) -> dict[int, tuple[np.ndarray, np.ndarray, float]]:
    """The stock's sector columns as arrays (each worker unites its own sectors' slabs)."""
    return {k: to_arrays(column) for k, column in stock.columns().items()}


def _columns(parts: list[dict]) -> list[mf.Manifold]:
    """The workers' columns in sector order, whichever worker replied first: the union's triangulation depends on
    the order, and a run must not depend on the workers' timing."""
    meshes = {k: arrays for part in parts for k, arrays in part.items()}
    return [from_arrays(*meshes[k]) for k in sorted(meshes)]


def _worker(gear, edge, plans, tols, sectors, tasks, results) -> None:
    """One worker: its share of the stock; cuts, meshes or finishes as the main process asks."""
    try:
        stock = Stock(gear, sectors=sectors)
        result = CutResult(None)
        cutters: dict[int, PassCutter] = {}
        while True:
            msg = tasks.get()
            if msg[0] == "cut":
                _, index, m, samples = msg
                if index not in cutters:
                    cutters[index] = PassCutter(stock, edge, plans[index], tols[index], result)
                before = result.subtractions
                chip = cutters[index].cut_passage(m, SampledMotion(plans[index].setup, index, *samples))
                results.put(("cut", index, m, chip, result.subtractions - before))
            elif msg[0] == "mesh":
                results.put(("mesh", _column_meshes(stock)))
            else:  # "finish"
                stats = (result.sweep_error, dict(result.pass_sweep_error), result.sweeps)
                results.put(("finish", _column_meshes(stock), stats))
                return
    except Exception:
        results.put(("error", traceback.format_exc()))


class ParallelRemoval:
    """Cuts in ``workers`` processes, each owning every ``workers``-th tooth space."""

    def __init__(self, gear: Gear, edge: CuttingEdge, plans: Sequence[PassMotion], tols: Sequence[float], workers: int):
        ctx = mp.get_context("spawn")  # a fork would copy manifold's thread pool state
        self.workers = workers
        self._tasks = [ctx.Queue() for _ in range(workers)]
        self._results = ctx.Queue()
        self._procs = [
            ctx.Process(
                target=_worker,
                args=(
                    gear,
                    edge,
                    list(plans),
                    list(tols),
                    list(range(w, gear.teeth, workers)),
                    self._tasks[w],
                    self._results,
                ),
                daemon=True,  # never outlive the run
            )
            for w in range(workers)
        ]
        for p in self._procs:
            p.start()
        self.result = CutResult(None)
        self._parts: dict[tuple[int, int], list] = {}  # passage -> [replies, volume, subtractions, chip]
        self._order: list[tuple[int, int]] = []
        self._replies: list[tuple] = []  # mesh / finish replies

    def submit(self, index: int, m: int, samples: Samples) -> None:
        self._parts[index, m] = [0, 0.0, 0, None]
        self._order.append((index, m))
        for q in self._tasks:
            q.put(("cut", index, m, samples))

    def _receive(self, block: bool) -> bool:
        try:
            msg = self._results.get(block=block, timeout=600 if block else None)
        except queue.Empty:
            if block:
                raise RuntimeError("a removal worker sent nothing for 10 minutes") from None
            return False
        if msg[0] == "error":
            self._stop()
            raise RuntimeError(f"a removal worker failed:\n{msg[1]}")
        if msg[0] != "cut":
            self._replies.append(msg)
            return True
        _, index, m, chip, subtractions = msg
        part = self._parts[index, m]
        part[0] += 1
        part[2] += subtractions
        if chip is not None:
            part[1] += chip.volume
            if part[3] is None or chip.sweeps > part[3].sweeps:  # the reply of a worker that sampled the passage
                part[3] = chip
        return True

    def finished(self, block: bool = False) -> list[Finished]:
        """The passages every worker has done, in submission order; with ``block`` at least the oldest one."""
        out: list[Finished] = []
        while True:
            while self._order and self._parts[self._order[0]][0] == self.workers:
                key = self._order.pop(0)
                _, volume, subtractions, chip = self._parts.pop(key)
                self.result.subtractions += subtractions
                if chip is not None:
                    chip.volume = volume
                    self.result.chips.append(chip)
                out.append((key[0], key[1], chip))
            if out or not self._order or not self._receive(block):
                return out

    def _collect(self, kind: str) -> list[tuple]:
        """Every worker's reply of ``kind`` (the passages before it are finished first: the queues are FIFO)."""
        while len([r for r in self._replies if r[0] == kind]) < self.workers:
            self._receive(True)
        replies = [r for r in self._replies if r[0] == kind]
        self._replies = [r for r in self._replies if r[0] != kind]
        return replies

    def stock_mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """The stock as it stands, a closed mesh for a picture (the solid's)."""
        return solid_mesh(self.solid())

    def solid(self) -> mf.Manifold:
        for q in self._tasks:
            q.put(("mesh",))
        replies = self._collect("mesh")
        return mf.Manifold.batch_boolean(_columns([r[1] for r in replies]), mf.OpType.Add)

    def close(self) -> CutResult:
        for q in self._tasks:
            q.put(("finish",))
        replies = self._collect("finish")
        for p in self._procs:
            p.join(timeout=60)
        for _, _, (err, pass_err, _sweeps) in replies:
            self.result.sweep_error = max(self.result.sweep_error, err)
            for k, v in pass_err.items():
                self.result.pass_sweep_error[k] = max(self.result.pass_sweep_error.get(k, 0.0), v)
        # each passage is sampled by the workers whose spaces it can reach: count it once
        self.result.sweeps = sum(chip.sweeps for chip in self.result.chips)
        self.result.finish_columns(_columns([r[1] for r in replies]))
        return self.result

    def _stop(self) -> None:
        for p in self._procs:
            if p.is_alive():
                p.terminate()
