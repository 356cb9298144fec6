"""The machine's thermal drift over a job: lumped first-order heat bodies whose growth moves the tool against the
blank as the job goes on (issue 43; the model and its figures: docs/machine_geometry.md, "Thermal drift").

Each lump (the tool head, the work spindle, the structure) is one body with one time constant tau: its state theta
(its growth as a share of the growth it would reach at a unit heat input) follows

    tau d theta / dt = u(t) - theta,

u(t) the lump's heat input as a share of its reference input (the spindle's speed ratio to a power, the cutting
power's share), held constant between the job's events; so theta is exact, a sum of exponentials, at any time.
Its growth is theta times the lump's growth vector at the reference input, in the machine's axes: x (the centre
distance: positive, the axes farther apart), y (along the axes' common perpendicular's normal, as the cutter's
offset), z (along the work axis: the cutter against the blank) and a tilt about x (the shaft angle). ISO 230-3 tests
what the lumps stand for: the drift at the spindle nose in x, y, z and the tilts while a spindle turns or an axis
moves, from a cold start.

The drift acts through the one forward kinematics of :mod:`cutting.skiving.machine_geometry`: the simulated machine
(`skive run`) adds it at every recorded instant (:meth:`ThermalDrift.offsets`); the ideal kinematics (`skive cut`)
take each pass's drift as the pass's own geometry, the drift at the pass's middle and its rate over the stroke
(:meth:`ThermalDrift.pass_geometry`): exact to the exponential's bow over the stroke, T / (8 tau) of the drift's
change over it, T the stroke's time (a stroke of a minute against a tool head's 20 min: 0.6 % of a change that is
itself T / tau of the drift's distance from its steady state; :meth:`ThermalDrift.linearisation_um` says how far).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from cutting.skiving.machine_geometry import MachineGeometry


@dataclass(frozen=True)
class Lump:
    """One heat body: ``name``, its time constant ``tau`` [s] and its growth at the reference heat input (theta = 1):
    ``growth`` = (x, y, z [mm], tilt about x [rad])."""

    name: str
    tau: float
    growth: tuple[float, float, float, float]


@dataclass(frozen=True)
class ThermalDrift:
    """The drift of a job: its ``lumps``, each lump's state at the job's start (``start``, theta at t = 0), the heat
    inputs as steps (``steps``: (time [s], each lump's u from then on), the first at t = 0), and the machine time at
    which each pass's feed stroke starts (``pass_starts`` [s], the run's program clock: run-up, settle, then per pass
    infeed, stroke, retract and return)."""

    lumps: tuple[Lump, ...]
    start: tuple[float, ...]
    steps: tuple[tuple[float, tuple[float, ...]], ...]
    pass_starts: tuple[float, ...]

    def states(self, t: np.ndarray | float) -> np.ndarray:
        """Each lump's theta at machine times ``t`` [s], (n, lumps): the exact solution between the input's steps."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        taus = np.array([lump.tau for lump in self.lumps])
        theta = np.tile(np.asarray(self.start, dtype=float), (len(t), 1))
        edges = [s[0] for s in self.steps[1:]] + [math.inf]
        done = np.zeros(len(t))  # how far each time has been carried
        for (t0, u), t1 in zip(self.steps, edges, strict=True):
            u = np.asarray(u, dtype=float)
            end = np.clip(t, t0, t1)  # a time before this step stays; one after it is carried to the step's end
            span = np.maximum(end - np.maximum(done, t0), 0.0)[:, None]
            theta = u + (theta - u) * np.exp(-span / taus)
            done = np.maximum(done, end)
        return theta

    def offsets(self, t: np.ndarray | float) -> np.ndarray:
        """The drift at machine times ``t`` [s], (n, 4): x, y, z [mm] and the tilt about x [rad]."""
        growth = np.array([lump.growth for lump in self.lumps])  # (lumps, 4)
        return self.states(t) @ growth

    def pass_geometry(
        self, geometry: MachineGeometry, index: int, s_start: float, v_s: float, duration: float
    ) -> MachineGeometry:
        """``geometry`` with pass ``index``'s drift added (the ideal kinematics of `skive cut`): the drift at the
        stroke's middle, and its rate over the stroke (the secant: its end minus its start over the stroke's
        ``duration`` [s]) per mm of the carriage (``s_start`` [mm], ``v_s`` [mm/s])."""
        t0 = self.pass_starts[index]
        first, mid, last = self.offsets(np.array([t0, t0 + duration / 2, t0 + duration]))
        rate = (last - first) / (duration * v_s)  # per mm of carriage
        s_mid = s_start + v_s * duration / 2
        at_zero = mid - rate * s_mid  # the line's value at s = 0, where the geometry's linear terms are zero
        return replace(
            geometry,
            centre_distance_offset=geometry.centre_distance_offset + at_zero[0],
            carriage_squareness_x=geometry.carriage_squareness_x + rate[0],
            cutter_offset_error=geometry.cutter_offset_error + at_zero[1],
            carriage_squareness_y=geometry.carriage_squareness_y + rate[1],
            axial_offset=geometry.axial_offset + at_zero[2],
            axial_rate=geometry.axial_rate + rate[2],
            shaft_angle_error=geometry.shaft_angle_error + mid[3],
        )

    def linearisation_um(self, index: int, duration: float) -> float:
        """How far pass ``index``'s straight line (:meth:`pass_geometry`) leaves the drift's x, y, z over the stroke
        [um] (the largest of 65 instants)."""
        t0 = self.pass_starts[index]
        t = t0 + np.linspace(0.0, duration, 65)
        d = self.offsets(t)[:, :3]
        line = d[32] + (d[-1] - d[0]) * ((t - t[32]) / duration)[:, None]
        return float(np.abs(d - line).max() * 1e3)
