"""The CNC of the form-milling machine (seed 003, the copying method): its program, its task and load hook on the
machine loop.

The flanks a real machine mills carry what its drives do to the planned path (screw and nut compliance, backlash,
friction, the Z weight, the cut's forces): :func:`simulate_form_milling` runs the passes (:class:`MillPass`) on the
simulated machine with the program (:func:`_plan`, its moves there), the servos (:class:`FormMillServo`, their law
there), the CNC's task :class:`FormMillCnc` and the cut's load hook :class:`MillLoad` on the machine loop
(:mod:`virtual_machine.runtime.loop`: the physics sub-steps with the divergence and runaway checks), and records the
feeds (:class:`FormMillRecord`). What the machine makes: docs/form-milling.md, "The machine".
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import mujoco
import numpy as np

from machine_models.form_mill import FormMillLayout, FormMillParams, build_form_mill_spec, stage_omega_h
from machine_models.parameters import ARCSEC
from virtual_machine.controllers.cascade import CascadeServo, ServoAxis
from virtual_machine.runtime.integrator import (
    BAD_ACCELERATION_OR_SPEED,
    Integrator,
    divergence_message,
    servo_substeps,
)
from virtual_machine.runtime.loop import MachineLoop, ToolLoad

AXES = ("A", "X", "Y", "Z", "B", "S")  # the CNC's axes; A rad, X Y Z m, B S rad
MOTORS = ("MA", "MX", "MY", "MZ", "MB", "MS")
_A, _X, _Y, _Z, _B, _S = range(6)
POSITIONED = 5  # A X Y Z B have position loops; the spindle S a velocity loop only
#: following errors in the records: A and B [arcsec], X Y Z [um]
ERROR_UNITS = (1 / ARCSEC, 1e6, 1e6, 1e6, 1 / ARCSEC)


@dataclass(frozen=True)
class MillPass:
    """One pass of the copying method: tooth space ``space`` (k), fed from ``z_start`` to ``z_end`` [mm, gear
    frame]; ``path(z)`` maps z [mm, array (N,)] to the commanded mill centre [x radial, y tangential] [mm,
    (N, 2)] in the space's frame (the gear frame turned by 2 pi k / z; for space 0 the gear frame itself), or
    (N, 3) with the centre's axial position third (a turned mill's centre is off the profiling plane's z).
    ``axis(z)`` (optional): the mill's unit axis (N, 3) in that frame; none: tangential (0, 1, 0). ``turn(z)``
    (optional, with no axis): the work's turn [rad] at z on top of the index, ``path`` then in the space's frame
    turned by it (a finger on a helical space: its axis stays along the head's spindle, the work follows the helix)."""

    space: int
    z_start: float
    z_end: float
    path: Callable[[np.ndarray], np.ndarray]
    axis: Callable[[np.ndarray], np.ndarray] | None = None
    turn: Callable[[np.ndarray], np.ndarray] | None = None


@dataclass(frozen=True)
class CncTuning:
    """Servo gains and motion limits of the CNC (per axis in the order A, X, Y, Z, B[, S])."""

    servo_rate: float = 2000.0  # Hz: position and velocity loops (the physics sub-steps a whole number of times)
    velocity_bandwidth: tuple[float, ...] = (40.0, 80.0, 80.0, 80.0, 40.0, 20.0)  # Hz: PI velocity loops, A-B, S
    position_gain: tuple[float, ...] = (60.0, 100.0, 100.0, 100.0, 60.0)  # 1/s: Kv of A X Y Z B
    rapid_speed: tuple[float, ...] = (2.0, 0.25, 0.25, 0.25, 1.0)  # rad/s, m/s: peak speed of a positioning move
    rapid_accel: tuple[float, ...] = (10.0, 2.5, 2.5, 2.5, 5.0)  # rad/s^2, m/s^2: peak acceleration of a move
    feed_ramp: float = 0.05  # s: cycloidal ramp of the feed at both ends of a pass
    spindle_ramp: float = 0.5  # s: half-cosine run-up of the spindle
    settle_time: float = 0.1  # s: least dwell before the feed starts
    settle_timeout: float = 2.0  # s: the feed starts anyway after this (the record notes the dwell)
    #: rad, m: encoder following errors of A X Y Z B under which the axes count as settled
    settle_tolerance: tuple[float, ...] = (1.0 * ARCSEC, 0.5e-6, 0.5e-6, 0.5e-6, 1.0 * ARCSEC)
    runaway: tuple[float, ...] = (0.05, 5e-3, 5e-3, 5e-3, 0.05)  # rad, m: a following error beyond this stops the run
    trace_every: int = 4  # servo ticks per sample of the whole-run traces


@dataclass
class PassRecord:
    """The feed segment of one pass at the servo rate, in the gear frame (site ``blank_frame``).

    ``centre`` [mm] and ``axis`` (unit vector) of the mill (site ``mill_frame``), ``commanded`` centre [mm]
    (the path turned by the space's angle ``angle`` [rad] = 2 pi k / z), ``following_error`` at the encoders
    (commanded - measured: A [arcsec], X, Y, Z [um], B [arcsec]), ``steady``: the feed at constant speed (after
    the ramp).
    """

    space: int
    angle: float
    t: np.ndarray
    centre: np.ndarray
    axis: np.ndarray
    commanded: np.ndarray
    following_error: np.ndarray
    steady: np.ndarray
    dwell: float  # s: settling dwell before this pass's feed

    def deviation(self) -> np.ndarray:
        """Recorded - commanded centre in the space's frame (radial, tangential, axial) [um], (N, 3)."""
        c, s = math.cos(self.angle), math.sin(self.angle)
        d = (self.centre - self.commanded) * 1e3
        return np.column_stack((c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1], d[:, 2]))


@dataclass
class FormMillRecord:
    """A form-milling run: the passes' feed records and whole-run traces (every ``trace_every`` servo ticks) of
    time [s], axes ``trace_q`` (A [rad], X Y Z [mm], B S [rad]), commands ``trace_command`` (A [rad], X Y Z [mm],
    B [rad], spindle speed [rad/s]), motor torques ``trace_torque`` [N m] (MA MX MY MZ MB MS) and encoder
    following errors ``trace_error`` (A [arcsec], X Y Z [um], B [arcsec]). Numpy only: picklable."""

    teeth: int
    feed_mm_min: float
    spindle_rpm: float
    passes: list[PassRecord]
    spaces: np.ndarray
    trace_t: np.ndarray
    trace_q: np.ndarray
    trace_command: np.ndarray
    trace_torque: np.ndarray
    trace_error: np.ndarray
    wall_time: float = 0.0  # s
    sim_time: float = 0.0  # s
    axes: tuple[str, ...] = field(default=AXES)


@dataclass
class _Segment:
    """Commanded A X Y Z B (rad, m) with speeds and accelerations per servo tick; a settle segment holds ``pos[0]``
    until the axes have settled; a feed segment is recorded for pass ``index``."""

    kind: str  # "move", "settle", "feed"
    pos: np.ndarray  # (n, 5)
    vel: np.ndarray
    acc: np.ndarray  # mean over the tick that starts at the sample (the torque is held for the tick)
    index: int = -1
    steady: np.ndarray | None = None
    commanded: np.ndarray | None = None  # (n, 3) gear frame [mm] (feed only)


def _move(q0: np.ndarray, q1: np.ndarray, dt: float, tuning: CncTuning) -> _Segment | None:
    """Minimum-jerk point-to-point move of A X Y Z B, all axes together: s = 10 u^3 - 15 u^4 + 6 u^5 (peak speed
    1.875 D / T, peak acceleration 5.77 D / T^2)."""
    d = q1 - q0
    if np.abs(d).max() < 1e-12:
        return None
    dist = np.abs(d)
    duration = max(
        float(np.max(1.875 * dist / np.asarray(tuning.rapid_speed))),
        float(np.max(np.sqrt(5.7735 * dist / np.asarray(tuning.rapid_accel)))),
        2 * dt,
    )
    n = math.ceil(duration / dt)
    duration = n * dt
    u = np.arange(n + 1)[:, None] * dt / duration  # samples at the ticks from the start to the end
    s = u**3 * (10 - 15 * u + 6 * u**2)
    ds = 30 * u**2 * (1 - u) ** 2 / duration
    dds = 60 * u * (1 - u) * (1 - 2 * u) / duration**2
    return _Segment("move", q0 + s * d, ds * d, _held(dds * d))


def _held(acc: np.ndarray) -> np.ndarray:
    """Accelerations at the ticks -> their means over the following tick (the zero-order hold of the torque)."""
    out = acc.copy()
    out[:-1] = (acc[:-1] + acc[1:]) / 2
    return out


def _hold(q: np.ndarray) -> _Segment:
    z = np.zeros((1, POSITIONED))
    return _Segment("settle", q[None, :].copy(), z, z.copy())


def _feed(p: MillPass, index: int, teeth: int, feed: float, dt: float, tuning: CncTuning):
    """The feed of pass ``p`` along z with the other axes on its path (:func:`_axes_on_path`; velocity and
    acceleration feed-forward from the path's derivatives by central differences, dz = 1e-3 mm)."""
    z0, z1 = p.z_start * 1e-3, p.z_end * 1e-3
    length, sign = abs(z1 - z0), math.copysign(1.0, z1 - z0)
    speed = feed / 60 * 1e-3  # m/s
    ramp = min(tuning.feed_ramp, length / speed)
    duration = length / speed + ramp
    n = math.ceil(duration / dt) + 1
    t = np.minimum(np.arange(n) * dt, duration)  # samples at the ticks from the start to the end
    w = 2 * math.pi / ramp

    def up(tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # cycloidal ramp: travel, speed, accel
        tau = np.minimum(tau, ramp)
        return (
            speed * (tau**2 / (2 * ramp) + (np.cos(w * tau) - 1) / (w**2 * ramp)),
            speed * (tau / ramp - np.sin(w * tau) / (2 * math.pi)),
            speed / ramp * (1 - np.cos(w * tau)),
        )

    s_up, v_up, a_up = up(t)
    s_dn, v_dn, a_dn = up(duration - t)
    cruise = np.clip(t - ramp, 0, duration - 2 * ramp) * speed
    late = t > duration - ramp
    s = np.where(late, length - s_dn, s_up + cruise)
    v = np.where(late, v_dn, np.where(t < ramp, v_up, speed))
    a = np.where(late, -a_dn, np.where(t < ramp, a_up, 0.0))
    z, zd, zdd = z0 + sign * s, sign * v, sign * a
    zmm, dz = z * 1e3, 1e-3
    a_k = -2 * math.pi * p.space / teeth  # A with space k facing +x
    q, centre = _axes_on_path(p, zmm, a_k)
    q_p, q_m = _axes_on_path(p, zmm + dz, a_k)[0], _axes_on_path(p, zmm - dz, a_k)[0]
    d1 = (q_p - q_m) / (2 * dz * 1e-3)  # per metre of feed
    d2 = (q_p - 2 * q + q_m) / (dz * 1e-3) ** 2
    vel = d1 * zd[:, None]
    acc = d2 * (zd**2)[:, None] + d1 * zdd[:, None]
    angle = 2 * math.pi * p.space / teeth
    c, s_ = math.cos(angle), math.sin(angle)
    commanded = np.column_stack(
        (c * centre[:, 0] - s_ * centre[:, 1], s_ * centre[:, 0] + c * centre[:, 1], centre[:, 2])
    )
    steady = (t >= ramp) & (t <= duration - ramp)
    return _Segment("feed", q, vel, _held(acc), index, steady, commanded)


def _path(p: MillPass, z: np.ndarray) -> np.ndarray:
    """The pass's mill centre (N, 3) [mm] in the space's frame: radial, tangential, axial."""
    xy = np.asarray(p.path(z), dtype=float)
    if xy.ndim != 2 or xy.shape[0] != len(z) or xy.shape[1] not in (2, 3) or not np.isfinite(xy).all():
        raise ValueError(f"MillPass.path must map z (N,) to finite (N, 2) or (N, 3) in mm; got shape {xy.shape}")
    return xy if xy.shape[1] == 3 else np.column_stack((xy, z))


def _axes_on_path(p: MillPass, z: np.ndarray, a_index: float) -> tuple[np.ndarray, np.ndarray]:
    """Commanded A X Y Z B (N, 5) [rad, m, m, m, rad] that put the mill of pass ``p`` at face positions ``z`` [mm],
    and its centre in the space's frame [mm]. The head turns the axis (0, 1, 0) about machine x by B into
    (0, cos B, sin B); a radial component a_r of the wanted axis a is taken by the work, turned by
    delta = atan2(a_r, a_t) from the index ``a_index`` (the space's frame turned by delta about z puts a in the
    head's plane), the centre turned with it."""
    centre = _path(p, z)
    if p.axis is None:
        a = a_index + (np.asarray(p.turn(z), dtype=float) if p.turn is not None else 0.0)
        q = np.column_stack((np.broadcast_to(a, len(z)), centre * 1e-3, np.zeros(len(z))))
        return q, centre
    axis = np.asarray(p.axis(z), dtype=float)
    if axis.shape != (len(z), 3) or not np.isfinite(axis).all():
        raise ValueError(f"MillPass.axis must map z (N,) to finite unit vectors (N, 3); got shape {axis.shape}")
    axis = axis / np.linalg.norm(axis, axis=1, keepdims=True)
    delta = np.arctan2(axis[:, 0], axis[:, 1])
    c, s = np.cos(delta), np.sin(delta)
    b = np.arctan2(axis[:, 2], s * axis[:, 0] + c * axis[:, 1])
    x, y = c * centre[:, 0] - s * centre[:, 1], s * centre[:, 0] + c * centre[:, 1]
    return np.column_stack((a_index + delta, x * 1e-3, y * 1e-3, centre[:, 2] * 1e-3, b)), centre


def _plan(
    layout: FormMillLayout, passes: Sequence[MillPass], feed_mm_min: float, dt: float, tuning: CncTuning
) -> list[_Segment]:
    """The CNC program as servo-rate segments: per pass retract X, rapid Z with the index of A, approach X/Y,
    settle, feed, retract X (zero-length moves left out).

    A pass mills one tooth space k with the profiled disc mill (or the finger mill, whose axis the right-angle head
    keeps along the space's symmetry line: its passes give no axis, B stays at 0, X Y Z carry its tip centre):
    retract X to the safe radius, rapid Z to the pass start, index the **indexing work axis** A to ``-2 pi k / z``
    (space k then faces +x, where the mill is) and swivel the head B to the pass's start, approach X/Y to the path,
    settle, feed along z at the feed rate with X and Y following the path (the mill centre in the **profiling
    plane** z = const), retract X. A pass whose mill is turned with the path (seed 003's transfer angles, eq. 6)
    gives the mill's axis per face position: B tilts it towards the gear axis and A turns the work by the small angle
    that puts the axis's radial component into the head's plane, X Y Z following the centre turned with the work
    (five axes at once). Moves are minimum-jerk (quintic) point-to-point profiles (:func:`_move`); the feed ramps up
    and down with a cycloidal (jerk-limited) velocity ramp (:func:`_feed`). The spindle runs at the commanded speed
    all the time (velocity loop, half-cosine run-up)."""
    q = np.array([layout.home_a, layout.home_x, layout.home_y, layout.home_z, 0.0])
    out: list[_Segment] = []

    def go(q1: np.ndarray) -> np.ndarray:
        seg = _move(q, q1, dt, tuning)
        if seg is not None:
            out.append(seg)
        return q1

    for i, p in enumerate(passes):
        q = go(np.array([q[_A], layout.safe_radius, q[_Y], q[_Z], q[_B]]))  # retract X
        start = _axes_on_path(p, np.array([p.z_start]), -2 * math.pi * p.space / layout.teeth)[0][0]
        q = go(np.array([start[_A], q[_X], q[_Y], start[_Z], start[_B]]))  # rapid Z, index A, swivel B
        q = go(start.copy())  # approach
        out.append(_hold(q))
        feed = _feed(p, i, layout.teeth, feed_mm_min, dt, tuning)
        out.append(feed)
        q = feed.pos[-1].copy()
        q = go(np.array([q[_A], layout.safe_radius, q[_Y], q[_Z], q[_B]]))  # retract
    return out


class FormMillServo(CascadeServo):
    """The six drives of the machine (:class:`virtual_machine.controllers.cascade.CascadeServo`): position loops
    (A X Y Z B) and PI velocity loops (A X Y Z B S) on the motor encoders; the spindle S has a velocity loop only.

    Per axis (A, X, Y, Z, B) the servo is the usual cascade on the **motor encoder** (semi-closed loop, as a machine
    with rotary encoders): position loop (gain Kv) with velocity feed-forward -> PI velocity loop -> torque, plus
    inertia (acceleration) feed-forward, limited to the motor's peak torque with anti-windup::

        e = q_cmd - q_enc      w_ref = (v_cmd + Kv e) / g      tau = J a_cmd / g + Kp (w_ref - w) + Ki int(w_ref - w)

    (g: axis motion per motor radian, J: inertia at the motor). Screw and nut compliance, backlash, friction and the
    Z weight therefore show in the relative motion of mill and gear but not at the encoders."""

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        layout: FormMillLayout,
        params: FormMillParams,
        tuning: CncTuning,
    ):
        self.tuning = tuning
        lead = layout.screw_pitch / (2 * math.pi)
        g = [params.work_drive.ratio]
        chains = [(("MA", 1.0), ("A", params.work_drive.ratio))]
        for s in "XYZ":
            drive = getattr(params, f"{s.lower()}_drive").ratio
            g.append(drive * lead)
            chains.append(((f"M{s}", 1.0), (f"T{s}", drive), (s, drive * lead)))
        g.append(params.head_drive.ratio)
        chains.append((("MB", 1.0), ("B", params.head_drive.ratio)))
        g.append(params.spindle_drive.ratio)
        chains.append((("MS", 1.0), ("S", params.spindle_drive.ratio)))
        gains = (*tuning.position_gain, 0.0)
        axes = [ServoAxis(m, g[k], chains[k], tuning.velocity_bandwidth[k], gains[k]) for k, m in enumerate(MOTORS)]
        self.qa = np.array([int(model.joint(a).qposadr[0]) for a in AXES])  # the axes themselves (the record)
        super().__init__(model, data, axes, data.qpos[self.qa].copy())  # encoders zero at the home keyframe


def _diagnose(layout: FormMillLayout, params: FormMillParams, t: float) -> str:
    """Which compliant stage's local mode is too fast for the time step (see ``stage_omega_h``)."""
    return divergence_message("form-milling machine", stage_omega_h(layout, params), params.timestep, t)


def _runaway(servo: FormMillServo, tuning: CncTuning, h: float, t: float) -> str:
    """Which servo ran away and what to change."""
    axis = AXES[int(np.argmax(np.abs(servo.error[:POSITIONED]) / np.asarray(tuning.runaway)))]
    return (
        f"the {axis} servo ran away at t = {t:.4f} s (following error beyond {tuning.runaway}): "
        f"lower CncTuning.velocity_bandwidth / position_gain of {axis}, check the motor's peak torque, or "
        f"reduce machine.timestep (now {h:g} s) if the stages' omega*h is near 2 (form_mill.stage_omega_h)"
    )


def simulate_form_milling(
    layout: FormMillLayout,
    passes: Sequence[MillPass],
    params: FormMillParams | None,
    feed_mm_min: float,
    spindle_rpm: float,
    progress: Callable[[float], None] | None = None,
    tuning: CncTuning | None = None,
    load: Callable[[int, np.ndarray], np.ndarray] | None = None,
) -> FormMillRecord:
    """Run the passes on the simulated machine (MuJoCo) with the CNC of this module; the spindle at
    ``spindle_rpm`` throughout, the feed at ``feed_mm_min`` [mm/min]. ``progress(fraction)`` is called now and
    then. Raises ValueError for bad inputs and :class:`cutting.errors.SimulationDivergedError` when the integration
    blows up or a servo runs away (the message names what to change). ``load(pass index, z)`` gives the cutting
    force on the mill [N] (n, 3) in the space's frame (tangential, radial out, axial) at the commanded mill-centre
    face positions z [mm] of the pass's feed; it acts at the mill's lowest point on the mill and, reversed, on the
    table (none: the passes cut air); a finger mill's (``layout.finger``) mid-way along its cutting length, and
    (n, 6) adds a torque [N m] on the mill (same frame; reversed on the table)."""
    params = params or FormMillParams()
    tuning = tuning or CncTuning()
    _check_passes(layout, passes, feed_mm_min, spindle_rpm)
    cnc = FormMillCnc(layout, passes, params, feed_mm_min, spindle_rpm, tuning, progress)
    hook = MillLoad(cnc, load) if load is not None else None
    MachineLoop(cnc.integrator, cnc, hook, cnc.body_m, cnc.body_b).run()
    return cnc.record()


def _check_passes(layout: FormMillLayout, passes: Sequence[MillPass], feed_mm_min: float, spindle_rpm: float) -> None:
    """ValueError for a run that cannot be: no passes, a feed or speed out of range, a pass off the gear."""
    if not passes:
        raise ValueError("no passes to mill")
    if not (math.isfinite(feed_mm_min) and feed_mm_min > 0):
        raise ValueError(f"feed_mm_min = {feed_mm_min}: must be > 0")
    if not (math.isfinite(spindle_rpm) and spindle_rpm >= 0):
        raise ValueError(f"spindle_rpm = {spindle_rpm}: must be >= 0")
    for p in passes:
        if not 0 <= p.space < layout.teeth or p.space != int(p.space):
            raise ValueError(f"MillPass.space = {p.space}: must be an integer in [0, {layout.teeth})")
        if not (math.isfinite(p.z_start) and math.isfinite(p.z_end)) or p.z_start == p.z_end:
            raise ValueError(f"MillPass z_start = {p.z_start}, z_end = {p.z_end}: must be finite and differ")


class FormMillCnc:
    """The form-milling machine's task on the machine loop: before each tick the program's command (a servo-rate
    segment of moves, settling and feeds: :meth:`_commands`), the spindle's run-up, the servo and the traces, and
    on a feed tick the mill's pose at the tick's start; after it the settling checks and the progress."""

    def __init__(
        self,
        layout: FormMillLayout,
        passes: Sequence[MillPass],
        params: FormMillParams,
        feed_mm_min: float,
        spindle_rpm: float,
        tuning: CncTuning,
        progress: Callable[[float], None] | None,
    ):
        self.layout, self.passes, self.tuning, self.progress = layout, passes, tuning, progress
        self.feed_mm_min, self.spindle_rpm = feed_mm_min, spindle_rpm
        self.model = model = build_form_mill_spec(layout, params).compile()
        h = model.opt.timestep
        substeps = servo_substeps(h, tuning.servo_rate)
        self.dt = substeps * h
        self.data = data = mujoco.MjData(model)
        mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
        self.servo = servo = FormMillServo(model, data, layout, params, tuning)
        self.program = _plan(layout, passes, feed_mm_min, self.dt, tuning)
        self.planned = sum(
            len(s.pos) if s.kind != "settle" else round(tuning.settle_time / self.dt) for s in self.program
        )
        self.omega = spindle_rpm * 2 * math.pi / 60
        self.site_b, self.site_m = int(model.site("blank_frame").id), int(model.site("mill_frame").id)
        self.body_m, self.body_b = int(model.site_bodyid[self.site_m]), int(model.site_bodyid[self.site_b])
        self.integrator = Integrator(
            model,
            data,
            substeps,
            servo.qa[_Z],
            lambda t: _diagnose(layout, params, t),
            BAD_ACCELERATION_OR_SPEED,
            servo.error[:POSITIONED],  # A X Y Z B: the spindle has no position loop
            tuning.runaway,
            lambda t: _runaway(servo, tuning, h, t),
        )
        self.pos, self.vel, self.acc = np.zeros(len(AXES)), np.zeros(len(AXES)), np.zeros(len(AXES))
        self.traces: list[np.ndarray] = []
        self.records: list[PassRecord] = []
        self.tick = 0
        self.wall0 = time.perf_counter()
        self.feed: _Segment | None = None  # the feed segment of this tick (its force row ``feed_row``)
        self.feed_row = 0
        self._commands_left = self._commands()

    def before_tick(self) -> bool:
        """The program's next command, then the spindle, the servo and the traces."""
        if not next(self._commands_left, False):  # the program has ended
            return False
        data, pos, vel, acc = self.data, self.pos, self.vel, self.acc
        t = data.time
        t_ramp = self.tuning.spindle_ramp
        if t < t_ramp:  # spindle run-up: half cosine of the speed
            vel[_S] = self.omega * 0.5 * (1 - math.cos(math.pi * t / t_ramp))
            acc[_S] = self.omega * 0.5 * math.pi / t_ramp * math.sin(math.pi * t / t_ramp)
        else:
            vel[_S], acc[_S] = self.omega, 0.0
        self.servo.update(self.dt, pos, vel, acc)
        if self.tick % self.tuning.trace_every == 0:
            row = np.empty(24)
            row[0] = t
            row[1:7] = data.qpos[self.servo.qa]
            row[7:12], row[12] = pos[:POSITIONED], vel[_S]
            row[13:19] = self.servo.torque
            row[19:24] = self.servo.error[:POSITIONED]
            self.traces.append(row)
        return True

    def after_tick(self) -> None:
        self.tick += 1
        if self.progress is not None and self.tick % 500 == 0:
            self.progress(min(self.tick / self.planned, 0.999))

    def _commands(self):
        """The program tick by tick: each step sets the tick's command (and on a feed tick records the mill's pose
        at the tick's start); a settle segment holds until the axes have settled (read after each tick)."""
        tuning, data = self.tuning, self.data
        pos, vel, acc = self.pos, self.vel, self.acc
        tol = np.asarray(tuning.settle_tolerance)
        dwell = 0.0
        for seg in self.program:
            if seg.kind == "settle":
                pos[:POSITIONED], vel[:POSITIONED], acc[:POSITIONED] = seg.pos[0], 0.0, 0.0
                t0 = data.time
                while True:
                    yield True
                    waited = data.time - t0
                    settled = (
                        waited >= tuning.settle_time
                        and data.time >= tuning.spindle_ramp
                        and np.all(np.abs(self.servo.error[:POSITIONED]) < tol)
                    )
                    if settled or waited >= tuning.settle_timeout:
                        dwell = waited
                        break
                continue
            if seg.kind == "feed":
                yield from self._feed_ticks(seg, dwell)
                continue
            for k in range(len(seg.pos)):
                pos[:POSITIONED], vel[:POSITIONED], acc[:POSITIONED] = seg.pos[k], seg.vel[k], seg.acc[k]
                yield True
        if self.progress is not None:
            self.progress(1.0)

    def _feed_ticks(self, seg: _Segment, dwell: float):
        """A feed segment: per tick the command and the mill's pose in the gear frame at the tick's start; its
        PassRecord when it ends."""
        data, model, pos, vel, acc = self.data, self.model, self.pos, self.vel, self.acc
        xpos, xmat = data.site_xpos, data.site_xmat
        site_b, site_m = self.site_b, self.site_m
        n = len(seg.pos)
        rec = np.empty((n, 7 + POSITIONED))
        self.feed = seg
        for k in range(n):
            pos[:POSITIONED], vel[:POSITIONED], acc[:POSITIONED] = seg.pos[k], seg.vel[k], seg.acc[k]
            self.feed_row = k
            # the state at this tick's time (site poses after a physics step are one sub-step old)
            mujoco.mj_kinematics(model, data)
            rb = xmat[site_b].reshape(3, 3)
            rec[k, 0] = data.time
            rec[k, 1:4] = rb.T @ (xpos[site_m] - xpos[site_b]) * 1e3
            rec[k, 4:7] = rb.T @ xmat[site_m].reshape(3, 3)[:, 2]
            yield True
            rec[k, 7:] = self.servo.error[:POSITIONED]
        self.feed = None
        p = self.passes[seg.index]
        fe = rec[:, 7:] * np.array(ERROR_UNITS)
        self.records.append(
            PassRecord(
                space=int(p.space),
                angle=2 * math.pi * p.space / self.layout.teeth,
                t=rec[:, 0].copy(),
                centre=rec[:, 1:4].copy(),
                axis=rec[:, 4:7].copy(),
                commanded=seg.commanded,
                following_error=fe,
                steady=seg.steady,
                dwell=dwell,
            )
        )

    def record(self) -> FormMillRecord:
        tr = np.array(self.traces)
        mm = np.array([1.0, 1e3, 1e3, 1e3, 1.0, 1.0])
        return FormMillRecord(
            teeth=int(self.layout.teeth),
            feed_mm_min=float(self.feed_mm_min),
            spindle_rpm=float(self.spindle_rpm),
            passes=self.records,
            spaces=np.array([int(p.space) for p in self.passes]),
            trace_t=tr[:, 0],
            trace_q=tr[:, 1:7] * mm,
            trace_command=tr[:, 7:13] * mm,
            trace_torque=tr[:, 13:19],
            trace_error=tr[:, 19:24] * np.array(ERROR_UNITS),
            wall_time=time.perf_counter() - self.wall0,
            sim_time=float(self.data.time),
        )


class MillLoad:
    """The form-milling machine's load hook: on a feed tick the cutting force (and a finger's torque) of ``load``
    at the tick's commanded face position, on the mill at its lowest point (a finger's: mid-way along its cutting
    length), reversed on the table; nothing between the feeds."""

    every_substep = False

    def __init__(self, cnc: FormMillCnc, load: Callable[[int, np.ndarray], np.ndarray]):
        self.cnc, self.load = cnc, load
        self._feed: _Segment | None = None
        self._forces = self._torques = None
        self._zero3 = np.zeros(3)

    def __call__(self, t: float, dt: float) -> tuple[ToolLoad, ...]:
        cnc = self.cnc
        seg = cnc.feed
        if seg is None:
            return ()
        if seg is not self._feed:  # space frame (tangential, radial, axial) -> machine frame (x radial, y tangential)
            f = np.asarray(self.load(seg.index, seg.pos[:, _Z] * 1e3), dtype=float)
            self._feed, self._forces = seg, np.column_stack([f[:, 1], f[:, 0], f[:, 2]])
            # a torque on the mill too (the finger's cutting torque about its axis)
            self._torques = np.column_stack([f[:, 4], f[:, 3], f[:, 5]]) if f.shape[1] == 6 else None
        k = cnc.feed_row
        xpos, site_m, layout = cnc.data.site_xpos, cnc.site_m, cnc.layout
        if layout.finger:  # mid-way along the finger's cutting length
            point = xpos[site_m] + cnc.data.site_xmat[site_m].reshape(3, 3)[:, 2] * (layout.mill_width / 2)
        else:  # the disc mill's lowest point
            point = xpos[site_m] - np.array([layout.mill_radius, 0.0, 0.0])
        torque = self._zero3 if self._torques is None else self._torques[k]
        return (ToolLoad(self._forces[k], torque, point),)
