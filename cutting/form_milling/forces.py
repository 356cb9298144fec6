"""The cutting force of the profiled disc mill (copying method), from the section each pass removes.

A pass removes per millimetre of feed the area A of its tooth-space section that is still material: for the left
pass the mill's section below the tip circle, for the right pass the strip the clearance left beside the right
flank. A plane of the face a distance s ahead of the mill's centre is cut down to the section raised by lift(s) = R
- sqrt(R^2 - s^2), so as the mill advances the planes ahead of it within the face deepen their cut from lift(s_max)
to lift(s_min): the removal rate is Q = v_f [A(lift(s_min)) - A(lift(s_max))], s_min and s_max the face's nearest
and farthest planes ahead of the centre (within the arc of contact). It rises as the mill enters, never reaches v_f
A on a face shorter than the arc, and falls to 0 as the centre leaves the face. With Kienzle's law at the mean chip
thickness h_m = f_z sqrt(a_e / D) of a disc mill (f_z the feed per tooth, a_e the tooth depth) the cutting power is
P = k_c(h_m) Q and the main (tangential) cutting force at the cutting speed v_c is F_t = P / v_c; the thrust pushing
the mill off the work F_r = RADIAL_RATIO F_t. The forces act at the mill's lowest point on the mill and, reversed,
on the gear. This is the steady force of the pass, not the pulsation of the single teeth (12 per revolution at ~4
Hz, far below the machine's modes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from cutting.form_milling.mill import DiscMill
from cutting.gear import Gear
from cutting.materials import Material

#: thrust over main cutting force of a milling tooth (the classic 0.3-0.5 of steel milling)
RADIAL_RATIO = 0.4


def removed_areas(gear: Gear, mill: DiscMill, clearance: float, lift: float = 0.0, samples: int = 4001) -> dict:
    """Area [mm^2] of the transverse space section each pass removes (nominal path points, left pass first), the
    mill raised by ``lift`` [mm] (its lowest point above the root circle: the section it cuts entering the face).
    On a helical space the mill's axis is set over by the helix angle (:func:`cutting.form_milling.helical.set_over`),
    so the transverse plane cuts its profile stretched by 1 / cos(set-over): the transverse u is u cos(set-over) along
    the mill's axis (the removal per millimetre of feed along the gear axis is the transverse section's)."""
    from cutting.form_milling.helical import set_over

    u0, u1 = -gear.tip_radius * math.sin(math.pi / gear.teeth), gear.tip_radius * math.sin(math.pi / gear.teeth)
    u = np.linspace(u0, u1, samples)
    tip = np.sqrt(np.maximum(gear.tip_radius**2 - u**2, 0.0)) - gear.root_radius  # the blank, from the root
    k = math.cos(set_over(gear))
    h_left = np.nan_to_num(mill.height(k * u + clearance / 2), nan=np.inf) + lift  # the mill at -c/2
    h_right = np.nan_to_num(mill.height(k * u - clearance / 2), nan=np.inf) + lift
    left = np.clip(tip - h_left, 0.0, None)
    both = np.clip(tip - np.minimum(h_left, h_right), 0.0, None)
    du = u[1] - u[0]
    return {"left": float(left.sum() * du), "right": float((both - left).sum() * du)}


@dataclass(frozen=True, eq=False)
class MillLoad:
    """The pass's cutting force [N] as a function of the mill centre's face position (see the module text)."""

    gear: Gear
    mill: DiscMill
    material: Material
    feed: float  # mm/min
    speed: float  # rpm
    clearance: float  # mm

    @cached_property
    def _areas(self) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        lifts = np.linspace(0.0, self.depth, 31)
        rows = [removed_areas(self.gear, self.mill, self.clearance, lift) for lift in lifts]
        return lifts, {s: np.array([r[s] for r in rows]) for s in ("left", "right")}

    @property
    def areas(self) -> dict[str, float]:
        """Area [mm^2] each pass removes in full engagement."""
        return {s: float(a[0]) for s, a in self._areas[1].items()}

    @property
    def depth(self) -> float:
        return self.gear.tip_radius - self.gear.root_radius

    @property
    def chip_thickness(self) -> float:
        """Mean chip thickness h_m [mm] = f_z sqrt(a_e / D)."""
        fz = self.feed / (self.speed * self.mill.teeth)
        return fz * math.sqrt(self.depth / (2 * self.mill.radius))

    def main_force(self, side: str) -> float:
        """F_t [N] of the ``side`` pass in full engagement: k_c(h_m) A v_f / v_c."""
        vf = self.feed / 60.0  # mm/s
        vc = math.pi * 2 * self.mill.radius * self.speed / 60.0  # mm/s
        return self.material.kc(self.chip_thickness) * self.areas[side] * vf / vc

    def engagement(self, side: str, z: np.ndarray, direction: float) -> np.ndarray:
        """Removal rate over v_f A at mill-centre face positions ``z`` for a feed towards sign(direction) z:
        [A(lift(s_min)) - A(lift(s_max))] / A (see the module text)."""
        d = np.sign(direction) * np.asarray(z, dtype=float)  # position along the feed, face from -b/2 to b/2
        half, r = self.gear.face_width / 2, self.mill.radius
        lifts, areas = self._areas

        def area(s: np.ndarray) -> np.ndarray:
            lift = r - np.sqrt(r**2 - np.minimum(s, r) ** 2)
            return np.interp(lift, lifts, areas[side], right=0.0)

        near, far = np.clip(-half - d, 0.0, r), np.clip(half - d, 0.0, r)
        return np.clip((area(near) - area(far)) / max(areas[side][0], 1e-12), 0.0, 1.0)

    def force(self, side: str, z: np.ndarray, direction: float) -> np.ndarray:
        """(n, 3) force on the mill [N] in the space frame (x tangential, y radial out, z): the thrust along +y
        (off the work) and the main force against the feed (up milling: the spindle turns so that the teeth at the
        bottom move against the feed, in both passes)."""
        ft = self.main_force(side) * self.engagement(side, z, direction)
        out = np.zeros((len(ft), 3))
        out[:, 1] = RADIAL_RATIO * ft
        out[:, 2] = -np.sign(direction) * ft
        return out
