"""The skiving machine's physics on the machine loop: a compiled machine model, its state and the signals the
controllers read (axis angles and speeds) and write (motor torques), and the diagnosis of a divergence (the stage to
soften), and its load hook (:class:`BlankFrameLoad`: the cut's loads in the blank frame)."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable

import mujoco
import numpy as np

from machine_models.parameters import SkivingMachineParams
from virtual_machine.runtime.loop import WorkpieceLoad

AXES = ("B1", "B2", "P3", "X", "TV")  # the machine's axes, in every structure


class MachinePhysics:
    """MuJoCo model + data with the joints and actuators of the machine resolved once (no name lookups per tick)."""

    def __init__(self, model: mujoco.MjModel, params: SkivingMachineParams):
        self.model, self.params = model, params
        self.data = mujoco.MjData(model)
        mujoco.mj_resetDataKeyframe(model, self.data, model.key("home").id)
        joints = [model.joint(j).name for j in range(model.njnt)]
        self.qadr = {a: int(model.joint(a).qposadr[0]) for a in joints}
        self.vadr = {a: int(model.joint(a).dofadr[0]) for a in joints}
        self.act = {model.actuator(a).name: a for a in range(model.nu)}
        self._spring = {  # engaged stiffness and damping of every compliant tendon (clutches release them)
            t: (
                float(model.tendon_stiffness[t]),
                float(model.tendon_damping[t]),
                float(np.diff(model.tendon_lengthspring[t])[0]),
            )
            for t in range(model.ntendon)
        }
        self.site_blank = int(model.site("blank_frame").id)
        self.site_cutter = int(model.site("cutter_frame").id)
        self.data.ctrl[self.act["X"]] = self.data.qpos[self.qadr["X"]]
        mujoco.mj_forward(model, self.data)
        self.blank_body = int(model.site_bodyid[self.site_blank])
        self.cutter_body = int(model.site_bodyid[self.site_cutter])

    @property
    def time(self) -> float:
        return float(self.data.time)

    def q(self, axis: str) -> float:
        return float(self.data.qpos[self.qadr[axis]])

    def v(self, axis: str) -> float:
        return float(self.data.qvel[self.vadr[axis]])

    def engage(self, tendon: str, on: bool) -> None:
        """A clutch: engage (re-centred on the chain's present relative position: the clutch takes hold where it
        is) or release the chain ``tendon`` (no force). A rigid chain's equality is switched the same way."""
        m, d = self.model, self.data
        t = m.tendon(tendon).id
        mujoco.mj_fwdPosition(m, d)  # the tendon length of the current state
        length = float(d.ten_length[t])
        eq = [i for i in range(m.neq) if m.eq_type[i] == mujoco.mjtEq.mjEQ_TENDON and m.eq_obj1id[i] == t]
        if eq:
            d.eq_active[eq[0]] = on
            m.eq_data[eq[0], 0] = length - m.tendon_length0[t]
            return
        k, c, gap = self._spring[t]
        m.tendon_stiffness[t], m.tendon_damping[t] = (k, c) if on else (0.0, 0.0)
        m.tendon_lengthspring[t] = [length - gap / 2, length + gap / 2]

    def cutter_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """The cutter frame in the blank frame: rotation (3, 3) and translation [mm] (current state)."""
        mujoco.mj_kinematics(self.model, self.data)
        rb = self.data.site_xmat[self.site_blank].reshape(3, 3)
        rc = self.data.site_xmat[self.site_cutter].reshape(3, 3)
        pb, pc = self.data.site_xpos[self.site_blank], self.data.site_xpos[self.site_cutter]
        return rb.T @ rc, rb.T @ (pc - pb) * 1e3

    def diagnose(self, t: float | None = None) -> str:
        """Which stage's natural frequency is too high for the time step (explicit springs need w h < ~1); ``t``:
        when it diverged (default: now; after a blow-up MuJoCo has reset the state, so the caller passes the tick's
        start)."""
        p, h = self.params, self.model.opt.timestep
        stages = {
            "work_drive": (p.work_drive, p.work_inertia, p.work_motor_inertia),
            "tool_drive": (p.tool_drive, p.tool_inertia, p.tool_motor_inertia),
            "feed_drive": (p.feed_drive, p.screw_inertia, p.feed_motor_inertia),
        }
        worst, worst_wh = "timestep", 0.0
        for name, (stage, j_out, j_motor) in stages.items():
            if stage.stiffness is None:
                continue
            j = 1 / (1 / j_out + stage.ratio**2 / j_motor)
            wh = math.sqrt(stage.stiffness / j) * h
            if wh > worst_wh:
                worst, worst_wh = name, wh
        t = self.time if t is None else t
        return (
            f"the simulation diverged at t = {t:.4f} s (MuJoCo reported bad accelerations). "
            f"Stiffest stage: {worst} with omega*h = {worst_wh:.2f}; lower machine.{worst}.stiffness, raise its "
            f"damping, or reduce machine.timestep (now {h:g} s)"
        )


class BlankFrameLoad:
    """The skiving machine's load hook: the cut's loads in the blank frame, ``cut(t, dt)``: (force [N] on the
    workpiece, point [mm], moment [N m]) per engaged tooth, each the mean over the tick, as loads on the workpiece in
    the world frame (the cutter takes the opposite: action and reaction through the chip). The frames are those of
    the last step (the servo tick holds the load over its sub-steps). ``rows`` keeps per tick the time [s], the
    loads' resultant on the workpiece (blank frame) [N] and its torque about the work axis [N m]."""

    every_substep = False

    def __init__(self, phys: MachinePhysics, cut: Callable[[float, float], Iterable[tuple]]):
        self.cut = cut
        self._xmat = phys.data.site_xmat[phys.site_blank]
        self._xpos = phys.data.site_xpos[phys.site_blank]
        self.rows: list[tuple[float, float, float, float, float]] = []

    def __call__(self, t: float, dt: float) -> list[WorkpieceLoad]:
        rb = self._xmat.reshape(3, 3)
        out = []
        fx = fy = fz = tz = 0.0
        for force, point, moment in self.cut(t, dt):
            p_world = self._xpos + rb @ point * 1e-3
            out.append(WorkpieceLoad(rb @ force, rb @ moment, p_world))
            fx, fy, fz = fx + force[0], fy + force[1], fz + force[2]
            tz += (point[0] * force[1] - point[1] * force[0]) * 1e-3 + moment[2]
        self.rows.append((t, fx, fy, fz, tz))
        return out
