"""The cutting force of the profiled disc and finger mills (copying method), from the section each pass removes.

A pass removes per millimetre of feed the area A of its tooth-space section that is still material: for the left
pass the mill's section below the tip circle, for the right pass the strip the clearance left beside the right
flank. A plane of the face a distance s ahead of the mill's centre is cut down to the section raised by lift(s) = R
- sqrt(R^2 - s^2), so as the mill advances the planes ahead of it within the face deepen their cut from lift(s_max)
to lift(s_min): the removal rate is Q = v_f [A(lift(s_min)) - A(lift(s_max))], s_min and s_max the face's nearest
and farthest planes ahead of the centre (within the arc of contact). It rises as the mill enters, never reaches v_f
A on a face shorter than the arc, and falls to 0 as the centre leaves the face.

The forces are the oblique model's (:mod:`cutting.oblique`, the skiving machine's; docs/forces.md, "The other
machines"). The teeth of both mills are form-relieved with a radial rake face and straight (:data:`MILL_RAKE`,
:data:`MILL_INCLINATION`): every element of the engaged edge cuts at normal rake 0 and inclination 0, so it takes a
cutting force along its velocity and a thrust normal to the surface it cuts, and no passive force. Each takes the
pass's mean chip thickness h_m (the disc mill's f_z sqrt(a_e / D), f_z the feed per tooth, a_e the tooth depth);
the teeth in cut at once have the chip width b = Q / (v_c h_m) (the mean section in cut over h_m, v_c the cutting
speed), so that they take F = f tau_s(h_m) (h_m - h_min) b + K_e b (:func:`tooth_load`): the cutting force F_t
(Kienzle's Q k_c(h_m) / v_c where the tooth is the table's sharp +6 deg tool) and the thrust. The cutting force
acts along the teeth's velocity at the mill's lowest point, against the feed (up milling); the thrust off the work
along the removal's mean cut-surface normal in the transverse plane (:func:`thrust_directions`): the left pass's
two flanks push the mill sideways against each other, so its thrust is mostly radial; the right pass cuts the strip
along the right flank, whose thrust pushes the mill off that flank, along its axis. Both act at the mill's lowest
point on the mill and, reversed, on the gear. This is the steady force of the pass, not the pulsation of the single
teeth (12 per revolution at ~4 Hz, far below the machine's modes). The form-milling job gives no edge radius: the
model's default (:data:`cutting.oblique.DEFAULT_EDGE_RADIUS`).

The finger (end) mill's force (:class:`FingerLoad`): Q = v_f x the section it removes, the same model at the end
mill's mean chip thickness, Altintas' mean forces of the teeth over their immersion (2012).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

import numpy as np

from cutting.form_milling.finger import FingerMill, fit_finger_mill
from cutting.form_milling.mill import DiscMill
from cutting.gear import Gear
from cutting.materials import Material
from cutting.oblique import DEFAULT_EDGE_RADIUS, ObliqueForces, material_forces

#: the normal rake [rad] of the mills' teeth: the job gives none; a form-relieved gear cutter (disc or finger) is
#: ground on a radial rake face, so that regrinding the face keeps its profile: 0 deg
MILL_RAKE = 0.0
#: the teeth's inclination [rad]: straight teeth, their edge in an axial plane of the mill and so normal to its
#: velocity about the axis (the feed's 1-2 % of the cutting speed aside): 0 deg
MILL_INCLINATION = 0.0


class ToothLoad(NamedTuple):
    """The mean forces [N] of a mill's teeth in cut (:func:`tooth_load`): ``shear`` the chip's (cutting, thrust,
    passive), ``edge`` the rounded edge's ploughing (cutting, thrust), and the chip width ``width`` b [mm]."""

    shear: tuple[float, float, float]
    edge: tuple[float, float]
    width: float

    @property
    def cutting(self) -> float:
        """Along the teeth's velocity [N]: the tangential forces' sum."""
        return self.shear[0] + self.edge[0]

    @property
    def thrust(self) -> float:
        """Normal to the cut surfaces [N], the elements' magnitudes summed (their directions: the caller's)."""
        return self.shear[1] + self.edge[1]

    @property
    def passive(self) -> float:
        """Along the edges [N]: zero for the straight teeth."""
        return self.shear[2]


def tooth_load(model: ObliqueForces, thickness: float, section: float) -> ToothLoad:
    """The teeth in cut taking chips ``thickness`` h [mm] thick, ``section`` [mm^2] the mean chip section in cut
    (Q / v_c): the chip width b = section / h, every element at the mills' rake and inclination, the shear
    f tau_s(h) (h - h_min)+ b and the edge's K_e b (:class:`cutting.oblique.ObliqueForces`)."""
    if thickness <= 0 or section <= 0:
        return ToothLoad((0.0, 0.0, 0.0), (0.0, 0.0), 0.0)
    b = section / thickness
    sheared = float(model.shear_stress(thickness)) * max(thickness - model.min_chip, 0.0) * b
    f = model.factors(MILL_RAKE, MILL_INCLINATION)
    ce, te = model.edge_coefficients
    return ToothLoad((float(f[0]) * sheared, float(f[1]) * sheared, float(f[2]) * sheared), (ce * b, te * b), b)


def removal_columns(
    gear: Gear, mill: DiscMill, clearance: float, lift: float = 0.0, samples: int = 4001
) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The transverse space section cut into columns: their positions u [mm] (x_s, across the space), per pass the
    depth of material each column loses (nominal path points, the mill raised by ``lift`` [mm], its lowest point above
    the root circle) and the slope dy/du of the surface the pass leaves there (the mill's edge). On a helical space
    the mill's axis is set over by the helix angle (:func:`cutting.form_milling.helical.set_over`), so the
    transverse plane cuts its profile stretched by 1 / cos(set-over): the transverse u is u cos(set-over) along the
    mill's axis (the removal per millimetre of feed along the gear axis is the transverse section's)."""
    from cutting.form_milling.helical import set_over

    u0, u1 = -gear.tip_radius * math.sin(math.pi / gear.teeth), gear.tip_radius * math.sin(math.pi / gear.teeth)
    u = np.linspace(u0, u1, samples)
    tip = np.sqrt(np.maximum(gear.tip_radius**2 - u**2, 0.0)) - gear.root_radius  # the blank, from the root
    k = math.cos(set_over(gear))
    h_left = np.nan_to_num(mill.height(k * u + clearance / 2), nan=np.inf) + lift  # the mill at -c/2
    h_right = np.nan_to_num(mill.height(k * u - clearance / 2), nan=np.inf) + lift
    left = np.clip(tip - h_left, 0.0, None)
    both = np.clip(tip - np.minimum(h_left, h_right), 0.0, None)
    uu, hh = mill.profile
    slope = np.gradient(hh, uu)
    slopes = {
        "left": k * np.interp(k * u + clearance / 2, uu, slope),
        "right": k * np.interp(k * u - clearance / 2, uu, slope),
    }
    return u, {"left": left, "right": both - left}, slopes


def removed_areas(gear: Gear, mill: DiscMill, clearance: float, lift: float = 0.0, samples: int = 4001) -> dict:
    """Area [mm^2] of the transverse space section each pass removes (:func:`removal_columns`, left pass first)."""
    u, depths, _ = removal_columns(gear, mill, clearance, lift, samples)
    du = u[1] - u[0]
    return {side: float(d.sum() * du) for side, d in depths.items()}


def thrust_directions(gear: Gear, mill: DiscMill, clearance: float, samples: int = 4001) -> dict[str, np.ndarray]:
    """Per pass the direction (x_s, y_s) of its teeth's thrust on the mill in the transverse plane: the mean of the
    cut surface's unit normal into the mill, (-y', 1) / sqrt(1 + y'^2) (y' the edge's slope, :func:`removal_columns`),
    over the columns weighted by their removal (a column's force is its share of Q at the pass's chip thickness).
    Its length is below 1 where the columns' normals oppose each other (the slotting pass's two flanks)."""
    _, depths, slopes = removal_columns(gear, mill, clearance, 0.0, samples)
    out = {}
    for side, depth in depths.items():
        w = depth / max(float(depth.sum()), 1e-300)
        norm = np.sqrt(1.0 + slopes[side] ** 2)
        out[side] = np.array([float(np.sum(w * -slopes[side] / norm)), float(np.sum(w / norm))])
    return out


@dataclass(frozen=True, eq=False)
class MillLoad:
    """The pass's cutting force [N] as a function of the mill centre's face position (see the module text); the
    teeth's edge radius ``edge_radius`` [mm] (the job gives none: the model's default)."""

    gear: Gear
    mill: DiscMill
    material: Material
    feed: float  # mm/min
    speed: float  # rpm
    clearance: float  # mm
    edge_radius: float = DEFAULT_EDGE_RADIUS

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

    @property
    def model(self) -> ObliqueForces:
        """The material's oblique model for the teeth's edge radius."""
        return material_forces(self.material, self.edge_radius)

    def section(self, side: str) -> float:
        """The mean chip section in cut [mm^2] of the ``side`` pass in full engagement: Q / v_c = A v_f / v_c."""
        vf = self.feed / 60.0  # mm/s
        vc = math.pi * 2 * self.mill.radius * self.speed / 60.0  # mm/s
        return self.areas[side] * vf / vc

    def load(self, side: str) -> ToothLoad:
        """The teeth's mean forces [N] of the ``side`` pass in full engagement (:func:`tooth_load` at h_m)."""
        return tooth_load(self.model, self.chip_thickness, self.section(side))

    def main_force(self, side: str) -> float:
        """F_t [N] of the ``side`` pass in full engagement: the teeth's cutting force (against the feed)."""
        return self.load(side).cutting

    @cached_property
    def directions(self) -> dict[str, np.ndarray]:
        """Per pass the thrust's direction (x_s, y_s) on the mill (:func:`thrust_directions`)."""
        return thrust_directions(self.gear, self.mill, self.clearance)

    def components(self, side: str) -> tuple[float, float, float]:
        """(along x_s, along y_s, against the feed) [N] on the mill in full engagement: the thrust along its
        direction (x_s: the mill's axis, off the flank the right pass finishes; y_s: radial, off the work) and the
        cutting force."""
        ld = self.load(side)
        d = self.directions[side]
        return ld.thrust * float(d[0]), ld.thrust * float(d[1]), ld.cutting

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
        """(n, 3) force on the mill [N] in the space frame (x tangential, y radial out, z): the thrust in the
        transverse plane (:meth:`components`) and the cutting force against the feed (up milling: the spindle turns
        so that the teeth at the bottom move against the feed, in both passes)."""
        e = self.engagement(side, z, direction)
        tx, ty, fc = self.components(side)
        out = np.zeros((len(e), 3))
        out[:, 0] = tx * e
        out[:, 1] = ty * e
        out[:, 2] = -np.sign(direction) * fc * e
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


def mean_forces(phi_start: float, phi_exit: float, radial_ratio: float) -> tuple[float, float, float]:
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


def edge_means(phi_start: float, phi_exit: float, radial_ratio: float) -> tuple[float, float]:
    """:func:`mean_forces` of the teeth's edge (ploughing) forces, which do not grow with the chip: a tooth in the cut
    takes K_te a tangentially and K_re a radially whatever its immersion (Altintas 2012, eq. 2.41's edge terms); over
    the engagement their means are (N a K_te / 2 pi) times feed: (sin phi_ex - sin phi_st) + K_re / K_te (cos phi_st
    - cos phi_ex), normal: (cos phi_st - cos phi_ex) - K_re / K_te (sin phi_ex - sin phi_st), tangential sum:
    phi_ex - phi_st. Returns (feed, normal) over the tangential sum; slotting (0, pi): (2 K_re / (pi K_te), 2 / pi)."""
    a, b = phi_start, phi_exit
    c, s = math.cos(a) - math.cos(b), math.sin(b) - math.sin(a)
    return (s + radial_ratio * c) / (b - a), (c - radial_ratio * s) / (b - a)


@dataclass(frozen=True, eq=False)
class FingerLoad:
    """The finger pass's cutting force [N] and torque [N m] as functions of the tip centre's face position.

    An end mill side-milling the space (its axis along the space's symmetry line, fed along the face): the removal
    rate is Q = v_f A, A the section the pass removes (:func:`finger_removed_areas`), at the mean chip thickness h_m
    of the pass's immersion (:func:`mean_forces`; the left pass slots the space, phi 0..pi, the right pass takes the
    clearance's strip a_e = c at the flank it finishes in down milling, phi pi - acos(1 - 2 c / D_m)..pi) and the
    cutting speed v_c = pi D_m n at the mean diameter D_m over the tooth depth. The oblique model on the teeth in
    cut (straight flutes with a radial face: rake and inclination 0; :func:`tooth_load`, the chip width
    Q / (v_c h_m)) gives the mean tangential force sum F_T (the teeth's cutting forces; the spindle torque
    F_T D_m / 2) and the teeth's thrust, normal to the finger's surface of revolution: its part normal to the axis is
    the teeth's radial force, its part along the axis pushes the tapered finger back from the root (:attr:`shares`).
    The resultant in the plane normal to the axis: Altintas' means over the immersion with each tooth's radial force
    K_r, the chip's (:func:`mean_forces`, K_r = f_t / f_c x the radial share) and the edge's (:func:`edge_means`):
    against the feed and normal to it, pushing the mill off the flank the pass finishes. The chip's part is taken at
    h_m (its share above h_min at the mean chip). Engagement: the share of the mill's front arc (x uniform across
    its mean diameter) within the face, so the force rises as the mill enters and falls as it leaves. The steady
    force of the pass, not the teeth's pulsation (4 teeth at 100 Hz). The job gives no edge radius: ``edge_radius``
    is the model's default."""

    gear: Gear
    mill: FingerMill
    material: Material
    feed: float  # mm/min
    speed: float  # rpm
    clearance: float  # mm
    edge_radius: float = DEFAULT_EDGE_RADIUS

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
        """[phi_st, phi_ex] [rad] of the ``side`` pass (Altintas' immersion, phi = 0 where a tooth enters in up
        milling): slotting for the left; for the right the clearance's strip, which lies on the down-milling side
        (the spindle turns the same way in both passes and the feed reverses: the side :meth:`force` pushes the mill
        off with a positive normal force), pi - acos(1 - c / R_m)..pi."""
        if side == "left":
            return 0.0, math.pi
        return math.pi - math.acos(max(1.0 - self.clearance / self.mean_radius, -1.0)), math.pi

    def chip_thickness(self, side: str) -> float:
        """Mean chip thickness h_m [mm] of the ``side`` pass."""
        return mean_forces(*self.immersion(side), 0.0)[2] * self.feed_per_tooth

    @property
    def model(self) -> ObliqueForces:
        """The material's oblique model for the teeth's edge radius."""
        return material_forces(self.material, self.edge_radius)

    def section(self, side: str) -> float:
        """The mean chip section in cut [mm^2] of the ``side`` pass in full engagement: Q / v_c = A v_f / v_c."""
        vf = self.feed / 60.0  # mm/s
        vc = math.pi * 2 * self.mean_radius * self.speed / 60.0  # mm/s
        return self.areas[side] * vf / vc

    def load(self, side: str) -> ToothLoad:
        """The teeth's mean forces [N] of the ``side`` pass in full engagement (:func:`tooth_load` at h_m)."""
        return tooth_load(self.model, self.chip_thickness(side), self.section(side))

    def main_force(self, side: str) -> float:
        """F_T [N] of the ``side`` pass in full engagement: the teeth's cutting forces' sum (tangential)."""
        return self.load(side).cutting

    @cached_property
    def shares(self) -> tuple[float, float]:
        """(normal to the axis, along it): the mean over the tooth depth (each row v from the tip to the tip circle
        takes the same chip) of the finger surface's unit normal, 1 / sqrt(1 + rho'^2) and rho' / sqrt(1 + rho'^2):
        how the teeth's thrust splits into their radial force and a force along the axis, away from the root."""
        v = np.linspace(0.0, self.depth, 201)
        slope = np.gradient(self.mill.rho(v), v)
        norm = np.sqrt(1.0 + slope**2)
        return float(np.mean(1.0 / norm)), float(np.mean(slope / norm))

    def axial(self, side: str) -> float:
        """The mean force [N] on the mill along its axis, away from the root (from its tip into it), in full
        engagement: the teeth's thrust x its share along the axis."""
        return self.load(side).thrust * self.shares[1]

    def torque(self, side: str) -> float:
        """Spindle torque [N m] of the ``side`` pass in full engagement: F_T D_m / 2."""
        return self.main_force(side) * self.mean_radius * 1e-3

    def components(self, side: str) -> tuple[float, float]:
        """(against the feed, normal to it) [N] in the plane normal to the axis in full engagement: the chip's and
        the edge's parts of the tangential sum, each with its radial force K_r (:func:`mean_forces`,
        :func:`edge_means`)."""
        ld, model = self.load(side), self.model
        fc, ft, _ = model.factors(MILL_RAKE, MILL_INCLINATION)
        ce, te = model.edge_coefficients
        radial = self.shares[0]
        chip_feed, chip_normal, _ = mean_forces(*self.immersion(side), radial * float(ft / fc))
        edge_feed, edge_normal = edge_means(*self.immersion(side), radial * te / ce if ce > 0 else 0.0)
        return (
            ld.shear[0] * chip_feed + ld.edge[0] * edge_feed,
            ld.shear[0] * chip_normal + ld.edge[0] * edge_normal,
        )

    def engagement(self, z: np.ndarray, direction: float) -> np.ndarray:
        """Share of the front arc within the face at tip-centre face positions ``z`` fed towards sign(direction) z."""
        d = np.sign(direction) * np.asarray(z, dtype=float)
        half, r = self.gear.face_width / 2, self.mean_radius
        a = np.sqrt(r**2 - np.clip(half - d, 0.0, r) ** 2)  # the arc's front beyond the far face: |x| < a
        b = np.sqrt(r**2 - np.clip(-half - d, 0.0, r) ** 2)  # still before the near face: |x| > b
        return np.clip((b - a) / r, 0.0, 1.0)

    def force(self, side: str, z: np.ndarray, direction: float) -> np.ndarray:
        """(n, 6) force on the mill [N] in the space frame (x tangential, y radial out, z) and the torque on it
        [N m] about the same axes: against the feed, normal pushing off the ``side`` flank, along the axis away from
        the root (:meth:`axial`), the cutting torque against the spindle's turn about the mill's axis (from its tip
        into it, (0, sense, 0))."""
        from cutting.form_milling.mill import flank_sign

        e = self.engagement(z, direction)
        feed, normal = self.components(side)
        out = np.zeros((len(e), 6))
        out[:, 0] = -flank_sign(self.gear, side) * normal * e  # type: ignore[arg-type]
        out[:, 1] = self.gear.sense * self.axial(side) * e
        out[:, 2] = -np.sign(direction) * feed * e
        out[:, 4] = -self.gear.sense * self.torque(side) * e
        return out
