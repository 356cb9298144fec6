"""Planing with overlapping cuts on a one-mode loop: regenerative chatter's known answer, run in MuJoCo.

A tool on one mode (mass, spring, damper normal to the cut surface: machine_models/loop.py's slide joint) planes a
closed track, each pass over the surface the previous pass left T seconds earlier (a face turned, or a slab planed
again and again). The chip at an instant is the nominal h0 less the tool's retreat since the previous pass:
h = h0 - (y(t) - y(t - T)), y along the surface's normal towards the tool; the thrust K b h pushes the tool away
(none once it leaves the cut, h <= 0). MuJoCo integrates the mode from that force (the machine loop's way); the
surface is the record of y one delay ago, sample by sample. Unstable above Tlusty's b_lim = -1 / (2 K Re[G]_min),
decaying below: tests/test_regeneration.py against :mod:`cutting.regeneration`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from machine_models.loop import LoopMode, add_modes


@dataclass(frozen=True)
class PlaningRun:
    """The tool's displacement ``y`` [m] at times ``t`` [s] and the chip ``h`` [m]; growth per pass of the vibration."""

    t: np.ndarray
    y: np.ndarray
    h: np.ndarray
    delay: float

    def growth(self) -> float:
        """The vibration's amplitude (about its mean) over the last 5 passes against the 5 after the first 5: > 1
        growing (chatter), < 1 decaying."""
        n = round(self.delay / (self.t[1] - self.t[0]))
        passes = len(self.y) // n
        y = self.y[: passes * n].reshape(passes, n)
        amp = np.ptp(y - y.mean(), axis=1)
        return float(amp[-5:].mean() / max(amp[5:10].mean(), 1e-300))

    def frequency(self) -> float:
        """The dominant vibration frequency over the last half of the run [Hz]."""
        half = self.y[len(self.y) // 2 :]
        spec = np.abs(np.fft.rfft(half - half.mean()))
        f = np.fft.rfftfreq(len(half), self.t[1] - self.t[0])
        return float(f[1:][np.argmax(spec[1:])])


def planer(mode: LoopMode, timestep: float) -> mujoco.MjModel:
    """The one-mode planer: the tool body on the mode's slide (its direction is the surface's normal)."""
    spec = mujoco.MjSpec()
    spec.option.timestep = timestep
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.gravity = [0.0, 0.0, 0.0]
    body = add_modes(spec.worldbody, (mode,), mode.at, np.eye(3), np.array([0.0, 0.0, 1.0]), 0.0)
    body.add_body(name="tool").add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.01], mass=0.0, contype=0)
    return spec.compile()


def plane(
    mode: LoopMode,
    coefficient: float,
    width: float,
    chip: float,
    delay: float,
    passes: int = 60,
    per_pass: int = 240,
    kick: float = 1e-7,
) -> PlaningRun:
    """Plane ``passes`` passes of ``delay`` [s] each with a chip ``chip`` [m] thick and ``width`` [m] wide, the thrust
    ``coefficient`` K [N/m^2] x b x h on the tool along the mode; ``per_pass`` MuJoCo steps per pass (the delay is a
    whole number of steps). The tool starts at its static deflection under the nominal chip, ``kick`` [m] off it."""
    dt = delay / per_pass
    model = planer(mode, dt)
    data = mujoco.MjData(model)
    static = coefficient * width * chip / mode.stiffness
    data.qpos[0] = static + kick
    n = passes * per_pass
    y = np.empty(n)
    h = np.empty(n)
    surface = np.full(per_pass, static)  # y one pass ago: the first pass meets a surface cut at rest
    for i in range(n):
        j = i % per_pass
        now = float(data.qpos[0])
        cut = chip - (now - surface[j])
        force = coefficient * width * max(cut, 0.0)
        # the surface this pass leaves: where the tool is; out of the cut the old surface stays
        surface[j] = now if cut > 0 else surface[j] - chip
        data.qfrc_applied[0] = force
        mujoco.mj_step(model, data)
        y[i], h[i] = now, cut
    return PlaningRun(np.arange(n) * dt, y, h, delay)


def limiting_width(
    mode: LoopMode, coefficient: float, chip: float, delay: float, low: float, high: float, tol: float = 0.01
) -> float:
    """The chip width [m] at which planing at ``delay`` turns from decaying to growing (bisection between ``low``
    (stable) and ``high`` (unstable) to ``tol`` relative)."""
    for _ in range(40):
        if high - low <= tol * low:
            break
        mid = math.sqrt(low * high)
        if plane(mode, coefficient, mid, chip, delay).growth() > 1.0:
            high = mid
        else:
            low = mid
    return math.sqrt(low * high)
