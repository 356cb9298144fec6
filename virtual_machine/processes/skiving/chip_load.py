"""The skiving machine's load hook: each servo tick, the chips the teeth in the cut are taking at that moment
(:mod:`cutting.skiving.chip_of_the_moment`), from the machine's own state at the tick.

Per feed tick the hook reads the axes, their speeds and the loop's deflection (the state the tick starts from), the
ideal kinematics' axes at the same cutter angle (the reference), and keeps the deviation between the two for the
stroke; the deviation one work revolution earlier is the surface the teeth left there. The engaged teeth are those
whose engagement window (the pass's half angle either side of the mesh) holds the cutter angle at the tick's start;
their loads act over the tick. The work is done in one compiled call per tick (chip_of_the_moment.machine_tick).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from cutting.forces import EdgeFaces, EngagementLoad
from cutting.oblique import ObliqueForces
from cutting.skiving.chip_of_the_moment import (
    COLUMNS,
    POWER,
    VOLUME_RATE,
    WIDTH,
    cut_phase,
    machine_tick,
    opened_space,
)
from cutting.skiving.ideal_moment import chip_constants
from cutting.skiving.trajectory import PassMotion
from machine_models.skiving_machine import MM
from virtual_machine.runtime.physics import AXES

FEED = "feed"


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
        self.chip = chip_constants(model)
        self.frames = np.ascontiguousarray(setup.tooth_frames, dtype=float)  # every tooth's rake frame, tooth 0 first
        self._pass: int | None = None  # the stroke in the cut (None between strokes)
        self._stroke: int | None = None  # the pass whose deviation the history holds
        self._zero = np.zeros(6)
        teeth = math.ceil(2 * max(self.halves, default=0.0) / self.pitch) + 2  # the most teeth a window holds
        self._out, self._passages = np.empty((teeth, COLUMNS)), np.empty(teeth, dtype=np.int64)
        #: per tick with a chip: t, pass, the engaged passages (m,) and their tick_load columns (m, COLUMNS)
        self.rows: list[tuple[float, int, np.ndarray, np.ndarray]] = []
        self.machine = None

    def bind(self, machine) -> None:
        """The machine run whose state the hook reads (virtual_machine.runtime.machine_run.MachineRun)."""
        self.machine = machine
        phys = machine.phys
        self._qa = np.array([phys.qadr[a] for a in AXES[:4]], dtype=np.int64)
        self._va = np.array([phys.vadr[a] for a in AXES[:4]], dtype=np.int64)
        self._qpos, self._qvel = phys.data.qpos, phys.data.qvel
        self._model, self._data = phys.model, phys.data

    def _start(self, k: int, dt: float) -> None:
        """A feed stroke begins: its constants for the compiled tick and its history (one row per tick)."""
        plan, st = self.plans[k], self.setup
        q = self._qpos.take(self._qa)
        b1_0, b2_0, p3_0 = self.machine.home
        previous = self.plans[k - 1].centre_distance if k > 0 else math.nan
        zeta = plan.v_s / plan.omega0  # the carriage per cutter radian [mm/rad]
        # the previous tooth in this space passed z2 cutter pitches ago: the cutter's turn over a work revolution
        # without the differential's share. A helical gear's work has turned by 2 pi plus the differential's turn over
        # that feed: the pose then is the present one moved back along the helix by the feed (a whole turn of the
        # work would leave the cutter a fraction of a pitch off, 0.08 mm at the edge on a small helical job)
        back = round(2 * math.pi / abs(st.speed_ratio) / self.pitch)
        revolution = back * self.pitch
        self._state = np.array(
            [q[0], q[2] / MM, b1_0, b2_0, p3_0, st.speed_ratio, st.differential_rotation_per_mm, zeta,
             plan.centre_distance, previous, self.halves[k], self.pitch, revolution, float(back), *self.geometry]
        )  # fmt: skip
        # from the second pass on, the space the passes before opened holds no chip (where this machine cut it)
        self._envelope = self.envelope
        if k > 0:
            stock = abs(plan.centre_distance - st.final_centre_distance) + st.passes[k]
            phase = cut_phase(st.speed_ratio, st.differential_rotation_per_mm, (b1_0, b2_0, p3_0))
            self._envelope = np.concatenate([self.envelope, opened_space(st.gear, stock, phase)])
        if self._stroke == k - 1:  # the pass before's deviation along its stroke
            self._last, self._last_count = self._history, self._count
        else:
            self._last, self._last_count = np.zeros((1, 8)), 0
        self._history = np.empty((int(plan.duration / dt) + 256, 8))
        self._count = 0
        self._pass = self._stroke = k

    def __call__(self, t: float, dt: float) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        tick = self.machine._tick
        if tick.segment != FEED:
            self._pass = None
            return []
        k = tick.pass_index
        if self._pass != k:
            self._start(k, dt)
        defl = self.machine.deflections
        if not defl:
            # the frames MuJoCo applies the load in are those of the last sub-step's start, half a tick old; the
            # machine with loop modes has just brought them up to date (its deflection), this one does so here: a
            # stale frame would put the tool's point of application ahead of the edge (+4.5 % of work)
            mujoco.mj_kinematics(self._model, self._data)
        if self._count == len(self._history):
            self._history = np.concatenate([self._history, np.empty_like(self._history)])
        # the teeth in the cut at the tick's start: MuJoCo applies the load in the frames of that instant (taken at
        # the tick's middle, the tool's point of application would run ahead of the edge by half a tick of the
        # relative motion, and the load would do 9 % more work than the chip takes)
        n = machine_tick(
            self._qpos, self._qvel, self._qa, self._va, np.asarray(defl[-1]) if defl else self._zero, self._state,
            self._history, self._count, self._last, self._last_count, self.frames, self.blank, self.edge, self.rake,
            self.body, self._envelope, self.chip, self._out, self._passages,
        )  # fmt: skip
        self._count += 1
        if n == 0:
            return []
        out = self._out[:n]
        cutting = out[:, WIDTH] > 0
        if not cutting.any():
            return []
        out = out[cutting].copy()
        self.rows.append((t, k, self._passages[:n][cutting].copy(), out))
        return [(row[0:3], row[3:6], row[6:9]) for row in out]

    def engagements(self, dt: float, chips: dict[tuple[int, int], tuple[float, float]]) -> list:
        """The loads that acted, one :class:`EngagementLoad` per (pass, passage) in time order, each with its
        removal chip's volume and thickness (``chips``: (pass, passage) -> (volume [mm^3], thickness [mm])); ``dt``
        the servo tick [s]. Its kc is the cutting work over the removal's volume."""
        from virtual_machine.processes.skiving.cosim import AppliedLoad

        if not self.rows:
            return []
        a = np.concatenate(
            [np.column_stack([np.full(len(m), t), np.full(len(m), k), m, out]) for t, k, m, out in self.rows]
        )
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
