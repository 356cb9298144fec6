"""The cutting force of the face-contour machine's elements (seed 004, continuous indexing): the chip each element
takes at each head angle and, per edge segment (the tip edge, the two flanks), the oblique model's cutting, thrust
and passive components at the segment's working rake and inclination (:mod:`cutting.oblique`, the skiving machine's
model; how the element maps onto it: docs/forces.md, "The other machines").

These forces are how the machine's drives feel the cut: :func:`chip` is the layer and the section an element takes
(their derivation there), :func:`element_forces` the forces and the torques they put on the head and the work,
:class:`FaceLoad` the tables the simulation reads every servo tick, :func:`sizing` the motors' torques the heaviest
pass needs. The measured forces and what they do to the slots: docs/face-contours-and-turning.md, "Cutting forces on
the face machine".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np
from scipy.optimize import brentq

from cutting.face_contour.slots import FaceCoupling, bisect_roots, element_path, path_velocity, tip_position, tool_frame
from cutting.materials import Material
from cutting.oblique import DEFAULT_EDGE_RADIUS, element_directions, material_forces

__all__ = [
    "Chip",
    "ElementForce",
    "FaceLoad",
    "Segment",
    "chip",
    "element_forces",
    "infeed",
    "previous_offset",
    "segments",
    "sizing",
]


def infeed(c: FaceCoupling, phi: np.ndarray | float) -> np.ndarray:
    """The programmed infeed f(phi) = clip(S phi / 2 pi, 0, depth) [mm] at head angle phi (the electronic
    gearbox's Z, gated at the depth)."""
    return np.clip(c.S * np.asarray(phi, dtype=float) / (2 * math.pi), 0.0, c.depth)


def previous_offset(c: FaceCoupling, element: int) -> float:
    """The head angle [rad] back to the pass before element ``element``'s over the same place (the same element
    psi): beta_i - beta_j to the element i passing just before it in the turn (larger beta passes first); for the
    first element (the largest beta) 2 pi m - (beta_j - beta_min), to the last element of the turn one workpiece
    revolution earlier."""
    beta = c.phases
    bj = float(beta[element])
    earlier = beta[beta > bj]
    if earlier.size:
        return float(earlier.min() - bj)
    return 2 * math.pi * c.m - float(bj - beta.min())


@dataclass(frozen=True)
class Chip:
    """Element j's chip at head angles phi (arrays of phi's shape): the tip's depth below the face ``d``, the layer
    ``layer`` (Delta, before clipping) and ``removed`` (Delta_e), the angle ``theta`` of V to the face [rad], the
    tip edge's thickness ``h_tip`` (width ``edge_width``), a flank's thickness ``h_flank`` and length ``b_flank``,
    and the section's area [mm^2] (all mm)."""

    d: np.ndarray
    layer: np.ndarray
    removed: np.ndarray
    theta: np.ndarray
    h_tip: np.ndarray
    h_flank: np.ndarray
    b_flank: np.ndarray
    area: np.ndarray
    edge_width: float


def chip(c: FaceCoupling, phi: np.ndarray | float, element: int = 0) -> Chip:
    """The chip of element ``element`` at head angles ``phi`` (absolute: 2 pi per tool turn from the programme's
    start, where f = 0).

    **The layer.** Element j's tip follows :func:`cutting.face_contour.slots.element_path` (eq. 5) with the machine's
    infeed in place of the seed's feed term: the electronic gearbox lowers the head by f(phi) = min(S phi / 2 pi,
    depth) (S per tool revolution, gated at the depth, :func:`infeed`), so the tip is at z(phi) = z_final(phi) +
    depth - f(phi), z_final the spark-out pass of :func:`~cutting.face_contour.slots.element_path` (``final=True``).
    The xy motion repeats every workpiece revolution (m tool revolutions: eq. 11 and the controls all have the period
    2 pi in phi), so the pass over the same slot one workpiece revolution earlier, at phi - 2 pi m, ran the same xy
    path higher by the layer

        Delta(phi) = f(phi) - f(phi - 2 pi m):  m S in the plunge, the remainder depth - S (phi / 2 pi - m) in the
        spark-out (a different one per slot, from m S down to 0 over the workpiece revolution), 0 after it.

    With several elements the pass before element j's is the element passing just before it in the same tool turn
    (larger phase beta first; element j's own psi = phi + beta_j at phi - (beta_i - beta_j)), for the first element
    the last one of the turn m revolutions before (:func:`previous_offset`); the small lateral offset
    (beta_i - beta_j) / m between their paths is neglected (the layer is taken vertical, on the same xy path). The
    material above the tip at phi is what neither that pass nor the face left: d = -z(phi) below the face, the layer
    clipped to d: Delta_e = clip(Delta, 0, d), and none where the tip is off the annular face (its radius outside
    ``inner_radius``..``outer_radius``).

    **The chip.** In the section across the slot (the tool axis n and the vertical) the element is a plate with a
    straight tip edge of width w = ``edge_width`` and flanks opening by kappa = ``flank_angle``. The section it
    removes is the trapezoid between its present and its earlier position, Delta_e (w + (2 d - Delta_e) tan kappa):
    the tip edge takes a chip of width w and thickness Delta_e, each flank one of thickness Delta_e sin kappa (the
    layer normal to the flank) over the length (d - Delta_e / 2) / cos kappa (from mid-corner to the face: the
    corner triangle counted at half its height, so the areas add up exactly). V is inclined by theta to the face (the
    tool circle at psi), so the thicknesses normal to V are these times cos theta.
    """
    phi = np.asarray(phi, dtype=float)
    path = element_path(c, phi, element, final=True)
    d = -(path[..., 2] + c.depth - infeed(c, phi))
    layer = infeed(c, phi) - infeed(c, phi - previous_offset(c, element))
    radius = np.linalg.norm(path[..., :2], axis=-1)
    on_face = (radius >= c.inner_radius) & (radius <= c.outer_radius)
    removed = np.where(on_face, np.clip(np.minimum(layer, d), 0.0, None), 0.0)
    v = path_velocity(c, phi, element)
    theta = np.arctan2(np.abs(v[..., 2]), np.linalg.norm(v[..., :2], axis=-1))
    k = c.flank_angle
    h_tip = removed * np.cos(theta)
    b_flank = np.where(removed > 0, (d - 0.5 * removed) / math.cos(k), 0.0)
    area = removed * (c.edge_width + (2 * d - removed) * math.tan(k))
    return Chip(d, layer, removed, theta, h_tip, h_tip * math.sin(k), b_flank, area, c.edge_width)


@dataclass(frozen=True)
class Segment:
    """One edge segment of an element at head angles phi (arrays of phi's shape, (..., 3) for directions, in the
    workpiece frame): the unit cutting direction ``v`` (V's), the cut surface's normal ``n`` towards the element, the
    passive direction ``p`` (the edge's part normal to V), the working normal ``rake`` and ``inclination`` [rad]."""

    v: np.ndarray
    n: np.ndarray
    p: np.ndarray
    rake: np.ndarray
    inclination: np.ndarray


def segments(c: FaceCoupling, phi: np.ndarray | float, element: int = 0) -> tuple[Segment, Segment, Segment]:
    """The tip edge and the flanks on the tool axis's +n and -n sides of element ``element`` at head angles phi:
    their directions and working angles (ISO 3002, as the skiving edge's: :func:`cutting.oblique.element_directions`,
    rake gamma_n = atan2(g . n, g . e1), e1 V's part normal to the edge).

    The element is a plate in the plane of the tool axis n and the head's radius rho
    (:func:`~cutting.face_contour.slots.plate_corners`); the job gives it no rake, so its face, the rake face, is the
    plate: normal to the tip's motion on the tool circle, g = cos psi u + sin psi z (0 deg rake to the head's turning).
    The tip edge runs along n, the flanks up from its corners along -rho cos kappa +- n sin kappa (kappa the flank
    angle). The relative velocity V (:func:`~cutting.face_contour.slots.path_velocity`, the tip's for all three: the
    flanks' points turn on radii within 2.5 % of R) adds the work's turning to the head's, so the segments cut at a
    small working rake and inclination: at M (V radial, the tool plane at the setting angle lambda to it) the tip edge
    at rake 0 and inclination lambda, the flanks at rake +-atan(tan lambda cos kappa) and inclination
    +-asin(sin kappa sin lambda)."""
    phi = np.asarray(phi, dtype=float)
    u2, n2 = tool_frame(c, phi)[:2]
    pad = np.zeros((*u2.shape[:-1], 1))
    u, n = np.concatenate([u2, pad], axis=-1), np.concatenate([n2, pad], axis=-1)
    psi = (phi + float(c.phases[element]))[..., None]
    up = np.array([0.0, 0.0, 1.0])
    rho = np.sin(psi) * u - np.cos(psi) * up  # from the head's centre to the tip
    g = np.cos(psi) * u + np.sin(psi) * up  # the plate's normal towards the chip
    velocity = path_velocity(c, phi, element)
    ck, sk = math.cos(c.flank_angle), math.sin(c.flank_angle)
    edges = (  # (tangent, a direction into the plate from the segment)
        (n, -rho),
        (-ck * rho + sk * n, -sk * rho - ck * n),
        (-ck * rho - sk * n, -sk * rho + ck * n),
    )
    out = []
    for tangent, body in edges:
        v, normal, passive, lam = element_directions(tangent, velocity, body)
        t = tangent / np.linalg.norm(tangent, axis=-1, keepdims=True)
        e1 = v - np.sum(t * v, axis=-1, keepdims=True) * t
        rake = np.arctan2(np.sum(g * normal, axis=-1), np.sum(g * e1, axis=-1) / np.linalg.norm(e1, axis=-1))
        out.append(Segment(v, normal, passive, rake, lam))
    return out[0], out[1], out[2]


@dataclass(frozen=True)
class ElementForce:
    """Element j's forces at head angles phi: the sums over its segments of the cutting ``F_c``, thrust ``F_t`` and
    passive ``F_p`` components [N], the ``force`` on the tool in the workpiece frame (..., 3) [N], the ``tip`` there
    (..., 3) [mm], the torque ``head_torque`` the cut puts on the head about its axis against its turning [N m] and
    ``work_torque`` on the workpiece about its axis z [N m], and the ``chip``."""

    F_c: np.ndarray
    F_t: np.ndarray
    F_p: np.ndarray
    force: np.ndarray
    tip: np.ndarray
    head_torque: np.ndarray
    work_torque: np.ndarray
    chip: Chip

    @property
    def lift(self) -> np.ndarray:
        """The force on the tool out of the face (+z, along the infeed: what the infeed nut and MZ carry) [N]."""
        return self.force[..., 2]


def element_forces(
    c: FaceCoupling,
    material: Material,
    phi: np.ndarray | float,
    element: int = 0,
    edge_radius: float = DEFAULT_EDGE_RADIUS,
) -> ElementForce:
    """The oblique model's forces on element ``element``'s segments (:func:`segments`) at head angles phi, with the
    torques they put on the head (R times the force's component along the tip's circle, opposing the head's
    turning) and on the workpiece (tip x (-F), about z).

    Per segment of :func:`chip`: the tip edge takes h_tip over its width, each flank h_flank over b_flank; the chip
    width normal to V is the segment's length x cos(inclination) (the skiving element's); the model
    (:meth:`cutting.oblique.ObliqueForces.element`, the material's Kienzle row, edge radius ``edge_radius``: the job
    gives none, so the model's default) gives F_c, F_t, F_p at the segment's rake and inclination. On the tool
    (reversed on the workpiece, both at the tip): -F_c v + F_t n - F_p p, i.e. the cutting force against V, the
    thrust pushing the element off each surface it cuts (out of the face at the tip edge, off the slot's sides and
    up at the flanks) and the passive force along the edges. The chip is the nominal one at the head angle (the
    machine's deflections do not change it: no regeneration).
    """
    phi = np.asarray(phi, dtype=float)
    ch = chip(c, phi, element)
    model = material_forces(material, edge_radius)
    force = np.zeros((*phi.shape, 3))
    sums = [np.zeros(phi.shape) for _ in range(3)]
    cuts = ((ch.h_tip, c.edge_width), (ch.h_flank, ch.b_flank), (ch.h_flank, ch.b_flank))
    for seg, (h, length) in zip(segments(c, phi, element), cuts, strict=True):
        fc, ft, fp = model.element(h, length * np.cos(seg.inclination), seg.rake, seg.inclination)
        force += -fc[..., None] * seg.v + ft[..., None] * seg.n - fp[..., None] * seg.p
        for total, part in zip(sums, (fc, ft, fp), strict=True):
            total += part
    tip = element_path(c, phi, element, final=True)
    tip[..., 2] += c.depth - infeed(c, phi)
    u = tool_frame(c, phi)[0]
    psi = phi + float(c.phases[element])
    # the tip's direction of motion on the tool circle (head rotation only): cos psi u + sin psi z
    tangent = np.concatenate([np.cos(psi)[..., None] * u, np.sin(psi)[..., None]], axis=-1)
    head = -c.R * 1e-3 * np.einsum("...k,...k->...", force, tangent)
    work = -1e-3 * (tip[..., 0] * force[..., 1] - tip[..., 1] * force[..., 0])
    return ElementForce(*sums, force, tip, head, work, ch)


@dataclass(eq=False)
class FaceLoad:
    """The cutting forces of every element as the simulation asks for them: per tool turn, tables over the pass
    window (head angles relative to 2 pi turn, :attr:`local`) and their running integrals. ``at(phi, dphi)``
    gives the mean force over the head angles phi..phi + dphi (elements, 3) on the tool [N] in the workpiece frame:
    held for a servo tick it carries the tick's true impulse, so that the entry into the face (a step of the force
    where the tip crosses the inner radius) does not jitter by up to a tick from pass to pass."""

    coupling: FaceCoupling
    material: Material
    window: tuple[float, float]
    samples: int = 1201
    edge_radius: float = DEFAULT_EDGE_RADIUS
    _tables: dict[int, np.ndarray] = field(default_factory=dict, repr=False)
    _integrals: dict[int, np.ndarray] = field(default_factory=dict, repr=False)

    @cached_property
    def local(self) -> np.ndarray:
        """The tables' head angles relative to 2 pi turn: ``samples`` over the window, and 1e-9 rad either side of
        each angle where an element's tip crosses the face's inner or outer radius (the force's steps; the xy path,
        and so these angles, repeat every turn), so that the tables hold the steps sharp."""
        c = self.coupling
        base = np.linspace(self.window[0], self.window[1], self.samples)
        extra = [base]
        for j in range(c.elements):
            beta = float(c.phases[j])

            def radius(x: np.ndarray, beta: float = beta) -> np.ndarray:
                return np.linalg.norm(tip_position(c, x, beta, final=True)[0], axis=-1)

            r = radius(base)
            for edge in (c.inner_radius, c.outer_radius):
                g = r - edge
                k = np.flatnonzero(np.signbit(g[:-1]) != np.signbit(g[1:]))
                if k.size:
                    x = bisect_roots(lambda x, edge=edge: radius(x) - edge, base[k], base[k + 1], g[k])
                    extra += [x - 1e-9, x + 1e-9]
        return np.unique(np.concatenate(extra))

    def table(self, turn: int) -> np.ndarray:
        """The forces at turn ``turn``'s :attr:`local` angles, (elements, points, 3) [N]."""
        if turn not in self._tables:
            phi = 2 * math.pi * turn + self.local
            self._tables[turn] = np.stack(
                [
                    element_forces(self.coupling, self.material, phi, j, self.edge_radius).force
                    for j in range(self.coupling.elements)
                ]
            )
        return self._tables[turn]

    def integral(self, turn: int) -> np.ndarray:
        """The running integral of :meth:`table` over the head angle (trapezoids), (elements, points, 3) [N rad]."""
        if turn not in self._integrals:
            tab = self.table(turn)
            inner = 0.5 * np.diff(self.local)[None, :, None] * (tab[:, 1:] + tab[:, :-1])
            self._integrals[turn] = np.concatenate([np.zeros_like(tab[:, :1]), np.cumsum(inner, axis=1)], axis=1)
        return self._integrals[turn]

    def _cell(self, x: float) -> tuple[int, float]:
        grid = self.local
        i = int(np.clip(np.searchsorted(grid, x, side="right") - 1, 0, len(grid) - 2))
        return i, x - grid[i]

    def _running(self, turn: int, x: float) -> np.ndarray:
        """The integral from the window's start to x (relative to 2 pi turn), exact on the piecewise linear table."""
        grid, tab, cum = self.local, self.table(turn), self.integral(turn)
        if x <= grid[0]:
            return cum[:, 0]
        if x >= grid[-1]:
            return cum[:, -1]
        i, s = self._cell(x)
        slope = (tab[:, i + 1] - tab[:, i]) / (grid[i + 1] - grid[i])
        return cum[:, i] + s * tab[:, i] + 0.5 * s * s * slope

    def at(self, phi: float, dphi: float = 0.0) -> np.ndarray | None:
        """The mean force on the tool over head angles phi..phi + dphi [rad] (the value at phi for dphi = 0),
        (elements, 3) [N]; None when no pass's window meets the interval."""
        turn = round((phi + 0.5 * dphi) / (2 * math.pi))
        x0 = phi - 2 * math.pi * turn
        x1 = x0 + max(dphi, 0.0)
        if x1 <= self.window[0] or x0 >= self.window[1]:
            return None
        if x1 - x0 > 1e-12:
            return (self._running(turn, x1) - self._running(turn, x0)) / (x1 - x0)
        grid, tab = self.local, self.table(turn)
        i, s = self._cell(x0)
        w = s / (grid[i + 1] - grid[i])
        return (1 - w) * tab[:, i] + w * tab[:, i + 1]

    def passes(self, turn: int) -> list[ElementForce]:
        """Every element's :class:`ElementForce` over turn ``turn``'s window."""
        phi = 2 * math.pi * turn + self.local
        c = self.coupling
        return [element_forces(c, self.material, phi, j, self.edge_radius) for j in range(c.elements)]


def _peak(
    c: FaceCoupling, material: Material, window: tuple[float, float], edge_radius: float = DEFAULT_EDGE_RADIUS
) -> dict[str, float]:
    """The largest head torque, work torque, thrust (the force out of the face, :attr:`ElementForce.lift`) and F_c
    [N m, N m, N, N] of the cycle's deepest full passes (the turns around the plunge's end at depth / S, where the
    layer is still m S and the tip deepest), the elements' loads at each head angle added (they cut together)."""
    end = c.depth / c.S
    turns = {max(math.floor(end) + k, 0) for k in (-1, 0, 1)}
    local = np.linspace(window[0], window[1], 801)
    out = {"head": 0.0, "work": 0.0, "thrust": 0.0, "F_c": 0.0}
    for turn in turns:
        f = [element_forces(c, material, 2 * math.pi * turn + local, j, edge_radius) for j in range(c.elements)]
        for key, values in (
            ("head", [x.head_torque for x in f]),
            ("work", [x.work_torque for x in f]),
            ("thrust", [x.lift for x in f]),
            ("F_c", [x.F_c for x in f]),
        ):
            out[key] = max(out[key], float(np.max(np.abs(np.sum(values, axis=0)))))
    return out


def sizing(
    c: FaceCoupling,
    material: Material,
    window: tuple[float, float],
    motors: dict[str, tuple[float, float]],
    share: float,
    edge_radius: float = DEFAULT_EDGE_RADIUS,
) -> dict[str, dict[str, float]]:
    """The motors' torques the cycle's heaviest pass needs: per motor (``"MH"``, ``"MA"``, ``"MZ"``, each (torque
    per unit of its joint's load [N m per N m, or N m per N], peak torque [N m])) the torque needed, the peak,
    and, where it exceeds ``share`` of the peak, the largest feed S [mm/rev] that keeps it within (brentq on the
    model, 1e-6 mm); the peak F_c and thrust. Loads: the head torque (MH), the work torque (MA), the thrust (MZ).
    ``edge_radius`` [mm]: the elements' (:func:`element_forces`)."""
    loads = {"MH": "head", "MA": "work", "MZ": "thrust"}
    peak = _peak(c, material, window, edge_radius)
    out: dict[str, dict[str, float]] = {}
    for name, (per, limit) in motors.items():
        need = peak[loads[name]] * per
        row = {"needed_N_m": need, "peak_N_m": limit, "F_c_N": peak["F_c"], "thrust_N": peak["thrust"]}
        if need > share * limit:

            def excess(s: float, name: str = name, per: float = per, limit: float = limit) -> float:
                return _peak(replace(c, S=s), material, window, edge_radius)[loads[name]] * per - share * limit

            lo = 1e-6
            row["feed_mm"] = brentq(excess, lo, c.S, xtol=1e-6) if excess(lo) < 0 else 0.0
        out[name] = row
    return out
