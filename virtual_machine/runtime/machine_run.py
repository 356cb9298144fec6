"""The skiving machine on the machine loop (:mod:`virtual_machine.runtime.loop`): its task (the CNC's program, the
structure's controllers at the servo rate, the record and the following-error alarm), its load hook (the cut's
forces in the blank frame, or a test's disturbance) and the motion record: per tick the axis positions, motor torques
and the synchronisation error, and per pass the pose trajectory of the cutter in the blank frame (the cutting
engine's input).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import mujoco
import numpy as np
from numba import njit

from cutting.errors import InputError, LostSynchronismError, Problem
from cutting.skiving.path_correction import PathCorrection
from cutting.skiving.sampled_motion import exp_rotations
from machine_models.parameters import SkivingMachineParams
from machine_models.skiving_machine import MM, build_spec
from machine_models.structure_drives import MOTOR_TORQUE_KEYS
from virtual_machine.controllers import InductionMotor
from virtual_machine.job import Job
from virtual_machine.reach.skiving import check_skiving_reach
from virtual_machine.reach.skiving_load import check_machine_holds
from virtual_machine.runtime.integrator import Integrator
from virtual_machine.runtime.loop import AxisDisturbance, LoadHook, MachineLoop
from virtual_machine.runtime.physics import AXES, BlankFrameLoad, MachinePhysics
from virtual_machine.runtime.program import ProgramSettings, program
from virtual_machine.setting.chains import chain_ratios
from virtual_machine.setting.machine_layout import machine_params, machine_size, skiving_layout
from virtual_machine.setting.plan import SkivingPlan, plan_of
from virtual_machine.setting.sheet import setup_sheet
from virtual_machine.structures.hydraulic import HydraulicS2, HydraulicS3
from virtual_machine.structures.mechanical import MechanicalS1
from virtual_machine.structures.mechatronic import MechatronicS4, MechatronicS4MasterSlave, S4Tuning

SEGMENTS = ("runup", "settle", "infeed", "feed", "retract", "return")


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
    #: (n, 6) the loop's deflection: the cutter frame's pose in the blank frame beyond what the axes give, as a small
    #: rotation vector [rad] and a translation [mm] in the blank frame (:func:`loop_deflection`); None: a rigid loop
    deflection: np.ndarray | None = None

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
    if m.structure in ("mechanical", "hydraulic-differential", "hydraulic-shaft"):
        return _build_chain_structure(job, params, phys, plan)
    if m.structure != "mechatronic":
        raise NotImplementedError(f"machine.structure = {m['structure']!r}: unknown structure")
    sheet = plan.sheet("mechatronic")
    st = sheet.settings
    setup = job.skiving
    j_tool = params.tool_motor_inertia + params.tool_inertia * params.tool_drive.ratio**2
    j_work = params.work_motor_inertia + params.work_inertia * params.work_drive.ratio**2
    lead = m.lead_screw_pitch * MM / (2 * math.pi)
    j_feed = (
        params.feed_motor_inertia + (params.screw_inertia + params.carriage_mass * lead**2) * params.feed_drive.ratio**2
    )
    ky = st["ky"].realisation.get("integer")
    adaptive = m.adaptive_correction if adaptive is None else adaptive
    # the amplifiers' current limits are the motors' peak torques of the machine (amplifiers 3, 11, 18)
    base = S4Tuning()
    tuning = S4Tuning(
        dataclasses.replace(base.tool, peak_torque=params.tool_motor_torque),
        dataclasses.replace(base.work, peak_torque=params.work_motor_torque),
        dataclasses.replace(base.feed, peak_torque=params.feed_motor_torque),
    )
    angle0 = (phys.q("B1"), phys.q("B2"), phys.q("TV"))
    if m.synchronization == "master-slave":
        feed_dir = -1 if setup.feed_direction == "down" else 1
        t_tv = m.lead_screw_pitch
        return MechatronicS4MasterSlave(
            f_ref=m.reference_frequency,
            p=m.command_pulses_per_rev,
            kv=st["kv"].realisation["integer"],
            ratio_x=setup.speed_ratio,  # work turn per tool turn
            ratio_y=setup.differential_rotation_per_mm * t_tv / (2 * math.pi),  # work rad per screw rad (B4)
            ratio_s=feed_dir * setup.axial_feed / t_tv * (1 if setup.speed_ratio > 0 else -1),  # screw per work
            encoder_lines=m.encoder_lines,
            ratios=(params.tool_drive.ratio, params.work_drive.ratio, params.feed_drive.ratio),
            inertias=(j_tool, j_work, j_feed),
            adaptive=adaptive,
            angle0=angle0,
            tuning=tuning,
        )
    return MechatronicS4(
        f_ref=m.reference_frequency,
        p=m.command_pulses_per_rev,
        kv=st["kv"].realisation["integer"],
        kx=st["kx"].realisation["integer"],
        ks=st["ks"].realisation["integer"],
        ky=ky,
        dir_work=1 if setup.speed_ratio > 0 else -1,
        dir_b4=1 if setup.differential_rotation_per_mm > 0 else -1,
        encoder_lines=m.encoder_lines,
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
        sync_speed=m.motor_speed * 2 * math.pi / 60 / (1 - params.main_motor_slip),
        rated_torque=params.main_motor_torque,
        rated_slip=params.main_motor_slip,
    )
    if m.structure == "mechanical":
        return MechanicalS1(
            motor, m.command_pulses_per_rev, m.encoder_lines, params.traverse_motor_inertia, phys.q("TV")
        )
    stepping = {
        "steps_per_rev": m.hydraulic_steps_per_rev,
        "stiffness": params.hydraulic_stiffness,
        "damping": params.hydraulic_damping,
        "leakage": params.hydraulic_leakage,
        "torque_limit": params.hydraulic_torque_limit,
    }
    if m.structure == "hydraulic-shaft":
        reverse = "up" if job.process.feed_direction == "down" else "down"
        back = dataclasses.replace(job, process=dataclasses.replace(job.process, feed_direction=reverse))
        sheets = (plan.sheet("hydraulic-shaft"), setup_sheet(back, "hydraulic-shaft"))  # the return stroke's own
        discs = tuple(s.settings["kx"].realisation["disc_windows"] for s in sheets)
        home = {j: phys.q(j) for j in ("B2", "TV", "GShD")}
        return HydraulicS3(motor, discs, stepping, m.command_pulses_per_rev, m.encoder_lines, home)
    sheet = plan.sheet("hydraulic-differential")
    windows = tuple(sheet.settings[k].realisation.get("disc_windows") for k in ("kx", "ky", "is"))
    home = {j: phys.q(j) for j in ("B1", "B2", "TV", "GShD1", "GShD2", "GShD3")}
    return HydraulicS2(
        motor, windows, stepping, m.command_pulses_per_rev, m.encoder_lines, chain_ratios(job).feed, home
    )


def check_correction(job: Job, correction: PathCorrection | None) -> None:
    """A tangential correction needs the electronic gearbox's summator 9 (S4, equal coordinates); the radial one
    every structure's radial slide makes."""
    if correction is None or not np.any(correction.dphi):
        return
    m = job.machine
    if m.structure != "mechatronic" or m.synchronization != "equal-coordinates":
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
    """The skiving machine on the machine loop (:class:`virtual_machine.runtime.loop.MachineLoop`), as a stepper:
    :meth:`advance` runs it up to a time, so another stage (the cutting co-simulation) can act between calls;
    :meth:`record` assembles the :class:`MotionRecord`. Its task: before each tick the CNC's program and the
    structure's controllers; after it the record and the CNC's following-error alarm.

    Without ``params`` the machine is the job's own (:func:`machine_params`: its size with the [machine.model]
    overrides), and a job beyond its reach or whose estimated cutting torque its motors cannot hold is refused
    before anything runs (:mod:`virtual_machine.reach.skiving`: MachineLimitError naming the limit); given
    ``params`` are taken as they are (tests, benchmarks). Without ``settings`` the run-up follows the machine's
    ``work_acceleration``. ``plan``: the job's setup, ideal passes and setting sheets as an earlier stage made them.
    ``cut(t, dt)``: the cut's loads in the blank frame (:class:`virtual_machine.runtime.physics.BlankFrameLoad`);
    ``disturbance(t)``: instead, an extra torque [N m] or force [N] on ``disturbance_axis`` (tests of the correction
    and the schemes).
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
        cut: Callable[[float, float], Iterable[tuple]] | None = None,
    ):
        if disturbance is not None and cut is not None:
            raise ValueError("one load hook per run: a disturbance or the cut's load")
        self.job = job
        self.plan = plan = plan_of(job, plan)
        if params is None:  # the job's own machine: refused before the run if it cannot do the job
            params = machine_params(job)
            check_skiving_reach(job, params, machine_size(job))
            check_machine_holds(job, params)
        self.params = params
        self.setup = setup = plan.setup
        structure = job.machine.structure
        chains = chain_ratios(job) if structure != "mechatronic" else None
        layout = skiving_layout(setup, job.machine.lead_screw_pitch, plan.passes[0])
        self.spec = build_spec(layout, self.params, structure, chains)
        self.phys = phys = MachinePhysics(self.spec.compile(), self.params)
        self.machine = machine = build_structure(job, self.params, phys, plan=plan)
        self.servo_substeps = servo_substeps
        self.dt = phys.model.opt.timestep * servo_substeps
        # the tick's physics; a divergence names the stage to soften (at the time MuJoCo leaves after the step)
        integrator = Integrator(phys.model, phys.data, servo_substeps, phys.qadr["B2"], phys.diagnose)
        #: the load hook: the cut's loads (their resultant per tick in its ``rows``), or a test's disturbance
        self.load: LoadHook | None = None
        if cut is not None:
            self.load = BlankFrameLoad(phys, cut)
        elif disturbance is not None:
            self.load = AxisDisturbance(phys.vadr[disturbance_axis], disturbance)
        self.loop = MachineLoop(integrator, self, self.load, phys.cutter_body, phys.blank_body)
        p = job.machine.command_pulses_per_rev
        ppm = p / job.machine.lead_screw_pitch  # screw pulses per mm of carriage
        settings = settings or ProgramSettings(runup_acceleration=self.params.work_acceleration)
        check_correction(job, correction)
        self.work_pulses_per_rad = p / (2 * math.pi)  # B4 command pulses of the work axis per radian
        self._ticks = program(
            setup, self.dt, ppm, machine, settings, correction, self.work_pulses_per_rad, passes=plan.passes
        )
        self.corrections: list[float] = []  # the tangential correction asked for at each tick [rad]
        # the CNC of the servo structures watches the synchronisation (following error); a chain has no CNC loop
        self.following_limit = settings.following_error_limit if structure == "mechatronic" else math.inf
        self.rows: list[tuple] = []
        #: per tick the loop's deflection (6 numbers, :func:`loop_deflection`) when the machine has loop modes
        self.deflections: list[tuple[float, ...]] | None = [] if self.params.loop else None
        self.home = (phys.q("B1"), phys.q("B2"), phys.q("P3") / MM)
        self._clutch_state: dict[str, bool] = {}
        self._last_cnc = None
        self._tick = None
        self._torques = (0.0,) * len(machine.actuators)
        self._progress: Callable[[float], None] | None = None
        # what the ticks read and write, bound once: data's arrays are live views
        data = phys.data
        self._qpos, self._qvel, self._ctrl = data.qpos, data.qvel, data.ctrl
        self._qa = [phys.qadr[a] for a in AXES]
        self._sensors = [phys.qadr[j] for j in machine.sensors]
        # the spindles' encoders as built (cutting/skiving/machine_geometry.py): what each reads ahead of its shaft
        g = setup.geometry
        self._encoders = [
            (k, e, phase)
            for k, joint in enumerate(machine.sensors)
            for name, e, phase in (
                ("B1", g.tool_encoder_eccentricity, g.tool_encoder_phase),
                ("B2", g.work_encoder_eccentricity, g.work_encoder_phase),
            )
            if joint == name and e
        ]
        self._speeds = [phys.vadr[j] for j in machine.speeds]
        self._acts = [phys.act[a] for a in machine.actuators]
        self._radial = phys.act["X"]
        self._segment = {name: k for k, name in enumerate(SEGMENTS)}
        self._b1, self._b2, self._p3 = phys.qadr["B1"], phys.qadr["B2"], phys.qadr["P3"]
        self._ratio, self._diff = setup.speed_ratio, setup.differential_rotation_per_mm
        self._limit = self.following_limit / (setup.gear.reference_radius * 1e3)  # rad of work spindle

    @property
    def time(self) -> float:
        return self.phys.time

    @property
    def finished(self) -> bool:
        """The program has ended."""
        return self.loop.finished

    @property
    def timing(self) -> dict[str, float]:
        """Seconds in the controllers, the physics (with the loads) and the records (the loop's)."""
        return self.loop.timing

    def advance(self, until: float = math.inf, progress: Callable[[float], None] | None = None) -> bool:
        """Run servo ticks while the machine time is below ``until`` [s]; False once the program has ended.
        ``progress(t)`` after each tick."""
        self._progress = progress
        return self.loop.run(until)

    def before_tick(self) -> bool:
        """The CNC's next tick of the program: the radial slide's target, the clutches, the controllers' torques."""
        tick = next(self._ticks, None)
        if tick is None:
            return False
        self._tick = tick
        self._ctrl[self._radial] = tick.radial  # the radial slide's position servo target [m]
        if tick.cnc is not self._last_cnc:  # the CNC's state objects are shared while a segment holds them
            self._last_cnc = tick.cnc
            for tendon, on in self.machine.clutches(tick.cnc).items():
                if self._clutch_state.get(tendon) != on:
                    self.phys.engage(tendon, on)
                    self._clutch_state[tendon] = on
        qpos = self._qpos
        angles = qpos.take(self._sensors).tolist()
        for k, e, phase in self._encoders:  # a graduation off its shaft's centre reads e sin(angle + phase) ahead
            angles[k] += e * math.sin(angles[k] + phase)
        self._torques = torques = self.machine.tick(self.dt, tick.cnc, angles, self._qvel.take(self._speeds).tolist())
        self._ctrl[self._acts] = torques
        return True

    def after_tick(self) -> None:
        """The tick's record, and the CNC's following-error alarm (LostSynchronismError)."""
        qpos, tick = self._qpos, self._tick
        t = self.phys.data.time
        segment = self._segment[tick.segment]
        axes = qpos.take(self._qa)
        self.rows.append((t, *axes.tolist(), segment, tick.pass_index, *self._torques))
        if self.deflections is not None:
            self.deflections.append(loop_deflection(self.setup, axes, *self.phys.cutter_pose()))
        wanted = tick.cnc.correction_b4 / self.work_pulses_per_rad  # a modification's extra turn is no error
        self.corrections.append(wanted)
        b1_0, b2_0, p3_0 = self.home
        delta = (
            (qpos[self._b2] - b2_0)
            - self._ratio * (qpos[self._b1] - b1_0)
            - self._diff * (qpos[self._p3] / MM - p3_0)
            - wanted
        )
        if abs(delta) > self._limit:
            raise LostSynchronismError(self._lost_synchronism(delta))
        if self._progress is not None:
            self._progress(t)

    def _lost_synchronism(self, delta: float) -> str:
        """What the CNC's following-error alarm says: where, how far, which motors were at their limit."""
        rows = self.rows[-round(0.2 / self.dt) :]
        n_ax = len(AXES)
        torques = np.abs(np.array([r[3 + n_ax :] for r in rows])).max(axis=0)
        last = rows[-1]
        seg = SEGMENTS[int(last[1 + n_ax])]
        model = self.phys.model
        keys = MOTOR_TORQUE_KEYS.get(self.job.machine.structure, {})
        peaks, saturated = [], []
        for name, value in zip(self.machine.actuators, torques, strict=True):
            limit = float(model.actuator_ctrlrange[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, name), 1])
            at_limit = value >= 0.98 * limit
            peaks.append(f"{name} {value:.1f} N m" + (f" (its limit, machine.model.{keys[name]})" if at_limit else ""))
            if at_limit and name in keys:
                saturated.append(f"machine.model.{keys[name]}")
        um = delta * self.setup.gear.reference_radius * 1e3
        more = f"give the motor at its limit more torque ({', '.join(saturated)})" if saturated else ""
        ringing = self._growing_vibration() if seg == "feed" else None
        if ringing is not None:  # chatter: more torque would only let it grow further
            f, before, after, n_s = ringing
            remedy = (
                f"It followed a vibration growing at {f:.0f} Hz ({before:.0f} -> {after:.0f} um peak to peak on the "
                f"reference circle over {n_s:.1f} s): chatter, which `skive stability` maps pass by pass. A stiffer "
                f"machine (machine.size, the drives in [machine.model]) or a loop of your machine's measured modes "
                f"([[machine.model.loop]]) where its lobes call the passes stable"
            )
        elif seg == "feed" and saturated:  # cutting: the chips' torque is what the motor cannot hold
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

    def _growing_vibration(self) -> tuple[float, float, float, float] | None:
        """:func:`growing_vibration` of the synchronisation error [um of arc on the reference circle] over the last
        two seconds (or what ran of them)."""
        n = min(round(2.0 / self.dt), len(self.rows))
        a = np.array([r[:6] for r in self.rows[-n:]])
        b1_0, b2_0, p3_0 = self.home
        delta = (a[:, 2] - b2_0) - self._ratio * (a[:, 1] - b1_0) - self._diff * (a[:, 3] / MM - p3_0)
        delta = (delta - np.array(self.corrections[-n:])) * self.setup.gear.reference_radius * 1e3
        return growing_vibration(delta, self.dt, self.following_limit)

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
        # the carriage positions where the tip circle's engagement overlaps the face
        reach = np.array([setup.engagement_range(c) for c in setup.pass_centre_distances])
        lo, hi = reach[np.clip(pass_index, 0, len(reach) - 1)].T
        b = setup.gear.face_width / 2
        cutting = (segment == feed) & (q[:, 2] + lo <= b) & (q[:, 2] + hi >= -b)
        deflection = np.array(self.deflections).reshape(-1, 6) if self.deflections is not None else None
        rec = MotionRecord(
            t=a[:, 0],
            q=q,
            torque=a[:, 3 + n_ax :],
            deflection=deflection,
            actuators=tuple(self.machine.actuators),
            model_xml=self.spec.to_xml(),
            sync_um=r2 * delta * 1e3,
            segment=segment,
            pass_index=pass_index,
            cutting=cutting,
        )
        for index in sorted(set(rec.pass_index[rec.segment == feed].tolist())):
            sel = (rec.segment == feed) & (rec.pass_index == index)
            defl = deflection[sel] if deflection is not None else None
            rec.passes.append(pass_trajectory(setup, index, rec.t[sel], rec.q[sel], defl))
        return rec


def pass_trajectory(
    setup, index: int, t: np.ndarray, q: np.ndarray, deflection: np.ndarray | None = None
) -> PassTrajectory:
    """The pose trajectory of one feed stroke from its recorded axis positions and the loop's deflection (t from
    the stroke's start)."""
    rot, trans = relative_pose(setup, q, deflection, t)
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
    ``timing``, if given, receives the seconds spent in the controllers, the physics and the records (benchmarks);
    ``plan``: the job's plan if the caller has it."""
    run = MachineRun(job, params, servo_substeps, settings, disturbance, disturbance_axis, plan=plan)
    run.advance(math.inf if duration is None else duration, progress)
    if timing is not None:
        timing.update(run.timing)
    return run.record()


def growing_vibration(signal: np.ndarray, dt: float, limit: float) -> tuple[float, float, float, float] | None:
    """A vibration that grew in ``signal`` (samples ``dt`` [s] apart, at least 0.4 s of them): its frequency [Hz]
    (the largest peak of the last 0.2 s), its peak to peak over the first and the last 0.1 s (linear trend taken
    out), and the span [s]; None if it did not grow 2-fold, stays under a tenth of ``limit`` (the signal's units) or
    is slower than 20 Hz (a drift, not a vibration)."""
    tenth = round(0.1 / dt)
    if len(signal) < 4 * tenth:
        return None

    def swing(part: np.ndarray) -> float:
        t = np.arange(len(part))
        return float(np.ptp(part - np.polyval(np.polyfit(t, part, 1), t)))

    before, after = swing(signal[:tenth]), swing(signal[-tenth:])
    if not (after > 2 * before and after > 0.1 * limit):
        return None
    late = signal[-2 * tenth :] - signal[-2 * tenth :].mean()
    spectrum = np.abs(np.fft.rfft(late * np.hanning(len(late))))
    frequency = float(np.fft.rfftfreq(len(late), dt)[1 + int(np.argmax(spectrum[1:]))])
    return (frequency, before, after, len(signal) * dt) if frequency >= 20.0 else None


def relative_pose(
    setup, q: np.ndarray, deflection: np.ndarray | None = None, t: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The cutter frame in the blank frame for recorded axis values ``q`` (rows as MotionRecord.q) and the loop's
    ``deflection`` (rows as MotionRecord.deflection; None: a rigid loop) at machine times ``t`` [s] (what the
    machine's thermal drift, ``setup.thermal``, needs; None: no drift).

    The axes' part is the forward kinematics of the model (blank_frame = Rz(B2 + work_phase); cutter_frame at
    (X, 0, P3), Rx(tilt) Rz(B1 + cutter_phase)); the loop's modes move the cutter frame further, by the recorded
    small rotation and translation in the blank frame (MuJoCo's own site poses; tests check both). The machine as
    built (``setup.geometry``, cutting/skiving/machine_geometry.py) places the head by its geometric errors: the
    same terms as the ideal kinematics' :meth:`SkivingSetup.machine_pose` (its spindle's error motion is the blank's,
    in ``setup.blank_frame``)."""
    from cutting.skiving.kinematics import rot_x, rot_z

    g = setup.geometry
    back = rot_z(-(q[:, 1] + setup.work_phase))
    centre = np.stack([q[:, 3], np.zeros(len(q)), q[:, 2]], -1)
    if setup.thermal is not None and t is not None:  # the drift at each instant (cutting/skiving/thermal_drift.py)
        drift = setup.thermal.offsets(t)
        a = setup.tilt + g.shaft_angle_error + drift[:, 3]
        tilt = np.zeros((len(a), 3, 3))
        tilt[:, 0, 0] = 1.0
        tilt[:, 1, 1] = tilt[:, 2, 2] = np.cos(a)
        tilt[:, 2, 1] = np.sin(a)
        tilt[:, 1, 2] = -tilt[:, 2, 1]  # rot_x of each row's angle
        rot = back @ tilt @ rot_z(q[:, 0] + setup.cutter_phase)
        centre = centre + drift[:, :3]
    else:
        rot = back @ rot_x(setup.tilt + g.shaft_angle_error) @ rot_z(q[:, 0] + setup.cutter_phase)
    if not g.exact:
        centre = centre + g.head_offset(q[:, 2])
    trans = np.matmul(back, centre[:, :, None])[:, :, 0]
    if deflection is None:
        return rot, trans
    turn = exp_rotations(deflection[:, :3])
    return turn @ rot, np.matmul(turn, trans[:, :, None])[:, :, 0] + deflection[:, 3:]


def loop_deflection(setup, axes: np.ndarray, rot: np.ndarray, trans: np.ndarray) -> tuple[float, ...]:
    """The loop's deflection at one instant: the cutter frame's pose in the blank frame ``rot``, ``trans`` [mm]
    (MuJoCo's sites) against the pose its axes give (``axes``: B1, B2 [rad], P3, X [m], TV as MuJoCo holds them), as
    C = real o rigid^-1 in the blank frame: its rotation vector [rad] and translation [mm] (6 numbers). Compiled:
    the run asks for it every servo tick."""
    out = _deflection(
        float(axes[0]), float(axes[1]), float(axes[2]) / MM, float(axes[3]) / MM,
        setup.tilt, setup.cutter_phase, setup.work_phase, np.ascontiguousarray(rot), np.ascontiguousarray(trans),
    )  # fmt: skip
    return tuple(out.tolist())


@njit(cache=True)
def _deflection(b1, b2, p3, x, tilt, cutter_phase, work_phase, rot, trans):
    """:func:`loop_deflection` in scalars: the rigid pose Rz(-(B2 + wp)) Rx(tilt) Rz(B1 + cp), centre
    Rz(-(B2 + wp)) (X, 0, P3); turn = rot rigid^T; its skew part (the rotation vector, exact to theta^3 / 6:
    1e-16 rad at 1e-5 rad) and shift = trans - turn centre."""
    cb, sb = math.cos(-(b2 + work_phase)), math.sin(-(b2 + work_phase))
    ct, st = math.cos(tilt), math.sin(tilt)
    cc, sc = math.cos(b1 + cutter_phase), math.sin(b1 + cutter_phase)
    back = np.array([[cb, -sb, 0.0], [sb, cb, 0.0], [0.0, 0.0, 1.0]])
    tx = np.array([[1.0, 0.0, 0.0], [0.0, ct, -st], [0.0, st, ct]])
    tc = np.array([[cc, -sc, 0.0], [sc, cc, 0.0], [0.0, 0.0, 1.0]])
    rigid = back @ tx @ tc
    centre = back @ np.array([x, 0.0, p3])
    turn = rot @ rigid.T
    out = np.empty(6)
    out[0] = 0.5 * (turn[2, 1] - turn[1, 2])
    out[1] = 0.5 * (turn[0, 2] - turn[2, 0])
    out[2] = 0.5 * (turn[1, 0] - turn[0, 1])
    shift = trans - turn @ centre
    out[3], out[4], out[5] = shift[0], shift[1], shift[2]
    return out
