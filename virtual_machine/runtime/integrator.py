"""The physics side of the machine loop (:mod:`virtual_machine.runtime.loop`): MuJoCo stepped over a servo tick with
the divergence and runaway checks every machine needs; what differs per machine is only what it watches and what its
messages say (the stage to soften, the servo gain to lower). The only place that steps MuJoCo.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Sequence

import mujoco
import numpy as np

from cutting.errors import SimulationDivergedError

#: the warnings MuJoCo raises when the integration blows up (it then resets the state and carries on)
BAD_ACCELERATION = (mujoco.mjtWarning.mjWARN_BADQACC,)
BAD_ACCELERATION_OR_SPEED = (mujoco.mjtWarning.mjWARN_BADQACC, mujoco.mjtWarning.mjWARN_BADQVEL)

_mj_step, _isfinite = mujoco.mj_step, math.isfinite  # bound once: a step is the skiving machine's hot path


def servo_substeps(timestep: float, servo_rate: float) -> int:
    """Physics steps per servo tick; ValueError unless the servo period is a whole multiple of the time step."""
    substeps = round(1 / (servo_rate * timestep))
    if substeps < 1 or abs(substeps * timestep * servo_rate - 1) > 1e-9:
        raise ValueError(
            f"the servo period 1/{servo_rate:g} s must be a whole multiple of machine.timestep ({timestep:g} s)"
        )
    return substeps


def divergence_message(machine: str, omega_h: dict[str, float], timestep: float, t: float) -> str:
    """Why ``machine`` diverged at ``t``: the compliant stage whose local mode is fastest for the time step
    (``omega_h``: omega * h per stage, as the machines' ``stage_omega_h`` give it) and what to change."""
    head = f"the {machine} diverged at t = {t:.4f} s (MuJoCo reported bad accelerations). "
    if not omega_h:
        return head + f"Every stage is rigid: reduce machine.timestep (now {timestep:g} s)"
    worst = max(omega_h, key=omega_h.__getitem__)
    what = f"machine.{worst}" if worst == "nut_stiffness" else f"machine.{worst}.stiffness"
    return head + (
        f"Stiffest stage: {worst} with omega*h = {omega_h[worst]:.2f} (explicit springs need < 2, better < 0.5); "
        f"lower {what}, raise its damping, or reduce machine.timestep (now {timestep:g} s)"
    )


class Integrator:
    """One servo tick of physics: ``nstep`` MuJoCo steps of ``model`` / ``data``, then the checks.

    Diverged (raises :class:`SimulationDivergedError` with ``diagnose(t)``, t the tick's start time [s]: MuJoCo
    resets the state when it reports bad accelerations): one of ``warnings`` (``mujoco.mjtWarning``) counted, or
    ``qpos[watch]`` not finite. Ran away (``runaway(t)``, t the time after the tick): some ``|error| > limits``,
    ``error`` a live array the servo writes its following errors into (a view of the entries to watch).

    Everything the checks read is bound here once (``data.warning[...]`` and ``data.qpos`` are live views), so a
    tick costs no allocations or look-ups beyond MuJoCo's own (the skiving machine runs tens of thousands of ticks).
    """

    __slots__ = ("_diagnose", "_error", "_limits", "_qpos", "_runaway", "_warnings", "_watch", "data", "model", "nstep")

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        nstep: int,
        watch: int,
        diagnose: Callable[[float], str],
        warnings: Sequence[mujoco.mjtWarning] = BAD_ACCELERATION,
        error: np.ndarray | None = None,
        limits: Sequence[float] | None = None,
        runaway: Callable[[float], str] | None = None,
    ):
        if (error is None) != (limits is None) or (error is None) != (runaway is None):
            raise ValueError("error, limits and runaway go together: give all three or none")
        self.model, self.data, self.nstep = model, data, int(nstep)
        self._warnings = tuple(data.warning[w] for w in warnings)
        self._qpos, self._watch = data.qpos, int(watch)
        self._diagnose = diagnose
        self._error = error
        self._limits = None if limits is None else np.asarray(limits, dtype=float)
        self._runaway = runaway

    def single(self) -> Integrator:
        """This integrator stepping one physics step at a time (a load that changes within the tick)."""
        one = copy.copy(self)
        one.nstep = 1
        return one

    def step(self) -> None:
        """Run one servo tick's physics sub-steps and check the result."""
        data = self.data
        t = data.time
        _mj_step(self.model, data, self.nstep)  # nstep positional: cheaper than a keyword through the binding
        for warning in self._warnings:
            if warning.number:
                raise SimulationDivergedError(self._diagnose(t))
        if not _isfinite(self._qpos[self._watch]):
            raise SimulationDivergedError(self._diagnose(t))
        if self._error is not None and np.any(np.abs(self._error) > self._limits):
            raise SimulationDivergedError(self._runaway(data.time))
