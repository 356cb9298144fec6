"""The CNC of the face-contour machine (seed 004, continuous indexing), its task and load hook on the machine loop,
and the cut and the measurement of the motion the machine really makes, with the geometry of
:mod:`cutting.face_contour.slots`.

The slots a real machine cuts carry its drives' errors and the cut's loads; this module runs the machine
(:func:`simulate_face_contour`: the electronic gearbox
:class:`virtual_machine.controllers.face_gearbox.ElectronicGearbox`, the servos :class:`FaceServo`, the task
:class:`FaceCnc`, the load hook :class:`ForceFeedback`), records the element tips' final passes
(:class:`FaceContourRecord`), and cuts (:func:`cut_recorded`) and measures (:func:`measure_recorded`) what they
made. The machine's measured slots: docs/face-contours-and-turning.md, "The face-contour machine".
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import manifold3d as mf
import mujoco
import numpy as np
from scipy.interpolate import CubicSpline

from cutting.face_contour.forces import FaceLoad
from cutting.face_contour.slots import (
    SWEEP_TOLERANCE,
    FaceCoupling,
    FaceCut,
    bisect_roots,
    element_path,
    first_sign_change,
    held_speed_factor,
    hull_steps,
    subtract_pieces,
    work_offset,
    workpiece_angle,
)
from machine_models.face_contour_machine import (
    FaceMachineLayout,
    FaceMachineParams,
    build_face_machine_spec,
    has_joint,
    head_angle_joints,
    relaxed_qpos,
    stage_omega_h,
)
from machine_models.parameters import ARCSEC
from machine_models.parts import tendon_coefs
from metrology.face_slots import SlotMeasure, bottom_form, measuring_radii, side_lines
from virtual_machine.controllers.cascade import CascadeServo, ServoAxis
from virtual_machine.controllers.face_gearbox import ElectronicGearbox
from virtual_machine.reach.face import check_cutting_load, check_face_reach
from virtual_machine.runtime.integrator import (
    BAD_ACCELERATION_OR_SPEED,
    Integrator,
    divergence_message,
    servo_substeps,
)
from virtual_machine.runtime.loop import MachineLoop, ToolLoad
from virtual_machine.setting.machine_layout import face_layout

__all__ = [
    "AXES",
    "FaceCnc",
    "FaceContourRecord",
    "FacePassRecord",
    "FaceServo",
    "FaceTuning",
    "ForceFeedback",
    "cut_recorded",
    "drive_twists",
    "final_turn",
    "measure_recorded",
    "pass_window",
    "recorded_bottom",
    "recorded_corners",
    "recorded_hulls",
    "recorded_sides",
    "simulate_face_contour",
]

AXES = ("A", "H", "E", "Z", "Y")  # work angle a, head angle phi, eccentric [rad], infeed, cross slide [m]
MOTORS = ("MA", "MH", "ME", "MZ", "MY")
_A, _H, _E, _Z, _Y = range(5)
#: bisection steps on a recorded pass (half a servo period / 2^40: far below a nanometre of tip motion)
BISECTION_STEPS = 40


@dataclass(frozen=True)
class FaceTuning:
    """Servo gains, the electronic gearbox's resolution and the run's limits (per axis in the order A, H, E, Z, Y)."""

    servo_rate: float = 2000.0  # Hz: position and speed loops (the physics sub-steps a whole number of times)
    velocity_bandwidth: tuple[float, ...] = (40.0, 40.0, 60.0, 80.0, 80.0)  # Hz: PI speed loops
    position_gain: tuple[float, ...] = (60.0, 60.0, 80.0, 100.0, 100.0)  # 1/s: Kv
    ramp: float = 0.5  # s: half-cosine run-up of reference generator 14
    pulses_per_rev: int = 2**24  # command pulses per revolution of A, H and E (3.7e-7 rad: 0.05 um at R = 125 mm)
    infeed_resolution: float = 1e-9  # m per infeed command pulse
    runaway: tuple[float, ...] = (0.01, 0.05, 0.05, 1e-3, 1e-3)  # rad, rad, rad, m, m: following error that stops
    trace_every: int = 8  # servo ticks per sample of the whole-run traces
    window_margin: float = 0.5  # mm: a pass is recorded while an element's tip (final pass) is below this height


@dataclass
class FacePassRecord:
    """One element pass over slot ``slot`` (tool turn ``turn``: the head angle passes 2 pi turn at its middle) at the
    servo rate, in the workpiece frame (site ``blank_frame``): time ``t`` [s], the head's absolute angle ``phi``
    (joints) and its command ``phi_cmd`` [rad], the workpiece angle ``a`` [rad]; per element j (first axis) the tip
    ``tip`` [mm], the tip edge's direction ``edge`` (the tool axis, site x) and the element's radial direction
    ``radial`` (head centre -> tip, site z), (E, n, 3); ``following_error`` at the encoders (A, H, E [arcsec],
    Z, Y [um]) (n, 5)."""

    slot: int
    turn: int
    t: np.ndarray
    phi: np.ndarray
    phi_cmd: np.ndarray
    a: np.ndarray
    tip: np.ndarray
    edge: np.ndarray
    radial: np.ndarray
    following_error: np.ndarray
    #: with cutting forces (``load``): per element the force on the tool in the workpiece frame (E, n, 3) [N], and
    #: the work drive's and the head drive's twists (driven - ratio x motor: the table behind its worm, the head
    #: behind its gear) (n, 2) [rad]; None without
    force: np.ndarray | None = None
    twist: np.ndarray | None = None

    def deviation(self, c: FaceCoupling) -> np.ndarray:
        """Recorded tip - the seed's tip (:func:`cutting.face_contour.slots.element_path`, final pass) at the
        recorded head
        angle, per element (E, n, 3) [um]: what the machine's coupling of A, E and Z to the head does wrong."""
        ideal = np.stack([element_path(c, self.phi, j, final=True) for j in range(len(self.tip))])
        return (self.tip - ideal) * 1e3

    def slot_deviation(self, c: FaceCoupling) -> np.ndarray:
        """:meth:`deviation` in the slot's frame: radial (along the slot's centre line), tangential (+ towards
        larger polar angles), axial [um], (E, n, 3)."""
        d = self.deviation(c)
        turn = 2 * math.pi * self.slot / c.m
        cs, sn = math.cos(turn), math.sin(turn)
        return np.stack([cs * d[..., 0] + sn * d[..., 1], -sn * d[..., 0] + cs * d[..., 1], d[..., 2]], axis=-1)


@dataclass
class FaceContourRecord:
    """A face-contour run: the ``coupling``, the final passes over the slots of interest (``passes``) and whole-run
    traces every ``trace_every`` servo ticks: time [s], the head's command angle [rad], the axes ``trace_q`` (A,
    phi, E [rad], Z [mm]), the synchronisation errors ``trace_sync`` against the head's real angle (A - a(phi)
    [arcsec], E - N phi [arcsec], Z - z(phi) [um]: what the electronic gearbox and the drives leave), motor torques
    ``trace_torque`` (MA, MH, ME, MZ) [N m] and encoder following errors ``trace_error`` (A, H, E [arcsec], Z [um]).
    Numpy and frozen dataclasses only: picklable."""

    coupling: FaceCoupling
    tool_rpm: float
    start_turn: int
    passes: list[FacePassRecord]
    trace_t: np.ndarray
    trace_phi_cmd: np.ndarray
    trace_q: np.ndarray
    trace_sync: np.ndarray
    trace_torque: np.ndarray
    trace_error: np.ndarray
    eccentric: bool
    #: the cross slide (control "work_setting"): Y and its sync error Y - T (1 - cos q_s phi) [um], MY [N m], its
    #: encoder's following error [um]; zeros without it
    trace_cross: np.ndarray | None = None
    wall_time: float = 0.0  # s
    sim_time: float = 0.0  # s
    axes: tuple[str, ...] = field(default=AXES)

    @property
    def slots(self) -> tuple[int, ...]:
        return tuple(p.slot for p in self.passes)

    def pass_of(self, slot: int) -> FacePassRecord:
        for p in self.passes:
            if p.slot == slot:
                return p
        raise ValueError(f"slot: {slot} was not recorded (recorded: {self.slots})")

    def deviation(self) -> np.ndarray:
        """All passes' :meth:`FacePassRecord.deviation` stacked along the samples, (E, n, 3) [um]."""
        return np.concatenate([p.deviation(self.coupling) for p in self.passes], axis=1)


# ---------------------------------------------------------------------------------------------------- programme


def pass_window(c: FaceCoupling, margin: float = 0.5) -> tuple[float, float]:
    """Head angles [rad] relative to 2 pi j between which some element's tip is below ``margin`` [mm] on the final
    pass over slot j mod m (the union over the elements, a grid step beyond)."""
    phi = np.linspace(-1.5, 1.5, 6001)
    lo, hi = math.inf, -math.inf
    for j in range(c.elements):
        z = element_path(c, phi, j, final=True)[:, 2]
        below = np.flatnonzero(z < margin)
        if below.size == 0:
            continue
        i0 = below[np.argmin(z[below])]
        a = b = i0
        while a > 0 and z[a - 1] < margin:
            a -= 1
        while b < len(phi) - 1 and z[b + 1] < margin:
            b += 1
        lo, hi = min(lo, phi[max(a - 1, 0)]), max(hi, phi[min(b + 1, len(phi) - 1)])
    if not math.isfinite(lo):
        raise ValueError(f"window_margin: no element goes below z = {margin} mm on the final pass")
    return float(lo), float(hi)


def final_turn(c: FaceCoupling, slot: int, window: tuple[float, float]) -> int:
    """The tool turn j whose pass is slot ``slot``'s final one: the first pass over it (j = slot mod m) that lies
    wholly after the plunge has reached the depth at phi = 2 pi depth / S (the spark-out's workpiece revolution
    passes every slot once at full depth)."""
    first = math.ceil(c.depth / c.S - window[0] / (2 * math.pi) - 1e-9)
    return first + (slot - first) % c.m


class FaceServo(CascadeServo):
    """The drives of the machine (:class:`virtual_machine.controllers.cascade.CascadeServo`): position loops and PI
    speed loops on the motor encoders (A, H, [E,] Z, [Y]); commands and ``torque``, ``error`` as (A, H, E, Z, Y), E
    zero without the eccentric, Y without the work setting. ``axis0``: the axes' start positions.

    Per axis the servo is the cascade of :mod:`virtual_machine.controllers.cascade` on the **motor encoder**
    (semi-closed loop): position loop (Kv) with speed feed-forward -> PI speed loop -> torque, plus inertia
    feed-forward, limited to the motor's peak torque with anti-windup. The commands and the speed feed-forward come
    from the electronic gearbox's converters (every axis counts the generator's pulses). The stages' compliance,
    backlash and friction therefore show between tip and workpiece, not at the encoders."""

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        params: FaceMachineParams,
        tuning: FaceTuning,
        axis0: np.ndarray,
    ):
        self.tuning = tuning
        self.eccentric = "E" in head_angle_joints(model)
        idx = [_A, _H, _E, _Z] if self.eccentric else [_A, _H, _Z]
        if has_joint(model, "Y"):
            idx.append(_Y)
        lead = params.screw_pitch / (2 * math.pi)
        g = [
            params.work_drive.ratio,
            params.head_drive.ratio,
            params.eccentric_drive.ratio,
            params.z_drive.ratio * lead,
            params.y_drive.ratio,
        ]
        chains = {
            _A: (("MA", 1.0), ("A", g[_A])),
            _H: (("MH", 1.0), ("H", g[_H])),  # the head's absolute angle moves, the eccentric held
            _E: (("ME", 1.0), ("E", g[_E]), ("H", -g[_E])),  # the head's absolute angle held by its drive
            _Z: (("MZ", 1.0), ("TZ", params.z_drive.ratio), ("Z", g[_Z])),
            _Y: (("MY", 1.0), ("Y", g[_Y])),
        }
        axes = [
            ServoAxis(MOTORS[i], g[i], chains[i], tuning.velocity_bandwidth[i], tuning.position_gain[i]) for i in idx
        ]
        super().__init__(model, data, axes, np.asarray(axis0)[idx], index=idx, size=5)


def _diagnose(layout: FaceMachineLayout, params: FaceMachineParams, t: float) -> str:
    """Which compliant stage's local mode is too fast for the time step (see ``stage_omega_h``)."""
    return divergence_message("face-contour machine", stage_omega_h(layout, params), params.timestep, t)


def _runaway(servo: FaceServo, tuning: FaceTuning, tool_rpm: float, h: float, t: float) -> str:
    """Which servo ran away and what to change: its motor's peak torque when it was saturated, else its gains."""
    i = int(np.argmax(np.abs(servo.error) / np.asarray(tuning.runaway)))
    axis, peak = AXES[i], f"machine.{MOTORS[i][1].lower()}_motor_torque"
    head = f"the {axis} servo ran away at t = {t:.4f} s (following error beyond {tuning.runaway[i]:g}). "
    k = int(np.flatnonzero(servo.idx == i)[0])
    if abs(servo.torque[i]) >= servo.peak[k] * (1 - 1e-9):
        return head + f"{MOTORS[i]} is at its peak torque: raise {peak} or lower tool_rpm (now {tool_rpm:g})"
    return head + (
        f"Lower FaceTuning.velocity_bandwidth / position_gain of {axis}, or reduce machine.timestep (now {h:g} s) if "
        f"a stage's omega*h is near 2 (face_contour_machine.stage_omega_h)"
    )


#: share of a motor's peak torque the held speed's inertia torque may take (the rest: the speed loop, friction)
HELD_TORQUE_SHARE = 0.8


def _check_held_speed(c: FaceCoupling, servo: FaceServo, omega: float, tool_rpm: float) -> None:
    """Eq. 16 makes the head's speed swing round each revolution (k from 1 at M to (R - N e) / (R + N e)), at
    accelerations that grow with the speed squared: omega^2 k dk/dphi on the head, N times that on the eccentric,
    1/m on the work. Each axis's motor needs its inertia times that; a motor it would saturate is refused before the
    run, naming the motor and the tool speed that keeps within HELD_TORQUE_SHARE of its peak."""
    phi = np.linspace(0.0, 2 * math.pi, 4001)
    k, dk = held_speed_factor(c, phi)
    head = float(np.max(np.abs(k * dk))) * omega**2  # rad/s^2
    for axis, acc in ((_A, head / c.m), (_H, head), (_E, head * c.eccentric_ratio)):
        hits = np.flatnonzero(servo.idx == axis)
        if not len(hits):
            continue
        j = int(hits[0])
        need = servo.inertia[j] * acc / abs(servo.g[j])
        allowed = HELD_TORQUE_SHARE * servo.peak[j]
        if need > allowed:
            rpm = tool_rpm * math.sqrt(allowed / need)
            raise ValueError(
                f"head_speed = 'held' (eq. 16) at {tool_rpm:g} rpm swings the head by a factor "
                f"{float(k.min()):.3f}..1 each turn: {MOTORS[axis]} would need {need:.1f} N m of its "
                f"{servo.peak[j]:g} N m peak; lower process.tool_speed to {math.floor(rpm)} rpm or below, raise "
                f"machine.model's {MOTORS[axis][1].lower()}_motor_torque, or use head_speed = 'constant'"
            )


class ForceFeedback:
    """The face-contour machine's load hook (as form milling's): each servo tick, at the head's real angle, every
    element's force from ``load`` acts at its tip (site ``element_frame*``) on the tool head and, reversed, on the
    workpiece (``blank_frame``'s body), held over the tick's physics sub-steps as their mean over the tick's head
    angles (the impulse right at the entry step); ``last`` the forces of the tick (E, 3) in the workpiece frame [N].
    The task hands it the tick's head angles (:meth:`at`) before the loop asks for the loads."""

    every_substep = False

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, load: FaceLoad, sites: list[int], site_b: int):
        self.model, self.data, self.load = model, data, load
        self.sites, self.site_b = sites, site_b
        self.body_t = [int(model.site_bodyid[s]) for s in sites]
        self.last = np.zeros((len(sites), 3))
        self.zero3 = np.zeros(3)
        self._phi = self._dphi = 0.0

    def at(self, phi: float, dphi: float) -> None:
        """The tick's head angles: phi..phi + dphi [rad]."""
        self._phi, self._dphi = phi, dphi

    def __call__(self, t: float, dt: float) -> list[ToolLoad]:
        """The mean forces over the tick's head angles, on the element tips."""
        m, d = self.model, self.data
        f = self.load.at(self._phi, self._dphi)
        if f is None:
            self.last[:] = 0.0
            return []
        mujoco.mj_kinematics(m, d)  # mj_applyFT takes the present kinematics (after a physics step they are stale)
        rb = d.site_xmat[self.site_b].reshape(3, 3)
        out = [ToolLoad(rb @ f[j], self.zero3, d.site_xpos[s].copy(), self.body_t[j]) for j, s in enumerate(self.sites)]
        self.last[:] = f
        return out


def drive_twists(model: mujoco.MjModel) -> Callable[[np.ndarray], np.ndarray]:
    """qpos -> the work drive's and the head drive's twists [rad] (their tendons: driven - ratio x motor)."""
    rows = []
    for tendon in ("work_drive", "head_drive"):
        coef = tendon_coefs(model, tendon)
        adr = np.array([int(model.joint(j).qposadr[0]) for j in coef])
        rows.append((adr, np.array(list(coef.values()))))
    return lambda q: np.array([float(q[a] @ k) for a, k in rows])


def simulate_face_contour(
    coupling: FaceCoupling,
    params: FaceMachineParams | None = None,
    slots: Sequence[int] = (0, 1, 2),
    tool_rpm: float = 150.0,
    run_in: int = 2,
    start_turn: int | None = None,
    tuning: FaceTuning | None = None,
    progress: Callable[[float], None] | None = None,
    hold_speed: bool = False,
    load: FaceLoad | None = None,
    master: str = "generator",
) -> FaceContourRecord:
    """Cut ``coupling``'s slots on the simulated machine (MuJoCo) with the electronic gearbox of this module, the
    head at ``tool_rpm`` (at M; ``hold_speed``: its speed by eq. 16 all round, so that the tip's speed under the
    eccentric stays that at M), and record the final pass over each of ``slots``. The run starts at rest ``run_in`` tool
    turns before the first of these passes (or at ``start_turn``) and ends after the last. Raises ValueError for bad
    inputs and :class:`cutting.errors.SimulationDivergedError` when the integration blows up or
    a servo runs away (the message names what to change). ``load``: the cutting forces
    (:class:`cutting.face_contour.forces.FaceLoad`), fed back at every tick (:class:`ForceFeedback`) after a check
    that the motors can take the cycle's heaviest pass (:func:`check_cutting_load`, InputError if not); none: the
    elements cut air. ``master``: what the work, the eccentric and the cross slide follow (the gearbox's
    ``master``): "generator" (the head's command) or "head" (its spindle encoder, what the head really does).

    **Electronic gearbox** (:class:`virtual_machine.controllers.face_gearbox.ElectronicGearbox`: reference generator
    14 -> head; divider 7 (1/m) -> summator 9 with the cyclic-ratio modulation -> work; x N -> eccentric; the
    infeed's S per turn, gated at the depth); the drives: :class:`FaceServo`.

    **Run.** The machine starts at rest at head turn ``start_turn`` (default: ``run_in`` turns before the first
    recorded pass) with every axis where the programme has it then and every stage relaxed: the plunge passes before
    it lie above the final ones (the xy motion does not depend on the feed), so they cut nothing the final passes
    leave. It runs up, and records, at the servo rate, the element tips' poses in the workpiece frame (sites
    ``element_frame*`` relative to ``blank_frame``) during the final (full-depth) pass over each slot of interest:
    the task :class:`FaceCnc` on the machine loop (:mod:`virtual_machine.runtime.loop`), whose physics has the
    divergence and runaway checks of :class:`virtual_machine.runtime.integrator.Integrator`.

    **Cutting forces** (``load``, :mod:`cutting.face_contour.forces`): checked before the run against the motors
    (:func:`virtual_machine.reach.face.check_cutting_load`: a feed the head motor cannot cut is refused, naming the
    feed that would do), then fed back at every tick (:class:`ForceFeedback`, the machine's load hook: at the element
    tips on the head and, reversed, on the workpiece); the passes record the forces and the work and head drives'
    twists (:class:`FacePassRecord`).
    """
    params = params or FaceMachineParams()
    tuning = tuning or FaceTuning()
    if not (math.isfinite(tool_rpm) and tool_rpm > 0):
        raise ValueError(f"tool_rpm = {tool_rpm}: must be > 0")
    check_face_reach(coupling, params, tool_rpm)
    slots = tuple(slots)
    if not slots or any(not isinstance(k, int | np.integer) or not 0 <= k < coupling.m for k in slots):
        raise ValueError(f"slots = {slots}: must be slot numbers in [0, {coupling.m})")
    if len(set(slots)) != len(slots):
        raise ValueError(f"slots = {slots}: each slot once")
    layout = face_layout(coupling)
    model = build_face_machine_spec(layout, params).compile()  # raises ValueError naming bad parameters
    servo_substeps(model.opt.timestep, tuning.servo_rate)  # the servo period a whole number of time steps
    omega = tool_rpm * 2 * math.pi / 60
    window = pass_window(coupling, tuning.window_margin)
    turns = {k: final_turn(coupling, k, window) for k in slots}
    first = min(turns.values())
    if start_turn is None:
        if not (isinstance(run_in, int) and run_in >= 1):
            raise ValueError(f"run_in = {run_in}: must be an integer >= 1 (tool turns before the first pass)")
        start_turn = first - run_in
    run_up = omega * tuning.ramp / 2  # rad: the head's angle during the run-up
    if 2 * math.pi * (first - start_turn) + window[0] < run_up + 0.1 * omega:
        raise ValueError(
            f"run_in = {first - start_turn}: the first recorded pass would start before the head has run up and "
            f"settled ({(run_up + 0.1 * omega) / (2 * math.pi):.2f} turns); raise run_in or shorten FaceTuning.ramp"
        )

    egb = ElectronicGearbox(
        coupling, start_turn, omega, tuning.pulses_per_rev, tuning.infeed_resolution, tuning.ramp, hold_speed, master
    )
    cnc = FaceCnc(coupling, layout, model, params, tuning, egb, window, turns, slots, tool_rpm, start_turn, progress)
    if hold_speed and coupling.eccentric_on:
        _check_held_speed(coupling, cnc.servo, omega, tool_rpm)
    hook = None
    if load is not None:
        check_cutting_load(coupling, load, params)
        hook = cnc.feedback = ForceFeedback(model, cnc.data, load, cnc.sites, cnc.site_b)
    MachineLoop(cnc.integrator, cnc, hook, int(model.site_bodyid[cnc.sites[0]]), cnc.body_b).run()
    return cnc.record()


class FaceCnc:
    """The face-contour machine's task on the machine loop: before each tick the electronic gearbox's command (with
    the head's encoder when the slaves follow it), the servo, and inside a recorded pass the element tips' poses at
    the tick's start and the traces; after it the gearbox's counters, the cut's forces of the tick and the
    progress. The program ends a little after the last recorded pass."""

    def __init__(
        self,
        coupling: FaceCoupling,
        layout: FaceMachineLayout,
        model: mujoco.MjModel,
        params: FaceMachineParams,
        tuning: FaceTuning,
        egb: ElectronicGearbox,
        window: tuple[float, float],
        turns: dict[int, int],
        slots: tuple[int, ...],
        tool_rpm: float,
        start_turn: int,
        progress: Callable[[float], None] | None,
    ):
        self.coupling, self.tuning, self.egb, self.turns, self.slots = coupling, tuning, egb, turns, slots
        self.tool_rpm, self.start_turn, self.progress, self.model = tool_rpm, start_turn, progress, model
        h = model.opt.timestep
        substeps = servo_substeps(h, tuning.servo_rate)
        self.dt = substeps * h
        pos, _, _ = egb.command(0.0, self.dt)
        self.eccentric = eccentric = layout.eccentric
        axes = {"A": pos[_A], "H": pos[_H] - pos[_E], "Z": pos[_Z]} | ({"E": pos[_E]} if eccentric else {})
        axes |= {"Y": pos[_Y]} if layout.work_setting else {}
        self.data = data = mujoco.MjData(model)
        data.qpos[:] = relaxed_qpos(model, axes)
        self.servo = servo = FaceServo(model, data, params, tuning, pos)
        self.qa = {n: int(model.joint(n).qposadr[0]) for n in ("A", "H", "Z")}
        self.qe = int(model.joint("E").qposadr[0]) if eccentric else -1
        self.qy = int(model.joint("Y").qposadr[0]) if layout.work_setting else -1
        self.site_b = int(model.site("blank_frame").id)
        self.body_b = int(model.site_bodyid[self.site_b])
        self.sites = [
            int(model.site("element_frame" if j == 0 else f"element_frame_{j}").id) for j in range(coupling.elements)
        ]
        self.feedback: ForceFeedback | None = None  # the cut's load hook, when the run has one
        self.twists = drive_twists(model)
        self.integrator = Integrator(
            model,
            data,
            substeps,
            self.qa["Z"],
            lambda t: _diagnose(layout, params, t),
            BAD_ACCELERATION_OR_SPEED,
            servo.error,
            tuning.runaway,
            lambda t: _runaway(servo, tuning, tool_rpm, h, t),
        )
        order = sorted(slots, key=turns.__getitem__)
        self.windows = [(k, 2 * math.pi * turns[k] + window[0], 2 * math.pi * turns[k] + window[1]) for k in order]
        self.phi_end = self.windows[-1][2] + 0.02
        self.total = self.phi_end - egb.phi0
        self.n_slot = 0
        self.rows: list[np.ndarray] = []
        self.extras: list[np.ndarray] = []  # per recorded tick: the forces (E x 3, with a load), the two twists
        self.passes: list[FacePassRecord] = []
        self.traces: list[np.ndarray] = []
        self.to_arcsec = np.array([1 / ARCSEC, 1 / ARCSEC, 1 / ARCSEC, 1e6, 1e6])
        self.tick, self.wall0 = 0, time.perf_counter()
        self.head_dofs = [int(model.joint(j).dofadr[0]) for j in head_angle_joints(model)]
        self.w_prev: float | None = None
        self._t = self._phi_cmd = 0.0  # the tick's start and its head command
        self._recorded = False  # this tick's row is in a recorded pass
        self._twist: np.ndarray | None = None

    def _phi(self) -> float:
        """The head's absolute angle now [rad]."""
        qpos = self.data.qpos
        return qpos[self.qa["H"]] + (qpos[self.qe] if self.eccentric else 0.0)

    def before_tick(self) -> bool:
        data, egb, servo = self.data, self.egb, self.servo
        t = self._t = data.time
        head = None
        if egb.master == "head":  # the spindle encoder: angle at the command resolution, speed, its change a tick
            w_now = float(sum(data.qvel[k] for k in self.head_dofs))
            dw = 0.0 if self.w_prev is None else (w_now - self.w_prev) / self.dt
            head = (round(self._phi() / egb.rad) * egb.rad, w_now, dw)
            self.w_prev = w_now
        cmd_pos, cmd_vel, cmd_acc = egb.command(t, self.dt, head)
        phi_cmd = self._phi_cmd = cmd_pos[_H]
        if phi_cmd > self.phi_end:
            return False
        servo.update(self.dt, cmd_pos, cmd_vel, cmd_acc)
        phi = self._phi()
        if self.feedback is not None:
            self.feedback.at(phi, cmd_vel[_H] * self.dt)  # the tick's head angles, for the load hook
        self._recorded = False
        windows = self.windows
        if self.n_slot < len(windows) and phi_cmd >= windows[self.n_slot][1]:
            if phi_cmd <= windows[self.n_slot][2]:
                self._record_tick(t, phi, phi_cmd)
            else:
                self._close_pass()
                self.n_slot += 1
        if self.tick % self.tuning.trace_every == 0:
            self._trace(t, phi, phi_cmd)
        return True

    def after_tick(self) -> None:
        if self._recorded:  # the tick's forces (the hook's, of this tick) beside the twists at its start
            forces = self.feedback.last.ravel() if self.feedback is not None else []
            self.extras.append(np.concatenate([forces, self._twist]))
        self.tick += 1
        self.egb.update(self.dt, self._t)
        if self.progress is not None and self.tick % 500 == 0:
            self.progress(min((self._phi_cmd - self.egb.phi0) / self.total, 0.999))

    def _record_tick(self, t: float, phi: float, phi_cmd: float) -> None:
        """The element tips' poses in the workpiece frame at the tick's start (after a physics step site poses are
        stale)."""
        data = self.data
        mujoco.mj_kinematics(self.model, data)
        xpos, xmat, site_b = data.site_xpos, data.site_xmat, self.site_b
        rb = xmat[site_b].reshape(3, 3)
        row = [np.array([t, phi, phi_cmd, data.qpos[self.qa["A"]]])]
        for s in self.sites:
            rs = rb.T @ xmat[s].reshape(3, 3)
            row += [rb.T @ (xpos[s] - xpos[site_b]) * 1e3, rs[:, 0], rs[:, 2]]
        row.append(self.servo.error.copy())
        self.rows.append(np.concatenate(row))
        self._twist = self.twists(data.qpos)
        self._recorded = True

    def _close_pass(self) -> None:
        k = self.windows[self.n_slot][0]
        r = np.array(self.rows)  # (n, 4 + 9 E + 4): t, phi, phi_cmd, a; per element tip, edge, radial; errors
        n, n_el = len(r), self.coupling.elements
        poses = r[:, 4 : 4 + 9 * n_el].reshape(n, n_el, 3, 3).transpose(1, 0, 2, 3)
        extras = np.array(self.extras)
        self.passes.append(
            FacePassRecord(
                slot=int(k),
                turn=int(self.turns[k]),
                t=r[:, 0].copy(),
                phi=r[:, 1].copy(),
                phi_cmd=r[:, 2].copy(),
                a=r[:, 3].copy(),
                tip=poses[:, :, 0].copy(),
                edge=poses[:, :, 1].copy(),
                radial=poses[:, :, 2].copy(),
                following_error=r[:, 4 + 9 * n_el :] * self.to_arcsec,
                force=extras[:, :-2].reshape(n, n_el, 3).transpose(1, 0, 2) if self.feedback else None,
                twist=extras[:, -2:],
            )
        )
        self.rows.clear()
        self.extras.clear()

    def _trace(self, t: float, phi: float, phi_cmd: float) -> None:
        data, c, egb, servo = self.data, self.coupling, self.egb, self.servo
        qa, qe, qy, to_arcsec = self.qa, self.qe, self.qy, self.to_arcsec
        q = np.array([data.qpos[qa["A"]], phi, data.qpos[qe] if self.eccentric else 0.0, data.qpos[qa["Z"]]])
        ideal_a = float(workpiece_angle(c, phi))
        ideal_z = -min(egb.feed_per_turn * phi / (2 * math.pi), c.depth * 1e-3)
        sync = [
            (q[0] - ideal_a) / ARCSEC,
            (q[2] - c.eccentric_ratio * phi) / ARCSEC if self.eccentric else 0.0,
            (q[3] - ideal_z) * 1e6,
        ]
        y = data.qpos[qy] if qy >= 0 else 0.0
        cross = [y * 1e6, (y * 1e3 - float(work_offset(c, phi)[0])) * 1e3]  # Y, Y - T (1 - cos q_s phi) [um]
        self.traces.append(
            np.concatenate(
                [
                    [t, phi_cmd],
                    q,
                    sync,
                    servo.torque[:4],
                    servo.error[:4] * to_arcsec[:4],
                    cross,
                    servo.torque[4:],
                    servo.error[4:] * to_arcsec[4:],
                ]
            )
        )

    def record(self) -> FaceContourRecord:
        if self.rows:
            self._close_pass()
        self.data.qfrc_applied[:] = 0.0
        if self.progress is not None:
            self.progress(1.0)
        tr = np.array(self.traces)
        return FaceContourRecord(
            coupling=self.coupling,
            tool_rpm=float(self.tool_rpm),
            start_turn=int(self.start_turn),
            passes=sorted(self.passes, key=lambda p: self.slots.index(p.slot)),
            trace_t=tr[:, 0],
            trace_phi_cmd=tr[:, 1],
            trace_q=tr[:, 2:6] * np.array([1.0, 1.0, 1.0, 1e3]),
            trace_sync=tr[:, 6:9],
            trace_torque=tr[:, 9:13],
            trace_error=tr[:, 13:17],
            trace_cross=tr[:, 17:21],
            eccentric=self.eccentric,
            wall_time=time.perf_counter() - self.wall0,
            sim_time=float(self.data.time),
        )


# ---------------------------------------------------------------------------------------------------- recorded cut


class _PassPath:
    """Cubic splines (in time) of one element's recorded pass: tip [mm], edge and radial directions."""

    def __init__(self, p: FacePassRecord, element: int):
        self.t = p.t
        self.tip = CubicSpline(p.t, p.tip[element], axis=0)
        self.edge = CubicSpline(p.t, p.edge[element], axis=0)
        self.radial = CubicSpline(p.t, p.radial[element], axis=0)

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        edge, radial = self.edge(t), self.radial(t)
        edge /= np.linalg.norm(edge, axis=-1, keepdims=True)
        radial /= np.linalg.norm(radial, axis=-1, keepdims=True)
        return self.tip(t), edge, radial


def recorded_corners(c: FaceCoupling, tip: np.ndarray, edge: np.ndarray, radial: np.ndarray) -> np.ndarray:
    """The element plate's four corners (..., 4, 3) from a recorded frame (tip [mm], edge = tool axis, radial =
    head centre -> tip): those of :func:`cutting.face_contour.slots.plate_corners`, whose frame comes from the ideal
    motion instead (the tip edge's ends, then the top's)."""
    w_tip = 0.5 * c.edge_width
    w_top = w_tip + c.element_height * math.tan(c.flank_angle)
    top = tip - c.element_height * radial
    return np.stack([tip - w_tip * edge, tip + w_tip * edge, top + w_top * edge, top - w_top * edge], axis=-2)


def recorded_hulls(c: FaceCoupling, p: FacePassRecord, tol: float = SWEEP_TOLERANCE) -> tuple[list, float]:
    """The convex pieces of a recorded pass's swept volume (every element): hulls of consecutive plate placements
    on the splined poses, the servo period subdivided until the chord error is within ``tol`` [mm]; and that
    error."""
    hulls, worst = [], 0.0
    for j in range(len(p.tip)):
        path = _PassPath(p, j)
        split = 1
        while True:
            t = np.linspace(p.t[0], p.t[-1], split * (len(p.t) - 1) + 1)
            lo, hi = hull_steps(t)
            c0, c1 = recorded_corners(c, *path.at(lo)), recorded_corners(c, *path.at(hi))
            err = 0.0
            for f in (0.25, 0.5, 0.75):
                q = recorded_corners(c, *path.at(lo + f * (hi - lo)))
                err = max(err, float(np.max(np.linalg.norm(q - ((1 - f) * c0 + f * c1), axis=-1))))
            if err <= tol:
                break
            split += 1
        worst = max(worst, err)
        hulls += [mf.Manifold.hull_points(np.vstack([a, b])) for a, b in zip(c0, c1, strict=True)]
    return hulls, worst


def cut_recorded(record: FaceContourRecord, tol: float = SWEEP_TOLERANCE) -> FaceCut:
    """The face blank with the recorded passes' swept volumes removed (one batched boolean), as
    :func:`cutting.face_contour.slots.cut_slots` does with the ideal motion; ``tol`` [mm] the chord error. The
    elements' plates (the plate corners of :func:`cutting.face_contour.slots.plate_corners`, here from the recorded
    frames) are swept as hulls through the face blank."""
    t0 = time.perf_counter()
    c = record.coupling
    pieces, worst = [], 0.0
    for p in record.passes:
        h, err = recorded_hulls(c, p, tol)
        pieces += h
        worst = max(worst, err)
    solid = subtract_pieces(c, pieces, tol)
    return FaceCut(solid, record.slots, len(pieces), worst, tol, time.perf_counter() - t0)


def recorded_bottom(record: FaceContourRecord, radii: np.ndarray, slot: int = 0) -> np.ndarray:
    """Slot ``slot``'s bottom z [mm] at ``radii`` on its radial centre line, from the recorded pass: the lowest
    height of any element's tip edge passing over the point (the root of (P - tip) . u = 0, u the horizontal
    normal of the edge, on the splined poses), as :func:`cutting.face_contour.slots.exact_bottom` on the ideal path."""
    c, p = record.coupling, record.pass_of(slot)
    turn = 2 * math.pi * slot / c.m
    r = np.asarray(radii, dtype=float)
    pt = np.stack([r * math.cos(turn), r * math.sin(turn)], axis=-1)
    best = np.full(r.shape, np.nan)
    for j in range(len(p.tip)):
        path = _PassPath(p, j)

        def gap(t: np.ndarray, path: _PassPath = path) -> np.ndarray:
            tip, edge, _ = path.at(t)
            u = np.stack([edge[..., 1], -edge[..., 0]], axis=-1)  # edge x z: the tool plane's horizontal direction
            return np.einsum("...k,...k->...", pt - tip[..., :2], u)

        u = np.stack([p.edge[j][:, 1], -p.edge[j][:, 0]], axis=-1)
        g = np.einsum("ink,nk->in", pt[:, None, :] - p.tip[j][None, :, :2], u)
        k, ok = first_sign_change(g)
        t = bisect_roots(gap, p.t[k], p.t[k + 1], g[np.arange(len(r)), k], BISECTION_STEPS)
        tip, edge, _ = path.at(t)
        across = np.abs(np.einsum("ij,ij->i", pt - tip[:, :2], edge[:, :2]))
        z = np.where(ok & (across <= 0.5 * c.edge_width), tip[:, 2], np.nan)
        best = np.fmin(best, z)
    return best


def recorded_sides(record: FaceContourRecord, radii: np.ndarray, height: float, slot: int = 0) -> np.ndarray:
    """Polar angles [rad] of slot ``slot``'s sides at ``radii`` and z = ``height`` from the recorded pass, (2, n):
    the - side and the + side (as :func:`cutting.face_contour.slots.exact_sides`): the ends of the plates' sections at
    that height, their crossings of the circles r bisected on the splined poses."""
    c, p = record.coupling, record.pass_of(slot)
    r = np.asarray(radii, dtype=float)
    out = np.stack([np.full(r.shape, np.inf), np.full(r.shape, -np.inf)])
    tan = math.tan(c.flank_angle)
    turn = 2 * math.pi * slot / c.m
    for j in range(len(p.tip)):
        path = _PassPath(p, j)
        for row, sign in ((0, -1), (1, 1)):

            def side(t: np.ndarray, path: _PassPath = path, sign: int = sign) -> tuple[np.ndarray, np.ndarray]:
                tip, edge, radial = path.at(t)
                s = (tip[..., 2] - height) / radial[..., 2]  # from the tip towards the head centre
                q = tip - s[..., None] * radial + (sign * (0.5 * c.edge_width + s * tan))[..., None] * edge
                return q[..., :2], (s >= 0) & (s <= c.element_height)

            pts, valid = side(p.t)
            g = np.where(valid, np.linalg.norm(pts, axis=-1), np.nan)[None, :] - r[:, None]
            k, ok = first_sign_change(np.nan_to_num(g, nan=-1.0))

            def gap(t: np.ndarray, side=side) -> np.ndarray:
                return np.linalg.norm(side(t)[0], axis=-1) - r

            t = bisect_roots(gap, p.t[k], p.t[k + 1], g[np.arange(len(r)), k], BISECTION_STEPS)
            q, reach = side(t)
            rel = np.angle(np.exp(1j * (np.arctan2(q[:, 1], q[:, 0]) - turn)))  # about the slot's centre line
            ang = np.where(ok & reach, turn + rel, np.nan)
            out[row] = np.fmin(out[row], ang) if sign < 0 else np.fmax(out[row], ang)
    return out


def measure_recorded(
    record: FaceContourRecord,
    slots: Sequence[int] | None = None,
    radii: np.ndarray | None = None,
    height: float | None = None,
) -> list[SlotMeasure]:
    """The recorded slots measured exactly on the recorded motion (bottom, sides at ``height``, default half the
    depth, and the centre at radius L), as :func:`metrology.face_slots.measure_slots` measures the ideal
    slots (:class:`cutting.face_contour.slots.ExactSlots`); the spacing follows with
    :func:`metrology.face_slots.slot_spacing`. Exactly: the slot bottom and sides are roots bisected on cubic splines
    of the recorded poses in time (:func:`recorded_bottom`, :func:`recorded_sides`)."""
    c = record.coupling
    radii = measuring_radii(c) if radii is None else np.asarray(radii, dtype=float)
    height = -0.5 * c.depth if height is None else height
    out = []
    for k in record.slots if slots is None else slots:
        bottom = recorded_bottom(record, radii, k)
        sides = recorded_sides(record, radii, height, k)
        centre = recorded_sides(record, np.array([c.L]), height, k)[:, 0]
        form, shape = bottom_form(radii, bottom)
        dev, bow = side_lines(radii, sides)
        out.append(SlotMeasure(k, radii, bottom, form, shape, height, sides, dev, bow, float(np.mean(centre))))
    return out
