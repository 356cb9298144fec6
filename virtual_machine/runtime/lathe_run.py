"""One threading stroke on the lathe of seed 001 (group Fv(B1 P2)): the fixed loop of
:mod:`virtual_machine.runtime.machine_run`
(controllers tick at the servo rate, physics sub-steps, record per tick) on the thread lathe model.

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

from machine_models.parameters import override
from machine_models.skiving_machine import MM
from machine_models.thread_lathe import ThreadLatheParams, build_thread_lathe_spec
from virtual_machine.job import Job, flatten_model
from virtual_machine.runtime.integrator import Integrator
from virtual_machine.runtime.lathe_reach import check_lathe_reach
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
    adaptive = m["adaptive_correction"]
    pulses = None
    if vibration is not None:
        if lay.form != "master-slave":
            raise ValueError(
                f"vibration turning needs machine.synchronization = 'master-slave' (the feed axis follows the "
                f"spindle's encoder, so the vibration stays synchronised to it); this job's form is {lay.form!r}"
            )
        per_m = m["command_pulses_per_rev"] / (2 * math.pi) / lay.feed_ratio / lay.screw_lead  # M2 pulses per m

        def pulses(theta: float) -> float:
            return float(vibration.axial(theta)) * MM * per_m

    if lay.form == "master-slave":
        kx = st["kx"].realisation
        return ThreadMasterSlave(
            lay.motor_speed,
            kx["block_N"],
            kx["counter_K"],
            lay.hand_sign,
            m["command_pulses_per_rev"],
            m["encoder_lines"],
            lay.feed_ratio,
            (j_m1, j_m2),
            adaptive,
            tuning,
            angle0,
            pulses,
        )
    return ThreadEqualCoordinates(
        m["reference_frequency"],
        st["kv"].realisation["integer"],
        st["kx"].realisation["integer"],
        lay.hand_sign,
        m["command_pulses_per_rev"],
        m["encoder_lines"],
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
    (:class:`CuttingLoad`), applied with ``mj_applyFT`` before every physics step (the servo tick's sub-steps are
    then stepped one by one).
    Raises :class:`virtual_machine.runtime.integrator.SimulationDivergedError` when MuJoCo reports bad
    accelerations."""
    params = params or override(ThreadLatheParams(), flatten_model(job.machine.get("model")))
    lay = thread_layout(job, params)
    feed = lay.lead * lay.spindle_speed / (2 * math.pi)  # m/s
    runup = params.runup_time
    t_end = duration if duration is not None else runup + (lay.approach - feed * runup / 2 + lay.length) / feed
    check_lathe_reach(job, params, lay, t_end)  # before the model: a stroke beyond the lathe is an input error
    model = build_thread_lathe_spec(lay, params).compile()
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    jnt = {model.joint(j).name: j for j in range(model.njnt)}
    qadr = {n: int(model.jnt_qposadr[j]) for n, j in jnt.items()}
    vadr = {n: int(model.jnt_dofadr[j]) for n, j in jnt.items()}
    electronic = "M2" in jnt
    i_b1, i_p2, i_tv, i_m1 = qadr["B1"], qadr["P2"], qadr["TV"], qadr["M1"]
    i_m2 = qadr.get("M2")
    v_m1, v_m2 = vadr["M1"], vadr.get("M2")
    a_m1 = model.actuator("M1").id
    a_m2 = model.actuator("M2").id if electronic else None
    qpos, qvel, ctrl, qfrc = data.qpos, data.qvel, data.ctrl, data.qfrc_applied
    dof_b1 = vadr["B1"]
    b1_0, p2_0 = float(qpos[i_b1]), float(qpos[i_p2])
    structure = build_thread_structure(job, params, (b1_0, float(qpos[i_tv])), vibration=vibration)
    dt = model.opt.timestep * servo_substeps
    n = round(t_end / dt)
    rows = np.empty((n, 8))
    cnc = ThreadCnc()

    def diverged(t: float) -> str:  # t: the tick's start (MuJoCo resets the state it blew up in)
        return (
            f"the thread lathe diverged at t = {t:.4f} s (MuJoCo reported bad accelerations): "
            f"lower a stage's stiffness, raise its damping or reduce the timestep (now {model.opt.timestep:g} s)"
        )

    if cut is None:
        step = Integrator(model, data, servo_substeps, i_p2, diverged).step
    else:
        step = _cutting_step(model, data, servo_substeps, Integrator(model, data, 1, i_p2, diverged).step, cut, lay)
    forces = np.zeros((n, 3)) if cut is not None else None
    for k in range(n):
        t = k * dt
        cnc.scale = _ramp(t, runup)
        t1, t2 = structure.tick(dt, cnc, (qpos[i_b1], qpos[i_tv]), (qvel[v_m1], qvel[v_m2] if electronic else 0.0))
        ctrl[a_m1] = t1
        if electronic:
            ctrl[a_m2] = t2
        if cut is None:
            if disturbance is not None:
                qfrc[dof_b1] = disturbance(t)
            step()
        else:
            forces[k] = step(disturbance(t) if disturbance is not None else 0.0)
        rows[k] = (data.time, qpos[i_b1], qpos[i_p2], qpos[i_tv], qpos[i_m1], qpos[i_m2] if electronic else 0.0, t1, t2)
    b1, p2 = rows[:, 1], rows[:, 2]
    error = (p2 - p2_0) - lay.lead / (2 * math.pi) * (b1 - b1_0) * lay.hand_sign
    travel = np.abs(p2 - p2_0)
    return ThreadRecord(
        form=lay.form,
        lead=lay.lead / MM,
        hand_sign=lay.hand_sign,
        runup=runup,
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


def _cutting_step(model: mujoco.MjModel, data: mujoco.MjData, substeps: int, step1, cut: CuttingLoad, lay):
    """One servo tick of ``substeps`` physics steps (``step1`` each), the cutting load applied before each from the
    state then (:class:`CuttingLoad`); returns the tick's mean forces (F_c, F_f, F_p) [N].

    mj_applyFT builds the Jacobian at the cutting point from ``data``'s kinematics, which ``mj_step`` leaves one step
    old (library notes A5). Here that is exact: B1 turns about the world z axis through the origin and P2 slides
    along z, so the Jacobian of a given world point does not depend on the configuration; the point itself is
    taken from the current ``qpos``."""
    qpos, qfrc = data.qpos, data.qfrc_applied
    i_b1, i_p2 = int(model.jnt_qposadr[model.joint("B1").id]), int(model.jnt_qposadr[model.joint("P2").id])
    dof_b1 = int(model.jnt_dofadr[model.joint("B1").id])
    body_c, body_s = int(model.body("carriage").id), int(model.body("spindle").id)
    b1_0, p2_0 = float(qpos[i_b1]), float(qpos[i_p2])
    hand, radius, force = float(lay.hand_sign), cut.radius * 1e-3, cut.force
    f, back, torque, point, total = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
    point[0] = radius
    apply = mujoco.mj_applyFT

    def step(extra_b1: float) -> np.ndarray:
        total[:] = 0.0
        for _ in range(substeps):
            z = float(qpos[i_p2])
            fc, ff, fp = force(data.time, float(qpos[i_b1]) - b1_0, hand * (z - p2_0) * 1e3)
            qfrc[:] = 0.0
            qfrc[dof_b1] = extra_b1
            if fc or ff or fp:
                f[0], f[1], f[2] = fp, fc, -hand * ff
                point[2] = z
                apply(model, data, f, torque, point, body_c, qfrc)
                np.negative(f, out=back)
                apply(model, data, back, torque, point, body_s, qfrc)
                total[0] += fc
                total[1] += ff
                total[2] += fp
            step1()
        qfrc[:] = 0.0
        return total / substeps

    return step
