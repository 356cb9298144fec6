"""The chip of the moment on the ideal machine: one cutter tooth turning through its engagement at mid face, by the
ideal kinematics, at a pass's centre distance after the pass before (:mod:`cutting.skiving.chip_of_the_moment`
with no deviation and no deflection). Each instant's chips are the co-simulation's own: each element's layer
between it and the surface the same element left one work revolution earlier (the previous tooth in the space),
the previous pass's surface, or the blank. What the pre-run load estimate
(virtual_machine/reach/skiving_load.py) and the stability lobes (virtual_machine/processes/skiving/stability.py)
read before a run.
"""

from __future__ import annotations

import math

import numpy as np

from cutting.forces import EdgeFaces
from cutting.oblique import H_FLOOR, ObliqueForces
from cutting.skiving.chip_of_the_moment import element_chips, opened_space, tick_load
from cutting.skiving.edge import make_edge
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.sweep import outline_points, simplify_outline, split_sides
from cutting.skiving.trajectory import ideal_passes
from cutting.skiving.working_angles import rake_normal


def chip_constants(model: ObliqueForces) -> np.ndarray:
    """The oblique model's constants as :func:`cutting.skiving.chip_of_the_moment.tick_load` takes them (``chip``):
    kc1.1 [N/mm^2], mc, the floor of h in kc(h) [mm], K_c / tau_s of the table's tool, h_min [mm], K_ce, K_te
    [N/mm], the friction angle and the rake floor [rad]."""
    ce, te = model.edge_coefficients
    c, mat = model.model, model.material
    return np.array(
        [mat.kc11, mat.mc, max(model.min_chip, H_FLOOR), model.reference_factor, model.min_chip, ce, te,
         c.friction_angle, c.rake_floor]
    )  # fmt: skip


def edge_elements(setup: SkivingSetup) -> tuple[np.ndarray, EdgeFaces]:
    """The involute edge (within micrometres of the conjugate one: the same engaged length) in elements of <= 0.2 mm,
    its shape within 5 um, as the co-simulation's, in the rake frame; and its faces."""
    edge = make_edge(setup, "involute")
    pts = outline_points(split_sides(simplify_outline(edge.outline, 0.005)[0], 0.2))
    return pts, EdgeFaces.of_outline(pts, rake_normal(setup))


class IdealMoment:
    """One tooth (passage 0) at ``centre_distance`` [mm] after a pass at ``previous`` [mm] (None: the first pass,
    into the blank), the carriage at mid face when the cutter angle is 0."""

    def __init__(self, setup: SkivingSetup, centre_distance: float, previous: float | None):
        g = setup.gear
        self.setup, self.centre_distance, self.previous = setup, centre_distance, previous
        self.points, self.faces = edge_elements(setup)
        self.omega0 = setup.tool_speed * 2 * math.pi / 60
        self.pitch = 2 * math.pi / setup.cutter.teeth
        # the previous tooth in a space passed z2 cutter pitches before (a whole number: chip_load's revolution)
        self.revolution = round(2 * math.pi / abs(setup.speed_ratio) / self.pitch) * self.pitch
        ratio, diff = setup.speed_ratio, setup.differential_rotation_per_mm
        self.zeta = ideal_passes(setup)[0].v_s / self.omega0  # the carriage per cutter radian [mm/rad], signed
        w = self.omega0
        self.rates = np.array([w, ratio * w + diff * self.zeta * w, self.zeta * w, 0.0])
        self.geometry = np.array([setup.tilt, setup.cutter_phase, setup.work_phase])
        envelope = np.array([g.tip_radius, 1.0 if g.internal else 0.0, g.face_width / 2])
        if previous is not None:  # the space the passes before opened holds no chip
            envelope = np.concatenate([envelope, opened_space(g, abs(previous - setup.final_centre_distance))])
        self.envelope = envelope
        self.teeth = np.ascontiguousarray(setup.passage_frames(np.array([0])))
        self.before = np.ascontiguousarray(setup.passage_frames(np.array([-round(self.revolution / self.pitch)])))
        self.blank = np.ascontiguousarray(setup.blank_frame, dtype=float)

    def axes(self, b1: float, centre_distance: float) -> np.ndarray:
        """B1, B2 [rad], P3, X [mm] of the ideal kinematics at cutter angle ``b1``."""
        st = self.setup
        z = self.zeta * b1
        return np.array([b1, st.speed_ratio * b1 + st.differential_rotation_per_mm * z, z, centre_distance])

    def _arguments(self, b1: float) -> tuple:
        a, prev = self.centre_distance, self.previous
        zero = np.zeros(6)
        return (
            self.axes(b1, a), self.rates, zero, self.geometry, self.teeth, self.blank, self.points, self.faces.rake,
            self.faces.body, self.envelope, self.before, self.axes(b1 - self.revolution, a), zero, True,
            self.axes(b1, prev if prev is not None else 0.0), zero, prev is not None,
        )  # fmt: skip

    def chips(self, b1: float, friction: float, floor: float) -> tuple:
        """:func:`cutting.skiving.chip_of_the_moment.element_chips` at cutter angle ``b1`` [rad]."""
        return element_chips(*self._arguments(b1), friction, floor)

    def load(self, b1: float, chip: np.ndarray, out: np.ndarray) -> int:
        """:func:`cutting.skiving.chip_of_the_moment.tick_load` at cutter angle ``b1`` [rad] into ``out`` (1,
        COLUMNS); ``chip``: :func:`chip_constants`."""
        return tick_load(*self._arguments(b1), chip, out)
