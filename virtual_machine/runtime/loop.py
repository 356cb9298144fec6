"""The machine loop every simulated machine runs: the skiving machine, the lathe, the form-milling and face-contour
CNCs (dm_control's fixed step, a servo tick at a time).

Per servo tick::

    task.before_tick()            the controllers: the CNC's commands, the servos' torques (writes data.ctrl)
    load hook -> data.qfrc_applied    the cut's load on the tool and the workpiece, before the tick or each sub-step
    Integrator                    the physics sub-steps, with the divergence and runaway checks
    task.after_tick()             the recorder and the machine's own checks (e.g. the CNC's following-error alarm)

A machine is a :class:`MachineTask` (its controllers, program and record) and at most one :class:`LoadHook` (its
cut); the loop owns the order, the applied forces and the accounting of their work. Nothing else steps MuJoCo.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable
from typing import NamedTuple, Protocol

import mujoco
import numpy as np

from virtual_machine.runtime.integrator import Integrator

_apply = mujoco.mj_applyFT
_clock = time.perf_counter


class ToolLoad(NamedTuple):
    """A load the cut puts on the tool at ``point`` (world frame, m): ``force`` [N] and ``moment`` [N m], world frame;
    the workpiece takes the opposite at the same point (action and reaction through the chip). ``body``: the tool's
    body that carries it, where a tool has several (-1: the loop's tool body)."""

    force: np.ndarray
    moment: np.ndarray
    point: np.ndarray
    body: int = -1


class WorkpieceLoad(NamedTuple):
    """The same load stated on the workpiece (the tool takes the opposite): for a cut whose force law gives the
    force on the workpiece."""

    force: np.ndarray
    moment: np.ndarray
    point: np.ndarray


class AxisLoad(NamedTuple):
    """A generalised force on one degree of freedom (``dof``: its index in qvel): a torque [N m] or force [N] from
    outside the cut, e.g. a test's disturbance on a spindle."""

    dof: int
    value: float


class MachineTask(Protocol):
    """What a machine supplies to the loop besides its physics."""

    def before_tick(self) -> bool:
        """The controllers of this tick (the state is the tick's start); False when the program has ended."""
        ...

    def after_tick(self) -> None:
        """Record the tick and check the machine's state after it (raise to stop the run)."""
        ...


class LoadHook(Protocol):
    """The cut's load: given the machine's state now (the tick's start, or each sub-step's with ``every_substep``),
    the loads on the tool (the workpiece takes the opposite). ``t`` [s] is the time, ``dt`` [s] the span the loads
    act over (the tick or the sub-step)."""

    every_substep: bool

    def __call__(self, t: float, dt: float) -> Iterable[ToolLoad | WorkpieceLoad | AxisLoad]: ...


class AxisDisturbance:
    """A load hook of a torque [N m] or force [N] ``value(t)`` on one degree of freedom (``dof``): a test's
    disturbance of a spindle or a slide, held over each tick."""

    every_substep = False

    def __init__(self, dof: int, value: Callable[[float], float]):
        self.dof, self.value = dof, value

    def __call__(self, t: float, dt: float) -> tuple[AxisLoad]:
        return (AxisLoad(self.dof, float(self.value(t))),)


class MachineLoop:
    """The fixed loop of one machine: ``integrator`` (its model, data and sub-steps per tick), the ``task`` and the
    ``load`` hook; ``tool_body`` and ``work_body`` (body ids) carry a :class:`ToolLoad` and its reaction.

    ``load_work`` and ``actuator_work`` [J] sum the work the loads and the actuators do on the machine (with a load
    hook); ``timing`` the seconds spent in the controllers, the physics with the loads, and the records."""

    def __init__(
        self,
        integrator: Integrator,
        task: MachineTask,
        load: LoadHook | None = None,
        tool_body: int = -1,
        work_body: int = -1,
    ):
        if load is not None and (tool_body < 0 or work_body < 0):
            raise ValueError("a load hook needs the tool's and the workpiece's bodies")
        self.integrator, self.task, self.load = integrator, task, load
        self.model, self.data = integrator.model, integrator.data
        self.tool_body, self.work_body = tool_body, work_body
        self._single = integrator.single()  # the sub-steps one by one, for a load of every sub-step
        self._reaction = (np.zeros(3), np.zeros(3))  # a load's opposite, without allocating per load
        self.finished = False
        self.load_work = self.actuator_work = 0.0
        self.timing = {"control": 0.0, "physics": 0.0, "record": 0.0}

    @property
    def dt(self) -> float:
        """The servo tick [s]."""
        return self.model.opt.timestep * self.integrator.nstep

    def run(self, until: float = math.inf) -> bool:
        """Run servo ticks while the machine time is below ``until`` [s]; False once the program has ended."""
        data, task, load, step = self.data, self.task, self.load, self.integrator.step
        before, after = task.before_tick, task.after_tick
        t_ctrl = t_phys = t_rec = 0.0
        try:
            while data.time < until:
                c0 = _clock()
                if not before():
                    self.finished = True
                    break
                c1 = _clock()
                if load is None:
                    step()
                elif load.every_substep:
                    self._substeps()
                else:
                    self._loaded_tick()
                c2 = _clock()
                after()
                t_ctrl += c1 - c0
                t_phys += c2 - c1
                t_rec += _clock() - c2
        finally:
            self.timing["control"] += t_ctrl
            self.timing["physics"] += t_phys
            self.timing["record"] += t_rec
        return not self.finished

    def apply_loads(self, t: float, dt: float) -> None:
        """The hook's loads at ``t`` over ``dt`` into ``qfrc_applied`` (cleared first): each on its body and its
        reaction on the other."""
        model, data = self.model, self.data
        qfrc = data.qfrc_applied
        qfrc[:] = 0.0
        f, m = self._reaction
        for ld in self.load(t, dt):
            kind = type(ld)
            if kind is AxisLoad:
                qfrc[ld.dof] += ld.value
                continue
            np.negative(ld.force, out=f)
            np.negative(ld.moment, out=m)
            if kind is WorkpieceLoad:
                _apply(model, data, ld.force, ld.moment, ld.point, self.work_body, qfrc)
                _apply(model, data, f, m, ld.point, self.tool_body, qfrc)
            else:
                _apply(model, data, ld.force, ld.moment, ld.point, self.tool_body if ld.body < 0 else ld.body, qfrc)
                _apply(model, data, f, m, ld.point, self.work_body, qfrc)

    def _loaded_tick(self) -> None:
        """The loads of the tick's start held over its sub-steps, and their work."""
        data = self.data
        dt = self.dt
        self.apply_loads(data.time, dt)
        self.integrator.step()
        self.load_work += float(data.qfrc_applied @ data.qvel) * dt
        self.actuator_work += float(data.actuator_force @ data.actuator_velocity) * dt

    def _substeps(self) -> None:
        """Each sub-step with the loads of its own start (the lathe: the chip follows the spindle's angle)."""
        data, substep = self.data, self._single.step
        h = self.model.opt.timestep
        for _ in range(self.integrator.nstep):
            self.apply_loads(data.time, h)
            substep()
            self.load_work += float(data.qfrc_applied @ data.qvel) * h
            self.actuator_work += float(data.actuator_force @ data.actuator_velocity) * h
        data.qfrc_applied[:] = 0.0
