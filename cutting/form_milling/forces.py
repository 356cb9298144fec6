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

The finger (end) mill's force (:class:`FingerLoad`): Q = v_f x the section it removes, Kienzle at the end mill's mean
chip thickness and the teeth's radial force as a stated ratio of their tangential one (Altintas 2012).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from cutting.form_milling.finger import FingerMill, fit_finger_mill
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


# ---- the finger (end) mill ------------------------------------------------------------------------------------------
def finger_removed_areas(gear: Gear, mill: FingerMill, clearance: float, samples: int = 4001) -> dict[str, float]:
    """Area [mm^2] of the transverse space section each finger pass removes (nominal path points, left pass first):
    per row y of the space frame the finger covers |x - x_0| < rho(v), v = sense (y - r_f) its distance from the
    tip, intersected with the blank's row (external: inside the tip circle; internal: outside it)."""
    r_f, r_a, sense = gear.root_radius, gear.tip_radius, gear.sense
    y = np.linspace(min(r_f, r_a), max(r_f, r_a), samples)
    rho = np.nan_to_num(mill.rho(sense * (y - r_f)), nan=0.0)
    half = np.sqrt(np.maximum(r_a**2 - y**2, 0.0))  # the tip circle's half chord on the row

    def covered(x0: np.ndarray, x1: np.ndarray) -> np.ndarray:  # length of [x0, x1] that is material
        inside = np.clip(np.minimum(x1, half) - np.maximum(x0, -half), 0.0, None)
        return inside if not gear.internal else np.clip(x1 - x0, 0.0, None) - inside

    xl, xr = finger_path_x(gear, "left", clearance), finger_path_x(gear, "right", clearance)
    left = covered(xl - rho, xl + rho)
    lo, hi = np.minimum(xl, xr) - rho, np.maximum(xl, xr) + rho  # the union of both passes' intervals
    both = covered(lo, hi)
    dy = y[1] - y[0]
    return {"left": float(np.trapezoid(left, dx=dy)), "right": float(np.trapezoid(both - left, dx=dy))}


def transverse_equivalent(gear: Gear) -> Gear:
    """The spur gear whose tooth section is ``gear``'s transverse section: module m_t, pressure angle alpha_t, the
    same tip and root diameters, and the profile shift that keeps the transverse thickness (x tan alpha_n /
    tan alpha_t: s_t = m_t (pi / 2 + 2 x tan alpha_n))."""
    at = gear.transverse_pressure_angle
    return Gear(
        teeth=gear.teeth,
        normal_module=gear.transverse_module,
        pressure_angle=at,
        face_width=gear.face_width,
        profile_shift=gear.profile_shift * math.tan(gear.pressure_angle) / math.tan(at),
        internal=gear.internal,
        tip_diameter=gear.tip_diameter_value,
        root_diameter=gear.root_diameter_value,
        rack=gear.rack,
    )


def finger_path_x(gear: Gear, side: str, clearance: float) -> float:
    """The tangential position x_s [mm] of the ``side`` pass's axis (:func:`cutting.form_milling.finger.path_point`)."""
    from cutting.form_milling.finger import path_point

    return float(path_point(gear, side, clearance)[0])  # type: ignore[arg-type]


def mean_forces(phi_start: float, phi_exit: float, radial_ratio: float = RADIAL_RATIO) -> tuple[float, float, float]:
    """Mean force of an end mill's teeth over a revolution, against the feed and normal to it, and the mean chip
    thickness, each over (resp. per) the mean tangential force sum F_T = T / R and the feed per tooth.

    Altintas, *Manufacturing Automation*, 2nd ed. (Cambridge 2012), sec. 2.3 (eqs. 2.37-2.44): a tooth at the
    immersion angle phi cuts the chip h = f_z sin(phi) with the tangential force F_t = K_t a h and the radial one
    K_r F_t; over the engagement [phi_st, phi_ex] their means are (N a f_z K_t / 2 pi) times
    feed: S1 + K_r S2, normal: S2 - K_r S1, tangential sum: cos phi_st - cos phi_ex, with S1 = int sin cos,
    S2 = int sin^2; the average chip thickness h_m = f_z (cos phi_st - cos phi_ex) / (phi_ex - phi_st).
    Returns (feed / F_T, normal / F_T, h_m / f_z); slotting (0, pi): (K_r pi / 4, pi / 4, 2 / pi)."""
    a, b = phi_start, phi_exit
    s1 = (math.sin(b) ** 2 - math.sin(a) ** 2) / 2
    s2 = (b - a) / 2 - (math.sin(2 * b) - math.sin(2 * a)) / 4
    t = math.cos(a) - math.cos(b)
    return (s1 + radial_ratio * s2) / t, (s2 - radial_ratio * s1) / t, t / (b - a)


@dataclass(frozen=True, eq=False)
class FingerLoad:
    """The finger pass's cutting force [N] and torque [N m] as functions of the tip centre's face position.

    An end mill side-milling the space (its axis along the space's symmetry line, fed along the face): the removal
    rate is Q = v_f A, A the section the pass removes (:func:`finger_removed_areas`); Kienzle's k_c at the mean
    chip thickness h_m of the pass's immersion (:func:`mean_forces`; the left pass slots the space, phi 0..pi, the
    right pass takes the clearance's strip a_e = c at the flank it finishes, phi 0..acos(1 - 2 c / D_m)) gives the
    cutting power P = k_c(h_m) Q and the mean tangential force sum F_T = P / v_c at the mean diameter D_m over the
    tooth depth (v_c = pi D_m n), the spindle torque F_T D_m / 2; the resultant in the plane normal to the axis
    follows from the teeth's radial force, the thrust RADIAL_RATIO F_t of each tooth (as the disc mill's): against
    the feed (S1 + K_r S2) / (cos phi_st - cos phi_ex) F_T and normal to it, pushing the mill off the flank the pass
    finishes, (S2 - K_r S1) / (...) F_T. Straight flutes: no force along the axis. Engagement: the share of the
    mill's front arc (x uniform across its mean diameter) within the face, so the force rises as the mill enters
    and falls as it leaves. The steady force of the pass, not the teeth's pulsation (4 teeth at 100 Hz)."""

    gear: Gear
    mill: FingerMill
    material: Material
    feed: float  # mm/min
    speed: float  # rpm
    clearance: float  # mm

    @cached_property
    def areas(self) -> dict[str, float]:
        """Area [mm^2] each pass removes in full engagement. On a helical space the finger's silhouette in its own
        axial plane is narrower than the space (the envelope touches the flanks off that plane: 3-7 % less area at
        beta 15-20 deg); what it sweeps in the transverse plane is the space's transverse section, a spur gear's
        (:func:`transverse_equivalent`), cut by that spur gear's finger."""
        if self.gear.helix_angle == 0.0:
            return finger_removed_areas(self.gear, self.mill, self.clearance)
        spur = transverse_equivalent(self.gear)
        return finger_removed_areas(spur, fit_finger_mill(spur, self.clearance), self.clearance)

    @property
    def depth(self) -> float:
        return abs(self.gear.tip_radius - self.gear.root_radius)

    @cached_property
    def mean_radius(self) -> float:
        """The mill's mean radius [mm] over the tooth depth (from its tip to the tip circle)."""
        v = np.linspace(0.0, self.depth, 201)
        return float(np.mean(self.mill.rho(v)))

    @property
    def feed_per_tooth(self) -> float:
        return self.feed / (self.speed * self.mill.teeth)

    def immersion(self, side: str) -> tuple[float, float]:
        """[phi_st, phi_ex] [rad] of the ``side`` pass: slotting for the left, the clearance's strip for the right."""
        if side == "left":
            return 0.0, math.pi
        return 0.0, math.acos(max(1.0 - self.clearance / self.mean_radius, -1.0))

    def chip_thickness(self, side: str) -> float:
        """Mean chip thickness h_m [mm] of the ``side`` pass."""
        return mean_forces(*self.immersion(side))[2] * self.feed_per_tooth

    def main_force(self, side: str) -> float:
        """F_T [N] of the ``side`` pass in full engagement: k_c(h_m) A v_f / v_c (the tangential forces' sum)."""
        vf = self.feed / 60.0  # mm/s
        vc = math.pi * 2 * self.mean_radius * self.speed / 60.0  # mm/s
        return self.material.kc(self.chip_thickness(side)) * self.areas[side] * vf / vc

    def torque(self, side: str) -> float:
        """Spindle torque [N m] of the ``side`` pass in full engagement: F_T D_m / 2."""
        return self.main_force(side) * self.mean_radius * 1e-3

    def components(self, side: str) -> tuple[float, float]:
        """(against the feed, normal to it) [N] in full engagement."""
        f, n, _ = mean_forces(*self.immersion(side))
        return f * self.main_force(side), n * self.main_force(side)

    def engagement(self, z: np.ndarray, direction: float) -> np.ndarray:
        """Share of the front arc within the face at tip-centre face positions ``z`` fed towards sign(direction) z."""
        d = np.sign(direction) * np.asarray(z, dtype=float)
        half, r = self.gear.face_width / 2, self.mean_radius
        a = np.sqrt(r**2 - np.clip(half - d, 0.0, r) ** 2)  # the arc's front beyond the far face: |x| < a
        b = np.sqrt(r**2 - np.clip(-half - d, 0.0, r) ** 2)  # still before the near face: |x| > b
        return np.clip((b - a) / r, 0.0, 1.0)

    def force(self, side: str, z: np.ndarray, direction: float) -> np.ndarray:
        """(n, 6) force on the mill [N] in the space frame (x tangential, y radial out, z) and the torque on it
        [N m] about the same axes: against the feed, normal pushing off the ``side`` flank, the cutting torque
        against the spindle's turn about the mill's axis (from its tip into it, (0, sense, 0))."""
        from cutting.form_milling.mill import flank_sign

        e = self.engagement(z, direction)
        feed, normal = self.components(side)
        out = np.zeros((len(e), 6))
        out[:, 0] = -flank_sign(self.gear, side) * normal * e  # type: ignore[arg-type]
        out[:, 2] = -np.sign(direction) * feed * e
        out[:, 4] = -self.gear.sense * self.torque(side) * e
        return out
