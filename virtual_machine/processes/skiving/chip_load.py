"""The skiving machine's load hook: each servo tick, the chips the teeth in the cut are taking at that moment
(:mod:`cutting.skiving.chip_of_the_moment`), from the machine's own state at the tick.

Per feed tick the hook reads the axes, their speeds and the loop's deflection (the state the tick starts from), the
ideal kinematics' axes at the same cutter angle (the reference), and keeps the deviation between the two for the
stroke; the deviation one work revolution earlier is the surface the teeth left there. The engaged teeth are those
whose engagement window (the pass's half angle either side of the mesh) holds the cutter angle at the tick's middle;
their loads act over the tick.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from cutting.forces import EdgeFaces, EngagementLoad
from cutting.oblique import H_FLOOR, ObliqueForces
from cutting.skiving.chip_of_the_moment import COLUMNS, POWER, VOLUME_RATE, WIDTH, deviation, tick_load
from cutting.skiving.trajectory import PassMotion
from machine_models.skiving_machine import MM
from virtual_machine.runtime.physics import AXES

FEED = "feed"


@dataclass
class _Stroke:
    """One feed stroke's history: the work angle (signed to grow) and the deviation (6) per tick."""

    index: int
    b1: float  # the cutter angle at the stroke's first tick [rad]
    p3: float  # the carriage there [mm]
    angle: np.ndarray = field(default_factory=lambda: np.empty(4096))
    deviation: np.ndarray = field(default_factory=lambda: np.empty((4096, 6)))
    n: int = 0

    def append(self, angle: float, dev: np.ndarray) -> None:
        if self.n == len(self.angle):
            self.angle = np.concatenate([self.angle, np.empty_like(self.angle)])
            self.deviation = np.concatenate([self.deviation, np.empty_like(self.deviation)])
        self.angle[self.n] = angle
        self.deviation[self.n] = dev
        self.n += 1

    def back(self, angle: float) -> np.ndarray:
        """The deviation when the work angle was ``angle`` (linear between ticks); before the stroke's start its
        first: the surface the previous pass left counts as ideal."""
        a = self.angle[: self.n]
        if angle <= a[0]:
            return self.deviation[0]
        i = min(int(np.searchsorted(a, angle)), self.n - 1)
        f = (angle - a[i - 1]) / (a[i] - a[i - 1]) if a[i] > a[i - 1] else 1.0
        return self.deviation[i - 1] + f * (self.deviation[i] - self.deviation[i - 1])


class ChipLoad:
    """The load hook ``cut(t, dt)``: the engaged teeth's loads in the blank frame (force [N] on the workpiece, point
    [mm], moment [N m]) held over the tick [t, t + dt], taken at its start. :meth:`bind` gives it the machine it reads.

    ``plans`` the passes' ideal motions, ``edge`` the edge's points in the rake frame and ``faces`` its faces,
    ``model`` the oblique model, ``halves`` each pass's engagement half angle [rad]."""

    def __init__(
        self, setup, plans: list[PassMotion], edge: np.ndarray, faces: EdgeFaces, model: ObliqueForces, halves: list
    ):
        g = setup.gear
        self.setup, self.plans, self.model = setup, plans, model
        self.edge = np.ascontiguousarray(edge, dtype=float)
        self.rake, self.body = np.ascontiguousarray(faces.rake), np.ascontiguousarray(faces.body)
        self.halves = list(halves)
        self.pitch = 2 * math.pi / setup.cutter.teeth
        self.blank = np.ascontiguousarray(setup.blank_frame, dtype=float)
        self.geometry = np.array([setup.tilt, setup.cutter_phase, setup.work_phase])
        self.envelope = np.array([g.tip_radius, 1.0 if g.internal else 0.0, g.face_width / 2])
        ratio = abs(setup.speed_ratio)  # work turns per cutter turn
        self.sign = 1.0 if setup.speed_ratio >= 0 else -1.0  # the cutter angle grows along a stroke; the work's so
        #: the cutter's turn over one work revolution [rad] and the passages it spans (z2 for an integer ratio)
        self.revolution = 2 * math.pi / ratio
        self.back = round(self.revolution / self.pitch)
        ce, te = model.edge_coefficients
        c, mat = model.model, model.material
        self.chip = np.array(
            [mat.kc11, mat.mc, max(model.min_chip, H_FLOOR), model._reference, model.min_chip, ce, te,
             c.friction_angle, c.rake_floor]
        )  # fmt: skip
        self._stroke: _Stroke | None = None
        self.rows: list[np.ndarray] = []  # per tooth and tick with a chip: t, pass, passage, then tick_load's columns
        self.machine = None

    def bind(self, machine) -> None:
        """The machine run whose state the hook reads (virtual_machine.runtime.machine_run.MachineRun)."""
        self.machine = machine
        phys = machine.phys
        self._qa = [phys.qadr[a] for a in AXES[:4]]
        self._va = [phys.vadr[a] for a in AXES[:4]]
        self._qpos, self._qvel = phys.data.qpos, phys.data.qvel
        self._model, self._data = phys.model, phys.data
        st = self.setup
        self._ratio_b, self._diff = st.speed_ratio, st.differential_rotation_per_mm

    def ideal(self, b1: float, stroke: _Stroke, centre_distance: float, plan: PassMotion) -> np.ndarray:
        """The ideal kinematics' axes at cutter angle ``b1`` [rad]: the carriage on the pass's feed per cutter
        radian from where the stroke started, the work where cutter and carriage put it, ``centre_distance`` [mm]."""
        b1_0, b2_0, p3_0 = self.machine.home
        z = stroke.p3 + plan.v_s / plan.omega0 * (b1 - stroke.b1)
        return np.array([b1, b2_0 + self._ratio_b * (b1 - b1_0) + self._diff * (z - p3_0), z, centre_distance])

    def __call__(self, t: float, dt: float) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        tick = self.machine._tick
        if tick.segment != FEED:
            self._stroke = None
            return []
        k = tick.pass_index
        plan = self.plans[k]
        if not self.machine.deflections:
            # the frames MuJoCo applies the load in are those of the last sub-step's start, half a tick old; the
            # machine with loop modes has just brought them up to date (its deflection), this one does so here: a
            # stale frame would put the tool's point of application ahead of the edge (+4.5 % of work)
            mujoco.mj_kinematics(self._model, self._data)
        q = self._qpos.take(self._qa)
        v = self._qvel.take(self._va)
        axes = np.array([q[0], q[1], q[2] / MM, q[3] / MM])
        rates = np.array([v[0], v[1], v[2] / MM, v[3] / MM])
        defl = self.machine.deflections
        loop = np.asarray(defl[-1]) if defl else np.zeros(6)
        stroke = self._stroke
        if stroke is None or stroke.index != k:
            stroke = self._stroke = _Stroke(k, float(axes[0]), float(axes[2]))
        # the machine's deviation from the ideal kinematics now, kept for the teeth one work revolution later
        dev = deviation(axes, loop, self.ideal(axes[0], stroke, plan.centre_distance, plan), self.geometry)
        angle = self.sign * axes[1]
        stroke.append(angle, dev)
        # the teeth in the cut at the tick's start: MuJoCo applies the load in the frames of that instant (taken at
        # the tick's middle, the tool's point of application would run ahead of the edge by half a tick of the
        # relative motion, and the load would do 9 % more work than the chip takes)
        mid = axes
        half = self.halves[k]
        lo, hi = math.ceil((mid[0] - half) / self.pitch), math.floor((mid[0] + half) / self.pitch)
        if hi < lo or half <= 0:
            return []
        passages = np.arange(lo, hi + 1)
        teeth = np.ascontiguousarray(self.setup.passage_frames(passages))
        previous = np.ascontiguousarray(self.setup.passage_frames(passages - self.back))
        visited = angle - 2 * math.pi >= stroke.angle[0]
        before = self.ideal(mid[0] - self.revolution, stroke, plan.centre_distance, plan)
        dev_before = stroke.back(angle - 2 * math.pi) if visited else np.zeros(6)
        passed = k > 0
        last = self.ideal(mid[0], stroke, self.plans[k - 1].centre_distance, plan) if passed else np.zeros(4)
        out = np.empty((len(passages), COLUMNS))
        if not tick_load(
            mid, rates, loop, self.geometry, teeth, self.blank, self.edge, self.rake, self.body, self.envelope,
            previous, before, dev_before, visited, last, passed, self.chip, out,
        ):  # fmt: skip
            return []
        loads = []
        for i, m in enumerate(passages):
            if out[i, WIDTH] > 0:
                row = out[i]
                self.rows.append(np.concatenate([[t, k, m], row]))
                loads.append((row[0:3], row[3:6], row[6:9]))
        return loads

    def engagements(self, dt: float, chips: dict[tuple[int, int], tuple[float, float]]) -> list:
        """The loads that acted, one :class:`EngagementLoad` per (pass, passage) in time order, each with its
        removal chip's volume and thickness (``chips``: (pass, passage) -> (volume [mm^3], thickness [mm])); ``dt``
        the servo tick [s]. Its kc is the cutting work over the removal's volume."""
        from virtual_machine.processes.skiving.cosim import AppliedLoad

        if not self.rows:
            return []
        a = np.array(self.rows)
        order = np.lexsort((a[:, 0], a[:, 2], a[:, 1]))
        a = a[order]
        keys = a[:, 1:3].astype(np.int64)
        cuts = np.flatnonzero(np.any(np.diff(keys, axis=0) != 0, axis=1)) + 1
        out = []
        for part in np.split(a, cuts):
            k, m = int(part[0, 1]), int(part[0, 2])
            volume, thickness = chips.get((k, m), (0.0, 0.0))
            work = float(part[:, 3 + POWER].sum() * dt)  # [J]: the tick's power held over the tick
            model_volume = float(part[:, 3 + VOLUME_RATE].sum() * dt)
            load = EngagementLoad(
                part[:, 0], part[:, 3:6], part[:, 6:9], part[:, 9:12], volume, thickness,
                work / volume * 1e3 if volume > 0 else 0.0, part[:, 12:15], model_volume,
            )  # fmt: skip
            out.append(AppliedLoad(k, m, load))
        out.sort(key=lambda a: a.load.t[0])
        return out
