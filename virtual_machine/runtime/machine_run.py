"""The simulation loop (fixed, dm_control style): CNC tick -> controllers -> physics sub-steps -> record.

Controllers run at the servo rate (``servo_substeps`` physics steps per tick, torques held between); the
record keeps per tick the axis positions, motor torques and the synchronisation error, and per pass the
pose trajectory of the cutter in the blank frame (the cutting engine's input).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco
import numpy as np

from cutting.errors import InputError, Problem
from cutting.skiving.path_correction import PathCorrection
from machine_models.parameters import SkivingMachineParams, override
from machine_models.sizes import size_for, size_params
from machine_models.skiving_machine import MM, build_spec
from machine_models.structure_drives import MOTOR_TORQUE_KEYS
from virtual_machine.controllers import InductionMotor
from virtual_machine.job import Job, flatten_model
from virtual_machine.runtime.integrator import Integrator
from virtual_machine.runtime.physics import AXES, MachinePhysics
from virtual_machine.runtime.program import ProgramSettings, program
from virtual_machine.setting.chains import chain_ratios
from virtual_machine.setting.machine_layout import skiving_layout, workpiece_diameter
from virtual_machine.setting.plan import SkivingPlan, plan_of
from virtual_machine.setting.sheet import setup_sheet
from virtual_machine.structures.hydraulic import HydraulicS2, HydraulicS3
from virtual_machine.structures.mechanical import MechanicalS1
from virtual_machine.structures.mechatronic import MechatronicS4, MechatronicS4MasterSlave, S4Tuning

SEGMENTS = ("runup", "settle", "infeed", "feed", "retract", "return")


class LostSynchronismError(RuntimeError):
    """The simulated machine stopped the job (the CNC's alarm), with what happened and what to change."""


def error_stats(e: np.ndarray) -> dict[str, float]:
    """Mean, RMS, RMS about the mean, peak-to-peak and largest magnitude of an error series [um] ({} if empty)."""
    if e.size == 0:
        return {}
    return {
        "mean_um": float(e.mean()),
        "rms_um": float(np.sqrt(np.mean(e**2))),
        "rms_about_mean_um": float(e.std()),
        "peak_to_peak_um": float(e.max() - e.min()),
        "max_abs_um": float(np.abs(e).max()),
    }


@dataclass
class PassTrajectory:
    """Poses of the cutter frame in the blank frame during one feed stroke: t [s] from the stroke's start."""

    index: int
    t: np.ndarray
    rot: np.ndarray  # (n, 3, 3)
    trans: np.ndarray  # (n, 3) mm
    cutter_angle: np.ndarray  # B1 [rad]
    carriage: np.ndarray  # P3 [mm]
    centre_distance: np.ndarray  # X [mm]


@dataclass
class MotionRecord:
    t: np.ndarray
    q: np.ndarray  # (n, len(AXES)): B1, B2 [rad], P3, X [mm], TV [rad]
    torque: np.ndarray  # (n, len(actuators)) [N m]
    sync_um: np.ndarray  # synchronisation error as arc on the work reference circle [um]
    segment: np.ndarray  # index into SEGMENTS
    pass_index: np.ndarray
    cutting: np.ndarray  # feed ticks in which the cutter can be in the blank (|P3| <= b/2 + engagement)
    actuators: tuple[str, ...] = ("M1", "M2", "M3")
    model_xml: str = ""  # the MJCF the run used
    passes: list[PassTrajectory] = field(default_factory=list)

    def sync_stats(self, during: str = "cut") -> dict[str, float]:
        """Synchronisation error statistics over a segment kind, or "cut": while the cutter can touch the blank."""
        sel = self.cutting if during == "cut" else self.segment == SEGMENTS.index(during)
        return error_stats(self.sync_um[sel])

    def periodic_part(self, teeth: int | None = None, bins: int = 64) -> dict[str, dict[str, float]]:
        """Synchronous averages of the sync error while cutting: per work revolution (shows as pitch and runout),
        per work tooth pitch (``teeth`` = z2; repeats in every space) and per cutter revolution. Peak-to-peak
        and RMS of each averaged curve [um]."""
        sel = self.cutting
        if sel.sum() < bins:
            return {}
        e = self.sync_um[sel] - self.sync_um[sel].mean()
        out = {}
        periods = {"work_revolution": (self.q[sel, 1], 1), "cutter_revolution": (self.q[sel, 0], 1)}
        if teeth:
            periods["work_tooth"] = (self.q[sel, 1], teeth)
        for name, (angle, n) in periods.items():
            phase = np.mod(angle * n / (2 * np.pi), 1.0)
            k = np.minimum((phase * bins).astype(int), bins - 1)
            count = np.bincount(k, minlength=bins)
            avg = np.bincount(k, weights=e, minlength=bins)[count > 0] / count[count > 0]
            out[name] = {"peak_to_peak_um": float(np.ptp(avg)), "rms_um": float(np.sqrt(np.mean(avg**2)))}
        return out


def machine_size(job: Job) -> str:
    """The name of the job's machine size: ``machine.size``, else the smallest size whose workpiece diameter and
    module hold the gear (machine_models/sizes.py)."""
    return job.machine.get("size") or size_for(workpiece_diameter(job.gear), job.gear.mn).name


def machine_params(job: Job) -> SkivingMachineParams:
    """The job's machine: its size's parameters with the job's [machine.model] overrides on top."""
    return override(size_params(machine_size(job)), flatten_model(job.machine.get("model")))


def build_structure(
    job: Job,
    params: SkivingMachineParams,
    phys: MachinePhysics,
    adaptive: bool | None = None,
    plan: SkivingPlan | None = None,
):
    """The controls of the job's structure with its setting sheet (``plan``: the run's, if handed on): S4
    (equal coordinates) here, S1-S3 in :func:`_build_chain_structure`."""
    m = job.machine
    plan = plan_of(job, plan)
    if m["structure"] in ("mechanical", "hydraulic-differential", "hydraulic-shaft"):
        return _build_chain_structure(job, params, phys, plan)
    if m["structure"] != "mechatronic":
        raise NotImplementedError(f"machine.structure = {m['structure']!r}: unknown structure")
    sheet = plan.sheet("mechatronic")
    st = sheet.settings
    setup = job.skiving
    j_tool = params.tool_motor_inertia + params.tool_inertia * params.tool_drive.ratio**2
    j_work = params.work_motor_inertia + params.work_inertia * params.work_drive.ratio**2
    lead = m["lead_screw_pitch"] * MM / (2 * math.pi)
    j_feed = (
        params.feed_motor_inertia + (params.screw_inertia + params.carriage_mass * lead**2) * params.feed_drive.ratio**2
    )
    ky = st["ky"].realisation.get("integer")
    adaptive = m["adaptive_correction"] if adaptive is None else adaptive
    # the amplifiers' current limits are the motors' peak torques of the machine (amplifiers 3, 11, 18)
    base = S4Tuning()
    tuning = S4Tuning(
        dataclasses.replace(base.tool, peak_torque=params.tool_motor_torque),
        dataclasses.replace(base.work, peak_torque=params.work_motor_torque),
        dataclasses.replace(base.feed, peak_torque=params.feed_motor_torque),
    )
    angle0 = (phys.q("B1"), phys.q("B2"), phys.q("TV"))
    if m["synchronization"] == "master-slave":
        feed_dir = -1 if setup.feed_direction == "down" else 1
        t_tv = m["lead_screw_pitch"]
        return MechatronicS4MasterSlave(
            f_ref=m["reference_frequency"],
            p=m["command_pulses_per_rev"],
            kv=st["kv"].realisation["integer"],
            ratio_x=setup.speed_ratio,  # work turn per tool turn
            ratio_y=setup.differential_rotation_per_mm * t_tv / (2 * math.pi),  # work rad per screw rad (B4)
            ratio_s=feed_dir * setup.axial_feed / t_tv * (1 if setup.speed_ratio > 0 else -1),  # screw per work
            encoder_lines=m["encoder_lines"],
            ratios=(params.tool_drive.ratio, params.work_drive.ratio, params.feed_drive.ratio),
            inertias=(j_tool, j_work, j_feed),
            adaptive=adaptive,
            angle0=angle0,
            tuning=tuning,
        )
    return MechatronicS4(
        f_ref=m["reference_frequency"],
        p=m["command_pulses_per_rev"],
        kv=st["kv"].realisation["integer"],
        kx=st["kx"].realisation["integer"],
        ks=st["ks"].realisation["integer"],
        ky=ky,
        dir_work=1 if setup.speed_ratio > 0 else -1,
        dir_b4=1 if setup.differential_rotation_per_mm > 0 else -1,
        encoder_lines=m["encoder_lines"],
        ratios=(params.tool_drive.ratio, params.work_drive.ratio, params.feed_drive.ratio),
        inertias=(j_tool, j_work, j_feed),
        adaptive=adaptive,
        angle0=angle0,
        tuning=tuning,
    )


def _build_chain_structure(job: Job, params: SkivingMachineParams, phys: MachinePhysics, plan: SkivingPlan):
    """S1 and S2: the main motor, and the CNC's or the hydraulic elements beside the chains of the model."""
    m = job.machine
    motor = InductionMotor(
        sync_speed=m["motor_speed"] * 2 * math.pi / 60 / (1 - params.main_motor_slip),
        rated_torque=params.main_motor_torque,
        rated_slip=params.main_motor_slip,
    )
    if m["structure"] == "mechanical":
        return MechanicalS1(
            motor, m["command_pulses_per_rev"], m["encoder_lines"], params.traverse_motor_inertia, phys.q("TV")
        )
    stepping = {
        "steps_per_rev": m["hydraulic_steps_per_rev"],
        "stiffness": params.hydraulic_stiffness,
        "damping": params.hydraulic_damping,
        "leakage": params.hydraulic_leakage,
        "torque_limit": params.hydraulic_torque_limit,
    }
    if m["structure"] == "hydraulic-shaft":
        reverse = "up" if job.process["feed_direction"] == "down" else "down"
        back = dataclasses.replace(job, process=dict(job.process, feed_direction=reverse))
        sheets = (plan.sheet("hydraulic-shaft"), setup_sheet(back, "hydraulic-shaft"))  # the return stroke's own
        discs = tuple(s.settings["kx"].realisation["disc_windows"] for s in sheets)
        home = {j: phys.q(j) for j in ("B2", "TV", "GShD")}
        return HydraulicS3(motor, discs, stepping, m["command_pulses_per_rev"], m["encoder_lines"], home)
    sheet = plan.sheet("hydraulic-differential")
    windows = tuple(sheet.settings[k].realisation.get("disc_windows") for k in ("kx", "ky", "is"))
    home = {j: phys.q(j) for j in ("B1", "B2", "TV", "GShD1", "GShD2", "GShD3")}
    return HydraulicS2(
        motor, windows, stepping, m["command_pulses_per_rev"], m["encoder_lines"], chain_ratios(job).feed, home
    )


def check_correction(job: Job, correction: PathCorrection | None) -> None:
    """A tangential correction needs the electronic gearbox's summator 9 (S4, equal coordinates); the radial one
    every structure's radial slide makes."""
    if correction is None or not np.any(correction.dphi):
        return
    m = job.machine
    if m["structure"] != "mechatronic" or m["synchronization"] != "equal-coordinates":
        raise InputError(
            Problem(
                "machine.structure",
                f"{m['structure']} / {m['synchronization']}",
                "the job's [modification] needs a tangential correction (different helices on the two flanks, or a "
                "helix angle modification), which only the electronic gearbox's summator 9 adds to the work's turn",
                'use structure = "mechatronic" with synchronization = "equal-coordinates", or a design the same on '
                "both flanks (a radial correction alone)",
            )
        )


class MachineRun:
    """The simulation loop as a stepper: :meth:`advance` runs the machine up to a time, so another stage (the
    cutting co-simulation) can act between calls; :meth:`record` assembles the :class:`MotionRecord`.

    Without ``params`` the machine is the job's own (:func:`machine_params`: its size with the [machine.model]
    overrides), and a job whose estimated cutting torque its motors cannot hold is refused before anything runs
    (virtual_machine/processes/skiving/cutting_load.py: InputError naming the motor); given ``params`` are taken as
    they are (tests,
    benchmarks). Without ``settings`` the run-up follows the machine's ``work_acceleration``.
    ``plan``: the job's setup, ideal passes and setting sheets as an earlier stage made them (else made here).

    ``load``, if set, gives the cutting loads of a servo tick, ``load(t, dt)``: (force [N] on the workpiece,
    point [mm], moment [N m]) in the blank frame, one per engaged tooth, each the mean over [t, t + dt]; each is
    applied to the blank and (opposite) to the cutter for the tick.
    """

    def __init__(
        self,
        job: Job,
        params: SkivingMachineParams | None = None,
        servo_substeps: int = 2,
        settings: ProgramSettings | None = None,
        disturbance: Callable[[float], float] | None = None,
        disturbance_axis: str = "B2",
        correction: PathCorrection | None = None,
        plan: SkivingPlan | None = None,
    ):
        self.job = job
        self.plan = plan = plan_of(job, plan)
        if params is None:  # the job's own machine: refused before the run if its motors cannot hold the cut
            from virtual_machine.processes.skiving.cutting_load import check_machine_holds
            from virtual_machine.processes.skiving.machine_reach import check_machine_reach

            params = machine_params(job)
            check_machine_reach(job, params, machine_size(job))
            check_machine_holds(job, params)
        self.params = params
        self.setup = setup = plan.setup
        structure = job.machine["structure"]
        chains = chain_ratios(job) if structure != "mechatronic" else None
        layout = skiving_layout(setup, job.machine["lead_screw_pitch"], plan.passes[0])
        self.spec = build_spec(layout, self.params, structure, chains)
        self.phys = phys = MachinePhysics(self.spec.compile(), self.params)
        self.machine = machine = build_structure(job, self.params, phys, plan=plan)
        self.servo_substeps = servo_substeps
        self.dt = phys.model.opt.timestep * servo_substeps
        # the tick's physics; a divergence names the stage to soften (at the time MuJoCo leaves after the step)
        self.integrator = Integrator(phys.model, phys.data, servo_substeps, phys.qadr["B2"], phys.diagnose)
        p = job.machine["command_pulses_per_rev"]
        ppm = p / job.machine["lead_screw_pitch"]  # screw pulses per mm of carriage
        settings = settings or ProgramSettings(runup_acceleration=self.params.work_acceleration)
        check_correction(job, correction)
        self.work_pulses_per_rad = p / (2 * math.pi)  # B4 command pulses of the work axis per radian
        self._ticks = program(
            setup, self.dt, ppm, machine, settings, correction, self.work_pulses_per_rad, passes=plan.passes
        )
        self.corrections: list[float] = []  # the tangential correction asked for at each tick [rad]
        # the CNC of the servo structures watches the synchronisation (following error); a chain has no CNC loop
        self.following_limit = settings.following_error_limit if structure == "mechatronic" else math.inf
        self._pending = None  # a tick fetched from the program but not yet run
        self.finished = False  # the program has ended
        self.disturbance, self.load = disturbance, None
        self._dof_dist = phys.vadr[disturbance_axis]
        self.rows: list[tuple] = []
        self.home = (phys.q("B1"), phys.q("B2"), phys.q("P3") / MM)
        self.timing = {"physics": 0.0, "control": 0.0}
        # with a cutting load: the work the load does on the machine and the work of the actuators [J] (per tick),
        # and per tick the load's resultant on the workpiece (blank frame) [N] and its torque about the work axis
        self.load_work = self.actuator_work = 0.0
        self.load_rows: list[tuple[float, float, float, float, float]] = []
        self._clutch_state: dict[str, bool] = {}
        self._last_cnc = None

    @property
    def time(self) -> float:
        return self.phys.time

    def advance(self, until: float = math.inf, progress: Callable[[float], None] | None = None) -> bool:
        """Run servo ticks while the machine time is below ``until`` [s]; False once the program has ended."""
        phys, machine, dt, step = self.phys, self.machine, self.dt, self.integrator.step
        data = phys.data
        qpos, qvel, ctrl, qfrc = data.qpos, data.qvel, data.ctrl, data.qfrc_applied
        qa = [phys.qadr[a] for a in AXES]
        sensors = [phys.qadr[j] for j in machine.sensors]
        speeds = [phys.vadr[j] for j in machine.speeds]
        acts = [phys.act[a] for a in machine.actuators]
        radial = phys.act["X"]
        segment_index = {name: k for k, name in enumerate(SEGMENTS)}
        rows, clock, disturbance, load = self.rows, time.perf_counter, self.disturbance, self.load
        t_phys = t_ctrl = 0.0
        b1, b2, p3 = phys.qadr["B1"], phys.qadr["B2"], phys.qadr["P3"]
        b1_0, b2_0, p3_0 = self.home
        ratio, diff = self.setup.speed_ratio, self.setup.differential_rotation_per_mm
        limit = self.following_limit / (self.setup.gear.reference_radius * 1e3)  # rad of work spindle
        while data.time < until:
            tick = self._pending or next(self._ticks, None)
            self._pending = None
            if tick is None:
                self.finished = True
                break
            ctrl[radial] = tick.radial  # the radial slide's position servo target [m]
            if tick.cnc is not self._last_cnc:  # the CNC's state objects are shared while a segment holds them
                self._last_cnc = tick.cnc
                for tendon, on in machine.clutches(tick.cnc).items():
                    if self._clutch_state.get(tendon) != on:
                        phys.engage(tendon, on)
                        self._clutch_state[tendon] = on
            c0 = clock()
            torques = machine.tick(dt, tick.cnc, qpos.take(sensors).tolist(), qvel.take(speeds).tolist())
            c1 = clock()
            ctrl[acts] = torques
            if disturbance is not None or load is not None:
                qfrc[:] = 0.0
                if disturbance is not None:
                    qfrc[self._dof_dist] = disturbance(data.time)
                if load is not None:
                    fx = fy = fz = tz = 0.0
                    for force, point, moment in load(data.time, dt):
                        phys.apply_cutting_load(force, point, moment)
                        fx, fy, fz = fx + force[0], fy + force[1], fz + force[2]
                        tz += (point[0] * force[1] - point[1] * force[0]) * 1e-3 + moment[2]
                    self.load_rows.append((data.time, fx, fy, fz, tz))
            step()
            if load is not None:
                self.load_work += float(qfrc @ qvel) * dt
                self.actuator_work += float(data.actuator_force @ data.actuator_velocity) * dt
            c2 = clock()
            t_ctrl += c1 - c0
            t_phys += c2 - c1
            rows.append((data.time, *qpos.take(qa).tolist(), segment_index[tick.segment], tick.pass_index, *torques))
            wanted = tick.cnc.correction_b4 / self.work_pulses_per_rad  # a modification's extra turn is no error
            self.corrections.append(wanted)
            delta = (qpos[b2] - b2_0) - ratio * (qpos[b1] - b1_0) - diff * (qpos[p3] / MM - p3_0) - wanted
            if abs(delta) > limit:
                raise LostSynchronismError(self._lost_synchronism(delta))
            if progress is not None:
                progress(data.time)
        self.timing["physics"] += t_phys
        self.timing["control"] += t_ctrl
        return not self.finished

    def _lost_synchronism(self, delta: float) -> str:
        """What the CNC's following-error alarm says: where, how far, which motors were at their limit."""
        rows = self.rows[-round(0.2 / self.dt) :]
        n_ax = len(AXES)
        torques = np.abs(np.array([r[3 + n_ax :] for r in rows])).max(axis=0)
        last = rows[-1]
        seg = SEGMENTS[int(last[1 + n_ax])]
        model = self.phys.model
        keys = MOTOR_TORQUE_KEYS.get(self.job.machine["structure"], {})
        peaks, saturated = [], []
        for name, value in zip(self.machine.actuators, torques, strict=True):
            limit = float(model.actuator_ctrlrange[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, name), 1])
            at_limit = value >= 0.98 * limit
            peaks.append(f"{name} {value:.1f} N m" + (f" (its limit, machine.model.{keys[name]})" if at_limit else ""))
            if at_limit and name in keys:
                saturated.append(f"machine.model.{keys[name]}")
        um = delta * self.setup.gear.reference_radius * 1e3
        more = f"give the motor at its limit more torque ({', '.join(saturated)})" if saturated else ""
        if seg == "feed" and saturated:  # cutting: the chips' torque is what the motor cannot hold
            remedy = f"{more}, or take less per pass (process.passes) or a smaller process.axial_feed"
        else:
            remedy = f"lower process.tool_speed (work spindle {abs(self.setup.work_speed):.0f} rpm), or " + (
                more or "give the work drive more torque or less inertia ([machine.model])"
            )
        return (
            f"the machine lost synchronism at t = {last[0]:.3f} s ({seg}): the work spindle is {um:+.0f} um of arc "
            f"on the reference circle off the position the tool spindle and carriage imply (the CNC's following-error "
            f"limit is {self.following_limit:.0f} um). Peak motor torques over the last 0.2 s: {', '.join(peaks)}. "
            f"{remedy[0].upper()}{remedy[1:]}"
        )

    def record(self) -> MotionRecord:
        """The motion record of everything run so far."""
        setup = self.setup
        b1_0, b2_0, p3_0 = self.home
        ratio, diff = setup.speed_ratio, setup.differential_rotation_per_mm
        r2 = setup.gear.reference_radius
        feed = SEGMENTS.index("feed")
        a = np.array(self.rows)
        n_ax = len(AXES)
        q = a[:, 1 : 1 + n_ax].copy()
        b1, b2, p3 = q[:, 0], q[:, 1], q[:, 2] / MM
        delta = (b2 - b2_0) - ratio * (b1 - b1_0) - diff * (p3 - p3_0) - np.asarray(self.corrections)
        q[:, 2:4] /= MM  # P3, X in mm
        segment, pass_index = a[:, 1 + n_ax].astype(int), a[:, 2 + n_ax].astype(int)
        reach = np.array(
            [setup.gear.face_width / 2 + setup.engagement_half_length(c) for c in setup.pass_centre_distances]
        )
        cutting = (segment == feed) & (np.abs(q[:, 2]) <= reach[np.clip(pass_index, 0, len(reach) - 1)])
        rec = MotionRecord(
            t=a[:, 0],
            q=q,
            torque=a[:, 3 + n_ax :],
            actuators=tuple(self.machine.actuators),
            model_xml=self.spec.to_xml(),
            sync_um=r2 * delta * 1e3,
            segment=segment,
            pass_index=pass_index,
            cutting=cutting,
        )
        for index in sorted(set(rec.pass_index[rec.segment == feed].tolist())):
            sel = (rec.segment == feed) & (rec.pass_index == index)
            rec.passes.append(pass_trajectory(setup, index, rec.t[sel], rec.q[sel]))
        return rec


def pass_trajectory(setup, index: int, t: np.ndarray, q: np.ndarray) -> PassTrajectory:
    """The pose trajectory of one feed stroke from its recorded axis positions (t from the stroke's start)."""
    rot, trans = relative_pose(setup, q)
    return PassTrajectory(index, t - t[0], rot, trans, q[:, 0], q[:, 2], q[:, 3])


def simulate(
    job: Job,
    params: SkivingMachineParams | None = None,
    duration: float | None = None,
    servo_substeps: int = 2,
    settings: ProgramSettings | None = None,
    disturbance: Callable[[float], float] | None = None,
    disturbance_axis: str = "B2",
    progress: Callable[[float], None] | None = None,
    timing: dict[str, float] | None = None,
    plan: SkivingPlan | None = None,
) -> MotionRecord:
    """Run the machine through the job's passes (no cutting). ``duration`` [s] stops early; ``disturbance(t)``
    is an extra torque [N m] (or force [N]) on ``disturbance_axis`` (tests of the correction and the schemes).
    ``timing``, if given, receives the seconds spent in the physics and in the controllers (benchmarks); ``plan``:
    the job's plan if the caller has it."""
    run = MachineRun(job, params, servo_substeps, settings, disturbance, disturbance_axis, plan=plan)
    run.advance(math.inf if duration is None else duration, progress)
    if timing is not None:
        timing.update(run.timing)
    return run.record()


def relative_pose(setup, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cutter frame in the blank frame for recorded axis values ``q`` (rows as MotionRecord.q).

    The bodies between the two frames are rigid, so this is the forward kinematics of the model
    (blank_frame = Rz(B2 + work_phase); cutter_frame at (X, 0, P3), Rx(tilt) Rz(B1 + cutter_phase));
    tests check it against MuJoCo's own site poses."""
    from cutting.skiving.setup import rot_x, rot_z

    back = rot_z(-(q[:, 1] + setup.work_phase))
    rot = back @ rot_x(setup.tilt) @ rot_z(q[:, 0] + setup.cutter_phase)
    centre = np.stack([q[:, 3], np.zeros(len(q)), q[:, 2]], -1)
    return rot, np.matmul(back, centre[:, :, None])[:, :, 0]
