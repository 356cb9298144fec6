"""Machine and cut together: the simulated machine moves, the removal cuts every tooth passage as soon as the
machine has moved through it, and the chips being cut act back on the machine.

The force: every servo tick the teeth in the cut take the chip of the moment (:mod:`cutting.skiving.chip_of_the_moment`
through the load hook :class:`~virtual_machine.processes.skiving.chip_load.ChipLoad`): the pass's nominal layer
changed by the machine's deviation now against one work revolution earlier, so that the loop's own motion changes
the chip that makes its force (regeneration, chatter). The removal: a passage is cut (the dexel lines, or the
manifold solid in worker processes) once the recorded motion covers its engagement window, the exact geometry of
the motion; its chip's volume is reported beside the force model's and its mean thickness sets the coefficients'
size effect for the pass.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import manifold3d as mf
import numpy as np

from cutting.errors import ChatterError
from cutting.forces import EdgeFaces, EngagementLoad
from cutting.materials import Material, material
from cutting.oblique import ObliqueForces, load_cutting_model
from cutting.skiving.dexel_cut import removal_summary
from cutting.skiving.edge import CuttingEdge, make_edge
from cutting.skiving.holder import check_holder_side
from cutting.skiving.interference import check_body_interference
from cutting.skiving.passages import (
    Chip,
    CutResult,
    engagement_half_angle,
    expected_genus,
    passage_count,
)
from cutting.skiving.path_correction import PathCorrection
from cutting.skiving.sweep import outline_points, simplify_outline, split_sides
from cutting.skiving.working_angles import check_working_clearance, rake_normal
from machine_models.parameters import SkivingMachineParams
from virtual_machine.job import Job, dexel_spacing
from virtual_machine.processes.skiving.chip_load import ChipLoad
from virtual_machine.processes.skiving.cosim_removal import (
    DexelRemoval,
    InlineRemoval,
    NoRemoval,
    ParallelRemoval,
    Samples,
)
from virtual_machine.runtime.machine_run import SEGMENTS, MachineRun, MotionRecord, relative_pose
from virtual_machine.setting.plan import SkivingPlan, plan_of

FEED = SEGMENTS.index("feed")


@dataclass
class AppliedLoad:
    """The load that acted over one engagement, in machine time, with its removal chip's volume."""

    pass_index: int
    passage: int
    load: EngagementLoad


@dataclass
class CoSimulation:
    record: MotionRecord | None
    cut: CutResult
    loads: list[AppliedLoad] = field(default_factory=list)
    seconds: dict[str, float] = field(default_factory=dict)
    material: Material | None = None
    load_work: float = 0.0  # work of the cutting loads on the machine [J] (negative: the chips absorb it)
    actuator_work: float = 0.0  # work of all actuators over the run [J]
    load_rows: np.ndarray | None = None  # per servo tick: t [s], resultant on the workpiece [N] (3), torque [N m]
    snapshots: list[tuple[float, np.ndarray, np.ndarray]] = field(default_factory=list)  # t, vertices, triangles
    edge: CuttingEdge | None = None  # the cutting edge the removal swept
    removal: str = "dexel"  # "dexel", "manifold" or "none"
    lag: int = 0  # passages the removal's chips were taken behind the machine
    dexel: dict | None = None  # the dexel removal's figures (cutting.skiving.dexel_cut.removal_summary)

    def chip_change(self) -> float:
        """Median relative change of the chip volume between consecutive engagements of a pass (the removal's
        chips)."""
        changes = []
        for a, b in zip(self.loads, self.loads[1:], strict=False):
            if a.pass_index == b.pass_index and b.passage == a.passage + 1 and a.load.volume > 0:
                changes.append(abs(b.load.volume - a.load.volume) / a.load.volume)
        return float(np.median(changes)) if changes else 0.0


class _Stroke:
    """The recorded samples of one feed stroke and the passages submitted from it."""

    def __init__(self, index: int, half: float, width: int = 6):
        self.index, self.half = index, half
        # t and the five axes (and the loop's deflection, 6 more), grown by doubling (a stroke has ~10^4 samples)
        self._rows = np.zeros((1024, width))
        self.n = 0
        self.next_m: int | None = None
        self.first_m = 0
        self.snapshots = 0  # taken so far
        self.total: int | None = None  # passages the ideal pass has
        self.idle = 0.0  # the share of them before the engagement zone (and after it): approach and overrun
        self.ended = False
        self.step: float | None = None  # cutter angle per sample (_ready_passages)
        self.step_n = 0  # samples when it was taken

    def append(self, row, deflection=None) -> None:
        if self.n == len(self._rows):
            self._rows = np.concatenate([self._rows, np.zeros_like(self._rows)])
        self._rows[self.n, :6] = row[:6]
        if deflection is not None:
            self._rows[self.n, 6:] = deflection
        self.n += 1

    @property
    def rows(self) -> np.ndarray:
        """The samples so far (a view): t [s] and the five axes (B1, B2 [rad], P3, X [m], TV [rad]), then the loop's
        deflection if the machine has modes (MotionRecord.deflection)."""
        return self._rows[: self.n]


class CuttingRun:
    """The skiving machine and its cut together, as a task object: the machine (:class:`MachineRun`, its load hook
    fed by the ``force`` predictor), the ``removal`` that cuts each passage once the machine has moved through it,
    and the chips that become the force acting on the machine. :meth:`run` drives them to the end of the program.

    See :func:`cosimulate` for the arguments."""

    def __init__(
        self,
        job: Job,
        params: SkivingMachineParams | None = None,
        edge_kind: str | None = None,
        forces: bool = True,
        servo_substeps: int = 2,
        snapshots_per_pass: int = 0,
        workers: int = 1,
        correction: PathCorrection | None = None,
        removal: str = "dexel",
        plan: SkivingPlan | None = None,
    ):
        plan = plan_of(job, plan)
        self.setup = setup = plan.setup
        self.plans = plans = plan.passes
        self.edge = edge = make_edge(setup, edge_kind or job.cutter_options.edge)
        self.lag = max_lag(workers, removal)
        self.material = material(job.process.material)
        # the three components per edge element at its working rake and inclination (cutting.oblique)
        self.forces_model = ObliqueForces(self.material, load_cutting_model(), job.cutter_options.edge_radius)
        # the force needs the edge's shape within 5 um and its engaged length (elements of at most 0.2 mm), not the
        # finest facets of the sweep
        self.edge_points = outline_points(split_sides(simplify_outline(edge.outline, 0.005)[0], 0.2))
        self.faces = EdgeFaces.of_outline(self.edge_points, rake_normal(setup))
        self.pitch = 2 * math.pi / setup.cutter.teeth
        # each pass's own engagement: a deeper pass engages earlier, and its passages' samples must cover the window
        self.halves = [engagement_half_angle(p, edge) for p in plans]
        self.force = ChipLoad(setup, plans, self.edge_points, self.faces, self.forces_model, self.halves)
        cut = self.force if forces else _no_force  # no force: the work accounting runs alike
        self.machine = MachineRun(job, params, servo_substeps, correction=correction, plan=plan, cut=cut)
        self.force.bind(self.machine)
        check_holder_side(plans, edge, setup.cutter.face_width, setup.holder_diameter_value)
        check_working_clearance(setup, edge)  # the relieved flank off the flank it generates
        check_body_interference(setup, edge)  # and the relieved tooth off the finished teeth over the whole mesh
        if removal == "none" and snapshots_per_pass:
            raise ValueError("snapshots of the stock need a workpiece: removal 'dexel' or 'manifold'")
        self.removal = _removal(job, setup, edge, plans, removal, workers)
        self.workers, self.snapshots_per_pass = workers, snapshots_per_pass
        self.chunk = self.pitch / (setup.tool_speed * 2 * math.pi / 60) / 2  # half a cutter pitch of machine time
        self.sim = CoSimulation(
            None, self.removal.result, material=self.material, edge=edge, removal=removal, lag=self.lag
        )
        self.chips: dict[tuple[int, int], tuple[float, float]] = {}  # (pass, passage): the removal's volume, thickness
        self._pending: dict[tuple[int, int], tuple[Samples, float]] = {}
        self._arrived: dict[tuple[int, int], Chip | None] = {}
        self._submitted: list[tuple[int, int]] = []
        self.applied = 0  # chips the removal has handed back
        self._stroke: _Stroke | None = None
        self._seen = 0  # machine rows read so far
        self.t_cut = 0.0  # wall seconds in the removal (or waiting for its workers)

    def run(
        self,
        progress: Callable[[float, int], None] | None = None,
        live: Callable[[np.ndarray, np.ndarray], None] | None = None,
    ) -> CoSimulation:
        """The whole program: the machine a chunk at a time, each chunk's passages cut and their chips applied;
        ``live(machine rows, load rows)`` takes each chunk's new rows (a viewer following the run)."""
        t_start = time.perf_counter()
        loads_seen = 0
        try:
            while True:
                seen = self._seen
                alive = self.machine.advance(self.machine.time + self.chunk)
                self._cut_chunk(alive, progress)
                if live is not None:
                    loads = np.asarray(self.machine.load.rows[loads_seen:]).reshape(-1, 5)
                    loads_seen = len(self.machine.load.rows)
                    live(np.asarray(self.machine.rows[seen : self._seen]), loads)
                if not alive:
                    break
            result = self._close()
        except BaseException:
            if isinstance(self.removal, ParallelRemoval):
                self.removal._stop()
            raise
        sim = self.sim
        sim.cut = result
        machine = self.machine
        sim.record = machine.record()
        sim.load_work, sim.actuator_work = machine.loop.load_work, machine.loop.actuator_work
        sim.load_rows = np.array(machine.load.rows).reshape(-1, 5)
        sim.loads = self.force.engagements(machine.dt, self.chips)
        if isinstance(self.removal, DexelRemoval):
            sim.dexel = removal_summary(self.removal.workpiece, self.removal.land_touched)
        sim.seconds = {
            "total": time.perf_counter() - t_start,
            "cut": self.t_cut,  # the removal in this process, or the wait for the workers
            "physics": machine.timing["physics"],
            "control": machine.timing["control"],
            "machine": machine.time,
            "workers": self.workers,
        }
        return sim

    def _cut_chunk(self, alive: bool, progress: Callable[[float, int], None] | None) -> None:
        """The machine's new rows to the feed stroke they belong to; the passages they complete submitted to the
        removal, the chips due applied."""
        rows, deflections = self.machine.rows, self.machine.deflections
        stroke = self._stroke
        for i in range(self._seen, len(rows)):
            row = rows[i]
            segment, index = int(row[6]), int(row[7])
            if segment == FEED:
                if stroke is None or stroke.index != index:
                    stroke = _Stroke(index, self.halves[index], 6 if deflections is None else 12)
                stroke.append(row, None if deflections is None else deflections[i])
            elif stroke is not None:
                stroke.ended = True
        self._seen = len(rows)
        if stroke is not None and not alive:
            stroke.ended = True  # the program ends in the last feed stroke
        self._stroke = stroke
        if stroke is None or stroke.n < 8:
            return
        c0 = time.perf_counter()
        applied = self.applied
        for m, samples, t0_stroke in _ready_passages(stroke, self.setup, self.pitch):
            key = (stroke.index, m)
            self._pending[key] = (samples, t0_stroke)
            self.removal.submit(stroke.index, m, samples)
            self._submitted.append(key)
            while len(self._submitted) > self.lag:
                self._apply(self._submitted.pop(0))
        if stroke.ended:  # the stroke's last chips before the return
            self._drain()
        if progress is not None and self.applied > applied:
            progress(self.machine.time, self.applied)
        if self.snapshots_per_pass:
            _snapshot(
                self.sim, self.removal, stroke, self.machine.time, self.snapshots_per_pass, self.plans, self.edge,
                self._drain,
            )  # fmt: skip
        self.t_cut += time.perf_counter() - c0
        if stroke.ended:
            self._stroke = None

    def _drain(self) -> None:
        """Every chip submitted so far taken (the stock as the machine has cut it)."""
        while self._submitted:
            self._apply(self._submitted.pop(0))

    def _apply(self, key: tuple[int, int]) -> None:
        """The chip of passage ``key`` (waiting for it): its volume and mean thickness for the report (the force is
        the chip of the moment's, :class:`ChipLoad`, and does not wait for it). Chips are taken in submission order
        at a fixed point of the simulation (``lag`` submissions later), never when a worker happens to finish: the
        run does not depend on the workers' timing."""
        while key not in self._arrived:
            self._arrived.update({(i, m): chip for i, m, chip in self.removal.finished(block=True)})
        chip = self._arrived.pop(key)
        self._pending.pop(key)
        if hasattr(self.removal, "motions"):
            self.removal.motions.pop(key, None)
        self.applied += 1
        if chip is None or chip.volume <= 0:
            return
        self.chips[key] = (chip.volume, chip.thickness_mean)

    def _close(self) -> CutResult:
        """The removal's result: the chips in order, the solid checked."""
        c0 = time.perf_counter()
        result = self.removal.close()
        result.chips.sort(key=lambda c: (c.pass_index, c.time))
        gear = self.setup.gear
        if isinstance(self.removal, NoRemoval):  # no solid: a torn gear shows in the vibration's warning only
            return result
        if result.gear.status() != mf.Error.NoError or result.gear.is_empty():
            raise RuntimeError(f"the removal left no valid solid ({result.gear.status()})")
        if result.gear.genus() != expected_genus(gear):
            torn = _chatter(self.machine.record(), self.setup)
            if torn:
                raise ChatterError(
                    f"the cut left a solid of genus {result.gear.genus()} (a gear has {expected_genus(gear)}): the "
                    f"machine chattered and tore the gear ({torn}). Make the tool-work loop stiffer or better damped "
                    "([[machine.model.loop]]), take less per pass, or move the tool speed to a stable lobe "
                    "(`skive stability JOB` draws them)"
                )
            raise RuntimeError(
                f"the removal left a solid of genus {result.gear.genus()} (a gear has {expected_genus(gear)}): "
                "report it with the job"
            )
        self.t_cut += time.perf_counter() - c0
        return result


def _chatter(record: MotionRecord, setup) -> str:
    """The passes whose vibration grew like chatter, as the run reports them (machine_effect.pass_deflection), or
    ""."""
    from virtual_machine.processes.skiving.machine_effect import pass_deflection

    return "; ".join(d["warning"] for d in pass_deflection(record, setup) if "warning" in d)


def _no_force(t: float, dt: float) -> tuple:
    return ()


def _removal(job: Job, setup, edge: CuttingEdge, plans, removal: str, workers: int):
    """The removal the run cuts with: the dexel workpiece, or the manifold reference inline or in ``workers``
    processes."""
    if removal == "none":
        return NoRemoval()
    if removal == "dexel":
        return DexelRemoval(setup.gear, edge, plans, dexel_spacing(job), job.process.sweep_error)
    if removal != "manifold":
        raise ValueError(f"removal {removal!r}: use 'dexel', 'manifold' or 'none'")
    n_pass = len(setup.passes)
    tols = [job.process.sweep_error if i == n_pass - 1 else job.process.roughing_sweep_error for i in range(n_pass)]
    if workers <= 1:
        return InlineRemoval(setup.gear, edge, plans, tols)
    return ParallelRemoval(setup.gear, edge, plans, tols, workers)


def cosimulate(
    job: Job,
    params: SkivingMachineParams | None = None,
    edge_kind: str | None = None,
    forces: bool = True,
    servo_substeps: int = 2,
    progress: Callable[[float, int], None] | None = None,
    snapshots_per_pass: int = 0,
    workers: int = 1,
    correction: PathCorrection | None = None,
    removal: str = "dexel",
    plan: SkivingPlan | None = None,
    live: Callable[[np.ndarray, np.ndarray], None] | None = None,
) -> CoSimulation:
    """Run the job's machine and cut its gear from the motion it really makes, with the chips' forces acting on
    the machine (``forces=False``: the cut follows the machine, no force acts back). ``progress(machine_time,
    passages)`` is called as passages finish. ``snapshots_per_pass``: meshes of the stock taken evenly through
    each pass (the last at its end), for the recording. ``workers`` > 1 cuts in that many processes; the machine
    then runs at most :func:`max_lag` passages ahead of the finished chips. ``correction``: the finishing pass's
    path corrections of a flank modification (virtual_machine/processes/skiving/modification_path.py), made by the
    CNC. ``removal``: "dexel" (the default: the dexel workpiece, cut a few passages at a time in this process;
    ``workers`` is moot), "manifold" (the reference: per-passage booleans, inline or in ``workers`` processes) or
    "none" (no workpiece: the motion, the loads and the exact swept surfaces only; no chips' volumes, solid or
    snapshots: :class:`NoRemoval`).
    ``plan``: the job's setup, ideal passes and setting sheets if an earlier stage made them. ``live(machine rows,
    load rows)``: each chunk's new rows as the run goes (:class:`virtual_machine.output.recorder.LiveView`)."""
    run = CuttingRun(
        job, params, edge_kind, forces, servo_substeps, snapshots_per_pass, workers, correction, removal, plan
    )
    return run.run(progress, live)


#: passages the dexel removal's chips are taken behind the machine: the batch it cuts in one call. Nothing waits for
#: a chip (the force is the chip of the moment; a snapshot drains the batch first), and a line takes its passages in
#: time order whatever the batch (the chips are the same bit for bit); a batch of 16 gives both threads cells to share
#: and the call's overhead to 16 passages: spur_external on a 10 mm face the removal 8.2 s against 12.0 s passage by
#: passage (CPU 20.1 against 25.1 s for the whole co-simulation; docs/performance.md)
DEXEL_LAG = 16


def max_lag(workers: int, removal: str = "manifold") -> int:
    """Passages the machine may run ahead of the finished chips: the dexel removal's batch; manifold: none inline,
    with workers two per worker (enough to keep them busy, as a passage's booleans fall mostly to the worker
    owning its tooth space)."""
    if removal == "dexel":
        return DEXEL_LAG
    return 0 if workers <= 1 else 2 * workers


def _snapshot(
    sim: CoSimulation, removal, stroke: _Stroke, t: float, per_pass: int, plans, edge, drain: Callable[[], None]
) -> None:
    """A mesh of the stock whenever the stroke has gone the next k / per_pass of the way through the blank (its
    passages from entering the engagement zone to leaving it: the approach and the overrun cut nothing), and at its
    end; ``drain()`` first cuts the passages the removal still holds, so the stock is the one the machine has cut."""
    plan = plans[stroke.index]
    if stroke.total is None:
        stroke.total = passage_count(plan, edge)
        st = plan.setup
        zone = st.gear.face_width + 2 * st.engagement_half_length(plan.centre_distance)
        stroke.idle = max(0.0, (abs(plan.v_s) * plan.duration - zone) / 2) / (abs(plan.v_s) * plan.duration)
    done = (stroke.next_m - stroke.first_m) / max(stroke.total, 1) if stroke.next_m is not None else 0.0
    through = (done - stroke.idle) / max(1.0 - 2 * stroke.idle, 1e-9)
    due = min(per_pass, max(0, math.floor(through * per_pass))) if not stroke.ended else per_pass
    if due > stroke.snapshots:
        stroke.snapshots = due
        drain()
        sim.snapshots.append((t, *removal.stock_mesh()))


def _ready_passages(stroke: _Stroke, setup, pitch: float):
    """The passages of ``stroke`` whose window the samples now cover (all that remain once it has ended), each
    with its samples (a slice around the window, time from the stroke's start) and the stroke's start time.
    Each call reads only the samples of the passages it yields (a stroke has ~10^4 of them)."""
    rows = stroke.rows
    n = len(rows)
    phi = rows[:, 1]  # the cutter angle B1 [rad], growing along the stroke
    half = stroke.half
    if stroke.next_m is None:
        stroke.next_m = stroke.first_m = math.ceil((phi[0] - half) / pitch)
    if stroke.step is None or n >= 2 * stroke.step_n:  # cutter angle per sample, re-taken as the stroke grows
        stroke.step, stroke.step_n = float(np.median(np.diff(phi[-min(n, 512) :]))), max(n, 8)
    step = stroke.step
    # a window is covered once the samples reach past its end (four samples more for the interpolation)
    last = math.floor((phi[-1] + half) / pitch) if stroke.ended else math.floor((phi[-1] - half - 4 * step) / pitch)
    while stroke.next_m <= last:
        m = stroke.next_m
        lo = np.searchsorted(phi, m * pitch - half - 4 * step)
        hi = np.searchsorted(phi, m * pitch + half + 4 * step) + 1
        lo, hi = max(lo - 1, 0), min(hi, n)
        if hi - lo < 4:
            lo, hi = max(0, hi - 4), max(hi, min(n, 4))
        t = rows[lo:hi, 0]
        q = rows[lo:hi, 1:6].copy()
        q[:, 2:4] /= 1e-3  # carriage P3 and radial X in mm
        rot, trans = relative_pose(setup, q, rows[lo:hi, 6:12] if rows.shape[1] > 6 else None, t)
        stroke.next_m += 1
        yield m, (t - rows[0, 0], rot, trans, q[:, 0], q[:, 2], q[:, 3]), float(rows[0, 0])
