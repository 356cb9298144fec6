"""The CNC servo of the form-milling (seed 003) and face-contour (seed 004) machines: a cascade per axis on the
motor encoder (semi-closed loop).

Per axis: position loop (Kv) with speed feed-forward -> PI speed loop -> motor torque, plus inertia feed-forward,
limited to the motor's peak torque with anti-windup (the integral stops while the torque is saturated outward).
The speed loop's gains follow the inertia the motor sees with its chain rigid (g^T M g over the chain's joints) and
its bandwidth: kp = J w, ki = kp w / 4. The integral starts at the static torque the axis holds (a weight less its
counterbalance: the drive holds it before its brake opens). The stages' compliance, backlash and friction show
between the motor and the tool, not in this loop: what a real semi-closed-loop CNC leaves to the machine.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np


@dataclass(frozen=True)
class ServoAxis:
    """One driven axis: its ``motor`` (joint and actuator name), ``ratio`` (axis motion per motor radian, the CNC's
    nominal ratio: rad/rad or m/rad), ``chain`` (the joints the motor moves and their motion per motor radian: the
    inertia it sees), ``bandwidth`` [Hz] of its speed loop and ``position_gain`` Kv [1/s] (0: a speed loop only)."""

    motor: str
    ratio: float
    chain: tuple[tuple[str, float], ...]
    bandwidth: float
    position_gain: float


class CascadeServo:
    """The drives of ``axes``. Commands come as vectors of ``size`` entries, of which ``index`` (default all) are
    these axes' (a machine whose optional axis is absent keeps its command layout); ``axis0``: the axes' positions
    when the encoders read zero. ``torque`` and ``error`` per command entry (zero where no axis is driven)."""

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        axes: Sequence[ServoAxis],
        axis0: np.ndarray,
        index: Sequence[int] | None = None,
        size: int | None = None,
    ):
        self.model, self.data = model, data
        self.idx = np.arange(len(axes)) if index is None else np.asarray(index)
        self.g = np.array([a.ratio for a in axes])
        self.qm = np.array([int(model.joint(a.motor).qposadr[0]) for a in axes])
        self.vm = np.array([int(model.joint(a.motor).dofadr[0]) for a in axes])
        self.act = np.array([int(model.actuator(a.motor).id) for a in axes])
        self.peak = model.actuator_ctrlrange[self.act, 1].copy()
        mujoco.mj_forward(model, data)
        self.qm0 = data.qpos[self.qm].copy()  # encoder zero
        self.axis0 = np.asarray(axis0, dtype=float).copy()
        load = data.qfrc_bias - data.qfrc_gravcomp
        self.inertia, hold = np.zeros(len(axes)), np.zeros(len(axes))
        for k, axis in enumerate(axes):
            vec = np.zeros(model.nv)
            for joint, ratio in axis.chain:
                vec[model.joint(joint).dofadr[0]] = ratio
            res = np.zeros(model.nv)
            mujoco.mj_mulM(model, data, res, vec)
            self.inertia[k] = vec @ res
            hold[k] = vec @ load
        w = 2 * math.pi * np.array([a.bandwidth for a in axes], dtype=float)
        self.kp = self.inertia * w
        self.ki = self.kp * w / 4
        self.kv = np.array([a.position_gain for a in axes], dtype=float)
        self.integral = np.clip(hold, -self.peak, self.peak)
        n = size or len(axes)
        self.torque = np.zeros(n)
        self.error = np.zeros(n)

    def measured(self) -> np.ndarray:
        """The axes' positions from the motor encoders."""
        return self.axis0 + self.g * (self.data.qpos[self.qm] - self.qm0)

    def update(self, dt: float, pos: np.ndarray, vel: np.ndarray, acc: np.ndarray) -> np.ndarray:
        """One servo tick: commanded positions, speeds and accelerations -> the motors' torques, written to ``ctrl``
        (held over the physics sub-steps) and returned."""
        d, g, i = self.data, self.g, self.idx
        e = pos[i] - (self.axis0 + g * (d.qpos[self.qm] - self.qm0))
        ew = (vel[i] + self.kv * e) / g - d.qvel[self.vm]
        integral = self.integral + self.ki * ew * dt
        u = self.inertia * acc[i] / g + self.kp * ew + integral
        sat = np.abs(u) > self.peak
        if sat.any():
            u = np.clip(u, -self.peak, self.peak)
            integral = np.where(sat & (np.sign(u) == np.sign(ew)), self.integral, integral)
        self.integral = integral
        self.torque[i] = u
        self.error[i] = e
        d.ctrl[self.act] = u
        return u
