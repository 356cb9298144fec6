"""Cutting forces of one tooth engagement from the chip the removal really took (Kienzle's law).

The edge is the outline polygon without its hub chord. During the engagement [t0, t1] the part of the edge
inside the blank's envelope cuts: in skiving every pass takes a U-shaped layer along the whole engaged
profile (both flanks and the bottom), so that part is the chip's width b(t). Each edge element dl moving at
the relative speed v sweeps dl * v of chip area per second, so the chip volume is

    V = h * integral( integral(|v| dl) dt )

which gives the mean uncut chip thickness h of this engagement from the removed volume V. The force on the
workpiece at each instant is Kienzle's  Fc = kc(h) * b * h  distributed along the engaged edge, each element
pushing the material along its own velocity (the tool drags the chip with it); the cutter feels the opposite.
Its work over the engagement is exactly kc(h) * V: the chip's specific energy times its volume.

:func:`engagement_load` with a :class:`cutting.oblique.ObliqueForces` model (the run's) gives each engaged edge
element the three components of oblique cutting (cutting along its velocity, thrust normal to the cut surface,
passive along the edge) at the element's own working normal rake and inclination (:func:`oblique_sums`), with the
rounded edge's ploughing; with a :class:`cutting.materials.Material` alone, Kienzle's main force at a fixed rake.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numba import njit

from cutting.materials import Material, rake_factor
from cutting.oblique import ObliqueForces
from cutting.skiving.sweep import PoseFunction, place, place_few


@dataclass
class EngagementLoad:
    """The load on the workpiece over one engagement, in the blank frame: the resultant ``force`` (n, 3) [N] at
    ``point`` (n, 3) [mm] (the engaged edge's centroid) and the ``moment`` (n, 3) [N m] of the distributed
    forces about that point, at times ``t`` (n,) [s]. For rigid bodies the wrench does the same work as the
    forces along the edge. The cutter takes the opposite wrench."""

    t: np.ndarray
    force: np.ndarray
    point: np.ndarray
    moment: np.ndarray
    volume: float  # chip volume [mm^3]
    thickness: float  # mean uncut chip thickness h [mm]
    kc: float  # specific cutting force used [N/mm^2] (oblique: the chip's work over its volume)
    #: (n, 3) [N]: the sums of the elements' cutting, thrust and passive components (oblique model only)
    components: np.ndarray | None = None
    #: the chip volume the force model took over the engagement [mm^3] (the chip of the moment's; None: ``volume``)
    model_volume: float | None = None

    @property
    def energy(self) -> float:
        """Cutting work of the engagement [J]: kc [N/mm^2] * V [mm^3] = N mm."""
        return self.kc * self.volume * 1e-3

    def peak(self) -> float:
        return float(np.linalg.norm(self.force, axis=1).max()) if len(self.t) else 0.0

    def shifted(self, dt: float) -> EngagementLoad:
        """The same load ``dt`` seconds later (the prediction for the next tooth: one cutter pitch on)."""
        return EngagementLoad(
            self.t + dt, self.force, self.point, self.moment, self.volume, self.thickness, self.kc, self.components,
            self.model_volume,
        )  # fmt: skip


def engaged_speed(
    pose: PoseFunction, edge: np.ndarray, times: np.ndarray, inside: Callable[[np.ndarray], np.ndarray]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per time and edge element: the element's length inside the blank [mm], its midpoint [mm] and its velocity
    relative to the workpiece [mm/s] (central difference over 1e-3 of the sampling interval)."""
    step = 1e-3 * (times[-1] - times[0]) / max(len(times) - 1, 1)
    n = len(times)
    placed = place(edge, *pose(np.concatenate([times, times - step, times + step])))  # one pose call: 3 n times
    w, w_before, w_after = placed[:n], placed[n : 2 * n], placed[2 * n :]
    a, b = w[:, :-1], w[:, 1:]
    mid = (a + b) / 2
    ins = inside(w).astype(float)
    share = (ins[:, :-1] + ins[:, 1:]) / 2  # an element half in the blank counts half
    length = np.linalg.norm(b - a, axis=2) * share
    vel = ((w_after[:, :-1] + w_after[:, 1:]) - (w_before[:, :-1] + w_before[:, 1:])) / (4 * step)
    return length, mid, vel


def engagement_load(
    pose: PoseFunction,
    edge: np.ndarray,
    t0: float,
    t1: float,
    volume: float,
    material: Material | ObliqueForces,
    inside: Callable[[np.ndarray], np.ndarray],
    rake_deg: float = 0.0,
    samples: int = 41,
    thickness: float | None = None,
    faces: EdgeFaces | None = None,
) -> EngagementLoad:
    """The load of one engagement: ``pose`` of the cutting tooth over [t0, t1], ``edge`` its points (n, 3) in the
    cutter frame (the cutting edge, an open polyline), ``volume`` [mm^3] the chip the removal took, ``inside``
    the blank's envelope (points -> bool). ``rake_deg``: the cutter's rake angle (0: rake face on the end plane).
    ``thickness`` [mm]: the chip's mean uncut thickness where the removal measured it (the dexel chip's, normal
    to the cut surface over its footprint); it sets kc(h), while the force along the edge stays scaled so that the
    engagement's work is kc(h) V. Without it, h is the volume over the area the engaged edge sweeps.

    ``material`` an :class:`ObliqueForces` model (with ``faces``, the edge's rake face and body side): the three
    components per element (:func:`oblique_load`); ``rake_deg`` is then moot (each element has its working rake).
    """
    if isinstance(material, ObliqueForces):
        if faces is None:
            raise ValueError("the oblique model needs the edge's faces (EdgeFaces)")
        return oblique_load(pose, edge, t0, t1, volume, material, inside, faces, samples, thickness)
    times = np.linspace(t0, t1, samples)
    step = 1e-3 * (times[-1] - times[0]) / max(len(times) - 1, 1)
    # the edge at the times and a central difference's step either side: one pose call (the co-simulation makes
    # one of these per engagement, so the sums below are compiled)
    placed = place_few(edge, *pose(np.concatenate([times, times - step, times + step])))
    ins = inside(placed[:samples]).astype(float)
    swept, unit_force, point, unit_moment = engagement_sums(placed, ins, times, step)
    if volume <= 0 or swept <= 0:
        zero = np.zeros((0, 3))
        return EngagementLoad(np.zeros(0), zero, zero, zero, max(volume, 0.0), 0.0, 0.0)
    h = volume / swept  # the layer the engaged edge would take if it cut all along
    h_chip = thickness if thickness is not None and thickness > 0 else h
    kc = material.kc(h_chip) * rake_factor(rake_deg)
    # each element pushes kc h dl along its velocity: the resultant and moment are kc h times the unit sums
    force = kc * h * unit_force  # [N] on the workpiece
    moment = kc * h * unit_moment * 1e-3  # N mm -> N m
    return EngagementLoad(times, force, point, moment, volume, h_chip, kc)


@njit(cache=True, error_model="numpy")
def engagement_sums(placed, ins, times, step):
    """For :func:`engagement_load` (as :func:`engaged_speed` and the sums over its elements): the chip area the
    engaged edge sweeps [mm^2] (trapezoid rule over ``times``) and per time the sum of dl * (unit velocity), the
    engaged edge's centroid (length-weighted element midpoints) and the moment of the dl * unit velocity about it
    [mm^2]. ``placed``: the edge at times, at times - step, at times + step (3 n, k, 3); ``ins``: (n, k) 1.0 where a
    point at ``times`` is inside the blank's envelope."""
    n, k = ins.shape
    force = np.zeros((n, 3))
    point = np.zeros((n, 3))
    moment = np.zeros((n, 3))
    rate = np.zeros(n)
    length = np.empty(k - 1)
    mid = np.empty((k - 1, 3))
    fe = np.empty((k - 1, 3))
    for i in range(n):
        weight = 0.0
        for j in range(k - 1):
            share = (ins[i, j] + ins[i, j + 1]) / 2  # an element half in the blank counts half
            dx = placed[i, j + 1, 0] - placed[i, j, 0]
            dy = placed[i, j + 1, 1] - placed[i, j, 1]
            dz = placed[i, j + 1, 2] - placed[i, j, 2]
            length[j] = math.sqrt(dx * dx + dy * dy + dz * dz) * share
            for c in range(3):
                mid[j, c] = (placed[i, j, c] + placed[i, j + 1, c]) / 2
                after = placed[2 * n + i, j, c] + placed[2 * n + i, j + 1, c]
                before = placed[n + i, j, c] + placed[n + i, j + 1, c]
                fe[j, c] = (after - before) / (4 * step)  # the element's velocity, scaled below
            speed = math.sqrt(fe[j, 0] ** 2 + fe[j, 1] ** 2 + fe[j, 2] ** 2)
            rate[i] += length[j] * speed
            for c in range(3):
                fe[j, c] *= length[j] / max(speed, 1e-12)
                force[i, c] += fe[j, c]
                point[i, c] += length[j] * mid[j, c]
            weight += length[j]
        for c in range(3):
            point[i, c] /= max(weight, 1e-12)
        for j in range(k - 1):
            r0, r1, r2 = mid[j, 0] - point[i, 0], mid[j, 1] - point[i, 1], mid[j, 2] - point[i, 2]
            moment[i, 0] += r1 * fe[j, 2] - r2 * fe[j, 1]
            moment[i, 1] += r2 * fe[j, 0] - r0 * fe[j, 2]
            moment[i, 2] += r0 * fe[j, 1] - r1 * fe[j, 0]
    swept = 0.0
    for i in range(n - 1):
        swept += (rate[i + 1] + rate[i]) / 2 * (times[i + 1] - times[i])
    return swept, force, point, moment


@dataclass(frozen=True)
class EdgeFaces:
    """What the oblique model needs of the edge beside its points (rake frame): the rake face's unit normal towards
    the chip ``rake`` (3,) and, per element (k - 1, 3), a unit direction into the tooth's body ``body`` (the side of
    the cut surface the tool is on: the thrust pushes the workpiece away from it)."""

    rake: np.ndarray
    body: np.ndarray

    @classmethod
    def of_outline(cls, points: np.ndarray, rake: np.ndarray) -> EdgeFaces:
        """The faces of a tooth outline ``points`` (k, 3) in its rake plane (z = 0): the body lies towards the
        outline's centroid (the tooth between its flanks and under its tip), the rake normal as given."""
        p = np.asarray(points, dtype=float)
        d = np.diff(p, axis=0)
        normal = np.column_stack([-d[:, 1], d[:, 0], np.zeros(len(d))])
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        inward = p.mean(axis=0) - (p[:-1] + p[1:]) / 2
        normal *= np.where(np.sum(normal * inward, axis=1) < 0, -1.0, 1.0)[:, None]
        r = np.asarray(rake, dtype=float)
        return cls(r / np.linalg.norm(r), np.ascontiguousarray(normal))


def oblique_load(
    pose: PoseFunction,
    edge: np.ndarray,
    t0: float,
    t1: float,
    volume: float,
    model: ObliqueForces,
    inside: Callable[[np.ndarray], np.ndarray],
    faces: EdgeFaces,
    samples: int = 41,
    thickness: float | None = None,
) -> EngagementLoad:
    """:func:`engagement_load` with the oblique model: per engaged element its working normal rake gamma_n and
    inclination lambda_s from the rake face and its velocity relative to the workpiece, its chip width
    b = dl cos(lambda_s) and the mean thickness h = V / (the area the engaged edge sweeps normal to the velocity);
    the element takes ``model.element`` (cutting along its velocity, thrust normal to the cut surface away from the
    body, passive along the edge's part normal to the velocity). ``thickness`` (the dexel chip's mean normal
    thickness) sets the coefficients' size effect and the share under the minimum chip; h sets the volume, so that
    the shear work is K_c V (1 - h_min / h_chip) plus the edge's ploughing."""
    times = np.linspace(t0, t1, samples)
    step = 1e-3 * (times[-1] - times[0]) / max(len(times) - 1, 1)
    rot, trans = pose(np.concatenate([times, times - step, times + step]))
    placed = place_few(edge, rot, trans)
    ins = inside(placed[:samples]).astype(float)
    c = model.model
    swept, width, mid, dirs, factors, speed = oblique_sums(
        placed, ins, np.ascontiguousarray(rot[:samples]), times, step, faces.rake, faces.body,
        c.friction_angle, c.rake_floor,
    )  # fmt: skip
    if volume <= 0 or swept <= 0:
        zero = np.zeros((0, 3))
        return EngagementLoad(np.zeros(0), zero, zero, zero, max(volume, 0.0), 0.0, 0.0, zero)
    h = volume / swept
    h_chip = thickness if thickness is not None and thickness > 0 else h
    tau = float(model.shear_stress(h_chip))
    sheared = h * max(1.0 - model.min_chip / h_chip, 0.0)
    ce, te = model.edge_coefficients
    force, point, moment, components, work = assemble(width, mid, dirs, factors, speed, times, tau * sheared, ce, te)
    return EngagementLoad(times, force, point, moment, volume, h_chip, work / volume * 1e3, components)


@njit(cache=True, error_model="numpy")
def oblique_sums(placed, ins, rot, times, step, rake, body, friction, floor):
    """For :func:`oblique_load`: the area the engaged edge sweeps normal to the velocities [mm^2] and per (time,
    element): its chip width b = dl cos(lambda_s) x its share in the blank [mm], its midpoint, its directions
    (cutting v, cut-surface normal n towards the body, passive p), the oblique factors (K_c, K_t, K_p) / tau_s at its
    working normal rake and inclination (cutting.oblique.ObliqueForces.factors, with Merchant's shear angle) and its
    speed [mm/s]. ``rot`` (n, 3, 3): the rake frame's rotations at ``times``; ``rake`` (3,), ``body`` (k - 1, 3) in
    the rake frame. Scalars only inside the loops: it runs once per engagement."""
    n, k = ins.shape
    e = k - 1
    width = np.zeros((n, e))
    mid = np.zeros((n, e, 3))
    dirs = np.zeros((n, e, 3, 3))
    factors = np.zeros((n, e, 3))
    speeds = np.zeros((n, e))
    tan_beta = math.tan(friction)
    rate = np.zeros(n)
    for i in range(n):
        r = rot[i]
        g0 = r[0, 0] * rake[0] + r[0, 1] * rake[1] + r[0, 2] * rake[2]
        g1 = r[1, 0] * rake[0] + r[1, 1] * rake[1] + r[1, 2] * rake[2]
        g2 = r[2, 0] * rake[0] + r[2, 1] * rake[1] + r[2, 2] * rake[2]
        for j in range(e):
            share = (ins[i, j] + ins[i, j + 1]) / 2
            if share <= 0:  # outside the blank: no chip, no force (most of the edge most of the time)
                continue
            tx = placed[i, j + 1, 0] - placed[i, j, 0]
            ty = placed[i, j + 1, 1] - placed[i, j, 1]
            tz = placed[i, j + 1, 2] - placed[i, j, 2]
            mid[i, j, 0] = (placed[i, j, 0] + placed[i, j + 1, 0]) / 2
            mid[i, j, 1] = (placed[i, j, 1] + placed[i, j + 1, 1]) / 2
            mid[i, j, 2] = (placed[i, j, 2] + placed[i, j + 1, 2]) / 2
            vx = placed[2 * n + i, j, 0] + placed[2 * n + i, j + 1, 0] - placed[n + i, j, 0] - placed[n + i, j + 1, 0]
            vy = placed[2 * n + i, j, 1] + placed[2 * n + i, j + 1, 1] - placed[n + i, j, 1] - placed[n + i, j + 1, 1]
            vz = placed[2 * n + i, j, 2] + placed[2 * n + i, j + 1, 2] - placed[n + i, j, 2] - placed[n + i, j + 1, 2]
            vx, vy, vz = vx / (4 * step), vy / (4 * step), vz / (4 * step)
            dl = math.sqrt(tx * tx + ty * ty + tz * tz)
            speed = math.sqrt(vx * vx + vy * vy + vz * vz)
            if dl <= 0 or speed <= 0:
                continue
            tx, ty, tz = tx / dl, ty / dl, tz / dl
            vx, vy, vz = vx / speed, vy / speed, vz / speed
            along = tx * vx + ty * vy + tz * vz
            lam = math.asin(min(max(along, -1.0), 1.0))
            px, py, pz = tx - along * vx, ty - along * vy, tz - along * vz
            pn = math.sqrt(px * px + py * py + pz * pz)
            if pn <= 1e-12:  # the edge along its velocity: no chip
                continue
            px, py, pz = px / pn, py / pn, pz / pn
            nx, ny, nz = py * vz - pz * vy, pz * vx - px * vz, px * vy - py * vx
            b = body[j]
            bx = r[0, 0] * b[0] + r[0, 1] * b[1] + r[0, 2] * b[2]
            by = r[1, 0] * b[0] + r[1, 1] * b[1] + r[1, 2] * b[2]
            bz = r[2, 0] * b[0] + r[2, 1] * b[1] + r[2, 2] * b[2]
            if nx * bx + ny * by + nz * bz < 0:
                nx, ny, nz = -nx, -ny, -nz
            # working normal rake in the plane normal to the edge: e1 = v's part normal to t, e2 = n (towards the body)
            ex, ey, ez = vx - along * tx, vy - along * ty, vz - along * tz
            en = math.sqrt(ex * ex + ey * ey + ez * ez)
            gamma = max(math.atan2(g0 * nx + g1 * ny + g2 * nz, (g0 * ex + g1 * ey + g2 * ez) / en), floor)
            beta_n = math.atan(tan_beta * math.cos(lam))
            phi = math.pi / 4 - (beta_n - gamma) / 2
            te = math.tan(lam)
            s = math.sqrt(math.cos(phi + beta_n - gamma) ** 2 + (te * math.sin(beta_n)) ** 2)
            base = 1.0 / (math.sin(phi) * s)
            factors[i, j, 0] = base * (math.cos(beta_n - gamma) + te * te * math.sin(beta_n))
            factors[i, j, 1] = base * math.sin(beta_n - gamma) / math.cos(lam)
            factors[i, j, 2] = base * (math.cos(beta_n - gamma) * te - te * math.sin(beta_n))
            width[i, j] = dl * math.cos(lam) * share
            speeds[i, j] = speed
            rate[i] += width[i, j] * speed
            dirs[i, j, 0, 0], dirs[i, j, 0, 1], dirs[i, j, 0, 2] = vx, vy, vz
            dirs[i, j, 1, 0], dirs[i, j, 1, 1], dirs[i, j, 1, 2] = nx, ny, nz
            dirs[i, j, 2, 0], dirs[i, j, 2, 1], dirs[i, j, 2, 2] = px, py, pz
    swept = 0.0
    for i in range(n - 1):
        swept += (rate[i + 1] + rate[i]) / 2 * (times[i + 1] - times[i])
    return swept, width, mid, dirs, factors, speeds


@njit(cache=True)
def element_force(fc, ft, fp, directions, out) -> float:
    """One element's force on the workpiece into ``out`` (3,) from its cutting, thrust and passive components [N]
    and its ``directions`` (3, 3): cutting along v, thrust along -n (away from the tool's body), passive along p;
    returns its magnitude [N]."""
    mag = 0.0
    for c in range(3):
        out[c] = fc * directions[0, c] - ft * directions[1, c] + fp * directions[2, c]
        mag += out[c] * out[c]
    return math.sqrt(mag)


@njit(cache=True, error_model="numpy")
def assemble(width, mid, dirs, factors, speeds, times, shear, ce, te):
    """For :func:`oblique_load`, per time: the resultant force on the workpiece [N] of the elements (each
    shear f b + the edge's K_ce b, K_te b; ``shear`` = tau_s (h - h_min) [N/mm^2 x mm]), its force-weighted point
    [mm] (the engaged elements' mean where no force acts), the moment about it [N m] and the sums of the cutting,
    thrust and passive components [N]; and the cutting components' work over the engagement [J] (element speeds
    ``speeds`` [mm/s], trapezoid rule over ``times``). On the workpiece: cutting along v, thrust along -n, passive
    along p."""
    n, e = width.shape
    force = np.zeros((n, 3))
    point = np.zeros((n, 3))
    moment = np.zeros((n, 3))
    comp = np.zeros((n, 3))
    power = np.zeros(n)
    fe = np.zeros((e, 3))
    for i in range(n):
        weight = 0.0
        count = 0.0
        plain = np.zeros(3)
        for j in range(e):
            b = width[i, j]
            if b <= 0:
                for c in range(3):
                    fe[j, c] = 0.0
                continue
            fc = shear * factors[i, j, 0] * b + ce * b
            ft = shear * factors[i, j, 1] * b + te * b
            fp = shear * factors[i, j, 2] * b
            comp[i, 0] += fc
            comp[i, 1] += ft
            comp[i, 2] += fp
            power[i] += fc * speeds[i, j]
            mag = element_force(fc, ft, fp, dirs[i, j], fe[j])
            for c in range(3):
                force[i, c] += fe[j, c]
            weight += mag
            count += 1.0
            for c in range(3):
                point[i, c] += mag * mid[i, j, c]
                plain[c] += mid[i, j, c]
        for c in range(3):
            point[i, c] = point[i, c] / weight if weight > 0 else (plain[c] / count if count > 0 else 0.0)
        for j in range(e):
            if width[i, j] <= 0:
                continue
            r0, r1, r2 = mid[i, j, 0] - point[i, 0], mid[i, j, 1] - point[i, 1], mid[i, j, 2] - point[i, 2]
            moment[i, 0] += (r1 * fe[j, 2] - r2 * fe[j, 1]) * 1e-3
            moment[i, 1] += (r2 * fe[j, 0] - r0 * fe[j, 2]) * 1e-3
            moment[i, 2] += (r0 * fe[j, 1] - r1 * fe[j, 0]) * 1e-3
    work = 0.0
    for i in range(n - 1):
        work += (power[i + 1] + power[i]) / 2 * (times[i + 1] - times[i])
    return force, point, moment, comp, work * 1e-3
