"""Machine and cut together: the simulated machine moves, the removal cuts every tooth passage as soon as the
machine has moved through it, and the chip's cutting force acts back on the machine.

Granularity: one tooth engagement. A passage is cut (cutting.removal.PassCutter) once the recorded motion covers
its engagement window; its chip gives the engagement's Kienzle load (cutting.forces). A passage's own force is
needed while it is being cut, before its chip exists, so the force acting during an engagement is the load of
the latest chip already cut, carried forward by whole cutter pitches (rotated with the work and moved with the
feed in the blank frame). Consecutive engagements take almost the same chip (the chip changes over L / f ~ tens
of engagements at the face's ends, and with the machine's own deviations), so the prediction is off by the
change of the chip over the 1-3 engagements of lag; the run reports that change.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import manifold3d as mf
import numpy as np

from cutting.edge import make_edge
from cutting.forces import EngagementLoad, engagement_load
from cutting.holder import check_holder_side
from cutting.materials import Material, material
from cutting.removal import CutResult, PassCutter, Stock, expected_genus, passage_count, tooth_pose
from cutting.sampled_motion import SampledMotion
from cutting.sweep import outline_points
from cutting.trajectory import ideal_passes
from machine_models.parameters import SkivingMachineParams
from virtual_machine.job import Job
from virtual_machine.simulate import SEGMENTS, MachineRun, MotionRecord, relative_pose

FEED = SEGMENTS.index("feed")


def _rot_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


class ForcePredictor:
    """The cutting loads acting at a time: the latest engagement's load (machine time, blank frame) repeated every
    cutter pitch ``period`` [s]; each repetition is turned by the work's rotation and moved by the feed over its
    delay (``turn_rate`` [rad/s] and ``feed_rate`` [mm/s] of the mesh zone in the blank frame)."""

    def __init__(self) -> None:
        self.latest: EngagementLoad | None = None
        self.period = self.turn_rate = self.feed_rate = 0.0

    def update(self, load: EngagementLoad, period: float, turn_rate: float, feed_rate: float) -> None:
        self.latest, self.period, self.turn_rate, self.feed_rate = load, period, turn_rate, feed_rate

    def clear(self) -> None:
        self.latest = None

    def __call__(self, t: float, dt: float) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """The loads over the servo tick [t, t + dt], each averaged over it (see EngagementLoad.mean)."""
        ld = self.latest
        if ld is None or not len(ld.t) or self.period <= 0:
            return []
        out = []
        first = max(1, math.ceil((t - ld.t[-1]) / self.period))
        # the engagements up to one window plus two pitches on: later ones get the load of a newer chip, and a
        # prediction that old is stale (the cutter may have left the blank)
        horizon = math.ceil((ld.t[-1] - ld.t[0]) / self.period) + 2
        last = min(math.floor((t + dt - ld.t[0]) / self.period), horizon)
        for j in range(first, last + 1):
            delay = j * self.period
            fp = ld.mean(t - delay, t + dt - delay)
            if fp is None:
                continue
            turn = _rot_z(self.turn_rate * delay)
            force, point, moment = fp
            out.append((turn @ force, turn @ point + np.array([0.0, 0.0, self.feed_rate * delay]), turn @ moment))
        return out


@dataclass
class AppliedLoad:
    """The load of one cut engagement, in machine time (what the engagements after it felt)."""

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

    def chip_change(self) -> float:
        """Median relative change of the chip volume between consecutive engagements of a pass: the size of the
        prediction's error (the force acting is the previous chips')."""
        changes = []
        for a, b in zip(self.loads, self.loads[1:], strict=False):
            if a.pass_index == b.pass_index and b.passage == a.passage + 1 and a.load.volume > 0:
                changes.append(abs(b.load.volume - a.load.volume) / a.load.volume)
        return float(np.median(changes)) if changes else 0.0


class _Stroke:
    """The recorded samples of one feed stroke and its passage cutter."""

    def __init__(self, index: int, cutter: PassCutter):
        self.index, self.cutter = index, cutter
        self.t: list[float] = []
        self.q: list[list[float]] = []
        self.next_m: int | None = None
        self.first_m = 0
        self.snapshots = 0  # taken so far
        self.total: int | None = None  # passages the ideal pass has
        self.ended = False


def cosimulate(
    job: Job,
    params: SkivingMachineParams | None = None,
    edge_kind: str | None = None,
    forces: bool = True,
    servo_substeps: int = 2,
    progress: Callable[[float, int], None] | None = None,
    snapshots_per_pass: int = 0,
) -> CoSimulation:
    """Run the job's machine and cut its gear from the motion it really makes, with the chips' forces acting on
    the machine (``forces=False``: the cut follows the machine, no force acts back). ``progress(machine_time,
    passages)`` is called after every cut passage. ``snapshots_per_pass``: meshes of the stock taken evenly
    through each pass (the last at its end), for the recording."""
    setup = job.skiving
    kind = edge_kind or job.cutter_options["edge"]
    edge = make_edge(setup, kind)
    plans = ideal_passes(setup)
    check_holder_side(plans, edge, setup.cutter.face_width, setup.holder_diameter_value)
    n_pass = len(setup.passes)
    tols = [
        job.process["sweep_error"] if i == n_pass - 1 else job.process["roughing_sweep_error"] for i in range(n_pass)
    ]
    mat = material(job.process["material"])
    run = MachineRun(job, params, servo_substeps)
    predictor = ForcePredictor()
    run.load = predictor if forces else (lambda t, dt: ())  # no force, but the work accounting runs alike
    stock = Stock(setup.gear)
    result = CutResult(None)
    edge_pts = outline_points(edge.outline)
    pitch = 2 * math.pi / setup.cutter.teeth
    chunk = pitch / (setup.tool_speed * 2 * math.pi / 60) / 2  # half a cutter pitch of machine time
    sim = CoSimulation(None, result, material=mat)  # the record is assembled at the end
    t_cut = 0.0
    strokes: dict[int, _Stroke] = {}
    seen = 0
    current: _Stroke | None = None
    passages = 0
    t_start = time.perf_counter()
    while True:
        alive = run.advance(run.time + chunk)
        rows = run.rows
        for row in rows[seen:]:
            segment, index = int(row[6]), int(row[7])
            if segment == FEED:
                if current is None or current.index != index:
                    current = strokes[index] = _Stroke(
                        index, PassCutter(stock, edge, plans[index], tols[index], result)
                    )
                current.t.append(row[0])
                current.q.append(list(row[1:6]))
            elif current is not None:
                current.ended = True
        seen = len(rows)
        if current is not None and not alive:
            current.ended = True  # the program ends in the last feed stroke
        if current is not None and len(current.t) >= 8:
            c0 = time.perf_counter()
            n = _cut_ready(current, setup, edge_pts, mat, pitch, predictor, sim, final=current.ended)
            t_cut += time.perf_counter() - c0
            passages += n
            if n and progress is not None:
                progress(run.time, passages)
            if snapshots_per_pass:
                _snapshot(sim, stock, current, run.time, snapshots_per_pass, plans, edge)
            if current.ended:
                predictor.clear()  # no chip in the return stroke
                current = None
        if not alive:
            break
    sim.record = run.record()
    sim.load_work, sim.actuator_work = run.load_work, run.actuator_work
    sim.load_rows = np.array(run.load_rows).reshape(-1, 5)
    c0 = time.perf_counter()
    result.gear = stock.solid()
    if result.gear.status() != mf.Error.NoError or result.gear.is_empty():
        raise RuntimeError(f"the removal left no valid solid ({result.gear.status()})")
    if result.gear.genus() != expected_genus(setup.gear):
        raise RuntimeError(
            f"the removal left a solid of genus {result.gear.genus()} (a gear has "
            f"{expected_genus(setup.gear)}): report it with the job"
        )
    t_cut += time.perf_counter() - c0
    total = time.perf_counter() - t_start
    sim.seconds = {
        "total": total,
        "cut": t_cut,
        "physics": run.timing["physics"],
        "control": run.timing["control"],
        "machine": run.time,
    }
    return sim


def _snapshot(sim: CoSimulation, stock: Stock, stroke: _Stroke, t: float, per_pass: int, plans, edge) -> None:
    """A mesh of the stock whenever the stroke has cut the next k / per_pass of its passages, and at its end."""
    if stroke.total is None:
        stroke.total = passage_count(plans[stroke.index], edge)
    total = stroke.total
    done = stroke.next_m - stroke.first_m if stroke.next_m is not None else 0
    due = min(per_pass, done * per_pass // max(total, 1)) if not stroke.ended else per_pass
    if due > stroke.snapshots:
        stroke.snapshots = due
        mesh = stock.solid().to_mesh()
        sim.snapshots.append((t, np.asarray(mesh.vert_properties)[:, :3].copy(), np.asarray(mesh.tri_verts).copy()))


def _cut_ready(
    stroke: _Stroke,
    setup,
    edge_pts,
    mat: Material,
    pitch: float,
    predictor: ForcePredictor,
    sim: CoSimulation,
    final: bool,
) -> int:
    """Cut every passage of ``stroke`` whose window the samples cover (all that remain when ``final``); returns how
    many were cut. Each chip's load becomes the prediction for the engagements after it."""
    t = np.asarray(stroke.t)
    q = np.asarray(stroke.q)
    q = np.column_stack([q[:, 0], q[:, 1], q[:, 2] / 1e-3, q[:, 3] / 1e-3, q[:, 4]])  # P3, X in mm
    phi = q[:, 0]
    cutter = stroke.cutter
    half = cutter.half
    if stroke.next_m is None:
        stroke.next_m = stroke.first_m = math.ceil((phi[0] - half) / pitch)
    step = float(np.median(np.diff(phi)))  # cutter angle per sample
    # a window is covered once the samples reach past its end (four samples more for the interpolation)
    last_m = math.floor((phi[-1] + half) / pitch) if final else math.floor((phi[-1] - half - 4 * step) / pitch)
    t0_stroke = t[0]
    count = 0
    while stroke.next_m <= last_m:
        m = stroke.next_m
        lo = np.searchsorted(phi, m * pitch - half - 4 * step)
        hi = np.searchsorted(phi, m * pitch + half + 4 * step) + 1
        lo, hi = max(lo - 1, 0), min(hi, len(t))
        if hi - lo < 4:
            lo, hi = max(0, hi - 4), max(hi, min(len(t), 4))
        rot, trans = relative_pose(setup, q[lo:hi])
        motion = SampledMotion(
            setup, stroke.index, t[lo:hi] - t0_stroke, rot, trans, phi[lo:hi], q[lo:hi, 2], q[lo:hi, 3]
        )
        chip = cutter.cut_passage(m, motion)
        stroke.next_m += 1
        count += 1
        if chip is None or chip.volume <= 0:
            predictor.clear()  # the tooth took nothing: none of the next engagements is predicted to cut
            continue
        load = engagement_load(
            tooth_pose(motion, m), edge_pts, chip.start, chip.end, chip.volume, mat, cutter.in_blank
        ).shifted(t0_stroke)
        sim.loads.append(AppliedLoad(stroke.index, m, load))
        # the mesh zone's motion in the blank frame: the cutter centre's turn about and travel along the work axis
        ang = np.unwrap(np.arctan2(trans[:, 1], trans[:, 0]))
        dt = motion.t[-1] - motion.t[0]
        predictor.update(load, pitch / motion.omega0, (ang[-1] - ang[0]) / dt, (trans[-1, 2] - trans[0, 2]) / dt)
    return count
