"""Measuring the radial slots of a face coupling cut by continuous indexing (seed 004): bottom form, side lines and
slot spacing, on the slotted face the caller hands over.

What is measured, per slot k (centre line the radial line at 2 pi k / m; the nominal data is the
:class:`cutting.face_contour.slots.FaceCoupling`: m, L, the slotted face ``inner_radius``..``outer_radius``, the
depth): at the measuring radii (``MEASURING_POINTS`` from the inner to the outer radius)

- the slot bottom along the centre line (the lowest z the tip edge left over each point), its form: the largest
  deviation from the straight line through its ends, + concave (deeper inside), - convex, "flat" within
  ``FLAT_TOLERANCE``;
- the slot's sides at a height (default half the depth below the face): their tangential deviation from the nominal
  radial line through the side at the middle radius, and their bow from the straight line through their ends;
- the slot's centre at radius L (the middle of its sides there, the point M where V is radial), and from the
  centres of the measured slots the slot spacing: the angular pitch's deviation from 2 pi / m.

What is measured is a :class:`SlottedFace`: it answers where a slot's bottom and sides are. Two answer here: the
exact slot (:class:`cutting.face_contour.slots.ExactSlots`, roots on the elements' motion, to 1e-9 mm; the
recorded motion of the face-contour machine is measured the same way in
:mod:`virtual_machine.processes.face_contour.cnc`) and the manifold solid of the cut (:class:`SolidSlots`: vertical
rays for the bottom, a plane section for the sides). They agree within the sweep's chord tolerance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import manifold3d as mf
import numpy as np

from cutting.face_contour.slots import FaceCoupling, FaceCut

__all__ = [
    "FLAT_TOLERANCE",
    "MEASURING_POINTS",
    "SlotMeasure",
    "SlottedFace",
    "SolidSlots",
    "bottom_form",
    "measure_mesh",
    "measure_slots",
    "measuring_radii",
    "mesh_bottom",
    "mesh_sides",
    "side_lines",
    "slot_spacing",
]

#: a slot bottom whose form is within this [mm] is "flat"
FLAT_TOLERANCE = 2e-3
#: measuring points along a slot
MEASURING_POINTS = 41


@runtime_checkable
class SlottedFace(Protocol):
    """What the slot measurement probes: a slotted face in the workpiece frame (axis z, the face at z = 0)."""

    def bottom(self, radii: np.ndarray, slot: int) -> np.ndarray:
        """The bottom z [mm] of slot ``slot`` on its radial centre line at ``radii`` (NaN where none)."""
        ...

    def sides(self, radii: np.ndarray, height: float, slot: int) -> np.ndarray:
        """Polar angles [rad] of slot ``slot``'s sides at ``radii`` and z = ``height``, (2, n): the - side (towards
        smaller angles) and the + side."""
        ...


# ---------------------------------------------------------------------------------------------------- evaluation


def bottom_form(radii: np.ndarray, z: np.ndarray) -> tuple[float, str]:
    """The bottom's form [mm]: the largest deviation from the straight line through its ends, signed + where the
    bottom lies below that line (concave, deeper inside), - above (convex); and its name ("flat" within
    FLAT_TOLERANCE)."""
    line = z[0] + (z[-1] - z[0]) * (radii - radii[0]) / (radii[-1] - radii[0])
    d = line - z
    form = float(d[np.argmax(np.abs(d))])
    shape = "flat" if abs(form) <= FLAT_TOLERANCE else ("concave" if form > 0 else "convex")
    return form, shape


def side_lines(radii: np.ndarray, angles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per side (rows of ``angles``): the tangential deviation [mm] from the nominal radial line through the side at
    the middle radius (r sin(theta - theta_mid)), and the bow [mm]: the largest signed distance (+ towards larger
    angles) of the side from the straight line through its ends."""
    mid = len(radii) // 2
    dev = radii * np.sin(angles - angles[:, mid : mid + 1])
    pts = np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=-1)
    chord = pts[:, -1] - pts[:, 0]
    normal = np.stack([-chord[:, 1], chord[:, 0]], axis=-1) / np.linalg.norm(chord, axis=-1, keepdims=True)
    dist = np.einsum("sik,sk->si", pts - pts[:, :1], normal)
    bow = dist[np.arange(len(dist)), np.argmax(np.abs(dist), axis=1)]
    return dev, bow


@dataclass(frozen=True, eq=False)
class SlotMeasure:
    """One slot measured: ``radii`` [mm], ``bottom`` z [mm], ``form`` [mm] (+ concave) and ``shape``; ``sides``
    (2, n) polar angles [rad] at ``height``, their ``side_deviation`` (2, n) [mm] from the nominal radial lines and
    ``side_bow`` (2,) [mm]; ``centre`` the slot's angle at radius L [rad]."""

    slot: int
    radii: np.ndarray
    bottom: np.ndarray
    form: float
    shape: str
    height: float
    sides: np.ndarray
    side_deviation: np.ndarray
    side_bow: np.ndarray
    centre: float


def _evaluate(
    slot: int, radii: np.ndarray, height: float, bottom: np.ndarray, sides: np.ndarray, centre_sides: np.ndarray
) -> SlotMeasure:
    form, shape = bottom_form(radii, bottom)
    dev, bow = side_lines(radii, sides)
    return SlotMeasure(slot, radii, bottom, form, shape, height, sides, dev, bow, float(np.mean(centre_sides)))


def measuring_radii(c: FaceCoupling, points: int = MEASURING_POINTS) -> np.ndarray:
    """The measuring points' radii [mm] along a slot, from the inner to the outer radius of the slotted face."""
    return np.linspace(c.inner_radius, c.outer_radius, points)


def measure_slots(
    face: SlottedFace,
    c: FaceCoupling,
    slots: tuple[int, ...] = (0,),
    radii: np.ndarray | None = None,
    height: float | None = None,
) -> list[SlotMeasure]:
    """The slots ``slots`` of ``face`` measured against the coupling ``c``: bottom at ``radii`` (default
    :func:`measuring_radii`), sides at ``height`` (default half the depth) and the centre at radius L."""
    radii = measuring_radii(c) if radii is None else np.asarray(radii, dtype=float)
    height = -0.5 * c.depth if height is None else height
    out = []
    for k in slots:
        bottom = face.bottom(radii, k)
        sides = face.sides(radii, height, k)
        centre = face.sides(np.array([c.L]), height, k)[:, 0]
        out.append(_evaluate(k, radii, height, bottom, sides, centre))
    return out


def slot_spacing(c: FaceCoupling, measures: list[SlotMeasure]) -> np.ndarray:
    """Deviations [rad] of the angular pitch between consecutive measured slots from 2 pi / m (per slot number
    step)."""
    k = np.array([s.slot for s in measures], dtype=float)
    a = np.array([s.centre for s in measures])
    return np.diff(a) / np.diff(k) - 2 * math.pi / c.m


# ---------------------------------------------------------------------------------------------------- the solid


def mesh_bottom(solid: mf.Manifold, c: FaceCoupling, radii: np.ndarray, slot: int = 0) -> np.ndarray:
    """The slot bottom z [mm] on the solid: a vertical ray down slot ``slot``'s centre line at each radius, its
    first hit."""
    turn = 2 * math.pi * slot / c.m
    top, bottom = 1.0, -(c.depth + 10.0)
    out = np.full(len(radii), np.nan)
    for i, r in enumerate(np.asarray(radii, dtype=float)):
        x, y = r * math.cos(turn), r * math.sin(turn)
        hits = solid.ray_cast((x, y, top), (x, y, bottom))
        if hits:
            out[i] = top + hits[0].distance * (bottom - top)
    return out


def mesh_sides(solid: mf.Manifold, c: FaceCoupling, radii: np.ndarray, height: float, slot: int = 0) -> np.ndarray:
    """Polar angles [rad] of slot ``slot``'s sides at ``radii`` on the solid's plane section at z = ``height``,
    (2, n): the section's edges crossing each circle r, the nearest crossing either side of the slot's centre line."""
    turn = 2 * math.pi * slot / c.m
    polys = solid.slice(height).to_polygons()
    a = np.vstack(polys)
    b = np.vstack([np.roll(p, -1, axis=0) for p in polys])
    d = b - a
    out = np.full((2, len(radii)), np.nan)
    for i, r in enumerate(np.asarray(radii, dtype=float)):
        # |a + t d|^2 = r^2, t in [0, 1]
        qa, qb, qc = np.einsum("ij,ij->i", d, d), 2 * np.einsum("ij,ij->i", a, d), np.einsum("ij,ij->i", a, a) - r * r
        disc = qb * qb - 4 * qa * qc
        ok = disc >= 0
        ts = []
        for sgn in (-1.0, 1.0):
            t = (-qb[ok] + sgn * np.sqrt(disc[ok])) / (2 * qa[ok])
            good = (t >= 0) & (t <= 1)
            ts.append(a[ok][good] + t[good, None] * d[ok][good])
        pts = np.vstack(ts)
        rel = np.angle(np.exp(1j * (np.arctan2(pts[:, 1], pts[:, 0]) - turn)))
        neg, pos = rel[rel < 0], rel[rel > 0]
        if len(neg) and len(pos):
            out[0, i], out[1, i] = neg.max() + turn, pos.min() + turn
    return out


@dataclass(frozen=True, eq=False)
class SolidSlots:
    """The manifold solid of a cut as a :class:`SlottedFace`: rays for the bottom, a plane section for the sides
    (``coupling`` places the slots' centre lines and bounds the rays below the depth)."""

    solid: mf.Manifold
    coupling: FaceCoupling

    def bottom(self, radii: np.ndarray, slot: int) -> np.ndarray:
        return mesh_bottom(self.solid, self.coupling, radii, slot)

    def sides(self, radii: np.ndarray, height: float, slot: int) -> np.ndarray:
        return mesh_sides(self.solid, self.coupling, radii, height, slot)


def measure_mesh(
    cut: FaceCut, c: FaceCoupling, radii: np.ndarray | None = None, height: float | None = None
) -> list[SlotMeasure]:
    """The cut slots measured on the manifold solid of ``cut`` (rays for the bottom, a plane section for the
    sides)."""
    return measure_slots(SolidSlots(cut.solid, c), c, cut.slots, radii, height)
