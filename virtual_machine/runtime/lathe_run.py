"""One threading stroke on the lathe of seed 001 (group Fv(B1 P2)) on the machine loop
(:mod:`virtual_machine.runtime.loop`: the controllers tick at the servo rate, the cutting load before every physics
sub-step, the record per tick) on the thread lathe model; the thread and turning processes both run it.

The stroke: the spindle runs up along a smooth 0.3 s ramp of the speed command (mechanical, master-slave) or
of the reference generator's frequency (equal coordinates), with the feed engaged from the start (the
carriage follows the spindle all the time), then the carriage travels the threaded length at speed. Only the
first pass's stroke is run. The record's **lead error** is the thread's synchronisation error::

    e = P2 - P2_0 - (P / (2 pi)) (B1 - B1_0) hand_sign          [um]

with ``hand_sign`` = -1 for a right-hand thread (see :mod:`machine_models.thread_lathe`): its variation is
the thread's pitch error, its slope per mm of travel the relative lead error of the settings.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import mujoco
import numpy as np

from cutting.errors import InputError, Problem
from machine_models.parameters import override
from machine_models.skiving_machine import MM
from machine_models.thread_lathe import ThreadLatheParams, build_thread_lathe_spec
from virtual_machine.job import Job, flatten_model
from virtual_machine.reach.lathe import check_lathe_reach
from virtual_machine.runtime.integrator import Integrator
from virtual_machine.runtime.loop import AxisLoad, MachineLoop, ToolLoad
from virtual_machine.runtime.machine_run import error_stats
from virtual_machine.setting.sheet import thread_sheet
from virtual_machine.setting.thread_layout import thread_layout
from virtual_machine.structures.thread_group import (
    ThreadCnc,
    ThreadEqualCoordinates,
    ThreadMasterSlave,
    ThreadMechanical,
    ThreadTuning,
)


@dataclass
class ThreadRecord:
    """Per servo tick: time [s], B1, TV, M1, M2 [rad], P2 [mm], motor torques (M1, M2) [N m], lead error [um];
    ``on_thread``: the tool on the threaded length (after the run-up and the clearance)."""

    form: str
    lead: float  # thread lead P [mm]
    hand_sign: int
    runup: float  # s
    t: np.ndarray
    b1: np.ndarray
    p2: np.ndarray
    tv: np.ndarray
    m1: np.ndarray
    m2: np.ndarray
    torque: np.ndarray  # (n, 2)
    lead_error_um: np.ndarray
    on_thread: np.ndarray
    #: (n, 3) cutting forces on the tool [N] (F_c tangential, F_f axial against the feed, F_p radial off the work),
    #: the mean over each tick's physics steps; None when the run had no cutting load
    force: np.ndarray | None = None

    def stats(self) -> dict[str, float]:
        """Lead error statistics while the tool is on the thread [um] (as MotionRecord.sync_stats)."""
        return error_stats(self.lead_error_um[self.on_thread])

    def drift(self) -> tuple[float, float]:
        """The lead error's change along the thread from a straight-line fit against the carriage position [um],
        and the carriage travel on the thread [mm] (signed). A realised lead P (1 + eps) drifts eps * travel."""
        z, e = self.p2[self.on_thread], self.lead_error_um[self.on_thread]
        slope = np.polyfit(z - z[0], e, 1)[0]
        travel = float(z[-1] - z[0])
        return float(slope * travel), travel


@dataclass(frozen=True)
class CuttingLoad:
    """A cutting load on the lathe (vibration turning): ``force(t, theta, z)`` is called at every physics step with
    the time [s], the spindle angle theta = B1 - B1_0 [rad] and the carriage's travel along the feed z =
    hand_sign (P2 - P2_0) [mm], and returns the forces on the tool (F_c, F_f, F_p) [N]. They act at the tool's
    cutting point (``radius`` [mm] from the axis, on the spindle's +x side, at the carriage's z): on the carriage
    F_p along +x (off the work), F_c along +y (with the workpiece's surface, the spindle turning about +z) and F_f
    against the feed; reversed on the spindle (its torque F_c radius brakes it)."""

    force: Callable[[float, float, float], tuple[float, float, float]]
    radius: float


def _ramp(t: float, runup: float) -> float:
    """Smooth run-up 0 -> 1 (half cosine: zero acceleration at both ends)."""
    return 1.0 if t >= runup else 0.5 * (1.0 - math.cos(math.pi * t / runup))


def build_thread_structure(
    job: Job, params: ThreadLatheParams, angle0: tuple[float, float], tuning=None, vibration=None
):
    """The controllers of the job's form with its setting sheet: ThreadMechanical / MasterSlave / EqualCoordinates.
    ``vibration`` (:class:`cutting.turning.vibration.FeedVibration`): the feed vibration of vibration turning,
    made by the slave's command (master-slave only: the feed axis follows the spindle's encoder)."""
    m = job.machine
    lay = thread_layout(job, params)
    sheet = thread_sheet(job, "mechanical" if lay.form == "mechanical" else "mechatronic")
    st = sheet.settings
    base = tuning or ThreadTuning()
    tuning = ThreadTuning(  # the amplifiers' current limits are the motors' peak torques of the model
        replace(base.spindle, peak_torque=params.spindle_motor_torque),
        replace(base.carriage, peak_torque=params.screw_motor_torque),
    )
    r_sp = lay.spindle_ratio
    j_carriage = params.screw_inertia + params.carriage_mass * lay.screw_lead**2
    if lay.form == "mechanical":
        j_m1 = params.spindle_motor_inertia + (params.spindle_inertia + j_carriage * lay.chain_ratio**2) * r_sp**2
        return ThreadMechanical(lay.motor_speed, tuning.spindle, j_m1)
    j_m1 = params.spindle_motor_inertia + params.spindle_inertia * r_sp**2
    j_m2 = params.screw_motor_inertia + j_carriage * lay.feed_ratio**2
    adaptive = m.adaptive_correction
    pulses = None
    if vibration is not None:
        if lay.form != "master-slave":
            raise InputError(
                Problem(
                    "machine.synchronization",
                    lay.form,
                    "vibration turning needs the feed axis to follow the spindle's encoder, so that the vibration "
                    "stays synchronised to it",
                    "use machine.structure = 'mechatronic' with machine.synchronization = 'master-slave'",
                ),
                job.source,
            )
        per_m = m.command_pulses_per_rev / (2 * math.pi) / lay.feed_ratio / lay.screw_lead  # M2 pulses per m

        def pulses(theta: float) -> float:
            return float(vibration.axial(theta)) * MM * per_m

    if lay.form == "master-slave":
        kx = st["kx"].realisation
        return ThreadMasterSlave(
            lay.motor_speed,
            kx["block_N"],
            kx["counter_K"],
            lay.hand_sign,
            m.command_pulses_per_rev,
            m.encoder_lines,
            lay.feed_ratio,
            (j_m1, j_m2),
            adaptive,
            tuning,
            angle0,
            pulses,
        )
    return ThreadEqualCoordinates(
        m.reference_frequency,
        st["kv"].realisation["integer"],
        st["kx"].realisation["integer"],
        lay.hand_sign,
        m.command_pulses_per_rev,
        m.encoder_lines,
        r_sp,
        lay.feed_ratio,
        (j_m1, j_m2),
        adaptive,
        tuning,
        angle0,
    )


def simulate_thread(
    job: Job,
    params: ThreadLatheParams | None = None,
    duration: float | None = None,
    disturbance: Callable[[float], float] | None = None,
    servo_substeps: int = 2,
    vibration=None,
    cut: CuttingLoad | None = None,
) -> ThreadRecord:
    """Run-up and the first threading stroke of ``job``, until the tool leaves the thread (``duration`` [s]
    overrides that). ``disturbance(t)`` is an extra torque on the spindle [N m] (a load on the master);
    ``vibration`` a feed vibration (vibration turning, seed 004) on the slave's command; ``cut`` the cutting load
    (:class:`CuttingLoad`), applied before every physics step (:class:`LatheLoad` on the machine loop).
    Raises :class:`cutting.errors.SimulationDivergedError` when MuJoCo reports bad accelerations."""
    params = params or override(ThreadLatheParams(), flatten_model(job.machine.model))
    lay = thread_layout(job, params)
    feed = lay.lead * lay.spindle_speed / (2 * math.pi)  # m/s
    runup = params.runup_time
    t_end = duration if duration is not None else runup + (lay.approach - feed * runup / 2 + lay.length) / feed
    check_lathe_reach(job, params, lay, t_end)  # before the model: a stroke beyond the lathe is an input error
    stroke = LatheStroke(job, params, lay, t_end, servo_substeps, vibration)
    hook = None
    if cut is not None or disturbance is not None:
        hook = LatheLoad(stroke, cut, disturbance, lay.hand_sign)
    MachineLoop(stroke.integrator, stroke, hook, stroke.body("carriage"), stroke.body("spindle")).run()
    return stroke.record(hook.forces if cut is not None else None)


class LatheStroke:
    """The lathe's task on the machine loop: before each tick the run-up's ramp and the structure's controllers,
    after it the tick's record; the program ends after ``t_end`` [s]."""

    def __init__(self, job: Job, params: ThreadLatheParams, lay, t_end: float, servo_substeps: int, vibration):
        self.lay = lay
        self.model = model = build_thread_lathe_spec(lay, params).compile()
        self.data = data = mujoco.MjData(model)
        mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
        mujoco.mj_forward(model, data)
        jnt = {model.joint(j).name: j for j in range(model.njnt)}
        self.qadr = {n: int(model.jnt_qposadr[j]) for n, j in jnt.items()}
        self.vadr = {n: int(model.jnt_dofadr[j]) for n, j in jnt.items()}
        self.electronic = "M2" in jnt
        self._q = [self.qadr[j] for j in ("B1", "P2", "TV", "M1")] + [self.qadr.get("M2")]
        self._v = (self.vadr["M1"], self.vadr.get("M2"))
        self._acts = (model.actuator("M1").id, model.actuator("M2").id if self.electronic else None)
        self.b1_0, self.p2_0 = float(data.qpos[self.qadr["B1"]]), float(data.qpos[self.qadr["P2"]])
        angle0 = (self.b1_0, float(data.qpos[self.qadr["TV"]]))
        self.structure = build_thread_structure(job, params, angle0, vibration=vibration)
        self.dt = model.opt.timestep * servo_substeps
        self.n = round(t_end / self.dt)
        self.rows = np.empty((self.n, 8))
        self.runup = params.runup_time
        self.cnc = ThreadCnc()
        self.k = 0
        self._torques = (0.0, 0.0)
        self.integrator = Integrator(model, data, servo_substeps, self.qadr["P2"], self._diverged)

    def body(self, name: str) -> int:
        return int(self.model.body(name).id)

    def _diverged(self, t: float) -> str:  # t: the tick's start (MuJoCo resets the state it blew up in)
        return (
            f"the thread lathe diverged at t = {t:.4f} s (MuJoCo reported bad accelerations): "
            f"lower a stage's stiffness, raise its damping or reduce the timestep (now {self.model.opt.timestep:g} s)"
        )

    def before_tick(self) -> bool:
        if self.k == self.n:
            return False
        qpos, qvel, ctrl = self.data.qpos, self.data.qvel, self.data.ctrl
        i_b1, _, i_tv, _, _ = self._q
        self.cnc.scale = _ramp(self.k * self.dt, self.runup)
        v_m1, v_m2 = self._v
        speeds = (qvel[v_m1], qvel[v_m2] if self.electronic else 0.0)
        t1, t2 = self.structure.tick(self.dt, self.cnc, (qpos[i_b1], qpos[i_tv]), speeds)
        a_m1, a_m2 = self._acts
        ctrl[a_m1] = t1
        if self.electronic:
            ctrl[a_m2] = t2
        self._torques = (t1, t2)
        return True

    def after_tick(self) -> None:
        qpos = self.data.qpos
        i_b1, i_p2, i_tv, i_m1, i_m2 = self._q
        m2 = qpos[i_m2] if self.electronic else 0.0
        self.rows[self.k] = (self.data.time, qpos[i_b1], qpos[i_p2], qpos[i_tv], qpos[i_m1], m2, *self._torques)
        self.k += 1

    def record(self, forces: np.ndarray | None) -> ThreadRecord:
        lay, rows = self.lay, self.rows
        b1, p2 = rows[:, 1], rows[:, 2]
        error = (p2 - self.p2_0) - lay.lead / (2 * math.pi) * (b1 - self.b1_0) * lay.hand_sign
        travel = np.abs(p2 - self.p2_0)
        return ThreadRecord(
            form=lay.form,
            lead=lay.lead / MM,
            hand_sign=lay.hand_sign,
            runup=self.runup,
            t=rows[:, 0],
            b1=b1,
            p2=p2 * 1e3,
            tv=rows[:, 3],
            m1=rows[:, 4],
            m2=rows[:, 5],
            torque=rows[:, 6:8],
            lead_error_um=error * 1e6,
            on_thread=(travel >= lay.approach) & (travel <= lay.approach + lay.length),
            force=forces,
        )


class LatheLoad:
    """The lathe's load hook: the cutting load (:class:`CuttingLoad`) before every physics step from the state then,
    at the tool's cutting point on the carriage (reversed on the spindle), and a disturbance torque on the spindle;
    ``forces`` per tick the mean (F_c, F_f, F_p) [N] over its sub-steps.

    mj_applyFT builds the Jacobian at the cutting point from ``data``'s kinematics, which ``mj_step`` leaves one step
    old (library notes A5). Here that is exact: B1 turns about the world z axis through the origin and P2 slides
    along z, so the Jacobian of a given world point does not depend on the configuration; the point itself is
    taken from the current ``qpos``."""

    def __init__(self, stroke: LatheStroke, cut: CuttingLoad | None, disturbance, hand_sign: int):
        self.every_substep = cut is not None  # the chip follows the spindle's angle within the tick
        self.stroke, self.cut, self.disturbance = stroke, cut, disturbance
        self.hand = float(hand_sign)
        self.dof_b1 = stroke.vadr["B1"]
        self.i_b1, self.i_p2 = stroke.qadr["B1"], stroke.qadr["P2"]
        self.forces = np.zeros((stroke.n, 3)) if cut is not None else None
        self._tick, self._sum, self._count = -1, np.zeros(3), 0

    def __call__(self, t: float, dt: float) -> list[ToolLoad | AxisLoad]:
        stroke = self.stroke
        out: list[ToolLoad | AxisLoad] = []
        if self.disturbance is not None:
            out.append(AxisLoad(self.dof_b1, float(self.disturbance(stroke.k * stroke.dt))))
        if self.cut is None:
            return out
        if stroke.k != self._tick:  # the tick's first sub-step
            self._tick, self._count = stroke.k, 0
            self._sum[:] = 0.0
        qpos = stroke.data.qpos
        z = float(qpos[self.i_p2])
        fc, ff, fp = self.cut.force(t, float(qpos[self.i_b1]) - stroke.b1_0, self.hand * (z - stroke.p2_0) * 1e3)
        self._sum += (fc, ff, fp)
        self._count += 1
        self.forces[stroke.k] = self._sum / self._count
        if fc or ff or fp:
            point = np.array([self.cut.radius * 1e-3, 0.0, z])
            out.append(ToolLoad(np.array([fp, fc, -self.hand * ff]), np.zeros(3), point))
        return out
